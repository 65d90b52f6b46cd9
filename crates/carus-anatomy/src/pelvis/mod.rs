//! The maternal bony pelvis: landmarks, obstetric planes, pelvic axis and the
//! triangle surface of the birth canal, for generated and imported pelvises alike.
//!
//! Everything here is in the pelvis frame of CONVENTIONS.md (metres): origin
//! at the inlet centre (midpoint of the obstetric conjugate), x to the
//! mother's right, y anterior, z cranial. Planes and axis are computed from
//! the landmarks by [`PelvisPlanes::from_landmarks`], the same way for every
//! pelvis, so a measured value means the same thing for a generated and an
//! imported one.

mod diameters;
mod generate;
mod interpolate;
mod landmarks;
mod layout;
pub mod measure;
mod spec;

pub use diameters::{DiameterError, PelvisDiameters, PELVIC_CANAL_DIAMETER_MM};
pub use landmarks::{PelvisLandmarks, LANDMARK_NAMES};
pub use measure::{axis_samples, measure, AxisSample, PelvisMeasurement, PlaneMeasurement};
pub use spec::{PelvisBuildError, PelvisSpec, VISIBLE_HUMAN_FEMALE};
pub(crate) use generate::mid_ring;
pub(crate) use interpolate::SuperRing as MidRing;

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
    #[error(transparent)]
    Axis(#[from] AxisError),
    #[error(transparent)]
    Diameters(#[from] DiameterError),
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

/// Soft tissues that close the bony pelvis where it is open but the fetus
/// may not pass, as open sheets facing the canal (pelvis frame, metres):
/// the lower anterior abdominal wall over the front of the false pelvis,
/// from the pubic crests and the inguinal ligaments up between the anterior
/// superior iliac spines, and the obturator membranes with the obturator
/// internus on them over the obturator foramina (Gray's Anatomy: the
/// membrane closes the foramen but for the obturator canal, and the muscle
/// lines the side wall of the true pelvis). Without them a fetal shoulder
/// above the brim can pass in front of the pubis, outside the canal
/// (docs/LABOUR.md, forty-fifth session).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SoftWalls {
    pub abdominal_wall: TriSurface,
    pub obturator_membranes: TriSurface,
}

/// A maternal bony pelvis in its own frame: the surface of the bony birth
/// canal, its landmarks, the obstetric planes and the pelvic axis, and the
/// soft walls that close its openings.
#[derive(Debug, Clone, PartialEq)]
pub struct Pelvis {
    pub surface: TriSurface,
    /// Laid on a generated canal's own grid; an imported pelvis has none
    /// (its openings are not found).
    pub soft_walls: SoftWalls,
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
        Ok(Pelvis { surface, soft_walls: SoftWalls::default(), landmarks, planes, axis })
    }

    /// Generates a pelvis from its obstetric diameters: landmarks placed so
    /// every diameter measures back exactly, and the bony canal's surface
    /// through them (docs/ANATOMY.md).
    pub fn generate(diameters: &PelvisDiameters) -> Result<Self, PelvisError> {
        let layout = layout::layout(diameters)?;
        let (surface, landmarks, soft_walls) = generate::canal_surface(&layout, diameters.outlet_oblique_mm)?;
        Ok(Pelvis { soft_walls, ..Pelvis::from_landmarks(landmarks, surface)? })
    }

    /// Arc length of each plane along the axis: inlet, greatest, mid, outlet.
    pub fn plane_sigmas(&self) -> [f64; 4] {
        let s = self.axis.plane_sigmas();
        [s[0], s[1], s[2], s[3]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn assert_measures_back(requested: &PelvisDiameters, pelvis: &Pelvis) {
        let measured = measure::diameters_from_landmarks(&pelvis.landmarks);
        let pairs = requested.sizes().into_iter().zip(measured.sizes());
        for ((key, want), (_, got)) in pairs {
            assert!((want - got).abs() < 0.1, "{key}: requested {want} mm, measured {got} mm");
        }
        assert!((requested.subpubic_angle_deg - measured.subpubic_angle_deg).abs() < 0.1);
        // The posterior sagittal diameters to a tenth of a millimetre too.
        for (key, share, got, ap) in [
            ("inlet_posterior_share", requested.inlet_posterior_share, measured.inlet_posterior_share, requested.inlet_ap_mm),
            ("mid_posterior_share", requested.mid_posterior_share, measured.mid_posterior_share, requested.mid_ap_mm),
        ] {
            assert!((share - got).abs() * ap < 0.1, "{key}: requested {share}, measured {got}");
        }
    }

    #[test]
    fn the_default_pelvis_is_closed_and_measures_back() {
        let d = PelvisDiameters::default();
        let pelvis = Pelvis::generate(&d).unwrap();
        pelvis.surface.check_closed().unwrap();
        assert_measures_back(&d, &pelvis);
        let m = measure(&pelvis);
        assert!(m.landmark_surface_gap_mm < 1e-9, "a landmark is {} mm off the surface", m.landmark_surface_gap_mm);
        assert_eq!(m.landmark_surface_gap_landmark, "");
        // A landmark moved off the bone is named with its distance.
        let mut moved = pelvis.clone();
        moved.landmarks.coccyx_tip.z -= 0.005;
        let m_moved = measure(&moved);
        assert_eq!(m_moved.landmark_surface_gap_landmark, "coccyx_tip");
        assert!(m_moved.landmark_surface_gap_mm > 1.0, "{}", m_moved.landmark_surface_gap_mm);
        // The canal is widest at the inlet and narrowest at the spines.
        let greatest = m.planes["greatest_dimensions"].transverse_mm.unwrap();
        assert!(greatest < d.inlet_transverse_mm && greatest > d.interspinous_mm, "greatest transverse {greatest}");
        // The axis is the C-shaped curve of Carus: it turns forward.
        let outlet = m.planes["outlet"].tilt_from_inlet_deg;
        assert!(outlet > m.planes["mid"].tilt_from_inlet_deg && outlet > 30.0);
        assert!(pelvis.axis.point(pelvis.axis.length()).y > 0.01);
    }

    /// Where the coccyx tip stands against the ischial tuberosities. In the
    /// pelvis frame (inlet horizontal) the default tip lies about 49 mm
    /// below them along z, but that frame is tilted 55-60 degrees from the
    /// standing posture (REFERENCE_DATA.md). Standing, and against the outlet
    /// plane, the tip is above the tuberosities, as in a real pelvis.
    #[test]
    fn the_coccyx_tip_stands_above_the_tuberosities_when_standing() {
        let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
        let l = &pelvis.landmarks;
        let tuberosities = 0.5 * (l.ischial_tuberosity_left + l.ischial_tuberosity_right);
        for inlet_inclination in [55.0f64, 60.0] {
            // Standing "up" in the pelvis frame: z turned towards -y (the
            // frame's y axis points forwards and down when standing).
            let (s, c) = inlet_inclination.to_radians().sin_cos();
            let up = DVec3::new(0.0, -s, c);
            let above = (l.coccyx_tip - tuberosities).dot(up);
            assert!(above > 0.015, "tip {above} m above the tuberosities at {inlet_inclination} degrees");
        }
        // The tip lies in the outlet plane; the tuberosities below it.
        let outlet = pelvis.planes.outlet;
        assert!((tuberosities - outlet.centre).dot(outlet.normal) > 0.01);
    }

    #[test]
    fn conflicts_found_by_the_geometry_are_named() {
        let far = PelvisDiameters { mid_ap_mm: 190.0, ..Default::default() };
        let message = Pelvis::generate(&far).unwrap_err().to_string();
        assert!(message.contains("mid_ap_mm") && message.contains("between"), "{message}");
        let coccyx = PelvisDiameters { outlet_ap_mm: 160.0, ..Default::default() };
        assert!(Pelvis::generate(&coccyx).unwrap_err().to_string().contains("outlet_ap_mm"));
        let oblique = PelvisDiameters { inlet_oblique_mm: 160.0, ..Default::default() };
        assert!(Pelvis::generate(&oblique).unwrap_err().to_string().contains("inlet_oblique_mm"));
        let ligament = PelvisDiameters { outlet_oblique_mm: 130.0, ..Default::default() };
        assert!(Pelvis::generate(&ligament).unwrap_err().to_string().contains("outlet_oblique_mm"));
    }

    /// The textbook outlet oblique range is reachable with the other
    /// diameters at their defaults; the sacral end of the ligament lies on
    /// the outer bone surface, behind the sacrum's anterior (canal) surface,
    /// and moves up the sacrum as the oblique grows.
    #[test]
    fn textbook_outlet_obliques_are_built_with_the_other_defaults() {
        let mut heights = Vec::new();
        for oblique in [110.0, 115.0, 120.0] {
            let d = PelvisDiameters { outlet_oblique_mm: oblique, ..Default::default() };
            let pelvis = Pelvis::generate(&d).unwrap();
            pelvis.surface.check_closed().unwrap();
            assert_measures_back(&d, &pelvis);
            let l = &pelvis.landmarks;
            for border in [l.sacral_border_left, l.sacral_border_right] {
                assert!(pelvis.surface.vertices.contains(&border));
            }
            assert_eq!(l.sacral_border_left, DVec3::new(-l.sacral_border_right.x, l.sacral_border_right.y, l.sacral_border_right.z));
            // Behind the sacrum's anterior surface (the promontory-apex chord).
            let chord = (l.sacral_apex - l.sacral_promontory).normalize();
            let behind = chord.cross(DVec3::X);
            assert!(behind.y < 0.0);
            let depth = (l.sacral_border_right - l.sacral_promontory).dot(behind) * 1e3;
            assert!(depth > 15.0, "sacral border only {depth} mm behind the sacral chord for {oblique} mm");
            heights.push(l.sacral_border_right.z);
        }
        assert!(heights.windows(2).all(|w| w[1] > w[0]), "{heights:?}");
        // Out of reach: the message names the key and the reachable range.
        let short = PelvisDiameters { outlet_oblique_mm: 90.0, ..Default::default() };
        match Pelvis::generate(&short) {
            Err(PelvisError::Diameters(DiameterError::OutOfReach { key, min, max, .. })) => {
                assert_eq!(key, "outlet_oblique_mm");
                assert!(min > 90.0 && min < 110.0 && max > 120.0 && max < 130.0, "{min}-{max}");
            }
            other => panic!("{other:?}"),
        }
    }

    /// The iliac wings of the default pelvis have adult female proportions
    /// (docs/ANATOMY.md, "Iliac wings"): about 270 mm between the outer lips
    /// of the crests and 235 mm between the anterior superior iliac spines
    /// (the most anterior bone a quarter of the inlet AP above the inlet),
    /// with the crest highest at the side, above the spines.
    #[test]
    fn the_iliac_wings_have_adult_female_proportions() {
        let d = PelvisDiameters::default();
        let pelvis = Pelvis::generate(&d).unwrap();
        let v = &pelvis.surface.vertices;
        let intercristal = 2e3 * v.iter().map(|p| p.x.abs()).fold(0.0, f64::max);
        assert!((250.0..290.0).contains(&intercristal), "intercristal {intercristal} mm");
        let a = d.inlet_ap_mm * 1e-3;
        let asis = v.iter().filter(|p| p.z > 0.25 * a).max_by(|p, q| p.y.total_cmp(&q.y)).unwrap();
        let inter_asis = 2e3 * asis.x.abs();
        assert!((220.0..250.0).contains(&inter_asis), "inter-ASIS {inter_asis} mm");
        let top = v.iter().max_by(|p, q| p.z.total_cmp(&q.z)).unwrap();
        assert!(top.z > asis.z + 0.02 && top.x.abs() > 0.5 * d.inlet_transverse_mm * 1e-3, "crest top {top}");
    }

    /// Random clinical diameter sets, from contracted to generous pelvises.
    fn diameter_sets() -> impl Strategy<Value = PelvisDiameters> {
        (
            (85.0..125.0f64, 115.0..145.0f64, 0.0..1.0f64, 100.0..130.0f64, 0.0..1.0f64, 0.85..1.08f64),
            (95.0..125.0f64, 0.0..1.0f64, 35.0..55.0f64, 90.0..120.0f64, 90.0..120.0f64, 12.0..30.0f64),
            (0.3..0.6f64, 0.3..0.55f64),
        )
            .prop_map(|((ap, t, oblique, mid_ap, spines, outlet_ap), (outlet_t, outlet_oblique, symphysis, sacrum, angle, depth), (inlet_share, mid_share))| {
                let hypotenuse = ap.hypot(t);
                let low = (ap.min(t) / hypotenuse).max(0.62);
                PelvisDiameters {
                    inlet_ap_mm: ap,
                    inlet_transverse_mm: t,
                    inlet_oblique_mm: hypotenuse * (low + oblique * (0.85 - low)),
                    mid_ap_mm: mid_ap,
                    interspinous_mm: 85.0 + spines * (t - 100.0),
                    outlet_ap_mm: outlet_ap * mid_ap,
                    outlet_transverse_mm: outlet_t,
                    outlet_oblique_mm: (0.85 + 0.3 * outlet_oblique) * outlet_t,
                    symphysis_length_mm: symphysis,
                    sacral_length_mm: sacrum,
                    subpubic_angle_deg: angle,
                    sacral_depth_mm: depth,
                    inlet_posterior_share: inlet_share,
                    mid_posterior_share: mid_share,
                }
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
        #[test]
        fn generated_pelvises_measure_back_and_are_closed(d in diameter_sets(), u in 0.0..1.0f64) {
            // The outlet oblique's reach depends on all the other diameters:
            // where the drawn value is out of reach, the range the error
            // states must be reachable, so take a value inside it.
            let (d, pelvis) = match Pelvis::generate(&d) {
                Err(PelvisError::Diameters(DiameterError::OutOfReach { key: "outlet_oblique_mm", min, max, .. })) => {
                    let inside = PelvisDiameters { outlet_oblique_mm: min + (0.01 + 0.98 * u) * (max - min), ..d };
                    (inside, Pelvis::generate(&inside))
                }
                other => (d, other),
            };
            let pelvis = match pelvis {
                Ok(p) => p,
                Err(PelvisError::Diameters(DiameterError::OutOfReach { key, .. })) if key != "outlet_oblique_mm" => {
                    return Err(TestCaseError::reject("out of reach"))
                }
                Err(e) => return Err(TestCaseError::fail(e.to_string())),
            };
            pelvis.surface.check_closed().map_err(|e| TestCaseError::fail(e.to_string()))?;
            assert_measures_back(&d, &pelvis);
            for (name, p) in pelvis.landmarks.named() {
                let nearest = pelvis.surface.vertices.iter().map(|v| (*v - p).length()).fold(f64::INFINITY, f64::min);
                prop_assert!(nearest < 1e-12, "{} is off the surface", name);
            }
        }
    }
}
