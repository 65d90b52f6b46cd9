//! The fetal trunk: neck, shoulders, chest, abdomen and hips as a closed
//! surface of superellipse rings, built from the bisacromial and
//! bitrochanteric diameters and the lengths of the cervical spine and of
//! the trunk below it.
//!
//! Trunk frame (metres): origin at the atlanto-occipital pivot, where the
//! trunk carries the head; x ventral, y towards the fetal left, z cranial, so
//! that with the neck straight it is the head frame moved to the pivot. The
//! spine axis k (CARDINAL_MOVEMENTS.md: from the pivot towards the breech)
//! is -z.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::axis::Plane;
use crate::surface::TriSurface;

/// Shoulder and hip widths of the fetus (canonical names of CONVENTIONS.md)
/// and the length of its neck, millimetres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrunkDiameters {
    /// Between the acromions. REFERENCE_DATA.md: bisacromial about 120 mm
    /// (neonatal mean 124, sd 10); the textbook 120 mm is taken.
    pub bisacromial_mm: f64,
    /// Between the greater trochanters. Engineering estimate: 95 mm, the
    /// figure of about 9.5 cm quoted in obstetric texts for the term breech;
    /// not yet in REFERENCE_DATA.md.
    pub bitrochanteric_mm: f64,
    /// From the atlanto-occipital pivot down to the first thoracic
    /// vertebra, where the neck meets the chest. "At birth, the cervical
    /// spine measures 3.7 cm in length" (Roche, Cervical Spine, Medical
    /// Radiology, Springer; doi 10.1007/978-3-540-68897-6_6). Not scaled
    /// with the shoulders: a wider girdle is not a longer neck.
    pub cervical_spine_mm: f64,
    /// From the neck base (T1) down to the buttocks' lowest ring, along
    /// the spine (the breech's cap rounds off below it).
    /// Engineering estimate: 186 mm, the proportion (1.55 bisacromial) the
    /// trunk was shaped with on a term neonate with 120 mm shoulders; with
    /// the head and neck it makes a 314 mm sitting height, near the
    /// newborn's 0.65 of a 50 cm length (docs/ANATOMY.md). Not scaled with
    /// the shoulders: a wider girdle is not a longer spine (macrosomic
    /// infants of diabetic mothers have larger shoulders at the same
    /// length, J Matern Fetal Med 1998;7(6):292), so the levels along it
    /// (the shoulder ring, the thoracolumbar junction, the hips) stay where
    /// they are when only the shoulders widen.
    pub trunk_length_mm: f64,
    /// Across the chest at its widest ring (0.35 of the trunk's level unit
    /// below the neck base), side to side over the skin: it sets the
    /// girths (the neck's, the chest's and the abdomen's, and every ring's
    /// depth), which are fractions of it, so that only the shoulders widen
    /// with `bisacromial_mm` (a wider girdle is not a bigger chest: macrosomic
    /// infants of diabetic mothers have larger shoulder circumferences at the
    /// same weight and length, J Matern Fetal Med 1998;7(6):292, and a
    /// chest-to-head disproportion of its own goes with shoulder dystocia,
    /// Modanlou et al. 1982, Obstet Gynecol 60:417).
    /// Engineering estimate: 108 mm, 0.9 of the 120 mm shoulders the
    /// sections were shaped on; with the ring's depth (0.82 of its breadth)
    /// its circumference is 322 mm, between the 295-299 mm below which a
    /// newborn is likely of low birth weight (Hong Kong Chinese newborns,
    /// Early Hum Dev 2005;81:781) and the 348 mm predicted for a 3360 g
    /// newborn with a 345 mm head circumference (CC = 14.87 + 0.003 W + 0.287
    /// HC, cm and g: Azevedo et al. 2019, BMC Pediatr 19:341).
    pub chest_breadth_mm: f64,
}

impl Default for TrunkDiameters {
    fn default() -> Self {
        TrunkDiameters {
            bisacromial_mm: 120.0,
            bitrochanteric_mm: 95.0,
            cervical_spine_mm: 37.0,
            trunk_length_mm: 186.0,
            chest_breadth_mm: 108.0,
        }
    }
}

