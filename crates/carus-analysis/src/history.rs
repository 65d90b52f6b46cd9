//! The pose history: what a run (forward physics, imposed trajectory or
//! hybrid alike) records, and all the detector ever reads.
//!
//! Constant data (head and trunk geometry in their body frames, the canal)
//! is kept apart from the per-sample state (poses, forces). Everything is SI
//! and in the pelvis frame of CONVENTIONS.md, except the clinical diameter
//! `biparietal_mm`, which keeps its canonical name.

use crate::canal::BirthCanal;
use carus_anatomy::fetus::{FetalHead, Trunk};
use glam::DVec3;
use serde::{Deserialize, Serialize};

pub use carus_anatomy::pose::RigidPose;

/// The fetal head in its own body frame (constant over a run).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeadGeometry {
    /// Head centre (the biparietal diameter's midpoint), m.
    pub centre_m: DVec3,
    /// Unit occipitofrontal direction `o` (occiput towards forehead).
    pub occipitofrontal: DVec3,
    /// Unit vertex direction `v` (foramen magnum towards vertex), orthogonal to `o`.
    pub vertex: DVec3,
    /// Biparietal diameter, mm (canonical name of CONVENTIONS.md).
    pub biparietal_mm: f64,
    /// Points of the skull surface (or a sampling of it dense enough to
    /// find the leading point), m.
    pub skull_points_m: Vec<DVec3>,
}

/// The fetal trunk in its own body frame (constant over a run).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrunkGeometry {
    /// Centre of the trunk (expulsion ends when it passes the outlet), m.
    pub centre_m: DVec3,
    /// Tip of the fetal right shoulder (acromion), m.
    pub right_acromion_m: DVec3,
    /// Tip of the fetal left shoulder (acromion), m.
    pub left_acromion_m: DVec3,
    /// Unit spine direction `k`: from the atlanto-occipital pivot along the
    /// spine towards the breech.
    pub spine: DVec3,
}

/// The fetal body that carried the largest contact force at a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FetalPart {
    Head,
    /// The trunk (thorax and, when the spine bends, the lower trunk).
    Trunk,
}

impl FetalPart {
    /// The name used in JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            FetalPart::Head => "head",
            FetalPart::Trunk => "trunk",
        }
    }
}

/// The part of the mother that carried the largest contact force on the
/// fetus at a sample (the labour crate classifies its contacts into these).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSite {
    Symphysis,
    PubicArch,
    SacralPromontory,
    Sacrum,
    Coccyx,
    IschialSpines,
    PelvicSidewall,
    /// The sacrospinous ligament with the coccygeus on it, closing the
    /// canal behind the side wall below the ischial spines.
    SacrospinousLigament,
    /// The lower anterior abdominal wall, closing the front of the false
    /// pelvis above the pubis.
    AbdominalWall,
    /// The obturator membrane with the obturator internus on it, closing
    /// the obturator foramen in the side wall.
    ObturatorMembrane,
    PelvicFloor,
}

impl ContactSite {
    /// Every site, for listing their names.
    pub const ALL: [ContactSite; 11] = [
        ContactSite::Symphysis,
        ContactSite::PubicArch,
        ContactSite::SacralPromontory,
        ContactSite::Sacrum,
        ContactSite::Coccyx,
        ContactSite::IschialSpines,
        ContactSite::PelvicSidewall,
        ContactSite::SacrospinousLigament,
        ContactSite::AbdominalWall,
        ContactSite::ObturatorMembrane,
        ContactSite::PelvicFloor,
    ];

    /// The name used in JSON and reports ("sacral_promontory", ...).
    pub fn name(self) -> &'static str {
        match self {
            ContactSite::Symphysis => "symphysis",
            ContactSite::PubicArch => "pubic_arch",
            ContactSite::SacralPromontory => "sacral_promontory",
            ContactSite::Sacrum => "sacrum",
            ContactSite::Coccyx => "coccyx",
            ContactSite::IschialSpines => "ischial_spines",
            ContactSite::PelvicSidewall => "pelvic_sidewall",
            ContactSite::SacrospinousLigament => "sacrospinous_ligament",
            ContactSite::AbdominalWall => "abdominal_wall",
            ContactSite::ObturatorMembrane => "obturator_membrane",
            ContactSite::PelvicFloor => "pelvic_floor",
        }
    }
}

