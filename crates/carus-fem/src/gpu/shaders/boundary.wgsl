// Small kernels around the step: follower surface pressure (before the
// node kernel), displacements held through the coupling API (after it),
// and the internal forces of a few probed nodes (read back for coupling).

// Pressure: per triangle [n0, n1, n2, shape, pressure (f32 bits)].
// Coupled: per node [node, target ux, uy, uz, normal nx, ny, nz (f32 bits),
// unused]; a zero normal holds the node in every direction. Probe: node indices.
@group(0) @binding(2) var<storage, read> records: array<u32>;
@group(0) @binding(3) var<storage, read> reference: array<f32>;
@group(0) @binding(4) var<storage, read> displacement: array<f32>;
@group(0) @binding(5) var<storage, read_write> forces: array<f32>;
@group(0) @binding(6) var<storage, read> node_table: array<u32>;
@group(0) @binding(7) var<storage, read_write> target_displacement: array<f32>;
@group(0) @binding(8) var<storage, read_write> probed: array<f32>;

fn position(n: u32) -> vec3<f32> {
    let i = 3u * n;
    return vec3<f32>(reference[i] + displacement[i], reference[i + 1u] + displacement[i + 1u], reference[i + 2u] + displacement[i + 2u]);
}

// Each node of a triangle takes -p A n / 3 on the current (deformed) area
// vector A n = (e1 x e2) / 2 (loads.rs: SurfacePressure is a follower load).
@compute @workgroup_size(WORKGROUP)
fn surface_pressure(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let t = flat_index(wg, groups, local);
    if (t >= params.triangle_count) {
        return;
    }
    let r = 5u * t;
    let x0 = position(records[r]);
    let an = cross(position(records[r + 1u]) - x0, position(records[r + 2u]) - x0);
    let p = bitcast<f32>(records[r + 4u]) * shape_now(records[r + 3u]);
    let f = an * (-p / 6.0);
    let o = params.triangle_forces_at + 9u * t;
    for (var a = 0u; a < 3u; a++) {
        forces[o + 3u * a] = f.x;
        forces[o + 3u * a + 1u] = f.y;
        forces[o + 3u * a + 2u] = f.z;
    }
}

// Displacements imposed through the coupling API win over every other
// condition; a sliding node keeps its free update along its plane and takes
// its target only along the normal (coupling.rs, CoupledNodes::constrain).
@compute @workgroup_size(WORKGROUP)
fn hold_coupled(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = flat_index(wg, groups, local);
    if (i >= params.coupled_count) {
        return;
    }
    let r = 8u * i;
    let base = 3u * records[r];
    let held = vec3<f32>(bitcast<f32>(records[r + 1u]), bitcast<f32>(records[r + 2u]), bitcast<f32>(records[r + 3u]));
    let normal = vec3<f32>(bitcast<f32>(records[r + 4u]), bitcast<f32>(records[r + 5u]), bitcast<f32>(records[r + 6u]));
    var u = held;
    if (any(normal != vec3<f32>(0.0))) {
        let free = vec3<f32>(target_displacement[base], target_displacement[base + 1u], target_displacement[base + 2u]);
        u = free - dot(free - held, normal) * normal;
    }
    target_displacement[base] = u.x;
    target_displacement[base + 1u] = u.y;
    target_displacement[base + 2u] = u.z;
}

// Internal forces F(u) at the probed nodes (the gather of the node kernel).
@compute @workgroup_size(WORKGROUP)
fn probe_forces(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = flat_index(wg, groups, local);
    if (i >= params.probe_count) {
        return;
    }
    let n = records[i];
    var f = vec3<f32>(0.0);
    for (var k = node_table[n]; k < node_table[n + 1u]; k++) {
        let o = node_table[params.slots_at + k];
        f += vec3<f32>(forces[o], forces[o + LANES], forces[o + 2u * LANES]);
    }
    probed[3u * i] = f.x;
    probed[3u * i + 1u] = f.y;
    probed[3u * i + 2u] = f.z;
}
