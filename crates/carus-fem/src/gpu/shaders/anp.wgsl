// T4ANP (Joldes, Wittek & Miller 2009): the dilatation averaged per node,
// in two passes before the element kernel (kernel/passes.rs on the CPU).

@group(0) @binding(2) var<storage, read> connectivity: array<u32>;
@group(0) @binding(3) var<storage, read> shape_derivatives: array<f32>;
// Pass 1: V_e / 4 per element. Pass 2: 1 / (sum of V_e / 4) per node.
@group(0) @binding(4) var<storage, read> volumes: array<f32>;
@group(0) @binding(5) var<storage, read> displacement: array<f32>;
@group(0) @binding(6) var<storage, read_write> shares: array<f32>;
@group(0) @binding(7) var<storage, read_write> status: array<atomic<u32>, 4>;
@group(0) @binding(8) var<storage, read> node_table: array<u32>;
@group(0) @binding(9) var<storage, read_write> nodal_j: array<f32>;

// Pass 1: current volume share J_e V_e / 4 of every element.
@compute @workgroup_size(WORKGROUP)
fn volume_shares(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let e = flat_index(wg, groups, local);
    if (e >= params.element_count) {
        return;
    }
    var f = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    for (var a = 0u; a < NPE; a++) {
        let n = connectivity[block_offset(e, a, 1u)];
        let u = vec3<f32>(displacement[3u * n], displacement[3u * n + 1u], displacement[3u * n + 2u]);
        let d = block_offset(e, a, 3u);
        f[0] += u * shape_derivatives[d];
        f[1] += u * shape_derivatives[d + LANES];
        f[2] += u * shape_derivatives[d + 2u * LANES];
    }
    let j = determinant(f);
    if (!(j > 0.0)) {
        atomicMin(&status[0], step.index);
        atomicMin(&status[1], e);
    }
    shares[e] = j * volumes[e];
}

// Pass 2: J_n = (sum of J_e V_e / 4) / (sum of V_e / 4) over the node's elements.
@compute @workgroup_size(WORKGROUP)
fn nodal_dilatation(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = flat_index(wg, groups, local);
    if (n >= params.node_count) {
        return;
    }
    let inv_volume = volumes[n];
    if (!(inv_volume > 0.0)) {
        // A node no element touches keeps J = 1.
        nodal_j[n] = 1.0;
        return;
    }
    var sum = 0.0;
    for (var i = node_table[n]; i < node_table[n + 1u]; i++) {
        sum += shares[slot_element(node_table[params.slots_at + i])];
    }
    nodal_j[n] = sum * inv_volume;
}
