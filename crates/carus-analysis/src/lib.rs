//! Reads a pose history and reports which cardinal movements of labour
//! happened, when and how large, and how labour ended (CARDINAL_MOVEMENTS.md,
//! docs/DETECTOR.md). The detector never looks at how the motion was made:
//! forward physics, an imposed trajectory and a hybrid are judged alike.
//!
//! - [`history`]: the recorded run (constant geometry + samples), JSON round trip;
//! - [`canal`]: the canal's planes and pelvic axis, and the leading-point search;
//! - [`measures`]: station, theta, phi, engagement depths, shoulders per sample;
//! - [`movements`]: the rules of "When a movement counts as observed";
//! - [`outcome`]: delivered, or arrested where and against what;
//! - [`shoulders`]: the shoulders' lie at the inlet and the head-to-body interval;
//! - [`detector`]: the entry point [`detect`] and [`DetectorReport`];
//! - [`moments`]: the key moments a report pictures, chosen from a detector's report;
//! - [`sanity`]: the clinical sanity cases and whether a report meets each;
//! - [`synthetic`]: pose histories built by hand, for tests and demonstrations.

pub mod canal;
pub mod detector;
pub mod history;
pub mod measures;
pub mod moments;
pub mod movements;
pub mod outcome;
pub mod sanity;
pub mod shoulders;
pub mod synthetic;

pub use canal::{BirthCanal, CanalPlanes};
pub use detector::{detect, DetectorReport};
pub use history::{
    ContactSite, FetalPart, HeadGeometry, HistoryError, PoseHistory, PoseSample, RigidPose, TrunkGeometry,
};
pub use measures::{Series, THETA_ILL_CONDITIONED_TILT_DEG};
pub use movements::{occiput_position, HeadBorn, Movement, Movements, NotHeldAtBirth, RotationOutsideWindow, Unit};
pub use outcome::{Arrest, ArrestStage, Outcome};
pub use shoulders::ShoulderPassage;
