//! Measures a pelvis, generated or imported, from its landmarks and surface:
//! every obstetric diameter (canonical names), the planes, the landmarks and
//! the pelvic axis, in mm and degrees as clinicians read them.
//!
//! Diameters as measured (all straight distances between landmarks):
//! inlet AP = promontory to upper inner symphysis border; inlet transverse =
//! between the iliopectineal points; inlet oblique = mean of the two
//! sacroiliac-to-opposite-iliopubic-eminence distances; mid AP = lower
//! symphysis border to S4-S5; interspinous; outlet AP = lower symphysis border
//! to coccyx tip; outlet transverse = between the tuberosities; outlet
//! oblique = mean of the two sacrotuberous-midpoint-to-opposite-ischiopubic-
//! junction distances; symphysis length = upper to lower border; sacral
//! length = promontory to apex; sacral depth = distance of S2-S3 from the
//! promontory-apex line; subpubic angle = angle at the lower symphysis border
//! between the lines to the tuberosities.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::Serialize;

use super::{Pelvis, PelvisDiameters, PelvisLandmarks};
use crate::axis::Plane;
use crate::surface::{closest_point_on_triangle, TriSurface};

const MM: f64 = 1e3;

/// One obstetric plane as measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlaneMeasurement {
    /// Centre (midpoint of the antero-posterior diameter), mm, pelvis frame.
    pub centre_mm: [f64; 3],
    /// Unit caudal normal.
    pub normal: [f64; 3],
    /// Angle between this plane and the inlet plane, degrees.
    pub tilt_from_inlet_deg: f64,
    /// Antero-posterior diameter, mm.
    pub ap_mm: f64,
    /// Transverse diameter, mm: between landmarks for the inlet, mid-pelvis
    /// and outlet; for the plane of greatest dimensions, the canal's width
    /// along the mother's left-right line through the centre, read off the surface.
    pub transverse_mm: Option<f64>,
    /// Arc length of the centre along the pelvic axis, mm.
    pub sigma_mm: f64,
}

/// Equal steps the pelvic axis is sampled in, inlet centre to outlet
/// centre (under 2 mm each in a gynecoid pelvis).
pub const AXIS_STEPS: usize = 60;

/// One point of the pelvic axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisSample {
    /// Arc length from the inlet's centre, mm.
    pub sigma_mm: f64,
    /// The point, mm, pelvis frame.
    pub point_mm: [f64; 3],
    /// Unit direction of descent there.
    pub tangent: [f64; 3],
}

/// Everything `carus measure pelvis` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PelvisMeasurement {
    /// The diameters under their canonical names, so they can be pasted back.
    #[serde(flatten)]
    pub diameters: PelvisDiameters,
    pub inlet_oblique_right_mm: f64,
    pub inlet_oblique_left_mm: f64,
    pub outlet_oblique_right_mm: f64,
    pub outlet_oblique_left_mm: f64,
    /// Posterior sagittal diameter of the inlet: the sacral promontory to
    /// where the widest transverse (between the iliopectineal points)
    /// crosses the obstetric conjugate, mm (`inlet_posterior_share` of it).
    pub inlet_posterior_sagittal_mm: f64,
    /// Posterior sagittal diameter of the mid-pelvis: S4-S5 to where the
    /// interspinous line crosses the mid-pelvis AP diameter, mm
    /// (`mid_posterior_share` of it).
    pub mid_posterior_sagittal_mm: f64,
    /// Posterior sagittal diameter of the outlet: midpoint of the
    /// intertuberous line to the coccyx tip, mm.
    pub outlet_posterior_sagittal_mm: f64,
    /// Inlet, greatest dimensions, mid-pelvis, outlet.
    pub planes: BTreeMap<&'static str, PlaneMeasurement>,
    /// Length of the pelvic axis from the inlet centre to the outlet centre, mm.
    pub axis_length_mm: f64,
    /// The pelvic axis itself (the curve station, theta and phi are read
    /// along): [`axis_samples`].
    pub axis_mm: Vec<AxisSample>,
    /// Landmarks, mm, pelvis frame.
    pub landmarks_mm: BTreeMap<&'static str, [f64; 3]>,
    /// The largest distance of a landmark from the surface, mm (0 for a
    /// generated pelvis; a check on hand-picked landmarks of an imported one).
    pub landmark_surface_gap_mm: f64,
    /// The landmark that lies that far (the first, where several do).
    pub landmark_surface_gap_landmark: &'static str,
}

