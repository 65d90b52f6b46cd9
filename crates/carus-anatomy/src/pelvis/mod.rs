//! The maternal bony pelvis: landmarks, obstetric planes, pelvic axis and the
//! triangle surface of the birth canal, for generated and imported pelvises alike.
//!
//! Everything here is in the pelvis frame of CONVENTIONS.md (metres): origin
//! at the inlet centre (midpoint of the obstetric conjugate), x to the
//! mother's right, y anterior, z cranial. Planes and axis are computed from
//! the landmarks by [`PelvisPlanes::from_landmarks`], the same way for every
//! pelvis, so a measured value means the same thing for a generated and an
//! imported one.

mod landmarks;

pub use landmarks::{PelvisLandmarks, LANDMARK_NAMES};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::axis::{AxisError, PelvicAxis, Plane};
use crate::surface::TriSurface;

/// Why a pelvis cannot be assembled from its landmarks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PelvisError {
    #[error("landmark `{name}` has a non-finite coordinate")]
    NonFiniteLandmark { name: &'static str },
    #[error("the {plane} plane is degenerate: its antero-posterior line ({posterior} to {anterior}) is parallel to its transverse line or has no length; check those landmarks")]
    DegeneratePlane { plane: &'static str, posterior: &'static str, anterior: &'static str },
    #[error("the pelvic axis cannot be built: {0}")]
    Axis(#[from] AxisError),
}

/// The four obstetric planes, each with its centre and caudal unit normal.
///
/// Every plane contains its antero-posterior diameter and is parallel to its
/// transverse diameter; its centre is the midpoint of the antero-posterior
/// diameter (for the inlet this is the origin of the pelvis frame):
/// - inlet: sacral promontory to upper inner border of the symphysis,
///   transverse between the iliopectineal points;
/// - greatest dimensions: junction of S2 and S3 to the middle of the inner
///   surface of the symphysis, transverse parallel to the inlet transverse;
/// - mid-pelvis: junction of S4 and S5 to the lower border of the symphysis,
///   transverse between the ischial spines;
/// - outlet: coccyx tip to the lower border of the symphysis, transverse
///   between the ischial tuberosities.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PelvisPlanes {
    pub inlet: Plane,
    pub greatest: Plane,
    pub mid: Plane,
    pub outlet: Plane,
}

impl PelvisPlanes {
    /// Computes the four planes from the landmarks (see the type's docs).
    pub fn from_landmarks(l: &PelvisLandmarks) -> Result<Self, PelvisError> {
        l.check_finite()?;
        let inlet_transverse = l.iliopectineal_right - l.iliopectineal_left;
        Ok(PelvisPlanes {
            inlet: plane(
                "inlet",
                ("sacral_promontory", l.sacral_promontory),
                ("symphysis_upper", l.symphysis_upper),
                inlet_transverse,
            )?,
            greatest: plane(
                "greatest dimensions",
                ("sacrum_s2_s3", l.sacrum_s2_s3),
                ("symphysis_upper/symphysis_lower midpoint", l.symphysis_middle()),
                inlet_transverse,
            )?,
            mid: plane(
                "mid-pelvis",
                ("sacrum_s4_s5", l.sacrum_s4_s5),
                ("symphysis_lower", l.symphysis_lower),
                l.ischial_spine_right - l.ischial_spine_left,
            )?,
            outlet: plane(
                "outlet",
                ("coccyx_tip", l.coccyx_tip),
                ("symphysis_lower", l.symphysis_lower),
                l.ischial_tuberosity_right - l.ischial_tuberosity_left,
            )?,
        })
    }

    /// The planes from the inlet down, in the order the axis passes them.
    pub fn in_order(&self) -> [Plane; 4] {
        [self.inlet, self.greatest, self.mid, self.outlet]
    }
}

/// The plane containing the antero-posterior line and parallel to `transverse`
/// (right minus left), centred on the antero-posterior midpoint, normal caudal:
/// (anterior - posterior) x (right - left) is -z for a pelvis in its own frame.
fn plane(
    name: &'static str,
    (posterior_name, posterior): (&'static str, DVec3),
    (anterior_name, anterior): (&'static str, DVec3),
    transverse: DVec3,
) -> Result<Plane, PelvisError> {
    let normal = (anterior - posterior).cross(transverse);
    let scale = (anterior - posterior).length() * transverse.length();
    if !(normal.length() > 1e-6 * scale && scale > 0.0) {
        return Err(PelvisError::DegeneratePlane { plane: name, posterior: posterior_name, anterior: anterior_name });
    }
    Ok(Plane { centre: 0.5 * (anterior + posterior), normal: normal.normalize() })
}

/// A maternal bony pelvis in its own frame: the surface of the bony birth
/// canal, its landmarks, the obstetric planes and the pelvic axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Pelvis {
    pub surface: TriSurface,
    pub landmarks: PelvisLandmarks,
    pub planes: PelvisPlanes,
    pub axis: PelvicAxis,
}

impl Pelvis {
    /// Assembles a pelvis from landmarks and a surface already in the pelvis
    /// frame, computing planes and axis the same way for every pelvis.
    /// Importers first map their mesh with [`PelvisLandmarks::to_pelvis_frame`].
    pub fn from_landmarks(landmarks: PelvisLandmarks, surface: TriSurface) -> Result<Self, PelvisError> {
        let planes = PelvisPlanes::from_landmarks(&landmarks)?;
        let right = landmarks.iliopectineal_right - landmarks.iliopectineal_left;
        let axis = PelvicAxis::new(&planes.in_order(), right)?;
        Ok(Pelvis { surface, landmarks, planes, axis })
    }

    /// Arc length of each plane along the axis: inlet, greatest, mid, outlet.
    pub fn plane_sigmas(&self) -> [f64; 4] {
        let s = self.axis.plane_sigmas();
        [s[0], s[1], s[2], s[3]]
    }
}
