//! The scenario file: anatomy, starting position, forces, contact, neck,
//! tissue and numerics of one labour, in TOML with the canonical keys of
//! CONVENTIONS.md. Unknown keys, wrong units and impossible values are
//! refused with the key's path and a hint (serde_path_to_error gives the
//! path, toml the line).

use std::fmt;
use std::num::NonZeroUsize;
use std::path::{Path, PathBuf};

use carus_anatomy::fetus::{AtlantoOccipitalPlacement, HeadDiameters, TrunkDiameters};
use carus_anatomy::floor::FloorParameters;
use carus_anatomy::pelvis::{PelvisDiameters, PelvisSpec, PELVIC_CANAL_DIAMETER_MM, VISIBLE_HUMAN_FEMALE};
use carus_io::toml_text::{holds_key, line_of_key, located};
use serde::de::value::MapAccessDeserializer;
use serde::de::{DeserializeSeed, Deserializer, Error as _, IntoDeserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};

use crate::trajectory::{Mode, TrajectorySection};

/// Why a scenario cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: {key}{message}\n  hint: {hint}")]
    Syntax {
        path: PathBuf,
        line: usize,
        key: String,
        message: String,
        hint: String,
    },
    #[error("{}: `{key}` = {value}: {problem}\n  hint: {hint}", located(.path, *.line))]
    Value {
        /// A boxed path and a non-zero line keep this, the largest
        /// variant, and every `Result` carrying it small.
        path: Box<Path>,
        /// The key's line in the text read (a file, or the scenario a
        /// checkpoint or sweep plan keeps); None for a key the text does not
        /// hold (refused through another key a `--set` changed: a value the
        /// setting itself gave is refused as a [`ScenarioError::Setting`]).
        line: Option<NonZeroUsize>,
        key: std::borrow::Cow<'static, str>,
        value: String,
        problem: String,
        hint: String,
    },
    #[error("no built-in scenario named `{0}`; `carus scenarios` lists them")]
    UnknownBuiltin(String),
    #[error("`{setting}`: {problem}\n  hint: {hint}")]
    Setting {
        setting: String,
        problem: String,
        hint: String,
    },
    #[error("cannot write the scenario as TOML: {0}")]
    Serialize(#[from] toml::ser::Error),
}

/// Which part of the head presents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Presentation {
    /// Vertex (occiput) presentation: `position` names the occiput.
    Vertex,
    /// Face presentation: the head fully extended, `position` names the chin (mentum).
    Face,
}

/// Clinical position of the denominator (occiput for a vertex, mentum for
/// a face presentation) in the maternal pelvis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Position {
    OA,
    LOA,
    LOT,
    LOP,
    OP,
    ROP,
    ROT,
    ROA,
    /// Mentum anterior (face presentation).
    MA,
    /// Mentum posterior (face presentation).
    MP,
    LMT,
    RMT,
}

impl Position {
    /// Angle of the denominator in the inlet cross-section from anterior,
    /// degrees, positive to the mother's right (CARDINAL_MOVEMENTS.md theta).
    pub fn theta_deg(self) -> f64 {
        match self {
            Position::OA | Position::MA => 0.0,
            Position::LOA => -45.0,
            Position::LOT | Position::LMT => -90.0,
            Position::LOP => -135.0,
            Position::OP | Position::MP => 180.0,
            Position::ROP => 135.0,
            Position::ROT | Position::RMT => 90.0,
            Position::ROA => 45.0,
        }
    }

    fn is_mentum(self) -> bool {
        matches!(
            self,
            Position::MA | Position::MP | Position::LMT | Position::RMT
        )
    }
}

/// `[trunk]`: the fetal trunk, joined to the head by the neck.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrunkSection {
    /// Without a trunk the expulsion force acts at the pivot on the head.
    pub enabled: bool,
    /// REFERENCE_DATA.md: bisacromial about 120 mm.
    pub bisacromial_mm: f64,
    /// Engineering estimate 95 mm (carus-anatomy TrunkDiameters).
    pub bitrochanteric_mm: f64,
    /// The neck, from the atlanto-occipital pivot to the first thoracic
    /// vertebra: 37 mm, the cervical spine's length at birth (Roche,
    /// carus-anatomy TrunkDiameters).
    pub cervical_spine_mm: f64,
    /// The trunk from the neck base (T1) to the breech: engineering
    /// estimate 186 mm, not scaled with the shoulders (carus-anatomy
    /// TrunkDiameters).
    pub trunk_length_mm: f64,
    /// Across the chest: engineering estimate 108 mm (a 322 mm
    /// circumference), setting the girths, so that `bisacromial_mm` widens
    /// the shoulders alone (carus-anatomy TrunkDiameters).
    pub chest_breadth_mm: f64,
}

impl Default for TrunkSection {
    fn default() -> Self {
        TrunkSection::with_diameters(&TrunkDiameters::default())
    }
}

impl TrunkSection {
    /// An enabled trunk of these diameters.
    pub fn with_diameters(d: &TrunkDiameters) -> Self {
        TrunkSection {
            enabled: true,
            bisacromial_mm: d.bisacromial_mm,
            bitrochanteric_mm: d.bitrochanteric_mm,
            cervical_spine_mm: d.cervical_spine_mm,
            trunk_length_mm: d.trunk_length_mm,
            chest_breadth_mm: d.chest_breadth_mm,
        }
    }

    /// The diameters carus-anatomy builds the trunk from.
    pub fn diameters(&self) -> TrunkDiameters {
        TrunkDiameters {
            bisacromial_mm: self.bisacromial_mm,
            bitrochanteric_mm: self.bitrochanteric_mm,
            cervical_spine_mm: self.cervical_spine_mm,
            trunk_length_mm: self.trunk_length_mm,
            chest_breadth_mm: self.chest_breadth_mm,
        }
    }
}

/// `[spine]`: a fetal spine that bends at the thoracolumbar junction, the
/// trunk then being two rigid segments (the thorax, which carries the head
/// and the shoulders, and the lower trunk with the hips) joined by a
/// six-degree-of-freedom spring like the neck's. The expulsion then acts on
/// the lower trunk. No measured fetal or neonatal thoracolumbar stiffness
/// or range was found (docs/LABOUR.md, tenth and eleventh sessions), so
/// every value here is an engineering choice; docs/LABOUR.md gives the runs
/// that show what they change.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpineSection {
    /// Off: the trunk is one rigid body.
    pub enabled: bool,
    /// Bending stiffness in flexion, extension and lateral bending, N m per
    /// degree. Engineering choice: 0.1, ten times the neck's flexion
    /// (REFERENCE_DATA.md) and a tenth of an adult cervical joint's 1.03
    /// (Voo et al. 1998, an upper bound for a term fetus's trunk).
    pub bending_nm_per_deg: f64,
    /// Axial rotation (twist) stiffness, N m per degree. Engineering
    /// choice: as the bending.
    pub axial_rotation_nm_per_deg: f64,
    /// End of the bending range to either side, degrees. Engineering
    /// choice: 45.
    pub bending_limit_deg: f64,
    /// End of the twist range to either side, degrees. Engineering choice: 45.
    pub axial_rotation_limit_deg: f64,
    /// Stiffness added beyond a limit, N m per degree. Numerical, as the
    /// neck's: it enforces the limit like a contact penalty.
    pub end_range_stiffness_nm_per_deg: f64,
    /// Stiffness of the joint against the segments' pulling apart, pushing
    /// together or shearing, N/m. Numerical: it keeps the segments joined
    /// (4 mm under the 120 N expulsion). The joint's point moves with an
    /// effective mass of about 0.1 kg (the thorax, 0.72 kg and 9e-4 kg m^2,
    /// and the lower trunk, 0.54 kg, each turning about its centre), so it
    /// rings at about 550 rad/s, 0.28 rad per 0.5 ms rigid step.
    pub joint_stiffness_n_per_m: f64,
    /// Rotational dashpot, N m s/rad. Numerical: about half critical for
    /// the bending spring (2 sqrt(k I) = 0.18 with I about 1.4e-3 kg m^2,
    /// the two segments about the joint), and small enough for the explicit
    /// step on the segments' own inertia (c dt / I about 0.3; 0.3 N m s/rad
    /// with 600 N s/m at the joint made the pair tumble within 0.1 s).
    pub rotational_damping_nm_s_per_rad: f64,
    /// Linear dashpot at the joint, N s/m. Numerical: about half critical
    /// for the joint spring (2 sqrt(k m) = 110 N s/m on the 0.1 kg), c dt / m
    /// about 0.5.
    pub linear_damping_n_s_per_m: f64,
}

impl Default for SpineSection {
    fn default() -> Self {
        SpineSection {
            enabled: false,
            bending_nm_per_deg: 0.1,
            axial_rotation_nm_per_deg: 0.1,
            bending_limit_deg: 45.0,
            axial_rotation_limit_deg: 45.0,
            end_range_stiffness_nm_per_deg: 1.0,
            joint_stiffness_n_per_m: 3e4,
            rotational_damping_nm_s_per_rad: 0.1,
            linear_damping_n_s_per_m: 50.0,
        }
    }
}

impl SpineSection {
    /// The thoracolumbar joint as carus-contact's six-degree-of-freedom
    /// spring, the thorax in the head's place.
    pub fn joint(&self) -> carus_contact::NeckStiffness {
        carus_contact::NeckStiffness {
            flexion_nm_per_deg: self.bending_nm_per_deg,
            extension_nm_per_deg: self.bending_nm_per_deg,
            lateral_bending_nm_per_deg: self.bending_nm_per_deg,
            axial_rotation_nm_per_deg: self.axial_rotation_nm_per_deg,
            compression_n_per_m: self.joint_stiffness_n_per_m,
            tension_n_per_m: self.joint_stiffness_n_per_m,
            shear_n_per_m: self.joint_stiffness_n_per_m,
            rotational_damping_nm_s_per_rad: self.rotational_damping_nm_s_per_rad,
            linear_damping_n_s_per_m: self.linear_damping_n_s_per_m,
            flexion_limit_deg: self.bending_limit_deg,
            extension_limit_deg: self.bending_limit_deg,
            lateral_bending_limit_deg: self.bending_limit_deg,
            axial_rotation_limit_deg: self.axial_rotation_limit_deg,
            end_range_stiffness_nm_per_deg: self.end_range_stiffness_nm_per_deg,
            // No stop: the joint spring alone keeps the segments together.
            compression_limit_mm: 0.0,
            end_range_compression_n_per_m: 0.0,
            // Joined straight: start and neutral are the same.
            rest_attitude: carus_contact::NeckRest::Start,
        }
    }

    /// The `[spine]` key that sets a field of [`SpineSection::joint`].
    pub fn key_of(joint_field: &'static str) -> &'static str {
        match joint_field {
            "compression_n_per_m" | "tension_n_per_m" | "shear_n_per_m" => "joint_stiffness_n_per_m",
            "flexion_nm_per_deg" | "extension_nm_per_deg" | "lateral_bending_nm_per_deg" => "bending_nm_per_deg",
            "flexion_limit_deg" | "extension_limit_deg" | "lateral_bending_limit_deg" => "bending_limit_deg",
            other => other,
        }
    }
}

/// The longest run a scenario may ask for, s: an hour of contractions,
/// 7.2 million rigid steps at the default step and over an hour of wall
/// time at the normal run's 0.6-0.8 ms a step (docs/PERFORMANCE.md). The
/// outcomes settle within the built-ins' 60 s; more is a slip of units or
/// digits, which would run for days and fill the memory with samples.
pub const LONGEST_END_TIME_S: f64 = 3600.0;

/// The finest rigid step a scenario may ask for, s: each rigid step takes
/// about 0.4 ms of wall time (docs/PERFORMANCE.md), so a finer one could
/// not finish a run.
pub const SMALLEST_RIGID_DT_S: f64 = 1e-5;

/// `[start]`: where the fetus starts (an input, CARDINAL_MOVEMENTS.md).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartSection {
    /// Station of the head's leading point, mm (negative above the spines).
    pub station_mm: f64,
    pub presentation: Presentation,
    pub position: Position,
    /// Head attitude phi relative to the trunk, degrees (positive: flexed).
    pub attitude_deg: f64,
}

impl Default for StartSection {
    fn default() -> Self {
        // LOT, head above the inlet, slightly flexed: the normal labour of
        // CARDINAL_MOVEMENTS.md ("Clinical sanity cases").
        StartSection {
            station_mm: -55.0,
            presentation: Presentation::Vertex,
            position: Position::LOT,
            attitude_deg: 5.0,
        }
    }
}

/// Where the expulsion force acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActsOn {
    Trunk,
    Pivot,
}

/// Which way the expulsion pushes: `"fetal_spine"`, `"inlet_axis"`, or a
/// fixed direction `[x, y, z]` in the pelvis frame (CONVENTIONS.md: x to
/// the mother's right, y anterior, z cranial), scaled to unit length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "not a direction: use \"fetal_spine\", \"inlet_axis\" or [x, y, z] in the pelvis frame (x right, y anterior, z cranial)"
)]
pub enum ExpulsionDirection {
    Named(NamedDirection),
    Fixed([f64; 3]),
}

/// The directions `[expulsion] direction` knows by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NamedDirection {
    /// Along the fetal spine, from the breech towards the head: the fundus
    /// pressing on the breech (the seed's generator, issue 4's default).
    FetalSpine,
    /// Down the axis of the pelvic inlet (-z, normal to the inlet plane),
    /// fixed in the pelvis whatever the fetus does: the intra-uterine
    /// pressure's resultant through the opening it pushes the fetus into
    /// (REFERENCE_DATA.md derives the expulsive force as that pressure over
    /// the head's area). A textbook idealisation, not a measured direction.
    InletAxis,
}

/// `[expulsion]`: the seed's generator, a sinusoid between a minimum and a
/// maximum, by default along the fetal spine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExpulsionSection {
    /// Force between contractions, N (negative lets the fetus slide back).
    pub force_min_n: f64,
    /// Peak of a contraction, N. REFERENCE_DATA.md: 70-140 N of expulsive force.
    pub force_max_n: f64,
    /// Contraction period, s. REFERENCE_DATA.md: 150 s cycles in the
    /// literature; compressed in time here (numerical choice).
    pub period_s: f64,
    pub acts_on: ActsOn,
    /// The push's direction; `fetal_spine` by default.
    pub direction: ExpulsionDirection,
}

impl Default for ExpulsionSection {
    fn default() -> Self {
        ExpulsionSection {
            force_min_n: 0.0,
            force_max_n: 120.0,
            period_s: 8.0,
            acts_on: ActsOn::Trunk,
            direction: ExpulsionDirection::Named(NamedDirection::FetalSpine),
        }
    }
}

/// `[contact]`: the penalty law with Coulomb friction (docs/CONTACT.md).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSection {
    /// Coulomb coefficient. REFERENCE_DATA.md: 0.35 (Shockey et al. 1985); 0 works.
    pub friction: f64,
    /// Numerical penalty stiffness, Pa/m (docs/CONTACT.md: 1 mm at 140 N).
    pub penalty_stiffness_pa_per_m: f64,
    /// Numerical Kelvin-Voigt time of the penalty, s (docs/CONTACT.md).
    pub damping_time_s: f64,
    /// Penalty stiffness of the trunk on bone, Pa/m. The shoulders and
    /// chest meet the canal through their soft-tissue cover over a mobile
    /// shoulder girdle, not bone on bone, so the penalty is that cover's
    /// stiffness as an elastic (Winkler) layer, k = E / h: E = 60 kPa
    /// (3 x a round 20 kPa shear modulus for passive muscle, nearly
    /// incompressible; resting adult levator ani measures 16-17 kPa,
    /// Gachon et al. 2019, see `FloorSection`) over h = 6 mm
    /// of skin, fat and muscle, 1.0e7 Pa/m: alone, the chest pressed with
    /// the full 120 N would sink about 9 mm (F = k pi R d^2, R = 50 mm);
    /// with the skeleton under the cover (`trunk_cover_depth_mm`) it sinks
    /// about 6.6. An engineering estimate, no measured neonatal value is
    /// cited (docs/LABOUR.md records the outcome at this and at 9.4e7).
    pub trunk_penalty_stiffness_pa_per_m: f64,
    /// Depth of that cover, mm: pressed through it, the shoulder girdle
    /// and ribs meet the bone, and the bone law's penalty
    /// (`penalty_stiffness_pa_per_m`) adds on, so the cover is not
    /// squeezed far past its own depth (docs/CONTACT.md, "The trunk's
    /// cover"). The same h as the stiffness above (engineering estimate).
    pub trunk_cover_depth_mm: f64,
    /// Spacing of the contact samples on the fetal surface, mm (numerical).
    pub sample_spacing_mm: f64,
    /// Contact of the head with the trunk below its thoracic inlet: the chin meets
    /// the chest and the shoulders meet the skull (the trunk's law, its
    /// soft cover on the head as on bone; the same friction). Without it
    /// the rigid bodies pass through each other wherever the neck spring
    /// lets them (up to 45 mm in the runs of docs/LABOUR.md, fifteenth
    /// session); off, they do again (for comparison with those runs).
    pub head_trunk: bool,
    /// Stiffness of the sacrospinous ligaments (with the coccygeus on them)
    /// as a share of the bone's, for the head's law and the trunk's (its
    /// cover and core alike): 1, as rigid as bone (the model's choice since
    /// the ligaments closed the sciatic openings). No measured transverse
    /// stiffness of the ligament was found, only its suture pull-out
    /// strength, about 120 N (Lazarou et al. 2004); orthopaedic pelvis
    /// models assume E = 251 MPa on a 32 mm^2 section or a 1400 N/mm spring,
    /// with which a 50 mm ligament pressed at its middle gives some 5-11
    /// mm at the 360-630 N of the normal run's snap. The normal outcome
    /// turns on it (docs/LABOUR.md, forty-third session).
    pub ligament_stiffness_ratio: f64,
    /// Close the front of a generated pelvis's false pelvis with the lower
    /// abdominal wall (`carus_anatomy::SoftWalls`), rising from the front
    /// of the pubic crests: without it a shoulder above the brim passes
    /// down in front of the pubis, outside the canal, as the anterior
    /// shoulder did in every run before (docs/LABOUR.md, forty-fifth
    /// session); off, it may again, for comparison. An imported pelvis has
    /// none.
    pub abdominal_wall: bool,
    /// Close a generated pelvis's obturator foramina with the obturator
    /// membranes and the obturator internus on them, lying on the canal
    /// wall. Off by default, the canal of every earlier run: rigid there
    /// they narrow the side wall where the head turns, while the muscle
    /// gives, and no stiffness for it was found; on, the normal run is held
    /// at the shoulders as it is off, its external rotation lost
    /// (docs/LABOUR.md, forty-fifth session).
    pub obturator_membranes: bool,
    /// Stiffness of those soft walls as a share of the bone's, for the
    /// head's law and the trunk's: 1, as rigid as bone, as the ligaments
    /// are (`ligament_stiffness_ratio`). Engineering choice: the abdominal
    /// wall gives far more than bone, but no transverse stiffness of it
    /// or of the obturator internus on its membrane was found.
    pub soft_wall_stiffness_ratio: f64,
}

