//! The job file of `carus solve`: a TOML description of a soft-tissue run
//! (docs/SOLVE.md). Every table refuses unknown keys; every key carries its
//! SI unit in its name (CONVENTIONS.md).

use std::fmt;

use serde::de::{self, Deserializer, Visitor};
use serde::Deserialize;
use carus_fem::{HourglassModulus, ModelOptions};

use crate::units::LengthUnit;

/// A whole job file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    pub mesh: MeshSpec,
    #[serde(default, rename = "material")]
    pub materials: Vec<MaterialSpec>,
    #[serde(default, rename = "fixed")]
    pub fixed: Vec<FixedSpec>,
    #[serde(default, rename = "displacement")]
    pub displacements: Vec<DisplacementSpec>,
    #[serde(default, rename = "force")]
    pub forces: Vec<ForceSpec>,
    #[serde(default, rename = "pressure")]
    pub pressures: Vec<PressureSpec>,
    pub gravity: Option<GravitySpec>,
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
}

/// `[mesh]`: the mesh file and its length unit.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Path relative to the job file; the extension picks the reader.
    pub file: String,
    /// Unit of the file's coordinates.
    pub length_unit: LengthUnit,
}

/// Constitutive law of a `[[material]]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    NeoHookean,
    MooneyRivlin,
}

/// `[[material]]`: a law and density on an element set (all elements when
/// `element_set` is left out; later tables override earlier ones).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub element_set: Option<String>,
    pub law: Law,
    /// Also read as `density_kg_per_m3`, as scenarios spell it.
    #[serde(alias = "density_kg_per_m3")]
    pub density_kg_m3: f64,
    pub shear_modulus_pa: Option<f64>,
    pub bulk_modulus_pa: Option<f64>,
    pub young_modulus_pa: Option<f64>,
    pub poisson_ratio: Option<f64>,
    pub c10_pa: Option<f64>,
    pub c01_pa: Option<f64>,
}

/// A displacement component name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
    Z,
}

/// `[[fixed]]`: components held at zero on a node set.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixedSpec {
    pub node_set: String,
    /// Default: all three.
    pub components: Option<Vec<Axis>>,
}

/// How a load grows in time (`load = { shape = "ramp_hold", ramp_s = 1.0 }`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum LoadSpec {
    /// Full load from t = 0.
    Step,
    /// Linear rise over `duration_s`, then held.
    Ramp { duration_s: f64 },
    /// Linear rise over `ramp_s`, then held (VALIDATION.md V3).
    RampHold { ramp_s: f64 },
    /// 3-4-5 polynomial rise over `duration_s` (no jump in velocity or
    /// acceleration), then held.
    Smooth345 { duration_s: f64 },
}

/// `[[displacement]]`: imposed displacement of a node set at full load;
/// a component left out stays free.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisplacementSpec {
    pub node_set: String,
    pub x_m: Option<f64>,
    pub y_m: Option<f64>,
    pub z_m: Option<f64>,
    pub load: LoadSpec,
}

/// `[[force]]`: nodal force on a node set, given per node or as a total
/// shared equally by the set's nodes.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    pub node_set: String,
    #[serde(default, deserialize_with = "crate::toml_text::optional_xyz")]
    pub force_per_node_n: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "crate::toml_text::optional_xyz")]
    pub total_force_n: Option<[f64; 3]>,
    pub load: LoadSpec,
}

/// `[[pressure]]`: follower pressure on a surface (positive pushes into
/// the body).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSpec {
    pub surface: String,
    pub pressure_pa: f64,
    pub load: LoadSpec,
}

/// `[gravity]`: a uniform body acceleration.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    #[serde(deserialize_with = "crate::toml_text::xyz")]
    pub acceleration_m_s2: [f64; 3],
}

/// Tetrahedron formulation of a job.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TetSpec {
    T4,
    T4anp,
}

/// Kernel precision of a job.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PrecisionSpec {
    F64,
    F32,
}

/// The time step: seconds, or `"auto"`: at most 0.9 x the critical step, in
/// whole steps to the end time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStep {
    Auto,
    Seconds(f64),
}

/// Safety factor of `time_step_s = "auto"` below the critical step (the
/// usual explicit-dynamics margin; NiftySim's examples run at 0.9 or less);
/// the step is then shortened so that whole steps end on `end_time_s`.
pub const AUTO_TIME_STEP_FRACTION: f64 = 0.9;

impl<'de> Deserialize<'de> for TimeStep {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct TimeStepVisitor;
        impl Visitor<'_> for TimeStepVisitor {
            type Value = TimeStep;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a time step in seconds or \"auto\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<TimeStep, E> {
                Ok(TimeStep::Seconds(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<TimeStep, E> {
                Ok(TimeStep::Seconds(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<TimeStep, E> {
                if v == "auto" {
                    Ok(TimeStep::Auto)
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
        }
        deserializer.deserialize_any(TimeStepVisitor)
    }
}

fn default_time_step() -> TimeStep {
    TimeStep::Auto
}
fn default_tet() -> TetSpec {
    TetSpec::T4anp
}
fn default_precision() -> PrecisionSpec {
    PrecisionSpec::F64
}
/// NiftySim's HGKappa used by Miller et al.'s cube (VALIDATION.md V3: 0.075).
fn default_hourglass() -> f64 {
    0.075
}

fn default_hourglass_modulus() -> HourglassModulus {
    ModelOptions::default().hourglass_modulus
}

/// `[solver]`: time integration and element options.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    pub end_time_s: f64,
    #[serde(default = "default_time_step")]
    pub time_step_s: TimeStep,
    /// Split a step above the critical one into sub-steps instead of
    /// refusing it.
    #[serde(default)]
    pub sub_stepping: bool,
    /// Mass-proportional damping alpha, 1/s.
    #[serde(default)]
    pub damping_per_s: f64,
    #[serde(default = "default_hourglass")]
    pub hourglass_coefficient: f64,
    /// "shear" (default, 2 mu) or "dilatational" (lambda + 2 mu, NiftySim's).
    #[serde(default = "default_hourglass_modulus")]
    pub hourglass_modulus: HourglassModulus,
    /// T4ANP by default: linear tetrahedra lock volumetrically in nearly
    /// incompressible tissue (Joldes, Wittek & Miller 2009).
    #[serde(default = "default_tet")]
    pub tet_formulation: TetSpec,
    #[serde(default = "default_precision")]
    pub precision: PrecisionSpec,
}

/// `[output]`: how often frames and history rows are written.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Default: end_time_s / 20.
    pub frame_interval_s: Option<f64>,
    /// Default: frame_interval_s / 10.
    pub history_interval_s: Option<f64>,
}
