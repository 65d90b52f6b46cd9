//! `carus run [NAME|FILE] [--set KEY=VALUE ...] [--out DIR] [--json] [--force] [--quiet] [--resume DIR]`:
//! the forward simulation of labour (carus-labour). No argument runs the
//! built-in normal scenario. Writes into an out dir it names on start and
//! never overwrites an existing run unless `--force`. Ctrl-C stops cleanly
//! with everything so far written; `--resume DIR` continues from the last checkpoint.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context};
use carus_analysis::{ArrestStage, DetectorReport, Movement, Movements, Outcome, Unit};
use carus_labour::record::FloorAtMoment;
use carus_labour::loads::GuideSummary;
use carus_labour::{LabourError, Mode, Observer, RunOptions, RunRecord, Scenario, Scene, Simulation, BUILTINS};
use serde_json::json;

use super::settings::{one_setting, one_setting_arg};
use super::{print_json, Status};

/// Where a labour command writes and what it prints (`carus run`, `carus sweep`, `carus sanity`).
#[derive(clap::Args)]
pub struct OutputArgs {
    /// Output folder; default the first free `runs/<scenario>-<n>` (`runs/sweep-<scenario>-<n>`
    /// for a sweep, `runs/sanity-<n>` for sanity).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
    /// Replace what the output folder holds, if carus wrote it all (a run, sweep or sanity folder; refused if it holds anything else).
    #[arg(long)]
    pub force: bool,
    /// No progress or notes on standard error.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(clap::Args)]
pub struct RunArgs {
    /// A built-in scenario name (`carus scenarios`) or a scenario file (TOML). Default: normal.
    pub scenario: Option<String>,
    /// KEY=VALUE changed in the scenario before it runs, a dotted key as
    /// `carus scenarios show` writes it (e.g. contact.friction=0.35);
    /// repeat for more keys. The run's scenario.toml keeps the changes.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = one_setting_arg)]
    pub settings: Vec<String>,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Continue the run in DIR from its last checkpoint.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scenario", "settings", "out", "force"])]
    pub resume: Option<PathBuf>,
}

/// A progress bar with simulated time and the estimated time left.
struct Bar(Option<indicatif::ProgressBar>);

impl Observer for Bar {
    fn progress(&mut self, simulated_s: f64, end_s: f64) {
        if let Some(bar) = &self.0 {
            bar.set_length((end_s * 1000.0) as u64);
            bar.set_position((simulated_s * 1000.0) as u64);
            bar.set_message(format!("t = {simulated_s:.2} / {end_s:.0} s simulated"));
        }
    }
}

pub fn run(args: &RunArgs) -> anyhow::Result<Status> {
    let options = stopped_by(&super::ctrl_c_flag());
    let show = super::shows_progress(args.output.quiet);
    let bar = show.then(super::progress_bar);
    let mut observer = Bar(bar);

    let (out_dir, record) = match &args.resume {
        Some(dir) => {
            // A sweep's or sanity's folder given for one of its runs.
            if let Some(kind) = super::folder_kind(dir).filter(|_| !dir.join(carus_labour::output::SCENARIO_FILE).exists()) {
                bail!("{} holds no run to resume: {kind}", dir.display());
            }
            // A file given for a run's folder: its run's, or a scenario.
            if dir.is_file() {
                let folder = dir.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(Path::new("."));
                match super::holds_run(folder) {
                    true => bail!(
                        "{} is a file; --resume takes the run's folder: `carus run --resume {}`",
                        dir.display(),
                        folder.display()
                    ),
                    false => bail!(
                        "{0} is a file, not a run's folder; --resume goes on with a run that `carus run` wrote \
                         (a scenario is run with `carus run {0}`)",
                        dir.display()
                    ),
                }
            }
            super::check_resume_dir(dir, "run", carus_labour::output::SCENARIO_FILE)?;
            // A folder the run cannot write in is found now, not after
            // simulating to the next checkpoint (the mark is rewritten).
            if super::holds_run(dir) && !run_ended(dir) {
                mark(dir).with_context(|| {
                    format!("--resume {}: the run cannot write its frames and checkpoint there", dir.display())
                })?;
            }
            // A run that ended or failed is refused by resume, unannounced.
            if !args.output.quiet && !run_ended(dir) {
                eprintln!("resuming the run in {}", dir.display());
            }
            (
                dir.clone(),
                carus_labour::resume(dir, &options, &mut observer)
                    .with_context(|| format!("run in {}", dir.display())),
            )
        }
        None => {
            let scenario = load_changed(args.scenario.as_deref(), &args.settings)?;
            // Before the build, which angles in radians often fail.
            if let Some(note) = scenario.trajectory.radians_note().filter(|_| !args.output.quiet) {
                eprintln!("note: {note}");
            }
            let named = args.scenario.as_deref().unwrap_or(DEFAULT_SCENARIO);
            let chosen = choose_out_dir(args.output.out.as_deref(), &scenario.name, args.output.force)?;
            // A scenario that cannot start is refused before the out dir is
            // made, or an earlier run in it cleared by --force.
            let building = Instant::now();
            let scene = in_scenario(Scene::build(&scenario), named)?;
            // Holes in an imported pelvis let the fetus through: said before it runs.
            let import_note = scene.pelvis_import.as_ref().and_then(|(report, mesh)| super::measure::import_note(report, mesh));
            if let Some(note) = import_note.filter(|_| !args.output.quiet) {
                eprintln!("note: {note}");
            }
            let sim = in_scenario(Simulation::new(&scene), named)?;
            let built = building.elapsed();
            let out_dir = chosen.make()?;
            // The run's wall time counts the build, not the clearing.
            let started = Instant::now().checked_sub(built).unwrap_or(building);
            if !args.output.quiet {
                let changed = match args.settings.is_empty() {
                    true => String::new(),
                    false => format!(" with {}", args.settings.join(", ")),
                };
                eprintln!(
                    "running scenario `{}`{changed} into {}",
                    scenario.name,
                    out_dir.display()
                );
            }
            let record = in_scenario(carus_labour::run_from_start(sim, &out_dir, &options, &mut observer, started), named);
            (out_dir, record)
        }
    };
    if let Some(bar) = &observer.0 {
        bar.finish_and_clear();
    }
    let record = record.map_err(|e| resumable(e, &out_dir))?;
    // The report must never cost the run's data: its failure is a warning.
    match write_report(&record, &out_dir) {
        Ok(warnings) => {
            for warning in warnings {
                eprintln!("warning: report.html: {warning}");
            }
        }
        Err(error) => eprintln!("warning: report.html was not written: {}", crate::error_text(&error)),
    }
    if let Some(failure) = &record.summary.failure {
        if record.summary.completed {
            eprintln!("error: {failure} (everything simulated is written)");
        } else {
            eprintln!("error: the run ended early at t = {:.2} s: {failure} (everything up to then is written)", record.summary.simulated_s);
        }
    } else if !record.summary.completed && !args.output.quiet {
        eprintln!(
            "stopped at t = {:.2} s; continue with: carus run --resume {}",
            record.summary.simulated_s,
            out_dir.display()
        );
    }
    if args.output.json {
        print_json(&json_summary(&record, &out_dir))?;
    } else {
        print_summary(&record, &out_dir);
    }
    // A stopped run is not a finished one: `carus run X && next` must not go on.
    Ok(if record.summary.failure.is_some() || !record.summary.completed {
        Status::Failed
    } else {
        Status::Success
    })
}

/// A run stopped by its output (a full disk, a folder made read-only)
/// keeps its last checkpoint: the error says how to go on from it.
fn resumable(error: anyhow::Error, out_dir: &Path) -> anyhow::Error {
    // Not when it is the checkpoint itself that cannot be read.
    let by_output = matches!(
        error.downcast_ref::<LabourError>(),
        Some(LabourError::Output { path, .. }) if !path.ends_with(carus_labour::output::CHECKPOINT_FILE)
    );
    if by_output && out_dir.join(carus_labour::output::CHECKPOINT_FILE).is_file() {
        anyhow::anyhow!(
            "{error:#}\n  hint: the last checkpoint is kept; once that is mended (space freed, \
             the folder writable), `carus run --resume {}` goes on from it",
            out_dir.display()
        )
    } else {
        error
    }
}

/// The most floor elements with a corner turned inside out at one sample,
/// out of all of them, and when they first appeared.
fn inverted_corners(record: &RunRecord) -> String {
    let most = record.floor.iter().map(|f| f.inverted_corner_elements).max().unwrap_or(0);
    let first = record.floor.iter().find(|f| f.inverted_corner_elements > 0);
    match first {
        Some(f) => format!(
            "up to {most} of {}, from t = {:.1} s",
            record.summary.floor_elements, f.time_s
        ),
        None => format!("none of {}", record.summary.floor_elements),
    }
}

/// Writes report.html beside the run's data. Pictures need a GPU or Mesa's
/// lavapipe; without one the page is still written, with a note instead.
pub(super) fn write_report(record: &RunRecord, out_dir: &Path) -> anyhow::Result<Vec<String>> {
    let Some(detector) = &record.detector else {
        return Ok(vec![
            "no report: the detector has nothing to read (fewer than two pose samples, or the run's failure says why)".into(),
        ]);
    };
    let summary = &record.summary;
    let scene = Scene::build(&record.scenario)?;
    let input = carus_report::ReportInput {
        title: run_title(&record.scenario),
        notice: match (&summary.failure, summary.completed) {
            (Some(f), _) => Some(format!("The run ended early at t = {:.2} s: {f}", summary.simulated_s)),
            // Stopped (Ctrl-C, a signal): what follows is the labour so far.
            (None, false) => Some(format!(
                "The run was stopped at t = {:.2} s, before its end at {} s: this page shows the labour \
                 so far, not its outcome. Go on with: {}",
                summary.simulated_s,
                record.scenario.numerics.end_time_s,
                resume_command(out_dir)
            )),
            (None, true) => None,
        },
        scenario_toml: Some(record.scenario.to_toml()?),
        run: carus_report::RunFigures {
            simulated_s: summary.simulated_s,
            wall_s: Some(summary.wall_s),
            steps: Some(summary.rigid_steps),
            extra: mode_line(record)
                .map(|line| ("mode".to_string(), line))
                .into_iter()
                .chain([
                (
                    // The outcome turns on it (docs/LABOUR.md), so it heads the figures.
                    "contact friction (0.009: the wetted canal; 0.35: muscle on bone)".into(),
                    format!("{}", record.scenario.contact.friction),
                ),
                (
                    "rigid step".into(),
                    format!("{:.3} ms", summary.rigid_dt_s * 1e3),
                ),
                (
                    "floor sub-steps per rigid step".into(),
                    summary.floor_substeps_per_step.to_string(),
                ),
                (
                    "rigid steps whose floor took finer sub-steps (an element pressed flat; docs/SOLVE.md)".into(),
                    if summary.floor_refined_steps == 0 {
                        "none".into()
                    } else {
                        format!(
                            "{} of {}, up to {} sub-steps",
                            summary.floor_refined_steps, summary.rigid_steps, summary.floor_most_substeps
                        )
                    },
                ),
                (
                    "floor elements with a corner turned inside out (stresses not to be trusted; docs/LABOUR.md)"
                        .into(),
                    inverted_corners(record),
                ),
            ])
            .collect(),
        },
        history: &record.history,
        detector,
        floor_peak_stretch: record
            .floor
            .iter()
            .map(|f| (f.time_s, f.peak_stretch))
            .collect(),
        floor_untrusted_from_s: carus_labour::sim::FloorSample::first_inverted_s(&record.floor),
        head_axial_moments: head_axial_moments(record, &scene),
        head_canal_forces: head_canal_forces(record, &scene),
        contact_load_n: contact_load(record),
        scene: Some(report_scene_with_forces(record, &scene, detector)?),
    };
    Ok(carus_report::write_report_file(
        &input,
        &out_dir.join(REPORT_FILE),
    )?)
}

/// A run's title: its scenario, and when the head was not moved by the
/// physics alone, how it was (said first).
pub(super) fn run_title(scenario: &Scenario) -> String {
    let name = &scenario.name;
    match scenario.trajectory.mode {
        Mode::Forward => format!("Carus: {name}"),
        mode => format!("Carus: {name} ({} trajectory, not the physics alone)", mode.name()),
    }
}

/// The report's scene, with the forces on the fetus at its key moments
/// drawn as the viewer draws them (docs/VIEWER.md, "How a force is
/// drawn"); none for a run that recorded no loads.
fn report_scene_with_forces(
    record: &RunRecord,
    scene: &Scene,
    detector: &carus_analysis::DetectorReport,
) -> anyhow::Result<carus_report::ReportScene> {
    let kept = record.key_moments.iter().filter_map(|m| m.floor.as_ref());
    let mut pictured = scene_with_floors(scene, kept.collect());
    if record.loads.is_empty() {
        return Ok(pictured);
    }
    let forces = carus_view::forces::Forces::new(record.loads.clone(), scene.pivot_in_head, scene.expulsion_at_pivot(), &pictured)?;
    let (moments, _) = carus_analysis::moments::key_moments(detector);
    pictured.forces = moments
        .iter()
        .map(|m| {
            let arrows = carus_view::forces::largest_first(forces.arrows(&record.history, m.sample));
            carus_report::SampleForces {
                sample: m.sample,
                arrows: arrows.iter().map(|a| a.mesh()).collect(),
                listed: arrows.iter().map(|a| (a.label.clone(), a.force_n.length(), a.rgb)).collect(),
            }
        })
        .collect();
    Ok(pictured)
}

/// What turned the head about the pelvic axis at each recorded instant,
/// the guide's share included where the head was moved by one.
fn head_axial_moments(record: &RunRecord, scene: &Scene) -> Vec<carus_report::AxialMomentSample> {
    record
        .loads
        .iter()
        .zip(&record.history.samples)
        .map(|(l, sample)| {
            let down = carus_labour::loads::down_the_canal(scene.canal.axis(), sample.head.position_m);
            carus_report::AxialMomentSample {
                time_s: l.time_s,
                bone_nm: l.head_axial.bone_nm,
                floor_nm: l.head_axial.floor_nm,
                neck_nm: l.head_axial.neck_nm,
                neck_push_nm: l.head_axial.neck_push_nm,
                trunk_nm: l.head_axial.trunk_nm,
                guide_nm: l.guide.map_or(0.0, |g| g.moment_nm.dot(down)),
            }
        })
        .collect()
}

/// How hard the pelvis and the floor pressed on the fetus at each recorded
/// instant (the sum of every site's pressing); none for a run recorded
/// before sites recorded it.
fn contact_load(record: &RunRecord) -> Vec<f64> {
    record
        .loads
        .iter()
        .map(|load| load.sites.iter().map(|site| site.pressing_n).sum::<Option<f64>>())
        .collect::<Option<Vec<f64>>>()
        .unwrap_or_default()
}

/// What pushed the head down the canal at each recorded instant: each
/// source's force on the head along the pelvic axis's tangent at the head
/// (the report's plot). None for a run with a trunk recorded before the
/// neck's force was.
fn head_canal_forces(record: &RunRecord, scene: &Scene) -> Vec<carus_report::CanalForceSample> {
    use carus_analysis::ContactSite;
    use carus_labour::loads::{down_the_canal, Body};
    let at_pivot = scene.expulsion_at_pivot();
    let mut samples = Vec::with_capacity(record.loads.len());
    for (load, sample) in record.loads.iter().zip(&record.history.samples) {
        let neck = match (load.neck_force_n, &scene.trunk) {
            (Some(neck), _) => neck,
            (None, None) => glam::DVec3::ZERO,
            (None, Some(_)) => return Vec::new(),
        };
        let down = down_the_canal(scene.canal.axis(), sample.head.position_m);
        let on_head = |floor: bool| -> f64 {
            load.sites
                .iter()
                .filter(|s| s.body == Body::Head && (s.site == ContactSite::PelvicFloor) == floor)
                .map(|s| s.force_n.dot(down))
                .sum()
        };
        let expulsion = if at_pivot { sample.expulsion_force_n } else { glam::DVec3::ZERO };
        samples.push(carus_report::CanalForceSample {
            time_s: load.time_s,
            push_n: (neck + expulsion).dot(down),
            trunk_n: load.head_trunk_force_n.dot(down),
            bone_n: on_head(false),
            floor_n: on_head(true),
            guide_n: load.guide.map_or(0.0, |g| g.force_n.dot(down)),
        });
    }
    samples
}

/// The surfaces a run's pictures and its replay draw, from `scene` (built
/// again from the run's scenario, which is deterministic) in the body
/// frames its poses refer to, with the floor in the states `floors`.
pub(super) fn scene_with_floors(scene: &carus_labour::Scene, floors: Vec<&FloorAtMoment>) -> carus_report::ReportScene {
    carus_report::ReportScene {
        pelvis: Some(scene.pelvis.surface.clone()),
        head: scene.head.surface.clone(),
        trunk: scene.trunk.as_ref().map(|t| t.surface.clone()),
        lower_trunk: scene.lower_trunk.as_ref().map(|t| t.surface.clone()),
        floor: scene.floor.as_ref().map(|floor| floor_surface(floor, floors)),
        fontanelles: Some(carus_report::Fontanelles {
            anterior: scene.head_landmarks.bregma,
            posterior: scene.head_landmarks.lambda,
        }),
        forces: Vec::new(),
    }
}

/// The floor for pictures: its outer faces, at rest and in the given
/// states, coloured by stretch (each node the mean of its elements'
/// largest principal stretch).
fn floor_surface(floor: &carus_labour::scene::FloorScene, mut states: Vec<&FloorAtMoment>) -> carus_report::FloorSurface {
    let every_element: Vec<u32> = (0..floor.mesh.element_count() as u32).collect();
    states.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    states.dedup_by(|a, b| a.time_s == b.time_s);
    carus_report::FloorSurface {
        triangles: floor.mesh.boundary_triangles(&every_element),
        rest_positions_m: floor.reference.clone(),
        frames: states
            .into_iter()
            .map(|state| carus_report::FloorFrame {
                time_s: state.time_s,
                positions_m: floor
                    .reference
                    .iter()
                    .zip(&state.displacement_m)
                    .map(|(rest, u)| *rest + glam::DVec3::from_array(*u))
                    .collect(),
                stretch: floor.mesh.nodal_mean(&state.element_stretch),
            })
            .collect(),
    }
}

/// The built-in scenario `carus run` runs when given none.
pub(super) const DEFAULT_SCENARIO: &str = "normal";

pub(super) fn load(name: Option<&str>) -> anyhow::Result<Scenario> {
    let name = name.unwrap_or(DEFAULT_SCENARIO);
    if BUILTINS.iter().any(|(n, _)| *n == name) {
        return Ok(Scenario::builtin(name)?);
    }
    let path = Path::new(name);
    if !path.exists() {
        let names: Vec<&str> = BUILTINS.iter().map(|(n, _)| *n).collect();
        bail!(
            "`{name}` is neither a built-in scenario ({}) nor a file",
            names.join(", ")
        );
    }
    Ok(Scenario::from_file(path)?)
}

/// A scenario as loaded, with the `--set KEY=VALUE` changes applied in
/// turn. A file refused for a value a setting changes is read again with
/// the settings made first, so that `--set` can mend it.
pub(crate) fn load_changed(name: Option<&str>, settings: &[String]) -> anyhow::Result<Scenario> {
    let changes = settings.iter().map(|text| one_setting(text)).collect::<anyhow::Result<Vec<_>>>()?;
    match load_mended(name, &changes)? {
        (scenario, true) => Ok(scenario),
        (scenario, false) => Ok(scenario.with_settings(&changes)?),
    }
}

/// A scenario as loaded, and whether it was mended: a file refused for a
/// value one of `changes` sets is read with the changes made first (and
/// returned so, `true`); otherwise it is returned as loaded (`false`).
pub(super) fn load_mended(name: Option<&str>, changes: &[(String, String)]) -> anyhow::Result<(Scenario, bool)> {
    let e = match load(name) {
        Ok(scenario) => return Ok((scenario, false)),
        Err(e) => e,
    };
    let mended = e.downcast_ref::<carus_labour::ScenarioError>().is_some_and(|e| match e {
        carus_labour::ScenarioError::Value { key, .. } => changes.iter().any(|(k, _)| k == key),
        _ => false,
    });
    match (mended, name) {
        (true, Some(file)) => Ok((Scenario::from_file_with_settings(Path::new(file), changes)?, true)),
        _ => Err(e),
    }
}

/// Names the scenario in an error from building or running it, unless
/// the error already points into its file (`mine.toml:47: ...`).
fn in_scenario<T>(result: Result<T, carus_labour::LabourError>, scenario: &str) -> anyhow::Result<T> {
    result.map_err(|e| match e.to_string().starts_with(&format!("{scenario}:")) {
        true => e.into(),
        false => anyhow::Error::new(e).context(format!("scenario {scenario}")),
    })
}

/// Where a run will write, chosen before anything is built.
pub(super) enum OutDir {
    /// `--out DIR`; `force`: clear what it holds.
    Given { path: PathBuf, force: bool },
    /// The default `runs/<name>-<n>`, the first n free when it is made.
    Numbered(String),
}

/// The out dir: as given, or `runs/<name>-<n>`. A given one that holds
/// files is refused unless `force`; nothing is made or cleared yet
/// ([`OutDir::make`]), so a run that cannot start leaves it as it was.
pub(super) fn choose_out_dir(out: Option<&Path>, name: &str, force: bool) -> anyhow::Result<OutDir> {
    let Some(path) = out else {
        return Ok(OutDir::Numbered(name.to_string()));
    };
    if path.exists() && !path.is_dir() {
        bail!("{} is a file, not a folder; choose another --out", path.display());
    }
    if holds_files(path)? {
        // Checked first, so that the hint offers --force only where it would work.
        let replaceable = check_replaceable(path);
        if !force {
            match replaceable {
                Ok(()) => bail!(
                    "{} already holds files; choose another --out, or add --force to replace them",
                    path.display()
                ),
                Err(e) => bail!("{} already holds files; {e}", path.display()),
            }
        }
        replaceable?;
    }
    Ok(OutDir::Given {
        path: path.to_path_buf(),
        force,
    })
}

/// The new out dir of a batch of runs (`carus sweep`, `carus sanity`),
/// made with its plan written in it first, the plan `--resume` goes on
/// from.
pub(super) fn make_batch_dir(output: &OutputArgs, name: &str, plan_file: &str, plan: &impl serde::Serialize) -> anyhow::Result<PathBuf> {
    let dir = choose_out_dir(output.out.as_deref(), name, output.force)?.make()?;
    let path = dir.join(plan_file);
    std::fs::write(&path, serde_json::to_string_pretty(plan)?).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(dir)
}

impl OutDir {
    /// Makes the folder and says where it is. A numbered folder is always a
    /// new one (a number taken meanwhile, by another run started at the same
    /// time, gives way to the next); a given one is cleared only with
    /// `--force`, and refused if it was filled meanwhile.
    pub(super) fn make(self) -> anyhow::Result<PathBuf> {
        match self {
            OutDir::Numbered(name) => {
                super::create_out_folder(Path::new("runs"), "--out")?;
                for n in 1.. {
                    let dir = PathBuf::from("runs").join(format!("{name}-{n}"));
                    // create_dir, not create_dir_all: it fails if the folder exists.
                    match std::fs::create_dir(&dir) {
                        Ok(()) => {
                            mark(&dir)?;
                            return Ok(dir);
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                        Err(e) => return Err(e).with_context(|| format!("cannot create {}", dir.display())),
                    }
                }
                unreachable!("a free number")
            }
            OutDir::Given { path, force } => {
                if holds_files(&path)? {
                    if !force {
                        bail!("{} was filled by another run meanwhile; choose another --out", path.display());
                    }
                    check_replaceable(&path)?;
                    std::fs::remove_dir_all(&path).with_context(|| format!("cannot clear {}", path.display()))?;
                }
                make_marked(&path)?;
                Ok(path)
            }
        }
    }
}

/// A run's report page.
pub(super) const REPORT_FILE: &str = "report.html";

/// The mark carus leaves in every out dir it makes, the moment it makes
/// it: a run cut off before it wrote anything else is still known as ours.
const OUT_DIR_MARK: &str = ".carus-out";

/// Files that together mark a folder carus wrote before it left
/// [`OUT_DIR_MARK`]: a run (its scenario with its record or checkpoint), a
/// sweep (its two tables) or a solve (its series with its summary). One
/// common file name alone is not enough.
const EARLIER_OUTPUT_MARKS: [&[&str]; 4] = [
    &["scenario.toml", "run.json"],
    &["scenario.toml", "checkpoint.json"],
    &[super::sweep::CSV_FILE, super::sweep::JSON_FILE],
    &[carus_io::job::SOLUTION_PVD, carus_io::job::SUMMARY_FILE],
];

/// Makes `dir` and marks it as an out dir of carus.
pub(super) fn make_marked(dir: &Path) -> anyhow::Result<()> {
    super::create_out_folder(dir, "--out")?;
    mark(dir)
}

/// Leaves [`OUT_DIR_MARK`] in `dir`, which exists.
fn mark(dir: &Path) -> anyhow::Result<()> {
    let mark = dir.join(OUT_DIR_MARK);
    std::fs::write(&mark, "written by carus: `--force` may replace this folder\n")
        .with_context(|| format!("cannot write {}", mark.display()))
}

/// Whether `dir` is an out dir of carus (a run's, a sweep's, sanity's).
pub(super) fn carus_made(dir: &Path) -> bool {
    dir.join(OUT_DIR_MARK).is_file() || EARLIER_OUTPUT_MARKS.iter().any(|files| files.iter().all(|f| dir.join(f).is_file()))
}

/// `--force` replaces a folder that carus wrote, never any other: a
/// mistyped `--out .` or `--out runs` must not delete a user's files or
/// the earlier runs beside them.
fn check_replaceable(dir: &Path) -> anyhow::Result<()> {
    let canonical = dir.canonicalize().with_context(|| format!("{}", dir.display()))?;
    // Both canonical, so that their forms agree (\\?\C:\ on Windows).
    if std::env::current_dir().and_then(|cwd| cwd.canonicalize()).is_ok_and(|cwd| cwd.starts_with(&canonical)) {
        bail!(
            "{} is the current folder or holds it, and --force does not clear that; choose a new --out",
            dir.display()
        );
    }
    // A run of a sweep or of sanity: their tables were written from it.
    if let Some(batch) = canonical.parent().filter(|p| super::holds_batch(p)) {
        bail!(
            "{} is one of the runs in {}, whose tables were written from it, and --force does not replace it; \
             choose another --out",
            dir.display(),
            batch.display()
        );
    }
    if !carus_made(dir) {
        bail!(
            "{} is not a folder that carus made (it has no {OUT_DIR_MARK}, nor a run's scenario.toml with \
             its run.json or checkpoint.json, nor a sweep's tables, nor a solve's series and summary), and \
             --force replaces only such a \
             folder; choose another --out, or empty it yourself",
            dir.display()
        );
    }
    let foreign = foreign_entries(dir)?;
    if !foreign.is_empty() {
        let shown: Vec<String> = foreign.iter().take(5).map(|p| p.display().to_string()).collect();
        bail!(
            "{} holds what carus did not write ({}{}), and --force deletes only carus's own files; \
             move them out first, or choose another --out",
            dir.display(),
            shown.join(", "),
            if foreign.len() > 5 { format!(" and {} more", foreign.len() - 5) } else { String::new() }
        );
    }
    Ok(())
}

/// What a folder carus made holds that carus did not write there (a
/// user's notes, an analysis folder, another run made inside it), which
/// `--force` must not delete: a run's files, its ParaView series, a
/// sweep's or sanity's plan and tables and its run folders, each checked
/// the same way, and `carus solve`'s frames, series, history and summary.
/// The files an operating system leaves in any folder it shows
/// (`.DS_Store`, `Thumbs.db`, `desktop.ini`) go with it.
pub(super) fn foreign_entries(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    use carus_labour::output::*;
    use carus_io::job as solve;
    let own = [
        OUT_DIR_MARK, SCENARIO_FILE, CHECKPOINT_FILE, HISTORY_JSON, HISTORY_CSV, CONTACTS_CSV, MOVEMENTS_FILE,
        RUN_FILE, PELVIS_VTU, LIGAMENTS_VTU, SOFT_WALLS_VTU, HEAD_BODY_VTU, TRUNK_BODY_VTU, LOWER_TRUNK_BODY_VTU, REPORT_FILE,
        super::sweep::PLAN_FILE, super::sweep::CSV_FILE, super::sweep::JSON_FILE, super::sanity::PLAN_FILE,
        super::sanity::RECORD_FILE, ".DS_Store", "Thumbs.db", "desktop.ini",
    ];
    // A sweep from before its plan was written has its two tables.
    let sweep_tables = [super::sweep::CSV_FILE, super::sweep::JSON_FILE];
    let batch = super::holds_batch(dir) || sweep_tables.iter().all(|f| dir.join(f).is_file());
    // Solve's common names (summary.json, history.csv) are its own only in
    // a folder that holds no run or batch: in a run's they are a user's.
    let solve_folder = !batch && !dir.join(SCENARIO_FILE).exists();
    let solve_own = [solve::SOLUTION_PVD, solve::HISTORY_FILE, solve::SUMMARY_FILE];
    let series = |name: &str| name.strip_suffix(".pvd").is_some_and(|stem| SERIES_STEMS.contains(&stem));
    // A file written whole goes through NAME.partial (write_json_whole, PVDs).
    let ours = |name: &str| {
        let name = name.strip_suffix(".partial").unwrap_or(name);
        own.contains(&name) || (solve_folder && solve_own.contains(&name)) || series(name)
    };
    let frame = |name: &str| {
        (solve_folder && solve::is_frame_name(name))
            || name.strip_suffix(".vtu").and_then(|stem| stem.rsplit_once('_')).is_some_and(|(stem, k)| {
                SERIES_STEMS.contains(&stem) && k.len() >= 4 && k.bytes().all(|b| b.is_ascii_digit())
            })
    };
    let list = |dir: &Path| -> anyhow::Result<Vec<(PathBuf, String, bool)>> {
        let mut entries = Vec::new();
        for entry in std::fs::read_dir(dir).with_context(|| format!("{}", dir.display()))? {
            let entry = entry.with_context(|| format!("{}", dir.display()))?;
            let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
            entries.push((entry.path(), entry.file_name().to_string_lossy().into_owned(), is_dir));
        }
        entries.sort();
        Ok(entries)
    };
    let mut foreign = Vec::new();
    for (path, name, is_dir) in list(dir)? {
        match is_dir {
            false if ours(&name) => {}
            true if name == FRAMES_DIR || name == solve::FRAMES_DIR => {
                foreign.extend(list(&path)?.into_iter().filter(|(_, n, d)| *d || !frame(n)).map(|(p, ..)| p))
            }
            true if batch && carus_made(&path) => foreign.extend(foreign_entries(&path)?),
            _ => foreign.push(path),
        }
    }
    Ok(foreign)
}

fn holds_files(dir: &Path) -> anyhow::Result<bool> {
    Ok(dir.exists()
        && std::fs::read_dir(dir)
            .with_context(|| format!("{}", dir.display()))?
            .next()
            .is_some())
}

/// Runs `scenario` from its start into `dir` (made here) with its report,
/// as `carus run` would, stopping cleanly when `stop` is set: one run of a
/// command that runs several (`carus sweep`, `carus sanity`).
pub(super) fn run_into(scenario: &Scenario, dir: &Path, stop: &Arc<AtomicBool>) -> anyhow::Result<RunRecord> {
    make_marked(dir)?;
    let record = carus_labour::run(scenario, dir, &stopped_by(stop), &mut carus_labour::SilentObserver)?;
    report_beside(&record, dir);
    Ok(record)
}

/// Run options that stop a run cleanly when `stop` is set (Ctrl-C).
fn stopped_by(stop: &Arc<AtomicBool>) -> RunOptions {
    RunOptions {
        stop: Some(stop.clone()),
        stop_at_s: None,
    }
}

/// A batch run's report.html; one that cannot be written is a warning,
/// never the run's loss.
fn report_beside(record: &RunRecord, dir: &Path) {
    if let Err(error) = write_report(record, dir) {
        eprintln!("warning: {}: report.html was not written: {}", dir.display(), crate::error_text(&error));
    }
}

/// The record of the run in `dir`, read from its run.json.
pub(super) fn read_record(dir: &Path) -> anyhow::Result<RunRecord> {
    let path = dir.join(carus_labour::output::RUN_FILE);
    let text = carus_io::input::read_text(&path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| {
        // The run's last checkpoint holds what the record is written from.
        let again = match dir.join(carus_labour::output::CHECKPOINT_FILE).is_file() {
            true => format!("`carus run --resume {}` writes it again from the run's last checkpoint", dir.display()),
            false => "run the scenario again".into(),
        };
        anyhow::anyhow!("{} is damaged ({e}); {again}", path.display())
    })
}

/// Whether the run in `dir` is over for good (`RunEnding::is_over`).
pub(super) fn run_ended(dir: &Path) -> bool {
    carus_labour::output::run_ending(dir).is_some_and(|e| e.is_over())
}

/// A run of a sweep or of the sanity cases into `dir`: run from the start
/// if it never began (always, in a new sweep's fresh folder), continued
/// from its checkpoint if it was stopped part way (with its report), kept
/// as it is if it ended.
pub(super) fn go_on_into(scenario: &Scenario, dir: &Path, stop: &Arc<AtomicBool>) -> anyhow::Result<RunRecord> {
    if run_ended(dir) {
        return read_record(dir);
    }
    if !dir.join(carus_labour::output::CHECKPOINT_FILE).exists() {
        return run_into(scenario, dir, stop);
    }
    let record = carus_labour::resume(dir, &stopped_by(stop), &mut carus_labour::SilentObserver)?;
    report_beside(&record, dir);
    Ok(record)
}

/// The command that goes on with the stopped run in `dir`: a run of a
/// sweep or sanity check goes on with its folder's, which also rewrites
/// the tables.
fn resume_command(dir: &Path) -> String {
    let parent = dir.parent().filter(|p| !p.as_os_str().is_empty());
    let command = parent.and_then(|p| {
        [("carus sweep", super::sweep::PLAN_FILE), ("carus sanity", super::sanity::PLAN_FILE)]
            .into_iter()
            .find(|(_, plan)| p.join(plan).is_file())
            .map(|(command, _)| format!("{command} --resume {}", p.display()))
    });
    command.unwrap_or_else(|| format!("carus run --resume {}", dir.display()))
}

pub(super) fn json_summary(record: &RunRecord, out_dir: &Path) -> serde_json::Value {
    json!({
        "outcome": record.summary.outcome,
        "movements": movements_json(&movements(record)),
        "simulated_s": record.summary.simulated_s,
        "wall_s": record.summary.wall_s,
        "out_dir": out_dir.display().to_string(),
        "completed": record.summary.completed,
        "failure": record.summary.failure,
        "posterior_rotation": record.detector.as_ref().map_or(Movement::absent(Unit::Deg), |d| d.posterior_rotation),
        "internal_rotation_outside_window": record
            .detector
            .as_ref()
            .and_then(|d| d.internal_rotation_outside_window),
        "head_born": record.detector.as_ref().and_then(|d| d.head_born),
        "not_held_at_birth": record.detector.as_ref().map_or(&[][..], |d| &d.not_held_at_birth),
        "shoulders": record.detector.as_ref().and_then(|d| d.shoulders),
        "scenario": record.summary.scenario,
        "mode": record.scenario.trajectory.mode.name(),
        "guide": GuideSummary::of(&record.loads),
    })
}

/// [`json_summary`]'s object, key for key, for a run that could not be
/// made (`failure` says why): nothing simulated, nothing observed, no
/// outcome reached (as a run stopped at its start reads); the scenario and
/// mode null, as the run never read them.
pub(super) fn json_summary_not_run(out_dir: &Path, failure: &str) -> serde_json::Value {
    json!({
        "outcome": Outcome { delivered: false, arrest: None },
        "movements": movements_json(&movement_list(&Movements::none())),
        "simulated_s": 0.0,
        "wall_s": 0.0,
        "out_dir": out_dir.display().to_string(),
        "completed": false,
        "failure": failure,
        "posterior_rotation": Movement::absent(Unit::Deg),
        "internal_rotation_outside_window": null,
        "head_born": null,
        "not_held_at_birth": [],
        "shoulders": null,
        "scenario": null,
        "mode": null,
        "guide": null,
    })
}

/// The seven movements as one JSON object under their canonical keys
/// (CONVENTIONS.md).
pub(super) fn movements_json(movements: &[(&'static str, Movement)]) -> serde_json::Value {
    let map: serde_json::Map<String, serde_json::Value> = movements
        .iter()
        .map(|(k, v)| (k.to_string(), serde_json::to_value(v).expect("plain data")))
        .collect();
    serde_json::Value::Object(map)
}

/// The seven movements under their canonical keys; all unobserved when the
/// run stopped before there was anything to detect.
pub(super) fn movements(record: &RunRecord) -> Vec<(&'static str, Movement)> {
    let all = record
        .detector
        .as_ref()
        .map_or_else(Movements::none, |d| d.movements);
    movement_list(&all)
}

/// The seven movements in canonical order, under their canonical keys.
pub(super) fn movement_list(all: &Movements) -> Vec<(&'static str, Movement)> {
    all.by_key().iter().map(|(k, m)| (*k, **m)).collect()
}

fn print_summary(record: &RunRecord, out_dir: &Path) {
    let s = &record.summary;
    println!("scenario {}: {}", s.scenario, outcome_line(&s.outcome));
    if let Some(line) = mode_line(record) {
        println!("{line}");
    }
    println!(
        "simulated {:.2} s in {:.1} s wall time ({} rigid steps)",
        s.simulated_s, s.wall_s, s.rigid_steps
    );
    print_movements(&movements(record), record.detector.as_ref());
    // Only what this run wrote: a run too short for a report has none.
    let mut written: Vec<&str> = [REPORT_FILE, "run.json", "movements.json", "pose_history.csv"]
        .into_iter()
        .filter(|f| out_dir.join(f).is_file())
        .collect();
    if record.files.head_pvd.is_some() {
        written.push("*.pvd");
    }
    print!("results in {} ({})", out_dir.display(), written.join(", "));
    match record.history.samples.len() >= 2 {
        true => println!("; replay it with `carus view {}`", out_dir.display()),
        false => println!(),
    }
}

/// What moved the head, when not the physics alone: the mode, and how
/// hard the guide (the teacher's hand) worked.
fn mode_line(record: &RunRecord) -> Option<String> {
    let trajectory = &record.scenario.trajectory;
    let how = match trajectory.mode {
        Mode::Forward => return None,
        Mode::Imposed => "the head followed its way-points (imposed mode, not the physics)",
        Mode::Hybrid => "the physics, with the head guided towards its way-points (hybrid mode)",
    };
    let guide = GuideSummary::of(&record.loads).map_or(String::new(), |g| {
        format!(
            "; the guide's force on the head: peak {:.0} N, mean {:.0} N; its moment: peak {:.2} N m, mean {:.2} N m",
            g.peak_force_n, g.mean_force_n, g.peak_moment_nm, g.mean_moment_nm
        )
    });
    let n = trajectory.waypoints.len();
    Some(format!("{how}, {n} way-point{}{guide}", if n == 1 { "" } else { "s" }))
}

/// The outcome in words: delivered, or where, what and against what it arrested.
pub(super) fn outcome_line(outcome: &Outcome) -> String {
    if outcome.delivered {
        return "delivered".to_string();
    }
    match &outcome.arrest {
        Some(a) => {
            // A history read from a table may name neither.
            let held = match a.part.as_str() {
                "unknown" => String::new(),
                part => format!(
                    "the {part}{} ",
                    a.shoulders_holding_head()
                        .map_or(String::new(), |s| format!(" (shoulders at station {s:+.0} mm)"))
                ),
            };
            let against = match a.against.as_str() {
                "unknown" => "a contact the history does not name",
                site => site,
            };
            // A shoulder arrest's station is the bisacromial midpoint's, and
            // how the shoulders lie says what holds them.
            let what = if a.stage == ArrestStage::Shoulders { "shoulders at station" } else { "station" };
            let lie = a.held_shoulders_from_ap_deg().map_or(String::new(), |deg| format!(" {deg:.0} deg from antero-posterior,"));
            format!(
                "arrested at the {} stage, {what} {:+.0} mm,{lie} {held}against {against}",
                serde_name(&a.stage),
                a.station_mm,
            )
        }
        None => "neither delivered nor arrested (the run ended too soon to tell)".to_string(),
    }
}

/// One line per movement: observed with its span and size, or not; an
/// internal rotation the rule did not count for where it happened says so.
/// Then how the head was born, if it was, and which counted movement it
/// had lost by then (`detector`: none before there was anything to detect).
pub(super) fn print_movements(movements: &[(&'static str, Movement)], detector: Option<&DetectorReport>) {
    let rotation_outside_window = detector.and_then(|d| d.internal_rotation_outside_window);
    let not_held = detector.map_or(&[][..], |d| &d.not_held_at_birth);
    // Times keep their column however long they run (a history in ms).
    let posterior = detector.map(|d| d.posterior_rotation);
    let width = movements
        .iter()
        .map(|(_, m)| m)
        .chain(posterior.as_ref())
        .flat_map(|m| [m.start_s, m.end_s])
        .flatten()
        .map(|t| format!("{t:.1}").len())
        .fold(6, usize::max);
    for (key, m) in movements {
        let unit = serde_name(&m.unit);
        match (m.observed, m.start_s, m.end_s, m.size) {
            (true, Some(a), Some(b), Some(size)) => {
                let lost = if not_held.iter().any(|n| n.movement == *key) { "  (not held at birth)" } else { "" };
                println!("{}{lost}", observed_line(key, [a, b], width, size, &unit))
            }
            _ => match rotation_outside_window.filter(|_| *key == "internal_rotation") {
                Some(r) => println!("  {key:18} not observed: {r}"),
                None => println!("  {key:18} not observed"),
            },
        }
    }
    // Not one of the seven, but what a head that turned to OP did instead.
    if let Some(Movement { observed: true, start_s: Some(a), end_s: Some(b), size: Some(size), .. }) = posterior {
        println!("{}  (to occiput posterior)", observed_line("posterior_rotation", [a, b], width, size, "deg"));
    }
    if let Some(born) = detector.and_then(|d| d.head_born) {
        println!("  {born}");
    }
    for lost in not_held {
        println!("  {lost}");
    }
    if let Some(passage) = detector.and_then(|d| d.shoulders) {
        println!("  {passage}");
    }
}

/// An observed movement's line: key, span (its times `width` wide) and size.
fn observed_line(key: &str, [start_s, end_s]: [f64; 2], width: usize, size: f64, unit: &str) -> String {
    format!("  {key:18} observed  {start_s:width$.1}-{end_s:width$.1} s  {size:6.1} {unit}")
}

/// The name an enum value has in the JSON output (e.g. `mid-pelvis`), so
/// the text summary and `--json` speak the same words.
pub(super) fn serde_name<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Long times widen the column for every line alike.
    #[test]
    fn a_movement_line_keeps_its_columns_for_long_times() {
        assert_eq!(observed_line("descent", [1.08, 11.39], 6, 142.6, "mm"), "  descent            observed     1.1-  11.4 s   142.6 mm");
        assert_eq!(observed_line("descent", [1080.0, 11390.0], 7, 142.6, "mm"), "  descent            observed   1080.0-11390.0 s   142.6 mm");
    }

    /// The coarse normal scenario run for `end_s`, its folder gone.
    fn coarse_record(end_s: f64) -> RunRecord {
        let dir = tempfile::tempdir().unwrap();
        let s = crate::commands::coarse_normal(end_s);
        carus_labour::run(&s, dir.path(), &RunOptions::default(), &mut carus_labour::SilentObserver).unwrap()
    }

    /// The report's row names the most elements with an inverted corner at
    /// one sample, out of the floor's, and when the first appeared.
    #[test]
    fn the_report_counts_inverted_corners() {
        let mut record = coarse_record(0.3);
        assert_eq!(record.summary.floor_elements, 48);
        assert_eq!(inverted_corners(&record), "none of 48");
        record.floor[1].inverted_corner_elements = 2;
        record.floor[2].inverted_corner_elements = 5;
        let t = record.floor[1].time_s;
        assert_eq!(inverted_corners(&record), format!("up to 5 of 48, from t = {t:.1} s"));
    }

    /// A run stopped before its end says so at the top of its report, with
    /// the command that goes on; a finished one has no notice.
    #[test]
    fn a_stopped_run_s_report_says_it_was_stopped() {
        let dir = tempfile::tempdir().unwrap();
        let s = crate::commands::coarse_normal(0.4);
        let stop = RunOptions { stop_at_s: Some(0.2), ..RunOptions::default() };
        let record = carus_labour::run(&s, dir.path(), &stop, &mut carus_labour::SilentObserver).unwrap();
        assert!(!record.summary.completed);
        write_report(&record, dir.path()).unwrap();
        let page = std::fs::read_to_string(dir.path().join("report.html")).unwrap();
        let expected = format!("The run was stopped at t = 0.20 s, before its end at 0.4 s: this page shows the labour so far, not its outcome. Go on with: carus run --resume {}", dir.path().display());
        assert!(page.contains(&carus_report::page::escape(&expected)), "{expected}");
        let finished = coarse_record(0.2);
        write_report(&finished, dir.path()).unwrap();
        assert!(!std::fs::read_to_string(dir.path().join("report.html")).unwrap().contains("id=\"notice\""));
    }

    /// A stopped run of a sweep or sanity check goes on with its folder's
    /// command, which also rewrites the tables; a plain run with its own.
    #[test]
    fn a_stopped_run_goes_on_with_the_command_that_made_it() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("01-x");
        std::fs::create_dir(&run).unwrap();
        assert_eq!(resume_command(&run), format!("carus run --resume {}", run.display()));
        for (plan, command) in [(super::super::sweep::PLAN_FILE, "carus sweep"), (super::super::sanity::PLAN_FILE, "carus sanity")] {
            std::fs::write(dir.path().join(plan), "{}").unwrap();
            assert_eq!(resume_command(&run), format!("{command} --resume {}", dir.path().display()));
            std::fs::remove_file(dir.path().join(plan)).unwrap();
        }
    }

    /// The report's pictures carry the forces at each key moment the run
    /// reached, at that moment's sample, listed largest first, the neck's
    /// push among them; a record without loads has none.
    #[test]
    fn the_report_draws_the_forces_at_each_key_moment() {
        let mut record = coarse_record(4.0);
        let detector = record.detector.clone().unwrap();
        let (moments, _) = carus_analysis::moments::key_moments(&detector);
        assert!(!moments.is_empty(), "the run reached no key moment");
        let built = Scene::build(&record.scenario).unwrap();
        let scene = report_scene_with_forces(&record, &built, &detector).unwrap();
        let samples: Vec<usize> = scene.forces.iter().map(|f| f.sample).collect();
        assert_eq!(samples, moments.iter().map(|m| m.sample).collect::<Vec<_>>());
        for forces in &scene.forces {
            let sizes: Vec<f64> = forces.listed.iter().map(|(_, n, _)| *n).collect();
            assert!(!sizes.is_empty() && sizes.windows(2).all(|w| w[0] >= w[1]), "{sizes:?}");
        }
        let labels: Vec<&str> = scene.forces.iter().flat_map(|f| f.listed.iter().map(|(l, _, _)| l.as_str())).collect();
        assert!(labels.contains(&"expulsion") && labels.contains(&"neck"), "{labels:?}");

        // The plot of what pushes the head: during a contraction the push
        // reaching it drives it down the canal, no more than the expulsion.
        let canal = head_canal_forces(&record, &built);
        assert_eq!(canal.len(), record.loads.len());
        let mut pushed = 0;
        for (f, sample) in canal.iter().zip(&record.history.samples) {
            let expulsion = sample.expulsion_force_n.length();
            if expulsion > 50.0 {
                assert!(f.push_n > 0.0 && f.push_n < expulsion, "t = {}: {f:?}", f.time_s);
                pushed += 1;
            }
            assert_eq!(f.guide_n, 0.0);
        }
        assert!(pushed > 0);
        // A run recorded before the neck's force was has no such plot.
        let mut older = record.clone();
        older.loads.iter_mut().for_each(|l| l.neck_force_n = None);
        assert!(head_canal_forces(&older, &built).is_empty());
        record.loads.clear();
        assert!(report_scene_with_forces(&record, &built, &detector).unwrap().forces.is_empty());
    }

    /// `--json` and the text summary say how the head was moved: the mode
    /// always, and how hard the guide worked when there was one.
    #[test]
    fn a_run_says_how_its_head_was_moved() {
        let run_with = |s: &Scenario| {
            let dir = tempfile::tempdir().unwrap();
            let record = carus_labour::run(s, dir.path(), &RunOptions::default(), &mut carus_labour::SilentObserver).unwrap();
            let json = json_summary(&record, dir.path());
            (record, json)
        };
        let forward = crate::commands::coarse_normal(0.1);
        let (record, json) = run_with(&forward);
        assert_eq!((json["mode"].as_str(), json["guide"].is_null()), (Some("forward"), true));
        assert_eq!(mode_line(&record), None);
        // A trunk's shoulders are reported even before they come near the inlet.
        assert!(json["shoulders"].is_object() && json["shoulders"]["inlet_s"].is_null(), "{json}");

        let mut imposed = forward.clone();
        imposed.trajectory.mode = Mode::Imposed;
        imposed.trajectory.waypoints =
            vec![carus_labour::Waypoint { time_s: 0.1, station_mm: -50.0, theta_deg: -80.0, phi_deg: 10.0, anterior_mm: 0.0 }];
        let (record, json) = run_with(&imposed);
        assert_eq!(json["mode"].as_str(), Some("imposed"));
        assert!(json["guide"]["peak_force_n"].as_f64().unwrap() > 0.0, "{json}");
        let line = mode_line(&record).unwrap();
        assert!(line.contains("imposed mode, not the physics") && line.contains("1 way-point;") && line.contains("peak"), "{line}");
    }

    /// A scenario whose pelvis cannot be built is refused with the table,
    /// the diameters and a hint, before any out dir is made, and an earlier
    /// run is kept even under --force.
    #[test]
    fn a_scenario_that_cannot_start_touches_no_out_dir() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("narrow.toml");
        std::fs::write(&file, "name = \"narrow\"\n[pelvis]\ninterspinous_mm = 140.0\n").unwrap();
        let args = |out: PathBuf, force: bool| RunArgs {
            scenario: Some(file.display().to_string()),
            settings: Vec::new(),
            output: OutputArgs { out: Some(out), json: true, force, quiet: true },
            resume: None,
        };
        let fresh = dir.path().join("fresh");
        let e = format!("{:#}", run(&args(fresh.clone(), false)).err().unwrap());
        assert!(e.contains("narrow.toml") && e.contains("[pelvis]") && e.contains("interspinous_mm = 140"), "{e}");
        assert!(e.contains("hint: `carus measure pelvis FILE`"), "{e}");
        assert!(!fresh.exists());

        let earlier = dir.path().join("earlier");
        std::fs::create_dir(&earlier).unwrap();
        std::fs::write(earlier.join("run.json"), "{}").unwrap();
        assert!(run(&args(earlier.clone(), true)).is_err());
        assert!(earlier.join("run.json").exists());
        // Without --force an occupied out dir is named first, and --force
        // is offered only for a folder it would replace.
        let e = format!("{:#}", run(&args(earlier.clone(), false)).err().unwrap());
        assert!(e.contains("already holds files") && e.contains("not a folder that carus made"), "{e}");
        assert!(!e.contains("add --force"), "{e}");

        // --resume given a run's file names the folder to give instead; a
        // scenario file, the command that runs it.
        let resume = |path: PathBuf| RunArgs {
            scenario: None,
            settings: Vec::new(),
            output: OutputArgs { out: None, json: true, force: false, quiet: true },
            resume: Some(path),
        };
        std::fs::write(earlier.join("scenario.toml"), "").unwrap();
        let e = format!("{:#}", run(&resume(earlier.join("run.json"))).err().unwrap());
        assert!(e.contains(&format!("is a file; --resume takes the run's folder: `carus run --resume {}`", earlier.display())), "{e}");
        let e = format!("{:#}", run(&resume(file.clone())).err().unwrap());
        assert!(e.contains(&format!("is a file, not a run's folder; --resume goes on with a run that `carus run` wrote (a scenario is run with `carus run {}`)", file.display())), "{e}");
    }

    /// `--set` changes the scenario a run starts from, and its folder's
    /// scenario.toml keeps the change (so `--resume` goes on with it); a
    /// key that does not exist is refused before any out dir is made.
    #[test]
    fn set_changes_the_scenario_a_run_starts_from() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("coarse.toml");
        std::fs::write(&file, crate::commands::coarse_normal(0.05).to_toml().unwrap()).unwrap();
        let args = |out: PathBuf, settings: &[&str]| RunArgs {
            scenario: Some(file.display().to_string()),
            settings: settings.iter().map(|s| s.to_string()).collect(),
            output: OutputArgs { out: Some(out), json: true, force: false, quiet: true },
            resume: None,
        };
        let out = dir.path().join("dry");
        run(&args(out.clone(), &["contact.friction=0.35", "numerics.end_time_s=0.02"])).unwrap();
        let kept = Scenario::from_file(&out.join("scenario.toml")).unwrap();
        assert_eq!(kept.contact.friction, 0.35);
        assert_eq!(kept.numerics.end_time_s, 0.02);
        // --force knows every file a run writes, and refuses to delete what
        // a user added to the folder.
        assert_eq!(foreign_entries(&out).unwrap(), Vec::<PathBuf>::new());
        let forced = |out: &Path| RunArgs {
            output: OutputArgs { out: Some(out.to_path_buf()), json: true, force: true, quiet: true },
            ..args(out.to_path_buf(), &["numerics.end_time_s=0.02"])
        };
        // A user's notes, folder, ParaView state, frame, and a run made
        // inside this one, each refused; what an OS leaves is not.
        let nested = out.join("variant");
        std::fs::create_dir(&nested).unwrap();
        std::fs::write(nested.join(OUT_DIR_MARK), "").unwrap();
        std::fs::create_dir(out.join("analysis")).unwrap();
        let frames = out.join(carus_labour::output::FRAMES_DIR);
        std::fs::create_dir_all(&frames).unwrap();
        let added = [out.join("my_notes.txt"), out.join("my_state.pvd"), frames.join("mine_0001.vtu")];
        for file in &added {
            std::fs::write(file, "mine").unwrap();
        }
        std::fs::write(out.join(".DS_Store"), "").unwrap();
        let e = format!("{:#}", run(&forced(&out)).err().unwrap());
        for name in ["my_notes.txt", "my_state.pvd", "mine_0001.vtu", "analysis", "variant"] {
            assert!(e.contains(name), "{name}: {e}");
        }
        assert!(!e.contains(".DS_Store") && e.contains("move them out first"), "{e}");
        assert!(added.iter().all(|f| f.exists()) && nested.exists() && out.join(carus_labour::output::RUN_FILE).exists());
        for file in &added {
            std::fs::remove_file(file).unwrap();
        }
        std::fs::remove_dir_all(&nested).unwrap();
        std::fs::remove_dir(out.join("analysis")).unwrap();
        run(&forced(&out)).unwrap();

        let misspelt = dir.path().join("misspelt");
        let e = format!("{:#}", run(&args(misspelt.clone(), &["contact.fiction=0.35"])).err().unwrap());
        assert!(e.contains("fiction") && e.contains("carus scenarios show"), "{e}");
        assert!(!misspelt.exists());
        assert!(one_setting_arg("contact.friction=0.1,0.35").unwrap_err().contains("carus sweep"));
        assert!(one_setting_arg("contact.friction").unwrap_err().contains("KEY=VALUE"));
    }

    /// A run stopped by its output says how to go on from its checkpoint,
    /// when it has one; other errors are left as they are.
    #[test]
    fn a_run_stopped_by_its_output_says_how_to_resume() {
        let dir = tempfile::tempdir().unwrap();
        let full = || anyhow::Error::from(LabourError::Output {
            path: dir.path().join("checkpoint.json.partial"),
            message: "No space left on device (os error 28)".into(),
        });
        assert!(!format!("{:#}", resumable(full(), dir.path())).contains("--resume"));
        std::fs::write(dir.path().join("checkpoint.json"), "{}").unwrap();
        let e = format!("{:#}", resumable(full().context("scenario normal"), dir.path()));
        assert!(e.contains("No space left") && e.contains(&format!("carus run --resume {}", dir.path().display())), "{e}");
        let other = anyhow::anyhow!("the fetal head left the birth canal");
        assert!(!format!("{:#}", resumable(other, dir.path())).contains("--resume"));
        // A checkpoint that cannot be read is no place to go on from.
        let damaged = anyhow::Error::from(LabourError::Output {
            path: dir.path().join("checkpoint.json"),
            message: "not a whole JSON file; run the scenario again from the start".into(),
        });
        assert!(!format!("{:#}", resumable(damaged, dir.path())).contains("--resume"));
    }

    /// `--set` mends a value the file has wrong; what else the file has
    /// wrong is still named at its own line.
    #[test]
    fn a_setting_mends_a_bad_value_in_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("bad.toml");
        let text = Scenario::builtin("normal").unwrap().to_toml().unwrap().replace("friction = 0.009", "friction = -0.1");
        std::fs::write(&file, &text).unwrap();
        let named = file.display().to_string();
        let e = load_changed(Some(&named), &[]).unwrap_err().to_string();
        assert!(e.contains("`contact.friction` = -0.1"), "{e}");
        let mended = load_changed(Some(&named), &["contact.friction=0.05".into()]).unwrap();
        assert_eq!(mended.contact.friction, 0.05);
        // Another key the file has wrong is named at its line, not by the settings.
        let twice_bad = text.replace("force_max_n = 120.0", "force_max_n = -5.0");
        std::fs::write(&file, &twice_bad).unwrap();
        let line = twice_bad.lines().position(|l| l.starts_with("force_max_n = -5.0")).unwrap() + 1;
        let e = load_changed(Some(&named), &["contact.friction=0.05".into()]).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{named}:{line}: `expulsion.force_max_n` = -5")), "{e}");
    }

