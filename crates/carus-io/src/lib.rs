//! Mesh input from the formats researchers already have (Gmsh `.msh`,
//! VTK `.vtk`/`.vtu`, Abaqus `.inp`) and result output (VTU frames, a PVD
//! time series, CSV histories).
//!
//! This is an I/O crate: it touches the file system, but never prints and
//! never panics on bad input; every error names the file, the line (or the
//! file's own node or element id) and the fix.

mod builder;
pub mod error;
pub mod abaqus;
pub mod gmsh;
mod text;
pub mod units;
pub mod vtk;
mod vtu_raw;

pub use builder::MeshFile;
pub use error::{ReadError, WriteError};
pub use units::LengthUnit;
