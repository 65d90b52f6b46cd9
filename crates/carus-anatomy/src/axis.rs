//! Obstetric planes and the pelvic axis (curve of Carus).
//!
//! The pelvic axis is the curve through the centres of the inlet, the plane of
//! greatest dimensions, the mid-pelvis (interspinous) plane and the outlet,
//! perpendicular to each of them (the textbook definition: the axis of the
//! canal meets every plane at right angles at its centre). It is built as a
//! cubic Hermite spline that interpolates the four centres with the four
//! caudal plane normals as tangents. A Hermite spline was chosen over a
//! fitted circular arc because an arc cannot honour four centres and four
//! normals at once, and over Catmull-Rom because its tangents would ignore
//! the plane orientations. The spline is re-parametrised by arc length
//! `sigma` (metres from the inlet centre, positive downward) and continued by
//! straight lines beyond both ends, so the fetus has an axis above the inlet
//! and below the outlet.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A plane with a point at its centre and a unit normal pointing caudally,
/// i.e. in the direction of descent (`-z` for the inlet in the pelvis frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    pub centre: DVec3,
    pub normal: DVec3,
}

impl Plane {
    /// Signed distance of `point` from the plane, positive on the caudal side
    /// (below the plane, the way the fetus descends), metres.
    pub fn signed_distance(&self, point: DVec3) -> f64 {
        (point - self.centre).dot(self.normal)
    }

    /// Orthogonal projection of `point` onto the plane.
    pub fn project(&self, point: DVec3) -> DVec3 {
        point - self.signed_distance(point) * self.normal
    }
}

/// The local canal frame at one arc length of the pelvic axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AxisFrame {
    /// Point of the axis.
    pub point: DVec3,
    /// Unit tangent, the direction of descent.
    pub tangent: DVec3,
    /// Unit transverse axis towards the mother's right, orthogonal to the tangent.
    pub transverse: DVec3,
    /// Unit local anterior axis, `transverse x tangent` (+y at the inlet).
    pub anterior: DVec3,
}

/// Why the axis cannot be built from the given planes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AxisError {
    #[error("pelvic axis: plane {index} has a non-finite centre or normal")]
    NonFinite { index: usize },
    #[error("pelvic axis: plane {index} has a zero normal")]
    ZeroNormal { index: usize },
    #[error("pelvic axis: the centres of planes {index} and {next} coincide, so the axis has no length there")]
    CoincidentCentres { index: usize, next: usize },
    #[error("pelvic axis: plane {index} (0 inlet, 1 greatest dimensions, 2 mid-pelvis, 3 outlet) faces against the way between its neighbouring centres: the planes do not follow each other from inlet to outlet; check the landmarks that define them")]
    Backwards { index: usize },
    #[error("pelvic axis: it runs along the mother's transverse direction at sigma = {sigma_m} m, so no anterior axis can be defined")]
    TangentAlongTransverse { sigma_m: f64 },
    #[error("pelvic axis: the mother's right ({right:?}) is not a finite direction (a zero or non-finite vector); give the pelvis frame's +x, [1, 0, 0]")]
    NoRight { right: [f64; 3] },
}

/// Sub-intervals per Hermite segment in the arc-length table.
const TABLE_STEPS_PER_SEGMENT: usize = 64;

/// Five-point Gauss-Legendre nodes and weights on [0, 1].
const GAUSS_NODES: [f64; 5] = [
    0.046_910_077_030_668,
    0.230_765_344_947_158_5,
    0.5,
    0.769_234_655_052_841_5,
    0.953_089_922_969_332,
];
const GAUSS_WEIGHTS: [f64; 5] = [
    0.118_463_442_528_094_5,
    0.239_314_335_249_683_2,
    0.284_444_444_444_444_4,
    0.239_314_335_249_683_2,
    0.118_463_442_528_094_5,
];

