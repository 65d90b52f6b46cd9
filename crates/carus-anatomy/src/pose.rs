//! The pose of a rigid body (fetal head, trunk) in the pelvis frame: one
//! type for the physics that moves the bodies (carus-contact) and the
//! history that records them (carus-analysis).

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// Position and orientation of a rigid body: a point `p` of the body frame
/// lies at `position_m + orientation * p`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RigidPose {
    /// Where the body frame's origin is, m.
    pub position_m: DVec3,
    /// Unit quaternion from the body frame to the pelvis frame (x, y, z, w in JSON).
    pub orientation: DQuat,
}

impl RigidPose {
    /// The body frame on the pelvis frame.
    pub const IDENTITY: RigidPose = RigidPose { position_m: DVec3::ZERO, orientation: DQuat::IDENTITY };

    pub fn new(position_m: DVec3, orientation: DQuat) -> Self {
        RigidPose { position_m, orientation }
    }

    /// A body-frame point in the pelvis frame.
    #[inline]
    pub fn point(&self, body_point: DVec3) -> DVec3 {
        self.position_m + self.orientation * body_point
    }

    /// A body-frame direction in the pelvis frame.
    #[inline]
    pub fn direction(&self, body_direction: DVec3) -> DVec3 {
        self.orientation * body_direction
    }

    /// A pelvis-frame point in the body frame.
    #[inline]
    pub fn inverse_point(&self, point: DVec3) -> DVec3 {
        self.orientation.inverse() * (point - self.position_m)
    }
}

impl Default for RigidPose {
    fn default() -> Self {
        RigidPose::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn inverse_point_undoes_point(
            t in proptest::array::uniform3(-1.0f64..1.0),
            axis in proptest::array::uniform3(-1.0f64..1.0),
            angle in -3.0f64..3.0,
            p in proptest::array::uniform3(-1.0f64..1.0),
        ) {
            let axis = DVec3::from(axis);
            prop_assume!(axis.length() > 1e-3);
            let pose = RigidPose::new(DVec3::from(t), DQuat::from_axis_angle(axis.normalize(), angle));
            let p = DVec3::from(p);
            prop_assert!((pose.inverse_point(pose.point(p)) - p).length() < 1e-12);
            prop_assert!((pose.direction(p) - (pose.point(p) - pose.point(DVec3::ZERO))).length() < 1e-12);
        }
    }
}
