//! The fetal head: a closed surface built from the six clinical diameters,
//! with its landmarks, in the head's body frame.
//!
//! Head frame (metres): origin at the head centre, the midpoint of the
//! occipitofrontal diameter; x = o (occiput towards forehead), y = b (towards
//! the fetal left), z = v (foramen magnum towards the vertex). The frame is
//! right-handed with b = v x o as CONVENTIONS.md defines it.
//!
//! Shape: the midline is the convex profile of the `profile` module; away from
//! it the head is the body g(o, v)^2 + (b / (BPD/2))^2 <= 1, where g is the
//! gauge of the profile about the head centre (0 at the centre, 1 on the
//! profile). It is convex, its midline section is the profile, its widest
//! transverse section is at the centre (the parietal eminences, exactly the
//! biparietal apart, in the plane of the occipitofrontal diameter as in the
//! transthalamic ultrasound plane), and it narrows towards the face, where
//! the temporal points lie on the level g = sqrt(1 - (BT/BPD)^2). The surface
//! is triangulated on a geodesic sphere whose vertices are moved onto the
//! landmark directions, so every surface landmark is a vertex, and as the
//! triangles are inscribed in a convex body, the mesh's extent along each
//! diameter is met exactly at its landmarks.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::diameters::{HeadDiameters, HeadError};
use super::profile::SagittalProfile;
use super::sphere::{geodesic_sphere, pin_directions};
use crate::surface::TriSurface;

/// Default sphere subdivisions: 2562 vertices, edges of about 4 mm on a term head.
pub const DEFAULT_HEAD_SUBDIVISIONS: u32 = 4;

/// Polar angle of the temporal points below the occipitofrontal line, seen
/// from the head centre in the midline: the temples lie in front of and a
/// little below the parietal eminences (engineering choice).
const TEMPORAL_ANGLE_DEG: f64 = -12.0;
/// Where the atlanto-occipital pivot lies in the head: under the skull
/// base at the foramen magnum, on the midline ray from the head centre that
/// points `behind_vertical_deg` behind straight down (towards the occiput),
/// drawn `depth` of the way in from the surface. Being behind the centre,
/// the pivot is nearer the occiput than the forehead: the head lever of
/// CARDINAL_MOVEMENTS.md. The defaults, 15 deg and 0.15, are an engineering
/// choice: no measurement of where a term fetus's foramen magnum lies
/// relative to its head centre was found (docs/LABOUR.md, thirty-fifth
/// session, gives how the outcome turns on them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtlantoOccipitalPlacement {
    /// Angle behind straight down, degrees, seen from the head centre in the midline.
    pub behind_vertical_deg: f64,
    /// Fraction of the centre-to-surface distance the pivot lies inside the skull.
    pub depth: f64,
}

impl Default for AtlantoOccipitalPlacement {
    fn default() -> Self {
        AtlantoOccipitalPlacement {
            behind_vertical_deg: 15.0,
            depth: 0.15,
        }
    }
}

impl AtlantoOccipitalPlacement {
    /// Angles behind straight down that keep the pivot in the skull base:
    /// from under the centre to halfway to the occiput.
    pub const BEHIND_VERTICAL_DEG: (f64, f64) = (0.0, 45.0);
    /// Depths that keep the pivot inside the head and below its centre.
    pub const DEPTH: (f64, f64) = (0.05, 0.5);

    /// Checks both against their ranges.
    pub fn validate(&self) -> Result<(), HeadError> {
        let checks = [
            ("behind_vertical_deg", self.behind_vertical_deg, Self::BEHIND_VERTICAL_DEG),
            ("depth", self.depth, Self::DEPTH),
        ];
        for (name, value, (least, most)) in checks {
            if !(least..=most).contains(&value) {
                return Err(HeadError::Pivot {
                    name,
                    value,
                    least,
                    most,
                });
            }
        }
        Ok(())
    }

    /// The pivot in the head frame, given the midline profile.
    fn locate(&self, profile: &SagittalProfile) -> DVec3 {
        let angle = -(90.0 + self.behind_vertical_deg).to_radians();
        let base = profile.radius(angle) * DVec2::new(angle.cos(), angle.sin());
        midline((1.0 - self.depth) * base)
    }
}

