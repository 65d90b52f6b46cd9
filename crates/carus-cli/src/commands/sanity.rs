//! `carus sanity [--set KEY=VALUE ...] [--out DIR] [--jobs N] [--json]
//! [--force] [--quiet]`: the clinical sanity cases of CARDINAL_MOVEMENTS.md
//! ("the same forces must give" delivery in the normal case, arrest in the
//! contracted inlet and the face, shoulder arrest with large shoulders),
//! each its built-in scenario run forward with the same changes, judged
//! against its expected outcome (carus_analysis::sanity). Each run is a
//! whole `carus run` in its own folder. Exit status 1 when a case is not met
//! or has no verdict (stopped by Ctrl-C, or unable to start).
//! `carus sanity --resume DIR` goes on with stopped cases, with the changes
//! they started with (sanity_plan.json).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context;
use carus_analysis::sanity::{SanityCase, Verdict};
use carus_analysis::Outcome;
use carus_labour::Scenario;
use rayon::prelude::*;
use serde_json::json;

use super::batch::{check_runs_match_plan, check_runs_start};
use super::run::{go_on_into, make_batch_dir, outcome_line, OutputArgs};
use super::settings::{one_setting, one_setting_arg};
use super::{ctrl_c_flag, labour_pool, print_json, Status};

#[derive(clap::Args)]
pub struct SanityArgs {
    /// KEY=VALUE applied to every case, a dotted key as `carus scenarios
    /// show` writes it (e.g. contact.friction=0.35: does the bar hold at
    /// the seed's friction?); repeat for more keys.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = one_setting_arg, conflicts_with = "resume")]
    pub settings: Vec<String>,
    /// Go on with the stopped cases in DIR, with the changes they started
    /// with: runs stopped part way continue from their checkpoints, runs
    /// not started start, ended ones are kept; then every case is judged.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "force"])]
    pub resume: Option<PathBuf>,
    /// Runs at a time; default one per core.
    #[arg(long)]
    pub jobs: Option<usize>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Where a case stands after the command: judged, or left without a
/// verdict (as `carus validate` leaves a case it could not run).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
enum CaseState {
    Met,
    NotMet,
    /// Stopped (Ctrl-C) before its run ended, or before it started:
    /// nothing to judge yet; `--resume` goes on with it.
    Stopped,
    /// Its run could not start (a change left it no anatomy).
    NotRun,
}

impl CaseState {
    /// The word a case's line leads with.
    fn label(self) -> &'static str {
        match self {
            CaseState::Met => "met",
            CaseState::NotMet => "NOT MET",
            CaseState::Stopped => "stopped",
            CaseState::NotRun => "not run",
        }
    }

    fn judged(self) -> bool {
        matches!(self, CaseState::Met | CaseState::NotMet)
    }
}

/// One case run and judged.
struct Judged {
    case: SanityCase,
    state: CaseState,
    verdict: Verdict,
    outcome: Option<Outcome>,
    /// `carus run`'s words for the outcome, and how the run ended.
    outcome_line: String,
    completed: bool,
    failure: Option<String>,
    out_dir: String,
}

/// The changes the cases run with, kept in their folder for `--resume`.
pub(super) const PLAN_FILE: &str = "sanity_plan.json";
/// The cases' verdicts.
pub(super) const RECORD_FILE: &str = "sanity.json";

#[derive(serde::Serialize, serde::Deserialize)]
struct SanityPlan {
    /// The `--set` arguments as given.
    set: Vec<String>,
}

