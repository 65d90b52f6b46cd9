//! The files of a run (the crate's only file-system module): pose history
//! (JSON, CSV), detector report, run record, checkpoints, and ParaView
//! series (VTU/PVD) of the fetus, the pelvis and the deforming floor.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use carus_analysis::{DetectorReport, PoseHistory};
use carus_contact::RigidPose;
use carus_fem::{Mesh, TledSolver};
use carus_io::{CsvWriter, FrameFields, PvdCollection};
use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::loads::LoadSample;
use crate::sim::{FloorSample, SimState};
use crate::LabourError;

pub const SCENARIO_FILE: &str = "scenario.toml";
pub const CHECKPOINT_FILE: &str = "checkpoint.json";
pub const HISTORY_JSON: &str = "pose_history.json";
pub const HISTORY_CSV: &str = "pose_history.csv";
pub const CONTACTS_CSV: &str = "contacts.csv";
pub const MOVEMENTS_FILE: &str = "movements.json";
pub const RUN_FILE: &str = "run.json";
pub const PELVIS_VTU: &str = "pelvis.vtu";
pub const LIGAMENTS_VTU: &str = "sacrospinous_ligaments.vtu";
pub const SOFT_WALLS_VTU: &str = "pelvic_soft_walls.vtu";
pub const HEAD_BODY_VTU: &str = "head_body.vtu";
pub const TRUNK_BODY_VTU: &str = "trunk_body.vtu";
pub const LOWER_TRUNK_BODY_VTU: &str = "lower_trunk_body.vtu";
pub const FRAMES_DIR: &str = "frames";

/// The folder of a run's VTU frames, made if it is not there.
pub fn make_frames_dir(out_dir: &Path) -> Result<(), LabourError> {
    let dir = out_dir.join(FRAMES_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| output_error(&dir, e))
}

fn output_error(path: &Path, e: impl std::fmt::Display) -> LabourError {
    // carus_io's write errors lead with the path already, which
    // LabourError::Output's own would say again.
    let message = e.to_string();
    let message = match message.strip_prefix(&format!("{}: ", path.display())) {
        Some(rest) => rest.to_string(),
        None => message,
    };
    LabourError::Output { path: path.to_path_buf(), message }
}

/// Writes `text` to `path` whole, or leaves no half file
/// (`carus_io::output::write_whole`).
pub fn write_text(path: &Path, text: &str) -> Result<(), LabourError> {
    carus_io::output::write_whole(path, text.as_bytes()).map_err(|e| output_error(path, e))
}

pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), LabourError> {
    let text = serde_json::to_string(value).map_err(|e| output_error(path, e))?;
    write_text(path, &text)
}

/// What a checkpoint holds: the scenario as written, the full state and the
/// VTU frames written so far.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub scenario_toml: String,
    /// Folder an imported pelvis path is relative to.
    pub base_dir: PathBuf,
    pub state: SimState,
    pub frame_times: Vec<f64>,
    /// Wall time of the run's legs up to this checkpoint, s.
    #[serde(default)]
    pub wall_s: f64,
    /// `Scene::pelvis_digest` of the pelvis the run started in, so that a
    /// resume in a pelvis changed since (an imported mesh or its landmarks
    /// edited) is refused; absent from checkpoints written before it.
    #[serde(default)]
    pub pelvis_digest: Option<String>,
}

impl Checkpoint {
    /// The scenario the run started with, as the checkpoint in `dir` keeps
    /// it; text that no longer reads is the checkpoint damaged, not a
    /// scenario to correct.
    pub fn scenario(&self, dir: &Path) -> Result<crate::Scenario, LabourError> {
        let path = dir.join(CHECKPOINT_FILE);
        crate::Scenario::parse_kept(&path, &self.scenario_toml, self.base_dir.clone()).map_err(|e| match e {
            crate::ScenarioError::Syntax { .. } | crate::ScenarioError::Value { .. } => output_error(
                &path,
                format!("damaged after carus wrote it ({e}); run the scenario again from the start"),
            ),
            other => other.into(),
        })
    }
}