/// Friction of the wetted canal, the built-in scenarios' `contact.friction`:
/// the scalp slides on the vaginal wall and the muscle lining the pelvis in
/// amniotic fluid, whose surfactant lubricates at 0.009 (Hills 1995, Aust N Z
/// J Obstet Gynaecol, "Remarkable lubricating capabilities of amniotic
/// surfactant"; fluid-lubricated soft tissues 0.007-0.054, docs/LABOUR.md).
/// Hills measured the surfactant extracted from amniotic fluid as a
/// boundary lubricant between test surfaces, not the scalp on the vaginal
/// wall, which no source found has measured; damp skin without such a
/// film grips far harder (above 1: Derler & Gerhardt 2012), and the
/// outcome turns on this value (docs/LABOUR.md, twentieth and
/// twenty-first sessions).
/// The contact default stays the seed's 0.35 (muscle on bone,
/// REFERENCE_DATA.md), which `normal-dry` runs.
pub const WETTED_CANAL_FRICTION: f64 = 0.009;

/// Young's modulus of the trunk's soft-tissue cover, Pa: 3 x 20 kPa, a
/// round passive-muscle shear modulus, nearly incompressible (engineering
/// value, see `trunk_penalty_stiffness_pa_per_m`).
pub const TRUNK_SOFT_TISSUE_MODULUS_PA: f64 = 60e3;
/// Depth of the soft tissue (skin, fat, muscle) over the fetal shoulder
/// girdle and chest, m (engineering estimate).
pub const TRUNK_SOFT_TISSUE_DEPTH_M: f64 = 6e-3;

impl Default for ContactSection {
    fn default() -> Self {
        let law = carus_contact::ContactLaw::default();
        ContactSection {
            friction: law.friction_coefficient,
            penalty_stiffness_pa_per_m: law.penalty_stiffness_pa_per_m,
            damping_time_s: law.damping_time_s,
            trunk_penalty_stiffness_pa_per_m: TRUNK_SOFT_TISSUE_MODULUS_PA
                / TRUNK_SOFT_TISSUE_DEPTH_M,
            trunk_cover_depth_mm: TRUNK_SOFT_TISSUE_DEPTH_M * 1e3,
            sample_spacing_mm: 4.0,
            head_trunk: true,
            ligament_stiffness_ratio: 1.0,
            abdominal_wall: true,
            obturator_membranes: false,
            soft_wall_stiffness_ratio: 1.0,
        }
    }
}

/// The trunk widths a scenario may give, mm: well around the newborn's
/// bisacromial, 124 +- 10 mm (REFERENCE_DATA.md), from a preterm trunk to
/// twice the mean, so that a width given in cm is refused.
pub const FETAL_TRUNK_WIDTH_MM: (f64, f64) = (50.0, 250.0);

/// The symphysis and sacral lengths a scenario may give, mm: from under
/// half the symphysis's 40-50 mm (the imported Visible Human pelvis
/// measures 26 mm) to over twice the sacrum's 100-110 mm
/// (REFERENCE_DATA.md), so that a length given in cm is refused.
pub const PELVIC_WALL_LENGTH_MM: (f64, f64) = (15.0, 250.0);

/// The finest VTU frame interval a scenario may give, s: a frame is a few
/// hundred kB, so finer ones fill a disk in minutes.
pub const MIN_VTU_EVERY_S: f64 = 0.01;

/// The neck lengths a scenario may give, mm: from 0.4 to 3 times the
/// newborn's 37 mm cervical spine (carus-anatomy TrunkDiameters), so that a
/// length given in cm is refused.
pub const FETAL_NECK_LENGTH_MM: (f64, f64) = (15.0, 110.0);

/// The trunk lengths (neck base to breech) a scenario may give, mm: from
/// under half to over twice the default 186 mm (carus-anatomy
/// TrunkDiameters), so that a length given in cm is refused.
pub const FETAL_TRUNK_LENGTH_MM: (f64, f64) = (80.0, 400.0);

/// The longest scenario name, bytes: a folder name of runs/ may take 255.
const MAX_NAME_BYTES: usize = 200;

/// The spacings of contact samples a scenario may give, mm: from four
/// times finer than the default 4 mm (some 2000 samples on the head at 4 mm;
/// at 1 mm 16 times as many) to coarser than the head's own curvature
/// allows, so that a spacing given in metres is refused before the
/// sampling runs out of memory.
pub const CONTACT_SAMPLE_SPACING_MM: (f64, f64) = (1.0, 30.0);

/// The head diameters a scenario may give, mm: a wide band around the
/// term head's 81-137.5 mm (REFERENCE_DATA.md), so that a diameter in cm,
/// or a slip of many digits, is refused before the head is shaped.
pub const FETAL_HEAD_DIAMETER_MM: (f64, f64) = (40.0, 250.0);

/// The densities a scenario may give its soft tissue, kg/m^3: a wide band
/// around fat (about 900) and muscle (1040-1060, ICRP 23 reference man),
/// which refuses values in g/cm^3.
pub const SOFT_TISSUE_DENSITY_KG_PER_M3: (f64, f64) = (500.0, 2000.0);

/// The softest floor a scenario may give, Pa: a tenth of the softest soft
/// tissue's shear modulus (brain, about 1 kPa: Budday et al. 2017, Acta
/// Biomater 48:319), so that a modulus given in kPa is refused.
pub const FLOOR_SHEAR_MODULUS_MIN_PA: f64 = 100.0;

/// `[fetus]`: mass and the resistance of the surroundings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FetusSection {
    /// Density of the fetal body, kg/m^3: soft tissue about 1050 (ICRP
    /// 23 reference man, muscle 1040-1060); masses and inertias follow
    /// from the head and trunk surfaces.
    pub density_kg_per_m3: f64,
    /// Viscous resistance to the trunk's translation, N s/m: the uterus
    /// and amniotic fluid around the trunk. No measured value was found:
    /// it compresses the hours of labour into a minute (the descent speed
    /// at a given net force), and with the head's drag it sets how the
    /// push divides between head and trunk while they move, so it is a
    /// model parameter, not a numerical one. The normal outcome depends on
    /// it: all seven movements at 2250 and 3000, no internal rotation or
    /// extension at 1500 and below, the head pushed into the canal at 4000
    /// and above (docs/LABOUR.md, "Parameters", forty-second session).
    pub trunk_linear_drag_n_s_per_m: f64,
    /// Viscous resistance to the trunk's rotation, N m s/rad (as above, no
    /// measured value; 1.5 to 6 leave the normal outcome as it is).
    pub trunk_angular_drag_nm_s_per_rad: f64,
    /// Viscous resistance to the head's translation, N s/m (as the trunk's,
    /// no measured value; the normal outcome keeps all seven from 1000 to
    /// 4000 and loses internal rotation and extension at 500 and below).
    pub head_linear_drag_n_s_per_m: f64,
    /// Viscous resistance to the head's rotation, N m s/rad (no measured
    /// value; 0.125 keeps the normal outcome, 2 loses internal rotation
    /// and extension).
    pub head_angular_drag_nm_s_per_rad: f64,
    /// Where the atlanto-occipital pivot lies in the head: degrees behind
    /// straight down from the head centre, towards the occiput. It sets the
    /// head lever (CARDINAL_MOVEMENTS.md, flexion). 15 deg: an engineering
    /// choice, no measurement found (carus_anatomy::fetus::AtlantoOccipitalPlacement).
    pub atlanto_occipital_behind_deg: f64,
    /// How far inside the skull base the pivot lies, as a fraction of the
    /// centre-to-surface distance on that ray: 0.15, an engineering choice.
    pub atlanto_occipital_depth: f64,
}

impl FetusSection {
    /// The head's pivot as the anatomy builds it.
    pub fn atlanto_occipital(&self) -> AtlantoOccipitalPlacement {
        AtlantoOccipitalPlacement {
            behind_vertical_deg: self.atlanto_occipital_behind_deg,
            depth: self.atlanto_occipital_depth,
        }
    }
}

impl Default for FetusSection {
    fn default() -> Self {
        FetusSection {
            density_kg_per_m3: 1050.0,
            trunk_linear_drag_n_s_per_m: 3000.0,
            trunk_angular_drag_nm_s_per_rad: 3.0,
            head_linear_drag_n_s_per_m: 1000.0,
            head_angular_drag_nm_s_per_rad: 0.5,
            atlanto_occipital_behind_deg: AtlantoOccipitalPlacement::default().behind_vertical_deg,
            atlanto_occipital_depth: AtlantoOccipitalPlacement::default().depth,
        }
    }
}

/// `[floor]`: the TLED pelvic floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FloorSection {
    pub enabled: bool,
    /// Neo-Hookean shear modulus, Pa: 16.5 kPa, the levator ani's shear
    /// modulus at rest measured in vivo by shear-wave elastography (mean of
    /// the right, 16.0 kPa, and left, 17.1 kPa, sides in 12 parous women;
    /// Gachon et al. 2019, Int Urogynecol J 30(7), "In vivo assessment of
    /// the levator ani muscles using shear wave elastography"). The same
    /// study measured 35.4 / 37.6 kPa during a Valsalva manoeuvre (the
    /// pushing of the second stage); docs/LABOUR.md gives the outcome there.
    /// Taken from non-pregnant women: the levator's stiffness did not change
    /// significantly through pregnancy in 59 nulliparous women (Davidson,
    /// Nielsen, Taberner & Kruger 2020, Int Urogynecol J 31(11), elastometry).
    pub shear_modulus_pa: f64,
    /// Bulk modulus, Pa: 20 x shear (nearly incompressible, nu about 0.475; numerical).
    pub bulk_modulus_pa: f64,
    /// Density of the floor, kg/m^3: skeletal muscle, 1060 (the top of
    /// ICRP 23 reference man's 1040-1060 for muscle, as the fetus's
    /// density cites). It sets the floor's mass and so its critical
    /// step; under the quasi-static push its inertia is small.
    pub density_kg_per_m3: f64,
    /// Mass-proportional damping, 1/s (numerical, quasi-static time compression).
    pub damping_per_s: f64,
    /// How deep inside a fetal body a floor node is still caught and put
    /// back on its surface, mm (carus-contact's `TissueContact` reach).
    /// Numerical: the body approaches tissue by at most its speed times the
    /// rigid step, about 0.06 mm (120 N against the head's 1000 N s/m drag,
    /// 0.5 ms); 1 mm is about sixteen times that. A node found deeper did not meet
    /// the surface: it got behind it when the thinned floor snapped round
    /// the head, and putting it on the near surface would flatten its
    /// element through its thickness (the inverted elements of
    /// docs/LABOUR.md). Such a node is left free until it comes out.
    pub coupling_reach_mm: f64,
    /// How the floor's nodes are held where the fetus or the bone meets
    /// them. `sliding` (the default): frictionless contact, a node held only
    /// along the surface's normal and free to slide along it, and only the
    /// normal part of its reaction acting on the fetus (a frictionless
    /// interface carries normal traction only, Johnson 1985, "Contact
    /// Mechanics", ch. 1; the fetal scalp on the amniotic-fluid-wetted
    /// vaginal wall and levator, docs/LABOUR.md). `held`: a node held in
    /// all three directions where it was put and its whole reaction acting
    /// on the fetus, as every run before the nineteenth session was.
    pub coupling: FloorCoupling,
    /// Volume ratio J below which a floor element counts as crushed, and the
    /// fetus lets go of its nodes (0 never lets go); an element with a
    /// corner turned inside out (scaled Jacobian below 0) counts as crushed
    /// whatever its J, a sliver the centre's J cannot see (docs/LABOUR.md,
    /// tenth session). Numerical, from the
    /// tissue's near-incompressibility: with the bulk modulus 20 x the shear
    /// (nu about 0.475) an element that has lost half its volume is not
    /// deforming but being crushed between the fetus and bone, which a layer
    /// one element thick cannot represent (real tissue is squeezed out
    /// sideways). Let go, the fetus passes over the tissue instead of
    /// flattening it until it turns inside out (docs/LABOUR.md).
    pub crushed_volume_ratio: f64,
    /// Hourglass control of the floor's one-point H8 elements (the
    /// Flanagan-Belytschko stiffness of DESIGN.md), NiftySim's HGKappa; 0
    /// switches it off. 0.075, the solver's default, with which it passes
    /// docs/VALIDATION.md V3. Numerical; the floor's corners turn inside
    /// out (`floor_inverted_corner_elements`) through the modes it resists.
    pub hourglass_coefficient: f64,
    /// The modulus that scales the hourglass stiffness (carus-fem
    /// `HourglassModulus`): `dilatational` (lambda + 2 mu, NiftySim's
    /// scaling, which every labour run since the first was measured with)
    /// or `shear` (2 mu, the solver's default for nearly incompressible
    /// solids; with the bulk modulus 20 x the shear, about 11 times softer).
    pub hourglass_modulus: carus_fem::HourglassModulus,
    /// Shape and resolution of the mesh (carus-anatomy FloorParameters).
    /// Keys left out of `[floor.mesh]` take this section's default, not
    /// the library's finer one (48 x 8 x 2, four times the elements).
    #[serde(deserialize_with = "floor_mesh_over_default")]
    pub mesh: FloorParameters,
}

/// `[floor.mesh]` as given, over [`FloorSection`]'s default mesh.
fn floor_mesh_over_default<'de, D: Deserializer<'de>>(d: D) -> Result<FloorParameters, D::Error> {
    floor_mesh_from(toml::Table::deserialize(d)?).map_err(D::Error::custom)
}

/// A floor mesh from the keys of `given` over the built-in scenarios'
/// (32 x 6 x 1 elements): the floor a run builds where a file leaves a key
/// out. Unknown keys are refused.
pub fn floor_mesh_from(given: toml::Table) -> Result<FloorParameters, toml::de::Error> {
    let mut merged = toml::Table::try_from(FloorSection::default().mesh).expect("a floor mesh is a table of numbers");
    merged.extend(given);
    FloorParameters::deserialize(toml::Value::Table(merged))
}

impl Default for FloorSection {
    fn default() -> Self {
        FloorSection {
            enabled: true,
            shear_modulus_pa: 16.5e3,
            bulk_modulus_pa: 330e3,
            density_kg_per_m3: 1060.0,
            damping_per_s: 400.0,
            coupling_reach_mm: 1.0,
            coupling: FloorCoupling::Sliding,
            crushed_volume_ratio: 0.5,
            hourglass_coefficient: 0.075,
            hourglass_modulus: carus_fem::HourglassModulus::Dilatational,
            mesh: FloorParameters {
                elements_around: 32,
                elements_across: 6,
                elements_through: 1,
                ..FloorParameters::default()
            },
        }
    }
}

/// `[floor] coupling`: how floor nodes are held on the fetus and the bone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FloorCoupling {
    /// Along the normal only, sliding freely (frictionless).
    Sliding,
    /// In all three directions where the node was put.
    Held,
}

/// `[numerics]`: numerical settings (none should shape the outcome beyond accuracy).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NumericsSection {
    /// Rigid-body step, s: 0.5 ms. Contact stability (docs/CONTACT.md):
    /// a head wedged at the outlet is held by contacts of about 6e5 N/m
    /// summed, which puts a 1 ms step past the stable limit, and its
    /// contact forces then alternate every step; at 0.5 ms they do not,
    /// and 0.25 ms arrests it within 1 mm of the same station
    /// (docs/LABOUR.md, twelfth session).
    pub rigid_dt_s: f64,
    /// Simulated time at which the run ends, s.
    pub end_time_s: f64,
    /// Stop early once the fetus is born: the trunk's centre 30 mm past the
    /// outlet plane (without a trunk, the head's centre 80 mm past it),
    /// seen at a pose sample, so that the history ends on the state the
    /// run stops in.
    pub stop_when_delivered: bool,
    /// Geodesic subdivisions of the head surface (3-6).
    pub head_subdivisions: u32,
    /// Largest TLED sub-step as a fraction of the floor's critical step
    /// (numerical: below 1 for the margin the critical-step estimate lacks,
    /// docs/LABOUR.md).
    pub floor_step_fraction: f64,
    /// Simulated seconds between checkpoints.
    pub checkpoint_every_s: f64,
}

impl Default for NumericsSection {
    fn default() -> Self {
        NumericsSection {
            rigid_dt_s: 5e-4,
            end_time_s: 60.0,
            stop_when_delivered: true,
            head_subdivisions: 4,
            floor_step_fraction: 0.8,
            checkpoint_every_s: 5.0,
        }
    }
}

/// `[output]`: what is recorded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSection {
    /// Pose-history sample interval, s. Fine enough for the detector to
    /// place the fastest movement within its station windows: in these
    /// time-compressed runs the head can pass the outlet, turning and
    /// extending, in 0.2-0.3 s, its station moving 8 mm in 0.1 s, and at
    /// 0.1 s the verdict on internal rotation (by +50 mm) turned on where
    /// the samples fell (docs/LABOUR.md, twentieth session).
    pub every_s: f64,
    /// Write ParaView series (VTU/PVD).
    pub vtu: bool,
    /// Interval of VTU frames, s.
    pub vtu_every_s: f64,
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            every_s: 0.01,
            vtu: true,
            vtu_every_s: 1.0,
        }
    }
}

