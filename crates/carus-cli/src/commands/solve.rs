//! `carus solve JOB.toml --out DIR`: runs a soft-tissue job file (mesh,
//! materials, loads, time stepping; docs/SOLVE.md) and writes VTU frames, a
//! PVD series, a CSV history and a summary. The work is done by
//! `carus_io::job`; this module parses flags and prints.

use std::path::PathBuf;

use carus_io::job::{prepare_job, JobReport, Progress, RunOptions};

use super::run::choose_out_dir;
use super::{print_json, Status};

#[derive(clap::Args)]
pub struct SolveArgs {
    /// Job file (TOML): mesh file, materials, boundary conditions, solver
    /// and output settings, as docs/SOLVE.md describes.
    pub job: PathBuf,
    /// Output folder (frames/*.vtu, solution.pvd, history.csv, summary.json).
    #[arg(long)]
    pub out: PathBuf,
    /// Replace what the output folder holds, if carus wrote it all (refused if it holds anything else).
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
    // As `carus run` chooses its folder: --force replaces only one that
    // carus made, and never deletes what a user added to it.
    let chosen = choose_out_dir(Some(&args.out), "solve", args.force)?;
    let show = super::shows_progress(args.quiet);
    if !args.quiet {
        eprintln!("solving {} into {}", args.job.display(), args.out.display());
    }
    let stop = super::ctrl_c_flag();
    let job = prepare_job(&args.job)?;
    // Ctrl-C while the model was built: the folder is not touched.
    if stop.load(std::sync::atomic::Ordering::Relaxed) {
        eprintln!("stopped before the solve began; {} was left as it was", args.out.display());
        return Ok(Status::Failed);
    }
    // Made (or an earlier run in it cleared) only now: a job that cannot
    // start leaves the folder as it was.
    let out_dir = chosen.make()?;
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
    let report = job.run_into(&out_dir, &RunOptions { stop: Some(stop) }, &mut progress);
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    /// A job of a few steps on the example cube, written in `dir`.
    fn quick_job(dir: &Path) -> PathBuf {
        let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cube_n5.msh");
        let job = dir.join("job.toml");
        let text = format!(
            "[mesh]\nfile = {mesh:?}\nlength_unit = \"m\"\n[[material]]\nlaw = \"neo_hookean\"\nshear_modulus_pa = 1000.0\n\
             bulk_modulus_pa = 50000.0\ndensity_kg_m3 = 1000.0\n[[fixed]]\nnode_set = \"x0\"\n[solver]\nend_time_s = 0.01\n"
        );
        std::fs::write(&job, text).unwrap();
        job
    }

    fn args(job: &Path, out: &Path, force: bool) -> SolveArgs {
        SolveArgs { job: job.to_path_buf(), out: out.to_path_buf(), force, json: true, quiet: true }
    }

    /// A folder carus did not make is refused, with or without --force,
    /// and --force is not offered for it; its files are left as they were.
    #[test]
    fn force_does_not_replace_a_folder_carus_did_not_make() {
        let dir = tempfile::tempdir().unwrap();
        let job = quick_job(dir.path());
        let mine = dir.path().join("mystudy");
        std::fs::create_dir_all(mine.join("frames")).unwrap();
        let files = [mine.join("history.csv"), mine.join("summary.json"), mine.join("frames/frame_00001.vtu")];
        for file in &files {
            std::fs::write(file, "mine").unwrap();
        }
        let e = format!("{:#}", run(&args(&job, &mine, false)).err().unwrap());
        assert!(e.contains("already holds files") && e.contains("is not a folder that carus made"), "{e}");
        assert!(!e.contains("--force to replace") && !e.contains("add --force"), "{e}");
        let e = format!("{:#}", run(&args(&job, &mine, true)).err().unwrap());
        assert!(e.contains("is not a folder that carus made") && e.contains("empty it yourself"), "{e}");
        assert!(files.iter().all(|f| std::fs::read_to_string(f).unwrap() == "mine"));
        assert!(!mine.join(".carus-out").exists());
    }

    /// A folder `carus solve` made is marked: --force replaces it, unless
    /// a user added something to it, which it names and keeps.
    #[test]
    fn force_replaces_a_solve_folder_and_keeps_what_a_user_added() {
        let dir = tempfile::tempdir().unwrap();
        let job = quick_job(dir.path());
        let out = dir.path().join("out");
        assert!(matches!(run(&args(&job, &out, false)).unwrap(), Status::Success));
        assert!(out.join(".carus-out").is_file() && out.join("frames/frame_00000.vtu").is_file());
        // --force knows every file a solve writes.
        assert_eq!(super::super::run::foreign_entries(&out).unwrap(), Vec::<PathBuf>::new());
        let e = format!("{:#}", run(&args(&job, &out, false)).err().unwrap());
        assert!(e.contains("already holds files") && e.contains("add --force to replace them"), "{e}");
        std::fs::write(out.join("summary.json"), "earlier").unwrap();
        assert!(matches!(run(&args(&job, &out, true)).unwrap(), Status::Success));
        assert_ne!(std::fs::read_to_string(out.join("summary.json")).unwrap(), "earlier");

        let added = [out.join("notes.txt"), out.join("frames/mine.vtu")];
        for file in &added {
            std::fs::write(file, "mine").unwrap();
        }
        let e = format!("{:#}", run(&args(&job, &out, true)).err().unwrap());
        assert!(e.contains("notes.txt") && e.contains("mine.vtu") && e.contains("move them out first"), "{e}");
        assert!(added.iter().all(|f| f.exists()) && out.join("summary.json").is_file());
    }

    /// A job that cannot start touches no folder: none is made, and an
    /// earlier run is kept even under --force.
    #[test]
    fn a_job_that_cannot_start_touches_no_out_dir() {
        let dir = tempfile::tempdir().unwrap();
        let job = quick_job(dir.path());
        let out = dir.path().join("out");
        run(&args(&job, &out, false)).unwrap();
        let earlier = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let text = std::fs::read_to_string(&job).unwrap().replace("end_time_s = 0.01", "end_time_s = -1.0");
        std::fs::write(&job, text).unwrap();
        let e = format!("{:#}", run(&args(&job, &out, true)).err().unwrap());
        assert!(e.contains("`solver.end_time_s`"), "{e}");
        assert_eq!(std::fs::read_to_string(out.join("summary.json")).unwrap(), earlier);
        let fresh = dir.path().join("fresh");
        assert!(run(&args(&job, &fresh, false)).is_err());
        assert!(!fresh.exists());
    }
}
