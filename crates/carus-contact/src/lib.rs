//! Contact mechanics of Carus: collision detection between the rigid fetus
//! and the rigid bony pelvis, and between the fetus's own head and trunk,
//! the penalty contact law with Coulomb friction and per-contact moments,
//! the rigid-body dynamics that contact drives, the six-degree-of-freedom
//! fetal neck, and the rigid-soft coupling helpers the labour loop uses
//! with the TLED pelvic floor. Method, parameters and
//! measured validation (C1, C3): docs/CONTACT.md.
//!
//! Frames: everything is in the pelvis frame (CONVENTIONS.md) unless a name
//! says "in body frame"; body frames have their origin at the centre of mass.
//! Units SI.

mod clearance;
mod collider;
mod coupling;
mod error;
mod law;
mod neck;
mod obstacle;
mod overlap;
mod pair;
mod rigid;
mod sampling;
mod tri_tri;

pub use clearance::DEFAULT_SKIN_M;
pub use collider::{SurfacePoint, TriangleCollider};
pub use coupling::{HeldNode, TissueContact, TissueReaction};
pub use error::ContactError;
pub use law::{
    default_penalty_stiffness, ContactForce, ContactLaw, SoftCover, DESIGN_EXPULSION_FORCE_N, DESIGN_HEAD_RADIUS_M,
    DESIGN_PENETRATION_M,
};
pub use neck::{HeadAxes, Neck, NeckAngles, NeckGeometry, NeckLoad, NeckRest, NeckStiffness, StableStep};
pub use overlap::{overlapping_triangles, self_intersections};
pub use pair::{pair_contacts, PairReport};
pub use obstacle::{
    obstacle_contacts, obstacle_contacts_by_region, BodyContactState, BodyMotion, Contact, ContactReport, RigidObstacle, RegionTable,
    DEFAULT_SEARCH_DEPTH_M,
};
pub use rigid::{MassProperties, RigidBodyModel, RigidBodyState, RigidPose, Wrench};
pub use sampling::SurfaceSamples;
pub use tri_tri::triangles_intersect;