/// A whole scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub name: String,
    #[serde(default)]
    pub description: String,
    #[serde(default, deserialize_with = "pelvis_by_key")]
    pub pelvis: PelvisSpec,
    #[serde(default)]
    pub head: HeadDiameters,
    #[serde(default)]
    pub trunk: TrunkSection,
    #[serde(default)]
    pub spine: SpineSection,
    #[serde(default)]
    pub start: StartSection,
    #[serde(default)]
    pub expulsion: ExpulsionSection,
    #[serde(default)]
    pub contact: ContactSection,
    #[serde(default)]
    /// `[neck]`: the six-degree-of-freedom spring at the atlanto-occipital
    /// pivot, REFERENCE_DATA.md (Lapeer et al. 2019 / Sadulaev 2019), with
    /// its range of motion (flexion: Ferrandini et al. 2025, MRI in labour;
    /// the other axes: Lynch-Caris et al. 2008, Öhman & Beckung 2008);
    /// docs/CONTACT.md.
    pub neck: carus_contact::NeckStiffness,
    #[serde(default)]
    pub fetus: FetusSection,
    #[serde(default)]
    pub floor: FloorSection,
    #[serde(default)]
    pub numerics: NumericsSection,
    #[serde(default)]
    pub output: OutputSection,
    /// `[trajectory]`: forward (the default), or an imposed or hybrid
    /// motion of the head through way-points (crate::trajectory).
    #[serde(default)]
    pub trajectory: TrajectorySection,
    /// Folder an imported pelvis path is relative to (the file's folder).
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The text this scenario was read from, so that a check made after
    /// reading names a key's line as reading does ([`Scenario::refuse`]);
    /// none for a built-in, whose lines no user has.
    #[serde(skip)]
    pub source: ReadFrom,
}

/// The file a scenario was read from, if any. Where a scenario was read
/// from is not what it says: two scenarios that say the same are equal, a
/// built-in and its `carus scenarios show` read back among them.
#[derive(Debug, Clone, Default)]
pub struct ReadFrom(Option<std::sync::Arc<ScenarioSource>>);

impl PartialEq for ReadFrom {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl ReadFrom {
    fn file(path: &Path, text: String) -> ReadFrom {
        ReadFrom(Some(std::sync::Arc::new(ScenarioSource { file: Some((path.to_path_buf(), text)), changed: Vec::new() })))
    }

    /// The file and line that `key` is written on, where a check made after
    /// reading should point; None for a built-in or a key changed since.
    fn locate(&self, key: &str) -> Option<(&Path, Option<NonZeroUsize>)> {
        let read = self.0.as_deref().filter(|read| !read.changed(key))?;
        let (path, text) = read.file.as_ref()?;
        Some((path.as_path(), line_of_key(text, key)))
    }

    /// The settings made since reading (a built-in's too), key and value
    /// as given, in the order made.
    fn settings(&self) -> &[(String, String)] {
        self.0.as_deref().map_or(&[], |read| &read.changed)
    }

    /// This source with `settings` made since; a key set again (a sweep's
    /// value over the one its file was mended with) keeps its last value.
    fn with_changed(&self, settings: &[(String, String)]) -> ReadFrom {
        let mut source = self.0.as_deref().cloned().unwrap_or(ScenarioSource { file: None, changed: Vec::new() });
        for (key, value) in settings {
            source.changed.retain(|(earlier, _)| !holds_key(key, earlier));
            source.changed.push((key.clone(), value.clone()));
        }
        ReadFrom(Some(std::sync::Arc::new(source)))
    }
}

#[cfg(test)]
impl Scenario {
    /// This scenario as a user's file `name` would give it, and the line
    /// there that begins `written` (`station_mm = 60`), for tests of the
    /// messages that point into a file.
    pub(crate) fn as_read_from(&self, name: &str, written: &str) -> (Scenario, usize) {
        let text = self.to_toml().unwrap();
        let line = text.lines().position(|l| l.starts_with(written)).expect("the key is written") + 1;
        (Scenario::parse(Path::new(name), &text, ".".into()).unwrap(), line)
    }
}

/// A scenario file's name and text (none for a built-in), and the keys
/// changed since it was read (`--set`, a sweep) with their values: their
/// lines in the file no longer hold them, and a check refusing another
/// key names them as what changed.
#[derive(Debug, Clone)]
pub struct ScenarioSource {
    file: Option<(PathBuf, String)>,
    changed: Vec<(String, String)>,
}

impl ScenarioSource {
    /// Whether `key` (`trajectory.waypoints[2].theta_deg`) was changed
    /// since reading: it, or a table or list holding it.
    fn changed(&self, key: &str) -> bool {
        self.changed.iter().any(|(c, _)| holds_key(c, key))
    }
}

/// Reads `[pelvis]` key by key, so that a mistake in it is reported at the
/// key's own line and dotted path as in every other table: `PelvisSpec`'s
/// own reader takes the table whole, which keeps neither.
fn pelvis_by_key<'de, D: Deserializer<'de>>(deserializer: D) -> Result<PelvisSpec, D::Error> {
    struct PelvisTable;
    impl<'de> Visitor<'de> for PelvisTable {
        type Value = PelvisSpec;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a table of pelvic diameters, or `import` naming a landmarks file or a built-in pelvis")
        }

        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<PelvisSpec, A::Error> {
            // The keys in the order `carus scenarios show` writes them.
            let written = toml::to_string(&PelvisDiameters::default()).map_err(A::Error::custom)?;
            let mut keys = PelvisKeys {
                map,
                diameters: written.lines().filter_map(|l| Some(l.split_once(" = ")?.0.to_string())).collect(),
                import: None,
                first_diameter: None,
            };
            let given = PelvisDiameters::deserialize(MapAccessDeserializer::new(&mut keys))?;
            Ok(match keys.import {
                Some(landmarks_file) => PelvisSpec::Imported { landmarks_file },
                None => PelvisSpec::Generated(given),
            })
        }
    }
    deserializer.deserialize_map(PelvisTable)
}

/// `[pelvis]` as the diameters read it, with `import` taken out on the way.
struct PelvisKeys<A> {
    map: A,
    diameters: Vec<String>,
    import: Option<PathBuf>,
    first_diameter: Option<String>,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for PelvisKeys<A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, A::Error> {
        while let Some(key) = self.map.next_key_seed(PelvisKey {
            diameters: &self.diameters,
            import: self.import.is_some(),
            first_diameter: self.first_diameter.as_deref(),
        })? {
            if key == "import" {
                self.import = Some(self.map.next_value()?);
            } else {
                self.first_diameter.get_or_insert_with(|| key.clone());
                return seed.deserialize(IntoDeserializer::<A::Error>::into_deserializer(key)).map(Some);
            }
        }
        Ok(None)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.map.next_value_seed(seed)
    }
}

/// One key of `[pelvis]`, checked while toml still knows its line.
struct PelvisKey<'a> {
    diameters: &'a [String],
    import: bool,
    first_diameter: Option<&'a str>,
}

impl<'de> DeserializeSeed<'de> for PelvisKey<'_> {
    type Value = String;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<String, D::Error> {
        let key = String::deserialize(deserializer)?;
        let clash = |diameter: &str| {
            D::Error::custom(format!(
                "`import` and `{diameter}` cannot be combined: an imported pelvis takes its diameters from its \
                 landmarks; remove one (from the command line, `--set 'pelvis={{{diameter}=...}}'` puts a \
                 generated pelvis in place of the whole [pelvis] table)"
            ))
        };
        if key == "import" {
            return self.first_diameter.map_or(Ok(key), |d| Err(clash(d)));
        }
        if !self.diameters.contains(&key) {
            let expected: Vec<String> = self.diameters.iter().map(|k| format!("`{k}`")).collect();
            return Err(D::Error::custom(format!(
                "unknown field `{key}`, expected one of {}, or `import` alone for a real pelvis",
                expected.join(", ")
            )));
        }
        if self.import {
            return Err(clash(&key));
        }
        Ok(key)
    }
}

/// The built-in scenarios, embedded in the binary: (name, TOML text).
pub const BUILTINS: [(&str, &str); 8] = [
    ("normal", include_str!("../../../scenarios/normal.toml")),
    (
        "normal-dry",
        include_str!("../../../scenarios/normal-dry.toml"),
    ),
    (
        "real-pelvis",
        include_str!("../../../scenarios/real-pelvis.toml"),
    ),
    (
        "contracted-inlet",
        include_str!("../../../scenarios/contracted-inlet.toml"),
    ),
    ("face", include_str!("../../../scenarios/face.toml")),
    (
        "occiput-posterior",
        include_str!("../../../scenarios/occiput-posterior.toml"),
    ),
    (
        "large-shoulders",
        include_str!("../../../scenarios/large-shoulders.toml"),
    ),
    ("textbook", include_str!("../../../scenarios/textbook.toml")),
];