/// Why a trunk cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrunkError {
    #[error("{name} = {value} mm: the trunk's diameters and neck must be positive, finite lengths")]
    NotPositive { name: &'static str, value: f64 },
}

impl TrunkDiameters {
    /// The girth scale G the sections' girths are fractions of, m: the
    /// chest's breadth over 0.9 (until the forty-fourth session the
    /// bisacromial diameter, which it equals to the bit for the defaults).
    pub fn girth_scale_m(&self) -> f64 {
        self.chest_breadth_mm * 1e-3 / CHEST_BREADTH_SHARE
    }

    pub fn validate(&self) -> Result<(), TrunkError> {
        for (name, value) in [
            ("bisacromial_mm", self.bisacromial_mm),
            ("bitrochanteric_mm", self.bitrochanteric_mm),
            ("cervical_spine_mm", self.cervical_spine_mm),
            ("trunk_length_mm", self.trunk_length_mm),
            ("chest_breadth_mm", self.chest_breadth_mm),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(TrunkError::NotPositive { name, value });
            }
        }
        Ok(())
    }
}

/// Points along the ring, a multiple of 4 so that the sideways extremes
/// (acromions, trochanters) are ring vertices.
const RING_POINTS: usize = 48;
/// Superellipse exponent of the cross-sections: a rounded, boxy torso
/// (engineering choice, docs/ANATOMY.md).
const SECTION_EXPONENT: f64 = 2.5;

/// One cross-section of the trunk: height, half-width (along y), half-depth
/// (along x) and the ventral offset of its centre from the spine line.
#[derive(Debug, Clone, Copy)]
struct Section {
    z: f64,
    half_width: f64,
    half_depth: f64,
    centre_x: f64,
}

/// The trunk's levels below the neck are given in units L of its length,
/// `trunk_length_mm` = 1.55 L (L = 120 mm by default, the term neonate the
/// sections were shaped on).
const LEVEL_UNITS_PER_TRUNK_LENGTH: f64 = 1.55;

/// The chest ring's breadth as a share of the girth scale G the sections'
/// fractions are of (G = 120 mm by default, the shoulders they were shaped on).
const CHEST_BREADTH_SHARE: f64 = 0.9;

/// Cross-sections from the neck down: the pivot, then the neck base at the
/// cervical spine's length below it, then the trunk at depths below the
/// neck base. Girths are fractions of a girth scale G (the chest's breadth
/// over 0.9) and depths fractions of the trunk's length in its 1.55
/// parts, L (engineering estimates shaped on a term neonate, where L = G =
/// 120 mm: neck about 48 mm thick, chest 108 x 88 mm and abdomen about 100
/// x 92 mm, i.e. circumferences near 31-33 cm), except the shoulder and hip
/// widths, which are the diameters themselves.
fn sections(d: &TrunkDiameters) -> [Section; 8] {
    let s = d.girth_scale_m();
    let shoulders = d.bisacromial_mm * 1e-3;
    let t = d.bitrochanteric_mm * 1e-3;
    let neck_base = d.cervical_spine_mm * 1e-3;
    let l = d.trunk_length_mm * 1e-3 / LEVEL_UNITS_PER_TRUNK_LENGTH;
    let section = |depth: f64, half_width: f64, half_depth: f64, centre: f64| Section {
        z: -(neck_base + depth * l),
        half_width,
        half_depth: half_depth * s,
        centre_x: centre * s,
    };
    let pivot = Section {
        z: 0.0,
        ..section(0.0, 0.18 * s, 0.18, 0.05)
    };
    [
        pivot,
        section(0.0, 0.20 * s, 0.19, 0.06),
        section(0.12, 0.5 * shoulders, 0.28, 0.12),
        section(0.35, 0.45 * s, 0.37, 0.20),
        section(0.75, 0.42 * s, 0.38, 0.22),
        section(1.15, 0.5 * t, 0.33, 0.18),
        section(1.42, 0.36 * t, 0.22, 0.12),
        section(LEVEL_UNITS_PER_TRUNK_LENGTH, 0.12 * t, 0.08, 0.08),
    ]
}

