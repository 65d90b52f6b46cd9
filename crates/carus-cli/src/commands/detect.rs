//! `carus detect PATH [--json]`: the cardinal-movement detector on a recorded
//! pose history (a run's `pose_history.json`, or any history written in its
//! format: forward, imposed or hybrid), or on a table of poses in
//! pose_history.csv's columns (a run's, or another tool's) with the anatomy
//! they are of, without simulating anything.

use std::path::{Path, PathBuf};

use anyhow::Context;
use carus_analysis::{detect, DetectorReport, PoseHistory};
use carus_labour::output::{HISTORY_CSV, HISTORY_JSON, RUN_FILE, SCENARIO_FILE};
use carus_labour::{Scenario, Scene, BUILTINS};
use serde_json::json;

use super::run::{movement_list, movements_json, outcome_line, print_movements, DEFAULT_SCENARIO};
use super::{print_json, Status};

#[derive(clap::Args)]
pub struct DetectArgs {
    /// A pose history: JSON as `carus run` writes it, a run folder holding pose_history.json, or a CSV table in pose_history.csv's columns (docs/DETECTOR.md).
    pub history: PathBuf,
    /// For a CSV table: the scenario whose pelvis, head and trunk the poses are of (a built-in name or a file). Without it, the scenario.toml beside the table (a run folder's), else the built-in `normal`.
    #[arg(long, value_name = "SCENARIO")]
    pub anatomy: Option<String>,
    /// Also write the detector's per-sample series (station, theta, phi, ...) to this CSV file, to check how a table was read.
    #[arg(long, value_name = "FILE.csv")]
    pub series: Option<PathBuf>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
}

/// The scenario whose anatomy a table's poses were read with.
#[derive(Debug)]
struct TableAnatomy {
    /// A built-in scenario's name, or the scenario file's path.
    scenario: String,
    builtin: bool,
    /// How it was chosen, for the reader.
    chosen: &'static str,
    /// The head's centre of mass (the point the table places) from the
    /// midpoint of its diameters, in the head's axes, mm.
    head_mass_centre_mm: [f64; 3],
    /// Whether the table gave the trunk's poses.
    trunk: bool,
}

/// Contractions further apart than this are no labour's, s: ten minutes,
/// twice the five of the slowest second stage (Williams Obstetrics,
/// chapter "Normal Labor": contractions every 2 to 3 minutes in the second
/// stage, every 5 or more only in early labour).
const SLOWEST_CONTRACTIONS_S: f64 = 600.0;

pub fn run(args: &DetectArgs) -> anyhow::Result<Status> {
    let path = history_file(&args.history);
    if let Some(series) = &args.series {
        check_series_target(series, &path)?;
    }
    let (report, anatomy) = detect_file(&path, args.anatomy.as_deref())?;
    if let Some(note) = time_unit_note(&path, report.contraction_period_s) {
        eprintln!("note: {note}");
    }
    if let Some(series) = &args.series {
        write_series(series, &report)?;
    }
    let movements = movement_list(&report.movements);
    if args.json {
        print_json(&json!({
            "history": path.display().to_string(),
            "anatomy": anatomy.as_ref().map(|a| &a.scenario),
            "anatomy_builtin": anatomy.as_ref().map(|a| a.builtin),
            "outcome": report.outcome,
            "movements": movements_json(&movements),
            "posterior_rotation": report.posterior_rotation,
            "internal_rotation_outside_window": report.internal_rotation_outside_window,
            "head_born": report.head_born,
            "not_held_at_birth": report.not_held_at_birth,
            "shoulders": report.shoulders,
            "contraction_period_s": report.contraction_period_s,
            "series": args.series.as_ref().map(|p| p.display().to_string()),
        }))?;
    } else {
        if let Some(a) = &anatomy {
            // Rounded first, so that a component of a few nanometres reads 0.0, not -0.0.
            let [o, b, v] = a.head_mass_centre_mm.map(|x| (x * 10.0).round() / 10.0 + 0.0);
            println!(
                "{}: the poses of the anatomy of {} ({}); the head's position is its centre of mass, \
                 {o:+.1} mm along the occipitofrontal axis, {b:+.1} mm along the biparietal, {v:+.1} mm along the vertex axis \
                 from the midpoint of its diameters{}",
                path.display(),
                if a.builtin { format!("the built-in `{}`", a.scenario) } else { a.scenario.clone() },
                a.chosen,
                if a.trunk {
                    ""
                } else {
                    "; no trunk poses, so neither the shoulders nor expulsion can be judged, and phi (flexion, \
                     extension) is measured against the expulsion force's direction (the canal's, without one) instead of the trunk's axis \
                     (docs/DETECTOR.md): it can differ from the run's own phi by tens of degrees"
                }
            );
        }
        println!("{}: {}", path.display(), outcome_line(&report.outcome));
        print_movements(&movements, Some(&report));
        if let Some(series) = &args.series {
            println!("per-sample series written to {}", series.display());
        }
    }
    Ok(Status::Success)
}