impl Scenario {
    /// A built-in scenario by name.
    pub fn builtin(name: &str) -> Result<Scenario, ScenarioError> {
        let (_, text) = BUILTINS
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| ScenarioError::UnknownBuiltin(name.into()))?;
        let scenario = Scenario::parse(
            Path::new(&format!("<built-in {name}>")),
            text,
            PathBuf::from("."),
        )?;
        Ok(Scenario { source: ReadFrom::default(), ..scenario })
    }

    /// Reads a scenario file.
    pub fn from_file(path: &Path) -> Result<Scenario, ScenarioError> {
        let (text, base) = Scenario::read_file(path)?;
        Scenario::parse(path, &text, base)
    }

    /// Reads a scenario file with each (key, value) change of
    /// [`Self::with_settings`] made before it is checked, so that a
    /// setting can mend a value the file has wrong; what else the file has
    /// wrong is still named at its line.
    pub fn from_file_with_settings(path: &Path, settings: &[(String, String)]) -> Result<Scenario, ScenarioError> {
        let (text, base) = Scenario::read_file(path)?;
        let table = text.parse::<toml::Table>().map_err(|e| toml_syntax(path, &text, &e))?;
        let source = ReadFrom::file(path, text);
        let name = table.get("name").and_then(toml::Value::as_str).unwrap_or("the scenario").to_string();
        Scenario::changed_table(table, settings, &name, base, source, false)
    }

    /// A scenario file's text, and the absolute folder it lies in.
    fn read_file(path: &Path) -> Result<(String, PathBuf), ScenarioError> {
        let text = carus_io::input::read_text(path).map_err(|source| ScenarioError::Io {
            path: path.to_path_buf(),
            source: match source.kind() {
                _ if path.is_dir() => std::io::Error::other(match path.join(crate::output::SCENARIO_FILE).is_file() {
                    true => format!(
                        "a folder, a run's by its look: `carus run --resume {0}` continues a run stopped part \
                         way, `carus view {0}` replays it, and `carus run {1} --out NEW_FOLDER` runs its \
                         scenario again",
                        path.display(),
                        path.join(crate::output::SCENARIO_FILE).display()
                    ),
                    false => "a folder, not a scenario file; give a scenario's TOML file or a built-in's name \
                              (`carus scenarios` lists them)"
                        .into(),
                }),
                std::io::ErrorKind::InvalidData => std::io::Error::new(
                    source.kind(),
                    "not a text file (UTF-8); a scenario is a TOML text file: `carus scenarios show normal \
                     > mine.toml` writes one",
                ),
                _ => source,
            },
        })?;
        // Absolute, so that a run resumed or measured from another folder
        // still finds an imported pelvis.
        let absolute = std::path::absolute(path).map_err(|source| ScenarioError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let base = absolute.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok((text, base))
    }

    /// Parses and checks the scenario text that the file `holder` keeps (a
    /// checkpoint, a sweep plan): errors name it as that text, whose lines
    /// they count, not the holder's.
    pub fn parse_kept(holder: &Path, text: &str, base_dir: PathBuf) -> Result<Scenario, ScenarioError> {
        Scenario::parse(&PathBuf::from(format!("{} (the scenario it keeps)", holder.display())), text, base_dir)
    }

    /// Parses and checks scenario text; `path` names it in errors.
    pub fn parse(path: &Path, text: &str, base_dir: PathBuf) -> Result<Scenario, ScenarioError> {
        let deserializer = toml::Deserializer::parse(text).map_err(|e| toml_syntax(path, text, &e))?;
        // A landmarks file never reads as a scenario: looked for only then.
        let mut scenario: Scenario = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let another_kind = text.parse::<toml::Table>().ok().and_then(|t| {
                check_not_landmarks_file(path, text, &t)
                    .and_then(|()| check_not_solve_job(path, &t))
                    .and_then(|()| check_not_anatomy_file(path, &t))
                    .err()
            });
            another_kind.unwrap_or_else(|| syntax(path, text, e.path().to_string(), e.inner()))
        })?;
        scenario.base_dir = base_dir;
        scenario.check_at_lines(path, text)?;
        check_pelvis_import(path, text, &scenario.pelvis, &scenario.base_dir)?;
        scenario.source = ReadFrom::file(path, text.to_string());
        Ok(scenario)
    }

    /// Refuses `key` = `value` for a reason found after reading (the start
    /// against the bony canal, a joint against the step): at the key's
    /// line when the scenario was read from a file and the key is as the
    /// file writes it; named as a setting otherwise (a built-in, a changed
    /// key).
    pub(crate) fn refuse(&self, key: String, value: String, problem: String, hint: String) -> ScenarioError {
        // Settings of other keys (a larger head) can make a value the
        // scenario has (its start) fail: they are named with it, for the
        // user changed those, not this one.
        let made = self.source.settings();
        let with = made.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ");
        match self.source.locate(&key) {
            Some((path, line)) => ScenarioError::Value {
                path: path.into(),
                line,
                key: key.into(),
                value: match line {
                    Some(_) => value,
                    None => format!("{value} (the default: the file does not set it)"),
                },
                problem: match made.is_empty() {
                    true => problem,
                    false => format!("with {with} set, {problem}"),
                },
                hint,
            },
            None if made.is_empty() || made.iter().any(|(k, _)| holds_key(k, &key)) => ScenarioError::Setting {
                setting: format!("{key} = {value}"),
                problem,
                hint,
            },
            None => ScenarioError::Setting {
                setting: with,
                problem: format!("then `{key}` = {value}, the scenario's own value: {problem}"),
                hint,
            },
        }
    }

    /// `file:line: ` where a check made after reading should point for
    /// `key`, as [`Self::refuse`] chooses; empty where it names a setting.
    pub(crate) fn located_key(&self, key: &str) -> String {
        self.source.locate(key).map_or(String::new(), |(path, line)| format!("{}: ", located(path, line)))
    }

    /// The scenario as a complete TOML file (every key explicit), as a run
    /// folder keeps it ([`Self::kept`]).
    pub fn to_toml(&self) -> Result<String, ScenarioError> {
        let mut text = String::new();
        if !self.description.is_empty() {
            text.push_str(&format!("# {}\n", self.description));
        }
        text.push_str("# Every key is written out; units are in the key names (CONVENTIONS.md).\n");
        text.push_str(&toml::to_string(&self.kept())?);
        Ok(text)
    }

    /// The scenario as a run keeps it, readable from anywhere: an imported
    /// pelvis's file named by its absolute path when the scenario came from
    /// a file (the path it gave is relative to that file's folder, which
    /// the run's record does not keep); a built-in pelvis keeps its name.
    pub fn kept(&self) -> Scenario {
        match &self.pelvis {
            PelvisSpec::Imported { landmarks_file }
                if landmarks_file.as_os_str() != VISIBLE_HUMAN_FEMALE && self.base_dir.is_absolute() =>
            {
                let pelvis = PelvisSpec::Imported { landmarks_file: self.base_dir.join(landmarks_file) };
                Scenario { pelvis, ..self.clone() }
            }
            _ => self.clone(),
        }
    }

    /// This scenario with each (key, value) change of
    /// [`Self::with_setting`] made, then checked once as a file would be,
    /// so that keys which must agree (a mode and its way-points) can
    /// change together.
    pub fn with_settings(&self, settings: &[(String, String)]) -> Result<Scenario, ScenarioError> {
        if settings.is_empty() {
            return Ok(self.clone());
        }
        for (k, (key, value)) in settings.iter().enumerate() {
            if let Some((_, first)) = settings[..k].iter().find(|(earlier, _)| earlier == key) {
                return Err(ScenarioError::Setting {
                    setting: format!("{key} = {first}, {key} = {value}"),
                    problem: format!("{key} is given twice"),
                    hint: "give each key once".into(),
                });
            }
        }
        let table = toml::Table::try_from(self)?;
        Scenario::changed_table(table, settings, &self.name, self.base_dir.clone(), self.source.clone(), true)
    }

    /// `table` with the settings made, checked as a file would be; `source`
    /// is the file it was read from, which later checks point into, not at
    /// a changed key. `checked_before`: the table is of a scenario that
    /// passed its checks, so whatever they now refuse the settings did.
    fn changed_table(
        mut table: toml::Table,
        settings: &[(String, String)],
        name: &str,
        base_dir: PathBuf,
        source: ReadFrom,
        checked_before: bool,
    ) -> Result<Scenario, ScenarioError> {
        for (key, value) in settings {
            set_key(&mut table, key, value)?;
        }
        let written: Vec<String> = settings.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let label = PathBuf::from(format!("{name} with {}", written.join(", ")));
        let text = toml::to_string(&table)?;
        // Line numbers would point into the generated text: name the
        // settings instead, or the file's line of a key they did not change.
        let in_file = |key: &str| source.locate(key).filter(|_| !settings.iter().any(|(k, _)| k == key));
        let changed = Scenario::parse(&label, &text, base_dir).map_err(|e| match e {
            ScenarioError::Syntax {
                key, message, hint, ..
            } => {
                // The setting at fault alone, not every one given.
                let faulty = key.trim_end_matches(": ").trim_matches('`');
                let setting = setting_at_fault(settings, faulty).map_or_else(|| written.join(", "), |(k, v)| format!("{k} = {v}"));
                ScenarioError::Setting { setting, problem: format!("{key}{message}"), hint }
            }
            // A value a setting gave that the checks refuse is that
            // setting's fault, as an unknown key is (a bad argument); so is
            // another key's, refused through it, in a scenario that passed.
            ScenarioError::Value { key, value, problem, hint, .. } if settings.iter().any(|(k, _)| *k == key) => {
                ScenarioError::Setting { setting: format!("{key} = {value}"), problem, hint }
            }
            ScenarioError::Value { key, value, problem, hint, .. } if checked_before => ScenarioError::Setting {
                setting: written.join(", "),
                problem: format!("then `{key}` = {value}: {problem}"),
                hint,
            },
            mut other => {
                if let ScenarioError::Value { path, line, key, .. } = &mut other {
                    match in_file(key) {
                        Some((file, at)) => (*path, *line) = (file.into(), at),
                        None => *line = None,
                    }
                }
                other
            }
        })?;
        // Later checks still point into the file read, but not at a changed
        // key, and name the settings made.
        let source = source.with_changed(settings);
        // The description was written for the scenario as it was: it says
        // what changed, so that a copy in a run folder or a report does
        // not describe the unchanged one (an imposed teaching run set to
        // forward, say).
        let description = match settings.iter().any(|(key, _)| key == "description") {
            true => changed.description.clone(),
            false => format!("{} (changed: {})", changed.description, written.join(", ")),
        };
        Ok(Scenario { source, description, ..changed })
    }

    /// This scenario with one key changed: `key` is a dotted path as `carus
    /// scenarios show` writes it (`expulsion.period_s`), `value` TOML text
    /// (`32.0`, `true`, `"pivot"`; a bare word is taken as a string). The
    /// result is checked as a file would be, so an unknown key or an
    /// impossible value is refused with the key named.
    pub fn with_setting(&self, key: &str, value: &str) -> Result<Scenario, ScenarioError> {
        self.with_settings(&[(key.to_string(), value.to_string())])
    }

    /// [`Self::check`], a refused value named at its line of `text`.
    fn check_at_lines(&self, path: &Path, text: &str) -> Result<(), ScenarioError> {
        self.check(path).map_err(|mut e| {
            if let ScenarioError::Value { line, key, .. } = &mut e {
                *line = line_of_key(text, key);
            }
            e
        })
    }

    /// The checks a scenario's `[pelvis]`, `[head]` and `[trunk]` get (a
    /// value in another unit, a size no pelvis or fetus has), for an anatomy file,
    /// which has those tables without the rest of a scenario: `carus
    /// measure`, `mesh` and `render` refuse what `carus run` refuses, at
    /// the same line.
    pub fn check_anatomy_tables(
        path: &Path,
        text: &str,
        pelvis: &PelvisSpec,
        head: &HeadDiameters,
        trunk: &TrunkDiameters,
    ) -> Result<(), ScenarioError> {
        let scenario = Scenario {
            pelvis: pelvis.clone(),
            head: *head,
            trunk: TrunkSection::with_diameters(trunk),
            ..Scenario::builtin("normal")?
        };
        scenario.check_at_lines(path, text)
    }

    /// Impossible values, named by their key with a hint.
    fn check(&self, path: &Path) -> Result<(), ScenarioError> {
        let err = |key: &'static str, value: f64, problem: &str, hint: &str| ScenarioError::Value {
            path: path.into(),
            line: None,
            key: key.into(),
            value: shown(value),
            problem: problem.into(),
            hint: hint.into(),
        };
        let positive: [(&'static str, f64, &str); 22] = [
            (
                "trunk.bisacromial_mm",
                self.trunk.bisacromial_mm,
                "a diameter in mm, e.g. 120.0",
            ),
            (
                "trunk.chest_breadth_mm",
                self.trunk.chest_breadth_mm,
                "a breadth in mm, e.g. 108.0",
            ),
            (
                "trunk.bitrochanteric_mm",
                self.trunk.bitrochanteric_mm,
                "a diameter in mm, e.g. 95.0",
            ),
            (
                "trunk.cervical_spine_mm",
                self.trunk.cervical_spine_mm,
                "a length in mm, e.g. 37.0",
            ),
            (
                "trunk.trunk_length_mm",
                self.trunk.trunk_length_mm,
                "a length in mm, e.g. 186.0",
            ),
            (
                "expulsion.period_s",
                self.expulsion.period_s,
                "seconds per contraction, e.g. 8.0",
            ),
            (
                "contact.penalty_stiffness_pa_per_m",
                self.contact.penalty_stiffness_pa_per_m,
                "Pa/m, e.g. 9.4e8",
            ),
            (
                "contact.sample_spacing_mm",
                self.contact.sample_spacing_mm,
                "mm between contact samples, e.g. 4.0",
            ),
            (
                "contact.trunk_penalty_stiffness_pa_per_m",
                self.contact.trunk_penalty_stiffness_pa_per_m,
                "Pa/m, e.g. 1.0e7 (the default)",
            ),
            (
                "contact.trunk_cover_depth_mm",
                self.contact.trunk_cover_depth_mm,
                "mm of soft tissue over the trunk's skeleton, e.g. 6.0",
            ),
            (
                "fetus.density_kg_per_m3",
                self.fetus.density_kg_per_m3,
                "kg/m^3, e.g. 1050.0",
            ),
            (
                "floor.shear_modulus_pa",
                self.floor.shear_modulus_pa,
                "Pa (not kPa), e.g. 16500.0",
            ),
            (
                "floor.coupling_reach_mm",
                self.floor.coupling_reach_mm,
                "mm, e.g. 1.0",
            ),
            (
                "floor.bulk_modulus_pa",
                self.floor.bulk_modulus_pa,
                "Pa, larger than the shear modulus",
            ),
            (
                "floor.density_kg_per_m3",
                self.floor.density_kg_per_m3,
                "kg/m^3, e.g. 1060.0",
            ),
            (
                "numerics.rigid_dt_s",
                self.numerics.rigid_dt_s,
                "seconds, e.g. 5e-4",
            ),
            (
                "numerics.end_time_s",
                self.numerics.end_time_s,
                "seconds of simulated time, e.g. 60.0",
            ),
            (
                "numerics.floor_step_fraction",
                self.numerics.floor_step_fraction,
                "a fraction of the critical step, at most 1",
            ),
            (
                "numerics.checkpoint_every_s",
                self.numerics.checkpoint_every_s,
                "seconds of simulated time, e.g. 5.0",
            ),
            (
                "output.every_s",
                self.output.every_s,
                "seconds between samples, e.g. 0.01 (the default)",
            ),
            (
                "output.vtu_every_s",
                self.output.vtu_every_s,
                "seconds between VTU frames, e.g. 1.0",
            ),
            (
                "expulsion.force_max_n",
                self.expulsion.force_max_n,
                "newtons, e.g. 120.0 (REFERENCE_DATA.md: 70-140 N)",
            ),
        ];
        for (key, value, hint) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(err(key, value, "must be a positive, finite number", hint));
            }
        }
        // A joint's angles are read within a half turn, so a limit past it is
        // never reached: most likely degrees mistaken for something else.
        let angle_limits = [
            ("neck.flexion_limit_deg", self.neck.flexion_limit_deg),
            ("neck.extension_limit_deg", self.neck.extension_limit_deg),
            ("neck.lateral_bending_limit_deg", self.neck.lateral_bending_limit_deg),
            ("neck.axial_rotation_limit_deg", self.neck.axial_rotation_limit_deg),
            ("spine.bending_limit_deg", self.spine.bending_limit_deg),
            ("spine.axial_rotation_limit_deg", self.spine.axial_rotation_limit_deg),
        ];
        for (key, value) in [
            ("contact.friction", self.contact.friction),
            ("contact.damping_time_s", self.contact.damping_time_s),
            ("fetus.trunk_linear_drag_n_s_per_m", self.fetus.trunk_linear_drag_n_s_per_m),
            (
                "fetus.trunk_angular_drag_nm_s_per_rad",
                self.fetus.trunk_angular_drag_nm_s_per_rad,
            ),
            (
                "fetus.head_linear_drag_n_s_per_m",
                self.fetus.head_linear_drag_n_s_per_m,
            ),
            (
                "fetus.head_angular_drag_nm_s_per_rad",
                self.fetus.head_angular_drag_nm_s_per_rad,
            ),
            ("floor.damping_per_s", self.floor.damping_per_s),
            ("floor.hourglass_coefficient", self.floor.hourglass_coefficient),
            ("neck.flexion_nm_per_deg", self.neck.flexion_nm_per_deg),
            ("neck.extension_nm_per_deg", self.neck.extension_nm_per_deg),
            (
                "neck.lateral_bending_nm_per_deg",
                self.neck.lateral_bending_nm_per_deg,
            ),
            (
                "neck.axial_rotation_nm_per_deg",
                self.neck.axial_rotation_nm_per_deg,
            ),
            ("neck.compression_n_per_m", self.neck.compression_n_per_m),
            ("neck.compression_limit_mm", self.neck.compression_limit_mm),
            (
                "neck.end_range_compression_n_per_m",
                self.neck.end_range_compression_n_per_m,
            ),
            ("neck.tension_n_per_m", self.neck.tension_n_per_m),
            ("neck.shear_n_per_m", self.neck.shear_n_per_m),
            ("neck.rotational_damping_nm_s_per_rad", self.neck.rotational_damping_nm_s_per_rad),
            ("neck.linear_damping_n_s_per_m", self.neck.linear_damping_n_s_per_m),
            (
                "neck.end_range_stiffness_nm_per_deg",
                self.neck.end_range_stiffness_nm_per_deg,
            ),
            ("spine.bending_nm_per_deg", self.spine.bending_nm_per_deg),
            ("spine.axial_rotation_nm_per_deg", self.spine.axial_rotation_nm_per_deg),
            (
                "spine.end_range_stiffness_nm_per_deg",
                self.spine.end_range_stiffness_nm_per_deg,
            ),
            ("spine.joint_stiffness_n_per_m", self.spine.joint_stiffness_n_per_m),
            (
                "spine.rotational_damping_nm_s_per_rad",
                self.spine.rotational_damping_nm_s_per_rad,
            ),
            ("spine.linear_damping_n_s_per_m", self.spine.linear_damping_n_s_per_m),
        ]
        .into_iter()
        .chain(angle_limits)
        {
            if !(value.is_finite() && value >= 0.0) {
                return Err(err(
                    key,
                    value,
                    "must be zero or more and finite",
                    "a non-negative number in the key's unit",
                ));
            }
        }
        for (key, value) in angle_limits {
            if value > 180.0 {
                return Err(err(
                    key,
                    value,
                    "is past a half turn, which no joint angle reaches, so the limit would never act",
                    "degrees from 0 to 180; `carus scenarios show normal` gives the defaults",
                ));
            }
        }
        let crushed = self.floor.crushed_volume_ratio;
        if !(crushed.is_finite() && (0.0..1.0).contains(&crushed)) {
            return Err(err(
                "floor.crushed_volume_ratio",
                crushed,
                "must be at least 0 and below 1",
                "a volume ratio J, e.g. 0.5 (0 never lets go)",
            ));
        }
        // Soft tissue in the canal's wall, as a share of the bone's stiffness.
        for (key, ratio, example) in [
            ("contact.ligament_stiffness_ratio", self.contact.ligament_stiffness_ratio, ", 0.03 about a ligament's give (docs/LABOUR.md)"),
            ("contact.soft_wall_stiffness_ratio", self.contact.soft_wall_stiffness_ratio, ""),
        ] {
            if !(ratio > 0.0 && ratio <= 1.0) {
                return Err(err(
                    key,
                    ratio,
                    "must be above 0 and at most 1",
                    &format!("a share of the bone's stiffness: 1 (the default) is as rigid as bone{example}"),
                ));
            }
        }
        if self.contact.friction > 2.0 {
            return Err(err(
                "contact.friction",
                self.contact.friction,
                "is not a plausible Coulomb coefficient",
                "0 to 2; REFERENCE_DATA.md: 0.35 (muscle on bone), 0.009 (wetted tissue)",
            ));
        }
        if self.expulsion.force_min_n > self.expulsion.force_max_n
            || !self.expulsion.force_min_n.is_finite()
        {
            return Err(err(
                "expulsion.force_min_n",
                self.expulsion.force_min_n,
                "must not exceed force_max_n",
                "the force between contractions, e.g. 0.0 or -10.0",
            ));
        }
        if self.expulsion.force_min_n < -2000.0 {
            return Err(err(
                "expulsion.force_min_n",
                self.expulsion.force_min_n,
                "is far beyond any pull back between contractions",
                "newtons (not mN): 0.0, or a few newtons below it to let the fetus slide back",
            ));
        }
        if self.expulsion.force_max_n > 2000.0 {
            return Err(err(
                "expulsion.force_max_n",
                self.expulsion.force_max_n,
                "is far above any expulsive force",
                "newtons (not mN): REFERENCE_DATA.md gives 70-140 N",
            ));
        }
        // Plausibility bands: values that would run but are in another unit.
        let in_band = |values: &[(&'static str, f64)], (least, most): (f64, f64), problem: &str, hint: &str| {
            match values.iter().find(|(_, v)| !(least..=most).contains(v)) {
                // The band itself, so that a value just outside is told where.
                Some(&(key, value)) => Err(err(key, value, &format!("{problem} (the band taken is {least} to {most})"), hint)),
                None => Ok(()),
            }
        };
        in_band(
            &[("contact.trunk_cover_depth_mm", self.contact.trunk_cover_depth_mm)],
            (0.1, 30.0),
            "is not a plausible depth of soft tissue over a neonate's shoulders and chest",
            "millimetres: the default is 6.0 (docs/CONTACT.md, \"The trunk's cover\")",
        )?;
        let h = &self.head;
        in_band(
            &[
                ("head.biparietal_mm", h.biparietal_mm),
                ("head.bitemporal_mm", h.bitemporal_mm),
                ("head.occipitofrontal_mm", h.occipitofrontal_mm),
                ("head.suboccipitobregmatic_mm", h.suboccipitobregmatic_mm),
                ("head.mentovertical_mm", h.mentovertical_mm),
                ("head.submentobregmatic_mm", h.submentobregmatic_mm),
            ],
            FETAL_HEAD_DIAMETER_MM,
            "is not a diameter of a fetal head",
            "mm (not cm): the term head's biparietal is 95 mm, its mentovertical 135-140 mm",
        )?;
        if let PelvisSpec::Generated(p) = &self.pelvis {
            in_band(
                &[
                    ("pelvis.inlet_ap_mm", p.inlet_ap_mm),
                    ("pelvis.inlet_transverse_mm", p.inlet_transverse_mm),
                    ("pelvis.inlet_oblique_mm", p.inlet_oblique_mm),
                    ("pelvis.mid_ap_mm", p.mid_ap_mm),
                    ("pelvis.interspinous_mm", p.interspinous_mm),
                    ("pelvis.outlet_ap_mm", p.outlet_ap_mm),
                    ("pelvis.outlet_transverse_mm", p.outlet_transverse_mm),
                    ("pelvis.outlet_oblique_mm", p.outlet_oblique_mm),
                ],
                PELVIC_CANAL_DIAMETER_MM,
                "is not a diameter of a pelvic canal",
                "mm (not cm): the gynecoid inlet is 110 mm front to back and 130-135 mm across",
            )?;
            in_band(
                &[
                    ("pelvis.symphysis_length_mm", p.symphysis_length_mm),
                    ("pelvis.sacral_length_mm", p.sacral_length_mm),
                ],
                PELVIC_WALL_LENGTH_MM,
                "is not the length of a pelvic wall",
                "mm (not cm): REFERENCE_DATA.md gives the symphysis 40-50 mm and the sacrum 100-110 mm",
            )?;
        }
        in_band(
            &[
                ("trunk.bisacromial_mm", self.trunk.bisacromial_mm),
                ("trunk.bitrochanteric_mm", self.trunk.bitrochanteric_mm),
            ],
            FETAL_TRUNK_WIDTH_MM,
            "is not the width of a fetal trunk",
            "mm (not cm): the newborn's bisacromial is 124 +- 10 mm",
        )?;
        in_band(
            &[("trunk.chest_breadth_mm", self.trunk.chest_breadth_mm)],
            FETAL_TRUNK_WIDTH_MM,
            "is not the width of a fetal trunk",
            "mm (not cm): a term newborn's chest is about 108 mm across (322 mm round; docs/ANATOMY.md)",
        )?;
        in_band(
            &[("trunk.cervical_spine_mm", self.trunk.cervical_spine_mm)],
            FETAL_NECK_LENGTH_MM,
            "is not the length of a fetal neck",
            "mm (not cm): the newborn's cervical spine is 37 mm long",
        )?;
        in_band(
            &[("trunk.trunk_length_mm", self.trunk.trunk_length_mm)],
            FETAL_TRUNK_LENGTH_MM,
            "is not the length of a fetal trunk",
            "mm (not cm): the trunk from the neck base to the breech is about 186 mm",
        )?;
        in_band(
            &[("contact.sample_spacing_mm", self.contact.sample_spacing_mm)],
            CONTACT_SAMPLE_SPACING_MM,
            "is not a spacing of contact samples on a fetal head",
            "mm (not m): 4.0 is the default, 2.0 a refinement",
        )?;
        // Soft tissue is about as dense as water: a value near 1 is in
        // g/cm^3, and would give a fetus too light for its neck's springs.
        in_band(
            &[
                ("fetus.density_kg_per_m3", self.fetus.density_kg_per_m3),
                ("floor.density_kg_per_m3", self.floor.density_kg_per_m3),
            ],
            SOFT_TISSUE_DENSITY_KG_PER_M3,
            "is not the density of soft tissue",
            "kg/m^3 (not g/cm^3): soft tissue is about 1050",
        )?;
        if self.floor.shear_modulus_pa < FLOOR_SHEAR_MODULUS_MIN_PA {
            return Err(err(
                "floor.shear_modulus_pa",
                self.floor.shear_modulus_pa,
                "is softer than any soft tissue",
                "Pa (not kPa): the levator ani at rest measures 16.5 kPa, 16500.0",
            ));
        }
        // Stiffer than any soft tissue, the floor's stable step would be too
        // small for a run to end (water's bulk modulus is 2.2 GPa).
        for (key, value, most, hint) in [
            ("floor.shear_modulus_pa", self.floor.shear_modulus_pa, 1e7, "Pa: the levator ani at rest measures 16.5 kPa, 16500.0"),
            ("floor.bulk_modulus_pa", self.floor.bulk_modulus_pa, 1e10, "Pa, about 20 x shear_modulus_pa; water's is 2.2e9"),
        ] {
            if value > most {
                return Err(err(key, value, "is stiffer than any soft tissue", hint));
            }
        }
        if self.floor.bulk_modulus_pa <= self.floor.shear_modulus_pa {
            return Err(err(
                "floor.bulk_modulus_pa",
                self.floor.bulk_modulus_pa,
                "must exceed the shear modulus (soft tissue is nearly incompressible)",
                "e.g. 20 x shear_modulus_pa",
            ));
        }
        if self.numerics.floor_step_fraction > 1.0 {
            return Err(err(
                "numerics.floor_step_fraction",
                self.numerics.floor_step_fraction,
                "a step above the critical one is unstable",
                "0.5 to 0.9",
            ));
        }
        if self.numerics.rigid_dt_s < SMALLEST_RIGID_DT_S {
            return Err(err(
                "numerics.rigid_dt_s",
                self.numerics.rigid_dt_s,
                "is below 1e-5 s (50 times finer than the default), too small for a run to finish",
                "1e-4 to 1e-3 s; the default is 5e-4",
            ));
        }
        if self.numerics.floor_step_fraction < 0.05 {
            return Err(err(
                "numerics.floor_step_fraction",
                self.numerics.floor_step_fraction,
                "would take the floor through twenty times its needed sub-steps or more",
                "0.5 to 0.9",
            ));
        }
        if self.numerics.end_time_s > LONGEST_END_TIME_S {
            return Err(err(
                "numerics.end_time_s",
                self.numerics.end_time_s,
                "is more than an hour of labour (3600 s): a slip of units or digits (the built-in scenarios run 60 s, \
                 each some 120 000 rigid steps and a minute or two of wall time)",
                "seconds of simulated time, 3600 or less; 60.0 is the default",
            ));
        }
        if self.numerics.rigid_dt_s > 2e-3 {
            return Err(err(
                "numerics.rigid_dt_s",
                self.numerics.rigid_dt_s,
                "is above the contact's stable step (about 2 ms for the head pushed through its centre; a head wedged in the canal chatters from 1 ms, docs/CONTACT.md)",
                "1e-4 to 1e-3 s; the default is 5e-4",
            ));
        }
        if self.numerics.end_time_s < self.numerics.rigid_dt_s * (1.0 - 1e-9) {
            return Err(err(
                "numerics.end_time_s",
                self.numerics.end_time_s,
                &format!("is shorter than one rigid step (numerics.rigid_dt_s = {} s): the run would simulate nothing", self.numerics.rigid_dt_s),
                "seconds of simulated time, at least the rigid step; 60.0 is the default",
            ));
        }
        // Finer than a step records nothing new; frames far finer than the
        // motion fill a disk (each is a few hundred kB). Each interval is
        // kept to whole rigid steps (docs/SCENARIOS.md).
        for (key, every_s, finest_s, hint) in [
            ("output.every_s", self.output.every_s, self.numerics.rigid_dt_s, "at least the rigid step; 0.01 is the default"),
            ("numerics.checkpoint_every_s", self.numerics.checkpoint_every_s, self.numerics.rigid_dt_s, "at least the rigid step; 5.0 is the default"),
            ("output.vtu_every_s", self.output.vtu_every_s, MIN_VTU_EVERY_S.max(self.numerics.rigid_dt_s), "at least 0.01 s (frames every 10 ms write some 14 MB a simulated second); 1.0 is the default"),
        ] {
            if every_s < finest_s * (1.0 - 1e-9) {
                return Err(err(key, every_s, "is finer than can be recorded", hint));
            }
        }
        for (key, value, (least, most), hint) in [
            (
                "fetus.atlanto_occipital_behind_deg",
                self.fetus.atlanto_occipital_behind_deg,
                AtlantoOccipitalPlacement::BEHIND_VERTICAL_DEG,
                "degrees behind straight down from the head centre, 0 to 45; 15 is the default",
            ),
            (
                "fetus.atlanto_occipital_depth",
                self.fetus.atlanto_occipital_depth,
                AtlantoOccipitalPlacement::DEPTH,
                "a fraction of the centre-to-skull distance, 0.05 to 0.5; 0.15 is the default",
            ),
        ] {
            if !(least..=most).contains(&value) {
                return Err(err(key, value, "would not put the pivot under the skull base", hint));
            }
        }
        if !(3..=6).contains(&self.numerics.head_subdivisions) {
            return Err(err(
                "numerics.head_subdivisions",
                self.numerics.head_subdivisions as f64,
                "must be 3 to 6",
                "4 is the default",
            ));
        }
        if !self.start.station_mm.is_finite() || self.start.station_mm.abs() > 200.0 {
            return Err(err(
                "start.station_mm",
                self.start.station_mm,
                "is outside the birth canal's reach",
                "mm from the spines, e.g. -55.0 (negative above)",
            ));
        }
        if !self.start.attitude_deg.is_finite() || self.start.attitude_deg.abs() > 90.0 {
            return Err(err(
                "start.attitude_deg",
                self.start.attitude_deg,
                "is not a head attitude",
                "degrees, -90 to 90 (positive flexed)",
            ));
        }
        // A start past the neck's range would load its end stop before the
        // first step (1 N m per degree) and fling the head.
        let (flexion, extension) = (self.neck.flexion_limit_deg, self.neck.extension_limit_deg);
        if self.start.attitude_deg > flexion || self.start.attitude_deg < -extension {
            return Err(err(
                "start.attitude_deg",
                self.start.attitude_deg,
                &format!(
                    "lies outside the neck's range of motion, {extension} deg of extension to \
                     {flexion} deg of flexion (neck.extension_limit_deg, neck.flexion_limit_deg)"
                ),
                &format!("an attitude from {} to {flexion}, or widen the neck's range", -extension),
            ));
        }
        if let ExpulsionDirection::Fixed(v) = self.expulsion.direction {
            let length = glam::DVec3::from_array(v).length();
            if !(length.is_finite() && length > 1e-9) {
                return Err(ScenarioError::Value {
                    path: path.into(),
                    line: None,
                    key: "expulsion.direction".into(),
                    value: format!("{v:?}"),
                    problem: "has no direction (zero or not finite)".into(),
                    hint: "a vector in the pelvis frame, e.g. [0.0, 0.0, -1.0] down the inlet axis, or \"fetal_spine\"".into(),
                });
            }
        }
        if self.spine.enabled && !self.trunk.enabled {
            return Err(ScenarioError::Value {
                path: path.into(),
                line: None,
                key: "spine.enabled".into(),
                value: "true".into(),
                problem: "a spine that bends needs the trunk it bends".into(),
                hint: "set trunk.enabled = true, or spine.enabled = false".into(),
            });
        }
        let mentum = self.start.position.is_mentum();
        let wrong_denominator = |problem: &str, hint: &str| ScenarioError::Value {
            path: path.into(),
            line: None,
            key: "start.position".into(),
            value: format!("\"{:?}\"", self.start.position),
            problem: problem.into(),
            hint: hint.into(),
        };
        match self.start.presentation {
            Presentation::Face if !mentum => {
                return Err(wrong_denominator(
                    "a face presentation is named by the chin",
                    "use MA, MP, LMT or RMT with presentation = \"face\"",
                ))
            }
            Presentation::Vertex if mentum => {
                return Err(wrong_denominator(
                    "a vertex presentation is named by the occiput",
                    "use OA, LOA, LOT, LOP, OP, ROP, ROT or ROA, or set presentation = \"face\"",
                ))
            }
            _ => {}
        }
        if self.name.trim().is_empty() {
            return Err(ScenarioError::Value {
                path: path.into(),
                line: None,
                key: "name".into(),
                value: "\"\"".into(),
                problem: "must not be empty".into(),
                hint: "a short name, used for the output folder".into(),
            });
        }
        // The name becomes a folder under runs/: it must stay one folder there.
        // Within the 255 bytes a file name may take, with room for the
        // sweep's `sweep-` prefix and a run's number.
        if self.name.len() > MAX_NAME_BYTES {
            return Err(ScenarioError::Value {
                path: path.into(),
                line: None,
                key: "name".into(),
                value: format!("{} bytes", self.name.len()),
                problem: format!("names the output folder runs/<name>-<n>, which file systems cap; at most {MAX_NAME_BYTES} bytes"),
                hint: "a short name; the description holds the rest".into(),
            });
        }
        if self.name.starts_with('.') || self.name.chars().any(|c| matches!(c, '/' | '\\' | ':') || c.is_control()) {
            return Err(ScenarioError::Value {
                path: path.into(),
                line: None,
                key: "name".into(),
                value: format!("{:?}", self.name),
                problem: "names the output folder runs/<name>-<n>, so it may not hold /, \\, : or control \
                          characters, nor start with a dot"
                    .into(),
                hint: "a plain folder name: letters, digits, - and _, e.g. \"narrow-inlet\"".into(),
            });
        }
        self.check_trajectory(path)
    }

    /// The mode and its way-points agree, and each way-point can be
    /// reached and placed: times rising within the run, stations and
    /// angles in the ranges a head in the canal takes.
    fn check_trajectory(&self, path: &Path) -> Result<(), ScenarioError> {
        let t = &self.trajectory;
        let err = |key: String, value: String, problem: &str, hint: &str| ScenarioError::Value {
            path: path.into(),
            line: None,
            key: key.into(),
            value,
            problem: problem.into(),
            hint: hint.into(),
        };
        match (t.mode, t.waypoints.is_empty()) {
            (Mode::Forward, false) => {
                return Err(err(
                    "trajectory.waypoints".into(),
                    format!("{} way-points", t.waypoints.len()),
                    "forward mode moves the head by the physics alone and reads no way-point",
                    "set trajectory.mode = \"imposed\" (the head follows them) or \"hybrid\" (the physics, guided \
                     towards them), or remove the way-points (`--set trajectory.waypoints=[]`)",
                ))
            }
            (Mode::Imposed | Mode::Hybrid, true) => {
                return Err(err(
                    "trajectory.mode".into(),
                    format!("\"{}\"", t.mode.name()),
                    "needs way-points to follow",
                    "add [[trajectory.waypoints]] tables with time_s, station_mm, theta_deg and phi_deg \
                     (`carus scenarios show textbook` has an example)",
                ))
            }
            _ => {}
        }
        for (key, value, hint) in [
            ("guide_stiffness_n_per_m", t.guide_stiffness_n_per_m, "N/m, 0 or more, e.g. 20000.0"),
            ("guide_torsion_nm_per_rad", t.guide_torsion_nm_per_rad, "N m/rad, 0 or more, e.g. 10.0"),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(err(format!("trajectory.{key}"), shown(value), "must be zero or more and finite", hint));
            }
        }
        let mut previous_s = 0.0;
        let dt = self.numerics.rigid_dt_s;
        for (i, w) in t.waypoints.iter().enumerate() {
            let key = |field: &str| format!("trajectory.waypoints[{i}].{field}");
            // A nan or inf time is no time at all: said so before any order.
            if !w.time_s.is_finite() {
                return Err(err(
                    key("time_s"),
                    shown(w.time_s),
                    "is not a finite number",
                    "give the way-point's time in seconds from the start, after the way-point before it, e.g. 3.0",
                ));
            }
            // A rigid step at least between two: the head's motion over a
            // step is read from the path, and a turn within one step would
            // be taken the short way round.
            if w.time_s < previous_s + dt {
                let (before, hint) = match i {
                    0 => ("the start, at 0 s, where [start] places the head".to_string(), "give it a time after 0 s"),
                    _ => (
                        format!("the way-point before it, at {previous_s} s"),
                        "list the way-points in time order, each at a later time",
                    ),
                };
                return Err(err(
                    key("time_s"),
                    shown(w.time_s),
                    &format!("must come at least a rigid step (numerics.rigid_dt_s = {dt} s) after {before}"),
                    hint,
                ));
            }
            if w.time_s > self.numerics.end_time_s {
                return Err(err(
                    key("time_s"),
                    shown(w.time_s),
                    &format!("lies past the run's end, numerics.end_time_s = {} s", self.numerics.end_time_s),
                    "an earlier time, or a later numerics.end_time_s",
                ));
            }
            previous_s = w.time_s;
            for (field, value, (low, high), hint) in [
                ("station_mm", w.station_mm, WAYPOINT_STATION_MM, "mm from the ischial spines, e.g. -20.0 or 45.0"),
                ("theta_deg", w.theta_deg, WAYPOINT_THETA_DEG, "degrees from anterior: OA 0, LOT -90, ROT 90, OP 180"),
                ("phi_deg", w.phi_deg, WAYPOINT_PHI_DEG, "degrees, flexion positive, e.g. 30.0"),
                ("anterior_mm", w.anterior_mm, WAYPOINT_ANTERIOR_MM, "mm off the pelvic axis towards the symphysis, e.g. 10.0"),
            ] {
                if !(value.is_finite() && (low..=high).contains(&value)) {
                    let finite = if value.is_finite() { "" } else { "is not a finite number: it " };
                    return Err(err(key(field), shown(value), &format!("{finite}must lie between {low} and {high}"), hint));
                }
            }
        }
        Ok(())
    }
}