pub fn run(args: &SanityArgs) -> anyhow::Result<Status> {
    let plan = match &args.resume {
        Some(dir) => {
            super::check_resume_dir(dir, "sanity", PLAN_FILE)?;
            let path = dir.join(PLAN_FILE);
            if let Some(kind) = super::folder_kind(dir).filter(|_| !path.exists()) {
                anyhow::bail!("{} holds no sanity cases: {kind}", dir.display());
            }
            let text = carus_io::input::read_text(&path).with_context(|| {
                format!("cannot read {}: --resume takes the folder of `carus sanity` run by this build", path.display())
            })?;
            serde_json::from_str(&text).with_context(|| format!("{} is damaged; run the cases again", path.display()))?
        }
        None => SanityPlan { set: args.settings.clone() },
    };
    let changes = plan.set.iter().map(|text| one_setting(text)).collect::<anyhow::Result<Vec<_>>>()?;
    // Every case's settings are made, and its anatomy and model built,
    // before any runs, so a misspelt key costs nothing and a case that
    // cannot start is judged so without ending the others.
    let scenarios = SanityCase::ALL
        .iter()
        .map(|case| {
            let scenario = Scenario::builtin(case.scenario())?;
            scenario.with_settings(&changes).with_context(|| format!("the {} case", case.scenario()))
        })
        .collect::<anyhow::Result<Vec<Scenario>>>()?;
    let names: Vec<String> = SanityCase::ALL.iter().map(|case| case.scenario().to_string()).collect();
    let cannot_start = check_runs_start(&scenarios, &names, "sanity cases", "its verdict gives the reason")?;
    // The pool is made first: a bad --jobs leaves no out dir behind.
    let (pool, jobs) = labour_pool(args.jobs, scenarios.len())?;
    let out_dir = match &args.resume {
        Some(dir) => dir.clone(),
        None => make_batch_dir(&args.output, "sanity", PLAN_FILE, &plan)?,
    };
    let dirs: Vec<PathBuf> = names.iter().map(|name| out_dir.join(name)).collect();
    if args.resume.is_some() {
        check_runs_match_plan(&out_dir.join(PLAN_FILE), &scenarios, &dirs)?;
    }
    let stop = ctrl_c_flag();
    if !args.output.quiet {
        eprintln!(
            "running the {} sanity cases, {jobs} at a time, into {}",
            scenarios.len(),
            out_dir.display()
        );
    }
    let judged: Vec<Judged> = pool.install(|| {
        (0..scenarios.len())
            .into_par_iter()
            .map(|i| {
                let case = SanityCase::ALL[i];
                if let Some(reason) = &cannot_start[i] {
                    return not_run(case, CaseState::NotRun, &format!("the run cannot start: {reason}"));
                }
                if stop.load(Ordering::Relaxed) {
                    return not_run(case, CaseState::Stopped, "stopped before it started");
                }
                // A run that fails outright is judged so; the others' verdicts are kept.
                judge_case(case, &scenarios[i], &dirs[i], &stop).unwrap_or_else(|e| Judged {
                    out_dir: dirs[i].display().to_string(),
                    outcome_line: "the run failed".into(),
                    verdict: Verdict { met: false, why: format!("the run failed: {e:#}") },
                    ..not_run(case, CaseState::NotMet, "")
                })
            })
            .collect()
    });
    let verdicts = verdicts_json(&judged, &changes, &out_dir);
    let record = out_dir.join(RECORD_FILE);
    std::fs::write(&record, serde_json::to_string_pretty(&verdicts)?)
        .with_context(|| format!("cannot write {}", record.display()))?;
    if args.output.json {
        print_json(&verdicts)?;
    } else {
        for j in &judged {
            println!("{}", case_lines(j));
        }
        println!("{}", count_line(&judged, &changes, &out_dir));
    }
    // A Ctrl-C after the last case that could start ended stops nothing.
    let stopped = judged.iter().any(|j| j.state == CaseState::Stopped);
    if stopped {
        eprintln!("stopped before every case ended; go on with: carus sanity --resume {}", out_dir.display());
    }
    Ok(if judged.iter().all(|j| j.state == CaseState::Met) {
        Status::Success
    } else {
        Status::Failed
    })
}

/// How many cases were judged, met, and left without a verdict.
struct Counts {
    met: usize,
    judged: usize,
    stopped: usize,
    not_run: usize,
}

fn counts(judged: &[Judged]) -> Counts {
    let count = |state| judged.iter().filter(|j| j.state == state).count();
    Counts {
        met: count(CaseState::Met),
        judged: judged.iter().filter(|j| j.state.judged()).count(),
        stopped: count(CaseState::Stopped),
        not_run: count(CaseState::NotRun),
    }
}