/// The diameters between the landmarks (see the module docs).
pub fn diameters_from_landmarks(l: &PelvisLandmarks) -> PelvisDiameters {
    let d = |a: DVec3, b: DVec3| (a - b).length() * MM;
    let inlet_obliques = inlet_obliques(l);
    let outlet_obliques = outlet_obliques(l);
    let chord = l.sacral_apex - l.sacral_promontory;
    let off_chord = l.sacrum_s2_s3 - l.sacral_promontory;
    let depth = (off_chord - off_chord.dot(chord) / chord.length_squared() * chord).length();
    let (left, right) = (
        l.ischial_tuberosity_left - l.symphysis_lower,
        l.ischial_tuberosity_right - l.symphysis_lower,
    );
    PelvisDiameters {
        inlet_posterior_share: posterior_share(l.sacral_promontory, l.symphysis_upper, l.iliopectineal_left, l.iliopectineal_right),
        mid_posterior_share: posterior_share(l.sacrum_s4_s5, l.symphysis_lower, l.ischial_spine_left, l.ischial_spine_right),
        inlet_ap_mm: d(l.sacral_promontory, l.symphysis_upper),
        inlet_transverse_mm: d(l.iliopectineal_left, l.iliopectineal_right),
        inlet_oblique_mm: 0.5 * (inlet_obliques.0 + inlet_obliques.1),
        mid_ap_mm: d(l.symphysis_lower, l.sacrum_s4_s5),
        interspinous_mm: d(l.ischial_spine_left, l.ischial_spine_right),
        outlet_ap_mm: d(l.symphysis_lower, l.coccyx_tip),
        outlet_transverse_mm: d(l.ischial_tuberosity_left, l.ischial_tuberosity_right),
        outlet_oblique_mm: 0.5 * (outlet_obliques.0 + outlet_obliques.1),
        symphysis_length_mm: d(l.symphysis_upper, l.symphysis_lower),
        sacral_length_mm: d(l.sacral_promontory, l.sacral_apex),
        subpubic_angle_deg: left.angle_between(right).to_degrees(),
        sacral_depth_mm: depth * MM,
    }
}

/// Where a transverse diameter (between `left` and `right`) crosses the AP
/// diameter from `back` to `front`: the share of it behind the crossing
/// (the posterior sagittal diameter over the AP), the transverse's midpoint
/// taken square onto the AP line.
fn posterior_share(back: DVec3, front: DVec3, left: DVec3, right: DVec3) -> f64 {
    let ap = front - back;
    (0.5 * (left + right) - back).dot(ap) / ap.length_squared()
}

/// (right, left) inlet obliques, mm: each named after the sacroiliac joint it starts from.
fn inlet_obliques(l: &PelvisLandmarks) -> (f64, f64) {
    (
        (l.sacroiliac_right - l.iliopubic_eminence_left).length() * MM,
        (l.sacroiliac_left - l.iliopubic_eminence_right).length() * MM,
    )
}

/// (right, left) outlet obliques, mm: each named after the ligament it starts from.
fn outlet_obliques(l: &PelvisLandmarks) -> (f64, f64) {
    (
        (l.sacrotuberous_right() - l.ischiopubic_left).length() * MM,
        (l.sacrotuberous_left() - l.ischiopubic_right).length() * MM,
    )
}