pub fn write_checkpoint(dir: &Path, checkpoint: &Checkpoint) -> Result<(), LabourError> {
    write_json_whole(&dir.join(CHECKPOINT_FILE), checkpoint)
}

/// Writes `value` as JSON beside `path`, then renames it there
/// (`carus_io::output::replace_whole`): an interrupted write never leaves a
/// broken file, and the viewer following a run never meets a half one.
pub fn write_json_whole<T: Serialize>(path: &Path, value: &T) -> Result<(), LabourError> {
    let text = serde_json::to_string(value).map_err(|e| output_error(path, e))?;
    carus_io::output::replace_whole(path, text.as_bytes()).map_err(|e| output_error(path, e))
}

/// How a run ended, as its run.json's summary says.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct RunEnding {
    /// It reached its end (its end time, or delivery).
    pub completed: bool,
    /// Why it ended early on a failure of the physics, or why the detector
    /// refused its history.
    pub failure: Option<String>,
    /// The simulated time reached, s.
    pub simulated_s: f64,
}

impl RunEnding {
    /// Over for good: it reached its end, or its physics failed (its
    /// checkpoint holds the state it failed in, so going on would fail
    /// alike). A run stopped by its output (a full disk) is not: it goes
    /// on from its checkpoint once there is room.
    pub fn is_over(&self) -> bool {
        self.completed || self.failure.as_deref().is_some_and(|f| !f.starts_with(crate::run::OUTPUT_FAILURE))
    }
}

/// How the run in `dir` ended; None where it has no readable run.json (a
/// run cut off before it wrote one).
pub fn run_ending(dir: &Path) -> Option<RunEnding> {
    #[derive(Deserialize)]
    struct Record {
        summary: RunEnding,
    }
    let text = carus_io::input::read_text(&dir.join(RUN_FILE)).ok()?;
    let Record { summary } = serde_json::from_str(&text).ok()?;
    Some(summary)
}

pub fn read_checkpoint(dir: &Path) -> Result<Checkpoint, LabourError> {
    let path = dir.join(CHECKPOINT_FILE);
    let text = carus_io::input::read_text(&path).map_err(|e| {
        let problem = match e.kind() {
            std::io::ErrorKind::InvalidData => format!(
                "not text ({e}): it was damaged after carus wrote it; run the scenario again from the start"
            ),
            // A run's folder cut off before its first checkpoint (killed,
            // or still going), or one it was taken from: say which and what next.
            std::io::ErrorKind::NotFound if dir.join(SCENARIO_FILE).is_file() => format!(
                "not there: {} holds no checkpoint to go on from; a run writes one every \
                 `numerics.checkpoint_every_s` of simulated time (its {SCENARIO_FILE} says how often) and when it \
                 stops, so this run was cut off before its first (or is still running to it), or the file was \
                 removed; run the scenario again from the start: `carus run {} --out NEW_FOLDER`",
                dir.display(),
                dir.join(SCENARIO_FILE).display()
            ),
            std::io::ErrorKind::NotFound => format!(
                "not there: {} holds no run (no {SCENARIO_FILE} either); --resume takes the folder that \
                 `carus run` wrote",
                dir.display()
            ),
            _ => format!("{e}; is this the out dir of a `carus run`?"),
        };
        output_error(&path, problem)
    })?;
    serde_json::from_str(&text).map_err(|e| {
        let problem = if e.is_eof() || e.is_syntax() {
            format!(
                "not a whole JSON file ({e}): it was cut short or damaged after carus wrote it \
                 (carus writes it whole, then renames it); run the scenario again from the start"
            )
        } else {
            format!(
                "not a checkpoint this version of Carus can continue ({e}); if an older \
                 version wrote it, run the scenario again from the start"
            )
        };
        output_error(&path, problem)
    })
}

/// A triangle surface as a VTU file, placed by `pose`; `time_s`: the
/// frame's time, for a frame of a series.
pub fn write_surface_vtu(
    path: &Path,
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
    pose: &RigidPose,
    time_s: Option<f64>,
) -> Result<(), LabourError> {
    let points: Vec<[f64; 3]> = vertices.iter().map(|v| pose.point(*v).to_array()).collect();
    carus_io::write_triangle_vtu(path, &points, triangles, time_s).map_err(|e| output_error(path, e))
}

