// Shared declarations of every TLED kernel. The Rust side prepends the
// compile-time constants NPE (nodes per element), HOURGLASS and ANP.

const WORKGROUP: u32 = 64u;
// Elements per structure-of-arrays block (kernel::lanes::LANES on the CPU).
const LANES: u32 = 8u;
const NONE: u32 = 0xffffffffu;

// Constant for a run; rewritten only when the coupled or probed node lists change.
struct Params {
    element_count: u32,
    node_count: u32,
    triangle_count: u32,
    coupled_count: u32,
    probe_count: u32,
    // Offset of the slot list in node_table (after node_count + 1 starts).
    slots_at: u32,
    // Offset of the triangle force copies in the force buffer.
    triangle_forces_at: u32,
    pad0: u32,
    // xyz: gravity, m/s^2; w: h^2.
    gravity_h2: vec4<f32>,
    // x: 1 - alpha h / 2; y: 1 / (1 + alpha h / 2); z: runaway displacement, m.
    integrator: vec4<f32>,
}

// One record per sub-step of a submission (dynamic uniform offset).
struct Step {
    // Sub-step index within the submission, reported in the status buffer.
    index: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    // Load-shape values at t_n (loads) and t_n+1 (imposed displacements).
    shape_now: array<vec4<f32>, 7>,
    shape_next: array<vec4<f32>, 7>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> step: Step;

fn shape_now(k: u32) -> f32 {
    return step.shape_now[k / 4u][k % 4u];
}

fn shape_next(k: u32) -> f32 {
    return step.shape_next[k / 4u][k % 4u];
}

// Flat invocation index of a dispatch that may spill into y when the count
// exceeds the per-dimension workgroup limit.
fn flat_index(wg: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (wg.y * groups.x + wg.x) * WORKGROUP + local;
}

// Offset of (element e, local node a, component x) in the block layout.
fn block_offset(e: u32, a: u32, fields: u32) -> u32 {
    return ((e / LANES * NPE + a) * fields) * LANES + e % LANES;
}

// Element of a force slot (kernel::blocks::ElementBlocks::slot_element).
fn slot_element(slot: u32) -> u32 {
    return (slot / (NPE * 3u * LANES)) * LANES + slot % LANES;
}