/// What `--json` prints and `sanity.json` keeps. A case without a verdict
/// keeps `met: false`, for readers from before `state`; `state` and the
/// top `status` say whether it was judged.
fn verdicts_json(judged: &[Judged], changes: &[(String, String)], out_dir: &Path) -> serde_json::Value {
    let Counts { met, judged: judged_count, stopped, not_run } = counts(judged);
    json!({
        "cases": judged.iter().map(|j| json!({
            "case": j.case,
            "scenario": j.case.scenario(),
            "expected": j.case.expected(),
            "state": j.state,
            "met": j.verdict.met,
            "why": j.verdict.why,
            "outcome": j.outcome,
            "outcome_line": j.outcome_line,
            "completed": j.completed,
            "failure": j.failure,
            "out_dir": j.out_dir,
        })).collect::<Vec<_>>(),
        "met": met,
        "of": judged.len(),
        "judged": judged_count,
        "stopped": stopped,
        "not_run": not_run,
        "status": super::validate::status(met, judged_count - met, stopped + not_run),
        "set": changes.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "out_dir": out_dir.display().to_string(),
    })
}

/// A case's three printed lines: its state, what decided it, the outcome.
fn case_lines(j: &Judged) -> String {
    format!(
        "{:18} {:8} expected: {}\n{:27} found:    {}\n{:27} outcome:  {}",
        j.case.scenario(),
        j.state.label(),
        j.case.expected(),
        "",
        j.verdict.why,
        "",
        j.outcome_line
    )
}