/// Index of the section at the base of the neck, where the shoulders begin.
const NECK_BASE: usize = 1;
/// Index of the shoulder (acromion), chest and hip (trochanter) sections.
const SHOULDER: usize = 2;
const CHEST: usize = 3;
const HIP: usize = 5;
/// Index of the buttocks' lowest ring, the end of the trunk's length.
const BUTTOCKS: usize = 7;
/// Index of the section at the thoracolumbar junction, below the chest
/// (0.75 L below the neck base, 127 mm below the pivot for the default
/// trunk). Engineering
/// estimate: in a term neonate the thoracic spine ends about halfway from
/// the atlas to the sacral tip; the cut is where the trunk bends.
const THORACOLUMBAR: usize = 4;

/// Named points of the trunk, metres, trunk frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrunkLandmarks {
    /// Where the trunk carries the head: the atlanto-occipital pivot (origin).
    pub neck: DVec3,
    pub acromion_left: DVec3,
    pub acromion_right: DVec3,
    /// Midpoint of the bisacromial diameter (CARDINAL_MOVEMENTS.md, expulsion).
    pub bisacromial_midpoint: DVec3,
    pub trochanter_left: DVec3,
    pub trochanter_right: DVec3,
    /// Centre of the trunk: midway between the bisacromial and bitrochanteric midpoints.
    pub centre: DVec3,
    /// Lowest point of the buttocks, on the spine axis side.
    pub breech: DVec3,
}

impl TrunkLandmarks {
    /// Every landmark with its name.
    pub fn named(&self) -> [(&'static str, DVec3); 8] {
        [
            ("neck", self.neck),
            ("acromion_left", self.acromion_left),
            ("acromion_right", self.acromion_right),
            ("bisacromial_midpoint", self.bisacromial_midpoint),
            ("trochanter_left", self.trochanter_left),
            ("trochanter_right", self.trochanter_right),
            ("centre", self.centre),
            ("breech", self.breech),
        ]
    }
}

/// The trunk: diameters, closed outward surface, landmarks and spine axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Trunk {
    pub diameters: TrunkDiameters,
    pub surface: TriSurface,
    pub landmarks: TrunkLandmarks,
    /// Unit spine axis k, from the pivot towards the breech (trunk frame).
    pub spine_axis: DVec3,
}

/// Point at parameter `theta` on a section: theta = 0 is the fetal left
/// (+y), pi/2 ventral (+x).
fn ring_point(s: &Section, theta: f64) -> DVec3 {
    let p = 2.0 / SECTION_EXPONENT;
    let (sin, cos) = theta.sin_cos();
    // Exact zeros at the quarter points keep the extremes exact.
    let shaped = |c: f64| {
        if c.abs() < 1e-12 {
            0.0
        } else {
            c.signum() * c.abs().powf(p)
        }
    };
    DVec3::new(s.centre_x + s.half_depth * shaped(sin), s.half_width * shaped(cos), s.z)
}

/// Closed surface of the rings of `sections`, capped by a fan to `top`
/// above the first ring and to `bottom` below the last.
fn closed_tube(sections: &[Section], top: DVec3, bottom: DVec3) -> TriSurface {
    let n = RING_POINTS;
    let mut vertices = Vec::with_capacity(sections.len() * n + 2);
    for s in sections {
        vertices.extend((0..n).map(|k| ring_point(s, std::f64::consts::TAU * k as f64 / n as f64)));
    }
    let apex = vertices.len() as u32;
    vertices.push(top);
    vertices.push(bottom);
    let ring = |r: usize, k: usize| (r * n + k % n) as u32;
    let mut triangles = Vec::with_capacity(2 * n * sections.len());
    // Rings run clockwise seen from above (left -> ventral -> right), so
    // going down, (upper k, lower k + 1, lower k) faces outwards.
    for r in 0..sections.len() - 1 {
        for k in 0..n {
            triangles.push([ring(r, k), ring(r + 1, k + 1), ring(r + 1, k)]);
            triangles.push([ring(r, k), ring(r, k + 1), ring(r + 1, k + 1)]);
        }
    }
    let lowest = sections.len() - 1;
    for k in 0..n {
        triangles.push([apex, ring(0, k + 1), ring(0, k)]);
        triangles.push([apex + 1, ring(lowest, k), ring(lowest, k + 1)]);
    }
    TriSurface::new(vertices, triangles)
}

