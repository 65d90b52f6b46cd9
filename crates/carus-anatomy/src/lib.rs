//! Maternal pelvis, fetus and pelvic floor: generated from clinical diameters
//! or imported from real meshes, in the pelvis frame of CONVENTIONS.md.

pub mod axis;
pub mod fetus;
pub mod floor;
pub mod import;
pub mod pelvis;
pub mod pose;
pub mod surface;

pub use axis::{AxisFrame, PelvicAxis, Plane};
pub use pelvis::{Pelvis, PelvisError, PelvisLandmarks, PelvisPlanes, SoftWalls};
pub use surface::{SurfaceDefect, TriSurface};
