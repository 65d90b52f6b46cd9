//! Forward simulation of labour (issue 4, docs/LABOUR.md), and for
//! teaching the same run with the head imposed or guided along way-points
//! (docs/TRAJECTORIES.md): a scenario in, a pose history, the
//! cardinal-movement detector's report, ParaView series and a run record out.
//!
//! - [`scenario`]: the TOML schema and the built-in scenarios;
//! - [`scene`]: the constant scene built from a scenario (anatomy, bodies, floor, start);
//! - [`expulsion`]: the expulsion force generator;
//! - [`sim`]: the mutable state and the step pipeline;
//! - [`trajectory`]: the imposed and hybrid modes' way-points (teaching);
//! - [`loads`]: the contact loads per site and the moments they cause;
//! - [`record`]: the run record (everything a report needs);
//! - [`output`]: the files of a run (the only module that writes);
//! - [`run`](mod@run): the driver: progress, stop flag, checkpoints, resume.

pub mod expulsion;
pub mod loads;
pub mod output;
pub mod record;
pub mod run;
pub mod scenario;
pub mod scene;
pub mod sim;
pub mod trajectory;

pub use record::{KeyMoment, RunRecord, RunSummary};
pub use run::{floor_frames, floor_frames_at, resume, run, run_from_start, Observer, RunOptions, SilentObserver};
pub use scenario::{FloorCoupling, Scenario, ScenarioError, BUILTINS};
pub use scene::Scene;
pub use sim::{SimState, Simulation, StageTimes};
pub use trajectory::{Mode, Trajectory, TrajectorySection, Waypoint};

/// Why a run cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum LabourError {
    /// Boxed: a scenario error carries its file, key and hint, and would
    /// make every `Result` of the run as large.
    #[error(transparent)]
    Scenario(Box<ScenarioError>),
    /// The anatomy cannot be built; `at` is `file:line: ` of the scenario
    /// key to change, where one is known (`Scenario::located_key`), or empty.
    #[error("{at}anatomy: {message}")]
    Anatomy { at: String, message: String },
    #[error("contact: {0}")]
    Contact(#[from] carus_contact::ContactError),
    #[error("pelvic floor solver: {0}")]
    Floor(#[from] carus_fem::FemError),
    /// An element of the floor turned inside out: where, and how far it was
    /// stretched just before.
    #[error("the pelvic floor failed at t = {time_s:.2} s: element {element} ({location}) turned inside out; {what}")]
    FloorFailed {
        time_s: f64,
        element: usize,
        location: String,
        what: String,
    },
    #[error("pose history: {0}")]
    History(#[from] carus_analysis::HistoryError),
    /// A table given as a pose history could not be read.
    #[error(transparent)]
    Table(#[from] carus_io::ReadError),
    #[error("{path}: {message}")]
    Output {
        path: std::path::PathBuf,
        message: String,
    },
    #[error("checkpoint: {0}")]
    Checkpoint(String),
    #[error("the run reached its end at t = {end_s:.2} s and everything it computed is written; there is nothing to resume (to run it again: carus run {} --out NEW_FOLDER)", scenario.display())]
    AlreadyEnded { end_s: f64, scenario: std::path::PathBuf },
    #[error("the run failed at t = {failed_s:.2} s ({failure}); its checkpoint holds the state it failed in, so resuming would fail alike: change what the failure names in {} and run it with a new --out", scenario.display())]
    AlreadyFailed { failed_s: f64, failure: String, scenario: std::path::PathBuf },
    #[error("{0}")]
    LeftCanal(String),
    /// A fetal body pressed through the bone contact's reach: the penalty
    /// could not hold the load, and what followed would be the body passing
    /// through bone.
    #[error(
        "the fetal {body} was pushed into the bony canal at t = {time_s:.3} s: a contact point \
         on the {site} went {depth_mm:.1} mm deep, past the contact's reach, where the bone no \
         longer pushes it out and the {body} would pass through bone; the run stops here \
         (everything simulated so far is written). The bone's whole push on the {body} then: \
         {force_n:.0} N\n  hint: a stiffer contact.penalty_stiffness_pa_per_m (for the trunk, \
         also a thinner contact.trunk_cover_depth_mm) keeps it out; shorten numerics.rigid_dt_s \
         if the run then refuses the stiffness"
    )]
    PushedThrough {
        time_s: f64,
        body: &'static str,
        site: &'static str,
        depth_mm: f64,
        force_n: f64,
    },
    /// The imposed trajectory drives the head through the bony canal.
    #[error(
        "the imposed trajectory drives the fetal head into the bony canal at t = {time_s:.3} s: a \
         contact point on the {site} went {depth_mm:.1} mm deep, past the contact's reach; the run \
         stops here (everything so far is written)\n  hint: at that time the canal is narrower than \
         the head in the attitude and position the way-points ask: change the way-points around \
         it (more flexion in [[trajectory.waypoints]] phi_deg, a theta along the canal's widest \
         diameter, or a later time for that station)"
    )]
    TrajectoryThroughBone { time_s: f64, site: &'static str, depth_mm: f64 },
    /// A fetal body's motion no longer finite, or thrown a metre or more:
    /// caught before the next contact query, which cannot search a
    /// bounding-volume tree for a NaN.
    #[error(
        "the fetal {body}'s motion blew up at t = {time_s:.3} s (its state no longer finite, or \
         thrown a metre from the canal): the rigid step cannot integrate the scenario's forces\n  hint: a stiffness, damping or drag far from its default makes the \
         explicit step unstable; compare the scenario with `carus scenarios show normal` and bring \
         such a value back towards it, or shorten numerics.rigid_dt_s"
    )]
    Diverged { time_s: f64, body: &'static str },
    /// A joint stiffer than the rigid step can integrate: the run would
    /// blow up within its first steps.
    #[error("{at}`{section}.{key}` = {stiffness}: the joint is unstable at the rigid step numerics.rigid_dt_s = {dt_s} s; the step must be below {limit_s:.3e} s for it\n  hint: {}", unstable_joint_fix(section, key, *limit_s))]
    UnstableJoint {
        /// `file:line: ` of the key in the scenario read, or empty
        /// (`Scenario::located_key`).
        at: String,
        section: &'static str,
        key: &'static str,
        /// As the scenario's messages show numbers (`scenario::shown`).
        stiffness: String,
        dt_s: f64,
        limit_s: f64,
    },
}

impl LabourError {
    /// An anatomy that cannot be built, not tied to one key.
    pub(crate) fn anatomy(message: impl Into<String>) -> Self {
        LabourError::Anatomy { at: String::new(), message: message.into() }
    }
}

impl From<ScenarioError> for LabourError {
    fn from(e: ScenarioError) -> Self {
        LabourError::Scenario(Box::new(e))
    }
}

/// How to steady an unstable joint: a shorter rigid step where one that
/// can still finish a run would do, else the value that the step cannot
/// integrate brought back down.
fn unstable_joint_fix(section: &str, key: &str, limit_s: f64) -> String {
    let lower = format!("lower {section}.{key} back towards its default (`carus scenarios show normal` lists it)");
    match limit_s >= scenario::SMALLEST_RIGID_DT_S {
        true => format!("set numerics.rigid_dt_s below {limit_s:.3e}, or {lower}"),
        false => format!("{lower}; the step it needs is below the smallest that can finish a run ({} s)", scenario::SMALLEST_RIGID_DT_S),
    }
}