/// The floor's current state as a VTU frame: the mesh where it is now, as
/// the fetal frames are posed, so that the series opens in ParaView as the
/// scene was; the displacement from the rest shape, von Mises stress,
/// maximum principal stretch and J ride on it.
pub fn write_floor_vtu(path: &Path, mesh: &Mesh, solver: &TledSolver, time_s: f64) -> Result<(), LabourError> {
    let u = solver.displacements();
    let fields = solver.element_fields();
    let mut placed = mesh.clone();
    for (node, d) in placed.nodes.iter_mut().zip(&u) {
        *node = std::array::from_fn(|i| node[i] + d[i]);
    }
    let mesh = &placed;
    let frame = FrameFields {
        displacement_m: &u,
        von_mises_pa: &fields.von_mises_pa,
        max_principal_stretch: &fields.max_principal_stretch,
        jacobian: &fields.jacobian,
        time_s: Some(time_s),
    };
    carus_io::write_vtu(path, mesh, &frame).map_err(|e| output_error(path, e))
}

/// The stems of a run's ParaView series (`<stem>.pvd` listing
/// `frames/<stem>_NNNN.vtu`): what `carus run --force` knows as its own.
pub const SERIES_STEMS: [&str; 4] = ["head", "trunk", "lower_trunk", "floor"];

/// A PVD time series of `frames/<stem>_NNNN.vtu`.
pub fn write_pvd(dir: &Path, stem: &str, times: &[f64]) -> Result<String, LabourError> {
    assert!(SERIES_STEMS.contains(&stem), "a series `{stem}` missing from SERIES_STEMS");
    let mut pvd = PvdCollection::new();
    for (k, t) in times.iter().enumerate() {
        pvd.push(*t, frame_name(stem, k));
    }
    let name = format!("{stem}.pvd");
    let path = dir.join(&name);
    pvd.write(&path).map_err(|e| output_error(&path, e))?;
    Ok(name)
}

/// Relative path of VTU frame `k` of a series.
pub fn frame_name(stem: &str, k: usize) -> String {
    assert!(SERIES_STEMS.contains(&stem), "a series `{stem}` missing from SERIES_STEMS");
    format!("{FRAMES_DIR}/{stem}_{k:04}.vtu")
}

/// The pose history as JSON: what `carus detect` reads back (the canal,
/// the fetal geometry, each sample's poses and forces), with the
/// detector's series beside each sample under pose_history.csv's column
/// names (`station_mm`, `theta_deg`, `phi_deg`...; null where a column
/// does not apply), which the detector's reader ignores. Without a report
/// (the detector refused the history) the samples are as recorded.
pub fn write_history_json(path: &Path, history: &PoseHistory, report: Option<&DetectorReport>) -> Result<(), LabourError> {
    let mut value = serde_json::to_value(history).map_err(|e| output_error(path, e))?;
    let samples = value.get_mut("samples").and_then(serde_json::Value::as_array_mut);
    if let (Some(report), Some(samples)) = (report, samples) {
        let (columns, rows) = report.series.table();
        for (sample, row) in samples.iter_mut().zip(&rows) {
            let Some(sample) = sample.as_object_mut() else { continue };
            for (column, cell) in columns.iter().zip(row) {
                // `time_s` is the sample's own; a recorded field is never replaced.
                sample
                    .entry(*column)
                    .or_insert_with(|| cell.map_or(serde_json::Value::Null, serde_json::Value::from));
            }
        }
    }
    write_json(path, &value)
}