/// Centre of a section's ring, where a flat cap closes it.
fn section_centre(s: &Section) -> DVec3 {
    DVec3::new(s.centre_x, 0.0, s.z)
}

/// The breech: below the last section, on its centre line.
fn breech_point(sections: &[Section]) -> DVec3 {
    let last = sections[sections.len() - 1];
    DVec3::new(last.centre_x, 0.0, last.z - 0.5 * last.half_depth)
}

/// The trunk cut at the thoracolumbar junction into two closed segments,
/// each capped flat at the cut, for a spine that bends there.
#[derive(Debug, Clone, PartialEq)]
pub struct TrunkSegments {
    /// Neck, shoulders and chest (trunk frame).
    pub thorax: TriSurface,
    /// Abdomen, hips and buttocks (trunk frame).
    pub lower: TriSurface,
    /// The joint between them, on the spine line at the cut (trunk frame).
    pub thoracolumbar: DVec3,
}

impl Trunk {
    pub fn new(d: &TrunkDiameters) -> Result<Self, TrunkError> {
        d.validate()?;
        let sections = sections(d);
        let breech = breech_point(&sections);
        let surface = closed_tube(&sections, section_centre(&sections[0]), breech);
        let n = RING_POINTS;
        let vertices = &surface.vertices;
        let ring = |r: usize, k: usize| r * n + k % n;
        let at = |section: usize, quarter: usize| vertices[ring(section, quarter * n / 4)];
        let acromion_left = at(SHOULDER, 0);
        let acromion_right = at(SHOULDER, 2);
        let trochanter_left = at(HIP, 0);
        let trochanter_right = at(HIP, 2);
        let bisacromial_midpoint = 0.5 * (acromion_left + acromion_right);
        let landmarks = TrunkLandmarks {
            neck: DVec3::ZERO,
            acromion_left,
            acromion_right,
            bisacromial_midpoint,
            trochanter_left,
            trochanter_right,
            centre: 0.5 * (bisacromial_midpoint + 0.5 * (trochanter_left + trochanter_right)),
            breech,
        };
        Ok(Trunk {
            diameters: *d,
            surface,
            landmarks,
            spine_axis: -DVec3::Z,
        })
    }

    /// The superior thoracic aperture, the plane where the neck ends and
    /// the chest begins, positive below (towards the chest). Gray's
    /// Anatomy (the thorax): the aperture is bounded by the first thoracic
    /// vertebra behind and the manubrium's jugular notch in front, and
    /// slopes down and forwards. Here it runs through the back of the neck
    /// base (at T1, the cervical spine's length below the pivot) and the
    /// front of the shoulder section (0.12 L lower), the clavicles lying
    /// almost level from the notch to the acromions (engineering reading
    /// for the fetus), across the
    /// shoulders from side to side. Below it bone lies under the skin;
    /// above it the front of the neck is throat, which the jaw presses in
    /// flexion and the neck joint models.
    pub fn thoracic_inlet(&self) -> Plane {
        let sections = sections(&self.diameters);
        let (base, shoulder) = (&sections[NECK_BASE], &sections[SHOULDER]);
        let first_thoracic = DVec3::new(base.centre_x - base.half_depth, 0.0, base.z);
        let jugular_notch = DVec3::new(shoulder.centre_x + shoulder.half_depth, 0.0, shoulder.z);
        // In the midline, perpendicular to the T1-notch line; the notch
        // lies ventral of T1, so y x (notch - T1) points caudally.
        let normal = DVec3::Y.cross(jugular_notch - first_thoracic).normalize();
        Plane { centre: first_thoracic, normal }
    }