/// One cubic Hermite segment between two plane centres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HermiteSegment {
    p0: DVec3,
    p1: DVec3,
    /// End derivatives (tangent times chord length).
    m0: DVec3,
    m1: DVec3,
}

impl HermiteSegment {
    fn point(&self, u: f64) -> DVec3 {
        let u2 = u * u;
        let u3 = u2 * u;
        self.p0 * (2.0 * u3 - 3.0 * u2 + 1.0)
            + self.m0 * (u3 - 2.0 * u2 + u)
            + self.p1 * (-2.0 * u3 + 3.0 * u2)
            + self.m1 * (u3 - u2)
    }

    fn derivative(&self, u: f64) -> DVec3 {
        let u2 = u * u;
        self.p0 * (6.0 * u2 - 6.0 * u)
            + self.m0 * (3.0 * u2 - 4.0 * u + 1.0)
            + self.p1 * (-6.0 * u2 + 6.0 * u)
            + self.m1 * (3.0 * u2 - 2.0 * u)
    }

    /// Arc length between parameters `a` and `b` (Gauss-Legendre).
    fn length(&self, a: f64, b: f64) -> f64 {
        let h = b - a;
        GAUSS_NODES
            .iter()
            .zip(GAUSS_WEIGHTS)
            .map(|(&x, w)| w * self.derivative(a + h * x).length())
            .sum::<f64>()
            * h
    }
}

/// The pelvic axis (curve of Carus), parametrised by arc length `sigma`.
#[derive(Debug, Clone, PartialEq)]
pub struct PelvicAxis {
    segments: Vec<HermiteSegment>,
    /// `sigma` at the start of each table step: `segments.len() * STEPS + 1` entries.
    table_sigma: Vec<f64>,
    /// The axis point at each `table_sigma`, kept because [`PelvicAxis::project`]
    /// searches them on every call and each costs an arc-length inversion.
    table_points: Vec<DVec3>,
    /// `sigma` of each plane centre, inlet first.
    plane_sigma: Vec<f64>,
    /// The mother's right (pelvis +x), projected off the tangent to give `x(sigma)`.
    right: DVec3,
}

impl PelvicAxis {
    /// Builds the axis through the centres of `planes` (inlet first, then the
    /// deeper planes in order), tangent to each plane's caudal normal.
    /// `right` is the mother's right (pelvis +x).
    pub fn new(planes: &[Plane], right: DVec3) -> Result<Self, AxisError> {
        if !right.is_finite() || right.length_squared() < 1e-24 {
            return Err(AxisError::NoRight { right: right.to_array() });
        }
        for (index, plane) in planes.iter().enumerate() {
            if !plane.centre.is_finite() || !plane.normal.is_finite() {
                return Err(AxisError::NonFinite { index });
            }
            if plane.normal.length_squared() < 1e-24 {
                return Err(AxisError::ZeroNormal { index });
            }
        }
        let mut segments = Vec::with_capacity(planes.len().saturating_sub(1));
        for (index, pair) in planes.windows(2).enumerate() {
            let (a, b) = (pair[0], pair[1]);
            let chord = b.centre - a.centre;
            let length = chord.length();
            if length < 1e-9 {
                return Err(AxisError::CoincidentCentres { index, next: index + 1 });
            }
            let (na, nb) = (a.normal.normalize(), b.normal.normalize());
            if na.dot(chord) <= 0.0 {
                return Err(AxisError::Backwards { index });
            }
            if nb.dot(chord) <= 0.0 {
                return Err(AxisError::Backwards { index: index + 1 });
            }
            segments.push(HermiteSegment { p0: a.centre, p1: b.centre, m0: na * length, m1: nb * length });
        }
        let mut table_sigma = vec![0.0];
        let mut plane_sigma = vec![0.0];
        for segment in &segments {
            for k in 0..TABLE_STEPS_PER_SEGMENT {
                let a = k as f64 / TABLE_STEPS_PER_SEGMENT as f64;
                let b = (k + 1) as f64 / TABLE_STEPS_PER_SEGMENT as f64;
                let last = *table_sigma.last().expect("table starts with 0");
                table_sigma.push(last + segment.length(a, b));
            }
            plane_sigma.push(*table_sigma.last().expect("table is not empty"));
        }
        let mut axis = PelvicAxis {
            segments,
            table_sigma,
            table_points: Vec::new(),
            plane_sigma,
            right: right.normalize_or_zero(),
        };
        axis.table_points = axis.table_sigma.iter().map(|&sigma| axis.point(sigma)).collect();
        // The transverse axis is the mother's right projected off the tangent:
        // refuse an axis that ever runs along it.
        let samples = 8 * axis.segments.len().max(1);
        for k in 0..=samples {
            let sigma = axis.length() * k as f64 / samples as f64;
            let t = axis.tangent(sigma);
            if (axis.right - axis.right.dot(t) * t).length() < 1e-3 {
                return Err(AxisError::TangentAlongTransverse { sigma_m: sigma });
            }
        }
        Ok(axis)
    }

