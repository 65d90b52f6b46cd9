//! Contact between two moving rigid bodies: the samples of one (the fetal
//! trunk) against the surface of the other (the fetal head), so the chin
//! meets the chest and the shoulders cannot slide into the head.
//!
//! The pass runs in the obstacle body's frame: the sampled body's pose and
//! velocity are taken relative to it, and the single-obstacle pass of
//! crate::obstacle does the rest (friction anchors then lie on the obstacle
//! body's surface, where they belong). The forces come back to the pelvis
//! frame as equal and opposite wrenches on the two bodies.

use glam::DVec3;

use crate::error::ContactError;
use crate::law::ContactLaw;
use crate::obstacle::{obstacle_contacts, BodyContactState, BodyMotion, RigidObstacle};
use crate::rigid::{RigidPose, Wrench};
use crate::sampling::SurfaceSamples;

/// What one pair pass found, in the pelvis frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairReport {
    /// On the sampled body, about its centre of mass.
    pub on_sampled: Wrench,
    /// On the obstacle body, about its centre of mass: the opposite force.
    pub on_obstacle: Wrench,
    /// Samples in contact.
    pub active: usize,
    /// Deepest penetration, m.
    pub deepest_m: f64,
    /// Samples deeper than the search band, the larger of the obstacle's
    /// search depth and twice the law's sink at its design load (no force).
    pub too_deep: usize,
}

/// Motion of `body` seen from the frame of `frame` (both in the pelvis
/// frame): the relative pose, and the velocity of the body's points
/// relative to the frame's material points at the same place.
fn relative_motion(body: &BodyMotion, frame: &BodyMotion) -> BodyMotion {
    let q = frame.pose.orientation.inverse();
    let offset = body.pose.position_m - frame.pose.position_m;
    let drift = body.linear_velocity - frame.linear_velocity - frame.angular_velocity.cross(offset);
    BodyMotion {
        pose: RigidPose::new(q * offset, q * body.pose.orientation),
        linear_velocity: q * drift,
        angular_velocity: q * (body.angular_velocity - frame.angular_velocity),
    }
}