/// A folder stands for the pose history a run wrote into it: its JSON, or
/// its table when only that is there.
fn history_file(path: &Path) -> PathBuf {
    if !path.is_dir() {
        return path.to_path_buf();
    }
    let json = path.join(HISTORY_JSON);
    let table = path.join(HISTORY_CSV);
    if !json.exists() && table.is_file() {
        table
    } else {
        json
    }
}

/// `--series` writes a new file or replaces one of the user's, never the
/// history it reads nor a file in a folder that carus wrote (a run's
/// records: run.json, pose_history.csv... would be lost).
fn check_series_target(series: &Path, history: &Path) -> anyhow::Result<()> {
    if !series.exists() {
        return Ok(());
    }
    if series.is_dir() {
        crate::bad_argument!(
            "--series {}: that is a folder; give the CSV file to write, e.g. {}",
            series.display(),
            series.join("series.csv").display()
        );
    }
    let same = |a: &Path, b: &Path| a.canonicalize().ok().is_some_and(|a| b.canonicalize().ok() == Some(a));
    if same(series, history) {
        crate::bad_argument!("--series {}: that is the pose history being read; write the series to a new file", series.display());
    }
    let folder = series.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if super::run::carus_made(folder) {
        crate::bad_argument!(
            "--series {}: that file is in a folder carus wrote (a run's or a sweep's), and is not replaced; \
             write the series to a new name, or outside it",
            series.display()
        );
    }
    Ok(())
}

/// Second-stage contractions come every 2 to 5 minutes; a period read off
/// the force as more than ten is most likely times in another unit.
fn time_unit_note(path: &Path, period_s: Option<f64>) -> Option<String> {
    let period = period_s.filter(|&p| p > SLOWEST_CONTRACTIONS_S)?;
    Some(format!(
        "{}: the expulsion force rises and falls every {period:.0} s, far slower than contractions \
         (every 2 to 5 minutes); check that `time_s` is in seconds (not ms)",
        path.display()
    ))
}

/// The detector's per-sample series as CSV.
fn write_series(path: &Path, report: &DetectorReport) -> anyhow::Result<()> {
    let (columns, rows) = report.series.table();
    let mut csv = carus_io::CsvWriter::create(path, &columns)?;
    for row in rows {
        csv.row(&carus_io::missing_as_nan(&row))?;
    }
    csv.flush()?;
    Ok(())
}

/// The detector's report on the history in `path`, and for a table the
/// scenario whose anatomy it was read with.
fn detect_file(path: &Path, anatomy: Option<&str>) -> anyhow::Result<(DetectorReport, Option<TableAnatomy>)> {
    // A folder of runs (a sweep's, sanity's) is said as such.
    let batch = path.parent().filter(|f| !path.exists() && super::holds_batch(f));
    if let Some((folder, kind)) = batch.and_then(|f| Some((f, super::folder_kind(f)?))) {
        anyhow::bail!("{} holds no pose history: {kind}; give `carus detect` one run's folder", folder.display());
    }
    if !path.exists() {
        anyhow::bail!(
            "{}: no such file or folder; give a run folder, or its pose_history.json or pose_history.csv",
            path.display()
        );
    }
    if path.file_name().is_some_and(|name| name == RUN_FILE) {
        anyhow::bail!(
            "{} is a run's record, not its pose history: give the run's folder, or the {HISTORY_JSON} beside it",
            path.display()
        );
    }
    let is_table = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let (history, anatomy) = if is_table {
        let (scenario, mut chosen) = table_anatomy(path, anatomy)?;
        let scene = Scene::build(&scenario).with_context(|| format!("cannot build the anatomy of {}", chosen.scenario))?;
        let history = carus_labour::output::read_history_csv(path, &scene)
            .with_context(|| format!("{} is not a table of poses in pose_history.csv's columns (docs/DETECTOR.md)", path.display()))?;
        chosen.head_mass_centre_mm = (-history.head.centre_m * 1e3).to_array();
        chosen.trunk = history.trunk.is_some();
        (history, Some(chosen))
    } else {
        if anatomy.is_some() {
            crate::bad_argument!(
                "{}: --anatomy is for a CSV table of poses; a JSON pose history carries its own anatomy",
                path.display()
            );
        }
        (read_json_history(path)?, None)
    };
    let report = detect(&history).with_context(|| format!("cannot detect the movements in {}", path.display()))?;
    Ok((report, anatomy))
}