/// The stations a way-point may name, mm: from well above the inlet to
/// well past the outlet, where the whole fetus is born.
pub const WAYPOINT_STATION_MM: (f64, f64) = (-150.0, 300.0);
/// theta of a way-point, degrees: two turns either way, so that a path
/// can turn past 180 without a jump.
pub const WAYPOINT_THETA_DEG: (f64, f64) = (-720.0, 720.0);
/// How far a way-point may put the head's centre off the pelvic axis, mm:
/// half the narrowest diameter of a normal canal (the interspinous, 100
/// mm), so that the centre stays inside it.
pub const WAYPOINT_ANTERIOR_MM: (f64, f64) = (-50.0, 50.0);
/// phi of a way-point, degrees: from full extension to full flexion.
pub const WAYPOINT_PHI_DEG: (f64, f64) = (-90.0, 90.0);

/// The one setting a reading error at `key` (`contact.friction`) is in:
/// the setting of that key or a table holding it, else the one setting
/// inside the table `key` names; None where that is not one setting
/// (a key no setting names).
fn setting_at_fault<'a>(settings: &'a [(String, String)], key: &str) -> Option<&'a (String, String)> {
    if key.is_empty() {
        return None;
    }
    if let Some(holding) = settings.iter().find(|(k, _)| holds_key(k, key)) {
        return Some(holding);
    }
    match settings.iter().filter(|(k, _)| holds_key(key, k)).collect::<Vec<_>>().as_slice() {
        [one] => Some(one),
        _ => None,
    }
}

/// Writes `key` (a dotted path) = `value` (TOML text; a bare word is
/// taken as a string) into a scenario's table, refusing a value with a
/// unit after it, an empty key or a path through a value, named by the
/// setting.
fn set_key(table: &mut toml::Table, key: &str, value: &str) -> Result<(), ScenarioError> {
    let refuse = |problem: &str, hint: &str| ScenarioError::Setting {
        setting: format!("{key} = {value}"),
        problem: problem.into(),
        hint: hint.into(),
    };
    let parsed = match format!("v = {value}").parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("the one key parsed"),
        Err(_) => {
            // A unit after a number gets the hint a scenario file gets.
            let (section, written) = key.rsplit_once('.').map_or((None, key), |(s, k)| (Some(s), k));
            let text = format!("{}{written} = {value}\n", section.map_or(String::new(), |s| format!("[{s}]\n")));
            let unit = text.parse::<toml::Table>().err().and_then(|e| unit_in_value(Path::new(key), &text, &e));
            if let Some(ScenarioError::Syntax { key, message, hint, .. }) = unit {
                return Err(refuse(&format!("{key}{message}"), &hint));
            }
            // Rust reads `1e400` as infinity; TOML refuses it, so it is no bare word either.
            if value.trim().parse::<f64>().is_ok_and(f64::is_infinite) && value.contains(|c: char| c.is_ascii_digit()) {
                return Err(refuse(
                    "the number is beyond the largest a value can hold (about 1.8e308)",
                    "check the exponent; units are in the key names (mm, deg, s, n, pa)",
                ));
            }
            // Digits alone past TOML's whole numbers: no bare word either.
            let whole = value.trim().replace('_', "").parse::<i128>();
            let too_large = match whole {
                Ok(n) => i64::try_from(n).is_err(),
                Err(e) => matches!(e.kind(), std::num::IntErrorKind::PosOverflow | std::num::IntErrorKind::NegOverflow),
            };
            if too_large {
                let hint = match normal_value(key) {
                    Some(example) => format!("give a smaller number, e.g. {key}={example} as the built-in normal has it"),
                    None => "give a smaller number".to_string(),
                };
                return Err(refuse(&format!("the whole number {} is too large: TOML's whole numbers end at {}", value.trim(), i64::MAX), &hint));
            }
            toml::Value::String(value.to_string())
        }
    };
    let mut parts: Vec<&str> = key.split('.').collect();
    let leaf = parts
        .pop()
        .filter(|k| !k.is_empty())
        .ok_or_else(|| refuse("no key given", "write SECTION.KEY=VALUE, e.g. expulsion.period_s=32"))?;
    let mut section = table;
    for part in parts {
        // `waypoints[2]`: one entry of an array of tables, as errors name it.
        let (name, index) = match part.split_once('[') {
            Some((name, rest)) => match rest.strip_suffix(']').and_then(|i| i.parse::<usize>().ok()) {
                Some(i) => (name, Some(i)),
                None => return Err(refuse(&format!("`{part}` is not an entry's name"), "write NAME[INDEX], counted from 0, e.g. trajectory.waypoints[2].theta_deg")),
            },
            None => (part, None),
        };
        let entry = section.entry(name).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        section = match (entry, index) {
            (toml::Value::Table(t), None) => t,
            (toml::Value::Array(entries), Some(i)) => {
                let count = entries.len();
                match entries.get_mut(i) {
                    Some(toml::Value::Table(t)) => t,
                    _ => {
                        return Err(refuse(
                            &format!("`{name}` has {count} entries, counted from 0: there is no [{i}]"),
                            "`carus scenarios show` lists them in order",
                        ))
                    }
                }
            }
            _ => {
                return Err(refuse(
                    &format!("`{part}` is a value, not a section"),
                    "the keys are those `carus scenarios show normal` lists",
                ))
            }
        };
    }
    // An imported pelvis takes all its diameters from its landmarks: the
    // import replaces a generated pelvis's table rather than joining it.
    if key == "pelvis.import" {
        section.clear();
    }
    section.insert(leaf.to_string(), parsed);
    Ok(())
}

/// The unit a key's name ends with, the longer endings first.
const KEY_UNITS: [(&str, &str); 13] = [
    ("_nm_s_per_rad", "N m s/rad"),
    ("_nm_per_deg", "N m per degree"),
    ("_nm_per_rad", "N m per radian"),
    ("_n_s_per_m", "N s/m"),
    ("_n_per_m", "N/m"),
    ("_pa_per_m", "Pa/m"),
    ("_kg_per_m3", "kg/m^3"),
    ("_per_s", "per second"),
    ("_mm", "millimetres"),
    ("_deg", "degrees"),
    ("_pa", "pascals"),
    ("_s", "seconds"),
    ("_n", "newtons"),
];

/// A number as a message shows it: as written, or with an exponent when
/// its decimals would run to hundreds of digits (1e300, 1e-300).
pub(crate) fn shown(value: f64) -> String {
    if value != 0.0 && !(1e-6..1e15).contains(&value.abs()) {
        format!("{value:e}")
    } else {
        value.to_string()
    }
}

