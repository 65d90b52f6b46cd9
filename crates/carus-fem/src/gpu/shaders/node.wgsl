// Node kernel: one invocation per node. Gathers the node's element force
// copies through the node-to-slot table (fixed order: no atomics, results
// reproducible), adds its applied loads, performs the central-difference
// update with mass-proportional damping (DESIGN.md, NiftySim)
//   u+ = [h^2 (R - F) / M + 2 u - (1 - alpha h / 2) u-] / (1 + alpha h / 2)
// and applies the fixed and imposed displacements at t_n+1.

// [slot start per node (node_count + 1) | slots (force-copy offsets)].
@group(0) @binding(2) var<storage, read> node_table: array<u32>;
// Per node: mass, 1 / mass (0 for a node no element touches).
@group(0) @binding(3) var<storage, read> node_mass: array<f32>;
// [record offset per node (NONE: free and unloaded) | records], see gpu/loads.rs.
@group(0) @binding(4) var<storage, read> node_loads: array<u32>;
@group(0) @binding(5) var<storage, read> forces: array<f32>;
@group(0) @binding(6) var<storage, read> previous: array<f32>;
@group(0) @binding(7) var<storage, read> current: array<f32>;
@group(0) @binding(8) var<storage, read_write> next: array<f32>;
@group(0) @binding(9) var<storage, read_write> status: array<atomic<u32>, 4>;

const FREE: u32 = 0u;
const FIXED: u32 = 1u;
const IMPOSED: u32 = 2u;

fn load_f32(i: u32) -> f32 {
    return bitcast<f32>(node_loads[i]);
}

@compute @workgroup_size(WORKGROUP)
fn advance_nodes(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = flat_index(wg, groups, local);
    if (n >= params.node_count) {
        return;
    }
    var internal = vec3<f32>(0.0);
    for (var i = node_table[n]; i < node_table[n + 1u]; i++) {
        let o = node_table[params.slots_at + i];
        internal += vec3<f32>(forces[o], forces[o + LANES], forces[o + 2u * LANES]);
    }
    let mass = node_mass[2u * n];
    let h2_over_m = params.gravity_h2.w * node_mass[2u * n + 1u];
    var applied = mass * params.gravity_h2.xyz;
    let record = node_loads[n];
    var kinds = 0u;
    if (record != NONE) {
        kinds = node_loads[record];
        let force_count = node_loads[record + 5u];
        let pressure_count = node_loads[record + 6u];
        var r = record + 7u;
        for (var k = 0u; k < force_count; k++) {
            applied += shape_now(node_loads[r]) * vec3<f32>(load_f32(r + 1u), load_f32(r + 2u), load_f32(r + 3u));
            r += 4u;
        }
        for (var k = 0u; k < pressure_count; k++) {
            let o = node_loads[r];
            applied += vec3<f32>(forces[o], forces[o + 1u], forces[o + 2u]);
            r += 1u;
        }
    }
    let base = 3u * n;
    let u = vec3<f32>(current[base], current[base + 1u], current[base + 2u]);
    let u_prev = vec3<f32>(previous[base], previous[base + 1u], previous[base + 2u]);
    var u_next = (h2_over_m * (applied - internal) + 2.0 * u - params.integrator.x * u_prev) * params.integrator.y;
    // Non-finite values fail both comparisons.
    let bound = params.integrator.z;
    if (!(all(u_next < vec3<f32>(bound)) && all(-u_next < vec3<f32>(bound)))) {
        atomicMin(&status[0], step.index);
        atomicMin(&status[2], n);
    }
    if (kinds != FREE) {
        let shapes = node_loads[record + 1u];
        for (var c = 0u; c < 3u; c++) {
            let kind = (kinds >> (2u * c)) & 3u;
            if (kind == FIXED) {
                u_next[c] = 0.0;
            } else if (kind == IMPOSED) {
                u_next[c] = shape_next((shapes >> (8u * c)) & 0xffu) * load_f32(record + 2u + c);
            }
        }
    }
    next[base] = u_next.x;
    next[base + 1u] = u_next.y;
    next[base + 2u] = u_next.z;
}
