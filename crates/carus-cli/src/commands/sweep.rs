//! `carus sweep [NAME|FILE] --set KEY=V1,V2,... [--set ...] [--with KEY=VALUE
//! ...] [--one-at-a-time] [--allow-large] [--out DIR] [--jobs N] [--json]
//! [--force] [--quiet]`: one labour run per combination of the values given (every
//! combination of every `--set`, or with `--one-at-a-time` the scenario as
//! it is and then each value of each key alone; `--with` sets a key in
//! every run), each a whole run in its own folder, and a table of their outcomes and movements
//! (sweep.csv, sweep.json) rewritten as each run ends, so Ctrl-C or a
//! failed run loses none that finished. `carus sweep --resume DIR` goes on
//! with a stopped sweep from its plan (sweep_plan.json): runs stopped part
//! way continue from their checkpoints, runs not started start, and the
//! tables are written whole again. The parameter studies of docs/LABOUR.md
//! are sweeps.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use anyhow::Context;
use carus_io::toml_text::holds_key;
use carus_analysis::movements::ROTATION_STATION_MAX_MM;
use carus_analysis::{Movements, Outcome};
use carus_labour::record::RunSummary;
use carus_labour::{RunRecord, Scenario};
use rayon::prelude::*;
use serde_json::json;

use super::batch::{check_runs_match_plan, check_runs_start};
use super::run::{
    go_on_into, json_summary, json_summary_not_run, load_mended, make_batch_dir, movements, outcome_line, read_record, run_ended, serde_name,
    OutputArgs,
};
use super::settings::{fixed_setting, fixed_setting_arg, parse_setting, setting_arg, Setting};
use super::{ctrl_c_flag, labour_pool, print_json, Status};

#[derive(clap::Args)]
pub struct SweepArgs {
    /// A built-in scenario name (`carus scenarios`) or a scenario file (TOML). Default: normal.
    #[arg(conflicts_with = "resume")]
    pub scenario: Option<String>,
    /// KEY=V1,V2,...: a dotted key as `carus scenarios show` writes it and
    /// the values to run it at (TOML values; repeat for more keys: every
    /// combination runs).
    #[arg(
        long = "set",
        value_name = "KEY=VALUES",
        required_unless_present = "resume",
        conflicts_with = "resume",
        value_parser = setting_arg
    )]
    pub settings: Vec<String>,
    /// KEY=VALUE set in every run, the first (unchanged) run of
    /// --one-at-a-time included (e.g. output.vtu=false); repeat for more keys.
    #[arg(long = "with", value_name = "KEY=VALUE", conflicts_with = "resume", value_parser = fixed_setting_arg)]
    pub with: Vec<String>,
    /// Go on with the stopped sweep in DIR, as it was planned: runs
    /// stopped part way continue from their checkpoints, runs not started
    /// start, finished ones are kept; the tables are written whole again.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["one_at_a_time", "out", "force"])]
    pub resume: Option<PathBuf>,
    /// Run the scenario as it is, then each value of each key alone with the
    /// other keys as the scenario has them (a one-at-a-time sensitivity
    /// study), instead of every combination.
    #[arg(long)]
    pub one_at_a_time: bool,
    /// Runs at a time; default one per core.
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Run a sweep of more than 1000 runs, which is refused without it
    /// (at about 30 s a run per core, a long list of values would take
    /// days and make a folder per run).
    #[arg(long, conflicts_with = "resume")]
    pub allow_large: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The most runs a sweep makes without `--allow-large`: a day's work for
/// a few cores, past which a list of values is more likely a slip.
const MOST_RUNS: usize = 1000;

/// Wall-clock seconds of the normal scenario's run on one core, for the
/// estimate a refused sweep gives.
const RUN_S_PER_CORE: f64 = 30.0;

/// The runs a new sweep would make: the product of the values' counts, or
/// with `one_at_a_time` the base and each value; None past counting.
fn planned_runs(settings: &[Setting], one_at_a_time: bool) -> Option<usize> {
    match one_at_a_time {
        true => settings.iter().try_fold(1usize, |n, s| n.checked_add(s.values.len())),
        false => settings.iter().try_fold(1usize, |n, s| n.checked_mul(s.values.len())),
    }
}