/// An imported pelvis (`[pelvis] import = ...` of the file `path`, whose
/// text is `text`) names a file that exists, relative to `base_dir`, or the
/// built-in pelvis: a misspelt name is told as that, with the built-in
/// names, not as a file that cannot be read. Scenarios and anatomy files
/// (`carus measure`, `carus mesh`) both check their import with it.
pub fn check_pelvis_import(path: &Path, text: &str, pelvis: &PelvisSpec, base_dir: &Path) -> Result<(), ScenarioError> {
    let PelvisSpec::Imported { landmarks_file } = pelvis else {
        return Ok(());
    };
    let resolved = base_dir.join(landmarks_file);
    if landmarks_file.as_os_str() == VISIBLE_HUMAN_FEMALE || resolved.is_file() {
        return Ok(());
    }
    #[derive(Deserialize)]
    struct File {
        pelvis: Import,
    }
    #[derive(Deserialize)]
    struct Import {
        import: toml::Spanned<String>,
    }
    let line = toml::from_str::<File>(text).map_or(0, |f| carus_io::input::line_at(text.as_bytes(), f.pelvis.import.span().start));
    let found = if resolved.is_dir() { "is a folder" } else { "does not exist" };
    let message = match landmarks_file.as_os_str().is_empty() {
        true => "is empty: it names no landmarks file and no built-in pelvis".to_string(),
        false => format!(
            "{:?} is neither a file ({} {found}) nor a built-in pelvis",
            landmarks_file.display().to_string(),
            std::path::absolute(&resolved).unwrap_or(resolved).display()
        ),
    };
    Err(ScenarioError::Syntax {
        path: path.to_path_buf(),
        line,
        key: "`pelvis.import`: ".into(),
        message,
        hint: format!(
            "the built-in pelvis names: `{VISIBLE_HUMAN_FEMALE}`; or a landmarks file's path from this \
             file's folder (docs/IMPORT.md)"
        ),
    })
}

/// The tables of a TOML file, refused as a scenario's syntax is: by line,
/// and a unit written after a number named as such (`carus measure` and
/// `carus mesh` read anatomy files this way).
pub fn toml_table(path: &Path, text: &str) -> Result<toml::Table, ScenarioError> {
    text.parse::<toml::Table>().map_err(|e| toml_syntax(path, text, &e))
}

/// A pelvis's landmarks file (it names a mesh and declares its axes) given
/// where a scenario or anatomy file belongs is refused with how to use it.
pub fn check_not_landmarks_file(path: &Path, text: &str, table: &toml::Table) -> Result<(), ScenarioError> {
    if !(table.contains_key("mesh") && (table.contains_key("axes") || table.contains_key("landmarks"))) {
        return Ok(());
    }
    Err(ScenarioError::Syntax {
        path: path.to_path_buf(),
        line: line_of_key(text, "mesh").map_or(1, NonZeroUsize::get),
        key: String::new(),
        message: "this is a pelvis's landmarks file (it names a `mesh` and its [axes] and [landmarks]), \
                  not a scenario or anatomy file"
            .into(),
        hint: format!(
            "refer to it from a scenario or anatomy file: a file holding `[pelvis]` and \
             `import = {:?}` (the path relative to that file), as docs/IMPORT.md shows",
            path.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())
        ),
    })
}

/// A `carus solve` job (a volume mesh with its materials and solver) given
/// for a scenario: named as one, with the command that runs it.
fn check_not_solve_job(path: &Path, table: &toml::Table) -> Result<(), ScenarioError> {
    if !(table.contains_key("mesh") && (table.contains_key("solver") || table.contains_key("material"))) {
        return Ok(());
    }
    Err(ScenarioError::Syntax {
        path: path.to_path_buf(),
        line: 1,
        key: String::new(),
        message: "this is a `carus solve` job (it has [mesh] with [solver] or [[material]]), not a labour scenario".into(),
        hint: format!("solve it with `carus solve {} --out DIR` (docs/SOLVE.md)", path.display()),
    })
}

/// The note for a message that names keys of `[table]` as `key = value`
/// where the file left some out (`left_out`), so that the defaults stood
/// in: a reader would take those for the file's own values.
pub fn defaults_note(table: &str, message: &str, left_out: impl Fn(&str) -> bool) -> Option<String> {
    let mut keys: Vec<&str> = Vec::new();
    for (at, _) in message.match_indices(" = ") {
        let before = &message[..at];
        let start = before.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
        let key = &before[start..];
        if !key.is_empty() && !keys.contains(&key) && left_out(key) {
            keys.push(key);
        }
    }
    let (last, rest) = keys.split_last()?;
    let named = match rest {
        [] => format!("{last} is the default"),
        _ => format!("{} and {last} are the defaults", rest.join(", ")),
    };
    Some(format!("{named}, not in the file's [{table}]: set {} there too", if rest.is_empty() { "it" } else { "them" }))
}

impl Scenario {
    /// [`defaults_note`] for this scenario: the keys its file leaves out
    /// (none for a built-in, nor for a key `--set` changed).
    pub fn defaults_note(&self, table: &str, message: &str) -> Option<String> {
        defaults_note(table, message, |key| matches!(self.source.locate(&format!("{table}.{key}")), Some((_, None))))
    }
}

/// [`defaults_note`] for the text of an anatomy file.
pub fn defaults_note_in(text: &str, table: &str, message: &str) -> Option<String> {
    defaults_note(table, message, |key| line_of_key(text, &format!("{table}.{key}")).is_none())
}

/// An anatomy file (`[pelvis]`, `[head]`, `[floor]` and no `name`) given
/// for a scenario: named as one, with what to do instead.
fn check_not_anatomy_file(path: &Path, table: &toml::Table) -> Result<(), ScenarioError> {
    let anatomy = ["pelvis", "head", "trunk", "floor"];
    if table.contains_key("name") || table.is_empty() || !table.keys().all(|k| anatomy.contains(&k.as_str())) {
        return Ok(());
    }
    Err(ScenarioError::Syntax {
        path: path.to_path_buf(),
        line: 1,
        key: String::new(),
        message: "this is an anatomy file ([pelvis], [head], [trunk], [floor] without a `name`), not a scenario".into(),
        hint: "`carus measure`, `carus mesh` and `carus render` read it as it is; to run or detect with it, add \
               `name = \"...\"` at its top, which makes it a scenario with the other tables at their defaults \
               (`carus scenarios show normal` lists them)"
            .into(),
    })
}

/// `text` read as a `T`, a wrong value named by its line as in a scenario
/// file (anatomy files: `carus measure`, `carus mesh`).
pub fn from_toml_text<T: serde::de::DeserializeOwned>(path: &Path, text: &str) -> Result<T, ScenarioError> {
    toml::from_str(text).map_err(|e| toml_syntax(path, text, &e))
}

/// A TOML syntax error by line, with the unit-after-a-number advice where
/// that is the fault.
fn toml_syntax(path: &Path, text: &str, error: &toml::de::Error) -> ScenarioError {
    unit_in_value(path, text, error).unwrap_or_else(|| syntax(path, text, String::new(), error))
}

/// A unit written after a number (`force_max_n = 120 N`, `biparietal_mm =
/// 9.5cm`): TOML's own advice, to quote it, would only lead to a type
/// error, for the unit belongs in the key's name.
fn unit_in_value(path: &Path, text: &str, error: &toml::de::Error) -> Option<ScenarioError> {
    let line = carus_io::input::line_at(text.as_bytes(), error.span()?.start);
    let (written_key, value) = text.lines().nth(line - 1)?.split_once('=')?;
    let written_key = written_key.trim();
    if written_key.is_empty() || !written_key.chars().all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c)) {
        return None;
    }
    let value = value.split('#').next()?.trim();
    // The longest number before a unit, so that `1e3mm` is 1e3 in mm.
    let (number, unit) = (1..value.len()).rev().filter(|&i| value.is_char_boundary(i)).find_map(|i| {
        let (number, unit) = (value[..i].trim(), value[i..].trim());
        let is_number = number.starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c))
            && number.contains(|c: char| c.is_ascii_digit())
            && number.replace('_', "").parse::<f64>().is_ok();
        // `e400` in `1e400` is the number's exponent (too large: TOML says so).
        let exponent = unit.len() > 1
            && unit.starts_with(['e', 'E'])
            && unit[1..].trim_start_matches(['+', '-']).chars().all(|c| c.is_ascii_digit());
        let is_unit = unit.starts_with(|c: char| c.is_alphabetic() || c == '°')
            && unit.chars().all(|c| c.is_alphanumeric() || "/^*.°".contains(c))
            && !exponent;
        (is_number && is_unit).then_some((number, unit))
    })?;
    let table = text
        .lines()
        .take(line - 1)
        .filter_map(|l| l.trim().starts_with('[').then(|| l.trim().trim_start_matches('[').split(']').next())?)
        .last()
        .map(str::trim);
    let full_key = table.map_or(written_key.to_string(), |t| format!("{t}.{written_key}"));
    let leaf = written_key.rsplit('.').next().unwrap_or(written_key);
    let hint = match KEY_UNITS.iter().find(|(ending, _)| leaf.ends_with(ending)) {
        Some((ending, name)) if unit.eq_ignore_ascii_case(&ending[1..]) => format!(
            "write the number alone, `{leaf} = {number}`: the unit is in the key's name (`{ending}`, {name})"
        ),
        Some((ending, name)) => format!(
            "write the number alone, converted to {name}: the unit is in the key's name (`{ending}`)"
        ),
        None if takes_a_number(&full_key) => "write the number alone: units are in the key names (`_mm` \
                 millimetres, `_deg` degrees, `_s` seconds, `_n` newtons, `_pa` pascals), and this key takes a \
                 plain number"
            .to_string(),
        // Not a number's key (`name = 2nd`): TOML's own message fits.
        None => return None,
    };
    Some(ScenarioError::Syntax {
        path: path.to_path_buf(),
        line,
        key: format!("`{full_key}`: "),
        message: format!("a unit after the number in `{value}` is not TOML, and quoted it is no number"),
        hint,
    })
}

/// serde's message with Rust's number types said as a reader would:
/// "expected usize" is "expected a whole number".
fn plain_types(message: &str) -> String {
    let mut plain = message.to_string();
    // A count or a size: a negative one is refused by its type alone.
    for rust in ["usize", "u64", "u32", "u16", "u8"] {
        plain = plain.replace(&format!("expected {rust}"), "expected a whole number of 0 or more");
    }
    for rust in ["isize", "i64", "i32", "i16", "i8"] {
        plain = plain.replace(&format!("expected {rust}"), "expected a whole number");
    }
    // toml reads a whole number past i64 as i128, which no key takes.
    if let Some(number) = plain.strip_prefix("invalid type: integer `").and_then(|rest| rest.split_once("` as i128")) {
        plain = format!("the whole number `{}` is too large: TOML's whole numbers end at {}", number.0, i64::MAX);
    }
    for rust in ["f64", "f32"] {
        plain = plain.replace(&format!("expected {rust}"), "expected a number");
    }
    plain = plain.replace("expected path string", "expected a file's path in quotes");
    // `expected struct Waypoint`: the Rust type's name means nothing in a scenario.
    if let Some(at) = plain.find("expected struct ") {
        let name_end = plain[at + 16..].find(|c: char| !c.is_alphanumeric() && c != '_').map_or(plain.len(), |n| at + 16 + n);
        plain.replace_range(at..name_end, "expected a table of keys");
    }
    plain
}

/// Whether the dotted key holds a number in a complete scenario file.
fn takes_a_number(full_key: &str) -> bool {
    normal_value(full_key).is_some_and(|v| v.is_integer() || v.is_float())
}

/// The dotted key's value in the built-in normal scenario written whole,
/// an example for a message; None for a key it has not (a way-point's).
fn normal_value(full_key: &str) -> Option<toml::Value> {
    let complete = Scenario::builtin("normal").ok()?.to_toml().ok()?;
    let root = toml::Value::Table(complete.parse::<toml::Table>().ok()?);
    let mut value = &root;
    for part in full_key.split('.') {
        value = value.get(part)?;
    }
    Some(value.clone())
}