/// One recorded instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseSample {
    pub time_s: f64,
    pub head: RigidPose,
    /// Present exactly when the history has a [`TrunkGeometry`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trunk: Option<RigidPose>,
    /// The lower trunk (abdomen and hips) when the spine bends; `trunk` is
    /// then the thorax. The detector does not read it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_trunk: Option<RigidPose>,
    /// Expulsion force acting on the fetus, N.
    pub expulsion_force_n: DVec3,
    /// Sum of the contact forces of the bony pelvis on the fetus, N.
    pub bone_contact_force_n: DVec3,
    /// Sum of the contact forces of the pelvic floor on the fetus, N.
    pub floor_contact_force_n: DVec3,
    /// Which part carried the largest contact force, when the run knows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dominant_contact: Option<ContactSite>,
    /// The fetal body that bore most of that site's force.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dominant_part: Option<FetalPart>,
}

/// A whole recorded run: constant geometry plus the samples in time order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseHistory {
    pub head: HeadGeometry,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trunk: Option<TrunkGeometry>,
    pub canal: BirthCanal,
    pub samples: Vec<PoseSample>,
}

/// A vector's length that does not overflow where its components do not:
/// squared, a coordinate of 1e300 (a slip of exponent) would make it
/// infinite, and the message would say `inf m`.
fn length_unbounded(p: DVec3) -> f64 {
    let largest = p.abs().max_element();
    match largest > 0.0 && largest.is_finite() {
        true => largest * (p / largest).length(),
        false => p.length(),
    }
}

/// A distance in metres as a message shows it: to the millimetre, or in
/// exponent form when huge (a plain 1e300 prints three hundred digits).
fn shown_distance(metres: f64) -> String {
    match metres.abs() < 1e6 {
        true => format!("{metres:.3}"),
        false => format!("{metres:.3e}"),
    }
}

/// What is wrong with a pose history, and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HistoryError {
    #[error("the pose history has {count} samples; the detector needs at least 2")]
    TooFewSamples { count: usize },
    #[error("sample {index}: {field} is not finite; every number must be a real value")]
    NotFinite { index: usize, field: &'static str },
    #[error("sample {index}: time_s = {} does not increase on the previous sample's {}; samples must be in strictly increasing time", carus_io::shown_number(*time_s), carus_io::shown_number(*previous_s))]
    TimeNotIncreasing {
        index: usize,
        time_s: f64,
        previous_s: f64,
    },
    #[error("sample {index}: the {body} orientation quaternion has length {length}; give a unit quaternion")]
    NotUnitQuaternion {
        index: usize,
        body: &'static str,
        length: f64,
    },
    #[error("sample {index} has a trunk pose but the history has no trunk geometry; add `trunk` or drop the sample's trunk pose")]
    TrunkPoseWithoutGeometry { index: usize },
    #[error("sample {index} has no trunk pose but the history has trunk geometry; record the trunk at every sample or drop `trunk`")]
    MissingTrunkPose { index: usize },
    #[error("sample {index}: {field} lies {} m from the pelvis origin, farther than a fetus goes in labour ({FARTHEST_POSITION_M} m); positions are metres in the pelvis frame (CONVENTIONS.md): divide a history written in millimetres by 1000", shown_distance(*.distance_m))]
    TooFar {
        index: usize,
        field: &'static str,
        distance_m: f64,
    },
    #[error("head geometry: {problem}")]
    BadHead { problem: String },
    #[error("trunk geometry: {problem}")]
    BadTrunk { problem: String },
    #[error("pose history JSON: {0}")]
    Json(String),
}