    /// The two segments of a spine that bends at the thoracolumbar junction.
    pub fn segments(&self) -> TrunkSegments {
        let sections = sections(&self.diameters);
        let (upper, lower) = (&sections[..=THORACOLUMBAR], &sections[THORACOLUMBAR..]);
        let cut = section_centre(&sections[THORACOLUMBAR]);
        TrunkSegments {
            thorax: closed_tube(upper, section_centre(&sections[0]), cut),
            lower: closed_tube(lower, cut, breech_point(&sections)),
            thoracolumbar: DVec3::new(0.0, 0.0, sections[THORACOLUMBAR].z),
        }
    }

    /// The trunk measured back, millimetres.
    pub fn measure(&self) -> TrunkMeasurement {
        let l = &self.landmarks;
        let (lo, hi) = self.surface.bounds().unwrap_or_default();
        let chest = &self.surface.vertices[CHEST * RING_POINTS..(CHEST + 1) * RING_POINTS];
        TrunkMeasurement {
            bisacromial_mm: l.acromion_left.distance(l.acromion_right) * 1e3,
            bitrochanteric_mm: l.trochanter_left.distance(l.trochanter_right) * 1e3,
            chest_breadth_mm: (chest[0].y - chest[RING_POINTS / 2].y) * 1e3,
            chest_circumference_mm: (0..RING_POINTS).map(|k| chest[k].distance(chest[(k + 1) % RING_POINTS])).sum::<f64>() * 1e3,
            width_mm: (hi.y - lo.y) * 1e3,
            length_mm: (hi.z - lo.z) * 1e3,
            cervical_spine_mm: (l.neck.z - self.surface.vertices[NECK_BASE * RING_POINTS].z) * 1e3,
            trunk_length_mm: (self.surface.vertices[NECK_BASE * RING_POINTS].z
                - self.surface.vertices[BUTTOCKS * RING_POINTS].z)
                * 1e3,
            landmarks_mm: l.named().into_iter().map(|(name, p)| (name.to_string(), (p * 1e3).to_array())).collect(),
        }
    }
}