fn syntax(path: &Path, text: &str, key: String, error: &toml::de::Error) -> ScenarioError {
    let mut line = error.span().map_or(0, |s| carus_io::input::line_at(text.as_bytes(), s.start));
    let mut message = plain_types(error.message().trim());
    // A key inside a nested table comes back as "...\nin `leaf`": one path.
    let key = match message.split_once("\nin `") {
        Some((said, leaf)) => {
            let leaf = leaf.trim_end_matches('`');
            // The span is the table's; the leaf's own line is the first of
            // that table that sets it.
            let sets_leaf = |l: &str| l.trim_start().strip_prefix(leaf).is_some_and(|rest| rest.trim_start().starts_with('='));
            if let Some(k) = text.lines().enumerate().skip(line.saturating_sub(1)).find_map(|(k, l)| sets_leaf(l).then_some(k)) {
                line = k + 1;
            }
            let key = if key == "." || key.is_empty() { leaf.to_string() } else { format!("{key}.{leaf}") };
            message = said.to_string();
            key
        }
        None => key,
    };
    let twice = carus_io::toml_text::written_twice(text, error).map(|t| t.message_and_fix());
    // A way-point's keys are shown by a scenario that has way-points.
    let in_trajectory = key.starts_with("trajectory");
    let hint = if let Some((said, fix)) = twice {
        message = said;
        fix.to_string()
    } else if message.starts_with("unknown field") && in_trajectory {
        "check the spelling against `carus scenarios show textbook`, whose way-points list every key \
         (docs/TRAJECTORIES.md)"
            .to_string()
    } else if message.starts_with("unknown field") {
        "check the spelling against `carus scenarios show normal`, which lists every key"
            .to_string()
    } else if message.starts_with("missing field") && in_trajectory {
        "docs/TRAJECTORIES.md lists what a way-point needs; `carus scenarios show textbook` has them".to_string()
    } else if message.starts_with("unknown variant") {
        "use one of the values listed".to_string()
    } else if message.starts_with("invalid type") && message.contains("expected a whole number") {
        "this key takes a whole number: no decimal point, no quotes".to_string()
    } else if message.ends_with("expected a whole number of 0 or more") || message.contains("is too large: TOML's whole numbers end at") {
        // A sign or a size no count has: the normal scenario's is an example.
        let what = match message.contains("is too large") {
            true => "a smaller number",
            false => "a whole number of 0 or more",
        };
        match normal_value(&key) {
            Some(example) => format!("give {what}, e.g. `{key} = {example}` as the built-in normal has it"),
            None => format!("give {what}"),
        }
    } else if message.starts_with("invalid type") {
        "numbers without quotes, names in quotes; units are in the key names (mm, deg, s, n, pa)"
            .to_string()
    } else {
        "see docs/SCENARIOS.md".to_string()
    };
    let key = if key == "." || key.is_empty() {
        String::new()
    } else {
        format!("`{key}`: ")
    };
    ScenarioError::Syntax {
        path: path.to_path_buf(),
        line,
        key,
        message,
        hint,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scenario, ScenarioError> {
        Scenario::parse(Path::new("test.toml"), text, PathBuf::from("."))
    }

    #[test]
    fn every_builtin_parses_and_round_trips_through_show() {
        for (name, _) in BUILTINS {
            let s = Scenario::builtin(name).unwrap();
            assert_eq!(s.name, name);
            let shown = s.to_toml().unwrap();
            let back = parse(&shown).unwrap();
            assert_eq!(back, s, "{name} does not round-trip:\n{shown}");
            for table in [
                "[pelvis]",
                "[head]",
                "[start]",
                "[expulsion]",
                "[contact]",
                "[neck]",
                "[floor]",
                "[numerics]",
            ] {
                assert!(shown.contains(table), "{name}: {table} missing");
            }
        }
    }

    #[test]
    fn a_setting_changes_one_key_and_is_checked_like_a_file() {
        let normal = Scenario::builtin("normal").unwrap();
        let slower = normal.with_setting("expulsion.period_s", "32").unwrap();
        assert_eq!(slower.expulsion.period_s, 32.0);
        // Nothing else changed, but the description says what did.
        assert_eq!(slower.description, format!("{} (changed: expulsion.period_s = 32)", normal.description));
        assert_eq!(Scenario { expulsion: normal.expulsion, description: normal.description.clone(), ..slower.clone() }, normal);
        let spine = normal.with_setting("spine.enabled", "true").unwrap();
        assert!(spine.spine.enabled);
        let pivot = normal.with_setting("expulsion.acts_on", "pivot").unwrap();
        assert_eq!(pivot.expulsion.acts_on, ActsOn::Pivot);

        let e = normal.with_setting("expulsion.periods", "32").unwrap_err().to_string();
        assert!(e.contains("expulsion.periods = 32") && e.contains("unknown field"), "{e}");
        assert!(!e.contains(".toml:"), "no line of generated text: {e}");
        let e = normal.with_setting("expulsion.period_s", "-8").unwrap_err().to_string();
        assert!(e.contains("expulsion.period_s") && e.contains("-8"), "{e}");
        let e = normal.with_setting("expulsion.period_s", "fast").unwrap_err().to_string();
        assert!(e.contains("period_s") && e.contains("invalid type"), "{e}");
        let e = normal.with_setting("expulsion.period_s.x", "1").unwrap_err().to_string();
        assert!(e.contains("`period_s` is a value"), "{e}");
        assert!(normal.with_setting("", "1").is_err());
    }

    #[test]
    fn the_push_direction_is_named_or_a_vector_and_refused_with_a_hint() {
        let normal = Scenario::builtin("normal").unwrap();
        assert_eq!(
            normal.expulsion.direction,
            ExpulsionDirection::Named(NamedDirection::FetalSpine)
        );
        let inlet = normal.with_setting("expulsion.direction", "inlet_axis").unwrap();
        assert_eq!(inlet.expulsion.direction, ExpulsionDirection::Named(NamedDirection::InletAxis));
        let fixed = normal.with_setting("expulsion.direction", "[0.0, 0.2, -1.0]").unwrap();
        assert_eq!(fixed.expulsion.direction, ExpulsionDirection::Fixed([0.0, 0.2, -1.0]));
        for s in [&inlet, &fixed] {
            assert_eq!(&parse(&s.to_toml().unwrap()).unwrap(), s, "round trip through show");
        }

        let e = normal.with_setting("expulsion.direction", "downwards").unwrap_err().to_string();
        assert!(e.contains("expulsion.direction") && e.contains("inlet_axis"), "{e}");
        let e = normal.with_setting("expulsion.direction", "[0, 0]").unwrap_err().to_string();
        assert!(e.contains("expulsion.direction") && e.contains("[x, y, z]"), "{e}");
        let e = parse("name = \"x\"\n[expulsion]\ndirection = [0.0, 0.0, 0.0]\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("test.toml") && e.contains("expulsion.direction") && e.contains("zero"), "{e}");
    }

    /// The mode and its way-points must agree, and every way-point is
    /// checked, named by its index and key.
    #[test]
    fn a_trajectory_is_checked_way_point_by_way_point() {
        let point = |t: f64, station: f64| format!("[[trajectory.waypoints]]\ntime_s = {t}\nstation_mm = {station}\ntheta_deg = -90.0\nphi_deg = 20.0\n");
        let with = |mode: &str, points: &str| parse(&format!("name = \"x\"\n[trajectory]\nmode = \"{mode}\"\n{points}"));
        let two = format!("{}{}", point(1.0, -40.0), point(2.0, -20.0));
        let imposed = with("imposed", &two).unwrap();
        assert_eq!(imposed.trajectory.mode, Mode::Imposed);
        assert_eq!(imposed.trajectory.waypoints[1].station_mm, -20.0);
        assert_eq!(imposed.trajectory.waypoints[1].anterior_mm, 0.0);
        assert_eq!(parse(&imposed.to_toml().unwrap()).unwrap(), imposed, "round trip through show");
        assert_eq!(Scenario::builtin("normal").unwrap().trajectory.mode, Mode::Forward);

        let refused = |mode: &str, points: &str| with(mode, points).unwrap_err().to_string();
        let e = refused("forward", &two);
        assert!(e.contains("`trajectory.waypoints`") && e.contains("reads no way-point") && e.contains("hybrid"), "{e}");
        let e = refused("hybrid", "");
        assert!(e.contains("`trajectory.mode`") && e.contains("needs way-points"), "{e}");
        let e = refused("imposed", &format!("{}{}", point(2.0, -40.0), point(1.0, -20.0)));
        assert!(e.contains("`trajectory.waypoints[1].time_s` = 1") && e.contains("time order"), "{e}");
        let e = refused("imposed", &format!("{}{}", point(1.0, -40.0), point(1.0001, -20.0)));
        assert!(e.contains("`trajectory.waypoints[1].time_s` = 1.0001") && e.contains("at least a rigid step"), "{e}");
        let e = refused("imposed", &point(1.0, -40.0).replace("time_s = 1", "time_s = 1 s"));
        assert!(e.contains("`trajectory.waypoints.time_s`") && e.contains("write the number alone"), "{e}");
        let e = refused("imposed", &point(0.0, -40.0));
        assert!(e.contains("`trajectory.waypoints[0].time_s` = 0") && e.contains("after the start, at 0 s, where [start] places the head") && e.contains("a time after 0 s"), "{e}");
        let e = refused("imposed", &point(61.0, -40.0));
        assert!(e.contains("`trajectory.waypoints[0].time_s` = 61") && e.contains("numerics.end_time_s"), "{e}");
        // A time that is no number is said to be that, not out of order.
        let e = refused("imposed", &format!("{}{}", point(1.0, -40.0), point(2.0, -20.0).replace("time_s = 2", "time_s = nan")));
        assert!(e.contains("`trajectory.waypoints[1].time_s` = NaN: is not a finite number") && !e.contains("rigid step"), "{e}");
        assert!(e.contains("hint: give the way-point's time in seconds"), "{e}");
        let e = refused("imposed", &point(1.0, -40.0).replace("phi_deg = 20.0", "phi_deg = inf"));
        assert!(e.contains("`trajectory.waypoints[0].phi_deg` = inf: is not a finite number: it must lie between -90 and 90"), "{e}");
        let e = refused("imposed", &point(1.0, -400.0));
        assert!(e.contains("`trajectory.waypoints[0].station_mm` = -400") && e.contains("between -150 and 300"), "{e}");
        let e = refused("imposed", &format!("{}anterior_mm = 80.0\n", point(1.0, -40.0)));
        assert!(e.contains("`trajectory.waypoints[0].anterior_mm` = 80"), "{e}");
        let e = refused("imposed", &format!("{}stationmm = 1.0\n", point(1.0, -40.0)));
        assert!(e.contains("trajectory.waypoints") && e.contains("stationmm") && e.contains("unknown field"), "{e}");
        let e = refused("guided", &two);
        assert!(e.contains("trajectory.mode") && e.contains("guided"), "{e}");
        let e = imposed.with_setting("trajectory.guide_stiffness_n_per_m", "-1").unwrap_err().to_string();
        assert!(e.contains("trajectory.guide_stiffness_n_per_m") && e.contains("zero or more"), "{e}");
        let hybrid = imposed.with_setting("trajectory.mode", "hybrid").unwrap();
        assert_eq!((hybrid.trajectory.mode, &hybrid.trajectory.waypoints), (Mode::Hybrid, &imposed.trajectory.waypoints));

        // Keys that must agree change together: the settings are checked once, after all of them.
        let textbook = Scenario::builtin("textbook").unwrap();
        let e = textbook.with_setting("trajectory.mode", "forward").unwrap_err().to_string();
        assert!(e.starts_with("`trajectory.mode = forward`: then `trajectory.waypoints` = 10 way-points:") && e.contains("reads no way-point"), "{e}");
        let setting = |k: &str, v: &str| (k.to_string(), v.to_string());
        let forward = textbook
            .with_settings(&[setting("trajectory.mode", "forward"), setting("trajectory.waypoints", "[]")])
            .unwrap();
        assert_eq!((forward.trajectory.mode, forward.trajectory.waypoints.len()), (Mode::Forward, 0));
        // Its description, written for the imposed run, says what changed.
        let said = format!("{} (changed: trajectory.mode = forward, trajectory.waypoints = [])", textbook.description);
        assert_eq!(forward.description, said);
        assert!(forward.to_toml().unwrap().starts_with(&format!("# {said}\n")));
        assert_eq!(textbook.with_setting("description", "\"mine\"").unwrap().description, "mine");
        let e = textbook
            .with_settings(&[setting("trajectory.mode", "forward"), setting("contact.fiction", "0.3")])
            .unwrap_err()
            .to_string();
        // The setting at fault alone leads the message.
        assert!(e.starts_with("`contact.fiction = 0.3`:") && e.contains("unknown field `fiction`"), "{e}");
        // One key set twice is a slip, not the last one winning.
        let e = textbook
            .with_settings(&[setting("contact.friction", "0.1"), setting("contact.friction", "0.2")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("contact.friction = 0.1, contact.friction = 0.2") && e.contains("given twice"), "{e}");
    }

    #[test]
    fn unknown_keys_are_named_with_their_path() {
        let e = parse("name = \"x\"\n[expulsion]\nforce_max = 100.0\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expulsion") && e.contains("force_max") && e.contains("test.toml:3"),
            "{e}"
        );
        let e = parse("name = \"x\"\n[head]\nbiparietal = 95.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("biparietal") && e.contains("hint"), "{e}");
    }

    #[test]
    fn wrong_units_and_impossible_values_are_refused_with_a_hint() {
        let e = parse("name = \"x\"\n[expulsion]\nforce_max_n = \"120 N\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expulsion.force_max_n") && e.contains("hint"),
            "{e}"
        );
        let e = parse("name = \"x\"\n[expulsion]\nforce_max_n = 120000.0\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expulsion.force_max_n") && e.contains("newtons"),
            "{e}"
        );
        let e = parse("name = \"x\"\n[floor]\nshear_modulus_pa = -3.0\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("test.toml:3: `floor.shear_modulus_pa` = -3") && e.contains("positive"),
            "the value's line is named: {e}"
        );
        // So is a way-point's, counted among the array's tables.
        let e = parse("name = \"x\"\n[trajectory]\nmode = \"imposed\"\n[[trajectory.waypoints]]\ntime_s = 1.0\nstation_mm = 0.0\ntheta_deg = 0.0\nphi_deg = 10.0\n[[trajectory.waypoints]]\ntime_s = 2.0\nstation_mm = 10.0\ntheta_deg = 0.0\nphi_deg = 95.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("test.toml:13: `trajectory.waypoints[1].phi_deg` = 95"), "{e}");
        // From the command line there is no file line to name.
        let e = Scenario::builtin("normal").unwrap().with_setting("floor.shear_modulus_pa", "-3").unwrap_err().to_string();
        assert!(e.starts_with("`floor.shear_modulus_pa = -3`: must be a positive"), "{e}");
        // Another key refused through a setting is the setting's fault too.
        let e = Scenario::builtin("textbook").unwrap().with_setting("trajectory.waypoints", "[]").unwrap_err();
        assert!(matches!(e, ScenarioError::Setting { .. }), "{e}");
        assert!(e.to_string().starts_with("`trajectory.waypoints = []`: then `trajectory.mode` = "), "{e}");
        let e = parse("name = \"x\"\n[expulsion]\nforce_min_n = 200.0\nforce_max_n = 100.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("force_min_n"), "{e}");
        let e = parse("name = \"x\"\n[expulsion]\nforce_min_n = -1e6\n").unwrap_err().to_string();
        assert!(e.contains("expulsion.force_min_n") && e.contains("far beyond any pull back"), "{e}");
        for key in ["ligament_stiffness_ratio", "soft_wall_stiffness_ratio"] {
            for ratio in ["0.0", "1.5", "nan"] {
                let e = parse(&format!("name = \"x\"\n[contact]\n{key} = {ratio}\n")).unwrap_err().to_string();
                assert!(e.contains(&format!("contact.{key}")) && e.contains("above 0 and at most 1") && e.contains("as rigid as bone"), "{e}");
            }
        }
        let e = parse("name = \"x\"\n[contact]\ntrunk_cover_depth_mm = 1000.0\n").unwrap_err().to_string();
        assert!(e.contains("contact.trunk_cover_depth_mm") && e.contains("0.1 to 30"), "{e}");
        let e = parse("name = \"x\"\n[head]\nbiparietal_mm = 9.5\n").unwrap_err().to_string();
        assert!(e.contains("`head.biparietal_mm` = 9.5") && e.contains("not cm"), "{e}");
        let e = parse("name = \"x\"\n[head]\nmentovertical_mm = 1e300\n").unwrap_err().to_string();
        assert!(e.contains("head.mentovertical_mm"), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\ninlet_ap_mm = 11.0\n").unwrap_err().to_string();
        assert!(e.contains("`pelvis.inlet_ap_mm` = 11") && e.contains("not cm"), "{e}");
        let e = parse("name = \"x\"\n[contact]\nfriction = 0.1\nfriction = 0.2\n").unwrap_err().to_string();
        assert!(e.contains("test.toml:4") && e.contains("duplicate key `friction`"), "{e}");
        let e = parse("name = \"x\"\n[contact]\nfriction = 0.1\n[contact]\n").unwrap_err().to_string();
        assert!(e.contains("test.toml:4") && e.contains("the table `contact` is given a second time"), "{e}");
        for name in ["../../etc", "a/b", ".hidden"] {
            let e = parse(&format!("name = {name:?}\n")).unwrap_err().to_string();
            assert!(e.contains("`name`") && e.contains("output folder"), "{e}");
        }
        let e = parse("name = \"x\"\n[start]\nposition = \"MP\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`start.position` = \"MP\"") && e.contains("face"),
            "the value written is shown: {e}"
        );
        let e = parse("name = \"x\"\n[floor]\ncrushed_volume_ratio = 1.5\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("floor.crushed_volume_ratio") && e.contains("below 1"), "{e}");
        let e = parse("name = \"x\"\n[floor]\nhourglass_coefficient = -0.1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("floor.hourglass_coefficient") && e.contains("zero or more"), "{e}");
        let e = parse("name = \"x\"\n[floor]\nhourglass_modulus = \"bulk\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("hourglass_modulus") && e.contains("shear"), "{e}");
        let s = parse("name = \"x\"\n[floor]\nhourglass_modulus = \"shear\"\n").unwrap();
        assert_eq!(s.floor.hourglass_modulus, carus_fem::HourglassModulus::Shear);
        assert_eq!(s.floor.coupling, FloorCoupling::Sliding);
        let e = parse("name = \"x\"\n[floor]\ncoupling = \"glued\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("coupling") && e.contains("sliding") && e.contains("held"), "{e}");
        let s = parse("name = \"x\"\n[floor]\ncoupling = \"held\"\n").unwrap();
        assert_eq!(s.floor.coupling, FloorCoupling::Held);
        let e = parse("name = \"x\"\n[spine]\nenabled = true\n[trunk]\nenabled = false\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("spine.enabled") && e.contains("trunk.enabled = true"), "{e}");
        // Keys that would run for ever, or run out of memory, are refused
        // by name; a number far out of range is shown with its exponent.
        for (text, named) in [
            ("[contact]\nsample_spacing_mm = 0.004\n", "`contact.sample_spacing_mm` = 0.004"),
            ("[neck]\naxial_rotation_limit_deg = nan\n", "`neck.axial_rotation_limit_deg` = NaN"),
            ("[neck]\naxial_rotation_limit_deg = 1000.0\n", "`neck.axial_rotation_limit_deg` = 1000"),
            ("[neck]\nlinear_damping_n_s_per_m = -1.0\n", "`neck.linear_damping_n_s_per_m` = -1"),
            ("[numerics]\nrigid_dt_s = 1e-300\n", "`numerics.rigid_dt_s` = 1e-300"),
            ("[numerics]\nend_time_s = 1e9\n", "`numerics.end_time_s` = 1000000000: is more than an hour of labour"),
            ("[numerics]\nfloor_step_fraction = 0.001\n", "`numerics.floor_step_fraction` = 0.001"),
            ("[floor]\nbulk_modulus_pa = 1e300\n", "`floor.bulk_modulus_pa` = 1e300: is stiffer than any soft tissue"),
            ("", "`name` = 201 bytes"),
        ] {
            let name = if text.is_empty() { "x".repeat(201) } else { "x".into() };
            let e = parse(&format!("name = \"{name}\"\n{text}")).unwrap_err().to_string();
            assert!(e.contains(named) && e.contains("hint:"), "{e}");
        }
        let e = parse("name = \"x\"\n[spine]\nbending_nm_per_deg = -0.1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("spine.bending_nm_per_deg") && e.contains("zero or more"), "{e}");
        // A run shorter than one rigid step would simulate nothing; drags
        // and the contact's damping time may be zero, not negative.
        let e = parse("name = \"x\"\n[numerics]\nend_time_s = 1e-4\n").unwrap_err().to_string();
        assert!(e.contains("numerics.end_time_s") && e.contains("shorter than one rigid step"), "{e}");
        for key in ["[contact]\ndamping_time_s", "[fetus]\ntrunk_linear_drag_n_s_per_m"] {
            assert!(parse(&format!("name = \"x\"\n{key} = 0.0\n")).is_ok(), "{key}");
            let e = parse(&format!("name = \"x\"\n{key} = -1.0\n")).unwrap_err().to_string();
            assert!(e.contains("must be zero or more"), "{e}");
        }
        let e = parse("name = \"x\"\n[start]\nposition = \"XYZ\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("start.position") && e.contains("LOT"), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\ninlet_ap_mm = 0.11\ninlet_ap_m = 0.11\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("inlet_ap_m"), "{e}");
        // A start past the neck's range of motion, either way.
        let e = parse("name = \"x\"\n[start]\nattitude_deg = 30.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("start.attitude_deg") && e.contains("neck.flexion_limit_deg"), "{e}");
        let e = parse("name = \"x\"\n[start]\nattitude_deg = -60.0\n[neck]\nextension_limit_deg = 50.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("start.attitude_deg") && e.contains("-50 to 19"), "{e}");
        assert!(parse("name = \"x\"\n[start]\nattitude_deg = 30.0\n[neck]\nflexion_limit_deg = 30.0\n").is_ok());
        let e = parse("name = \"x\"\n[floor]\nshear_modulus_pa = 16.5\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("floor.shear_modulus_pa") && e.contains("not kPa"), "{e}");
        let e = parse("name = \"x\"\n[trunk]\nbisacromial_mm = 12.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("trunk.bisacromial_mm") && e.contains("not cm"), "{e}");
        let e = parse("name = \"x\"\n[trunk]\nchest_breadth_mm = 10.8\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("trunk.chest_breadth_mm") && e.contains("not cm"), "{e}");
        let e = parse("name = \"x\"\n[trunk]\ncervical_spine_mm = 3.7\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("trunk.cervical_spine_mm") && e.contains("37 mm"), "{e}");
        let e = parse("name = \"x\"\n[trunk]\ntrunk_length_mm = 18.6\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("trunk.trunk_length_mm") && e.contains("186 mm"), "{e}");
        let e = parse("name = \"x\"\n[fetus]\natlanto_occipital_behind_deg = 60.0\n").unwrap_err().to_string();
        assert!(e.contains("fetus.atlanto_occipital_behind_deg") && e.contains("0 to 45"), "{e}");
        let e = parse("name = \"x\"\n[fetus]\natlanto_occipital_depth = 15.0\n").unwrap_err().to_string();
        assert!(e.contains("fetus.atlanto_occipital_depth") && e.contains("0.05 to 0.5"), "{e}");
        // A [floor.mesh] of one key keeps the runs' resolution, not the library's.
        let floor = parse("name = \"x\"\n[floor.mesh]\nsag_mm = 25.0\n").unwrap().floor.mesh;
        assert_eq!(floor, FloorParameters { sag_mm: 25.0, ..FloorSection::default().mesh });
        let e = parse("name = \"x\"\n[pelvis]\nsymphysis_length_mm = 4.5\n").unwrap_err().to_string();
        assert!(e.contains("pelvis.symphysis_length_mm") && e.contains("not cm"), "{e}");
        let e = parse("name = \"x\"\n[output]\nvtu_every_s = 1e-9\n").unwrap_err().to_string();
        assert!(e.contains("output.vtu_every_s") && e.contains("0.01"), "{e}");
        let e = parse("name = \"x\"\n[output]\nevery_s = 1e-5\n").unwrap_err().to_string();
        assert!(e.contains("output.every_s") && e.contains("rigid step"), "{e}");
        // A density in g/cm^3.
        for table in ["fetus", "floor"] {
            let e = parse(&format!("name = \"x\"\n[{table}]\ndensity_kg_per_m3 = 1.05\n"))
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("{table}.density_kg_per_m3")) && e.contains("g/cm^3"), "{e}");
        }
    }

    /// The scenario a run folder keeps names an imported pelvis so that it is
    /// found from there, whatever folder the run was started in or resumed from.
    #[test]
    fn an_imported_pelvis_is_found_from_the_run_folder() {
        let relative = Scenario::from_file(Path::new("../../scenarios/normal.toml")).unwrap();
        assert!(relative.base_dir.is_absolute() && relative.base_dir.ends_with("scenarios"), "{:?}", relative.base_dir);

        let dir = tempfile::tempdir().unwrap();
        let anatomy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/anatomy");
        std::fs::create_dir_all(dir.path().join("imp/anat")).unwrap();
        for file in ["visible-human-female-pelvis.landmarks.toml", "visible-human-female-pelvis.stl"] {
            std::fs::copy(anatomy.join(file), dir.path().join("imp/anat").join(file)).unwrap();
        }
        let file = dir.path().join("imp/s.toml");
        std::fs::write(&file, "name = \"x\"\n[pelvis]\nimport = \"anat/visible-human-female-pelvis.landmarks.toml\"\n")
            .unwrap();
        let scenario = Scenario::from_file(&file).unwrap();
        let landmarks = dir.path().join("imp/anat/visible-human-female-pelvis.landmarks.toml");
        let shown = scenario.to_toml().unwrap();
        assert!(shown.contains(&format!("import = {:?}", landmarks.display().to_string())), "{shown}");

        // The run folder's copy, read as `carus measure` reads it, and the
        // checkpoint's, as `--resume` reads it, with an unrelated base.
        std::fs::create_dir(dir.path().join("run")).unwrap();
        let copy = dir.path().join("run/scenario.toml");
        std::fs::write(&copy, &shown).unwrap();
        let measured = Scenario::from_file(&copy).unwrap();
        let resumed = Scenario::parse(Path::new("checkpoint.json"), &shown, PathBuf::from("elsewhere")).unwrap();
        for s in [&measured, &resumed] {
            assert_eq!(s.pelvis, PelvisSpec::Imported { landmarks_file: landmarks.clone() });
            s.pelvis.build(&s.base_dir).unwrap();
            assert_eq!(s.to_toml().unwrap(), shown, "written again unchanged");
        }
        // The run's record (run.json, which `carus view` builds from) keeps
        // the scenario without its folder: it names the file absolutely too.
        let recorded: Scenario = serde_json::from_str(&serde_json::to_string(&scenario.kept()).unwrap()).unwrap();
        assert_eq!(recorded.pelvis, PelvisSpec::Imported { landmarks_file: landmarks.clone() });
        recorded.pelvis.build(&recorded.base_dir).unwrap();
    }

    /// A mistake in `[pelvis]` is named at its own line and dotted path, as
    /// in every other table, whether the pelvis is generated or imported.
    /// A folder given for a scenario file is named as one; a run's folder
    /// gets the commands that use it.
    #[test]
    fn a_folder_given_for_a_scenario_says_what_to_do_with_it() {
        let dir = tempfile::tempdir().unwrap();
        let e = Scenario::from_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("a folder, not a scenario file") && e.contains("carus scenarios"), "{e}");
        std::fs::write(dir.path().join(crate::output::SCENARIO_FILE), "").unwrap();
        let e = Scenario::from_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains(&format!("carus run --resume {}", dir.path().display())) && e.contains("--out NEW_FOLDER"), "{e}");
    }

    /// A refusal that names keys the file left out says they are defaults;
    /// a key the file sets, or a built-in's, is not named so.
    #[test]
    fn keys_left_to_their_defaults_are_named_as_such() {
        let text = "name = \"x\"\n[pelvis]\ninlet_ap_mm = 132.0\n";
        let message = "inlet_oblique_mm = 124 is shorter than both inlet_ap_mm = 132 and inlet_transverse_mm = 130";
        let note = defaults_note_in(text, "pelvis", message).unwrap();
        assert_eq!(note, "inlet_oblique_mm and inlet_transverse_mm are the defaults, not in the file's [pelvis]: set them there too");
        let read = Scenario::parse(Path::new("x.toml"), text, PathBuf::new()).unwrap();
        assert_eq!(read.defaults_note("pelvis", message), Some(note));
        assert_eq!(defaults_note_in(text, "pelvis", "inlet_ap_mm = 132 is too long"), None);
        assert_eq!(Scenario::builtin("normal").unwrap().defaults_note("pelvis", message), None);
    }

    /// A `carus solve` job given for a scenario is named as one, with the
    /// command that solves it; so is a scenario given to `carus solve`.
    #[test]
    fn a_solve_job_and_a_scenario_are_told_apart() {
        let job = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cube_extension.toml");
        let e = Scenario::from_file(&job).unwrap_err().to_string();
        assert!(e.contains("this is a `carus solve` job") && e.contains(&format!("carus solve {} --out DIR", job.display())), "{e}");
        let scenario = Scenario::builtin("normal").unwrap().to_toml().unwrap();
        let e = carus_io::job::parse_job(Path::new("normal.toml"), &scenario).unwrap_err().to_string();
        assert!(e.contains("this is a labour scenario") && e.contains("carus run normal.toml"), "{e}");
        // An anatomy file, too.
        let anatomy = "[head]\nbiparietal_mm = 94.0\n";
        let e = Scenario::parse(Path::new("anatomy.toml"), anatomy, PathBuf::new()).unwrap_err().to_string();
        assert!(e.contains("this is an anatomy file") && e.contains("add `name"), "{e}");
        let e = carus_io::job::parse_job(Path::new("anatomy.toml"), anatomy).unwrap_err().to_string();
        assert!(e.contains("this is an anatomy file") && e.contains("carus mesh floor anatomy.toml"), "{e}");
    }

    /// A device that never ends is named, not read until the memory runs out.
    #[cfg(unix)]
    #[test]
    fn an_endless_device_given_for_a_scenario_is_refused() {
        let e = Scenario::from_file(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("/dev/zero") && e.contains("did not end within 256 MiB"), "{e}");
    }

    /// From the command line an import replaces a generated pelvis, and a
    /// generated pelvis's table replaces an import.
    #[test]
    fn a_pelvis_is_swapped_whole_from_the_command_line() {
        let normal = Scenario::builtin("normal").unwrap();
        let real = normal.with_setting("pelvis.import", "visible-human-female").unwrap();
        assert!(matches!(real.pelvis, PelvisSpec::Imported { .. }), "{:?}", real.pelvis);
        let back = real.with_setting("pelvis", "{inlet_ap_mm = 105.0}").unwrap();
        assert_eq!(back.pelvis, PelvisSpec::Generated(PelvisDiameters { inlet_ap_mm: 105.0, ..Default::default() }));
        let e = real.with_setting("pelvis.inlet_ap_mm", "105").unwrap_err().to_string();
        assert!(e.contains("cannot be combined") && e.contains("--set 'pelvis={inlet_ap_mm=...}'"), "{e}");
    }

    /// One way-point's value is set by its index, as errors name it.
    #[test]
    fn one_way_point_is_set_by_its_index() {
        let textbook = Scenario::builtin("textbook").unwrap();
        let turned = textbook.with_setting("trajectory.waypoints[2].theta_deg", "-30").unwrap();
        assert_eq!(turned.trajectory.waypoints[2].theta_deg, -30.0);
        assert_eq!(turned.trajectory.waypoints[3], textbook.trajectory.waypoints[3]);
        let count = textbook.trajectory.waypoints.len();
        let e = textbook.with_setting(&format!("trajectory.waypoints[{count}].theta_deg"), "0").unwrap_err().to_string();
        assert!(e.contains(&format!("`waypoints` has {count} entries, counted from 0: there is no [{count}]")), "{e}");
        let e = textbook.with_setting("trajectory.waypoints[x].theta_deg", "0").unwrap_err().to_string();
        assert!(e.contains("is not an entry's name"), "{e}");
    }

    /// A pelvis's landmarks file given as a scenario says what it is and how
    /// to use it.
    #[test]
    fn a_landmarks_file_given_as_a_scenario_says_how_to_use_it() {
        let path = carus_anatomy::import::visible_human_female_pelvis_path();
        let e = Scenario::from_file(&path).unwrap_err().to_string();
        assert!(e.contains("this is a pelvis's landmarks file") && e.contains("`[pelvis]` and `import = "), "{e}");
    }

    /// A wrong type in a nested table names the whole key and its own
    /// line, and says the type as a reader would, not as Rust does.
    #[test]
    fn a_wrong_type_in_a_nested_table_names_the_whole_key() {
        let e = parse("name = \"x\"\n[floor.mesh]\nelements_across = 6\nelements_around = 32.5\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:4: `floor.mesh.elements_around`: invalid type: floating point `32.5`, expected a whole number"), "{e}");
        assert!(e.contains("this key takes a whole number") && !e.contains("usize"), "{e}");
        let normal = Scenario::builtin("normal").unwrap();
        let e = normal.with_setting("floor.mesh.elements_around", "32.5").unwrap_err().to_string();
        assert!(e.contains("`floor.mesh.elements_around`: invalid type") && !e.contains("\nin `"), "{e}");
        let e = normal.with_setting("contact.friction", "true").unwrap_err().to_string();
        assert!(e.contains("expected a number") && !e.contains("f64"), "{e}");
        let e = normal.with_setting("contact", "0.3").unwrap_err().to_string();
        assert!(e.contains("expected a table of keys") && !e.contains("struct"), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\nimport = 5\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `pelvis.import`: invalid type: integer `5`, expected a file's path in quotes"), "{e}");
    }

    /// A count given a sign, or a number past TOML's whole numbers, is
    /// named at its line as that, with the normal scenario's value for an
    /// example; in a file and as a setting alike.
    #[test]
    fn a_negative_or_huge_count_says_what_it_takes() {
        let e = parse("name = \"x\"\n[floor.mesh]\nelements_around = -32\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `floor.mesh.elements_around`: invalid value: integer `-32`, expected a whole number of 0 or more"), "{e}");
        assert!(e.contains("hint: give a whole number of 0 or more, e.g. `floor.mesh.elements_around = 32`"), "{e}");
        let e = parse("name = \"x\"\n[floor.mesh]\nelements_around = 99999999999999999999\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `floor.mesh.elements_around`: the whole number `99999999999999999999` is too large"), "{e}");
        assert!(e.contains("hint: give a smaller number, e.g. `floor.mesh.elements_around = 32`") && !e.contains("i128"), "{e}");
        let normal = Scenario::builtin("normal").unwrap();
        let e = normal.with_setting("floor.mesh.elements_around", "-32").unwrap_err().to_string();
        assert!(e.starts_with("`floor.mesh.elements_around = -32`:") && e.contains("of 0 or more"), "{e}");
        let e = normal.with_setting("floor.mesh.elements_around", "99999999999999999999").unwrap_err().to_string();
        assert!(e.contains("is too large") && e.contains("give a smaller number, e.g. floor.mesh.elements_around=32"), "{e}");
        assert!(!e.contains("invalid type: string"), "{e}");
    }

    /// Of several settings, a reading error names only the one at fault.
    #[test]
    fn a_refused_setting_is_named_alone() {
        let normal = Scenario::builtin("normal").unwrap();
        let setting = |k: &str, v: &str| (k.to_string(), v.to_string());
        let e = normal.with_settings(&[setting("contact.friction", "abc"), setting("numerics.end_time_s", "0.02")]).unwrap_err().to_string();
        assert!(e.starts_with("`contact.friction = abc`: ") && !e.contains("end_time_s"), "{e}");
        let e = normal.with_settings(&[setting("expulsion.period_s", "8"), setting("expulsion.periods", "32")]).unwrap_err().to_string();
        assert!(e.starts_with("`expulsion.periods = 32`: ") && e.contains("unknown field"), "{e}");
        let e = normal.with_settings(&[setting("numerics.end_time_s", "0.02"), setting("expulsion", "{periods=3}")]).unwrap_err().to_string();
        assert!(e.starts_with("`expulsion = {periods=3}`: `expulsion.periods`: unknown field"), "{e}");
    }

    #[test]
    fn a_mistake_in_the_pelvis_table_names_its_line_and_key() {
        let s = parse("name = \"x\"\n[pelvis]\ninlet_ap_mm = 100.0\n").unwrap();
        assert_eq!(s.pelvis, PelvisSpec::Generated(PelvisDiameters { inlet_ap_mm: 100.0, ..Default::default() }));
        let s = parse("name = \"x\"\n[pelvis]\n").unwrap();
        assert_eq!(s.pelvis, PelvisSpec::default());
        let s = parse(&format!("name = \"x\"\n[pelvis]\nimport = {VISIBLE_HUMAN_FEMALE:?}\n")).unwrap();
        assert_eq!(s.pelvis, PelvisSpec::Imported { landmarks_file: VISIBLE_HUMAN_FEMALE.into() });

        let e = parse("name = \"x\"\n[pelvis]\nmid_ap_mm = 115.0\ninterspinous_mm = \"102\"\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:4: `pelvis.interspinous_mm`: invalid type: string \"102\""), "{e}");
        assert!(e.contains("numbers without quotes"), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\nmid_ap_mm = 115.0\ninlet_apmm = 110.0\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:4: `pelvis.inlet_apmm`: unknown field `inlet_apmm`"), "{e}");
        assert!(e.contains("expected one of `inlet_ap_mm`, `inlet_transverse_mm`") && e.contains("`import`"), "{e}");
        assert!(e.contains("check the spelling"), "{e}");
        // toml hands the keys over in its own order: the second of the pair met is named.
        let e = parse("name = \"x\"\n[pelvis]\nmid_ap_mm = 115.0\nimport = \"a.toml\"\n").unwrap_err().to_string();
        assert!(
            ["test.toml:3: `pelvis.mid_ap_mm`: ", "test.toml:4: `pelvis.import`: "].iter().any(|at| e.starts_with(at))
                && e.contains("`import` and `mid_ap_mm` cannot be combined"),
            "{e}"
        );
        let e = parse("name = \"x\"\n[pelvis]\nimport = \"a.toml\"\nmid_ap_mm = 115.0\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:4: `pelvis.mid_ap_mm`: `import` and `mid_ap_mm` cannot be combined"), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\nimport = 3\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `pelvis.import`: invalid type"), "{e}");
    }

    /// `force_max_n = 120 N`: TOML would say to quote it, which only leads
    /// to a type error; the number is to be written alone.
    #[test]
    fn a_unit_written_in_a_value_is_refused_with_the_key_s_unit() {
        for value in ["120N", "120 N", "120 n # peak"] {
            let e = parse(&format!("name = \"x\"\n[expulsion]\nforce_max_n = {value}\n")).unwrap_err().to_string();
            assert!(e.starts_with("test.toml:3: `expulsion.force_max_n`: a unit after the number"), "{e}");
            assert!(e.contains("write the number alone, `force_max_n = 120`") && e.contains("newtons"), "{e}");
        }
        let e = parse("name = \"x\"\n[head]\nbiparietal_mm = 9.5cm\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `head.biparietal_mm`: a unit after the number in `9.5cm`"), "{e}");
        assert!(e.contains("converted to millimetres") && e.contains("`_mm`"), "{e}");
        let e = parse("name = \"x\"\n[floor.mesh]\nthickness_mm = 1e1 mm\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `floor.mesh.thickness_mm`") && e.contains("`thickness_mm = 1e1`"), "{e}");
        let e = parse("name = \"x\"\n[contact]\nfriction = 0.3 mu\n").unwrap_err().to_string();
        assert!(e.contains("`contact.friction`") && e.contains("this key takes a plain number"), "{e}");
        // A bare word is not a unit, nor a key that takes no number a
        // number's key: TOML's own message stands.
        let e = parse("name = \"x\"\n[start]\nposition = LOT\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: string values must be quoted"), "{e}");
        let e = parse("name = 2nd\n").unwrap_err().to_string();
        assert!(!e.contains("a unit after the number") && !e.contains("plain number"), "{e}");
        // The same on the command line (`--set`).
        let normal = Scenario::builtin("normal").unwrap();
        let e = normal.with_setting("expulsion.force_max_n", "120 N").unwrap_err().to_string();
        assert!(e.contains("`expulsion.force_max_n`: a unit after the number") && e.contains("`force_max_n = 120`"), "{e}");
        // An exponent is no unit: a number too large is named as one.
        let e = normal.with_setting("contact.friction", "1e400").unwrap_err().to_string();
        assert!(e.contains("contact.friction = 1e400") && e.contains("beyond the largest a value can hold"), "{e}");
        // A word Rust would read as infinity is still a word (a name, here).
        assert_eq!(normal.with_setting("name", "Infinity").unwrap().name, "Infinity");
        assert!(normal.with_setting("start.position", "LOT").is_ok());
    }

    /// A misspelt built-in pelvis is told as neither a file nor a built-in,
    /// with the built-in names.
    #[test]
    fn a_misspelt_builtin_pelvis_is_named_with_the_builtins() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("s.toml");
        std::fs::write(&file, "name = \"x\"\n\n[pelvis]\nimport = \"visible-human-femal\"\n").unwrap();
        let e = Scenario::from_file(&file).unwrap_err().to_string();
        let resolved = dir.path().join("visible-human-femal");
        assert!(e.starts_with(&format!("{}:4: `pelvis.import`: \"visible-human-femal\" is neither a file", file.display())), "{e}");
        assert!(e.contains(&format!("({} does not exist)", resolved.display())), "{e}");
        assert!(e.contains(&format!("`{VISIBLE_HUMAN_FEMALE}`")), "{e}");
        let e = parse("name = \"x\"\n[pelvis]\nimport = \"\"\n").unwrap_err().to_string();
        assert!(e.starts_with("test.toml:3: `pelvis.import`: is empty: it names no landmarks file"), "{e}");
    }

    #[test]
    fn keys_left_out_take_the_defaults() {
        let s = parse("name = \"minimal\"\n").unwrap();
        assert_eq!(s.contact.friction, 0.35);
        assert_eq!(s.start.position, Position::LOT);
        assert_eq!(s.neck.extension_nm_per_deg, 0.04);
        let frictionless = parse("name = \"x\"\n[contact]\nfriction = 0.0\n").unwrap();
        assert_eq!(frictionless.contact.friction, 0.0);
    }

    /// The dry normal case is the normal case with the seed's friction,
    /// and nothing else changed; every other built-in runs in the wetted
    /// canal.
    #[test]
    fn the_dry_normal_case_differs_from_normal_in_its_friction_alone() {
        let normal = Scenario::builtin("normal").unwrap();
        let mut dry = Scenario::builtin("normal-dry").unwrap();
        assert_eq!((normal.contact.friction, dry.contact.friction), (WETTED_CANAL_FRICTION, 0.35));
        assert_eq!(dry.contact.friction, ContactSection::default().friction);
        dry.contact.friction = normal.contact.friction;
        dry.name = normal.name.clone();
        dry.description = normal.description.clone();
        assert_eq!(dry, normal);
        for (name, _) in BUILTINS.iter().filter(|(n, _)| *n != "normal-dry") {
            assert_eq!(Scenario::builtin(name).unwrap().contact.friction, WETTED_CANAL_FRICTION, "{name}");
        }
    }
}
