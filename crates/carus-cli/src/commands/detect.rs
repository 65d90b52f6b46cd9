//! `carus detect PATH [--json]`: the cardinal-movement detector on a recorded
//! pose history (a run's `pose_history.json`, or any history written in its
//! format: forward, imposed or hybrid), or on a table of poses in
//! pose_history.csv's columns (a run's, or another tool's) with the anatomy
//! they are of, without simulating anything.

use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_analysis::{detect, DetectorReport, PoseHistory};
use carus_labour::output::{HISTORY_JSON, SCENARIO_FILE};
use carus_labour::{Scenario, Scene};
use serde_json::json;

use super::run::{movement_list, movements_json, outcome_line, print_movements};
use super::{print_json, Status};

#[derive(clap::Args)]
pub struct DetectArgs {
    /// A pose history: JSON as `carus run` writes it, a run folder holding pose_history.json, or a CSV table in pose_history.csv's columns (docs/DETECTOR.md).
    pub history: PathBuf,
    /// For a CSV table: the scenario whose pelvis, head and trunk the poses are of (a built-in name or a file). Without it, the scenario.toml beside the table (a run folder's), else the built-in `normal`.
    #[arg(long, value_name = "SCENARIO")]
    pub anatomy: Option<String>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &DetectArgs) -> anyhow::Result<Status> {
    let path = history_file(&args.history);
    let (report, anatomy) = detect_file(&path, args.anatomy.as_deref())?;
    let movements = movement_list(&report.movements);
    if args.json {
        print_json(&json!({
            "history": path.display().to_string(),
            "anatomy": anatomy,
            "outcome": report.outcome,
            "movements": movements_json(&movements),
            "posterior_rotation": report.posterior_rotation,
            "internal_rotation_outside_window": report.internal_rotation_outside_window,
            "head_born": report.head_born,
            "contraction_period_s": report.contraction_period_s,
        }))?;
    } else {
        if let Some(anatomy) = &anatomy {
            println!("{}: the poses of the anatomy of {anatomy}", path.display());
        }
        println!("{}: {}", path.display(), outcome_line(&report.outcome));
        print_movements(&movements, report.internal_rotation_outside_window, report.head_born);
    }
    Ok(Status::Success)
}

/// A folder stands for the pose history a run wrote into it.
fn history_file(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join(HISTORY_JSON)
    } else {
        path.to_path_buf()
    }
}

/// The detector's report on the history in `path`, and for a table the
/// scenario whose anatomy it was read with.
fn detect_file(path: &Path, anatomy: Option<&str>) -> anyhow::Result<(DetectorReport, Option<String>)> {
    let is_table = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let (history, anatomy) = if is_table {
        let (scenario, label) = table_anatomy(path, anatomy)?;
        let scene = Scene::build(&scenario).with_context(|| format!("cannot build the anatomy of {label}"))?;
        let history = carus_labour::output::read_history_csv(path, &scene)
            .with_context(|| format!("{} is not a table of poses in pose_history.csv's columns (docs/DETECTOR.md)", path.display()))?;
        (history, Some(label))
    } else {
        if anatomy.is_some() {
            anyhow::bail!(
                "{}: --anatomy is for a CSV table of poses; a JSON pose history carries its own anatomy",
                path.display()
            );
        }
        (read_json_history(path)?, None)
    };
    let report = detect(&history).with_context(|| format!("cannot detect the movements in {}", path.display()))?;
    Ok((report, anatomy))
}

/// The scenario a table's poses are read with, and how to name it.
fn table_anatomy(path: &Path, anatomy: Option<&str>) -> anyhow::Result<(Scenario, String)> {
    if let Some(name) = anatomy {
        return Ok((super::run::load(Some(name))?, format!("`{name}`")));
    }
    let beside = path.parent().unwrap_or(Path::new(".")).join(SCENARIO_FILE);
    if beside.is_file() {
        let scenario = Scenario::from_file(&beside)
            .with_context(|| format!("the run's scenario beside the table (give --anatomy to choose another)"))?;
        return Ok((scenario, beside.display().to_string()));
    }
    Ok((super::run::load(None)?, "the built-in `normal` scenario (--anatomy chooses another)".into()))
}