    /// A scenario file's start refused by the anatomy points at its line,
    /// once; a built-in's is named by the scenario.
    #[test]
    fn a_start_the_anatomy_refuses_names_its_file_once() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("high.toml");
        let text = Scenario::builtin("normal").unwrap().with_setting("start.station_mm", "60").unwrap().to_toml().unwrap();
        std::fs::write(&file, &text).unwrap();
        let line = text.lines().position(|l| l.starts_with("station_mm = 60")).unwrap() + 1;
        let named = file.display().to_string();
        let scenario = load_changed(Some(&named), &[]).unwrap();
        let e = crate::error_text(&in_scenario(Scene::build(&scenario), &named).map(drop).unwrap_err());
        assert!(e.starts_with(&format!("{named}:{line}: `start.station_mm` = 60: the head starts")), "{e}");
        let builtin = load_changed(Some("normal"), &["start.station_mm=60".into()]).unwrap();
        let e = crate::error_text(&in_scenario(Scene::build(&builtin), "normal").map(drop).unwrap_err());
        assert!(e.starts_with("scenario normal: `start.station_mm = 60`: the head starts"), "{e}");
    }

    /// An out dir filled between its choice and its making (another run
    /// started at the same time) is never cleared without --force.
    #[test]
    fn an_out_dir_filled_meanwhile_is_not_cleared() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let chosen = choose_out_dir(Some(&out), "x", false).unwrap();
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("run.json"), "{}").unwrap();
        std::fs::write(out.join("scenario.toml"), "").unwrap();
        let e = format!("{:#}", chosen.make().err().unwrap());
        assert!(e.contains("filled by another run meanwhile"), "{e}");
        assert!(out.join("run.json").exists());
        let forced = choose_out_dir(Some(&out), "x", true).unwrap().make().unwrap();
        assert_eq!(forced, out);
        assert!(!out.join("run.json").exists());
    }

    /// `--force` replaces a folder that carus wrote and nothing else: not
    /// a user's folder, not the folder that holds earlier runs.
    #[test]
    fn force_replaces_only_a_folder_that_carus_wrote() {
        let dir = tempfile::tempdir().unwrap();
        let mine = dir.path().join("thesis");
        std::fs::create_dir(&mine).unwrap();
        std::fs::write(mine.join("notes.txt"), "mine").unwrap();
        let e = format!("{:#}", choose_out_dir(Some(&mine), "x", true).err().unwrap());
        assert!(e.contains("is not a folder that carus made") && e.contains(".carus-out"), "{e}");
        assert!(mine.join("notes.txt").exists());

        let runs = dir.path().join("runs");
        std::fs::create_dir_all(runs.join("normal-1")).unwrap();
        std::fs::write(runs.join("normal-1/run.json"), "{}").unwrap();
        assert!(choose_out_dir(Some(&runs), "x", true).is_err());
        assert!(runs.join("normal-1/run.json").exists());

        // One common file name alone does not make a folder ours.
        let lone = dir.path().join("lone");
        std::fs::create_dir(&lone).unwrap();
        std::fs::write(lone.join("run.json"), "{}").unwrap();
        assert!(choose_out_dir(Some(&lone), "x", true).is_err());

        // A run inside a sweep's or sanity's folder is theirs to redo.
        for (name, plan) in [("sweep", super::super::sweep::PLAN_FILE), ("sanity", super::super::sanity::PLAN_FILE)] {
            let batch = dir.path().join(name);
            let member = batch.join("normal");
            std::fs::create_dir_all(&member).unwrap();
            std::fs::write(batch.join(plan), "{}").unwrap();
            std::fs::write(member.join(OUT_DIR_MARK), "").unwrap();
            let e = format!("{:#}", choose_out_dir(Some(&member), "x", true).err().unwrap());
            assert!(e.contains("is one of the runs in") && !e.contains("add --force"), "{e}");
            let e = format!("{:#}", choose_out_dir(Some(&member), "x", false).err().unwrap());
            assert!(e.contains("is one of the runs in") && !e.contains("add --force"), "{e}");
            assert!(member.join(OUT_DIR_MARK).exists());
        }

        let marks: Vec<&[&str]> = [&[OUT_DIR_MARK][..]].into_iter().chain(EARLIER_OUTPUT_MARKS).collect();
        for (i, files) in marks.into_iter().enumerate() {
            let earlier = dir.path().join(format!("earlier-{i}"));
            std::fs::create_dir(&earlier).unwrap();
            for f in files {
                std::fs::write(earlier.join(f), "{}").unwrap();
            }
            let frame = earlier.join(carus_labour::output::frame_name("head", 0));
            std::fs::create_dir(frame.parent().unwrap()).unwrap();
            std::fs::write(&frame, "").unwrap();
            assert_eq!(choose_out_dir(Some(&earlier), "x", true).unwrap().make().unwrap(), earlier);
            assert!(!frame.exists(), "{files:?}");
            // The folder made is marked, so it can be replaced again.
            assert!(earlier.join(OUT_DIR_MARK).is_file());
        }

        // `carus solve`'s common names are a user's in a run's folder.
        let run = dir.path().join("run");
        std::fs::create_dir_all(run.join("frames")).unwrap();
        for f in [OUT_DIR_MARK, "scenario.toml", "run.json"] {
            std::fs::write(run.join(f), "{}").unwrap();
        }
        let users = [run.join("summary.json"), run.join("history.csv"), run.join("frames/frame_00001.vtu")];
        for f in &users {
            std::fs::write(f, "mine").unwrap();
        }
        let e = format!("{:#}", choose_out_dir(Some(&run), "x", true).err().unwrap());
        assert!(e.contains("holds what carus did not write") && e.contains("summary.json") && e.contains("frame_00001.vtu"), "{e}");
        assert!(users.iter().all(|f| f.exists()));
    }
}
