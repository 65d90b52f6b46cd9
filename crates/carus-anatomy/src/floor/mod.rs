//! The pelvic floor: a hexahedral (H8) volume mesh of the levator ani
//! hammock and the perineal body, shaped to the pelvis it belongs to.
//!
//! The floor's mid-surface is a U-shaped sheet spanned between two curves:
//! - the attachment, from the back of the pubic bone along the tendinous
//!   arch of the levator ani (over the obturator internus) to the ischial
//!   spine, then along the sacrospinous line to the coccyx tip (rounded so
//!   the two sides meet smoothly there), and the same
//!   on the other side (the arch follows the mid-pelvis ring through the
//!   lower symphysis and the spines, which lies on the bony wall);
//! - the rim of the urogenital hiatus, an opening in front that starts at
//!   the pubis and ends at the perineal body behind it, sinking from the
//!   pubis to `sag_mm` below the outlet plane at the back.
//!
//! The sheet between them sags further towards the hiatus, so it forms the
//! gutter that slopes forwards, downwards and medially (CARDINAL_MOVEMENTS.md,
//! internal rotation). Everything is built from landmarks and planes only,
//! so the floor fits generated and imported pelvises alike.
//!
//! Node ordering is VTK's (carus_fem::mesh): bottom face on the perineal
//! side, top face on the fetal side.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use carus_fem::mesh::{ElementKind, Mesh};

use crate::pelvis::Pelvis;

/// Settable shape and resolution of the pelvic floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FloorParameters {
    /// Thickness of the levator ani sheet, mm. About 7 mm: pubovisceral
    /// muscle thickness at rest on 3D ultrasound (Dietz, Shek & Clarke 2005,
    /// Ultrasound Obstet Gynecol 25:580).
    pub thickness_mm: f64,
    /// How far the back of the hiatus rim lies below the outlet plane, mm: 20 mm, the
    /// upper limit of normal muscular descent (M line) of the HMO MRI
    /// grading (Comiter et al. 1999, Urology 54:454).
    pub sag_mm: f64,
    /// Antero-posterior length of the urogenital (levator) hiatus, mm:
    /// 50 mm, H line of the HMO grading (Comiter et al. 1999) and the
    /// hiatal AP diameter at rest (about 50 mm, Dietz et al. 2005).
    pub hiatus_length_mm: f64,
    /// Transverse width of the hiatus, mm: about 38 mm at rest (Dietz et al. 2005).
    pub hiatus_width_mm: f64,
    /// Extra thickness of the perineal body behind the hiatus, mm.
    /// Engineering choice (the perineal body is a fibromuscular node about
    /// as tall as the levator sheet is thick, several times over).
    pub perineal_body_mm: f64,
    /// Elements round the U from one pubic insertion to the other (even).
    pub elements_around: usize,
    /// Elements across the sheet, from the attachment to the hiatus rim.
    pub elements_across: usize,
    /// Elements through the thickness.
    pub elements_through: usize,
}

impl Default for FloorParameters {
    fn default() -> Self {
        FloorParameters {
            thickness_mm: 7.0,
            sag_mm: 20.0,
            hiatus_length_mm: 50.0,
            hiatus_width_mm: 38.0,
            perineal_body_mm: 8.0,
            elements_around: 48,
            elements_across: 8,
            elements_through: 2,
        }
    }
}

