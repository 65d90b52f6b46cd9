//! The birth canal as the detector sees it: the four obstetric planes and
//! the pelvic axis (curve of Carus) through their centres.
//!
//! The axis itself is carus-anatomy's [`PelvicAxis`]; this module only keeps
//! the planes it is built from, so a pose history can carry its canal as
//! plain data (JSON) and rebuild the identical axis when read back.

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
            &[planes.inlet, planes.greatest_dimensions, planes.spines, planes.outlet],
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
        let planes =
            CanalPlanes { inlet: p.inlet, greatest_dimensions: p.greatest, spines: p.mid, outlet: p.outlet, right };
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

    /// The largest arc length reached by any of `points`, i.e. the sigma of
    /// the deepest point along the axis, starting the search at `start_sigma`
    /// (a sigma no deeper than the answer, e.g. that of the body's centre).
    ///
    /// The cross-sections of the canal are the axis's normal planes, and
    /// `project(p)` is the sigma whose normal plane holds `p`. The deepest
    /// point is therefore the last normal plane that still has a point on its
    /// caudal side: the root of `g(sigma) = max_i (p_i - r(sigma)) . t(sigma)`,
    /// found by bisection. That costs one axis frame and one pass over the
    /// points per step, instead of one projection per point (the projection
    /// searches the whole axis and would dominate the detector's run time).
    pub fn deepest_sigma(&self, points: &[DVec3], start_sigma: f64) -> f64 {
        let beyond = |sigma: f64| {
            let (r, t) = (self.axis.point(sigma), self.axis.tangent(sigma));
            points.iter().map(|&p| (p - r).dot(t)).fold(f64::NEG_INFINITY, f64::max)
        };
        if points.is_empty() {
            return start_sigma;
        }
        // Bracket the root: g(lo) > 0 >= g(hi), widening by doubling steps.
        let (mut lo, mut hi) = (start_sigma, start_sigma);
        let g_start = beyond(start_sigma);
        let mut step = g_start.abs().max(1e-3);
        for _ in 0..64 {
            if g_start > 0.0 {
                hi = lo + step;
                if beyond(hi) <= 0.0 {
                    break;
                }
                lo = hi;
            } else {
                lo = hi - step;
                if beyond(lo) > 0.0 {
                    break;
                }
                hi = lo;
            }
            step *= 2.0;
        }
        // 1e-7 m is far below any clinical resolution (stations are read in mm).
        while hi - lo > 1e-7 {
            let mid = 0.5 * (lo + hi);
            if beyond(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
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