fn read_json_history(path: &Path) -> anyhow::Result<PoseHistory> {
    let text = carus_io::input::read_text(path).with_context(|| {
        format!(
            "cannot read {}: give a pose history (JSON or CSV) or a run folder that holds {HISTORY_JSON}",
            path.display()
        )
    })?;
    PoseHistory::from_json_str(&text).with_context(|| {
        format!(
            "{} is not a pose history in the format `carus run` writes (docs/DETECTOR.md)",
            path.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use carus_labour::{RunOptions, SilentObserver};

    /// Detecting a run's own history gives the run's result, read from the
    /// folder or from the file.
    #[test]
    fn a_runs_history_gives_the_runs_movements_and_outcome() {
        let s = crate::commands::coarse_normal(3.0);
        let dir = tempfile::tempdir().unwrap();
        let record = carus_labour::run(&s, dir.path(), &RunOptions::default(), &mut SilentObserver).unwrap();
        let own = record.detector.expect("a detector report");
        for path in [dir.path().to_path_buf(), dir.path().join(HISTORY_JSON)] {
            let (again, _) = detect_file(&history_file(&path), None).unwrap();
            assert_eq!(again.outcome, own.outcome);
            assert_eq!(again.movements, own.movements);
            assert_eq!(again.posterior_rotation, own.posterior_rotation);
        }
    }

    /// A missing file and a file that is not a history are refused, naming
    /// the file and what to give instead.
    #[test]
    fn bad_input_names_the_file_and_the_fix() {
        let dir = tempfile::tempdir().unwrap();
        let missing = detect_file(&history_file(dir.path()), None).unwrap_err();
        let text = format!("{missing:#}");
        assert!(text.contains(HISTORY_JSON) && text.contains("run folder"), "{text}");

        let wrong = dir.path().join("not_a_history.json");
        std::fs::write(&wrong, "{\"head\": 1}").unwrap();
        let text = format!("{:#}", detect_file(&wrong, None).unwrap_err());
        assert!(text.contains("not_a_history.json") && text.contains("pose history"), "{text}");

        let text = format!("{:#}", detect_file(&wrong, Some("normal")).unwrap_err());
        assert!(text.contains("--anatomy is for a CSV table"), "{text}");
    }

    /// A run's pose_history.csv, read with the scenario beside it, gives
    /// the run's own result: the table holds the poses, forces and
    /// dominant contacts bit for bit.
    #[test]
    fn a_runs_table_gives_the_runs_result() {
        let s = crate::commands::coarse_normal(3.0);
        let dir = tempfile::tempdir().unwrap();
        let record = carus_labour::run(&s, dir.path(), &RunOptions::default(), &mut SilentObserver).unwrap();
        let own = record.detector.expect("a detector report");
        let table = dir.path().join(carus_labour::output::HISTORY_CSV);
        let (again, anatomy) = detect_file(&table, None).unwrap();
        assert!(anatomy.unwrap().ends_with(SCENARIO_FILE));
        assert_eq!(again.outcome, own.outcome);
        assert_eq!(again.movements, own.movements);
        assert_eq!(again.head_born, own.head_born);
        assert!(again.series.table() == own.series.table(), "the series differ");
    }

    /// Another tool's table: the head alone, in millimetres, quaternions
    /// rounded to five digits, with the built-in anatomy; a straight push
    /// down the inlet's axis is engagement and descent only.
    #[test]
    fn a_minimal_table_of_head_poses_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("tracked.csv");
        // LOT: the occiput to the mother's left (o = +x), the vertex down the
        // axis (v = -z), b = v x o = -y; as a rotation from the head's axes,
        // half a turn about x (0.70711 rounded).
        let mut text = String::from("time_s,head_x_mm,head_y_mm,head_z_mm,head_qx,head_qy,head_qz,head_qw\r\n");
        for k in 0..=40 {
            let t = k as f64 * 0.25;
            text.push_str(&format!("{t},0,0,{},1.00000,0,0,0.00001\r\n", 60.0 - 12.0 * t));
        }
        std::fs::write(&table, text).unwrap();
        let (report, anatomy) = detect_file(&table, None).unwrap();
        assert!(anatomy.unwrap().contains("normal"));
        let m = &report.movements;
        assert!(m.engagement.observed && m.descent.observed, "{m:?}");
        assert!(!m.flexion.observed && !m.internal_rotation.observed && !m.extension.observed, "{m:?}");
        // An arrest read from such a table names no contact, and says so.
        let unnamed = carus_analysis::Outcome {
            delivered: false,
            arrest: Some(carus_analysis::Arrest {
                stage: carus_analysis::ArrestStage::Outlet,
                station_mm: 80.0,
                against: "unknown".into(),
                part: "unknown".into(),
                shoulders_station_mm: None,
            }),
        };
        assert_eq!(
            crate::commands::run::outcome_line(&unnamed),
            "arrested at the outlet stage, station +80 mm, against a contact the history does not name"
        );
        let (_, named) = detect_file(&table, Some("contracted-inlet")).unwrap();
        assert_eq!(named.unwrap(), "`contracted-inlet`");
    }

    /// Tables that cannot be poses are refused at their line and column.
    #[test]
    fn a_bad_table_names_the_line_and_the_fix() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("poses.csv");
        let header = "time_s,head_x_m,head_y_m,head_z_m,head_qx,head_qy,head_qz,head_qw";
        for (body, expected) in [
            ("time_s,station_mm\n0,0\n", "there are no head pose columns"),
            ("time_s,head_x_m,head_qx\n0,0,1\n", "lacks the column(s) head_y_m, head_z_m, head_qy"),
            (&format!("{header}\n0,0,0,0,0,0,0,1\n1,0,0,abc,0,0,0,1\n") as &str, "poses.csv:3: `head_z_m` = \"abc\" is not a number"),
            (&format!("{header}\n0,0,0,0,0,0,0,1\n1,0,0,0,0,0,0,2\n"), "poses.csv:3: the head's quaternion (qx, qy, qz, qw) has length 2"),
            (&format!("{header}\n0,0,0,0,0,0,0,1\n1,0,0,,0,0,0,1\n"), "poses.csv:3: the head's pose has 1 empty cells of 7"),
            (&format!("{header}\n1,0,0,0,0,0,0,1\n0.5,0,0,0,0,0,0,1\n"), "poses.csv:3: sample 1: time_s = 0.5 does not increase"),
            (&format!("{header},dominant_contact\n0,0,0,0,0,0,0,1,sacrum\n1,0,0,0,0,0,0,1,knee\n"), "poses.csv:3: `dominant_contact` = \"knee\" names no part of the canal"),
        ] {
            std::fs::write(&table, body).unwrap();
            let text = format!("{:#}", detect_file(&table, Some("normal")).unwrap_err());
            assert!(text.contains(expected) && text.contains("fix"), "{expected}: {text}");
        }
    }

    /// A sample that lacks a field is named by its index.
    #[test]
    fn a_broken_sample_is_named_by_its_index() {
        let s = crate::commands::coarse_normal(0.05);
        let dir = tempfile::tempdir().unwrap();
        carus_labour::run(&s, dir.path(), &RunOptions::default(), &mut SilentObserver).unwrap();
        let path = dir.path().join(HISTORY_JSON);
        let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        json["samples"][2].as_object_mut().unwrap().remove("head");
        std::fs::write(&path, json.to_string()).unwrap();
        let text = format!("{:#}", detect_file(&path, None).unwrap_err());
        assert!(text.contains("samples[2]") && text.contains("missing field `head`"), "{text}");
    }
}
