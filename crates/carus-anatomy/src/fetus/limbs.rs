//! Fetal limbs as chains of capsules (upper arm and forearm, thigh and leg)
//! with their joint points, in the fetal attitude of flexion, ready for
//! later articulation.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::trunk::Trunk;

/// A chain of capsules: segment k runs from `joints[k]` to `joints[k + 1]`
/// with radius `radii[k]` (metres, trunk frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CapsuleChain {
    /// Proximal joint first (shoulder or hip), then elbow or knee, then wrist or ankle.
    pub joints: Vec<DVec3>,
    pub radii: Vec<f64>,
}

impl CapsuleChain {
    /// The segments as (start, end, radius).
    pub fn segments(&self) -> impl Iterator<Item = (DVec3, DVec3, f64)> + '_ {
        self.joints.windows(2).zip(&self.radii).map(|(w, &r)| (w[0], w[1], r))
    }
}

/// The four limbs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Limbs {
    pub arm_left: CapsuleChain,
    pub arm_right: CapsuleChain,
    pub leg_left: CapsuleChain,
    pub leg_right: CapsuleChain,
}

/// Segment lengths and radii of a term fetus, metres (engineering estimates
/// from term long-bone lengths of about 65 mm humerus, 58 mm ulna, 75 mm
/// femur and 65 mm tibia, lengthened to the joint centres and to include the
/// hand and foot; radii include soft tissue).
const UPPER_ARM: (f64, f64) = (0.070, 0.015);
const FOREARM: (f64, f64) = (0.085, 0.012);
const THIGH: (f64, f64) = (0.080, 0.020);
const LEG: (f64, f64) = (0.095, 0.015);

impl Limbs {
    /// Limbs attached to the trunk in the flexed fetal attitude: arms folded
    /// over the chest, hips and knees flexed with the thighs against the
    /// abdomen. Joint centres sit inside the trunk under the acromions and
    /// trochanters.
    pub fn flexed(trunk: &Trunk) -> Self {
        let l = &trunk.landmarks;
        let arm = |acromion: DVec3| {
            let side = acromion.y.signum();
            let shoulder = acromion - DVec3::new(0.0, side * UPPER_ARM.1, UPPER_ARM.1);
            // Upper arm down and forwards along the chest, forearm across it.
            let elbow = shoulder + UPPER_ARM.0 * DVec3::new(0.45, -side * 0.15, -0.88).normalize();
            let wrist = elbow + FOREARM.0 * DVec3::new(0.35, -side * 0.55, 0.76).normalize();
            CapsuleChain {
                joints: vec![shoulder, elbow, wrist],
                radii: vec![UPPER_ARM.1, FOREARM.1],
            }
        };
        let leg = |trochanter: DVec3| {
            let side = trochanter.y.signum();
            let hip = trochanter - DVec3::new(0.0, side * THIGH.1, 0.0);
            // Thigh forwards and up along the abdomen, leg folded back down.
            let knee = hip + THIGH.0 * DVec3::new(0.8, 0.05 * side, 0.6).normalize();
            let ankle = knee + LEG.0 * DVec3::new(-0.15, -0.1 * side, -0.98).normalize();
            CapsuleChain {
                joints: vec![hip, knee, ankle],
                radii: vec![THIGH.1, LEG.1],
            }
        };
        Limbs {
            arm_left: arm(l.acromion_left),
            arm_right: arm(l.acromion_right),
            leg_left: leg(l.trochanter_left),
            leg_right: leg(l.trochanter_right),
        }
    }

    pub fn named(&self) -> [(&'static str, &CapsuleChain); 4] {
        [
            ("arm_left", &self.arm_left),
            ("arm_right", &self.arm_right),
            ("leg_left", &self.leg_left),
            ("leg_right", &self.leg_right),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fetus::trunk::TrunkDiameters;

    #[test]
    fn limbs_hang_on_their_own_side_with_their_lengths() {
        let trunk = Trunk::new(&TrunkDiameters::default()).unwrap();
        let limbs = Limbs::flexed(&trunk);
        for (name, chain) in limbs.named() {
            let side = if name.ends_with("left") { 1.0 } else { -1.0 };
            assert!(chain.joints[0].y * side > 0.0, "{name}");
            let lengths: Vec<f64> = chain.segments().map(|(a, b, _)| a.distance(b)).collect();
            let expected = if name.starts_with("arm") {
                [UPPER_ARM.0, FOREARM.0]
            } else {
                [THIGH.0, LEG.0]
            };
            for (got, want) in lengths.iter().zip(expected) {
                assert!((got - want).abs() < 1e-12, "{name}");
            }
        }
    }
}