/// The pose history as CSV: the detector's series (station, theta, phi,
/// forces...) beside the head and trunk poses in the pelvis frame, and the
/// moments that spin the head about the pelvic axis.
pub fn write_history_csv(
    path: &Path,
    history: &PoseHistory,
    report: Option<&DetectorReport>,
    floor: &[FloorSample],
    loads: &[LoadSample],
) -> Result<(), LabourError> {
    let (series_columns, rows) = match report {
        Some(r) => r.series.table(),
        None => (
            vec!["time_s"],
            history
                .samples
                .iter()
                .map(|s| vec![Some(s.time_s)])
                .collect(),
        ),
    };
    let mut header: Vec<&str> = series_columns.clone();
    let poses = [
        "head_x_m",
        "head_y_m",
        "head_z_m",
        "head_qx",
        "head_qy",
        "head_qz",
        "head_qw",
        "trunk_x_m",
        "trunk_y_m",
        "trunk_z_m",
        "trunk_qx",
        "trunk_qy",
        "trunk_qz",
        "trunk_qw",
        "expulsion_fx_n",
        "expulsion_fy_n",
        "expulsion_fz_n",
        "bone_fx_n",
        "bone_fy_n",
        "bone_fz_n",
        "floor_fx_n",
        "floor_fy_n",
        "floor_fz_n",
        "floor_peak_stretch",
        "floor_inverted_corner_elements",
        "head_axial_moment_bone_nm",
        "head_axial_moment_floor_nm",
        "head_axial_moment_neck_nm",
        "neck_flexion_deg",
        "neck_lateral_bending_deg",
        "neck_axial_rotation_deg",
        "head_axial_moment_neck_push_nm",
        "lower_trunk_x_m",
        "lower_trunk_y_m",
        "lower_trunk_z_m",
        "lower_trunk_qx",
        "lower_trunk_qy",
        "lower_trunk_qz",
        "lower_trunk_qw",
        "spine_flexion_deg",
        "spine_lateral_bending_deg",
        "spine_axial_rotation_deg",
        "head_trunk_fx_n",
        "head_trunk_fy_n",
        "head_trunk_fz_n",
        "head_axial_moment_trunk_nm",
        "neck_fx_n",
        "neck_fy_n",
        "neck_fz_n",
        DOMINANT_CONTACT_COLUMN,
        DOMINANT_PART_COLUMN,
    ];
    header.extend_from_slice(&poses);
    let mut csv = CsvWriter::create(path, &header).map_err(|e| output_error(path, e))?;
    for (k, (row, sample)) in rows.iter().zip(&history.samples).enumerate() {
        let mut values = carus_io::missing_as_nan(row);
        values.extend(pose_columns(Some(sample.head)));
        values.extend(pose_columns(sample.trunk));
        for f in [
            sample.expulsion_force_n,
            sample.bone_contact_force_n,
            sample.floor_contact_force_n,
        ] {
            values.extend(f.to_array());
        }
        values.push(floor.get(k).map_or(f64::NAN, |f| f.peak_stretch));
        values.push(floor.get(k).map_or(f64::NAN, |f| f.inverted_corner_elements as f64));
        match loads.get(k) {
            Some(l) => values.extend([
                l.head_axial.bone_nm,
                l.head_axial.floor_nm,
                l.head_axial.neck_nm,
            ]),
            None => values.extend([f64::NAN; 3]),
        }
        match loads.get(k).and_then(|l| l.neck) {
            Some(n) => values.extend([n.flexion_deg, n.lateral_bending_deg, n.axial_rotation_deg]),
            None => values.extend([f64::NAN; 3]),
        }
        values.push(loads.get(k).map_or(f64::NAN, |l| l.head_axial.neck_push_nm));
        values.extend(pose_columns(sample.lower_trunk));
        match loads.get(k).and_then(|l| l.spine) {
            Some(n) => values.extend([n.flexion_deg, n.lateral_bending_deg, n.axial_rotation_deg]),
            None => values.extend([f64::NAN; 3]),
        }
        match loads.get(k) {
            Some(l) => {
                values.extend(l.head_trunk_force_n.to_array());
                values.push(l.head_axial.trunk_nm);
            }
            None => values.extend([f64::NAN; 4]),
        }
        match loads.get(k).and_then(|l| l.neck_force_n) {
            Some(f) => values.extend(f.to_array()),
            None => values.extend([f64::NAN; 3]),
        }
        let labels = [
            sample.dominant_contact.map_or("", |c| c.name()),
            sample.dominant_part.map_or("", |p| p.name()),
        ];
        csv.row_with_labels(&values, &labels).map_err(|e| output_error(path, e))?;
    }
    csv.flush().map_err(|e| output_error(path, e))
}