/// The landmarks of CONVENTIONS.md, metres, in the head frame. All lie on
/// the surface (as mesh vertices) except the atlanto-occipital pivot, which
/// lies inside, above the skull base.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeadLandmarks {
    /// Upper end of the mentovertical diameter, the point of the vault farthest from the chin.
    pub vertex: DVec3,
    /// Back end of the occipitofrontal diameter.
    pub occiput: DVec3,
    /// Front end of the occipitofrontal diameter (frontal point).
    pub glabella: DVec3,
    pub nasion: DVec3,
    /// Point of the chin, lower end of the mentovertical diameter.
    pub menton: DVec3,
    /// Junction of neck and jaw, lower end of the submentobregmatic diameter.
    pub submental: DVec3,
    /// Centre of the anterior fontanelle.
    pub bregma: DVec3,
    /// Posterior fontanelle.
    pub lambda: DVec3,
    pub parietal_eminence_left: DVec3,
    pub parietal_eminence_right: DVec3,
    pub temporal_left: DVec3,
    pub temporal_right: DVec3,
    /// Below the occipital protuberance, lower end of the suboccipitobregmatic diameter.
    pub suboccipital: DVec3,
    /// Where the spine pushes the head; inside, above the skull base.
    pub atlanto_occipital: DVec3,
}

/// Landmark names, in the order of [`HeadLandmarks::named`].
pub const HEAD_LANDMARK_NAMES: [&str; 14] = [
    "vertex",
    "occiput",
    "glabella",
    "nasion",
    "menton",
    "submental",
    "bregma",
    "lambda",
    "parietal_eminence_left",
    "parietal_eminence_right",
    "temporal_left",
    "temporal_right",
    "suboccipital",
    "atlanto_occipital",
];

impl HeadLandmarks {
    /// Every landmark moved by `f`, for example into another frame.
    pub fn map(&self, f: impl Fn(DVec3) -> DVec3) -> HeadLandmarks {
        HeadLandmarks {
            vertex: f(self.vertex),
            occiput: f(self.occiput),
            glabella: f(self.glabella),
            nasion: f(self.nasion),
            menton: f(self.menton),
            submental: f(self.submental),
            bregma: f(self.bregma),
            lambda: f(self.lambda),
            parietal_eminence_left: f(self.parietal_eminence_left),
            parietal_eminence_right: f(self.parietal_eminence_right),
            temporal_left: f(self.temporal_left),
            temporal_right: f(self.temporal_right),
            suboccipital: f(self.suboccipital),
            atlanto_occipital: f(self.atlanto_occipital),
        }
    }

    pub fn named(&self) -> [(&'static str, DVec3); 14] {
        let p = [
            self.vertex,
            self.occiput,
            self.glabella,
            self.nasion,
            self.menton,
            self.submental,
            self.bregma,
            self.lambda,
            self.parietal_eminence_left,
            self.parietal_eminence_right,
            self.temporal_left,
            self.temporal_right,
            self.suboccipital,
            self.atlanto_occipital,
        ];
        std::array::from_fn(|k| (HEAD_LANDMARK_NAMES[k], p[k]))
    }
}

/// A fetal head: its diameters, closed outward surface and landmarks, in
/// the head frame (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct FetalHead {
    pub diameters: HeadDiameters,
    pub surface: TriSurface,
    pub landmarks: HeadLandmarks,
}

/// A point of the midline profile in the head frame.
fn midline(p: DVec2) -> DVec3 {
    DVec3::new(p.x, 0.0, p.y)
}

/// The head body: the profile swept out to the biparietal half-width.
struct HeadBody {
    profile: SagittalProfile,
    half_biparietal: f64,
}

impl HeadBody {
    /// Distance from the head centre to the surface along unit direction `d`.
    fn radius(&self, d: DVec3) -> f64 {
        let sagittal = DVec2::new(d.x, d.z);
        let s = sagittal.length();
        if s < 1e-15 {
            return self.half_biparietal;
        }
        let rho = self.profile.radius(sagittal.y.atan2(sagittal.x));
        1.0 / ((s / rho).powi(2) + (d.y / self.half_biparietal).powi(2)).sqrt()
    }
}

impl FetalHead {
    /// Builds the head at the default resolution, its pivot where
    /// [`AtlantoOccipitalPlacement::default`] puts it.
    pub fn new(diameters: &HeadDiameters) -> Result<Self, HeadError> {
        Self::with_subdivisions(diameters, &AtlantoOccipitalPlacement::default(), DEFAULT_HEAD_SUBDIVISIONS)
    }