    /// Total length from the inlet centre to the last plane's centre, m.
    pub fn length(&self) -> f64 {
        *self.table_sigma.last().expect("table is not empty")
    }

    /// `sigma` of each plane's centre, in the order given to [`PelvicAxis::new`].
    pub fn plane_sigmas(&self) -> &[f64] {
        &self.plane_sigma
    }

    /// Segment index and local Hermite parameter at arc length `sigma`
    /// (clamped to the curved part).
    fn locate(&self, sigma: f64) -> (usize, f64) {
        let sigma = sigma.clamp(0.0, self.length());
        let step = match self.table_sigma.partition_point(|&s| s <= sigma) {
            0 => 0,
            k => (k - 1).min(self.table_sigma.len() - 2),
        };
        let segment = step / TABLE_STEPS_PER_SEGMENT;
        let k = step % TABLE_STEPS_PER_SEGMENT;
        let h = 1.0 / TABLE_STEPS_PER_SEGMENT as f64;
        let (lo, hi) = (k as f64 * h, (k + 1) as f64 * h);
        let target = sigma - self.table_sigma[step];
        let seg = &self.segments[segment];
        let span = self.table_sigma[step + 1] - self.table_sigma[step];
        let mut u = lo + h * if span > 0.0 { target / span } else { 0.0 };
        // Newton on the arc length inside the step; the step is short, so it converges in a few iterations.
        for _ in 0..6 {
            let speed = seg.derivative(u).length();
            if speed <= 0.0 {
                break;
            }
            u = (u - (seg.length(lo, u) - target) / speed).clamp(lo, hi);
        }
        (segment, u)
    }

    /// Point of the axis at arc length `sigma`; straight continuation beyond both ends.
    pub fn point(&self, sigma: f64) -> DVec3 {
        if self.segments.is_empty() {
            return DVec3::ZERO;
        }
        if sigma < 0.0 {
            let first = &self.segments[0];
            return first.p0 + sigma * first.m0.normalize();
        }
        if sigma > self.length() {
            let last = self.segments.last().expect("not empty");
            return last.p1 + (sigma - self.length()) * last.m1.normalize();
        }
        let (segment, u) = self.locate(sigma);
        self.segments[segment].point(u)
    }

    /// Unit tangent (direction of descent) at `sigma`.
    pub fn tangent(&self, sigma: f64) -> DVec3 {
        if self.segments.is_empty() {
            return DVec3::NEG_Z;
        }
        let (segment, u) = self.locate(sigma);
        self.segments[segment].derivative(u).normalize()
    }

    /// Unit transverse axis (mother's right, orthogonal to the tangent) at `sigma`.
    pub fn transverse(&self, sigma: f64) -> DVec3 {
        let t = self.tangent(sigma);
        (self.right - self.right.dot(t) * t).normalize()
    }

