//! Length units of mesh files. Meshes are read as given and scaled to
//! metres (SI inside the program, CONVENTIONS.md) by the unit a job declares.

use serde::{Deserialize, Serialize};

/// The length unit a mesh file's coordinates are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LengthUnit {
    /// Metres.
    #[serde(rename = "m")]
    Metre,
    /// Millimetres (the usual unit of segmented anatomy).
    #[serde(rename = "mm")]
    Millimetre,
}

impl LengthUnit {
    /// Metres per one unit.
    pub const fn metres_per_unit(self) -> f64 {
        match self {
            LengthUnit::Metre => 1.0,
            LengthUnit::Millimetre => 1e-3,
        }
    }

    /// As a job file writes it.
    pub const fn name(self) -> &'static str {
        match self {
            LengthUnit::Metre => "m",
            LengthUnit::Millimetre => "mm",
        }
    }
}
