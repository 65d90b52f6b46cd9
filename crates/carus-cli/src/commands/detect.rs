//! `carus detect PATH [--json]`: the cardinal-movement detector on a recorded
//! pose history (a run's `pose_history.json`, or any history written in its
//! format: forward, imposed or hybrid), without simulating anything.

use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_analysis::{detect, DetectorReport, PoseHistory};
use carus_labour::output::HISTORY_JSON;
use serde_json::json;

use super::run::{movement_list, movements_json, outcome_line, print_movements};
use super::{print_json, Status};

#[derive(clap::Args)]
pub struct DetectArgs {
    /// A pose history (JSON, as `carus run` writes it) or a run folder holding pose_history.json.
    pub history: PathBuf,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &DetectArgs) -> anyhow::Result<Status> {
    let path = history_file(&args.history);
    let report = detect_file(&path)?;
    let movements = movement_list(&report.movements);
    if args.json {
        print_json(&json!({
            "history": path.display().to_string(),
            "outcome": report.outcome,
            "movements": movements_json(&movements),
            "posterior_rotation": report.posterior_rotation,
            "internal_rotation_outside_window": report.internal_rotation_outside_window,
            "head_born": report.head_born,
            "contraction_period_s": report.contraction_period_s,
        }))?;
    } else {
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

fn detect_file(path: &Path) -> anyhow::Result<DetectorReport> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")) {
        anyhow::bail!(
            "{}: the detector reads the pose history as JSON; give {HISTORY_JSON} beside it, or the run folder",
            path.display()
        );
    }
    let text = carus_io::input::read_text(path).with_context(|| {
        format!(
            "cannot read {}: give a pose history (JSON) or a run folder that holds {HISTORY_JSON}",
            path.display()
        )
    })?;
    let history = PoseHistory::from_json_str(&text).with_context(|| {
        format!(
            "{} is not a pose history in the format `carus run` writes (docs/DETECTOR.md)",
            path.display()
        )
    })?;
    detect(&history).with_context(|| format!("cannot detect the movements in {}", path.display()))
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
            let again = detect_file(&history_file(&path)).unwrap();
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
        let missing = detect_file(&history_file(dir.path())).unwrap_err();
        let text = format!("{missing:#}");
        assert!(text.contains(HISTORY_JSON) && text.contains("run folder"), "{text}");

        let wrong = dir.path().join("not_a_history.json");
        std::fs::write(&wrong, "{\"head\": 1}").unwrap();
        let text = format!("{:#}", detect_file(&wrong).unwrap_err());
        assert!(text.contains("not_a_history.json") && text.contains("pose history"), "{text}");

        let csv = dir.path().join("pose_history.csv");
        std::fs::write(&csv, "time_s,station_mm\n0,0\n").unwrap();
        let text = format!("{:#}", detect_file(&csv).unwrap_err());
        assert!(text.contains("as JSON") && text.contains(HISTORY_JSON), "{text}");
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
        let text = format!("{:#}", detect_file(&path).unwrap_err());
        assert!(text.contains("samples[2]") && text.contains("missing field `head`"), "{text}");
    }
}