/// Why a floor cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FloorError {
    #[error("{key} = {value} must be a positive, finite size")]
    NotPositive { key: &'static str, value: f64 },
    #[error("{key} = {value} is too coarse: at least {min} elements are needed")]
    TooFewElements { key: &'static str, value: usize, min: usize },
    #[error("elements_around = {0} must be even, so the posterior midline (coccyx) is a row of nodes")]
    OddAround(usize),
    #[error("hiatus_width_mm = {width} does not fit between the ischial spines ({interspinous:.1} mm apart); make it narrower than 0.6 x the interspinous diameter")]
    HiatusTooWide { width: f64, interspinous: f64 },
    #[error("hiatus_length_mm = {length} reaches the coccyx ({outlet_ap:.1} mm behind the symphysis); make it shorter than 0.75 x the outlet AP diameter")]
    HiatusTooLong { length: f64, outlet_ap: f64 },
    #[error("the floor would have an inverted element ({element}) for this pelvis: reduce thickness_mm or sag_mm")]
    Inverted { element: usize },
}

/// Name of the node set fixed to bone.
pub const ATTACHED: &str = "attached";
/// Name of the fetal-side (upper) surface.
pub const UPPER_SURFACE: &str = "upper";
/// Name of the perineal-side (lower) surface.
pub const LOWER_SURFACE: &str = "lower";
/// Element sets.
pub const LEVATOR_ANI: &str = "levator_ani";
pub const PERINEAL_BODY: &str = "perineal_body";

/// Where the levator rises from the pubis, as a turn position (1/64 turns
/// from the front midline) on the mid-pelvis ring: about 25 mm lateral to
/// the symphysis in a gynecoid pelvis, where the levator's origin runs
/// along the superior ramus (engineering choice).
const PUBIC_ORIGIN_TURN: f64 = 6.0;
/// The hiatus rim starts at the pubis this share of the hiatus half-width
/// from the midline (the puborectalis inserts beside the symphysis).
const HIATUS_FRONT_SHARE: f64 = 0.5;
/// How far out (share of the spine's lateral offset) the tail's Bezier
/// control point lies beside the coccyx tip.
const COCCYX_APPROACH: f64 = 0.6;
/// Segments of the table that spaces the hiatus rim's nodes evenly.
const RIM_TABLE: usize = 256;
/// Passes of neighbour averaging of the sheet normals.
const NORMAL_SMOOTHING_PASSES: usize = 10;

impl FloorParameters {
    fn validate(&self) -> Result<(), FloorError> {
        for (key, value) in [
            ("thickness_mm", self.thickness_mm),
            ("sag_mm", self.sag_mm),
            ("hiatus_length_mm", self.hiatus_length_mm),
            ("hiatus_width_mm", self.hiatus_width_mm),
            ("perineal_body_mm", self.perineal_body_mm),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FloorError::NotPositive { key, value });
            }
        }
        for (key, value, min) in [
            ("elements_around", self.elements_around, 8),
            ("elements_across", self.elements_across, 2),
            ("elements_through", self.elements_through, 1),
        ] {
            if value < min {
                return Err(FloorError::TooFewElements { key, value, min });
            }
        }
        if !self.elements_around.is_multiple_of(2) {
            return Err(FloorError::OddAround(self.elements_around));
        }
        Ok(())
    }
}

/// The two curves the sheet spans, as functions of the position round the U
/// (`u` in [0, 1] from the left pubic insertion through the coccyx to the right).
struct Outline<'a> {
    pelvis: &'a Pelvis,
    ring: crate::pelvis::MidRing,
    hiatus_front: DVec3,
    backwards: DVec3,
    right: DVec3,
    down: DVec3,
    parameters: &'a FloorParameters,
}

