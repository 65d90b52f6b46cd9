//! The named landmarks of a maternal pelvis (CONVENTIONS.md, "Landmarks").

use glam::{DAffine3, DMat3, DVec3};
use serde::{Deserialize, Serialize};

use super::PelvisError;

/// The pelvis landmarks, metres, in the pelvis frame (or, before
/// [`PelvisLandmarks::to_pelvis_frame`], in a mesh's own frame).
///
/// Beyond the landmarks CONVENTIONS.md names, the obstetric diameters need:
/// the sacroiliac joints and iliopubic (iliopectineal) eminences (ends of the
/// inlet obliques), the S2-S3 and S4-S5 junctions on the sacrum's anterior
/// surface (back ends of the greatest-dimensions and mid-pelvis
/// antero-posterior diameters), the sacral apex (sacrococcygeal joint, the end
/// of the sacral length), the lateral borders of the sacrum where the
/// sacrotuberous ligaments attach, and the junctions of the ischial and pubic
/// rami (ends of the outlet obliques). Every landmark lies on the bone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PelvisLandmarks {
    /// Sacral promontory, back end of the obstetric conjugate.
    pub sacral_promontory: DVec3,
    /// Upper border of the symphysis, inner surface: front end of the obstetric conjugate.
    pub symphysis_upper: DVec3,
    /// Lower border of the symphysis, inner surface: apex of the subpubic arch.
    pub symphysis_lower: DVec3,
    /// Iliopectineal line at the widest inlet transverse, mother's left.
    pub iliopectineal_left: DVec3,
    /// Iliopectineal line at the widest inlet transverse, mother's right.
    pub iliopectineal_right: DVec3,
    /// Sacroiliac joint at the pelvic brim, left (back end of the left oblique).
    pub sacroiliac_left: DVec3,
    /// Sacroiliac joint at the pelvic brim, right (back end of the right oblique).
    pub sacroiliac_right: DVec3,
    /// Iliopubic eminence, left (front end of the right oblique).
    pub iliopubic_eminence_left: DVec3,
    /// Iliopubic eminence, right (front end of the left oblique).
    pub iliopubic_eminence_right: DVec3,
    /// Junction of the second and third sacral vertebrae, anterior surface.
    pub sacrum_s2_s3: DVec3,
    /// Junction of the fourth and fifth sacral vertebrae, anterior surface.
    pub sacrum_s4_s5: DVec3,
    /// Sacral apex (sacrococcygeal joint), anterior surface.
    pub sacral_apex: DVec3,
    /// Tip of the coccyx.
    pub coccyx_tip: DVec3,
    pub ischial_spine_left: DVec3,
    pub ischial_spine_right: DVec3,
    /// Ischial tuberosity, inner (medial) surface, left.
    pub ischial_tuberosity_left: DVec3,
    /// Ischial tuberosity, inner (medial) surface, right.
    pub ischial_tuberosity_right: DVec3,
    /// Sacral end of the sacrotuberous ligament on the lateral border of the
    /// sacrum (its dorsal edge on a generated pelvis), left.
    pub sacral_border_left: DVec3,
    /// Sacral end of the sacrotuberous ligament on the lateral border of the
    /// sacrum (its dorsal edge on a generated pelvis), right.
    pub sacral_border_right: DVec3,
    /// Junction of the ischial and pubic rami (inner edge of the pubic arch), left.
    pub ischiopubic_left: DVec3,
    /// Junction of the ischial and pubic rami (inner edge of the pubic arch), right.
    pub ischiopubic_right: DVec3,
}

/// The landmark names, in the order [`PelvisLandmarks::named`] lists them.
pub const LANDMARK_NAMES: [&str; 21] = [
    "sacral_promontory",
    "symphysis_upper",
    "symphysis_lower",
    "iliopectineal_left",
    "iliopectineal_right",
    "sacroiliac_left",
    "sacroiliac_right",
    "iliopubic_eminence_left",
    "iliopubic_eminence_right",
    "sacrum_s2_s3",
    "sacrum_s4_s5",
    "sacral_apex",
    "coccyx_tip",
    "ischial_spine_left",
    "ischial_spine_right",
    "ischial_tuberosity_left",
    "ischial_tuberosity_right",
    "sacral_border_left",
    "sacral_border_right",
    "ischiopubic_left",
    "ischiopubic_right",
];

