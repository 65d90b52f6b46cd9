//! Maternal pelvis, fetus and pelvic floor: generated from clinical diameters
//! or imported from real meshes, in the pelvis frame of CONVENTIONS.md.

pub mod surface;

pub use surface::{SurfaceDefect, TriSurface};
