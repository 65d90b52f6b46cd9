//! `carus bench tled`: times the TLED solver on the V3 cube and, in the same
//! run, the plain single-threaded baseline of the same algorithm
//! (`carus_fem::baseline`), so the speed-up is measured, not assumed. Also
//! reports the process's peak resident memory per element.
//!
//! The cube: edge 0.1 m, n^3 H8 or 6 n^3 T4, the V3 tissue, x = 0 fixed,
//! x = L pulled 0.03 m over 1 s (VALIDATION.md V3), dt the critical step.
//!
//! `carus bench labour [NAME|FILE]`: a whole labour run, as `carus run`
//! makes it (outputs and report included, into a folder removed after),
//! with the wall time of each stage of the rigid step, against issue 4's
//! target for the normal scenario.

use std::time::Instant;

use anyhow::Context;
use carus_fem::gpu::{bench_tled, AdapterChoice, DeviceError, GpuDevice, GpuError, MIN_TIMED_S};
use carus_fem::validation::cube::{baseline_solver, CubeElement, CubeSetup, CubeVariant, RAMP_S};
use carus_fem::validation::tissue_model;
use carus_fem::{ElementKind, LoadShape, Precision, StepControl, TledSolver};
use carus_labour::StageTimes;
use serde::Serialize;

use super::run::{load_changed, run_into};
use super::settings::one_setting_arg;
use super::{ctrl_c_flag, print_json, Status};

#[derive(clap::Subcommand)]
pub enum BenchCommand {
    /// Time the TLED solver (and the plain baseline) on the V3 cube.
    Tled(TledBenchArgs),
    /// Time a whole labour run, stage by stage (default: the normal scenario).
    Labour(LabourBenchArgs),
}

#[derive(clap::Args)]
pub struct LabourBenchArgs {
    /// A built-in scenario name (`carus scenarios`) or a scenario file (TOML). Default: normal.
    pub scenario: Option<String>,
    /// KEY=VALUE changed in the scenario, as `carus run --set` does
    /// (e.g. floor.mesh.elements_around=48); repeat for more keys.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = one_setting_arg)]
    pub settings: Vec<String>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
    /// Accepted as every long command accepts it: the labour bench shows
    /// no progress, and writes only warnings on standard error.
    #[arg(long)]
    pub quiet: bool,
}

/// Issue 4: the normal scenario runs to its end in under 2 minutes on a
/// 2-core machine like CI's.
const NORMAL_TARGET_WALL_S: f64 = 120.0;

