//! Places the landmarks of a generated pelvis analytically from its diameters
//! (pelvis frame, metres), so each diameter measured back between its
//! landmarks is exact. The mid-sagittal profile (symphysis, sacrum, coccyx)
//! is solved in closed form; the anatomical proportions the diameters do not
//! fix are the named constants below (engineering choices, docs/ANATOMY.md).
//! The sacral ends of the sacrotuberous ligaments (the outlet oblique's back
//! ends) lie on the outer bone surface, so the surface generator places them
//! (generate.rs).

use glam::{DVec2, DVec3};

use super::diameters::{DiameterError, PelvisDiameters};
use super::PelvisLandmarks;

/// Forward tilt of the symphysis' inner surface from the inlet normal, rad.
/// Engineering choice: a standing pelvis with a 55-60 degree inlet
/// (REFERENCE_DATA.md) and its symphysis leaning about 45 degrees.
const SYMPHYSIS_TILT: f64 = 0.26;
/// Fractions of the sacral arc at the S2-S3 and S4-S5 junctions (vertebral
/// heights S1 > S2 > ... > S5; S2-S3 at the middle, where the concavity is measured).
pub(crate) const S2_S3_FRACTION: f64 = 0.5;
pub(crate) const S4_S5_FRACTION: f64 = 0.85;
/// Sacral tilt (chord from the inlet normal, positive backwards) allowed, rad:
/// the bracket the closed-form profile is solved in (numerical), not a shape.
const SACRAL_TILT_RANGE: (f64, f64) = (-1.05, 0.52);
/// Coccyx length as a fraction of the sacral length (about 35 mm for 105 mm).
/// Engineering choice (docs/ANATOMY.md); no measured ratio is cited.
const COCCYX_RATIO: f64 = 0.33;
/// Bend of the coccyx from the sacral curve's end tangent, forward positive,
/// rad: from pointing straight down (the sacrum's end turns forward about 40
/// degrees) to curled forward. The bracket it is solved in (numerical).
const COCCYX_BEND_RANGE: (f64, f64) = (-1.2, 1.3);
/// How far the tuberosities lie below the outlet's AP line, seen from the
/// side, as an angle at the symphysis, rad (the outlet's anterior triangle
/// is tilted down from its posterior one). Engineering choice (docs/ANATOMY.md).
const OUTLET_ANTERIOR_TILT: f64 = 0.35;
/// Junction of the ischial and pubic rami (inner edge of the pubic arch).
/// The inferior rami do not run straight from the symphysis to the
/// tuberosities: the arch is round, so the junction lies well out to the side
/// and bowed forward. On the Visible Human female pelvis (docs/ANATOMY.md)
/// it lies at 0.51 and 0.57 of the tuberosities' distance from the
/// midsagittal plane (left, right), 1 and 12 mm in
/// front of the lower symphysis border and 16-22 mm below it (pelvis frame,
/// a third of the tuberosities' depth below it). The generated junction: at
/// `ISCHIOPUBIC_WIDTH_SHARE` of the tuberosity's half-width, at
/// `ISCHIOPUBIC_FRACTION` of the sagittal chord from the lower symphysis
/// border to the tuberosity, pushed forward, square to that chord, by
/// `PUBIC_ARCH_BOW` times its length (about 6 mm in front of the lower
/// symphysis border and 20 mm below it for the defaults).
const ISCHIOPUBIC_WIDTH_SHARE: f64 = 0.6;
const ISCHIOPUBIC_FRACTION: f64 = 0.4;
const PUBIC_ARCH_BOW: f64 = 0.3;
/// The lower lateral angle of the sacrum (beside the apex, where the sacral
/// border turns in to the coccyx): this far behind the apex's anterior
/// surface, square to the sacral chord (the lateral mass stands behind the
/// vertebral bodies), m, and at this share of the outlet transverse from the
/// midline. It shapes the canal wall beside the apex; the sacrotuberous
/// attachment itself lies on the outer surface (generate.rs). Engineering
/// choices (docs/ANATOMY.md).
pub(crate) const LOWER_LATERAL_ANGLE_DEPTH: f64 = 0.015;
pub(crate) const LOWER_LATERAL_ANGLE_SHARE: f64 = 0.2;
/// Inlet shape exponent range: s = 2^(-1/n) is the share of the bounding
/// diagonal the oblique takes; 0.6-0.9 spans a near-diamond to a near-box.
/// The bracket the obliques are solved in (numerical), not a shape.
const INLET_OBLIQUE_SHARE: (f64, f64) = (0.6, 0.9);