/// Trunk diameters measured between landmarks and the trunk's extents, mm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrunkMeasurement {
    pub bisacromial_mm: f64,
    pub bitrochanteric_mm: f64,
    /// Across the chest's ring, and round it.
    pub chest_breadth_mm: f64,
    pub chest_circumference_mm: f64,
    /// Extent from side to side (the widest of shoulders, chest and hips).
    pub width_mm: f64,
    /// Extent along the spine, neck to breech.
    pub length_mm: f64,
    /// From the pivot down to the neck base (T1).
    pub cervical_spine_mm: f64,
    /// From the neck base down to the buttocks' lowest ring.
    pub trunk_length_mm: f64,
    /// Landmark positions, mm, trunk frame.
    pub landmarks_mm: std::collections::BTreeMap<String, [f64; 3]>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        #[test]
        fn trunks_are_closed_and_measure_back(s in 90.0..180.0f64, t in 70.0..120.0f64, c in 20.0..50.0f64, l in 120.0..260.0f64, b in 80.0..140.0f64) {
            let d = TrunkDiameters { bisacromial_mm: s, bitrochanteric_mm: t, cervical_spine_mm: c, trunk_length_mm: l, chest_breadth_mm: b };
            let trunk = Trunk::new(&d).unwrap();
            trunk.surface.check_closed().unwrap();
            let m = trunk.measure();
            prop_assert!((m.bisacromial_mm - s).abs() < 0.1);
            prop_assert!((m.bitrochanteric_mm - t).abs() < 0.1);
            prop_assert!((m.chest_breadth_mm - b).abs() < 0.1);
            prop_assert!((m.width_mm - s.max(t).max(b)).abs() < 0.1);
            prop_assert!((m.cervical_spine_mm - c).abs() < 0.1);
            prop_assert!((m.trunk_length_mm - l).abs() < 0.1);
            // The shoulders widen the trunk, not lengthen it.
            let wider = Trunk::new(&TrunkDiameters { bisacromial_mm: 1.3 * s, ..d }).unwrap();
            prop_assert!((wider.measure().trunk_length_mm - m.trunk_length_mm).abs() < 1e-9);
            prop_assert!((wider.landmarks.acromion_left.z - trunk.landmarks.acromion_left.z).abs() < 1e-12);
            // ... nor its chest: only the shoulder ring moves.
            let moved = |a: &Trunk, b: &Trunk| a.surface.vertices.iter().zip(&b.surface.vertices).filter(|(p, q)| p != q).count();
            prop_assert_eq!(moved(&wider, &trunk), RING_POINTS - 2);
            prop_assert_eq!(wider.measure().chest_circumference_mm, m.chest_circumference_mm);
        }

        #[test]
        fn the_segments_close_and_fill_the_trunk(s in 90.0..180.0f64, t in 70.0..120.0f64, c in 20.0..50.0f64, l in 120.0..260.0f64, b in 80.0..140.0f64) {
            let d = TrunkDiameters { bisacromial_mm: s, bitrochanteric_mm: t, cervical_spine_mm: c, trunk_length_mm: l, chest_breadth_mm: b };
            let trunk = Trunk::new(&d).unwrap();
            let parts = trunk.segments();
            parts.thorax.check_closed().unwrap();
            parts.lower.check_closed().unwrap();
            let (thorax, lower) = (parts.thorax.signed_volume(), parts.lower.signed_volume());
            prop_assert!(thorax > 0.0 && lower > 0.0);
            let whole = trunk.surface.signed_volume();
            prop_assert!((thorax + lower - whole).abs() < 1e-9 * whole.max(1.0) + 1e-12);
            // The shoulders ride on the thorax, the hips on the lower trunk.
            let (_, thorax_top) = parts.thorax.bounds().unwrap();
            let (lower_bottom, lower_top) = parts.lower.bounds().unwrap();
            let l = trunk.landmarks;
            prop_assert!(l.acromion_left.z > parts.thoracolumbar.z && l.trochanter_left.z < parts.thoracolumbar.z);
            // The chest begins below the pivot, lower in front than behind,
            // with the acromions and the hips below it.
            let inlet = trunk.thoracic_inlet();
            prop_assert!(inlet.signed_distance(l.neck) < 0.0);
            prop_assert!(inlet.normal.x < 0.0 && inlet.normal.y == 0.0);
            prop_assert!(inlet.signed_distance(l.acromion_left) > 0.0 && inlet.signed_distance(l.acromion_right) > 0.0);
            prop_assert!(inlet.signed_distance(l.trochanter_left) > 0.0);
            prop_assert!((lower_top.z - parts.thoracolumbar.z).abs() < 1e-12 && thorax_top.z <= 1e-12);
            prop_assert!((lower_bottom.z - l.breech.z).abs() < 1e-12);
        }
    }

    #[test]
    fn defaults_and_errors() {
        let trunk = Trunk::new(&TrunkDiameters::default()).unwrap();
        let l = trunk.landmarks;
        assert!(l.acromion_left.y > 0.0 && l.acromion_right.y < 0.0);
        assert!(l.breech.z < l.trochanter_left.z && l.trochanter_left.z < l.acromion_left.z);
        assert!((trunk.spine_axis - (l.breech - l.neck).normalize()).length() < 0.2);
        // The default chest is the one the sections were shaped on: 108 mm
        // across, 322 mm round (docs/ANATOMY.md).
        let m = trunk.measure();
        assert!((m.chest_breadth_mm - 108.0).abs() < 1e-9 && (m.chest_circumference_mm - 322.5).abs() < 0.1, "{m:?}");
        let bad = TrunkDiameters {
            bitrochanteric_mm: 0.0,
            ..Default::default()
        };
        assert!(Trunk::new(&bad).unwrap_err().to_string().contains("bitrochanteric_mm"));
        let no_neck = TrunkDiameters {
            cervical_spine_mm: -1.0,
            ..Default::default()
        };
        assert!(Trunk::new(&no_neck).unwrap_err().to_string().contains("cervical_spine_mm"));
    }
}