#[derive(clap::Args)]
pub struct TledBenchArgs {
    /// Element type of the cube.
    #[arg(long, value_enum, default_value = "h8")]
    pub element: ElementArg,
    /// Elements per edge (the cube has n^3 H8 or 6 n^3 T4).
    #[arg(long, default_value_t = 20)]
    pub n: usize,
    /// Timed steps (default: about 2e7 element-steps, at least 10; on a GPU, more until a run lasts a second).
    #[arg(long)]
    pub steps: Option<u64>,
    /// Worker threads of the CPU solver (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Precision of the CPU kernels: f32 by default, the precision of the
    /// hot loops that V3 validates (`carus validate v3`: f32 within 3e-5 of
    /// the edge of f64, tolerance 1e-2) and the GPU backend runs.
    #[arg(long, value_enum, default_value = "f32")]
    pub precision: PrecisionArg,
    /// Where the step loop runs: cpu, gpu (f32, its own threads), or auto
    /// (a real GPU if present, the CPU when --threads or --precision f64 is given).
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: BackendArg,
    /// GPU: the device's peak memory bandwidth, GB/s, for the fraction of peak.
    #[arg(long)]
    pub peak_gbs: Option<f64>,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
    /// No progress or notes on standard error (no progress either when it
    /// is not a terminal).
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ElementArg {
    H8,
    T4,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum PrecisionArg {
    F64,
    F32,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendArg {
    Cpu,
    Gpu,
    Auto,
}

/// The figures of one CPU bench run; the first eight keys are issue 2's.
#[derive(Serialize)]
struct CpuBenchReport {
    elements: usize,
    nodes: usize,
    steps: u64,
    wall_s: f64,
    us_per_element_step: f64,
    element_steps_per_s: f64,
    threads: usize,
    backend: &'static str,
    element: &'static str,
    n: usize,
    precision: &'static str,
    dt_s: f64,
    baseline_steps: u64,
    baseline_wall_s: f64,
    baseline_us_per_element_step: f64,
    /// Baseline time per element-step over the solver's.
    speedup: f64,
    /// Peak resident set (VmHWM) after the solver's run, before the
    /// baseline is built: mesh, model and solver state together.
    peak_rss_bytes: Option<u64>,
    bytes_per_element: Option<f64>,
    /// The model's own arrays (mesh copy and kernel data) per element.
    model_bytes_per_element: f64,
}

/// The figures of one labour bench run.
#[derive(Serialize)]
struct LabourBenchReport {
    scenario: String,
    simulated_s: f64,
    /// The whole run as `carus run` spends it: build, steps, outputs, report.
    wall_s: f64,
    simulated_s_per_wall_s: f64,
    threads: usize,
    completed: bool,
    failure: Option<String>,
    delivered: bool,
    rigid_steps: u64,
    rigid_dt_s: f64,
    us_per_rigid_step: f64,
    floor_elements: usize,
    floor_substeps_per_step: u32,
    /// Rigid steps whose floor was sub-stepped finer (an element pressed
    /// flat), and the most sub-steps one took: they cost more.
    floor_refined_steps: u64,
    floor_most_substeps: u32,
    /// Wall time of each stage of the rigid steps, in step order.
    stages_wall_s: StageTimes,
    /// Before the first step: building the scene, writing the parts that
    /// do not move (pelvis, ligaments, fetal bodies, scenario.toml).
    setup_wall_s: f64,
    /// Writing frames and checkpoints, keeping floor snapshots, detecting
    /// the movements and writing the pose history.
    output_wall_s: f64,
    /// run.json, then report.html with its pictures.
    report_wall_s: f64,
    peak_rss_bytes: Option<u64>,
    /// Issue 4's figure for the built-in normal scenario; null for any other.
    target_wall_s: Option<f64>,
    /// Whether the run beat it; null without a target, or for a run that
    /// did not reach its end.
    target_met: Option<bool>,
}

pub fn run(cmd: &BenchCommand) -> anyhow::Result<Status> {
    match cmd {
        BenchCommand::Tled(args) => tled(args),
        BenchCommand::Labour(args) => labour(args),
    }
}

fn labour(args: &LabourBenchArgs) -> anyhow::Result<Status> {
    let report = labour_bench(args.scenario.as_deref(), &args.settings)?;
    // Figures of a run that did not reach its end time no whole run.
    let status = if report.completed { Status::Success } else { Status::Failed };
    if args.json {
        print_json(&report)?;
        return Ok(status);
    }
    let ending = match (&report.failure, report.completed, report.delivered) {
        (Some(failure), _, _) => format!("ended early: {failure}"),
        (None, false, _) => "stopped before its end".to_string(),
        (None, true, true) => "delivered".to_string(),
        (None, true, false) => "not delivered".to_string(),
    };
    println!(
        "labour `{}`: {:.2} s simulated in {:.1} s wall ({:.2} simulated s per wall s), {} threads; {ending}",
        report.scenario, report.simulated_s, report.wall_s, report.simulated_s_per_wall_s, report.threads
    );
    println!(
        "  {} rigid steps of {} ms, {:.0} us each; floor {} elements, {} TLED sub-steps per rigid step",
        report.rigid_steps,
        report.rigid_dt_s * 1e3,
        report.us_per_rigid_step,
        report.floor_elements,
        report.floor_substeps_per_step
    );
    if report.floor_refined_steps > 0 {
        println!(
            "  {} rigid steps sub-stepped finer on a flattened floor element, up to {} sub-steps",
            report.floor_refined_steps, report.floor_most_substeps
        );
    }
    let share = |s: f64| 100.0 * s / report.wall_s;
    for (name, s) in report.stages_wall_s.named() {
        println!("  {name:<14} {s:>7.2} s  {:>4.1} %", share(s));
    }
    for (name, s) in [
        ("setup", report.setup_wall_s),
        ("output", report.output_wall_s),
        ("report", report.report_wall_s),
    ] {
        println!("  {name:<14} {s:>7.2} s  {:>4.1} %", share(s));
    }
    if let Some(rss) = report.peak_rss_bytes {
        println!("  peak RSS {:.0} MiB", rss as f64 / 1048576.0);
    }
    if let Some(target) = report.target_wall_s {
        let verdict = match report.target_met {
            None => "not judged, the run did not reach its end",
            Some(true) => "met",
            Some(false) => "NOT met",
        };
        println!("  issue 4's target, the normal scenario to its end in under {target:.0} s on 2 cores: {verdict} on this machine");
    }
    Ok(status)
}

/// Runs the scenario as `carus run` would, into a folder removed after,
/// and reads the figures off its record.
fn labour_bench(scenario: Option<&str>, settings: &[String]) -> anyhow::Result<LabourBenchReport> {
    let scenario = load_changed(scenario, settings)?;
    // The target is for the built-in scenario as it is, not an edit of it.
    let is_builtin_normal = scenario.to_toml()? == carus_labour::Scenario::builtin("normal")?.to_toml()?;
    let folder = tempfile::tempdir().context("cannot make a folder for the bench's run")?;
    let dir = folder.path().join(&scenario.name);
    let stop = ctrl_c_flag();
    let started = Instant::now();
    let record = run_into(&scenario, &dir, &stop)?;
    let wall_s = started.elapsed().as_secs_f64();
    let summary = &record.summary;
    let stages = summary.stage_wall_s;
    let stepping_s = stages.total_s();
    let target_wall_s = is_builtin_normal.then_some(NORMAL_TARGET_WALL_S);
    Ok(LabourBenchReport {
        scenario: scenario.name.clone(),
        simulated_s: summary.simulated_s,
        wall_s,
        simulated_s_per_wall_s: summary.simulated_s / wall_s,
        threads: rayon::current_num_threads(),
        completed: summary.completed,
        failure: summary.failure.clone(),
        delivered: summary.outcome.delivered,
        rigid_steps: summary.rigid_steps,
        rigid_dt_s: summary.rigid_dt_s,
        us_per_rigid_step: stepping_s * 1e6 / summary.rigid_steps.max(1) as f64,
        floor_elements: summary.floor_elements,
        floor_substeps_per_step: summary.floor_substeps_per_step,
        floor_refined_steps: summary.floor_refined_steps,
        floor_most_substeps: summary.floor_most_substeps,
        stages_wall_s: stages,
        // The run's own wall time is its setup, its steps and its writing.
        setup_wall_s: (summary.wall_s - stepping_s - summary.output_wall_s).max(0.0),
        output_wall_s: summary.output_wall_s,
        report_wall_s: (wall_s - summary.wall_s).max(0.0),
        peak_rss_bytes: peak_rss_bytes(),
        target_wall_s,
        target_met: target_wall_s.filter(|_| summary.completed).map(|target| wall_s < target),
    })
}

fn tled(args: &TledBenchArgs) -> anyhow::Result<Status> {
    if args.n == 0 {
        crate::bad_argument!("--n must be at least 1");
    }
    if args.threads == Some(0) {
        crate::bad_argument!("--threads must be at least 1");
    }
    if args.steps == Some(0) {
        crate::bad_argument!("--steps must be at least 1: a rate needs timed steps");
    }
    if let Some(peak) = args.peak_gbs.filter(|p| !(p.is_finite() && *p > 0.0)) {
        crate::bad_argument!("--peak-gbs {peak}: the device's peak memory bandwidth, a positive number of GB/s (e.g. 3350 for an H100)");
    }
    // The GPU's kernels are f32 and its threads its own: flags it would ignore are refused.
    if args.backend == BackendArg::Gpu && args.threads.is_some() {
        crate::bad_argument!("--threads sets the CPU solver's worker threads; --backend gpu has none (drop --threads, or use --backend cpu)");
    }
    if args.backend == BackendArg::Gpu && matches!(args.precision, PrecisionArg::F64) {
        crate::bad_argument!("--precision f64: the GPU kernels are f32; f64 runs with --backend cpu");
    }
    let cpu_only = args.threads.is_some() || matches!(args.precision, PrecisionArg::F64);
    let kind = match args.element {
        ElementArg::H8 => ElementKind::H8,
        ElementArg::T4 => ElementKind::T4,
    };
    let per_cell = if kind == ElementKind::H8 { 1 } else { 6 };
    super::check_cube_size(args.n, per_cell, false)?;
    let elements = args.n.pow(3) * per_cell;
    let steps = args.steps.unwrap_or((2e7 as u64 / elements as u64).clamp(10, 5000));
    // `auto` with a CPU-only flag times the CPU, as asked.
    if args.backend == BackendArg::Gpu || (args.backend == BackendArg::Auto && !cpu_only) {
        match gpu_bench(args, kind, steps)? {
            Some(status) => return Ok(status),
            None if args.quiet => {}
            None => eprintln!("notice: no real GPU adapter found; `--backend auto` runs on the CPU"),
        }
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if let Some(threads) = args.threads.filter(|t| *t > cores && !args.quiet) {
        // Allowed (it measures oversubscription), but rarely meant.
        eprintln!("notice: --threads {threads} on {cores} cores: the threads take turns, so the figures time their contention as well as the solver");
    }
    let report = match args.threads {
        Some(threads) => rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("could not start the worker threads")?
            .install(|| cpu_bench(args, kind, steps))?,
        None => cpu_bench(args, kind, steps)?,
    };
    if args.json {
        print_json(&report)?;
    } else {
        println!(
            "TLED {} n={} ({} elements, {} nodes), {} threads, {}, dt {:.3e} s",
            report.element, report.n, report.elements, report.nodes, report.threads, report.precision, report.dt_s
        );
        println!(
            "  solver:   {} steps in {:.3} s: {:.4} us per element-step, {:.3e} element-steps/s",
            report.steps, report.wall_s, report.us_per_element_step, report.element_steps_per_s
        );
        println!(
            "  baseline: {} steps in {:.3} s: {:.4} us per element-step (single-threaded scalar f64)",
            report.baseline_steps, report.baseline_wall_s, report.baseline_us_per_element_step
        );
        println!("  speed-up: {:.2} x", report.speedup);
        if let (Some(rss), Some(per)) = (report.peak_rss_bytes, report.bytes_per_element) {
            println!(
                "  memory:   peak RSS {:.1} MiB, {:.0} bytes per element ({:.0} in the model)",
                rss as f64 / 1048576.0,
                per,
                report.model_bytes_per_element
            );
        }
    }
    Ok(Status::Success)
}

/// Runs the GPU bench; None when `auto` found no real GPU.
fn gpu_bench(args: &TledBenchArgs, kind: ElementKind, steps: u64) -> anyhow::Result<Option<Status>> {
    let choice = if args.backend == BackendArg::Gpu { AdapterChoice::BestAvailable } else { AdapterChoice::RealGpuOnly };
    let device = match GpuDevice::headless(choice) {
        Ok(device) => device,
        Err(DeviceError::NoAdapter { .. }) if args.backend == BackendArg::Auto => return Ok(None),
        Err(error) => return Err(GpuError::from(error).into()),
    };
    // Without --steps, a GPU run times at least MIN_TIMED_S (submission latency).
    let min_wall_s = args.steps.is_none().then_some(MIN_TIMED_S);
    let report = bench_tled(&device, kind, args.n, steps, min_wall_s, args.peak_gbs)?;
    if args.json {
        print_json(&report)?;
    } else {
        println!(
            "TLED {} n={} ({} elements, {} nodes) on {}: {} steps in {:.3} s: {:.4} us per element-step, {:.3e} element-steps/s, {:.1} GB/s",
            kind.name(),
            args.n,
            report.elements,
            report.nodes,
            report.adapter,
            report.steps,
            report.wall_s,
            report.us_per_element_step,
            report.element_steps_per_s,
            report.achieved_bandwidth_gbs
        );
    }
    Ok(Some(Status::Success))
}

fn cpu_bench(args: &TledBenchArgs, kind: ElementKind, steps: u64) -> anyhow::Result<CpuBenchReport> {
    let element = if kind == ElementKind::H8 { CubeElement::H8 } else { CubeElement::T4 };
    let precision = match args.precision {
        PrecisionArg::F64 => Precision::F64,
        PrecisionArg::F32 => Precision::F32,
    };
    let setup = CubeSetup { precision, ..CubeSetup::miller(args.n, element, CubeVariant::FreeLateral) };
    let mesh = setup.mesh();
    let model = tissue_model(&mesh, &setup.options())?;
    let dt = model.critical_time_step();
    let model_bytes_per_element = model.memory_bytes() as f64 / model.element_count() as f64;
    let bcs = setup.boundary_conditions(&mesh);
    let (elements, nodes) = (model.element_count(), model.node_count());
    let show = super::shows_progress(args.quiet);
    if show {
        eprintln!("timing the solver: {steps} steps of {elements} elements ...");
    }
    let mut solver = TledSolver::new(model, &bcs, dt, StepControl::Refuse)?;
    // Warm-up: first touches of the state arrays and the thread pool.
    solver.step()?;
    let start = Instant::now();
    for _ in 0..steps {
        solver.step()?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let peak_rss_bytes = peak_rss_bytes();
    drop(solver);

    if show {
        eprintln!("timing the single-threaded baseline: {steps} steps ...");
    }
    let mut baseline = baseline_solver(&setup, &mesh, dt)?;
    let shape = LoadShape::RampHold { ramp_s: RAMP_S };
    baseline.step(shape.value(dt))?;
    let start = Instant::now();
    for step in 2..steps + 2 {
        baseline.step(shape.value(step as f64 * dt))?;
    }
    let baseline_wall_s = start.elapsed().as_secs_f64();

    let element_steps = (elements as u64 * steps) as f64;
    let us_per_element_step = wall_s * 1e6 / element_steps;
    let baseline_us_per_element_step = baseline_wall_s * 1e6 / element_steps;
    Ok(CpuBenchReport {
        elements,
        nodes,
        steps,
        wall_s,
        us_per_element_step,
        element_steps_per_s: element_steps / wall_s,
        threads: rayon::current_num_threads(),
        backend: "cpu",
        element: kind.name(),
        n: args.n,
        precision: match precision {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        },
        dt_s: dt,
        baseline_steps: steps,
        baseline_wall_s,
        baseline_us_per_element_step,
        speedup: baseline_us_per_element_step / us_per_element_step,
        peak_rss_bytes,
        bytes_per_element: peak_rss_bytes.map(|b| b as f64 / elements as f64),
        model_bytes_per_element,
    })
}

/// Peak resident set size of this process (VmHWM in /proc/self/status),
/// None where the file is absent (not Linux).
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Flags only the CPU has are bad arguments with the GPU backend.
    #[test]
    fn the_gpu_backend_refuses_cpu_only_flags() {
        let args = |threads: Option<usize>, precision: PrecisionArg| TledBenchArgs {
            element: ElementArg::H8,
            n: 2,
            steps: Some(1),
            threads,
            precision,
            backend: BackendArg::Gpu,
            peak_gbs: None,
            json: true,
            quiet: true,
        };
        for (threads, precision, flag) in [(Some(2), PrecisionArg::F32, "--threads"), (None, PrecisionArg::F64, "--precision f64")] {
            let e = tled(&args(threads, precision)).expect_err(flag);
            assert!(e.downcast_ref::<crate::commands::BadArgument>().is_some() && e.to_string().starts_with(flag), "{e}");
        }
    }

    /// The labour bench runs the scenario as `carus run` would and accounts
    /// for its wall time stage by stage, with its `--set` changes; the
    /// target applies to `normal` only.
    #[test]
    fn the_labour_bench_accounts_for_the_runs_wall_time() {
        let s = crate::commands::coarse_normal(0.3);
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("coarse.toml");
        std::fs::write(&file, s.to_toml().unwrap()).unwrap();
        let shortened = ["numerics.end_time_s=0.2".to_string()];
        let report = labour_bench(Some(file.to_str().unwrap()), &shortened).unwrap();
        assert!(report.completed && report.failure.is_none());
        assert_eq!(report.simulated_s, 0.2);
        assert_eq!(report.rigid_steps, (0.2 / s.numerics.rigid_dt_s).round() as u64);
        let stages = report.stages_wall_s;
        assert!(stages.named().iter().all(|(_, t)| *t >= 0.0));
        assert!(stages.bone_contacts_s > 0.0 && stages.floor_tled_s > 0.0);
        // The parts were timed inside the run, the whole outside it.
        let run_wall_s = report.wall_s - report.report_wall_s;
        assert!(stages.total_s() + report.output_wall_s <= run_wall_s, "{stages:?} in {run_wall_s} s");
        assert!(report.setup_wall_s > 0.0 && report.report_wall_s > 0.0);
        assert_eq!(report.target_wall_s, None, "the coarse scenario is not the built-in `normal`");
        assert_eq!(report.target_met, None);
        assert!(report.floor_elements > 0 && report.floor_substeps_per_step > 0);
        // 0.2 s in, the floor has not been touched: nothing refined.
        assert_eq!((report.floor_refined_steps, report.floor_most_substeps), (0, report.floor_substeps_per_step));
    }
}
