//! The run record: everything a report needs, serialisable to run.json.

use carus_analysis::{DetectorReport, Outcome, PoseHistory, RigidPose};
use serde::{Deserialize, Serialize};

use crate::loads::LoadSample;
use crate::scenario::Scenario;
use crate::sim::{FloorSample, StageTimes};

/// The headline figures of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    pub scenario: String,
    pub outcome: Outcome,
    /// Simulated time reached, s.
    pub simulated_s: f64,
    /// Wall-clock time of the run, s; a resumed run's counts every leg.
    pub wall_s: f64,
    /// Of it, each stage of the rigid steps (`carus bench labour`); a
    /// resumed run's, of its last leg only.
    #[serde(default)]
    pub stage_wall_s: StageTimes,
    /// Of it, writing frames and checkpoints, keeping the floor's
    /// snapshots, detecting the movements and writing the pose history, up
    /// to the summary (run.json and the report come after); a resumed
    /// run's, of its last leg only.
    #[serde(default)]
    pub output_wall_s: f64,
    /// Whether the run reached its end (false: stopped, resumable, or failed).
    pub completed: bool,
    /// Why the run ended early, when the physics failed (for example a floor
    /// element crushed inside out), and why it has no detector report if
    /// the detector refused its history; everything simulated is written.
    pub failure: Option<String>,
    pub rigid_steps: u64,
    pub rigid_dt_s: f64,
    pub floor_substeps_per_step: u32,
    /// Rigid steps whose floor took finer sub-steps, because contact had
    /// pressed an element flat and its stable step had shrunk, and the most
    /// sub-steps one took (docs/SOLVE.md).
    #[serde(default)]
    pub floor_refined_steps: u64,
    #[serde(default)]
    pub floor_most_substeps: u32,
    pub floor_elements: usize,
    pub head_samples: usize,
    pub trunk_samples: usize,
    pub head_mass_kg: f64,
    /// The trunk's mass, or the thorax's when the spine bends.
    pub trunk_mass_kg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_trunk_mass_kg: Option<f64>,
}

/// An instant worth a picture (engagement, full internal rotation,
/// crowning, restitution, and an arrested run's end), with the poses, the
/// nearest ParaView frame and the floor's state nearest it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KeyMoment {
    pub name: String,
    pub time_s: f64,
    pub head: RigidPose,
    pub trunk: Option<RigidPose>,
    /// Index of the nearest VTU frame (floor_NNNN.vtu, head_NNNN.vtu), if written.
    pub frame: Option<usize>,
    /// The pelvic floor's state nearest the moment, for its picture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<FloorAtMoment>,
}

/// The pelvic floor at (or nearest) a key moment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorAtMoment {
    /// When this state is from: within a floor snapshot's interval of the
    /// moment, or for a resumed run's earlier moments its nearest VTU frame.
    pub time_s: f64,
    /// Node displacements from rest, pelvis frame, m.
    pub displacement_m: Vec<[f64; 3]>,
    /// Largest principal stretch of each element.
    pub element_stretch: Vec<f64>,
}

/// Everything a report needs (run.json in the out dir).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    pub scenario: Scenario,
    pub summary: RunSummary,
    pub history: PoseHistory,
    /// None when the run stopped before its second sample.
    pub detector: Option<DetectorReport>,
    /// Peak stretch and stress of the pelvic floor over time.
    pub floor: Vec<FloorSample>,
    /// Contact loads per body and site, and the moments spinning the head
    /// about the pelvic axis, at the pose samples' instants.
    #[serde(default)]
    pub loads: Vec<LoadSample>,
    pub key_moments: Vec<KeyMoment>,
    /// Files of the run, relative to the out dir: surfaces and series.
    pub files: Files,
}

/// Where the run's files are, relative to its out dir.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Files {
    pub scenario: String,
    pub pose_history_json: String,
    pub pose_history_csv: String,
    /// Contact loads per body and site (crate::output::write_contacts_csv).
    #[serde(default)]
    pub contacts_csv: String,
    pub movements: String,
    pub pelvis_vtu: String,
    /// The sacrospinous ligaments, part of the canal's rigid wall.
    #[serde(default)]
    pub ligaments_vtu: String,
    /// The soft walls that close the pelvis's openings, part of the canal's
    /// rigid wall too (`contact.abdominal_wall`, `contact.obturator_membranes`;
    /// none for an imported pelvis).
    #[serde(default)]
    pub soft_walls_vtu: Option<String>,
    /// Head and trunk surfaces in their body frames (place with the poses).
    pub head_body_vtu: String,
    pub trunk_body_vtu: Option<String>,
    pub head_pvd: Option<String>,
    pub trunk_pvd: Option<String>,
    /// The lower trunk, when the spine bends.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_trunk_body_vtu: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_trunk_pvd: Option<String>,
    pub floor_pvd: Option<String>,
    pub checkpoint: String,
}

/// The key moments the report pictures (`carus_analysis::moments`, the
/// one rule), each with its sample of `history` (the one `report` was
/// detected in: a sample per series entry) and the VTU frame nearest it.
pub fn key_moments(
    history: &PoseHistory,
    report: &DetectorReport,
    frame_times: &[f64],
) -> Vec<KeyMoment> {
    let (moments, _) = carus_analysis::moments::key_moments(report);
    moments
        .iter()
        .filter_map(|moment| {
            let (name, t) = (moment.kind.name(), moment.time_s);
            let sample = history.samples.get(moment.sample)?;
            let frame = (0..frame_times.len()).min_by(|&a, &b| {
                (frame_times[a] - t)
                    .abs()
                    .total_cmp(&(frame_times[b] - t).abs())
            });
            Some(KeyMoment {
                name: name.to_string(),
                time_s: sample.time_s,
                head: sample.head,
                trunk: sample.trunk,
                frame,
                floor: None,
            })
        })
        .collect()
}
