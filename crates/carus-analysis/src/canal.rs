//! The birth canal as the detector sees it: the four obstetric planes and
//! the pelvic axis (curve of Carus) through their centres.
//!
//! The axis itself is carus-anatomy's [`PelvicAxis`]; this module only keeps
//! the planes it is built from, so a pose history can carry its canal as
//! plain data (JSON) and rebuild the identical axis when read back.

use crate::history::RigidPose;
use carus_anatomy::axis::{AxisError, PelvicAxis, Plane};
use carus_anatomy::Pelvis;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The four planes of the canal in the pelvis frame (metres, caudal normals),
/// inlet first. This is what a pose history stores.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CanalPlanes {
    pub inlet: Plane,
    pub greatest_dimensions: Plane,
    /// Mid-pelvis plane through the ischial spines (station 0).
    pub spines: Plane,
    pub outlet: Plane,
    /// The mother's right (+x of the pelvis frame, or the pelvis's own
    /// inlet transverse), from which the axis's transverse x(sigma) is made.
    pub right: DVec3,
}

/// Planes plus the axis built from them, with the arc lengths the detector
/// uses at every sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CanalPlanes", into = "CanalPlanes")]
pub struct BirthCanal {
    planes: CanalPlanes,
    axis: PelvicAxis,
}

impl BirthCanal {
    /// Builds the axis through the plane centres, inlet first.
    pub fn new(planes: CanalPlanes) -> Result<Self, AxisError> {
        let axis = PelvicAxis::new(
            &[
                planes.inlet,
                planes.greatest_dimensions,
                planes.spines,
                planes.outlet,
            ],
            planes.right,
        )?;
        Ok(BirthCanal { planes, axis })
    }

    /// The canal of a pelvis, generated or imported: its planes, with the
    /// axis rebuilt from them exactly as [`Pelvis::from_landmarks`] builds it
    /// (so a canal read back from JSON is the same canal).
    pub fn from_pelvis(pelvis: &Pelvis) -> Result<Self, AxisError> {
        let p = &pelvis.planes;
        let right = pelvis.landmarks.iliopectineal_right - pelvis.landmarks.iliopectineal_left;
        let planes = CanalPlanes {
            inlet: p.inlet,
            greatest_dimensions: p.greatest,
            spines: p.mid,
            outlet: p.outlet,
            right,
        };
        BirthCanal::new(planes)
    }

    pub fn planes(&self) -> &CanalPlanes {
        &self.planes
    }

    pub fn axis(&self) -> &PelvicAxis {
        &self.axis
    }

    pub fn inlet(&self) -> &Plane {
        &self.planes.inlet
    }

    pub fn spines(&self) -> &Plane {
        &self.planes.spines
    }

    pub fn outlet(&self) -> &Plane {
        &self.planes.outlet
    }

    /// Arc length of the ischial-spine plane's centre (station 0), m.
    pub fn spines_sigma(&self) -> f64 {
        self.axis.plane_sigmas()[2]
    }

    /// Arc length of the outlet plane's centre, m.
    pub fn outlet_sigma(&self) -> f64 {
        self.axis.plane_sigmas()[3]
    }

    /// The leading point of a body at `pose` whose centre lies at arc
    /// length `centre_sigma`: of its `body_points` (body frame), the one
    /// furthest along the canal tangent there, in the pelvis frame, and its
    /// arc length.
    ///
    /// CARDINAL_MOVEMENTS.md asks for the "deepest point along the axis".
    /// Taken literally (the largest projected sigma of any point) it is
    /// ill-conditioned: the canal's cross-sections (the axis's normal planes)
    /// fan out around the curve of Carus and meet near the symphysis, so
    /// points on the anterior side of the head get arc lengths far beyond
    /// the vertex's (20-25 mm at the mid-pelvis of the reference canal),
    /// and the station would jump as the head turns. Depth is therefore
    /// judged along the tangent at the head, where the canal is locally
    /// straight, and the chosen point's own sigma is reported
    /// (docs/DETECTOR.md).
    pub fn leading_point(
        &self,
        body_points: &[DVec3],
        pose: &RigidPose,
        centre_sigma: f64,
    ) -> Option<(DVec3, f64)> {
        // Compare in the body frame: one rotation instead of one per point.
        let tangent = pose.orientation.inverse() * self.axis.tangent(centre_sigma);
        let leading = body_points
            .iter()
            .copied()
            .max_by(|a, b| a.dot(tangent).total_cmp(&b.dot(tangent)))?;
        let leading = pose.point(leading);
        Some((leading, self.axis.project(leading)))
    }
}

impl TryFrom<CanalPlanes> for BirthCanal {
    type Error = AxisError;
    fn try_from(planes: CanalPlanes) -> Result<Self, AxisError> {
        BirthCanal::new(planes)
    }
}

impl From<BirthCanal> for CanalPlanes {
    fn from(canal: BirthCanal) -> Self {
        canal.planes
    }
}