/// Finds the contacts of `samples` (on the body moving as `sampled`) with
/// `obstacle` (the surface of the body moving as `other`, in that body's
/// centre-of-mass frame), applies the law and returns the wrenches on both.
/// `memory` holds the sampled body's friction anchors, in the obstacle
/// body's frame.
pub fn pair_contacts(
    obstacle: &RigidObstacle,
    law: &ContactLaw,
    samples: &SurfaceSamples,
    sampled: &BodyMotion,
    other: &BodyMotion,
    memory: &mut BodyContactState,
) -> Result<PairReport, ContactError> {
    let relative = relative_motion(sampled, other);
    let local = obstacle_contacts(obstacle, law, samples, &relative, DVec3::ZERO, memory)?;
    let to_world = |v: DVec3| other.pose.orientation * v;
    let mut report = PairReport {
        active: local.contacts.len(),
        deepest_m: local.deepest_m,
        too_deep: local.too_deep,
        ..PairReport::default()
    };
    for c in &local.contacts {
        let point = other.pose.point(c.body_point);
        let force = to_world(c.force());
        report.on_sampled += Wrench::at_point(force, point, sampled.pose.position_m);
        report.on_obstacle += Wrench::at_point(-force, point, other.pose.position_m);
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use proptest::prelude::*;

    /// A 1 m square through the obstacle body's centre of mass, outward
    /// normal along its own +z: exact normals, so the tests need no
    /// allowance for facets.
    fn slab() -> RigidObstacle {
        let v = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| DVec3::new(x, y, 0.0));
        RigidObstacle::new("slab", &v, &[[0, 1, 2], [0, 2, 3]], None).unwrap()
    }

    fn still(position: DVec3, orientation: DQuat) -> BodyMotion {
        BodyMotion::at_rest(RigidPose::new(position, orientation))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The relative motion gives every point of the body the velocity
        /// it has relative to the frame body's material point there, in
        /// that body's frame.
        #[test]
        fn relative_point_velocities_are_exact(
            a in prop::array::uniform3(-1.0..1.0f64), b in prop::array::uniform3(-1.0..1.0f64),
            va in prop::array::uniform3(-1.0..1.0f64), vb in prop::array::uniform3(-1.0..1.0f64),
            wa in prop::array::uniform3(-3.0..3.0f64), wb in prop::array::uniform3(-3.0..3.0f64),
            qa in prop::array::uniform3(-3.0..3.0f64), qb in prop::array::uniform3(-3.0..3.0f64),
            p in prop::array::uniform3(-0.2..0.2f64),
        ) {
            let body = BodyMotion {
                pose: RigidPose::new(DVec3::from(a), DQuat::from_scaled_axis(DVec3::from(qa))),
                linear_velocity: DVec3::from(va),
                angular_velocity: DVec3::from(wa),
            };
            let frame = BodyMotion {
                pose: RigidPose::new(DVec3::from(b), DQuat::from_scaled_axis(DVec3::from(qb))),
                linear_velocity: DVec3::from(vb),
                angular_velocity: DVec3::from(wb),
            };
            let world = body.pose.point(DVec3::from(p));
            let expected = (body.linear_velocity + body.angular_velocity.cross(world - body.pose.position_m))
                - (frame.linear_velocity + frame.angular_velocity.cross(world - frame.pose.position_m));
            let r = relative_motion(&body, &frame);
            let local = r.pose.point(DVec3::from(p));
            prop_assert!((frame.pose.point(local) - world).length() < 1e-12);
            let got = r.linear_velocity + r.angular_velocity.cross(local - r.pose.position_m);
            prop_assert!((frame.pose.orientation * got - expected).length() < 1e-12);
        }
    }

    /// A sample pressed 1 mm into a turned, displaced slab gets the law's
    /// normal force along the slab's outward normal; the slab's body gets
    /// the opposite force, and the pair's moments balance about any point.
    #[test]
    fn the_pair_forces_are_equal_opposite_and_balance() {
        let law = ContactLaw { friction_coefficient: 0.0, ..ContactLaw::default() };
        let obstacle = slab();
        let turn = DQuat::from_rotation_z(0.7) * DQuat::from_rotation_x(-0.4);
        let centre = DVec3::new(0.3, -0.1, 0.2);
        let other = still(centre, turn);
        // The sample sits 1 mm under the slab, 3 cm off its centre.
        let outward = turn * DVec3::Z;
        let sample_world = centre + turn * DVec3::new(0.03, -0.02, -0.001);
        let sampled_centre = centre + outward * 0.2;
        let sampled = still(sampled_centre, DQuat::IDENTITY);
        let samples = SurfaceSamples { points: vec![sample_world - sampled_centre], areas: vec![1e-4] };
        let mut memory = BodyContactState::new(&samples);
        let r = pair_contacts(&obstacle, &law, &samples, &sampled, &other, &mut memory).unwrap();
        assert_eq!(r.active, 1);
        let expected = law.penalty_stiffness_pa_per_m * 1e-4 * 1e-3;
        let f = r.on_sampled.force;
        assert!((f - expected * outward).length() < 1e-9 * expected, "{f}");
        assert!((r.on_obstacle.force + f).length() < 1e-12);
        // Moments about the origin: each body's torque plus r_com x force.
        let total = r.on_sampled.torque + sampled_centre.cross(f) + r.on_obstacle.torque + centre.cross(r.on_obstacle.force);
        assert!(total.length() < 1e-12 * expected.max(1.0), "{total}");
        // Apart, nothing.
        let far = still(centre + outward * 0.5, DQuat::IDENTITY);
        let mut memory = BodyContactState::new(&samples);
        let r = pair_contacts(&obstacle, &law, &samples, &far, &other, &mut memory).unwrap();
        assert_eq!(r.active, 0);
        assert_eq!(r.on_sampled, Wrench::default());
    }

    /// Friction acts on the relative sliding only: both bodies moving
    /// together at any velocity, the sample pressed into the obstacle
    /// feels the normal force alone; the sample sliding over it feels
    /// friction against its motion relative to the obstacle.
    #[test]
    fn friction_sees_only_the_relative_sliding() {
        let law = ContactLaw { friction_coefficient: 0.35, ..ContactLaw::default() };
        let obstacle = slab();
        let sample_world = DVec3::new(0.0, 0.0, -0.001);
        let samples = SurfaceSamples { points: vec![sample_world - DVec3::new(0.0, 0.0, 0.2)], areas: vec![1e-4] };
        let common = DVec3::new(0.4, -0.3, 0.1);
        let moving = |v: DVec3, centre: DVec3| BodyMotion {
            pose: RigidPose::new(centre, DQuat::IDENTITY),
            linear_velocity: v,
            angular_velocity: DVec3::ZERO,
        };
        let other = moving(common, DVec3::ZERO);
        // Together: the regularised friction sees no slip.
        let mut memory = BodyContactState::new(&samples);
        let r = pair_contacts(&obstacle, &law, &samples, &moving(common, DVec3::new(0.0, 0.0, 0.2)), &other, &mut memory).unwrap();
        let f = r.on_sampled.force;
        assert!(f.z > 0.0 && f.truncate().length() < 1e-9 * f.z, "{f}");
        // Sliding along +x relative to the slab: friction along -x, at most mu N.
        let mut memory = BodyContactState::new(&samples);
        let slide = common + DVec3::new(0.5, 0.0, 0.0);
        let r = pair_contacts(&obstacle, &law, &samples, &moving(slide, DVec3::new(0.0, 0.0, 0.2)), &other, &mut memory).unwrap();
        let f = r.on_sampled.force;
        // 0.5 m/s through the 1 ms dashpot is past the cap: on the cone, against the slip.
        assert!(f.z > 0.0 && f.x < 0.0, "{f}");
        assert!((-f.x - 0.35 * f.z).abs() < 1e-9 * 0.35 * f.z, "{f}");
        assert!(f.y.abs() < 1e-12 * f.z, "{f}");
    }
}