impl Outline<'_> {
    /// Attachment on one side (`left`), `f` in [0, 1] from the pubis to the coccyx tip.
    fn attachment_half(&self, left: bool, f: f64) -> DVec3 {
        let l = &self.pelvis.landmarks;
        let spine = if left { l.ischial_spine_left } else { l.ischial_spine_right };
        let sign = if left { 1.0 } else { -1.0 };
        let arch_length = self.arch_length(sign);
        // Chord length: a fair share of nodes for the curved tail.
        let tail_length = (l.coccyx_tip - spine).length();
        let split = arch_length / (arch_length + tail_length);
        if f <= split {
            let turn = PUBIC_ORIGIN_TURN + (16.0 - PUBIC_ORIGIN_TURN) * f / split;
            self.ring.at(sign * turn)
        } else {
            // Spine to coccyx tip, arriving square to the midline so the two
            // sides meet smoothly (a quadratic Bezier).
            let t = (f - split) / (1.0 - split);
            let across = (spine - l.coccyx_tip).dot(self.right) * self.right;
            let control = l.coccyx_tip + COCCYX_APPROACH * across;
            (1.0 - t) * (1.0 - t) * spine + 2.0 * t * (1.0 - t) * control + t * t * l.coccyx_tip
        }
    }

    fn arch_length(&self, sign: f64) -> f64 {
        let n = 32;
        (0..n)
            .map(|k| {
                let t = |k: usize| PUBIC_ORIGIN_TURN + (16.0 - PUBIC_ORIGIN_TURN) * k as f64 / n as f64;
                (self.ring.at(sign * t(k + 1)) - self.ring.at(sign * t(k))).length()
            })
            .sum()
    }

    fn attachment(&self, u: f64) -> DVec3 {
        if u <= 0.5 {
            self.attachment_half(true, 2.0 * u)
        } else {
            self.attachment_half(false, 2.0 * (1.0 - u))
        }
    }

    /// Angle along the hiatus rim at arc-length fraction `f` of a half rim.
    fn rim_angle(&self, f: f64) -> f64 {
        let p = self.parameters;
        let (half_width, length) = (0.5 * p.hiatus_width_mm, p.hiatus_length_mm);
        let point = |phi: f64| {
            let back = 0.5 * (1.0 - phi.cos()) + 0.25 * phi.sin() * (1.0 + phi.cos());
            let lateral = (1.0 - HIATUS_FRONT_SHARE) * phi.sin() + HIATUS_FRONT_SHARE * 0.5 * (1.0 + phi.cos());
            glam::DVec2::new(back * length, lateral * half_width)
        };
        let n = RIM_TABLE;
        let angle = |k: usize| std::f64::consts::PI * k as f64 / n as f64;
        let mut cumulative = vec![0.0; n + 1];
        for k in 0..n {
            cumulative[k + 1] = cumulative[k] + (point(angle(k + 1)) - point(angle(k))).length();
        }
        let target = f * cumulative[n];
        let k = cumulative.partition_point(|&c| c <= target).clamp(1, n) - 1;
        let span = cumulative[k + 1] - cumulative[k];
        let t = if span > 0.0 { (target - cumulative[k]) / span } else { 0.0 };
        angle(k) + t * (angle(k + 1) - angle(k))
    }

    /// Hiatus rim: half an ellipse on each side, from beside the symphysis
    /// round to the perineal body on the midline behind, sinking from the
    /// pubis (where the puborectalis inserts) to `sag_mm` below the outlet
    /// plane at the back.
    fn hiatus(&self, u: f64) -> DVec3 {
        let p = self.parameters;
        let (half_width, length) = (0.5e-3 * p.hiatus_width_mm, 1e-3 * p.hiatus_length_mm);
        let (f, side) = if u <= 0.5 { (2.0 * u, -1.0) } else { (2.0 * (1.0 - u), 1.0) };
        // A U: leaving the pubis already heading back, widest near the
        // middle, closing square to the midline behind (no cusp there);
        // nodes spaced evenly along it.
        let phi = self.rim_angle(f);
        let back = 0.5 * (1.0 - phi.cos()) + 0.25 * phi.sin() * (1.0 + phi.cos());
        let lateral = (1.0 - HIATUS_FRONT_SHARE) * phi.sin() + HIATUS_FRONT_SHARE * 0.5 * (1.0 + phi.cos());
        self.hiatus_front
            + back * length * self.backwards
            + side * half_width * lateral * self.right
            + back * 1e-3 * p.sag_mm * self.down
    }
}