/// Measures `pelvis` (see the module docs for the definitions).
pub fn measure(pelvis: &Pelvis) -> PelvisMeasurement {
    let l = &pelvis.landmarks;
    let mm3 = |p: DVec3| [p.x * MM, p.y * MM, p.z * MM];
    let sigmas = pelvis.plane_sigmas();
    let inlet = pelvis.planes.inlet;
    let right = (l.iliopectineal_right - l.iliopectineal_left).normalize();
    let gap = farthest_landmark_from_bone(&pelvis.landmarks, &pelvis.surface);
    let plane = |p: Plane, ap: f64, transverse: Option<f64>, sigma: f64| PlaneMeasurement {
        centre_mm: mm3(p.centre),
        normal: p.normal.to_array(),
        tilt_from_inlet_deg: p.normal.angle_between(inlet.normal).to_degrees(),
        ap_mm: ap,
        transverse_mm: transverse,
        sigma_mm: sigma * MM,
    };
    let d = |a: DVec3, b: DVec3| (a - b).length() * MM;
    let greatest = pelvis.planes.greatest;
    let in_plane_right = (right - right.dot(greatest.normal) * greatest.normal).normalize();
    let greatest_transverse =
        canal_width(&pelvis.surface, greatest.centre, in_plane_right).map(|w| w * MM);
    let planes = BTreeMap::from([
        (
            "inlet",
            plane(
                inlet,
                d(l.sacral_promontory, l.symphysis_upper),
                Some(d(l.iliopectineal_left, l.iliopectineal_right)),
                sigmas[0],
            ),
        ),
        (
            "greatest_dimensions",
            plane(
                greatest,
                d(l.sacrum_s2_s3, l.symphysis_middle()),
                greatest_transverse,
                sigmas[1],
            ),
        ),
        (
            "mid",
            plane(
                pelvis.planes.mid,
                d(l.sacrum_s4_s5, l.symphysis_lower),
                Some(d(l.ischial_spine_left, l.ischial_spine_right)),
                sigmas[2],
            ),
        ),
        (
            "outlet",
            plane(
                pelvis.planes.outlet,
                d(l.coccyx_tip, l.symphysis_lower),
                Some(d(l.ischial_tuberosity_left, l.ischial_tuberosity_right)),
                sigmas[3],
            ),
        ),
    ]);
    let inlet_obliques = inlet_obliques(l);
    let outlet_obliques = outlet_obliques(l);
    let tuberosity_midpoint = 0.5 * (l.ischial_tuberosity_left + l.ischial_tuberosity_right);
    let diameters = diameters_from_landmarks(l);
    PelvisMeasurement {
        inlet_posterior_sagittal_mm: diameters.inlet_posterior_share * diameters.inlet_ap_mm,
        mid_posterior_sagittal_mm: diameters.mid_posterior_share * diameters.mid_ap_mm,
        diameters,
        inlet_oblique_right_mm: inlet_obliques.0,
        inlet_oblique_left_mm: inlet_obliques.1,
        outlet_oblique_right_mm: outlet_obliques.0,
        outlet_oblique_left_mm: outlet_obliques.1,
        outlet_posterior_sagittal_mm: d(tuberosity_midpoint, l.coccyx_tip),
        planes,
        axis_length_mm: pelvis.axis.length() * MM,
        axis_mm: axis_samples(pelvis),
        landmarks_mm: l
            .named()
            .into_iter()
            .map(|(name, p)| (name, mm3(p)))
            .collect(),
        landmark_surface_gap_mm: gap.1 * MM,
        landmark_surface_gap_landmark: gap.0,
    }
}

/// The landmark farthest from the pelvis's surface and its distance, m
/// (the first, where several are as far; `("", 0)` when all lie on it).
pub fn farthest_landmark_from_bone(landmarks: &PelvisLandmarks, surface: &TriSurface) -> (&'static str, f64) {
    landmarks
        .named()
        .into_iter()
        .map(|(name, p)| (name, distance_to_surface(surface, p)))
        .fold(("", 0.0), |far, next| if next.1 > far.1 { next } else { far })
}