/// The generated pelvis' landmarks plus the shape data the surface needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Layout {
    /// The landmarks; the sacral borders stand at the lower lateral angles of
    /// the sacrum until the surface generator moves them up the sacrum's
    /// outer border to make the outlet oblique exact.
    pub landmarks: PelvisLandmarks,
    /// The sacrum's lower lateral angle, mother's right.
    pub lower_lateral_angle: DVec3,
    /// Unit sagittal (y, z) direction square to the sacral chord, backwards.
    pub sacrum_behind: DVec2,
    /// Superellipse exponent of the inlet outline.
    pub inlet_exponent: f64,
    /// y of the widest inlet transverse.
    pub inlet_transverse_y: f64,
    /// Half-width and sagittal (y, z) of the lateral points of the greatest-dimensions ring.
    pub greatest_half_width: f64,
    pub greatest_lateral: DVec2,
    /// Sagittal (y, z) of the spines and of the tuberosities' midpoint.
    pub spine: DVec2,
    pub tuberosity: DVec2,
    /// Unit sagittal direction of the coccyx (apex to tip).
    pub coccyx_direction: DVec2,
}

/// A point from its x and sagittal (y, z).
pub(crate) fn point(x: f64, s: DVec2) -> DVec3 {
    DVec3::new(x, s.x, s.y)
}