/// Refuses a new sweep of more than [`MOST_RUNS`] runs unless
/// `--allow-large` is given, before anything is checked or made: the
/// count, what it would cost, and the ways out. One too large to count is
/// refused even so.
fn check_sweep_size(args: &SweepArgs) -> anyhow::Result<()> {
    let settings = args.settings.iter().map(|s| parse_setting(s)).collect::<anyhow::Result<Vec<_>>>()?;
    let runs = planned_runs(&settings, args.one_at_a_time);
    if runs.is_some_and(|n| n <= MOST_RUNS || args.allow_large) {
        return Ok(());
    }
    let counts: Vec<String> = settings.iter().map(|s| format!("{} values of {}", s.values.len(), s.key)).collect();
    let Some(runs) = runs else {
        crate::bad_argument!("this sweep would make more runs than can be counted ({}, every combination); give fewer values", counts.join(" x "));
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let at_once = args.jobs.unwrap_or(cores).clamp(1, cores);
    let hours = runs as f64 * RUN_S_PER_CORE / at_once as f64 / 3600.0;
    let cores_said = if at_once == 1 { "1 core".to_string() } else { format!("{at_once} cores") };
    let took = match hours {
        h if h < 1.0 => format!("{:.0} minutes", h * 60.0),
        h if h < 48.0 => format!("{h:.0} hours"),
        h => format!("{:.0} days", h / 24.0),
    };
    let how = match args.one_at_a_time {
        true => format!("the base and {}", counts.join(", ")),
        false => format!("{}, every combination", counts.join(" x ")),
    };
    let alone = planned_runs(&settings, true).map_or(String::new(), |n| format!(" ({n} runs)"));
    let instead = match args.one_at_a_time {
        true => "give fewer values".to_string(),
        false => format!("give fewer values, or vary one key at a time with --one-at-a-time{alone}"),
    };
    crate::bad_argument!(
        "this sweep makes {runs} runs ({how}), more than the {MOST_RUNS} a sweep makes unasked: at about \
         {RUN_S_PER_CORE:.0} s a run per core (the normal scenario's), about {took} on {cores_said}, and a folder \
         per run; {instead}; or, to run them all, add --allow-large"
    )
}

/// The first key that two `--set`s name.
fn key_given_twice(settings: &[Setting]) -> Option<&str> {
    settings
        .iter()
        .enumerate()
        .find(|&(i, s)| settings[..i].iter().any(|earlier| earlier.key == s.key))
        .map(|(_, s)| s.key.as_str())
}

/// The scenario a new sweep varies, with its `--with` settings. A file
/// refused for a value that every run sets (a `--with` key, or a full
/// sweep of that key) is read again with that value (a swept key's first),
/// so that it mends the file as `carus run --set` does; each run then sets
/// its own value. A one-at-a-time sweep runs the file as it is first, so
/// its swept keys mend nothing.
fn load_base(args: &SweepArgs) -> anyhow::Result<Scenario> {
    let settings = args.settings.iter().map(|s| parse_setting(s)).collect::<anyhow::Result<Vec<_>>>()?;
    let with = args.with.iter().map(|s| fixed_setting(s)).collect::<anyhow::Result<Vec<_>>>()?;
    // One key, or a table or list and a key in it.
    let overlap = |a: &str, b: &str| holds_key(a, b) || holds_key(b, a);
    for (i, (key, _)) in with.iter().enumerate() {
        if let Some((earlier, _)) = with[..i].iter().find(|(k, _)| overlap(k, key)) {
            crate::bad_argument!("--with {earlier} and --with {key} set one key twice; a key set in every run takes one value");
        }
        if let Some(swept) = settings.iter().find(|s| overlap(&s.key, key)) {
            crate::bad_argument!("--with {key} and --set {} change one key; --with sets it in every run, --set sweeps it: keep one", swept.key);
        }
    }
    let mut every_run = with.clone();
    if !args.one_at_a_time {
        every_run.extend(settings.iter().map(|s| (s.key.clone(), s.values[0].clone())));
    }
    // A mended file was read with every run's settings made already.
    match load_mended(args.scenario.as_deref(), &every_run)? {
        (base, true) => Ok(base),
        (base, false) => Ok(base.with_settings(&with)?),
    }
}

/// A plan written by an older build, before a key its runs now take by
/// default, would finish with runs of another model than the ones done:
/// refused, naming the key, unless its default is the old model for every
/// run (carus_labour::run::keys_missing) or the sweep sets it.
fn check_plan_keeps_the_model(
    dir: &Path,
    planned: &str,
    scenarios: &[Scenario],
    combinations: &[Vec<(String, String)>],
) -> anyhow::Result<()> {
    for (scenario, combination) in scenarios.iter().zip(combinations) {
        let missing: Vec<String> = carus_labour::run::keys_missing(planned, scenario)?
            .into_iter()
            .filter(|key| !combination.iter().any(|(set, _)| holds_key(set, key)))
            .collect();
        if !missing.is_empty() {
            anyhow::bail!(
                "{}: the sweep was planned by an older carus, before {} existed; its runs not yet done \
                 would take the default and so another model than the runs done; start the sweep again \
                 (carus sweep ... --out NEW_FOLDER)",
                dir.join(PLAN_FILE).display(),
                missing.join(", ")
            );
        }
    }
    Ok(())
}

/// Every combination of the settings' values, the first setting varying slowest.
fn combinations(settings: &[Setting]) -> Vec<Vec<(String, String)>> {
    settings.iter().fold(vec![Vec::new()], |acc, s| {
        acc.iter()
            .flat_map(|prefix| {
                s.values.iter().map(move |v| {
                    let mut c = prefix.clone();
                    c.push((s.key.clone(), v.clone()));
                    c
                })
            })
            .collect()
    })
}

/// The scenario unchanged (no setting), then every value of every setting
/// alone, in the order given.
fn one_at_a_time(settings: &[Setting]) -> Vec<Vec<(String, String)>> {
    std::iter::once(Vec::new())
        .chain(
            settings
                .iter()
                .flat_map(|s| s.values.iter().map(|v| vec![(s.key.clone(), v.clone())])),
        )
        .collect()
}

/// A variant's folder name spelled out: its number and every setting
/// (`base` for none), in characters any file system takes. Sweeps made
/// before the plan kept its folders' names were named so, whole.
fn spelled_name(index: usize, combination: &[(String, String)]) -> String {
    if combination.is_empty() {
        return format!("{:02}-base", index + 1);
    }
    let settings: Vec<String> = combination.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{:02}-{}", index + 1, file_characters(&settings.join("_")))
}

/// `text` with every character a file name may not hold made `-`.
fn file_characters(text: &str) -> String {
    text.chars().map(|c| if c.is_ascii_alphanumeric() || "._=+-".contains(c) { c } else { '-' }).collect()
}

/// A variant's folder name: [`spelled_name`] where it fits in
/// [`FOLDER_NAME_MAX`] characters (a file name may have 255 bytes);
/// otherwise the settings that differ between runs (`varying`) first,
/// as many whole ones as fit (or the first cut short), tagged with a
/// checksum of the whole name. The run's scenario.toml and the tables give
/// the settings whole.
fn folder_name(index: usize, combination: &[(String, String)], varying: &[&str]) -> String {
    let spelled = spelled_name(index, combination);
    if spelled.len() <= FOLDER_NAME_MAX {
        return spelled;
    }
    let tag = crc32fast::hash(spelled.as_bytes());
    let (first, rest): (Vec<_>, Vec<_>) = combination.iter().partition(|(k, _)| varying.contains(&k.as_str()));
    let room = FOLDER_NAME_MAX - 9;
    let mut name = format!("{:02}", index + 1);
    for (i, (key, value)) in first.into_iter().chain(rest).enumerate() {
        let part = file_characters(&format!("{}{key}={value}", if i == 0 { "-" } else { "_" }));
        if name.len() + part.len() > room {
            // Every character is ASCII, so any cut is on a boundary.
            if i == 0 {
                name.push_str(&part[..room - name.len()]);
            }
            break;
        }
        name.push_str(&part);
    }
    format!("{name}-{tag:08x}")
}

/// The most characters of a run's folder name.
const FOLDER_NAME_MAX: usize = 120;

/// The finished run of one variant, as the table reports it.
struct Finished {
    summary: serde_json::Value,
    row: Vec<String>,
}

/// What a sweep runs, kept in its folder (sweep_plan.json) so that
/// `--resume` goes on with the same variants in the same folders.
#[derive(serde::Serialize, serde::Deserialize)]
struct SweepPlan {
    /// The base scenario, complete (`Scenario::to_toml`).
    scenario_toml: String,
    /// Where the base scenario's relative paths are read from.
    base_dir: PathBuf,
    /// The `--set` arguments as given.
    set: Vec<String>,
    one_at_a_time: bool,
    /// Each run's folder, in the order of the runs (empty in the plans of
    /// sweeps made before it was kept: their folders are spelled out whole).
    #[serde(default)]
    folders: Vec<String>,
}

pub(super) const PLAN_FILE: &str = "sweep_plan.json";
/// The sweep's tables: one row per run.
pub(super) const CSV_FILE: &str = "sweep.csv";
pub(super) const JSON_FILE: &str = "sweep.json";

pub fn run(args: &SweepArgs) -> anyhow::Result<Status> {
    let (mut plan, base, out_dir) = match &args.resume {
        Some(dir) => {
            let plan = read_plan(dir)?;
            let base = Scenario::parse_kept(&dir.join(PLAN_FILE), &plan.scenario_toml, plan.base_dir.clone())
                .with_context(|| damaged_plan(dir))?;
            (plan, base, Some(dir.clone()))
        }
        None => {
            // A sweep too large is refused before its scenario is read.
            check_sweep_size(args)?;
            let base = load_base(args)?;
            let plan = SweepPlan {
                scenario_toml: base.to_toml()?,
                base_dir: base.base_dir.clone(),
                set: args.settings.clone(),
                one_at_a_time: args.one_at_a_time,
                folders: Vec::new(),
            };
            (plan, base, None)
        }
    };
    // What a resumed sweep reads from its plan, a damaged plan is to blame for.
    let from_plan = |e: anyhow::Error| match &args.resume {
        Some(dir) => e.context(damaged_plan(dir)),
        None => e,
    };
    let settings = plan
        .set
        .iter()
        .map(|s| parse_setting(s))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(from_plan)?;
    if let Some(key) = key_given_twice(&settings) {
        let twice = format!("--set {key} is given twice; list all its values in one --set, e.g. --set {key}=1,2");
        match &args.resume {
            Some(_) => return Err(from_plan(anyhow::anyhow!(twice))),
            None => crate::bad_argument!("{twice}"),
        }
    }
    let combinations = if plan.one_at_a_time {
        one_at_a_time(&settings)
    } else {
        combinations(&settings)
    };
    // Every variant is checked before any runs, so a typo costs nothing;
    // building each one's anatomy takes a moment, so a big sweep says so.
    if !args.output.quiet && combinations.len() > 1 {
        eprintln!("checking that each of the {} runs can start", combinations.len());
    }
    let scenarios = combinations
        .iter()
        .map(|c| base.with_settings(c))
        .collect::<Result<Vec<Scenario>, _>>()
        .map_err(|e| from_plan(e.into()))?;
    if let Some(dir) = &args.resume {
        check_plan_keeps_the_model(dir, &plan.scenario_toml, &scenarios, &combinations)?;
    }
    let varying: Vec<&str> = settings.iter().filter(|s| s.values.len() > 1).map(|s| s.key.as_str()).collect();
    // A new sweep names its folders in its plan; an older plan kept none,
    // and its folders were spelled out whole.
    match (&args.resume, plan.folders.is_empty()) {
        (None, _) => plan.folders = combinations.iter().enumerate().map(|(i, c)| folder_name(i, c, &varying)).collect(),
        (Some(_), true) => plan.folders = combinations.iter().enumerate().map(|(i, c)| spelled_name(i, c)).collect(),
        (Some(_), false) if plan.folders.len() == combinations.len() => {}
        (Some(_), false) => return Err(from_plan(anyhow::anyhow!("it names {} folders for {} runs", plan.folders.len(), combinations.len()))),
    }
    let names = &plan.folders;
    check_runs_start(&scenarios, names, "sweep", "its row in the table gives the reason")?;
    // The pool is made first: a bad --jobs leaves no out dir behind.
    let (pool, jobs) = labour_pool(args.jobs, scenarios.len())?;
    let out_dir = match out_dir {
        Some(dir) => dir,
        None => make_batch_dir(&args.output, &format!("sweep-{}", base.name), PLAN_FILE, &plan)?,
    };
    let stop = ctrl_c_flag();
    if !args.output.quiet {
        let verb = if args.resume.is_some() { "going on with the sweep of" } else { "sweeping" };
        eprintln!(
            "{verb} `{}` over {} runs, {jobs} at a time, in {}",
            base.name,
            scenarios.len(),
            out_dir.display()
        );
    }
    let keys: Vec<&str> = settings.iter().map(|s| s.key.as_str()).collect();
    let dirs: Vec<PathBuf> = names.iter().map(|name| out_dir.join(name)).collect();
    if args.resume.is_some() {
        check_runs_match_plan(&out_dir.join(PLAN_FILE), &scenarios, &dirs)?;
    }
    let variant = |i: usize| Variant { scenario: &scenarios[i], dir: &dirs[i], keys: &keys, combination: &combinations[i] };
    // A resumed sweep's ended runs are rows from the start, so the tables
    // written as the others end (or are stopped again) keep them; a new
    // sweep's folders do not exist yet.
    let kept: Vec<Option<Finished>> = (0..scenarios.len())
        .map(|i| {
            let v = variant(i);
            run_ended(v.dir).then(|| v.kept().unwrap_or_else(|error| unmade(v.dir, v.combination, &keys, &error)))
        })
        .collect();
    let to_run: Vec<usize> = (0..kept.len()).filter(|&i| kept[i].is_none()).collect();
    let table = Mutex::new(kept);
    let failures = pool.install(|| {
        to_run
            .into_par_iter()
            .map(|i| {
                if stop.load(Ordering::Relaxed) {
                    return Ok(false);
                }
                let dir = &dirs[i];
                // A run that cannot be made is a row of the table, not the end of the sweep.
                let finished = variant(i)
                    .finish(&stop, args.output.quiet)
                    .unwrap_or_else(|error| unmade(dir, &combinations[i], &keys, &error));
                let failed = finished.summary["failure"].is_string();
                let mut rows = table.lock().expect("no run panics while holding the table");
                rows[i] = Some(finished);
                write_table(&out_dir, &keys, &rows)?;
                Ok(failed)
            })
            .collect::<anyhow::Result<Vec<bool>>>()
    })?;
    let rows = table.into_inner().expect("no run panics while holding the table");
    write_table(&out_dir, &keys, &rows)?;
    let done = rows
        .iter()
        .flatten()
        .filter(|r| r.summary["completed"] == json!(true))
        .count();
    if args.output.json {
        print_json(&sweep_json(&out_dir, &keys, &rows))?;
    } else {
        print_table(&keys, &rows);
        println!("results in {} (sweep.csv, sweep.json, one folder per run)", out_dir.display());
    }
    // A Ctrl-C after the last run finished stops nothing.
    if stop.load(Ordering::Relaxed) && done < rows.len() {
        eprintln!(
            "stopped with {done} of {} runs complete; go on with: carus sweep --resume {}",
            rows.len(),
            out_dir.display()
        );
    }
    Ok(if failures.iter().any(|&f| f) || done < rows.len() {
        Status::Failed
    } else {
        Status::Success
    })
}

/// What to do when the plan a sweep kept no longer reads.
fn damaged_plan(dir: &Path) -> String {
    format!(
        "{} is damaged (what it keeps of the sweep's scenario or --set values does not read); run the \
         sweep again with a new --out",
        dir.join(PLAN_FILE).display()
    )
}

/// The sweep's plan in `dir`, with what to do when it is not there.
fn read_plan(dir: &Path) -> anyhow::Result<SweepPlan> {
    super::check_resume_dir(dir, "sweep", PLAN_FILE)?;
    let path = dir.join(PLAN_FILE);
    if let Some(kind) = super::folder_kind(dir).filter(|_| !path.exists()) {
        anyhow::bail!("{} holds no sweep: {kind}", dir.display());
    }
    let text = carus_io::input::read_text(&path).with_context(|| {
        format!(
            "cannot read {}: --resume takes the folder of a sweep this build of carus made (older sweeps \
             have no plan: run their stopped runs with carus run --resume on each run's folder)",
            path.display()
        )
    })?;
    serde_json::from_str(&text).with_context(|| format!("{} is damaged; run the sweep again", path.display()))
}

/// One variant of the sweep and the folder it runs in.
struct Variant<'a> {
    scenario: &'a Scenario,
    dir: &'a Path,
    keys: &'a [&'a str],
    combination: &'a [(String, String)],
}