/// Distance from `p` to the nearest point of the surface's triangles, m
/// (infinite for a surface without triangles).
pub fn distance_to_surface(surface: &TriSurface, p: DVec3) -> f64 {
    (0..surface.triangles.len())
        .map(|t| {
            let [a, b, c] = surface.corners(t);
            (closest_point_on_triangle(p, a, b, c) - p).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Width of the canal through `centre` along `direction`: the distance
/// between the nearest surface hits on either side, m; `None` if a side is open.
fn canal_width(surface: &TriSurface, centre: DVec3, direction: DVec3) -> Option<f64> {
    let hit = |d: DVec3| {
        (0..surface.triangles.len())
            .filter_map(|t| {
                let [a, b, c] = surface.corners(t);
                ray_triangle(centre, d, a, b, c)
            })
            .fold(None, |best: Option<f64>, s| {
                Some(best.map_or(s, |b| b.min(s)))
            })
    };
    Some(hit(direction)? + hit(-direction)?)
}

/// Distance along the ray `origin + s * dir` (s > 0) to triangle `abc` (Moller-Trumbore).
pub(crate) fn ray_triangle(origin: DVec3, dir: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let h = dir.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-18 {
        return None;
    }
    let f = 1.0 / det;
    let s = origin - a;
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = f * dir.dot(q);
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = f * e2.dot(q);
    (t > 0.0).then_some(t)
}

/// The pelvic axis in [`AXIS_STEPS`] equal steps from the inlet's centre
/// to the outlet's.
pub fn axis_samples(pelvis: &Pelvis) -> Vec<AxisSample> {
    let length = pelvis.axis.length();
    (0..=AXIS_STEPS)
        .map(|k| {
            let sigma = length * k as f64 / AXIS_STEPS as f64;
            let p = pelvis.axis.point(sigma);
            AxisSample {
                sigma_mm: sigma * MM,
                point_mm: [p.x * MM, p.y * MM, p.z * MM],
                tangent: pelvis.axis.tangent(sigma).to_array(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The axis runs from the inlet's centre, down its normal, to the
    /// outlet's centre, in equal steps.
    #[test]
    fn the_axis_samples_run_from_the_inlet_centre_to_the_outlet_centre() {
        let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
        let m = measure(&pelvis);
        let (first, last) = (m.axis_mm.first().unwrap(), m.axis_mm.last().unwrap());
        let close = |a: [f64; 3], b: [f64; 3], tol: f64| (DVec3::from(a) - DVec3::from(b)).length() < tol;
        assert!(close(first.point_mm, m.planes["inlet"].centre_mm, 1e-6));
        assert!(close(first.tangent, m.planes["inlet"].normal, 1e-6));
        assert!(close(last.point_mm, m.planes["outlet"].centre_mm, 1e-3));
        assert_eq!(m.axis_mm.len(), AXIS_STEPS + 1);
        assert!((last.sigma_mm - m.axis_length_mm).abs() < 1e-9);
        for pair in m.axis_mm.windows(2) {
            let chord = (DVec3::from(pair[1].point_mm) - DVec3::from(pair[0].point_mm)).length();
            assert!(chord <= pair[1].sigma_mm - pair[0].sigma_mm + 1e-6, "a chord longer than its arc");
        }
    }

    #[test]
    fn closest_points_on_a_triangle() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!(
            (closest_point_on_triangle(DVec3::new(0.2, 0.2, 1.0), a, b, c)
                - DVec3::new(0.2, 0.2, 0.0))
            .length()
                < 1e-15
        );
        assert_eq!(
            closest_point_on_triangle(DVec3::new(-1.0, -1.0, 0.0), a, b, c),
            a
        );
        assert_eq!(
            closest_point_on_triangle(DVec3::new(0.5, -2.0, 0.0), a, b, c),
            DVec3::new(0.5, 0.0, 0.0)
        );
        let on_hypotenuse = closest_point_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((on_hypotenuse - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
        assert!(
            (ray_triangle(DVec3::new(0.2, 0.2, 1.0), DVec3::NEG_Z, a, b, c).unwrap() - 1.0).abs()
                < 1e-15
        );
        assert_eq!(
            ray_triangle(DVec3::new(0.2, 0.2, 1.0), DVec3::Z, a, b, c),
            None
        );
    }
}