/// Builds the pelvic floor mesh for `pelvis`.
pub fn pelvic_floor(pelvis: &Pelvis, parameters: &FloorParameters) -> Result<Mesh, FloorError> {
    parameters.validate()?;
    let l = &pelvis.landmarks;
    let interspinous = (l.ischial_spine_right - l.ischial_spine_left).length() * 1e3;
    if parameters.hiatus_width_mm >= 0.6 * interspinous {
        return Err(FloorError::HiatusTooWide { width: parameters.hiatus_width_mm, interspinous });
    }
    let outlet_ap = (l.coccyx_tip - l.symphysis_lower).length() * 1e3;
    if parameters.hiatus_length_mm >= 0.75 * outlet_ap {
        return Err(FloorError::HiatusTooLong { length: parameters.hiatus_length_mm, outlet_ap });
    }
    let backwards = (l.coccyx_tip - l.symphysis_lower).normalize();
    let transverse = l.ischial_tuberosity_right - l.ischial_tuberosity_left;
    let right = (transverse - transverse.dot(backwards) * backwards).normalize();
    let outline = Outline {
        pelvis,
        ring: crate::pelvis::mid_ring(l),
        // The hiatus opens just behind the lower border of the symphysis.
        hiatus_front: l.symphysis_lower + 0.005 * backwards,
        backwards,
        right,
        down: pelvis.planes.outlet.normal,
        parameters,
    };

    let (na, nc, nt) = (parameters.elements_around, parameters.elements_across, parameters.elements_through);
    let (rows_a, rows_c, rows_t) = (na + 1, nc + 1, nt + 1);
    // Mid-surface, sagging further between attachment and rim.
    let sag = 0.25e-3 * parameters.sag_mm;
    let mut middle = vec![DVec3::ZERO; rows_a * rows_c];
    for i in 0..rows_a {
        let u = i as f64 / na as f64;
        let (outer, inner) = (outline.attachment(u), outline.hiatus(u));
        // The pubic insertions are straight lines on the bone: no sag there.
        let taper = smoothstep(0.0, 0.2, u.min(1.0 - u));
        for j in 0..rows_c {
            let r = j as f64 / nc as f64;
            middle[i * rows_c + j] = outer.lerp(inner, r) + 4.0 * r * (1.0 - r) * taper * sag * outline.down;
        }
    }
    // Thickness along the mid-surface normal (around x across, which points
    // to the fetal side); the perineal body thickens the posterior rim.
    let at = |i: usize, j: usize| middle[i * rows_c + j];
    let mut normals = vec![DVec3::ZERO; rows_a * rows_c];
    for i in 0..rows_a {
        for j in 0..rows_c {
            let around = at((i + 1).min(na), j) - at(i.saturating_sub(1), j);
            let across = at(i, (j + 1).min(nc)) - at(i, j.saturating_sub(1));
            normals[i * rows_c + j] = around.cross(across).normalize();
        }
    }
    // Smoothed normals keep the layers parallel where the sheet curves
    // tightly (the narrow pubic insertions), so the elements stay square.
    for _ in 0..NORMAL_SMOOTHING_PASSES {
        let previous = normals.clone();
        for i in 0..rows_a {
            for j in 0..rows_c {
                let n = |i: usize, j: usize| previous[i * rows_c + j];
                let sum = n(i, j) * 2.0 + n((i + 1).min(na), j) + n(i.saturating_sub(1), j) + n(i, (j + 1).min(nc)) + n(i, j.saturating_sub(1));
                normals[i * rows_c + j] = sum.normalize();
            }
        }
    }
    let mut nodes = Vec::with_capacity(rows_a * rows_c * rows_t);
    let mut perineal = vec![0.0; rows_a * rows_c];
    for i in 0..rows_a {
        for j in 0..rows_c {
            let normal = normals[i * rows_c + j];
            let (u, r) = (i as f64 / na as f64, j as f64 / nc as f64);
            let bump = (-((u - 0.5) / 0.1).powi(2)).exp() * smoothstep(0.3, 1.0, r);
            perineal[i * rows_c + j] = bump;
            let thickness = 1e-3 * (parameters.thickness_mm + parameters.perineal_body_mm * bump);
            for k in 0..rows_t {
                let offset = (k as f64 / nt as f64 - 0.5) * thickness;
                let p = at(i, j) + offset * normal;
                nodes.push([p.x, p.y, p.z]);
            }
        }
    }
    let node = |i: usize, j: usize, k: usize| ((i * rows_c + j) * rows_t + k) as u32;
    let mut connectivity = Vec::with_capacity(na * nc * nt * 8);
    let (mut levator, mut perineal_body) = (Vec::new(), Vec::new());
    let mut upper = Vec::new();
    let mut lower = Vec::new();
    for i in 0..na {
        for j in 0..nc {
            let mean_bump = 0.25
                * (perineal[i * rows_c + j]
                    + perineal[(i + 1) * rows_c + j]
                    + perineal[i * rows_c + j + 1]
                    + perineal[(i + 1) * rows_c + j + 1]);
            for k in 0..nt {
                let e = (connectivity.len() / 8) as u32;
                let bottom = [node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k)];
                let top = bottom.map(|n| n + 1);
                connectivity.extend_from_slice(&bottom);
                connectivity.extend_from_slice(&top);
                if mean_bump > 0.5 {
                    perineal_body.push(e);
                } else {
                    levator.push(e);
                }
                if k == nt - 1 {
                    upper.push([top[0], top[1], top[2]]);
                    upper.push([top[0], top[2], top[3]]);
                }
                if k == 0 {
                    lower.push([bottom[0], bottom[2], bottom[1]]);
                    lower.push([bottom[0], bottom[3], bottom[2]]);
                }
            }
        }
    }
    let mut mesh = Mesh::new(ElementKind::H8, nodes, connectivity);
    let mut attached = Vec::new();
    for i in 0..rows_a {
        for j in 0..rows_c {
            if j == 0 || i == 0 || i == na {
                attached.extend((0..rows_t).map(|k| node(i, j, k)));
            }
        }
    }
    mesh.node_sets.insert(ATTACHED.to_string(), attached);
    mesh.element_sets.insert(LEVATOR_ANI.to_string(), levator);
    mesh.element_sets.insert(PERINEAL_BODY.to_string(), perineal_body);
    mesh.surfaces.insert(UPPER_SURFACE.to_string(), upper);
    mesh.surfaces.insert(LOWER_SURFACE.to_string(), lower);
    if let Some(element) = (0..mesh.element_count()).find(|&e| {
        let x: Vec<[f64; 3]> = mesh.element(e).iter().map(|&n| mesh.nodes[n as usize]).collect();
        carus_fem::quality::scaled_jacobian(ElementKind::H8, &x) <= 0.0
    }) {
        return Err(FloorError::Inverted { element });
    }
    Ok(mesh)
}

fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    let s = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pelvis::{PelvisDiameters, PelvisLandmarks};
    use crate::surface::TriSurface;
    use proptest::prelude::*;

    /// Minimum scaled Jacobian the solver's quality check is run against:
    /// for the default pelvis and floor, and for any accepted pelvis with
    /// any thickness and sag in the property test's ranges.
    const DEFAULT_MIN_SCALED_JACOBIAN: f64 = 0.35;
    const ANY_MIN_SCALED_JACOBIAN: f64 = 0.15;

    fn check(pelvis: &Pelvis, parameters: &FloorParameters, threshold: f64) -> Mesh {
        let mesh = pelvic_floor(pelvis, parameters).unwrap();
        let report = carus_fem::quality::check_quality(&mesh, threshold).unwrap();
        assert!(report.passes(), "worst element {} at {}", report.worst_element, report.worst_scaled_jacobian);
        let n = parameters.elements_around * parameters.elements_across * parameters.elements_through;
        assert_eq!(mesh.element_count(), n);
        mesh
    }

    #[test]
    fn the_default_floor_is_valid_attached_and_shaped_as_a_gutter() {
        let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
        let mesh = check(&pelvis, &FloorParameters::default(), DEFAULT_MIN_SCALED_JACOBIAN);
        let x = |n: u32| DVec3::from_array(mesh.nodes[n as usize]);
        // Attached nodes lie near the bony landmarks' ring, not in the canal's middle.
        let attached = &mesh.node_sets[ATTACHED];
        let axis = &pelvis.axis;
        for &n in attached {
            let sigma = axis.project(x(n));
            assert!((x(n) - axis.point(sigma)).length() > 0.015);
        }
        // The upper surface faces the fetus: cranially, against the outlet normal.
        let down = pelvis.planes.outlet.normal;
        let upper = &mesh.surfaces[UPPER_SURFACE];
        let facing: f64 = upper.iter().map(|t| (x(t[1]) - x(t[0])).cross(x(t[2]) - x(t[0])).dot(-down)).sum();
        assert!(facing > 0.0);
        // The gutter: the hiatus rim lies deeper (along the outlet normal)
        // than the lateral attachment at the spines.
        let spine = pelvis.landmarks.ischial_spine_left;
        let rim_depth = mesh.nodes.iter().map(|p| DVec3::from_array(*p).dot(down)).fold(f64::NEG_INFINITY, f64::max);
        assert!(rim_depth > spine.dot(down) + 0.02);
        assert!(!mesh.element_sets[PERINEAL_BODY].is_empty());
    }

    #[test]
    fn a_pelvis_from_landmarks_alone_gets_a_floor() {
        let generated = Pelvis::generate(&PelvisDiameters::default()).unwrap();
        // Perturb the landmarks asymmetrically, as a hand-picked set would be.
        let landmarks: PelvisLandmarks = generated.landmarks.map(|p| p + DVec3::new(0.003 * p.y.sin(), 0.002 * p.x.cos(), 0.0));
        let pelvis = Pelvis::from_landmarks(landmarks, TriSurface::default()).unwrap();
        check(&pelvis, &FloorParameters::default(), ANY_MIN_SCALED_JACOBIAN);
    }

    #[test]
    fn the_imported_visible_human_pelvis_gets_a_floor() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/anatomy/visible-human-female-pelvis.landmarks.toml");
        let imported = crate::import::import_pelvis(&path).unwrap();
        check(&imported.pelvis, &FloorParameters::default(), ANY_MIN_SCALED_JACOBIAN);
    }

    #[test]
    fn bad_parameters_are_named() {
        let pelvis = Pelvis::generate(&PelvisDiameters::default()).unwrap();
        let thin = FloorParameters { thickness_mm: 0.0, ..Default::default() };
        assert!(pelvic_floor(&pelvis, &thin).unwrap_err().to_string().contains("thickness_mm"));
        let wide = FloorParameters { hiatus_width_mm: 90.0, ..Default::default() };
        assert!(matches!(pelvic_floor(&pelvis, &wide), Err(FloorError::HiatusTooWide { .. })));
        let odd = FloorParameters { elements_around: 47, ..Default::default() };
        assert!(matches!(pelvic_floor(&pelvis, &odd), Err(FloorError::OddAround(47))));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
        #[test]
        fn every_generated_pelvis_gets_a_valid_floor(
            ap in 90.0..125.0f64, t in 120.0..145.0f64, spines in 90.0..110.0f64,
            outlet_t in 95.0..120.0f64, angle in 90.0..120.0f64,
            thickness in 4.0..12.0f64, sag in 5.0..35.0f64,
        ) {
            let d = PelvisDiameters {
                inlet_ap_mm: ap,
                inlet_transverse_mm: t,
                inlet_oblique_mm: 0.73 * ap.hypot(t),
                interspinous_mm: spines,
                outlet_transverse_mm: outlet_t,
                outlet_oblique_mm: 0.85 * outlet_t,
                subpubic_angle_deg: angle,
                ..Default::default()
            };
            let Ok(pelvis) = Pelvis::generate(&d) else {
                return Err(TestCaseError::reject("diameters out of reach"));
            };
            let parameters = FloorParameters { thickness_mm: thickness, sag_mm: sag, ..Default::default() };
            check(&pelvis, &parameters, ANY_MIN_SCALED_JACOBIAN);
        }
    }
}
