//! Total Lagrangian Explicit Dynamics (Miller et al. 2007) for soft tissue.
//!
//! A constant [`TledModel`]-style model (precomputed shape derivatives,
//! volumes, lumped masses) is kept apart from the mutable state
//! (displacements of the current and previous steps).

pub mod baseline;
pub mod generate;
pub mod mesh;

pub use mesh::{ElementKind, Mesh};