/// The part of the canal that bore the most force at a sample, and the
/// fetal body it bore on: the last two columns of pose_history.csv.
const DOMINANT_CONTACT_COLUMN: &str = "dominant_contact";
const DOMINANT_PART_COLUMN: &str = "dominant_part";

/// What to check when a table's positions cannot be where its columns put them.
const UNIT_AND_FRAME_FIX: &str = "check the positions' unit (`_m` columns hold metres, `_mm` millimetres) and frame: the pelvis frame's origin is the inlet's centre, z normal to the inlet towards the mother's head, y towards the symphysis (CONVENTIONS.md)";

/// Farthest the head's centre can lie from the pelvic axis before it is
/// born: half the widest inlet diameter (about 130 mm transverse,
/// REFERENCE_DATA.md) with room to spare. Farther, the table's positions
/// are in another unit or frame than its columns say.
const HEAD_REACH_FROM_AXIS_M: f64 = 0.1;

/// A head whose given position never leaves a millimetre around the
/// pelvis origin has positions in metres written under `_mm` columns.
const STILL_AT_ORIGIN_M: f64 = 1e-3;

/// The table's head positions are in the canal: each within
/// [`HEAD_REACH_FROM_AXIS_M`] of the pelvic axis until past the outlet,
/// and not all within [`STILL_AT_ORIGIN_M`] of the origin. Else the line
/// of the first sample at fault and what is wrong.
fn check_within_canal(
    table: &carus_io::CsvTable,
    samples: &[carus_analysis::PoseSample],
    scene: &crate::Scene,
) -> Result<(), (usize, String)> {
    let axis = scene.canal.axis();
    let outlet_sigma = scene.canal.outlet_sigma();
    let centre = |s: &carus_analysis::PoseSample| s.head.point(scene.head_geometry.centre_m);
    for (sample, row) in samples.iter().zip(&table.rows) {
        let c = centre(sample);
        let sigma = axis.project(c);
        let off_axis = (c - axis.point(sigma)).length();
        if sigma < outlet_sigma && off_axis > HEAD_REACH_FROM_AXIS_M {
            return Err((
                row.line,
                format!(
                    "the head's centre lies {:.0} mm from the pelvic axis before it is born, outside any birth canal",
                    off_axis * 1e3
                ),
            ));
        }
    }
    if samples.len() > 1 && samples.iter().all(|s| s.head.position_m.length() < STILL_AT_ORIGIN_M) {
        return Err((
            table.rows.first().map_or(0, |r| r.line),
            format!(
                "the head's position stays within {} mm of the pelvis origin over the whole table: positions in metres under `_mm` columns?",
                STILL_AT_ORIGIN_M * 1e3
            ),
        ));
    }
    Ok(())
}

/// The name in a label column's cell (`None` when the table has no such
/// column or the cell is empty), or what is wrong with it.
fn label_cell<T: serde::de::DeserializeOwned>(
    row: &carus_io::CsvRow,
    column: Option<usize>,
    wrong: &str,
    names: &str,
) -> Result<Option<T>, String> {
    let Some(name) = column.map(|c| row.cells[c].as_str()).filter(|c| !c.is_empty()) else {
        return Ok(None);
    };
    serde_json::from_value(serde_json::Value::String(name.to_string()))
        .map(Some)
        .map_err(|_| format!("{name:?} {wrong} (the names: {names})"))
}

/// How far a quaternion read from a table may be from unit length and
/// still be taken (normalised) as a rotation: a table of 4-6 digits.
const TABLE_QUATERNION_TOLERANCE: f64 = 1e-3;