impl PelvisLandmarks {
    /// Every landmark with its canonical name.
    pub fn named(&self) -> [(&'static str, DVec3); 21] {
        let p = [
            self.sacral_promontory,
            self.symphysis_upper,
            self.symphysis_lower,
            self.iliopectineal_left,
            self.iliopectineal_right,
            self.sacroiliac_left,
            self.sacroiliac_right,
            self.iliopubic_eminence_left,
            self.iliopubic_eminence_right,
            self.sacrum_s2_s3,
            self.sacrum_s4_s5,
            self.sacral_apex,
            self.coccyx_tip,
            self.ischial_spine_left,
            self.ischial_spine_right,
            self.ischial_tuberosity_left,
            self.ischial_tuberosity_right,
            self.sacral_border_left,
            self.sacral_border_right,
            self.ischiopubic_left,
            self.ischiopubic_right,
        ];
        std::array::from_fn(|k| (LANDMARK_NAMES[k], p[k]))
    }

    /// Applies `f` to every landmark.
    pub fn map(&self, f: impl Fn(DVec3) -> DVec3) -> Self {
        PelvisLandmarks {
            sacral_promontory: f(self.sacral_promontory),
            symphysis_upper: f(self.symphysis_upper),
            symphysis_lower: f(self.symphysis_lower),
            iliopectineal_left: f(self.iliopectineal_left),
            iliopectineal_right: f(self.iliopectineal_right),
            sacroiliac_left: f(self.sacroiliac_left),
            sacroiliac_right: f(self.sacroiliac_right),
            iliopubic_eminence_left: f(self.iliopubic_eminence_left),
            iliopubic_eminence_right: f(self.iliopubic_eminence_right),
            sacrum_s2_s3: f(self.sacrum_s2_s3),
            sacrum_s4_s5: f(self.sacrum_s4_s5),
            sacral_apex: f(self.sacral_apex),
            coccyx_tip: f(self.coccyx_tip),
            ischial_spine_left: f(self.ischial_spine_left),
            ischial_spine_right: f(self.ischial_spine_right),
            ischial_tuberosity_left: f(self.ischial_tuberosity_left),
            ischial_tuberosity_right: f(self.ischial_tuberosity_right),
            sacral_border_left: f(self.sacral_border_left),
            sacral_border_right: f(self.sacral_border_right),
            ischiopubic_left: f(self.ischiopubic_left),
            ischiopubic_right: f(self.ischiopubic_right),
        }
    }

    /// Middle of the inner surface of the symphysis.
    pub fn symphysis_middle(&self) -> DVec3 {
        0.5 * (self.symphysis_upper + self.symphysis_lower)
    }

    /// Midpoint of the left sacrotuberous ligament (sacral border to
    /// tuberosity): back end of the left outlet oblique.
    pub fn sacrotuberous_left(&self) -> DVec3 {
        0.5 * (self.sacral_border_left + self.ischial_tuberosity_left)
    }

    /// Midpoint of the right sacrotuberous ligament: back end of the right outlet oblique.
    pub fn sacrotuberous_right(&self) -> DVec3 {
        0.5 * (self.sacral_border_right + self.ischial_tuberosity_right)
    }

    pub(super) fn check_finite(&self) -> Result<(), PelvisError> {
        match self.named().into_iter().find(|(_, p)| !p.is_finite()) {
            Some((name, _)) => Err(PelvisError::NonFiniteLandmark { name }),
            None => Ok(()),
        }
    }

    /// The rigid map from the frame these landmarks are given in to the
    /// pelvis frame (CONVENTIONS.md): origin at the midpoint of the obstetric
    /// conjugate, y along it towards the symphysis, x towards the mother's
    /// right (the inlet transverse made orthogonal to y), z = x cross y.
    /// Importers apply it to the mesh and to the landmarks.
    pub fn to_pelvis_frame(&self) -> Result<DAffine3, PelvisError> {
        self.check_finite()?;
        let origin = 0.5 * (self.sacral_promontory + self.symphysis_upper);
        let y = self.symphysis_upper - self.sacral_promontory;
        let transverse = self.iliopectineal_right - self.iliopectineal_left;
        let x = transverse - transverse.dot(y) / y.length_squared().max(f64::MIN_POSITIVE) * y;
        if y.length() < 1e-9 || x.length() < 1e-6 * transverse.length().max(1e-9) || transverse.length() < 1e-9 {
            return Err(PelvisError::DegeneratePlane {
                plane: "inlet",
                posterior: "sacral_promontory",
                anterior: "symphysis_upper",
            });
        }
        let (x, y) = (x.normalize(), y.normalize());
        let z = x.cross(y);
        // Rows of the rotation are the pelvis axes expressed in the mesh frame.
        let rotation = DMat3::from_cols(x, y, z).transpose();
        Ok(DAffine3::from_mat3_translation(rotation, -(rotation * origin)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PelvisLandmarks {
        PelvisLandmarks {
            sacral_promontory: DVec3::new(0.0, -0.055, 0.0),
            symphysis_upper: DVec3::new(0.0, 0.055, 0.0),
            iliopectineal_left: DVec3::new(-0.065, -0.005, 0.0),
            iliopectineal_right: DVec3::new(0.065, -0.005, 0.0),
            ..PelvisLandmarks::zeroed()
        }
    }

    impl PelvisLandmarks {
        fn zeroed() -> Self {
            PelvisLandmarks {
                sacral_promontory: DVec3::ZERO,
                symphysis_upper: DVec3::ZERO,
                symphysis_lower: DVec3::ZERO,
                iliopectineal_left: DVec3::ZERO,
                iliopectineal_right: DVec3::ZERO,
                sacroiliac_left: DVec3::ZERO,
                sacroiliac_right: DVec3::ZERO,
                iliopubic_eminence_left: DVec3::ZERO,
                iliopubic_eminence_right: DVec3::ZERO,
                sacrum_s2_s3: DVec3::ZERO,
                sacrum_s4_s5: DVec3::ZERO,
                sacral_apex: DVec3::ZERO,
                coccyx_tip: DVec3::ZERO,
                ischial_spine_left: DVec3::ZERO,
                ischial_spine_right: DVec3::ZERO,
                ischial_tuberosity_left: DVec3::ZERO,
                ischial_tuberosity_right: DVec3::ZERO,
                sacral_border_left: DVec3::ZERO,
                sacral_border_right: DVec3::ZERO,
                ischiopubic_left: DVec3::ZERO,
                ischiopubic_right: DVec3::ZERO,
            }
        }
    }

    #[test]
    fn names_follow_the_fields() {
        let mut l = sample();
        l.coccyx_tip = DVec3::new(1.0, 2.0, 3.0);
        let named = l.named();
        let (name, p) = named.iter().find(|(_, p)| *p == DVec3::new(1.0, 2.0, 3.0)).unwrap();
        assert_eq!(*name, "coccyx_tip");
        assert_eq!(*p, l.coccyx_tip);
    }

    #[test]
    fn the_frame_map_sends_a_moved_pelvis_home() {
        let home = sample();
        let motion = DAffine3::from_rotation_translation(
            glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            DVec3::new(0.4, -0.2, 1.3),
        );
        let moved = home.map(|p| motion.transform_point3(p));
        let back = moved.to_pelvis_frame().unwrap();
        for ((_, a), (_, b)) in home.named().iter().zip(moved.map(|p| back.transform_point3(p)).named()) {
            assert!((*a - b).length() < 1e-12);
        }
    }

    #[test]
    fn non_finite_landmarks_are_named() {
        let mut l = sample();
        l.ischial_spine_left.y = f64::NAN;
        assert_eq!(l.to_pelvis_frame(), Err(PelvisError::NonFiniteLandmark { name: "ischial_spine_left" }));
    }
}