/// The closing count. Cases stopped or not run are no verdict: counted
/// apart, and the whole said incomplete rather than not met, as `carus
/// validate` says of a case it could not run.
fn count_line(judged: &[Judged], changes: &[(String, String)], out_dir: &Path) -> String {
    let Counts { met, judged: judged_count, stopped, not_run } = counts(judged);
    // The changes are part of the verdict: "3 of 4" at another friction is another claim.
    let with = match changes.is_empty() {
        true => String::new(),
        false => format!(" with {}", changes.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")),
    };
    let mut unjudged = Vec::new();
    if stopped > 0 {
        unjudged.push(format!("{stopped} stopped before {} ended", if stopped == 1 { "it" } else { "they" }));
    }
    if not_run > 0 {
        unjudged.push(format!("{not_run} could not start"));
    }
    if unjudged.is_empty() {
        return format!("{met} of {} cases met{with}; runs in {}", judged.len(), out_dir.display());
    }
    // A case judged and not met fails the whole, whatever the rest would show.
    let incomplete = match met == judged_count {
        true => ": incomplete, not passed",
        false => "",
    };
    format!(
        "{met} of {judged_count} judged cases met{with}; {}, not judged{incomplete}; runs in {}",
        unjudged.join(", "),
        out_dir.display()
    )
}

/// Runs one case into `dir` with its report, as `carus run` would (or,
/// resumed, goes on with it), and judges what emerged.
fn judge_case(case: SanityCase, scenario: &Scenario, dir: &Path, stop: &Arc<AtomicBool>) -> anyhow::Result<Judged> {
    let record =
        go_on_into(scenario, dir, stop).with_context(|| format!("sanity case {}", case.scenario()))?;
    let canal = &record.history.canal;
    let outlet_station_mm = (canal.outlet_sigma() - canal.spines_sigma()) * 1000.0;
    let summary = &record.summary;
    // A run that failed or was stopped ended before its outcome did: it
    // meets nothing, whatever its last samples show; a stopped one is not
    // judged at all (`--resume` ends it).
    let stopped = summary.failure.is_none() && !summary.completed;
    let ended_early = match (&summary.failure, summary.completed) {
        (Some(failure), _) => Some(format!("ended early: {failure}")),
        (None, false) => Some(format!("stopped at t = {:.1} s", summary.simulated_s)),
        (None, true) => None,
    };
    let verdict = match (&record.detector, &ended_early) {
        (_, Some(why)) => Verdict {
            met: false,
            why: format!("the run {why}"),
        },
        (Some(report), None) => case.judge(report, outlet_station_mm),
        (None, None) => Verdict {
            met: false,
            why: "nothing could be detected in the run".into(),
        },
    };
    let outcome_line = match &ended_early {
        Some(why) => format!("{}; {why}", outcome_line(&summary.outcome)),
        None => outcome_line(&summary.outcome),
    };
    let state = match (stopped, verdict.met) {
        (true, _) => CaseState::Stopped,
        (false, true) => CaseState::Met,
        (false, false) => CaseState::NotMet,
    };
    Ok(Judged {
        case,
        state,
        verdict,
        outcome: Some(summary.outcome.clone()),
        outcome_line,
        completed: summary.completed,
        failure: summary.failure.clone(),
        out_dir: dir.display().to_string(),
    })
}

/// A case that was not run, or whose run could not be made, and why.
fn not_run(case: SanityCase, state: CaseState, why: &str) -> Judged {
    Judged {
        case,
        state,
        verdict: Verdict {
            met: false,
            why: format!("not run: {why}"),
        },
        outcome: None,
        outcome_line: "not run".into(),
        completed: false,
        failure: None,
        out_dir: String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case whose expected outcome emerges is judged met through the run
    /// it makes: the contracted inlet, coarse, arrests its head at the
    /// inlet (as the labour crate's own coarse test finds). About 6 s.
    #[test]
    fn a_case_whose_outcome_emerges_is_met() {
        let dir = tempfile::tempdir().unwrap();
        let changes: Vec<(String, String)> = [
            "numerics.end_time_s=60.0",
            "numerics.rigid_dt_s=0.001",
            "numerics.head_subdivisions=3",
            "contact.sample_spacing_mm=8.0",
            "floor.mesh.elements_around=16",
            "floor.mesh.elements_across=3",
            "output.vtu=false",
        ]
        .iter()
        .map(|text| one_setting(text).unwrap())
        .collect();
        let case = SanityCase::ContractedInlet;
        let scenario = Scenario::builtin(case.scenario()).unwrap().with_settings(&changes).unwrap();
        let judged = judge_case(case, &scenario, dir.path(), &Arc::new(AtomicBool::new(false))).unwrap();
        assert!(judged.verdict.met, "{}", judged.verdict.why);
        assert!(judged.completed && judged.failure.is_none());
        let arrest = judged.outcome.as_ref().and_then(|o| o.arrest.as_ref()).expect("arrested");
        assert_eq!(arrest.stage, carus_analysis::ArrestStage::Inlet);
        assert!(judged.outcome_line.contains("inlet"), "{}", judged.outcome_line);
        assert!(dir.path().join("report.html").is_file());
    }

    /// A case whose run is stopped (Ctrl-C) before it ends has no verdict:
    /// it is stopped, not "not met", whatever its samples so far show.
    #[test]
    fn a_case_stopped_before_its_run_ended_is_not_judged() {
        let dir = tempfile::tempdir().unwrap();
        let changes: Vec<(String, String)> =
            ["numerics.head_subdivisions=3", "contact.sample_spacing_mm=8.0", "floor.mesh.elements_around=16", "floor.mesh.elements_across=3", "output.vtu=false"]
                .iter()
                .map(|text| one_setting(text).unwrap())
                .collect();
        let case = SanityCase::Normal;
        let scenario = Scenario::builtin(case.scenario()).unwrap().with_settings(&changes).unwrap();
        let judged = judge_case(case, &scenario, dir.path(), &Arc::new(AtomicBool::new(true))).unwrap();
        assert_eq!(judged.state, CaseState::Stopped);
        assert!(!judged.verdict.met && !judged.completed && judged.failure.is_none());
        assert!(judged.verdict.why.contains("stopped at t = 0.0 s"), "{}", judged.verdict.why);
        assert!(case_lines(&judged).starts_with("normal             stopped  expected:"), "{}", case_lines(&judged));
    }

    /// Cases stopped before they ended are counted apart from the judged
    /// ones, and sanity.json says so of each (keeping `met: false`): the
    /// whole is incomplete, not failed, unless a judged case is not met.
    #[test]
    fn stopped_cases_are_counted_apart_from_the_judged() {
        let out = Path::new("runs/sanity-1");
        let judged_as = |state: CaseState| Judged {
            verdict: Verdict { met: state == CaseState::Met, why: "delivered".into() },
            completed: true,
            ..not_run(SanityCase::Normal, state, "")
        };
        let mut judged: Vec<Judged> = std::iter::once(judged_as(CaseState::Met))
            .chain(SanityCase::ALL[1..].iter().map(|&case| not_run(case, CaseState::Stopped, "stopped before it started")))
            .collect();
        let record = verdicts_json(&judged, &[], out);
        let figures = ["met", "of", "judged", "stopped", "not_run"].map(|key| record[key].as_u64().unwrap());
        assert_eq!((figures, record["status"].as_str()), ([1, 4, 1, 3, 0], Some("incomplete")));
        let cases = record["cases"].as_array().unwrap();
        assert_eq!((cases[0]["state"].as_str(), cases[0]["met"].as_bool()), (Some("met"), Some(true)));
        assert!(cases[1..].iter().all(|c| c["state"] == json!("stopped") && c["met"] == json!(false)), "{record}");
        assert_eq!(
            count_line(&judged, &[], out),
            "1 of 1 judged cases met; 3 stopped before they ended, not judged: incomplete, not passed; runs in runs/sanity-1"
        );
        assert!(case_lines(&judged[1]).starts_with("contracted-inlet   stopped  expected:"), "{}", case_lines(&judged[1]));
        assert!(!case_lines(&judged[1]).contains("NOT MET"));
        // A judged case not met fails the whole, stopped cases or not.
        judged[0] = judged_as(CaseState::NotMet);
        judged[3] = not_run(SanityCase::LargeShoulders, CaseState::NotRun, "the run cannot start: no pelvis");
        assert_eq!(verdicts_json(&judged, &[], out)["status"], json!("fail"));
        let changes = [("contact.friction".to_string(), "0.35".to_string())];
        assert_eq!(
            count_line(&judged, &changes, out),
            "0 of 1 judged cases met with contact.friction=0.35; 2 stopped before they ended, 1 could not start, not judged; \
             runs in runs/sanity-1"
        );
        // Every case judged: the count as it always was.
        let all: Vec<Judged> = SanityCase::ALL.iter().map(|_| judged_as(CaseState::Met)).collect();
        assert_eq!(count_line(&all, &[], out), "4 of 4 cases met; runs in runs/sanity-1");
        assert_eq!(verdicts_json(&all, &[], out)["status"], json!("pass"));
    }

    /// The four cases run (cut to a fifth of a second and made coarse
    /// through --set, so nothing can deliver) into their own folders, and
    /// none is met: the command reports failure rather than success.
    #[test]
    fn the_cases_run_in_their_folders_and_an_unmet_bar_fails() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("sanity");
        let args = SanityArgs {
            settings: [
                "numerics.end_time_s=0.2",
                "numerics.head_subdivisions=3",
                "contact.sample_spacing_mm=8.0",
                "floor.mesh.elements_around=16",
                "floor.mesh.elements_across=3",
                "output.vtu=false",
            ]
            .map(String::from)
            .to_vec(),
            resume: None,
            jobs: Some(2),
            output: OutputArgs {
                out: Some(out.clone()),
                json: true,
                force: false,
                quiet: true,
            },
        };
        assert!(matches!(run(&args).unwrap(), Status::Failed));
        for case in SanityCase::ALL {
            let dir = out.join(case.scenario());
            let record: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.join("movements.json")).unwrap()).unwrap();
            // A fifth of a second delivers nothing and arrests nothing.
            assert_eq!(record["outcome"]["delivered"], json!(false), "{}", case.scenario());
            assert!(record["outcome"]["arrest"].is_null(), "{}", case.scenario());
        }
        let verdicts: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("sanity.json")).unwrap()).unwrap();
        assert_eq!((verdicts["met"].clone(), verdicts["of"].clone()), (json!(0), json!(4)));
        // --force knows every file sanity writes.
        assert_eq!(super::super::run::foreign_entries(&out).unwrap(), Vec::<std::path::PathBuf>::new());
        for case in SanityCase::ALL {
            let toml = std::fs::read_to_string(out.join(case.scenario()).join("scenario.toml")).unwrap();
            assert!(toml.contains("end_time_s = 0.2"), "{}", case.scenario());
        }

        // As Ctrl-C would leave them: the face stopped part way, the large
        // shoulders not begun. --resume ends both as before, with the
        // changes the cases started with.
        let history = |case: &str| std::fs::read_to_string(out.join(case).join("pose_history.csv")).unwrap();
        let whole = [history("face"), history("large-shoulders")];
        let face = out.join("face");
        std::fs::remove_dir_all(&face).unwrap();
        std::fs::remove_dir_all(out.join("large-shoulders")).unwrap();
        std::fs::create_dir(&face).unwrap();
        let changes: Vec<(String, String)> = args.settings.iter().map(|text| one_setting(text).unwrap()).collect();
        let scenario = Scenario::builtin("face").unwrap().with_settings(&changes).unwrap();
        let stop = carus_labour::RunOptions { stop_at_s: Some(0.1), ..Default::default() };
        carus_labour::run(&scenario, &face, &stop, &mut carus_labour::SilentObserver).unwrap();
        let resume = SanityArgs {
            settings: Vec::new(),
            resume: Some(out.clone()),
            output: OutputArgs { out: None, ..args.output },
            ..args
        };
        assert!(matches!(run(&resume).unwrap(), Status::Failed));
        assert_eq!([history("face"), history("large-shoulders")], whole);
        let verdicts: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("sanity.json")).unwrap()).unwrap();
        assert_eq!((verdicts["met"].clone(), verdicts["of"].clone()), (json!(0), json!(4)));
        assert!(verdicts["cases"].as_array().unwrap().iter().all(|c| c["completed"] == json!(true)), "{verdicts}");
        let args = SanityArgs { resume: None, settings: resume.settings.clone(), ..resume };
        // Several values for one key belong to a sweep.
        let several = SanityArgs {
            settings: vec!["contact.friction=0.1,0.35".into()],
            output: OutputArgs {
                out: Some(dir.path().join("several")),
                ..args.output
            },
            ..args
        };
        let e = run(&several).expect_err("refused").to_string();
        assert!(e.contains("one value per key") && e.contains("carus sweep"), "{e}");
        assert!(!dir.path().join("several").exists());
    }

    /// A change that leaves some cases without an anatomy judges those "not
    /// run" and still runs the others; the verdicts are all written.
    #[test]
    fn a_case_that_cannot_start_is_judged_so_and_the_others_run() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("sanity");
        let args = SanityArgs {
            settings: [
                "numerics.end_time_s=0.05",
                "numerics.head_subdivisions=3",
                "contact.sample_spacing_mm=8.0",
                "floor.mesh.elements_around=16",
                "floor.mesh.elements_across=3",
                "output.vtu=false",
                // Below the default inlet's antero-posterior 110 mm: only the contracted inlet, whose own is shorter, keeps a pelvis.
                "pelvis.inlet_oblique_mm=106",
            ]
            .map(String::from)
            .to_vec(),
            resume: None,
            jobs: Some(2),
            output: OutputArgs { out: Some(out.clone()), json: true, force: false, quiet: true },
        };
        assert!(matches!(run(&args).unwrap(), Status::Failed));
        let verdicts: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("sanity.json")).unwrap()).unwrap();
        for case in verdicts["cases"].as_array().unwrap() {
            let why = case["why"].as_str().unwrap();
            match case["scenario"].as_str().unwrap() {
                "contracted-inlet" => assert!(case["completed"] == json!(true) && !why.starts_with("not run"), "{case}"),
                _ => assert!(
                    case["state"] == json!("not_run") && why.starts_with("not run: the run cannot start") && why.contains("inlet_oblique_mm"),
                    "{case}"
                ),
            }
        }
        assert_eq!((verdicts["judged"].clone(), verdicts["not_run"].clone()), (json!(1), json!(3)));
        assert!(out.join("contracted-inlet").join("movements.json").is_file());
        assert!(!out.join("normal").exists());
    }
}