impl Variant<'_> {
    /// The row of a run that has ended, read from its run.json.
    fn kept(&self) -> anyhow::Result<Finished> {
        Ok(self.row(&read_record(self.dir)?))
    }

    /// Runs the variant with its report, as `carus run` would, or goes on
    /// with it where a resumed sweep stopped it part way (ended ones are
    /// [`Variant::kept`]).
    fn finish(&self, stop: &Arc<AtomicBool>, quiet: bool) -> anyhow::Result<Finished> {
        let dir = self.dir;
        let record = go_on_into(self.scenario, dir, stop)?;
        if !quiet {
            let note = record.summary.failure.as_deref().map_or(String::new(), |f| format!(": {f}"));
            let verb = state(&record.summary);
            eprintln!("{verb} {} in {:.0} s{note}", dir.display(), record.summary.wall_s);
        }
        Ok(self.row(&record))
    }

    /// The run's row of both tables.
    fn row(&self, record: &RunRecord) -> Finished {
        let mut summary = json_summary(record, self.dir);
        summary["set"] = set_json(self.combination);
        summary["at_station_50mm"] = at_window_end(record);
        let row = table_row(record, self.dir, self.keys, self.combination, &summary);
        Finished { summary, row }
    }
}

/// A variant's settings as a JSON object, key to value as given.
fn set_json(combination: &[(String, String)]) -> serde_json::Value {
    combination
        .iter()
        .map(|(k, v)| (k.clone(), json!(v)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// Each key's value in a variant, in the keys' order; empty where the
/// variant leaves the key as the scenario has it (one at a time).
fn set_values(keys: &[&str], combination: &[(String, String)]) -> Vec<String> {
    keys.iter()
        .map(|k| {
            combination
                .iter()
                .find(|(key, _)| key == k)
                .map_or(String::new(), |(_, v)| v.clone())
        })
        .collect()
}

/// The row of a variant whose run could not be made (its folder not
/// writable, say): the settings and why.
fn unmade(dir: &Path, combination: &[(String, String)], keys: &[&str], error: &anyhow::Error) -> Finished {
    let why = format!("{error:#}");
    let columns = header(keys);
    let mut row = vec![String::new(); columns.len()];
    row[0] = dir.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
    for (k, v) in set_values(keys, combination).into_iter().enumerate() {
        row[k + 1] = v;
    }
    for (column, value) in [("completed", "false"), ("failure", why.as_str()), ("state", "not run")] {
        if let Some(i) = columns.iter().position(|c| c == column) {
            row[i] = value.to_string();
        }
    }
    let mut summary = json_summary_not_run(dir, &why);
    summary["set"] = set_json(combination);
    summary["at_station_50mm"] = serde_json::Value::Null;
    Finished { summary, row }
}

/// Where the head was turned when its leading point first reached station
/// +50 mm, where CARDINAL_MOVEMENTS.md's window for internal rotation
/// closes, or null if it never did: theta (CARDINAL_MOVEMENTS.md), the
/// head's twist about the canal and the occiput's tilt, which says whether
/// theta can be trusted there (docs/DETECTOR.md).
fn at_window_end(record: &RunRecord) -> serde_json::Value {
    let Some(series) = record.detector.as_ref().map(|d| &d.series) else {
        return serde_json::Value::Null;
    };
    series
        .station_mm
        .iter()
        .position(|&s| s >= ROTATION_STATION_MAX_MM)
        .map_or(serde_json::Value::Null, |k| {
            json!({
                "time_s": series.time_s[k],
                "theta_deg": series.theta_deg[k],
                "head_twist_deg": series.head_twist_deg[k],
                "occiput_tilt_deg": series.occiput_tilt_deg[k],
            })
        })
}

/// sweep.csv's columns: the run, each setting, the outcome, each movement
/// under its canonical key and unit (in the detector's order, the order
/// `table_row` writes them), then the rest.
fn header(keys: &[&str]) -> Vec<String> {
    let mut h = vec!["run".to_string()];
    h.extend(keys.iter().map(|k| k.to_string()));
    h.extend(["delivered", "arrest_stage", "arrest_against", "arrest_station_mm"].map(String::from));
    h.extend(
        Movements::none()
            .by_key()
            .iter()
            .map(|(k, m)| format!("{k}_{}", serde_name(&m.unit))),
    );
    h.extend(
        [
            "posterior_rotation_deg",
            "theta_at_station_50mm_deg",
            "head_twist_at_station_50mm_deg",
            "occiput_tilt_at_station_50mm_deg",
            "simulated_s",
            "wall_s",
            "completed",
            "failure",
            "arrest_part",
            "arrest_shoulders_station_mm",
            "internal_rotation_outside_window_station_mm",
            "head_born_s",
            "head_born_theta_deg",
            "head_born_phi_deg",
            "not_held_at_birth",
            "state",
            "shoulders_inlet_from_ap_deg",
            "head_to_body_s",
            "arrest_shoulders_from_ap_deg",
        ]
        .map(String::from),
    );
    h
}

fn table_row(
    record: &RunRecord,
    dir: &Path,
    keys: &[&str],
    combination: &[(String, String)],
    summary: &serde_json::Value,
) -> Vec<String> {
    let number = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
    let s = &record.summary;
    let mut row = vec![dir.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())];
    row.extend(set_values(keys, combination));
    row.push(s.outcome.delivered.to_string());
    let arrest = s.outcome.arrest.as_ref();
    row.push(arrest.map_or(String::new(), |a| serde_name(&a.stage)));
    row.push(arrest.map_or(String::new(), |a| a.against.clone()));
    row.push(number(arrest.map(|a| a.station_mm)));
    row.extend(
        movements(record)
            .into_iter()
            .map(|(_, m)| number(m.observed.then_some(m.size).flatten())),
    );
    let posterior = record.detector.as_ref().map(|d| d.posterior_rotation);
    row.push(number(posterior.filter(|m| m.observed).and_then(|m| m.size)));
    let at = &summary["at_station_50mm"];
    for key in ["theta_deg", "head_twist_deg", "occiput_tilt_deg"] {
        row.push(number(at[key].as_f64()));
    }
    row.push(number(Some(s.simulated_s)));
    row.push(number(Some(s.wall_s)));
    row.push(s.completed.to_string());
    row.push(s.failure.clone().unwrap_or_default());
    row.push(arrest.map_or(String::new(), |a| a.part.clone()));
    row.push(number(arrest.and_then(|a| a.shoulders_station_mm)));
    let outside = record.detector.as_ref().and_then(|d| d.internal_rotation_outside_window);
    row.push(number(outside.map(|r| r.station_mm)));
    let born = record.detector.as_ref().and_then(|d| d.head_born);
    row.push(number(born.map(|h| h.time_s)));
    row.push(number(born.map(|h| h.theta_deg)));
    row.push(number(born.map(|h| h.phi_deg)));
    let lost = record.detector.as_ref().map_or(&[][..], |d| &d.not_held_at_birth);
    row.push(lost.iter().map(|n| n.movement.as_str()).collect::<Vec<_>>().join(" "));
    row.push(state(s).to_string());
    let shoulders = record.detector.as_ref().and_then(|d| d.shoulders);
    row.push(number(shoulders.and_then(|p| p.inlet_from_ap_deg)));
    row.push(number(shoulders.and_then(|p| p.head_to_body_s)));
    row.push(number(arrest.and_then(|a| a.shoulders_from_ap_deg)));
    row
}

/// How a run that was made ended: "failed" (`failure` says why),
/// "finished", or "stopped" (Ctrl-C; `--resume` goes on with it).
fn state(summary: &RunSummary) -> &'static str {
    match (&summary.failure, summary.completed) {
        (Some(_), _) => "failed",
        (None, true) => "finished",
        (None, false) => "stopped",
    }
}

/// A CSV field, quoted when it holds a comma, quote or line break.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// sweep.csv and sweep.json with the runs finished so far, in sweep order.
fn write_table(out_dir: &Path, keys: &[&str], rows: &[Option<Finished>]) -> anyhow::Result<()> {
    let mut csv = header(keys).iter().map(|h| field(h)).collect::<Vec<_>>().join(",");
    csv.push('\n');
    for row in rows.iter().flatten() {
        // One line per run, so that line-based tools count runs: a
        // failure's hint joins its message (sweep.json keeps the breaks).
        csv.push_str(&row.row.iter().map(|f| field(&f.split_whitespace().collect::<Vec<_>>().join(" "))).collect::<Vec<_>>().join(","));
        csv.push('\n');
    }
    let path = out_dir.join(CSV_FILE);
    std::fs::write(&path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    let path = out_dir.join(JSON_FILE);
    let text = serde_json::to_string_pretty(&sweep_json(out_dir, keys, rows))?;
    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
}

fn sweep_json(out_dir: &Path, keys: &[&str], rows: &[Option<Finished>]) -> serde_json::Value {
    json!({
        "out_dir": out_dir.display().to_string(),
        "settings": keys,
        "runs_planned": rows.len(),
        "runs": rows.iter().flatten().map(|r| r.summary.clone()).collect::<Vec<_>>(),
    })
}

/// The table on standard output: settings, outcome and observed movements.
fn print_table(keys: &[&str], rows: &[Option<Finished>]) {
    for finished in rows.iter().flatten() {
        let r = &finished.summary;
        let set: Vec<String> = keys
            .iter()
            .filter_map(|k| r["set"][*k].as_str().map(|v| format!("{k}={v}")))
            .collect();
        let set = if set.is_empty() { "as the scenario is".to_string() } else { set.join(" ") };
        let outcome = serde_json::from_value::<Outcome>(r["outcome"].clone())
            .map_or("not run".to_string(), |o| outcome_line(&o));
        // In the textbook's order, as `carus run` lists them.
        let movements = serde_json::from_value::<Movements>(r["movements"].clone()).ok();
        let observed: Vec<&str> = movements
            .as_ref()
            .map(|m| m.by_key().into_iter().filter(|(_, m)| m.observed).map(|(key, _)| key).collect())
            .unwrap_or_default();
        let failure = match (r["failure"].as_str(), r["completed"].as_bool()) {
            // A run never made read no scenario.
            (Some(f), _) if r["scenario"].is_null() => {
                println!("{set}: not run: {f}");
                continue;
            }
            (Some(f), _) => format!("; ended early: {f}"),
            (None, Some(false)) => format!("; stopped at t = {:.1} s", r["simulated_s"].as_f64().unwrap_or(0.0)),
            _ => String::new(),
        };
        let observed = if observed.is_empty() {
            "no movement observed".to_string()
        } else {
            observed.join(", ")
        };
        println!("{set}: {outcome}; {observed}{failure}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use carus_labour::{RunOptions, SilentObserver};

    #[test]
    fn every_combination_runs_once_the_first_key_slowest() {
        let settings = [
            parse_setting("a=1,2").unwrap(),
            parse_setting("b=x,y,z").unwrap(),
        ];
        let c = combinations(&settings);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], vec![("a".into(), "1".into()), ("b".into(), "x".into())]);
        assert_eq!(c[5], vec![("a".into(), "2".into()), ("b".into(), "z".into())]);
        assert_eq!(folder_name(4, &c[4], &["a", "b"]), "05-a=2_b=y");
        assert_eq!(folder_name(0, &[("start.position".into(), "\"LOT\"".into())], &[]), "01-start.position=-LOT-");
        // Settings too long for a file name are cut and told apart by a checksum.
        let waypoints = |last: f64| (0..8).map(|i| format!("{{time_s={i}.0, station_mm={last}}}")).collect::<Vec<_>>().join(",");
        let long = [("trajectory.waypoints".to_string(), format!("[{}]", waypoints(1.0)))];
        let other = [("trajectory.waypoints".to_string(), format!("[{}]", waypoints(2.0)))];
        let varying = ["trajectory.waypoints"];
        let (a, b) = (folder_name(11, &long, &varying), folder_name(11, &other, &varying));
        assert!(a.len() <= FOLDER_NAME_MAX && a.starts_with("12-trajectory.waypoints=-") && a != b, "{a} {b}");
        assert_eq!(a, folder_name(11, &long, &varying), "the same settings, the same folder");
        // Many keys: the one that varies comes first, and only whole settings are kept.
        let mut many: Vec<(String, String)> = (0..8).map(|i| (format!("numerics.setting_number_{i}"), "0.25".to_string())).collect();
        many.push(("contact.friction".into(), "0.1".into()));
        let name = folder_name(0, &many, &["contact.friction"]);
        assert!(name.len() <= FOLDER_NAME_MAX && name.starts_with("01-contact.friction=0.1_numerics.setting_number_0=0.25_"), "{name}");
        let settings = name[3..name.len() - 9].split('_').filter(|p| p.contains('=')).count();
        assert!(name[3..name.len() - 9].ends_with("=0.25") && settings >= 3, "whole settings only: {name}");
        // Short names are those earlier sweeps made.
        assert_eq!(folder_name(2, &c[2], &["a", "b"]), spelled_name(2, &c[2]));
    }

    /// One at a time: the scenario as it is, then each value alone, with
    /// the other keys' cells left empty in the table.
    #[test]
    fn one_at_a_time_runs_the_base_then_each_value_alone() {
        let settings = [
            parse_setting("a=1,2").unwrap(),
            parse_setting("b=x,y,z").unwrap(),
        ];
        let c = one_at_a_time(&settings);
        assert_eq!(c.len(), 1 + 2 + 3);
        assert!(c[0].is_empty());
        assert_eq!(c[2], vec![("a".into(), "2".into())]);
        assert_eq!(c[5], vec![("b".into(), "z".into())]);
        assert_eq!(folder_name(0, &c[0], &[]), "01-base");
        assert_eq!(folder_name(3, &c[3], &[]), "04-b=x");
        assert_eq!(set_values(&["a", "b"], &c[3]), ["", "x"]);
        assert_eq!(set_values(&["a", "b"], &c[0]), ["", ""]);
        let r = unmade(Path::new("runs/x/04-b=x"), &c[3], &["a", "b"], &anyhow::anyhow!("no"));
        assert_eq!(&r.row[..3], ["04-b=x", "", "x"]);
    }

    #[test]
    fn a_run_that_cannot_be_made_is_a_row_with_its_reason() {
        let combination = [("contact.friction".to_string(), "0.1".to_string())];
        let error = anyhow::anyhow!("cannot create runs/x");
        let r = unmade(Path::new("runs/x/01-contact.friction=0.1"), &combination, &["contact.friction"], &error);
        let header = header(&["contact.friction"]);
        assert_eq!(r.row.len(), header.len());
        assert_eq!(r.row[0], "01-contact.friction=0.1");
        assert_eq!(r.row[1], "0.1");
        let at = |column: &str| &r.row[header.iter().position(|c| c == column).unwrap()];
        assert_eq!(at("completed"), "false");
        assert_eq!(at("failure"), "cannot create runs/x");
        assert_eq!(at("arrest_part"), "");
        assert_eq!(at("state"), "not run");
        assert_eq!(r.summary["set"]["contact.friction"], "0.1");
        assert_eq!(r.summary["failure"], "cannot create runs/x");
        // sweep.csv has one line per run, the hint joined to its message.
        let dir = tempfile::tempdir().unwrap();
        let two_lines = anyhow::anyhow!("no pelvis\n  hint: widen it");
        let rows = [Some(unmade(&dir.path().join("01-a=1"), &[("a".into(), "1".into())], &["a"], &two_lines))];
        write_table(dir.path(), &["a"], &rows).unwrap();
        let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
        assert_eq!(csv.lines().count(), 2, "{csv}");
        assert!(csv.contains(",no pelvis hint: widen it,"), "{csv}");
    }

    /// A sweep of `scenario`, written as a file in `dir`, over `settings`,
    /// two runs at a time, quiet, into `dir/sweep` (the second of the pair).
    fn coarse_sweep(scenario: &Scenario, dir: &Path, settings: &[&str]) -> (SweepArgs, std::path::PathBuf) {
        let file = dir.join("coarse.toml");
        std::fs::write(&file, scenario.to_toml().unwrap()).unwrap();
        let out = dir.join("sweep");
        let args = SweepArgs {
            scenario: Some(file.display().to_string()),
            settings: settings.iter().map(|s| s.to_string()).collect(),
            with: Vec::new(),
            one_at_a_time: false,
            resume: None,
            jobs: Some(2),
            allow_large: false,
            output: OutputArgs {
                out: Some(out.clone()),
                json: true,
                force: false,
                quiet: true,
            },
        };
        (args, out)
    }

    /// A sweep of more runs than a sweep makes unasked is refused at once,
    /// before any scenario is read or folder made, with its count, its
    /// cost and the ways out; --allow-large lets it through to the checks.
    #[test]
    fn a_sweep_too_large_is_refused_before_anything_is_made() {
        let dir = tempfile::tempdir().unwrap();
        let hundred = |key: &str| format!("{key}={}", (1..=100).map(|i| i.to_string()).collect::<Vec<_>>().join(","));
        let settings = [hundred("contact.friction"), hundred("expulsion.force_max_n"), hundred("expulsion.period_s")];
        let (args, out) = coarse_sweep(&crate::commands::coarse_normal(0.05), dir.path(), &[]);
        // A scenario that does not exist: the refusal comes before it is read.
        let large = SweepArgs { scenario: Some("no-such-scenario".into()), settings: settings.to_vec(), ..args };
        let e = run(&large).expect_err("refused");
        assert!(e.downcast_ref::<crate::commands::BadArgument>().is_some(), "{e}");
        let e = e.to_string();
        for part in [
            "this sweep makes 1000000 runs (100 values of contact.friction x 100 values of expulsion.force_max_n x 100 values of expulsion.period_s, every combination)",
            "more than the 1000 a sweep makes unasked",
            "at about 30 s a run per core",
            "or vary one key at a time with --one-at-a-time (301 runs)",
            "add --allow-large",
        ] {
            assert!(e.contains(part), "{part}: {e}");
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()).min(2);
        assert!(e.contains(&format!("days on {cores} core")), "{e}");
        assert!(!out.exists());
        // One at a time, 301 runs pass the count (and stop at the unknown scenario).
        let once = SweepArgs { one_at_a_time: true, ..large };
        assert!(run(&once).expect_err("no such scenario").to_string().contains("no-such-scenario"));
        let allowed = SweepArgs { one_at_a_time: false, allow_large: true, ..once };
        assert!(run(&allowed).expect_err("no such scenario").to_string().contains("no-such-scenario"));
        assert_eq!(planned_runs(&[], false), Some(1));
        let many = vec![parse_setting(&hundred("a")).unwrap(); 20];
        assert_eq!(planned_runs(&many, false), None);
        let e = run(&SweepArgs { settings: (0..20).map(|k| hundred(&format!("k{k}"))).collect(), allow_large: true, ..allowed }).unwrap_err();
        assert!(e.to_string().contains("more runs than can be counted"), "{e}");
        assert!(!out.exists());
    }

    /// A file refused for a value every run sets is mended by the sweep's
    /// values, as `carus run --set` mends it; a one-at-a-time sweep, whose
    /// first run is the file as it is, is refused. The same key twice is a
    /// bad argument.
    #[test]
    fn a_swept_key_mends_the_file_that_has_it_wrong() {
        let s = crate::commands::coarse_normal(0.05);
        let dir = tempfile::tempdir().unwrap();
        let (args, out) = coarse_sweep(&s, dir.path(), &["contact.friction=0.1,0.2"]);
        let file = dir.path().join("coarse.toml");
        let text = std::fs::read_to_string(&file).unwrap();
        let wrong = text.replacen(&format!("friction = {:?}", s.contact.friction), "friction = -0.1", 1);
        assert_ne!(wrong, text, "the friction line is found");
        std::fs::write(&file, wrong).unwrap();
        let once = SweepArgs { one_at_a_time: true, output: OutputArgs { out: Some(dir.path().join("once")), ..args.output }, ..args };
        let e = run(&once).expect_err("the base run is the file as it is").to_string();
        assert!(e.contains("contact.friction") && e.contains("-0.1"), "{e}");
        let args = SweepArgs { one_at_a_time: false, output: OutputArgs { out: Some(out.clone()), ..once.output }, ..once };
        assert!(matches!(run(&args).unwrap(), Status::Success));
        for (folder, friction) in [("01-contact.friction=0.1", "friction = 0.1\n"), ("02-contact.friction=0.2", "friction = 0.2\n")] {
            let toml = std::fs::read_to_string(out.join(folder).join("scenario.toml")).unwrap();
            assert!(toml.contains(friction), "{folder}");
        }
        let twice = SweepArgs {
            settings: vec!["contact.friction=0.1".into(), "contact.friction=0.2".into()],
            output: OutputArgs { out: Some(dir.path().join("twice")), ..args.output },
            ..args
        };
        let e = run(&twice).expect_err("refused");
        assert!(e.downcast_ref::<crate::commands::BadArgument>().is_some() && e.to_string().contains("given twice"), "{e}");
    }

    /// `--with` sets a key in every run, the unchanged first run of a
    /// one-at-a-time sweep included, and mends a file that has it wrong; a
    /// key both set in every run and swept, or set twice, is a bad argument.
    #[test]
    fn a_with_setting_is_in_every_run() {
        let s = crate::commands::coarse_normal(0.05);
        let dir = tempfile::tempdir().unwrap();
        let (args, out) = coarse_sweep(&s, dir.path(), &["contact.friction=0.1"]);
        let file = dir.path().join("coarse.toml");
        let text = std::fs::read_to_string(&file).unwrap();
        let wrong = text.replacen(&format!("damping_time_s = {:?}", s.contact.damping_time_s), "damping_time_s = -1.0", 1);
        assert_ne!(wrong, text, "the damping line is found");
        std::fs::write(&file, wrong).unwrap();
        let args = SweepArgs { one_at_a_time: true, with: vec!["contact.damping_time_s=0.001".into(), "output.vtu=false".into()], ..args };
        assert!(matches!(run(&args).unwrap(), Status::Success));
        for folder in ["01-base", "02-contact.friction=0.1"] {
            let toml = std::fs::read_to_string(out.join(folder).join("scenario.toml")).unwrap();
            assert!(toml.contains("damping_time_s = 0.001\n") && toml.contains("vtu = false\n"), "{folder}");
            // Made once, though the file was mended with it.
            let description = toml.lines().find(|l| l.starts_with("description")).unwrap();
            assert_eq!(description.matches("contact.damping_time_s = 0.001").count(), 1, "{folder}: {description}");
        }
        // Only the swept key has a column.
        let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
        assert!(csv.starts_with("run,contact.friction,delivered"), "{csv}");
        for (with, says) in [
            (vec!["contact.friction=0.2"], "--with contact.friction and --set contact.friction change one key"),
            (vec!["contact={friction=0.2}"], "--with contact and --set contact.friction change one key"),
            (vec!["output.vtu=false", "output.vtu=true"], "--with output.vtu and --with output.vtu set one key twice"),
            (vec!["output.vtu=false", "output={vtu=true}"], "--with output.vtu and --with output set one key twice"),
        ] {
            let (fresh, _) = coarse_sweep(&s, dir.path(), &["contact.friction=0.1"]);
            let bad = SweepArgs {
                with: with.into_iter().map(String::from).collect(),
                output: OutputArgs { out: Some(dir.path().join("bad")), ..fresh.output },
                ..fresh
            };
            let e = run(&bad).expect_err("refused");
            assert!(e.downcast_ref::<crate::commands::BadArgument>().is_some() && e.to_string().contains(says), "{e}");
            assert!(!dir.path().join("bad").exists());
        }
        let e = super::super::settings::fixed_setting_arg("output.every_s=0.01,0.02").unwrap_err();
        assert!(e.contains("--with output.every_s=0.01,0.02: one value per key here; sweep a key's values with --set"), "{e}");
    }

    /// One at a time through the command: the base run and each value
    /// alone, each row with only its own key's cell filled.
    #[test]
    fn a_one_at_a_time_sweep_tabulates_the_base_and_each_change() {
        let s = crate::commands::coarse_normal(0.2);
        let dir = tempfile::tempdir().unwrap();
        let (args, out) = coarse_sweep(&s, dir.path(), &["expulsion.force_max_n=60", "contact.friction=0.1"]);
        let args = SweepArgs { one_at_a_time: true, ..args };
        assert!(matches!(run(&args).unwrap(), Status::Success));
        let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 4, "{csv}");
        assert!(lines[0].starts_with("run,expulsion.force_max_n,contact.friction,delivered"), "{}", lines[0]);
        assert!(lines[1].starts_with("01-base,,,"), "{}", lines[1]);
        assert!(lines[2].starts_with("02-expulsion.force_max_n=60,60,,"), "{}", lines[2]);
        assert!(lines[3].starts_with("03-contact.friction=0.1,,0.1,"), "{}", lines[3]);
        let base = std::fs::read_to_string(out.join("01-base/scenario.toml")).unwrap();
        assert_eq!(base, s.to_toml().unwrap());
        // --force knows every file a sweep writes.
        assert_eq!(super::super::run::foreign_entries(&out).unwrap(), Vec::<PathBuf>::new());
    }

    /// A sweep stopped with one run part way and one not started goes on
    /// with `--resume`: each run ends as in the uninterrupted sweep, bit
    /// for bit, and the tables hold both, finished.
    #[test]
    fn a_stopped_sweep_resumes_to_the_uninterrupted_result() {
        let s = crate::commands::coarse_normal(0.3);
        let dir = tempfile::tempdir().unwrap();
        let (args, out) = coarse_sweep(&s, dir.path(), &["expulsion.force_max_n=60,120"]);
        assert!(matches!(run(&args).unwrap(), Status::Success));
        let [first, second] = ["01-expulsion.force_max_n=60", "02-expulsion.force_max_n=120"].map(|d| out.join(d));
        let history = |d: &Path| std::fs::read_to_string(d.join("pose_history.csv")).unwrap();
        let whole = [history(&first), history(&second)];
        // As Ctrl-C would leave it: the first stopped at 0.1 s, the second not begun.
        std::fs::remove_dir_all(&first).unwrap();
        std::fs::remove_dir_all(&second).unwrap();
        std::fs::create_dir(&first).unwrap();
        let variant = s.with_setting("expulsion.force_max_n", "60").unwrap();
        let stop = RunOptions { stop_at_s: Some(0.1), ..RunOptions::default() };
        let stopped = carus_labour::run(&variant, &first, &stop, &mut SilentObserver).unwrap();
        assert!(!stopped.summary.completed);

        let resume = SweepArgs { scenario: None, settings: Vec::new(), resume: Some(out.clone()), ..args };
        assert!(matches!(run(&resume).unwrap(), Status::Success));
        assert_eq!([history(&first), history(&second)], whole);
        let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3, "{csv}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
        assert!(json["runs"].as_array().unwrap().iter().all(|r| r["completed"] == json!(true)), "{json}");
        // Resumed again, the finished runs are kept as they are.
        assert!(matches!(run(&resume).unwrap(), Status::Success));
        assert_eq!([history(&first), history(&second)], whole);

        // A plan edited since would label the kept runs with settings they
        // did not run with: the base scenario, then the values, each refused.
        let plan_path = out.join(PLAN_FILE);
        let original = std::fs::read_to_string(&plan_path).unwrap();
        let mut plan: serde_json::Value = serde_json::from_str(&original).unwrap();
        let base = plan["scenario_toml"].as_str().unwrap().replace("friction = 0.009", "friction = 0.05");
        assert_ne!(base, plan["scenario_toml"].as_str().unwrap(), "the coarse scenario sets no wetted friction");
        plan["scenario_toml"] = json!(base);
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        let e = format!("{:#}", run(&resume).err().unwrap());
        assert!(e.contains("01-expulsion.force_max_n=60 ran another scenario") && e.contains("was changed"), "{e}");
        let mut plan: serde_json::Value = serde_json::from_str(&original).unwrap();
        plan["set"] = json!(["expulsion.force_max_n=60,90"]);
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        let e = format!("{:#}", run(&resume).err().unwrap());
        assert!(e.contains("02-expulsion.force_max_n=120 ran another scenario"), "{e}");
        // A plan from before the folders were kept names them spelled out.
        assert_eq!(plan["folders"], json!(["01-expulsion.force_max_n=60", "02-expulsion.force_max_n=120"]));
        plan.as_object_mut().unwrap().remove("folders");
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        let e = format!("{:#}", run(&resume).err().unwrap());
        assert!(e.contains("02-expulsion.force_max_n=120 is a run the plan no longer makes"), "{e}");
        let mut older: serde_json::Value = serde_json::from_str(&original).unwrap();
        older.as_object_mut().unwrap().remove("folders");
        std::fs::write(&plan_path, older.to_string()).unwrap();
        assert!(matches!(run(&resume).unwrap(), Status::Success));
        // A plan whose kept values no longer read is said to be damaged, not a command line.
        let mut plan: serde_json::Value = serde_json::from_str(&original).unwrap();
        plan["set"] = json!(["expulsion.force_max_n"]);
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        let e = format!("{:#}", run(&resume).err().unwrap());
        assert!(e.contains("sweep_plan.json is damaged") && e.contains("run the sweep again"), "{e}");
        // A plan from before the chest's key goes on where its default is
        // the old chest (120 mm shoulders), and is refused where it is not.
        let without_chest = |text: &str| -> String { text.lines().filter(|l| !l.starts_with("chest_breadth_mm")).map(|l| format!("{l}\n")).collect() };
        let mut plan: serde_json::Value = serde_json::from_str(&original).unwrap();
        plan["scenario_toml"] = json!(without_chest(plan["scenario_toml"].as_str().unwrap()));
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        assert!(matches!(run(&resume).unwrap(), Status::Success));
        plan["scenario_toml"] = json!(plan["scenario_toml"].as_str().unwrap().replace("bisacromial_mm = 120.0", "bisacromial_mm = 175.0"));
        std::fs::write(&plan_path, plan.to_string()).unwrap();
        let e = format!("{:#}", run(&resume).err().unwrap());
        assert!(e.contains("planned by an older carus, before trunk.chest_breadth_mm existed"), "{e}");
        std::fs::write(&plan_path, original).unwrap();
        assert!(matches!(run(&resume).unwrap(), Status::Success));
        assert_eq!([history(&first), history(&second)], whole);

        // A folder without a plan is not a sweep to go on with: one of
        // its runs is named as a run's folder, any other by the plan it lacks.
        let e = format!("{:#}", read_plan(&first).err().unwrap());
        assert!(e.contains("holds no sweep") && e.contains("is a run's folder: `carus run --resume"), "{e}");
        let empty = tempfile::tempdir().unwrap();
        let e = format!("{:#}", run(&SweepArgs { resume: Some(empty.path().to_path_buf()), ..resume }).err().unwrap());
        assert!(e.contains("sweep_plan.json") && e.contains("--resume takes the folder of a sweep"), "{e}");
    }

    #[test]
    fn fields_with_commas_are_quoted() {
        assert_eq!(field("a, \"b\""), "\"a, \"\"b\"\"\"");
        assert_eq!(field("mid-pelvis"), "mid-pelvis");
    }

    /// A sweep of two short runs of a coarse normal scenario: both run, each
    /// as a plain run of the same settings would (bit for bit), and the
    /// table holds a row for each with its setting.
    #[test]
    fn a_sweep_runs_every_variant_as_carus_run_would() {
        let mut s = crate::commands::coarse_normal(0.3);
        let dir = tempfile::tempdir().unwrap();
        let (args, out) = coarse_sweep(&s, dir.path(), &["expulsion.force_max_n=60,120"]);
        assert!(matches!(run(&args).unwrap(), Status::Success));

        let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3, "{csv}");
        assert!(lines[0].starts_with("run,expulsion.force_max_n,delivered,arrest_stage"), "{}", lines[0]);
        assert!(lines[1].starts_with("01-expulsion.force_max_n=60,60,"), "{}", lines[1]);
        assert!(lines[2].starts_with("02-expulsion.force_max_n=120,120,"), "{}", lines[2]);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
        assert_eq!(json["runs"].as_array().unwrap().len(), 2);
        assert_eq!(json["runs"][1]["set"]["expulsion.force_max_n"], "120");
        assert_eq!(json["runs"][1]["simulated_s"], json!(0.3));
        let state = lines[0].split(',').position(|h| h == "state").unwrap();
        assert_eq!(lines[1].split(',').nth(state), Some("finished"), "{}", lines[1]);
        // A run that could not be made has every key a made one has.
        let keys = |run: &serde_json::Value| run.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
        let not_made = unmade(&out.join("03-x"), &[], &["expulsion.force_max_n"], &anyhow::anyhow!("no"));
        assert_eq!(keys(&not_made.summary), keys(&json["runs"][1]));

        // The second variant against a plain run of the same scenario.
        s.expulsion.force_max_n = 120.0;
        let plain = dir.path().join("plain");
        std::fs::create_dir(&plain).unwrap();
        let record = carus_labour::run(&s, &plain, &RunOptions::default(), &mut SilentObserver).unwrap();
        let swept = std::fs::read_to_string(out.join("02-expulsion.force_max_n=120/pose_history.csv")).unwrap();
        assert_eq!(swept, std::fs::read_to_string(plain.join("pose_history.csv")).unwrap());
        assert!(record.summary.completed);

        // An existing sweep is not overwritten, and a bad key runs nothing.
        assert!(run(&args).is_err());
        let bad = SweepArgs {
            settings: vec!["expulsion.period=8".into()],
            output: OutputArgs {
                out: Some(dir.path().join("bad")),
                ..args.output
            },
            ..args
        };
        let Err(e) = run(&bad) else {
            panic!("a sweep over an unknown key ran");
        };
        let e = e.to_string();
        assert!(e.contains("expulsion.period = 8"), "{e}");
        assert!(!dir.path().join("bad").exists());
        let twice = SweepArgs {
            settings: vec!["contact.friction=0.1".into(), "contact.friction=0.2".into()],
            output: OutputArgs {
                out: Some(dir.path().join("twice")),
                ..bad.output
            },
            ..bad
        };
        let e = run(&twice).expect_err("a key given twice is refused").to_string();
        assert!(e.contains("contact.friction is given twice"), "{e}");
        // Diameters that make no pelvis in every variant: refused before
        // any out dir, each variant named with its reason.
        let unbuildable = SweepArgs {
            settings: vec!["pelvis.inlet_oblique_mm=155,160".into()],
            output: OutputArgs {
                out: Some(dir.path().join("unbuildable")),
                ..twice.output
            },
            ..twice
        };
        let e = format!("{:#}", run(&unbuildable).expect_err("no variant can start"));
        assert!(e.contains("no run of the sweep can start"), "{e}");
        assert!(e.contains("01-pelvis.inlet_oblique_mm=155: ") && e.contains("02-pelvis.inlet_oblique_mm=160: "), "{e}");
        assert!(e.contains("inlet_oblique_mm"), "{e}");
        assert!(!dir.path().join("unbuildable").exists());
    }
}
