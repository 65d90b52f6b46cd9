//! `carus solve JOB.toml --out DIR`: runs a soft-tissue job file (mesh,
//! materials, loads, time stepping; docs/SOLVE.md) and writes VTU frames, a
//! PVD series, a CSV history and a summary. The work is done by
//! `carus_io::job`; this module parses flags and prints.

use std::path::PathBuf;

use carus_io::job::{run_job, JobReport, Progress, RunOptions};

use super::{print_json, Status};

#[derive(clap::Args)]
pub struct SolveArgs {
    /// Job file (TOML): mesh file, materials, boundary conditions, solver
    /// and output settings, as docs/SOLVE.md describes.
    pub job: PathBuf,
    /// Output folder (frames/*.vtu, solution.pvd, history.csv, summary.json).
    #[arg(long)]
    pub out: PathBuf,
    /// Replace an earlier run in the output folder.
    #[arg(long)]
    pub force: bool,
    /// Print one JSON object on standard output and nothing else there.
    #[arg(long)]
    pub json: bool,
    /// No progress or notes on standard error.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: &SolveArgs) -> anyhow::Result<Status> {
    let show = super::shows_progress(args.quiet);
    if !args.quiet {
        eprintln!("solving {} into {}", args.job.display(), args.out.display());
    }
    let bar = show.then(super::progress_bar);
    let mut progress = |p: &Progress| {
        if let Some(bar) = &bar {
            bar.set_length((p.end_time_s * 1e6) as u64);
            bar.set_position((p.time_s * 1e6) as u64);
            bar.set_message(format!(
                "t = {:.4} / {:.4} s, {} steps, {} frames",
                p.time_s, p.end_time_s, p.steps, p.frames
            ));
        }
    };
    let report = run_job(
        &args.job,
        &args.out,
        &RunOptions {
            force: args.force,
            stop: Some(super::ctrl_c_flag()),
        },
        &mut progress,
    );
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let report = report?;
    if !args.quiet {
        for note in &report.notes {
            eprintln!("note: {note}");
        }
    }
    if args.json {
        print_json(&report)?;
    } else {
        print_summary(&report);
    }
    match &report.failure {
        Some(failure) => {
            eprintln!("error: the run stopped early: {failure}");
            Ok(Status::Failed)
        }
        None => Ok(Status::Success),
    }
}

fn print_summary(report: &JobReport) {
    println!(
        "{} {} elements, {} nodes; {} frames written to {} (solution.pvd, history.csv, summary.json)",
        report.elements,
        report.element_kind.to_uppercase(),
        report.nodes,
        report.frames,
        report.out_dir
    );
    let substeps = match report.substeps_per_step {
        1 => String::new(),
        n => format!(", {n} sub-steps each"),
    };
    println!(
        "{} steps of {:.4e} s (critical step {:.4e} s{substeps}): {:.6} s simulated in {:.2} s",
        report.steps, report.dt_s, report.critical_dt_s, report.simulated_s, report.wall_s
    );
    println!(
        "largest displacement at the end: {:.4} mm",
        report.max_displacement_m * 1e3
    );
    for (set, f) in &report.reactions_n {
        println!(
            "reaction on {set}: [{:.6e}, {:.6e}, {:.6e}] N",
            f[0], f[1], f[2]
        );
    }
}