/// The scenario a table's poses are read with, and how it was chosen.
fn table_anatomy(path: &Path, anatomy: Option<&str>) -> anyhow::Result<(Scenario, TableAnatomy)> {
    let named = |scenario: String, chosen| TableAnatomy {
        builtin: BUILTINS.iter().any(|(n, _)| *n == scenario),
        scenario,
        chosen,
        head_mass_centre_mm: [0.0; 3],
        trunk: false,
    };
    if let Some(name) = anatomy {
        return Ok((super::run::load(Some(name))?, named(name.to_string(), "--anatomy")));
    }
    let beside = path.parent().unwrap_or(Path::new(".")).join(SCENARIO_FILE);
    if beside.is_file() {
        let scenario = Scenario::from_file(&beside)
            .context("the run's scenario beside the table (give --anatomy to choose another)")?;
        let mut chosen = named(beside.display().to_string(), "the scenario beside the table");
        chosen.builtin = false;
        return Ok((scenario, chosen));
    }
    Ok((super::run::load(None)?, named(DEFAULT_SCENARIO.into(), "the default; --anatomy chooses another")))
}

fn read_json_history(path: &Path) -> anyhow::Result<PoseHistory> {
    let text = carus_io::input::read_text(path).with_context(|| {
        format!(
            "cannot read {}: give a pose history (JSON or CSV) or a run folder that holds {HISTORY_JSON}",
            path.display()
        )
    })?;
    let looks_like_table = text.trim_start_matches('\u{feff}').lines().next().is_some_and(|l| l.contains("time_s") && !l.contains('{'));
    PoseHistory::from_json_str(&text).with_context(|| {
        format!(
            "{} is not a pose history in the format `carus run` writes (docs/DETECTOR.md){}",
            path.display(),
            if looks_like_table { "; it reads like a CSV table: give it a .csv name" } else { "" }
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
        // A table that is not there is not called the wrong kind of table.
        let text = format!("{:#}", detect_file(&dir.path().join("nosuch.csv"), None).unwrap_err());
        assert!(text.contains("nosuch.csv: no such file") && !text.contains("not a table of poses"), "{text}");

        let wrong = dir.path().join("not_a_history.json");
        std::fs::write(&wrong, "{\"head\": 1}").unwrap();
        let text = format!("{:#}", detect_file(&wrong, None).unwrap_err());
        assert!(text.contains("not_a_history.json") && text.contains("pose history"), "{text}");

        let text = format!("{:#}", detect_file(&wrong, Some("normal")).unwrap_err());
        assert!(text.contains("--anatomy is for a CSV table"), "{text}");

        // A run's record, and a sweep's folder, are named for what they are.
        let record = dir.path().join(RUN_FILE);
        std::fs::write(&record, "{}").unwrap();
        let text = format!("{:#}", detect_file(&record, None).unwrap_err());
        assert!(text.contains("is a run's record, not its pose history") && text.contains(HISTORY_JSON), "{text}");
        let sweep = dir.path().join("sweep");
        std::fs::create_dir(&sweep).unwrap();
        std::fs::write(sweep.join(super::super::sweep::PLAN_FILE), "{}").unwrap();
        let text = format!("{:#}", detect_file(&history_file(&sweep), None).unwrap_err());
        assert!(text.contains("holds no pose history") && text.contains("a sweep's folder") && text.contains("one run's folder"), "{text}");
        // A file missing from a run's folder is named as missing.
        std::fs::write(dir.path().join("scenario.toml"), "").unwrap();
        let text = format!("{:#}", detect_file(&dir.path().join("nosuch.json"), None).unwrap_err());
        assert!(text.contains("nosuch.json: no such file"), "{text}");

        let misnamed = dir.path().join("table.json");
        std::fs::write(&misnamed, "time_s,head_x_m\n0,0\n").unwrap();
        let text = format!("{:#}", detect_file(&misnamed, None).unwrap_err());
        assert!(text.contains("reads like a CSV table: give it a .csv name"), "{text}");
    }

    /// A contraction period no labour has is noted as a likely unit slip.
    #[test]
    fn a_history_in_milliseconds_is_noted() {
        let note = time_unit_note(Path::new("h.csv"), Some(8000.0)).expect("8000 s is no contraction");
        assert!(note.starts_with("h.csv: the expulsion force rises and falls every 8000 s") && note.contains("(not ms)"), "{note}");
        // The model's own time-compressed 8 s, and a clinical 3 minutes, are not.
        assert_eq!(time_unit_note(Path::new("h.csv"), Some(8.0)), None);
        assert_eq!(time_unit_note(Path::new("h.csv"), Some(180.0)), None);
        assert_eq!(time_unit_note(Path::new("h.csv"), None), None);
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
        let anatomy = anatomy.unwrap();
        assert!(anatomy.scenario.ends_with(SCENARIO_FILE) && !anatomy.builtin && anatomy.trunk);
        assert_eq!(again.outcome, own.outcome);
        assert_eq!(again.movements, own.movements);
        assert_eq!(again.head_born, own.head_born);
        assert!(again.series.table() == own.series.table(), "the series differ");
    }

    /// A run without a trunk writes its trunk columns empty; its table
    /// reads back as a history without a trunk, with the run's result.
    #[test]
    fn a_trunkless_runs_table_gives_the_runs_result() {
        let mut s = crate::commands::coarse_normal(1.0);
        s.trunk.enabled = false;
        let dir = tempfile::tempdir().unwrap();
        let record = carus_labour::run(&s, dir.path(), &RunOptions::default(), &mut SilentObserver).unwrap();
        let own = record.detector.expect("a detector report");
        let (again, anatomy) = detect_file(&dir.path().join(HISTORY_CSV), None).unwrap();
        assert!(!anatomy.unwrap().trunk);
        assert_eq!(again.outcome, own.outcome);
        assert_eq!(again.movements, own.movements);
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
        let anatomy = anatomy.unwrap();
        assert!(anatomy.scenario == "normal" && anatomy.builtin && !anatomy.trunk);
        // The default head's centre of mass, from its diameters' midpoint.
        let [o, b, v] = anatomy.head_mass_centre_mm;
        assert!((o - 2.0).abs() < 0.1 && b.abs() < 1e-3 && (v + 4.9).abs() < 0.1, "{o} {b} {v}");
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
                shoulders_from_ap_deg: None,
            }),
        };
        assert_eq!(
            crate::commands::run::outcome_line(&unnamed),
            "arrested at the outlet stage, station +80 mm, against a contact the history does not name"
        );
        let mut site_only = unnamed.clone();
        site_only.arrest.as_mut().unwrap().against = "sacrum".into();
        assert_eq!(crate::commands::run::outcome_line(&site_only), "arrested at the outlet stage, station +80 mm, against sacrum");
        // Shoulders held: their station and how they lie.
        let mut shoulders = site_only.clone();
        let a = shoulders.arrest.as_mut().unwrap();
        (a.stage, a.station_mm, a.part, a.shoulders_from_ap_deg) = (carus_analysis::ArrestStage::Shoulders, -43.6, "trunk".into(), Some(64.6));
        assert_eq!(
            crate::commands::run::outcome_line(&shoulders),
            "arrested at the shoulders stage, shoulders at station -44 mm, 65 deg from antero-posterior, the trunk against sacrum"
        );
        let (_, named) = detect_file(&table, Some("contracted-inlet")).unwrap();
        assert_eq!(named.unwrap().scenario, "contracted-inlet");
    }

    /// A table whose positions are in another unit or frame than its
    /// columns say is refused, not judged; a folder holding only a table
    /// is read through it; the series can be written.
    #[test]
    fn a_table_outside_the_canal_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join(HISTORY_CSV);
        let rows = |x_mm: f64, scale: f64| {
            let mut text = String::from("time_s,head_x_mm,head_y_mm,head_z_mm,head_qx,head_qy,head_qz,head_qw\n");
            for k in 0..=20 {
                let t = k as f64 * 0.5;
                text.push_str(&format!("{t},{},0,{},1,0,0,0\n", x_mm * scale, (60.0 - 12.0 * t) * scale));
            }
            text
        };
        for (text, expected) in [
            (rows(300.0, 1.0), "mm from the pelvic axis before it is born, outside any birth canal"),
            (rows(0.0, 1e-3), "poses.csv:2: the head's position stays within 1 mm of the pelvis origin"),
        ] {
            let poses = dir.path().join("poses.csv");
            std::fs::write(&poses, text).unwrap();
            let e = format!("{:#}", detect_file(&poses, None).unwrap_err());
            assert!(e.contains(expected) && e.contains("`_mm` millimetres"), "{e}");
        }
        let mixed = rows(0.0, 1.0).replacen("head_x_mm", "head_x_m", 1);
        std::fs::write(dir.path().join("poses.csv"), mixed).unwrap();
        let e = format!("{:#}", detect_file(&dir.path().join("poses.csv"), None).unwrap_err());
        assert!(e.contains("both metres") && e.contains("one unit"), "{e}");

        std::fs::write(&table, rows(0.0, 1.0)).unwrap();
        assert_eq!(history_file(dir.path()), table);
        let (report, _) = detect_file(&history_file(dir.path()), Some("normal")).unwrap();
        let series = dir.path().join("series.csv");
        write_series(&series, &report).unwrap();
        let written = carus_io::CsvTable::read(&series).unwrap();
        assert_eq!(written.rows.len(), 21);
        let station = written.column("station_mm").unwrap();
        assert!(written.number(&written.rows[0], station).unwrap().unwrap() < written.number(&written.rows[20], station).unwrap().unwrap());
    }

    /// `--series` never replaces the history it reads nor a run's records.
    #[test]
    fn the_series_is_not_written_over_a_runs_files() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("run");
        std::fs::create_dir(&run).unwrap();
        for f in ["scenario.toml", "run.json", "pose_history.csv"] {
            std::fs::write(run.join(f), "kept").unwrap();
        }
        let history = run.join("pose_history.csv");
        let e = format!("{:#}", check_series_target(&history, &history).unwrap_err());
        assert!(e.contains("the pose history being read") && e.contains("new file"), "{e}");
        let e = format!("{:#}", check_series_target(&run.join("run.json"), &history).unwrap_err());
        assert!(e.contains("run.json") && e.contains("folder carus wrote") && e.contains("outside it"), "{e}");
        let e = format!("{:#}", check_series_target(dir.path(), &history).unwrap_err());
        assert!(e.contains("that is a folder") && e.contains("series.csv"), "{e}");
        // A new file, even in the run's folder, and a user's own file elsewhere are written.
        check_series_target(&run.join("series.csv"), &history).unwrap();
        let own = dir.path().join("series.csv");
        std::fs::write(&own, "old").unwrap();
        check_series_target(&own, &history).unwrap();
        assert_eq!(std::fs::read_to_string(run.join("run.json")).unwrap(), "kept");
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
            (&format!("{header}\n1,0,0,0,0,0,0,1\n-1e300,0,0,0,0,0,0,1\n"), "poses.csv:3: sample 1: time_s = -1e300 does not increase"),
            // Squared, 1e300 would overflow: the distance is a number, not inf.
            (&format!("{header}\n0,0,0,0,0,0,0,1\n1,1e300,1e300,1e300,0,0,0,1\n"), "poses.csv:3: a position lies 1.732e300 m from the pelvis origin"),
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
        // A position a slip of exponent away: its distance is printed as a number.
        let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        json["samples"][2] = json["samples"][3].clone();
        json["samples"][2]["time_s"] = serde_json::json!(json["samples"][1]["time_s"].as_f64().unwrap() * 0.5 + json["samples"][3]["time_s"].as_f64().unwrap() * 0.5);
        json["samples"][2]["head"]["position_m"] = serde_json::json!([1e300, 0.0, 0.0]);
        std::fs::write(&path, json.to_string()).unwrap();
        let text = format!("{:#}", detect_file(&path, None).unwrap_err());
        assert!(text.contains("sample 2: head.position_m lies 1.000e300 m from the pelvis origin") && !text.contains("inf"), "{text}");
    }
}