/// Farthest a recorded position may lie from its frame's origin, metres: a
/// fetus in labour moves a few tenths of a metre through the pelvis (one
/// born and left to drift for a minute, a metre or two) and a skull point
/// lies a decimetre from the head's centre, so a figure past this is a
/// length written in millimetres, not metres.
pub const FARTHEST_POSITION_M: f64 = 10.0;

/// Biparietal diameters a head can have, millimetres: below it the figure
/// is in centimetres or metres (a term head's is about 95 mm,
/// REFERENCE_DATA.md).
const BIPARIETAL_MM: std::ops::RangeInclusive<f64> = 10.0..=1000.0;

/// Tolerance on unit lengths and orthogonality of given directions: loose
/// enough for values written to JSON with a dozen digits. A checkpoint's
/// orientations are held to it too (carus-labour).
pub const UNIT_TOLERANCE: f64 = 1e-6;

fn check_unit(v: DVec3, what: &str) -> Result<(), String> {
    if !v.is_finite() || (v.length() - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!("{what} must be a unit vector, got {v}"));
    }
    Ok(())
}

impl HeadGeometry {
    /// Checks the axes, the diameter and the skull points.
    pub fn validate(&self) -> Result<(), HistoryError> {
        let bad = |problem: String| HistoryError::BadHead { problem };
        check_unit(self.occipitofrontal, "occipitofrontal").map_err(bad)?;
        check_unit(self.vertex, "vertex").map_err(bad)?;
        if self.occipitofrontal.dot(self.vertex).abs() > UNIT_TOLERANCE {
            return Err(bad("occipitofrontal and vertex must be orthogonal".into()));
        }
        if !self.centre_m.is_finite() {
            return Err(bad("centre_m is not finite".into()));
        }
        if !(self.biparietal_mm.is_finite() && BIPARIETAL_MM.contains(&self.biparietal_mm)) {
            return Err(bad(format!(
                "biparietal_mm = {} is not a head's biparietal diameter in millimetres (a term head's is about 95)",
                self.biparietal_mm
            )));
        }
        if self.skull_points_m.is_empty() {
            return Err(bad(
                "skull_points_m is empty; give the skull surface points".into(),
            ));
        }
        if let Some(i) = self.skull_points_m.iter().position(|p| !p.is_finite()) {
            return Err(bad(format!("skull point {i} is not finite")));
        }
        let far = |p: &DVec3| (*p - self.centre_m).length() > FARTHEST_POSITION_M;
        if let Some(i) = self.skull_points_m.iter().position(far) {
            return Err(bad(format!(
                "skull point {i} lies {:.3} m from centre_m; skull points are metres in the head's frame: divide millimetres by 1000",
                (self.skull_points_m[i] - self.centre_m).length()
            )));
        }
        Ok(())
    }

    /// The geometry of a carus-anatomy head, whose frame is already the
    /// detector's: origin at the head centre, x = o, y = b, z = v; every
    /// surface vertex is a candidate leading point.
    pub fn from_fetal_head(head: &FetalHead) -> Self {
        HeadGeometry {
            centre_m: DVec3::ZERO,
            occipitofrontal: DVec3::X,
            vertex: DVec3::Z,
            biparietal_mm: head.diameters.biparietal_mm,
            skull_points_m: head.surface.vertices.clone(),
        }
    }

    /// `b = v x o`, towards the fetal left, in the body frame.
    pub fn biparietal_axis(&self) -> DVec3 {
        self.vertex.cross(self.occipitofrontal)
    }
}

impl TrunkGeometry {
    /// The geometry of a carus-anatomy trunk, in its own frame (origin at
    /// the atlanto-occipital pivot, x ventral, y fetal left, z cranial).
    pub fn from_trunk(trunk: &Trunk) -> Self {
        TrunkGeometry {
            centre_m: trunk.landmarks.centre,
            right_acromion_m: trunk.landmarks.acromion_right,
            left_acromion_m: trunk.landmarks.acromion_left,
            spine: trunk.spine_axis,
        }
    }