/// A pose history read from a table in pose_history.csv's columns, for
/// the anatomy of `scene` (the head, trunk and canal the poses are of).
///
/// Read: `time_s`; the head's pose, `head_x_m`, `head_y_m`, `head_z_m`
/// (or `_mm`) and `head_qx`..`head_qw`; the trunk's in `trunk_` columns
/// when the table has them (then every row needs it and so does the
/// anatomy); the forces `expulsion_`, `bone_` and `floor_` `fx_n`..`fz_n`
/// when present (zero where absent or empty); `dominant_contact` and
/// `dominant_part` when present. Every other column is ignored: the
/// detector derives station, theta and phi itself.
pub fn read_history_csv(path: &Path, scene: &crate::Scene) -> Result<PoseHistory, LabourError> {
    let table = carus_io::CsvTable::read(path)?;
    let content = |problem: String, fix: &str| -> LabourError {
        carus_io::ReadError::Content {
            path: path.to_path_buf(),
            problem,
            fix: fix.to_string(),
        }
        .into()
    };
    let at = |line: usize, problem: String, fix: &str| -> LabourError {
        carus_io::ReadError::Syntax {
            path: path.to_path_buf(),
            line,
            problem,
            fix: fix.to_string(),
        }
        .into()
    };
    // A position column in metres, or in millimetres scaled to metres.
    let position = |name: &str| -> Option<(usize, f64)> {
        table
            .column(&format!("{name}_m"))
            .map(|c| (c, 1.0))
            .or_else(|| table.column(&format!("{name}_mm")).map(|c| (c, 1e-3)))
    };
    // One unit for a body's three position columns, and only one of them.
    let position_unit = |body: &str| -> Result<&'static str, LabourError> {
        let units: Vec<&'static str> = ["m", "mm"]
            .into_iter()
            .filter(|unit| ["x", "y", "z"].iter().any(|a| table.column(&format!("{body}_{a}_{unit}")).is_some()))
            .collect();
        match units[..] {
            [unit] => Ok(unit),
            [] => Ok("m"),
            _ => Err(content(
                format!("the {body}'s position has columns in both metres (`{body}_x_m`...) and millimetres (`{body}_x_mm`...)"),
                "give its x, y and z in one unit, once",
            )),
        }
    };
    let pose_column_indices = |body: &str| -> Result<Option<[(usize, f64); 7]>, LabourError> {
        let unit = position_unit(body)?;
        let names = ["x", "y", "z", "qx", "qy", "qz", "qw"].map(|a| format!("{body}_{a}"));
        let found: Vec<Option<(usize, f64)>> = names
            .iter()
            .enumerate()
            .map(|(i, n)| if i < 3 { position(n) } else { table.column(n).map(|c| (c, 1.0)) })
            .collect();
        match found.iter().filter(|c| c.is_some()).count() {
            0 => Ok(None),
            7 => Ok(Some(std::array::from_fn(|i| found[i].unwrap_or_default()))),
            _ => {
                let missing: Vec<String> = names
                    .iter()
                    .zip(&found)
                    .filter(|(_, c)| c.is_none())
                    .map(|(n, _)| if n.ends_with(['x', 'y', 'z']) && !n.contains("_q") { format!("{n}_{unit}") } else { n.clone() })
                    .collect();
                Err(content(
                    format!("the {body}'s pose lacks the column(s) {}", missing.join(", ")),
                    "give the position (x, y, z in m, or _mm) and the orientation quaternion (qx, qy, qz, qw) of the pelvis frame",
                ))
            }
        }
    };
    let time = table.column("time_s").ok_or_else(|| {
        content("there is no `time_s` column".into(), "name the time column `time_s`, in seconds")
    })?;
    let head = pose_column_indices("head")?.ok_or_else(|| {
        content(
            "there are no head pose columns".into(),
            "give head_x_m, head_y_m, head_z_m (or _mm) and head_qx, head_qy, head_qz, head_qw: the head's centre-of-mass frame in the pelvis frame (docs/DETECTOR.md)",
        )
    })?;
    // A run without a trunk writes its trunk columns empty in every row.
    let trunk = pose_column_indices("trunk")?
        .filter(|columns| table.rows.iter().any(|row| columns.iter().any(|&(c, _)| !row.cells[c].is_empty())));
    if trunk.is_some() && scene.trunk_geometry.is_none() {
        return Err(content(
            "the table has trunk poses but the anatomy has no trunk".into(),
            "give an anatomy with `trunk.enabled = true`, or drop the trunk columns",
        ));
    }
    let force_columns = |body: &str| ["fx", "fy", "fz"].map(|a| table.column(&format!("{body}_{a}_n")));
    let forces = ["expulsion", "bone", "floor"].map(force_columns);
    let label = |name: &str| table.column(name);
    let (contact_column, part_column) = (label(DOMINANT_CONTACT_COLUMN), label(DOMINANT_PART_COLUMN));

    let site_names = carus_analysis::ContactSite::ALL.map(|site| site.name()).join(", ");
    let mut samples = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let number = |column: usize| table.number(row, column);
        let Some(time_s) = number(time)? else {
            return Err(at(row.line, "`time_s` is empty".into(), "give every row its time"));
        };
        let pose = |columns: &[(usize, f64); 7], body: &str| -> Result<Option<RigidPose>, LabourError> {
            let mut v = [0.0; 7];
            let mut empty = 0;
            for (slot, &(column, scale)) in v.iter_mut().zip(columns) {
                match number(column)? {
                    Some(x) => *slot = x * scale,
                    None => empty += 1,
                }
            }
            match empty {
                0 => {}
                7 => return Ok(None),
                _ => {
                    return Err(at(
                        row.line,
                        format!("the {body}'s pose has {empty} empty cells of 7"),
                        "give all seven numbers of the pose at every sample",
                    ))
                }
            }
            let q = glam::DQuat::from_xyzw(v[3], v[4], v[5], v[6]);
            let length = q.length();
            if length.is_nan() || (length - 1.0).abs() > TABLE_QUATERNION_TOLERANCE {
                return Err(at(
                    row.line,
                    format!("the {body}'s quaternion (qx, qy, qz, qw) has length {length}, not 1"),
                    "give the orientation as a unit quaternion, scalar part last",
                ));
            }
            Ok(Some(RigidPose {
                position_m: DVec3::new(v[0], v[1], v[2]),
                // A run's own quaternions are kept bit for bit.
                orientation: if (length - 1.0).abs() > 1e-12 { q.normalize() } else { q },
            }))
        };
        let head_pose = pose(&head, "head")?.ok_or_else(|| {
            at(row.line, "the head's pose is empty".into(), "give the head's pose at every sample")
        })?;
        let trunk_pose = match &trunk {
            Some(columns) => Some(pose(columns, "trunk")?.ok_or_else(|| {
                at(
                    row.line,
                    "the trunk's pose is empty".into(),
                    "give the trunk's pose at every sample, or drop the trunk columns",
                )
            })?),
            None => None,
        };
        let mut force = [DVec3::ZERO; 3];
        for (f, columns) in force.iter_mut().zip(&forces) {
            for (axis, column) in columns.iter().enumerate() {
                if let Some(column) = column {
                    f[axis] = number(*column)?.unwrap_or(0.0);
                }
            }
        }
        let dominant_contact = label_cell(row, contact_column, "names no part of the canal", &site_names)
            .map_err(|problem| at(row.line, format!("`{DOMINANT_CONTACT_COLUMN}` = {problem}"), &format!("use {site_names}, or leave it empty")))?;
        let dominant_part = label_cell(row, part_column, "names no fetal body", "head or trunk")
            .map_err(|problem| at(row.line, format!("`{DOMINANT_PART_COLUMN}` = {problem}"), "use head or trunk, or leave it empty"))?;
        samples.push(carus_analysis::PoseSample {
            time_s,
            head: head_pose,
            trunk: trunk_pose,
            lower_trunk: None,
            expulsion_force_n: force[0],
            bone_contact_force_n: force[1],
            floor_contact_force_n: force[2],
            dominant_contact,
            dominant_part,
        });
    }
    let mut history = crate::run::history_of(scene, samples);
    if trunk.is_none() {
        history.trunk = None;
    }
    history.validate().map_err(|e| {
        // The history's samples are the table's rows, in order.
        let line = |index: usize| table.rows.get(index).map_or(0, |r| r.line);
        let index = match &e {
            carus_analysis::HistoryError::NotFinite { index, .. }
            | carus_analysis::HistoryError::TimeNotIncreasing { index, .. }
            | carus_analysis::HistoryError::NotUnitQuaternion { index, .. }
            | carus_analysis::HistoryError::TooFar { index, .. } => Some(*index),
            _ => None,
        };
        match (index, &e) {
            (Some(i), carus_analysis::HistoryError::TooFar { distance_m, .. }) => at(
                line(i),
                format!("a position lies {distance_m:.3e} m from the pelvis origin, farther than a fetus goes"),
                UNIT_AND_FRAME_FIX,
            ),
            (Some(i), _) => at(line(i), e.to_string(), "correct the row"),
            (None, carus_analysis::HistoryError::TooFewSamples { .. }) => content(e.to_string(), "give at least two samples"),
            (None, _) => content(e.to_string(), "check the anatomy the table is read with (--anatomy)"),
        }
    })?;
    check_within_canal(&table, &history.samples, scene).map_err(|(line, problem)| {
        at(
            line,
            problem,
            UNIT_AND_FRAME_FIX,
        )
    })?;
    Ok(history)
}

