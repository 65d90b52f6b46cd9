//! What a report is made from: plain data that any run (forward physics,
//! imposed trajectory, synthetic history) can supply. The labour crate
//! fills it in; this crate never depends on the simulation.

use carus_analysis::{DetectorReport, PoseHistory};
use carus_anatomy::TriSurface;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Everything one report shows.
#[derive(Debug, Clone)]
pub struct ReportInput<'a> {
    /// Page title (the scenario's name, for example "normal").
    pub title: String,
    /// A notice shown in a box under the title, for what a reader must
    /// know first (for example that the motion was imposed, not simulated).
    pub notice: Option<String>,
    /// The scenario file as run, shown verbatim in a collapsible block.
    pub scenario_toml: Option<String>,
    /// Figures of the run itself.
    pub run: RunFigures,
    /// The recorded poses, in the pelvis frame.
    pub history: &'a PoseHistory,
    /// The detector's verdict on `history` (carus_analysis::detect).
    pub detector: &'a DetectorReport,
    /// Peak principal stretch of the pelvic floor over time, `(time_s, stretch)`;
    /// empty when the run had no floor.
    pub floor_peak_stretch: Vec<(f64, f64)>,
    /// When a floor element first had a corner turned inside out: the
    /// floor's stretches from then on are not to be trusted (docs/LABOUR.md);
    /// `None` when none ever did.
    pub floor_untrusted_from_s: Option<f64>,
    /// What spun the head about the pelvic axis over time; empty when the
    /// history does not know (an imposed trajectory has no forces).
    pub head_axial_moments: Vec<AxialMomentSample>,
    /// What pushed the head down the canal (and what held it back) over
    /// time; empty when not known (no forces recorded, or a run recorded
    /// before the neck's force was).
    pub head_canal_forces: Vec<CanalForceSample>,
    /// At each sample of `history`, the sum of the sizes of the contact
    /// forces on the fetus, N: the bone's and ligaments' point by point,
    /// and the pelvic floor's push: how hard it is pressed, where the
    /// vector total lets pushes from opposite sides cancel. Empty when not
    /// known.
    pub contact_load_n: Vec<f64>,
    /// The meshes for the pictures of the key moments; `None`: no pictures.
    pub scene: Option<ReportScene>,
}

/// Forces on the head along the pelvic axis at one instant, N: the
/// component of each source's force along the axis's tangent at the head,
/// pointing down the canal. Positive pushes the head deeper.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CanalForceSample {
    pub time_s: f64,
    /// The push that reaches the head at the atlanto-occipital pivot: the
    /// neck's force (the trunk's push passed on), and the expulsion itself
    /// where it acts at the pivot (no trunk, or `acts_on = "pivot"`).
    pub push_n: f64,
    /// The trunk pressing on the head (chin on chest).
    pub trunk_n: f64,
    /// The bony pelvis and its ligaments, friction included.
    pub bone_n: f64,
    pub floor_n: f64,
    /// The guide of an imposed or hybrid run (zero in forward mode).
    pub guide_n: f64,
}

/// Moments on the head about the pelvic axis at one instant, N m: the
/// component along the axis (pointing down the canal at the head) of each
/// source's moment about the head's centre of mass. Positive turns theta up
/// (from LOT at -90 towards OA at 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AxialMomentSample {
    pub time_s: f64,
    /// Contact with the bony pelvis, friction included.
    pub bone_nm: f64,
    pub floor_nm: f64,
    pub neck_nm: f64,
    /// The part of `neck_nm` from the force the trunk pushes through the
    /// atlanto-occipital pivot (off the head's centre); the rest is the
    /// neck's springs.
    #[serde(default)]
    pub neck_push_nm: f64,
    /// The fetus's own trunk pressing on the head below its thoracic inlet (chin on
    /// chest, shoulders on the skull).
    #[serde(default)]
    pub trunk_nm: f64,
    /// The imposed and hybrid modes' guide (not the physics); 0 in forward runs.
    #[serde(default)]
    pub guide_nm: f64,
}

/// Figures of the run (not of the labour).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunFigures {
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the run, s; `None` for a history made without a solver.
    pub wall_s: Option<f64>,
    /// Rigid-body steps taken; `None` for a history made without a solver.
    pub steps: Option<u64>,
    /// Further rows for the figures table, `(name, value)` as shown.
    pub extra: Vec<(String, String)>,
}

/// The surfaces drawn in the pictures, each in its own frame: the pose
/// history places the head and the trunk at each moment.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportScene {
    /// Bony pelvis in the pelvis frame, m (drawn semi-transparent).
    pub pelvis: Option<TriSurface>,
    /// Fetal head in the head body frame of the history, m.
    pub head: TriSurface,
    /// Fetal trunk in the trunk body frame of the history, m; drawn only
    /// when the history records trunk poses.
    pub trunk: Option<TriSurface>,
    /// The lower trunk in its body frame, m, when the spine bends (the
    /// trunk is then the thorax); drawn when the history records its poses.
    pub lower_trunk: Option<TriSurface>,
    /// The pelvic floor, deforming, coloured by stretch.
    pub floor: Option<FloorSurface>,
    /// The head's fontanelles, drawn on it so that a picture shows which
    /// way the occiput points; `None`: the head's landmarks are not known.
    pub fontanelles: Option<Fontanelles>,
    /// The forces on the fetus at pose samples, drawn as arrows in the
    /// pictures of the key moments at those samples (empty: none drawn).
    pub forces: Vec<SampleForces>,
}

/// The fontanelles in the head body frame of the history, m: what the
/// accoucheur feels to tell the head's position (the occiput lies behind
/// the posterior one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fontanelles {
    /// Bregma, where the sagittal suture meets the coronal sutures.
    pub anterior: DVec3,
    /// Lambda, where the sagittal suture meets the lambdoid sutures.
    pub posterior: DVec3,
}

/// The forces on the fetus at one pose sample, as arrows and in words.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleForces {
    /// Index of the pose sample.
    pub sample: usize,
    /// The arrows, in the pelvis frame.
    pub arrows: Vec<carus_render::RenderMesh>,
    /// What pushes, its size in newtons and its arrow's colour (sRGB), largest first.
    pub listed: Vec<(String, f64, [f32; 3])>,
}

/// The pelvic floor's boundary surface and its state at recorded instants.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorSurface {
    /// Boundary triangles (indices into the node list), outward normals by
    /// the right-hand rule.
    pub triangles: Vec<[u32; 3]>,
    /// Node positions at rest in the pelvis frame, m.
    pub rest_positions_m: Vec<DVec3>,
    /// Recorded states in time order; the picture of a moment uses the one
    /// nearest in time. Empty: the floor is drawn at rest, uncoloured.
    pub frames: Vec<FloorFrame>,
}

/// The pelvic floor at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorFrame {
    pub time_s: f64,
    /// Node positions in the pelvis frame, m (one per rest position).
    pub positions_m: Vec<DVec3>,
    /// Maximum principal stretch at each node (dimensionless, 1 at rest).
    pub stretch: Vec<f64>,
}