    /// Unit local anterior axis `x cross t` at `sigma` (+y at the inlet).
    pub fn anterior(&self, sigma: f64) -> DVec3 {
        self.transverse(sigma).cross(self.tangent(sigma))
    }

    /// The whole local frame at `sigma`.
    pub fn frame(&self, sigma: f64) -> AxisFrame {
        let tangent = self.tangent(sigma);
        let transverse = (self.right - self.right.dot(tangent) * tangent).normalize();
        AxisFrame { point: self.point(sigma), tangent, transverse, anterior: transverse.cross(tangent) }
    }

    /// Arc length of the point of the (extended) axis closest to `point`.
    pub fn project(&self, point: DVec3) -> f64 {
        if self.segments.is_empty() {
            return 0.0;
        }
        let mut best_sigma = 0.0;
        let mut best_distance = f64::INFINITY;
        let consider = |sigma: f64, best_sigma: &mut f64, best_distance: &mut f64| {
            let d = (self.point(sigma) - point).length_squared();
            if d < *best_distance {
                *best_distance = d;
                *best_sigma = sigma;
            }
        };
        // Straight continuations above the inlet and below the outlet.
        let first = &self.segments[0];
        let before = (point - first.p0).dot(first.m0.normalize());
        if before < 0.0 {
            consider(before, &mut best_sigma, &mut best_distance);
        }
        let last = self.segments.last().expect("not empty");
        let after = (point - last.p1).dot(last.m1.normalize());
        if after > 0.0 {
            consider(self.length() + after, &mut best_sigma, &mut best_distance);
        }
        // Curved part: coarse search over the table, then refine each local
        // minimum with a bracketed Newton on d/dsigma |r - p|^2 / 2 = (r - p) . t.
        let n = self.table_sigma.len();
        let distance = |k: usize| self.table_points.get(k).map_or(f64::INFINITY, |&q| (q - point).length_squared());
        // A sliding window over the table, so a call allocates nothing.
        let mut window = [f64::INFINITY, distance(0), distance(1)];
        for k in 0..n {
            let [left, here, right] = window;
            window = [here, right, distance(k + 2)];
            if here > left || here > right {
                continue;
            }
            let lo = self.table_sigma[k.saturating_sub(1)];
            let hi = self.table_sigma[(k + 1).min(n - 1)];
            let sigma = self.refine_projection(point, self.table_sigma[k], lo, hi);
            consider(sigma, &mut best_sigma, &mut best_distance);
        }
        best_sigma
    }

