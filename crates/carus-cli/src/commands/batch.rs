//! Several labour runs in one folder (`carus sweep`, `carus sanity`):
//! checked before any runs, and resumed only as they were planned.

use std::path::{Path, PathBuf};

use anyhow::bail;
use carus_labour::{Scenario, Scene, Simulation};

/// Builds every run's anatomy and model before any runs, so one that
/// cannot start (diameters that make no pelvis, say) is named now rather
/// than when its turn comes, hours into a long batch. Returns why each
/// cannot start (`None` for those that can), warning of each with where
/// the `batch` will `report` it; a batch in which none can start is
/// refused.
pub(super) fn check_runs_start(scenarios: &[Scenario], names: &[String], batch: &str, report: &str) -> anyhow::Result<Vec<Option<String>>> {
    let reasons: Vec<Option<String>> = scenarios
        .iter()
        .map(|scenario| Scene::build(scenario).and_then(|scene| Simulation::new(&scene).map(drop)).err().map(|e| e.to_string()))
        .collect();
    let failures: Vec<String> =
        names.iter().zip(&reasons).filter_map(|(name, reason)| reason.as_ref().map(|r| format!("{name}: {r}"))).collect();
    if !failures.is_empty() && failures.len() == scenarios.len() {
        bail!("no run of the {batch} can start:\n  {}", failures.join("\n  "));
    }
    for failure in &failures {
        eprintln!("warning: {failure}\n  this run will not start; {report}");
    }
    Ok(reasons)
}

/// A resumed batch keeps its finished runs and goes on with its stopped
/// ones, each as it started; a plan (`plan`, in the batch's folder)
/// edited since would label them with settings they did not run with, so
/// it is refused, naming the run.
pub(super) fn check_runs_match_plan(plan: &Path, scenarios: &[Scenario], dirs: &[PathBuf]) -> anyhow::Result<()> {
    let edited = |what: String| {
        anyhow::anyhow!(
            "{what}: {} was changed since the runs started, and --resume goes on with them as they were \
             planned; undo the change, or run them from the start with a new --out",
            plan.display()
        )
    };
    for (scenario, dir) in scenarios.iter().zip(dirs) {
        let path = dir.join(carus_labour::output::SCENARIO_FILE);
        let Ok(text) = carus_io::input::read_text(&path) else {
            continue;
        };
        let ran = Scenario::parse(&path, &text, scenario.base_dir.clone())?;
        if ran.to_toml()? != scenario.to_toml()? {
            return Err(edited(format!("{} ran another scenario than the plan now makes", dir.display())));
        }
    }
    let out_dir = plan.parent().unwrap_or(Path::new("."));
    let entries = std::fs::read_dir(out_dir).map_err(|e| anyhow::anyhow!("cannot list {}: {e}", out_dir.display()))?;
    for entry in entries.flatten() {
        let path = entry.path();
        if path.join(carus_labour::output::SCENARIO_FILE).is_file() && !dirs.contains(&path) {
            return Err(edited(format!("{} is a run the plan no longer makes", path.display())));
        }
    }
    Ok(())
}
