//! The fetus: a head built from its six clinical diameters, a trunk with
//! its shoulders and hips, and limbs as capsule chains, joined at the
//! atlanto-occipital pivot.
//!
//! Frames: the head frame (origin at the head centre, x = o, y = b, z = v;
//! see [`head`]) and the trunk frame (origin at the pivot, x ventral, y to
//! the fetal left, z cranial; spine axis k = -z; see [`trunk`]). With the
//! neck straight the two frames are parallel, the trunk frame sitting at the
//! pivot: [`Fetus::trunk_to_head`].

mod diameters;
pub mod head;
mod limbs;
mod profile;
mod sphere;
pub mod trunk;

pub use diameters::{HeadDiameters, HeadError};
pub use head::{
    AtlantoOccipitalPlacement, FetalHead, HeadExtents, HeadLandmarks, HeadMeasurement, DEFAULT_HEAD_SUBDIVISIONS, HEAD_LANDMARK_NAMES,
};
pub use limbs::{CapsuleChain, Limbs};
pub use trunk::{Trunk, TrunkDiameters, TrunkError, TrunkLandmarks, TrunkMeasurement, TrunkSegments};

use glam::{DAffine3, DVec3};

/// Why a fetus cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FetusError {
    #[error("fetal head: {0}")]
    Head(#[from] HeadError),
    #[error("fetal trunk: {0}")]
    Trunk(#[from] TrunkError),
}

/// A whole fetus: head, trunk and limbs, joined at the neck pivot.
#[derive(Debug, Clone, PartialEq)]
pub struct Fetus {
    pub head: FetalHead,
    pub trunk: Trunk,
    /// Limbs in the trunk frame.
    pub limbs: Limbs,
    /// The atlanto-occipital pivot in the head frame; the trunk frame's origin.
    pub neck_pivot: DVec3,
}

impl Fetus {
    /// Builds the head (default resolution), trunk and flexed limbs.
    pub fn new(head: &HeadDiameters, trunk: &TrunkDiameters) -> Result<Self, FetusError> {
        let head = FetalHead::new(head)?;
        let trunk = Trunk::new(trunk)?;
        let limbs = Limbs::flexed(&trunk);
        let neck_pivot = head.landmarks.atlanto_occipital;
        Ok(Fetus {
            head,
            trunk,
            limbs,
            neck_pivot,
        })
    }

    /// The average term fetus of REFERENCE_DATA.md.
    pub fn term() -> Result<Self, FetusError> {
        Self::new(&HeadDiameters::default(), &TrunkDiameters::default())
    }

    /// Maps trunk-frame points into the head frame with the neck straight.
    pub fn trunk_to_head(&self) -> DAffine3 {
        DAffine3::from_translation(self.neck_pivot)
    }

    /// The spine axis k (pivot towards the breech) in the head frame, neck straight.
    pub fn spine_axis_in_head(&self) -> DVec3 {
        self.trunk_to_head().transform_vector3(self.trunk.spine_axis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_term_fetus_hangs_together_at_the_pivot() {
        let f = Fetus::term().unwrap();
        let to_head = f.trunk_to_head();
        assert_eq!(
            to_head.transform_point3(f.trunk.landmarks.neck),
            f.head.landmarks.atlanto_occipital
        );
        // The shoulders lie below the head's skull base, the breech further down.
        let shoulders = to_head.transform_point3(f.trunk.landmarks.bisacromial_midpoint);
        assert!(shoulders.z < f.head.landmarks.submental.z);
        assert!(f.spine_axis_in_head().dot(DVec3::Z) < -0.99);
    }

    #[test]
    fn errors_name_the_part() {
        let bad = HeadDiameters {
            biparietal_mm: 0.0,
            ..Default::default()
        };
        let err = Fetus::new(&bad, &TrunkDiameters::default()).unwrap_err().to_string();
        assert!(err.starts_with("fetal head") && err.contains("biparietal_mm"), "{err}");
    }
}
