//! Total Lagrangian Explicit Dynamics (Miller et al. 2007) for soft tissue.
//!
//! The constant [`TledModel`] (precomputed shape derivatives, volumes,
//! lumped masses, hourglass vectors, gather table) is kept apart from the
//! mutable state of a run, held by [`TledSolver`].

// Tensor maths reads best with explicit indices; `!(x > 0.0)` is the
// deliberate NaN-catching form of the checks.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod baseline;
pub mod coupling;
pub mod error;
pub mod fields;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod generate;
pub mod kernel;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod model;
pub mod quality;
pub mod solver;
pub mod validation;

pub use coupling::CoupledNodes;
pub use error::FemError;
pub use fields::{ElementFields, Energies};
pub use loads::{BoundaryConditions, FixedDofs, ImposedDisplacement, LoadShape, NodalForce, SurfacePressure};
pub use material::{Material, MaterialLaw, MooneyRivlin, NeoHookean};
pub use mesh::{ElementKind, Mesh};
pub use model::{HourglassModulus, MaterialRegion, ModelOptions, Precision, TetFormulation, TledModel};
pub use quality::{check_quality, QualityReport};
pub use solver::{ClockOrigin, SolverSnapshot, StepControl, TledSolver};
