//! Errors of the TLED solver. Each names the element, node, set or value at
//! fault and, where there is one, the fix.

use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum FemError {
    #[error("mesh has no elements")]
    EmptyMesh,
    #[error(
        "mesh connectivity has {len} entries, not a multiple of {per_element} nodes per element"
    )]
    RaggedConnectivity { len: usize, per_element: usize },
    #[error("element {element} refers to node {node}, but the mesh has only {node_count} nodes")]
    NodeOutOfRange {
        element: usize,
        node: u32,
        node_count: usize,
    },
    #[error("node {node} has a non-finite coordinate")]
    NonFiniteNode { node: usize },
    #[error("element {element} is inverted in the input mesh (Jacobian {jacobian:.3e} <= 0 at a corner); reorder its nodes (VTK order) or fix the mesh")]
    InvertedElement { element: usize, jacobian: f64 },
    #[error("element {element} is degenerate (volume {volume_m3:.3e} m^3 is negligible for its size); remove or remesh it")]
    DegenerateElement { element: usize, volume_m3: f64 },
    #[error("element {element} inverted during the run at t = {time_s:.6e} s (J = {jacobian:.3e}); reduce the load or the time step, or refine the mesh there")]
    ElementInvertedDuringRun {
        element: usize,
        jacobian: f64,
        time_s: f64,
    },
    #[error("the run diverged at t = {time_s:.6e} s ({what}); the last good state (t = {last_good_time_s:.6e} s) is kept")]
    Diverged {
        time_s: f64,
        last_good_time_s: f64,
        what: String,
    },
    #[error("time step {dt_s:.6e} s is above the critical time step {critical_s:.6e} s; use a step at or below it, or let the solver split it into sub-steps (in a `carus solve` job, `sub_stepping = true` under [solver])")]
    TimeStepAboveCritical { dt_s: f64, critical_s: f64 },
    #[error("time step must be positive and finite, got {dt_s}")]
    InvalidTimeStep { dt_s: f64 },
    #[error("element set `{set}` named by a material region is not in the mesh")]
    UnknownElementSet { set: String },
    #[error("element set `{set}` lists element {element}, but the mesh has only {element_count} elements")]
    ElementSetOutOfRange {
        set: String,
        element: u32,
        element_count: usize,
    },
    #[error("element {element} has no material: add a MaterialRegion covering it (element_set: None covers every element)")]
    MissingMaterial { element: usize },
    #[error("invalid material: {reason}")]
    InvalidMaterial { reason: String },
    #[error("invalid option `{option}`: {reason}")]
    InvalidOption {
        option: &'static str,
        reason: String,
    },
    #[error("{what} refers to node {node}, but the mesh has only {node_count} nodes")]
    BoundaryNodeOutOfRange {
        what: &'static str,
        node: u32,
        node_count: usize,
    },
    #[error("invalid boundary condition: {reason}")]
    InvalidBoundaryCondition { reason: String },
    #[error("snapshot has {got} nodes, the model has {expected}")]
    SnapshotMismatch { got: usize, expected: usize },
}