    /// Builds the head on a geodesic sphere subdivided `subdivisions` times
    /// (3 to 6), its atlanto-occipital pivot placed by `pivot`.
    pub fn with_subdivisions(
        diameters: &HeadDiameters,
        pivot: &AtlantoOccipitalPlacement,
        subdivisions: u32,
    ) -> Result<Self, HeadError> {
        diameters.validate()?;
        pivot.validate()?;
        if !(3..=6).contains(&subdivisions) {
            return Err(HeadError::Resolution(subdivisions));
        }
        let profile = SagittalProfile::new(diameters)?;
        let half_biparietal = 0.5e-3 * diameters.biparietal_mm;
        let half_bitemporal = 0.5e-3 * diameters.bitemporal_mm;

        // Temporal points: on the gauge level where the half-width is BT/2.
        let temporal_gauge = (1.0 - (half_bitemporal / half_biparietal).powi(2)).sqrt();
        let angle = TEMPORAL_ANGLE_DEG.to_radians();
        let temporal = temporal_gauge * profile.radius(angle) * DVec2::new(angle.cos(), angle.sin());

        let landmarks = HeadLandmarks {
            vertex: midline(profile.vertex),
            occiput: midline(profile.occiput),
            glabella: midline(profile.glabella),
            nasion: midline(profile.nasion),
            menton: midline(profile.menton),
            submental: midline(profile.submental),
            bregma: midline(profile.bregma),
            lambda: midline(profile.lambda),
            parietal_eminence_left: DVec3::new(0.0, half_biparietal, 0.0),
            parietal_eminence_right: DVec3::new(0.0, -half_biparietal, 0.0),
            temporal_left: DVec3::new(temporal.x, half_bitemporal, temporal.y),
            temporal_right: DVec3::new(temporal.x, -half_bitemporal, temporal.y),
            suboccipital: midline(profile.suboccipital),
            atlanto_occipital: pivot.locate(&profile),
        };
        let body = HeadBody {
            profile,
            half_biparietal,
        };

        let (mut directions, triangles) = geodesic_sphere(subdivisions);
        let on_surface: Vec<DVec3> = landmarks.named()[..13].iter().map(|(_, p)| p.normalize()).collect();
        let pinned = pin_directions(&mut directions, &on_surface).ok_or(HeadError::Resolution(subdivisions))?;
        let mut vertices: Vec<DVec3> = directions.iter().map(|&d| body.radius(d) * d).collect();
        // Landmarks are placed exactly, not through the radial function's rounding.
        for (&vertex, (_, p)) in pinned.iter().zip(landmarks.named()) {
            vertices[vertex as usize] = p;
        }
        Ok(FetalHead {
            diameters: *diameters,
            surface: TriSurface::new(vertices, triangles),
            landmarks,
        })
    }

    /// Measures the head back from its surface and landmarks.
    pub fn measure(&self) -> HeadMeasurement {
        HeadMeasurement::new(&self.surface, &self.landmarks)
    }
}

/// The head's extents measured on its surface, millimetres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadExtents {
    /// Along o (occiput to forehead).
    pub along_o_mm: f64,
    /// Along b (side to side).
    pub along_b_mm: f64,
    /// Along v (skull base or chin to the top).
    pub along_v_mm: f64,
    /// The presenting diameter of each attitude: the largest antero-posterior
    /// extent of the head projected on the plane normal to the direction of
    /// descent, the descent being perpendicular, in the midline, to the
    /// diameter of that attitude. Deflexed (vertex presentation): across the
    /// occipitofrontal line.
    pub presenting_deflexed_mm: f64,
    /// Well flexed: across the suboccipitobregmatic line.
    pub presenting_flexed_mm: f64,
    /// Brow presentation: across the mentovertical line.
    pub presenting_brow_mm: f64,
    /// Fully extended (face presentation): across the submentobregmatic line.
    pub presenting_face_mm: f64,
}

/// A fetal head measured back: the six diameters between their landmarks
/// (canonical names), the surface extents and every landmark, millimetres
/// in the head frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadMeasurement {
    pub biparietal_mm: f64,
    pub bitemporal_mm: f64,
    pub occipitofrontal_mm: f64,
    pub suboccipitobregmatic_mm: f64,
    pub mentovertical_mm: f64,
    pub submentobregmatic_mm: f64,
    pub extents: HeadExtents,
    /// Landmark positions, mm, head frame (x = o, y = b, z = v).
    pub landmarks_mm: std::collections::BTreeMap<String, [f64; 3]>,
}