    /// Solves `(r(sigma) - p) . t(sigma) = 0` in `[lo, hi]` by safeguarded Newton.
    fn refine_projection(&self, point: DVec3, start: f64, mut lo: f64, mut hi: f64) -> f64 {
        let g = |s: f64| (self.point(s) - point).dot(self.tangent(s));
        let (g_lo, g_hi) = (g(lo), g(hi));
        if g_lo > 0.0 {
            return lo;
        }
        if g_hi < 0.0 {
            return hi;
        }
        let mut sigma = start;
        for _ in 0..40 {
            let value = g(sigma);
            if value.abs() < 1e-13 {
                break;
            }
            if value < 0.0 {
                lo = sigma;
            } else {
                hi = sigma;
            }
            // d/dsigma of g = 1 + (r - p) . dt/dsigma; approximated by 1 (the
            // curvature term is small near the curve), kept inside the bracket.
            let next = sigma - value;
            sigma = if next > lo && next < hi { next } else { 0.5 * (lo + hi) };
            if hi - lo < 1e-13 {
                break;
            }
        }
        sigma
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A textbook-like C-shaped set of planes (metres, pelvis frame).
    fn planes() -> Vec<Plane> {
        let tilt = |deg: f64| {
            let r = deg.to_radians();
            DVec3::new(0.0, r.sin(), -r.cos())
        };
        vec![
            Plane { centre: DVec3::ZERO, normal: DVec3::NEG_Z },
            Plane { centre: DVec3::new(0.0, -0.004, -0.035), normal: tilt(15.0) },
            Plane { centre: DVec3::new(0.0, 0.0, -0.065), normal: tilt(35.0) },
            Plane { centre: DVec3::new(0.0, 0.02, -0.095), normal: tilt(65.0) },
        ]
    }

    fn axis() -> PelvicAxis {
        PelvicAxis::new(&planes(), DVec3::X).unwrap()
    }

    #[test]
    fn the_inlet_frame_is_the_pelvis_frame() {
        let f = axis().frame(0.0);
        assert!(f.point.length() < 1e-12);
        assert!((f.tangent - DVec3::NEG_Z).length() < 1e-9);
        assert!((f.transverse - DVec3::X).length() < 1e-9);
        assert!((f.anterior - DVec3::Y).length() < 1e-9);
    }

    #[test]
    fn the_axis_passes_through_every_centre_perpendicular_to_its_plane() {
        let a = axis();
        for (plane, &sigma) in planes().iter().zip(a.plane_sigmas()) {
            assert!((a.point(sigma) - plane.centre).length() < 1e-9);
            assert!((a.tangent(sigma) - plane.normal.normalize()).length() < 1e-6);
        }
        assert!(a.length() > 0.095);
    }

    #[test]
    fn planes_out_of_order_are_refused() {
        let mut p = planes();
        p.swap(1, 2);
        p.swap(2, 3);
        assert!(matches!(PelvicAxis::new(&p, DVec3::X), Err(AxisError::Backwards { .. })));
        let mut q = planes();
        q[1].centre = q[0].centre;
        assert!(matches!(PelvicAxis::new(&q, DVec3::X), Err(AxisError::CoincidentCentres { .. })));
        // No right to project off the tangent: said so, not as an axis along it.
        for right in [DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0)] {
            let e = PelvicAxis::new(&planes(), right).unwrap_err();
            assert!(matches!(e, AxisError::NoRight { .. }) && e.to_string().contains("give the pelvis frame's +x"), "{e}");
        }
    }

    #[test]
    fn the_extension_is_straight() {
        let a = axis();
        assert!((a.point(-0.05) - DVec3::new(0.0, 0.0, 0.05)).length() < 1e-12);
        let end = a.point(a.length());
        let t = a.tangent(a.length());
        assert!((a.point(a.length() + 0.03) - (end + 0.03 * t)).length() < 1e-9);
        assert!((a.project(DVec3::new(0.0, 0.0, 0.07)) + 0.07).abs() < 1e-9);
    }

    proptest! {
        #[test]
        fn frames_are_orthonormal_and_right_handed(s in -0.05f64..0.2) {
            let f = axis().frame(s);
            for v in [f.tangent, f.transverse, f.anterior] {
                prop_assert!((v.length() - 1.0).abs() < 1e-9);
            }
            prop_assert!(f.tangent.dot(f.transverse).abs() < 1e-9);
            prop_assert!(f.tangent.dot(f.anterior).abs() < 1e-9);
            prop_assert!((f.transverse.cross(f.tangent) - f.anterior).length() < 1e-9);
        }

        #[test]
        fn projection_inverts_the_parametrisation(s in -0.05f64..0.2) {
            let a = axis();
            prop_assert!((a.project(a.point(s)) - s).abs() < 1e-8);
        }

        #[test]
        fn sigma_is_arc_length(s in 0.0f64..0.12, ds in 1e-4f64..1e-3) {
            let a = axis();
            let chord = (a.point(s + ds) - a.point(s)).length();
            prop_assert!((chord - ds).abs() < 1e-3 * ds + 1e-9);
        }

        #[test]
        fn a_point_off_the_axis_projects_to_its_foot(s in 0.001f64..0.11, off in -0.01f64..0.01) {
            let a = axis();
            let f = a.frame(s);
            let p = f.point + off * f.anterior;
            prop_assert!((a.project(p) - s).abs() < 1e-7);
        }
    }
}