/// Rotation in the sagittal plane by `angle` (positive turns +y towards +z).
fn rotate(v: DVec2, angle: f64) -> DVec2 {
    let (s, c) = angle.sin_cos();
    DVec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Of the two rotations of `v` by `+-angle`, the one pointing lower (caudal).
fn rotate_caudally(v: DVec2, angle: f64) -> DVec2 {
    let (a, b) = (rotate(v, angle), rotate(v, -angle));
    if a.y <= b.y {
        a
    } else {
        b
    }
}

/// Angle at a triangle's vertex opposite `opposite`, from its sides (law of cosines);
/// `None` when the triangle cannot close.
fn angle_from_sides(side_a: f64, side_b: f64, opposite: f64) -> Option<f64> {
    let c = (side_a * side_a + side_b * side_b - opposite * opposite) / (2.0 * side_a * side_b);
    (-1.0..=1.0).contains(&c).then(|| c.acos())
}

/// The sacrum as a circular arc from the promontory, bulging backwards.
struct SacralArc {
    length: f64,
    depth: f64,
}

impl SacralArc {
    /// Local coordinates (along the chord, behind the chord) at arc fraction `f`.
    fn local(&self, f: f64) -> DVec2 {
        let half_angle = 2.0 * (2.0 * self.depth / self.length).atan();
        let radius = 0.5 * self.length / half_angle.sin();
        let theta = half_angle * (2.0 * f - 1.0);
        DVec2::new(0.5 * self.length + radius * theta.sin(), radius * theta.cos() - (radius - self.depth))
    }

    /// Sagittal point at fraction `f` for a chord leaving the promontory along `chord`.
    fn at(&self, promontory: DVec2, chord: DVec2, f: f64) -> DVec2 {
        let behind = rotate(chord, -std::f64::consts::FRAC_PI_2);
        let l = self.local(f);
        promontory + l.x * chord + l.y * behind
    }
}

/// Chord direction of a sacrum tilted `tilt` rad backwards from the inlet normal.
fn sacral_chord(tilt: f64) -> DVec2 {
    DVec2::new(-tilt.sin(), -tilt.cos())
}

pub(crate) fn layout(d: &PelvisDiameters) -> Result<Layout, DiameterError> {
    d.validate()?;
    let mm = 1e-3;
    let (a, t) = (d.inlet_ap_mm * mm, d.inlet_transverse_mm * mm);

    // Inlet: a superellipse through the conjugate's ends and the widest
    // transverse; its exponent makes the oblique exact: the 45-degree points
    // are at s = 2^(-1/n) of the half-axes, so oblique = s * sqrt(a^2 + t^2).
    let diagonal = a.hypot(t);
    let share = d.inlet_oblique_mm * mm / diagonal;
    if !(INLET_OBLIQUE_SHARE.0..=INLET_OBLIQUE_SHARE.1).contains(&share) {
        return Err(DiameterError::OutOfReach {
            key: "inlet_oblique_mm",
            value: d.inlet_oblique_mm,
            reason: "the inlet outline would be a diamond or a box (from inlet_ap_mm and inlet_transverse_mm)",
            min: INLET_OBLIQUE_SHARE.0 * diagonal / mm,
            max: INLET_OBLIQUE_SHARE.1 * diagonal / mm,
        });
    }
    let inlet_exponent = std::f64::consts::LN_2 / -share.ln();
    let promontory = DVec2::new(-0.5 * a, 0.0);
    let symphysis_upper = DVec2::new(0.5 * a, 0.0);
    let inlet_transverse_y = -0.5 * a + d.inlet_posterior_share * a;
    let (front, back) = (0.5 * a - inlet_transverse_y, inlet_transverse_y + 0.5 * a);
    let eminence = DVec2::new(inlet_transverse_y + share * front, 0.0);
    let sacroiliac = DVec2::new(inlet_transverse_y - share * back, 0.0);

    let symphysis_lower =
        symphysis_upper + d.symphysis_length_mm * mm * DVec2::new(SYMPHYSIS_TILT.sin(), -SYMPHYSIS_TILT.cos());

    // Sacrum: a rigid arc hinged at the promontory, turned until the S4-S5
    // junction is mid_ap_mm from the lower symphysis.
    let arc = SacralArc { length: d.sacral_length_mm * mm, depth: d.sacral_depth_mm * mm };
    let s45_local = arc.local(S4_S5_FRACTION);
    let to_symphysis = symphysis_lower - promontory;
    let mid_ap_at = |tilt: f64| (arc.at(promontory, sacral_chord(tilt), S4_S5_FRACTION) - symphysis_lower).length();
    let mid_ap_range = || {
        let (lo, hi) = (mid_ap_at(SACRAL_TILT_RANGE.0), mid_ap_at(SACRAL_TILT_RANGE.1));
        (lo.min(hi) / mm, lo.max(hi) / mm)
    };
    let mid_ap = d.mid_ap_mm * mm;
    let Some(opening) = angle_from_sides(to_symphysis.length(), s45_local.length(), mid_ap) else {
        let (min, max) = mid_ap_range();
        return Err(DiameterError::OutOfReach {
            key: "mid_ap_mm",
            value: d.mid_ap_mm,
            reason: "the sacrum (sacral_length_mm, sacral_depth_mm) cannot reach that far from the symphysis",
            min,
            max,
        });
    };
    let towards_s45 = rotate_caudally(to_symphysis.normalize(), opening);
    let chord = rotate(towards_s45, s45_local.y.atan2(s45_local.x));
    let tilt = (-chord.x).atan2(-chord.y);
    if !(SACRAL_TILT_RANGE.0..=SACRAL_TILT_RANGE.1).contains(&tilt) {
        let (min, max) = mid_ap_range();
        return Err(DiameterError::OutOfReach {
            key: "mid_ap_mm",
            value: d.mid_ap_mm,
            reason: "the sacrum would have to tilt beyond 60 degrees forward or 30 degrees back",
            min,
            max,
        });
    }
    let s2_s3 = arc.at(promontory, chord, S2_S3_FRACTION);
    let s4_s5 = arc.at(promontory, chord, S4_S5_FRACTION);
    let apex = arc.at(promontory, chord, 1.0);

    // Coccyx: a rigid segment hinged at the apex, bent until its tip is
    // outlet_ap_mm from the lower symphysis.
    let coccyx_length = COCCYX_RATIO * arc.length;
    let end_tangent = (apex - arc.at(promontory, chord, 1.0 - 1e-6)).normalize();
    let apex_to_symphysis = symphysis_lower - apex;
    // Forward bend turns the tangent towards the symphysis (+y).
    let forward = if rotate(end_tangent, 0.1).x > end_tangent.x { 1.0 } else { -1.0 };
    let outlet_ap_at = |bend: f64| (apex + coccyx_length * rotate(end_tangent, forward * bend) - symphysis_lower).length();
    let outlet_ap_range = || {
        let samples = (0..=64).map(|k| {
            let f = k as f64 / 64.0;
            outlet_ap_at(COCCYX_BEND_RANGE.0 + f * (COCCYX_BEND_RANGE.1 - COCCYX_BEND_RANGE.0)) / mm
        });
        samples.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let outlet_ap = d.outlet_ap_mm * mm;
    let coccyx_direction = angle_from_sides(apex_to_symphysis.length(), coccyx_length, outlet_ap)
        .map(|opening| rotate_caudally(apex_to_symphysis.normalize(), opening))
        .filter(|dir| {
            let bend = forward * end_tangent.perp_dot(*dir).atan2(end_tangent.dot(*dir));
            (COCCYX_BEND_RANGE.0..=COCCYX_BEND_RANGE.1).contains(&bend)
        });
    let Some(coccyx_direction) = coccyx_direction else {
        let (min, max) = outlet_ap_range();
        return Err(DiameterError::OutOfReach {
            key: "outlet_ap_mm",
            value: d.outlet_ap_mm,
            reason: "the coccyx cannot bend that far from the sacrum's end (after mid_ap_mm, sacral_length_mm)",
            min,
            max,
        });
    };
    let coccyx_tip = apex + coccyx_length * coccyx_direction;

    let spine = s4_s5 + d.mid_posterior_share * (symphysis_lower - s4_s5);
    let greatest_lateral = s2_s3 + d.inlet_posterior_share * (0.5 * (symphysis_upper + symphysis_lower) - s2_s3);
    let (i, ot) = (d.interspinous_mm * mm, d.outlet_transverse_mm * mm);
    let greatest_half_width = 0.5 * t - 0.1 * (t - i);

    // Tuberosities: the subpubic angle fixes how far behind the symphysis
    // their midpoint lies (half the intertuberous over tan of half the angle).
    let half_angle = 0.5 * d.subpubic_angle_deg.to_radians();
    let anterior_sagittal = 0.5 * ot / half_angle.tan();
    let to_coccyx = coccyx_tip - symphysis_lower;
    if anterior_sagittal >= 0.8 * to_coccyx.length() {
        let min_angle = 2.0 * (0.5 * ot / (0.8 * to_coccyx.length())).atan().to_degrees();
        return Err(DiameterError::OutOfReach {
            key: "subpubic_angle_deg",
            value: d.subpubic_angle_deg,
            reason: "the pubic arch would reach back to the coccyx (with outlet_transverse_mm, outlet_ap_mm)",
            min: min_angle,
            max: 150.0,
        });
    }
    let tuberosity = symphysis_lower + anterior_sagittal * rotate_caudally(to_coccyx.normalize(), OUTLET_ANTERIOR_TILT);
    let arch = tuberosity - symphysis_lower;
    let mut bow = arch.perp();
    if bow.x < 0.0 {
        bow = -bow;
    }
    let ischiopubic = symphysis_lower + ISCHIOPUBIC_FRACTION * arch + PUBIC_ARCH_BOW * bow;
    let ischiopubic_x = ISCHIOPUBIC_WIDTH_SHARE * 0.5 * ot;

    // Lower lateral angle of the sacrum. The sacrotuberous attachment (the
    // sacral_border landmarks) starts here and is moved up the sacrum's
    // outer border by the surface generator until the outlet oblique is
    // exact (generate.rs); outlet_oblique_mm is checked there.
    let behind_sacrum = rotate(chord, -std::f64::consts::FRAC_PI_2);
    let lower_lateral_angle = apex + LOWER_LATERAL_ANGLE_DEPTH * behind_sacrum;
    let border_half_width = LOWER_LATERAL_ANGLE_SHARE * ot;

    let mirror = |p: DVec3| DVec3::new(-p.x, p.y, p.z);
    let sacroiliac_right = point(share * 0.5 * t, sacroiliac);
    let eminence_right = point(share * 0.5 * t, eminence);
    let spine_right = point(0.5 * i, spine);
    let tuberosity_right = point(0.5 * ot, tuberosity);
    let border_right = point(border_half_width, lower_lateral_angle);
    let ischiopubic_right = point(ischiopubic_x, ischiopubic);
    let landmarks = PelvisLandmarks {
        sacral_promontory: point(0.0, promontory),
        symphysis_upper: point(0.0, symphysis_upper),
        symphysis_lower: point(0.0, symphysis_lower),
        iliopectineal_left: DVec3::new(-0.5 * t, inlet_transverse_y, 0.0),
        iliopectineal_right: DVec3::new(0.5 * t, inlet_transverse_y, 0.0),
        sacroiliac_left: mirror(sacroiliac_right),
        sacroiliac_right,
        iliopubic_eminence_left: mirror(eminence_right),
        iliopubic_eminence_right: eminence_right,
        sacrum_s2_s3: point(0.0, s2_s3),
        sacrum_s4_s5: point(0.0, s4_s5),
        sacral_apex: point(0.0, apex),
        coccyx_tip: point(0.0, coccyx_tip),
        ischial_spine_left: mirror(spine_right),
        ischial_spine_right: spine_right,
        ischial_tuberosity_left: mirror(tuberosity_right),
        ischial_tuberosity_right: tuberosity_right,
        sacral_border_left: mirror(border_right),
        sacral_border_right: border_right,
        ischiopubic_left: mirror(ischiopubic_right),
        ischiopubic_right,
    };
    Ok(Layout {
        landmarks,
        lower_lateral_angle: border_right,
        sacrum_behind: behind_sacrum,
        inlet_exponent,
        inlet_transverse_y,
        greatest_half_width,
        greatest_lateral,
        spine,
        tuberosity,
        coccyx_direction,
    })
}