impl HeadMeasurement {
    /// Measures any head surface (generated or imported) with its landmarks.
    pub fn new(surface: &TriSurface, l: &HeadLandmarks) -> Self {
        let mm = |a: DVec3, b: DVec3| (b - a).length() * 1e3;
        let extent = |u: DVec3| {
            let (lo, hi) = surface
                .vertices
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.dot(u)), hi.max(p.dot(u))));
            (hi - lo) * 1e3
        };
        let presenting = |from: DVec3, to: DVec3| {
            let u = to - from;
            // In the midline plane: drop any sideways component.
            extent(DVec3::new(u.x, 0.0, u.z).normalize_or_zero())
        };
        HeadMeasurement {
            biparietal_mm: mm(l.parietal_eminence_right, l.parietal_eminence_left),
            bitemporal_mm: mm(l.temporal_right, l.temporal_left),
            occipitofrontal_mm: mm(l.occiput, l.glabella),
            suboccipitobregmatic_mm: mm(l.suboccipital, l.bregma),
            mentovertical_mm: mm(l.menton, l.vertex),
            submentobregmatic_mm: mm(l.submental, l.bregma),
            extents: HeadExtents {
                along_o_mm: extent(DVec3::X),
                along_b_mm: extent(DVec3::Y),
                along_v_mm: extent(DVec3::Z),
                presenting_deflexed_mm: presenting(l.occiput, l.glabella),
                presenting_flexed_mm: presenting(l.suboccipital, l.bregma),
                presenting_brow_mm: presenting(l.menton, l.vertex),
                presenting_face_mm: presenting(l.submental, l.bregma),
            },
            landmarks_mm: l
                .named()
                .iter()
                .map(|(name, p)| (name.to_string(), (*p * 1e3).to_array()))
                .collect(),
        }
    }

    /// The diameters measured between landmarks, as a set that can be fed back.
    pub fn diameters(&self) -> HeadDiameters {
        HeadDiameters {
            biparietal_mm: self.biparietal_mm,
            bitemporal_mm: self.bitemporal_mm,
            occipitofrontal_mm: self.occipitofrontal_mm,
            suboccipitobregmatic_mm: self.suboccipitobregmatic_mm,
            mentovertical_mm: self.mentovertical_mm,
            submentobregmatic_mm: self.submentobregmatic_mm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every diameter back within 0.1 mm, from the landmarks and as the
    /// presenting extent of its attitude; closed and outward.
    fn check(d: &HeadDiameters, head: &FetalHead) {
        head.surface.check_closed().unwrap();
        let m = head.measure();
        let e = &m.extents;
        for ((name, want), (_, got)) in d.named().iter().zip(m.diameters().named()) {
            assert!((want - got).abs() < 0.1, "{name}: asked {want}, measured {got}");
        }
        for (what, want, got) in [
            ("extent along o", d.occipitofrontal_mm, e.along_o_mm),
            ("extent along b", d.biparietal_mm, e.along_b_mm),
            ("deflexed", d.occipitofrontal_mm, e.presenting_deflexed_mm),
            ("flexed", d.suboccipitobregmatic_mm, e.presenting_flexed_mm),
            ("brow", d.mentovertical_mm, e.presenting_brow_mm),
            ("face", d.submentobregmatic_mm, e.presenting_face_mm),
        ] {
            assert!((want - got).abs() < 0.1, "{what}: asked {want}, measured {got}");
        }
        // The head lever: the pivot nearer the occiput than the forehead, and inside.
        let l = &head.landmarks;
        assert!(l.atlanto_occipital.distance(l.occiput) < l.atlanto_occipital.distance(l.glabella));
        assert!(l.atlanto_occipital.z < 0.0 && l.atlanto_occipital.x < 0.0);
    }

    #[test]
    fn the_default_head_measures_back_exactly() {
        let d = HeadDiameters::default();
        let head = FetalHead::new(&d).unwrap();
        check(&d, &head);
        // Presenting diameters shrink with flexion, as in the textbooks.
        let e = head.measure().extents;
        assert!(e.presenting_flexed_mm < e.presenting_deflexed_mm && e.presenting_deflexed_mm < e.presenting_brow_mm);
        // Landmarks where anatomy puts them.
        let l = head.landmarks;
        assert!(l.vertex.z > 0.0 && l.bregma.z > 0.0 && l.lambda.z > 0.0);
        assert!(l.bregma.x > l.vertex.x && l.lambda.x < l.bregma.x);
        assert!(l.menton.z < l.glabella.z && l.nasion.z < l.glabella.z && l.menton.x > 0.0);
        assert!(l.temporal_left.x > 0.0 && l.temporal_left.y > 0.0 && l.parietal_eminence_left.y > 0.0);
    }

    #[test]
    fn every_surface_landmark_is_a_vertex() {
        let head = FetalHead::new(&HeadDiameters::default()).unwrap();
        for (name, p) in &head.landmarks.named()[..13] {
            assert!(head.surface.vertices.contains(p), "{name} is not a vertex");
        }
        let inside = head.landmarks.atlanto_occipital;
        assert!(!head.surface.vertices.contains(&inside));
    }

    #[test]
    fn a_pivot_out_of_its_range_is_refused_by_name() {
        for (placement, name) in [
            (AtlantoOccipitalPlacement { behind_vertical_deg: -5.0, depth: 0.15 }, "behind_vertical_deg"),
            (AtlantoOccipitalPlacement { behind_vertical_deg: f64::NAN, depth: 0.15 }, "behind_vertical_deg"),
            (AtlantoOccipitalPlacement { behind_vertical_deg: 15.0, depth: 0.9 }, "depth"),
        ] {
            let err = FetalHead::with_subdivisions(&HeadDiameters::default(), &placement, 3).unwrap_err();
            assert!(matches!(err, HeadError::Pivot { name: n, .. } if n == name), "{err}");
            assert!(err.to_string().contains(name), "{err}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]
        #[test]
        fn the_pivot_lies_on_its_ray_at_its_depth_and_leaves_the_surface_alone(
            behind in 0.0..=45.0f64,
            depth in 0.05..=0.5f64,
        ) {
            let d = HeadDiameters::default();
            let placement = AtlantoOccipitalPlacement { behind_vertical_deg: behind, depth };
            let head = FetalHead::with_subdivisions(&d, &placement, 3).unwrap();
            let shallow = AtlantoOccipitalPlacement { depth: 0.05, ..placement };
            let reference = FetalHead::with_subdivisions(&d, &shallow, 3).unwrap();
            let (p, q) = (head.landmarks.atlanto_occipital, reference.landmarks.atlanto_occipital);
            // In the midline, `behind` degrees behind straight down (-v towards -o).
            prop_assert!(p.y == 0.0 && p.z < 0.0 && p.x <= 1e-15);
            prop_assert!(((-p.x).atan2(-p.z).to_degrees() - behind).abs() < 1e-9);
            // Drawn in from the surface in proportion to `depth`.
            prop_assert!((p.length() / q.length() - (1.0 - depth) / 0.95).abs() < 1e-12);
            // The pivot is not part of the skull's shape.
            prop_assert_eq!(&head.surface, &reference.surface);
        }
    }

    #[test]
    fn the_measurement_serialises_with_canonical_names() {
        let m = FetalHead::new(&HeadDiameters::default()).unwrap().measure();
        let json = serde_json::to_value(&m).unwrap();
        for key in [
            "biparietal_mm",
            "bitemporal_mm",
            "occipitofrontal_mm",
            "suboccipitobregmatic_mm",
            "mentovertical_mm",
            "submentobregmatic_mm",
        ] {
            assert!(json[key].is_f64(), "{key}");
        }
        assert!(json["landmarks_mm"]["atlanto_occipital"].is_array());
    }

    #[test]
    fn bad_resolutions_are_refused() {
        assert_eq!(
            FetalHead::with_subdivisions(&HeadDiameters::default(), &AtlantoOccipitalPlacement::default(), 9),
            Err(HeadError::Resolution(9))
        );
    }

    #[test]
    fn impossible_proportions_are_refused_with_the_region() {
        // A long mentovertical with short bregmatic diameters cannot close.
        let d = HeadDiameters {
            suboccipitobregmatic_mm: 60.0,
            submentobregmatic_mm: 60.0,
            mentovertical_mm: 200.0,
            ..Default::default()
        };
        let err = FetalHead::new(&d).unwrap_err();
        assert!(matches!(err, HeadError::Unshapeable { .. }), "{err}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn random_heads_measure_back_within_a_tenth_of_a_millimetre(
            biparietal in 85.0..105.0f64,
            temporal_ratio in 0.78..0.92f64,
            occipitofrontal in 108.0..128.0f64,
            suboccipitobregmatic in 88.0..102.0f64,
            mentovertical in 130.0..145.0f64,
            submentobregmatic in 88.0..102.0f64,
        ) {
            let d = HeadDiameters {
                biparietal_mm: biparietal,
                bitemporal_mm: temporal_ratio * biparietal,
                occipitofrontal_mm: occipitofrontal,
                suboccipitobregmatic_mm: suboccipitobregmatic,
                mentovertical_mm: mentovertical,
                submentobregmatic_mm: submentobregmatic,
            };
            let head = FetalHead::with_subdivisions(&d, &AtlantoOccipitalPlacement::default(), 3).unwrap();
            check(&d, &head);
        }
    }
}