    /// Checks the spine direction and the shoulder points.
    pub fn validate(&self) -> Result<(), HistoryError> {
        let bad = |problem: String| HistoryError::BadTrunk { problem };
        check_unit(self.spine, "spine").map_err(bad)?;
        for (name, p) in [
            ("centre_m", self.centre_m),
            ("right_acromion_m", self.right_acromion_m),
            ("left_acromion_m", self.left_acromion_m),
        ] {
            if !p.is_finite() {
                return Err(bad(format!("{name} is not finite")));
            }
        }
        if (self.left_acromion_m - self.right_acromion_m).length() < 1e-6 {
            return Err(bad("the two acromions coincide".into()));
        }
        Ok(())
    }
}

impl PoseHistory {
    /// Checks everything the detector relies on, naming the first problem.
    pub fn validate(&self) -> Result<(), HistoryError> {
        self.head.validate()?;
        if let Some(trunk) = &self.trunk {
            trunk.validate()?;
        }
        if self.samples.len() < 2 {
            return Err(HistoryError::TooFewSamples {
                count: self.samples.len(),
            });
        }
        for (index, s) in self.samples.iter().enumerate() {
            let finite = [
                ("time_s", s.time_s.is_finite()),
                ("head.position_m", s.head.position_m.is_finite()),
                ("head.orientation", s.head.orientation.is_finite()),
                ("expulsion_force_n", s.expulsion_force_n.is_finite()),
                ("bone_contact_force_n", s.bone_contact_force_n.is_finite()),
                ("floor_contact_force_n", s.floor_contact_force_n.is_finite()),
                (
                    "trunk.position_m",
                    s.trunk.is_none_or(|t| t.position_m.is_finite()),
                ),
                (
                    "trunk.orientation",
                    s.trunk.is_none_or(|t| t.orientation.is_finite()),
                ),
            ];
            if let Some((field, _)) = finite.iter().find(|(_, ok)| !ok) {
                return Err(HistoryError::NotFinite { index, field });
            }
            let positions = [("head.position_m", Some(s.head.position_m)), ("trunk.position_m", s.trunk.map(|t| t.position_m))];
            for (field, position) in positions {
                let distance_m = position.map_or(0.0, length_unbounded);
                if distance_m > FARTHEST_POSITION_M {
                    return Err(HistoryError::TooFar { index, field, distance_m });
                }
            }
            if index > 0 {
                let previous_s = self.samples[index - 1].time_s;
                if s.time_s <= previous_s {
                    return Err(HistoryError::TimeNotIncreasing {
                        index,
                        time_s: s.time_s,
                        previous_s,
                    });
                }
            }
            let poses = [("head", Some(s.head)), ("trunk", s.trunk)];
            for (body, pose) in poses {
                if let Some(pose) = pose {
                    let length = pose.orientation.length();
                    if (length - 1.0).abs() > UNIT_TOLERANCE {
                        return Err(HistoryError::NotUnitQuaternion {
                            index,
                            body,
                            length,
                        });
                    }
                }
            }
            match (&self.trunk, s.trunk) {
                (None, Some(_)) => return Err(HistoryError::TrunkPoseWithoutGeometry { index }),
                (Some(_), None) => return Err(HistoryError::MissingTrunkPose { index }),
                _ => {}
            }
        }
        Ok(())
    }

    /// Reads and validates a history from JSON text.
    pub fn from_json_str(text: &str) -> Result<Self, HistoryError> {
        let mut json = serde_json::Deserializer::from_str(text);
        let history: PoseHistory = serde_path_to_error::deserialize(&mut json).map_err(|e| {
            let at = e.path().to_string();
            HistoryError::Json(if at == "." { e.inner().to_string() } else { format!("at {at}: {}", e.inner()) })
        })?;
        history.validate()?;
        Ok(history)
    }

    /// The history as JSON text (the inverse of [`PoseHistory::from_json_str`]).
    pub fn to_json_string(&self) -> Result<String, HistoryError> {
        serde_json::to_string(self).map_err(|e| HistoryError::Json(e.to_string()))
    }
}