/// Position and orientation quaternion of a pose, NaN when there is none.
fn pose_columns(pose: Option<RigidPose>) -> [f64; 7] {
    pose.map_or([f64::NAN; 7], |p| {
        let (x, q) = (p.position_m, p.orientation);
        [x.x, x.y, x.z, q.x, q.y, q.z, q.w]
    })
}

/// The contact loads as CSV, one row per recorded instant, body and site
/// that carried load: force, its friction part, and its moment about the
/// atlanto-occipital pivot, in the pelvis frame.
pub fn write_contacts_csv(path: &Path, loads: &[LoadSample]) -> Result<(), LabourError> {
    let mut text = String::from(
        "time_s,body,site,points,fx_n,fy_n,fz_n,friction_fx_n,friction_fy_n,friction_fz_n,\
         moment_x_nm,moment_y_nm,moment_z_nm,pressing_n\n",
    );
    for sample in loads {
        for l in &sample.sites {
            let _ = write!(
                text,
                "{},{},{},{}",
                sample.time_s,
                l.body.name(),
                l.site.name(),
                l.points
            );
            for v in [l.force_n, l.friction_force_n, l.moment_about_pivot_nm] {
                let _ = write!(text, ",{},{},{}", v.x, v.y, v.z);
            }
            // Empty for a run recorded before sites recorded it.
            let _ = writeln!(text, ",{}", l.pressing_n.map_or(String::new(), |p| p.to_string()));
        }
    }
    write_text(path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file that cannot be written is named once, not once by carus_io
    /// and again by the run.
    #[test]
    fn a_write_failure_names_the_file_once() {
        let dir = tempfile::tempdir().unwrap();
        // A file where the run's folder should be: no write can go there.
        let blocked = dir.path().join("trap");
        std::fs::write(&blocked, "").unwrap();
        let path = blocked.join(HISTORY_CSV);
        let e = output_error(&path, carus_io::CsvWriter::create(&path, &["time_s"]).err().unwrap()).to_string();
        let named = path.display().to_string();
        assert_eq!(e.matches(&named).count(), 1, "{e}");
        assert!(e.starts_with(&format!("{named}: cannot write the file")), "{e}");
    }

    /// A run's folder without its checkpoint says so, how often a run
    /// writes one and what to do; a folder with no run says that.
    #[test]
    fn a_missing_checkpoint_says_why_and_what_to_do() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_checkpoint(dir.path()).err().unwrap().to_string();
        assert!(e.contains("checkpoint.json: not there") && e.contains("holds no run (no scenario.toml either)"), "{e}");
        assert!(!e.contains("os error"), "{e}");
        std::fs::write(dir.path().join(SCENARIO_FILE), "").unwrap();
        let e = read_checkpoint(dir.path()).err().unwrap().to_string();
        let d = dir.path().display();
        for part in [
            format!("{d}/checkpoint.json: not there: {d} holds no checkpoint to go on from"),
            "every `numerics.checkpoint_every_s` of simulated time".to_string(),
            format!("`carus run {d}/scenario.toml --out NEW_FOLDER`"),
        ] {
            assert!(e.contains(&part), "{part}: {e}");
        }
    }
}
