//! One module per subcommand; each owns its clap arguments and its `run`.

pub mod bench;
pub mod detect;
pub mod measure;
pub mod mesh;
pub mod render;
pub mod run;
pub mod sanity;
pub mod scenarios;
pub mod solve;
pub mod sweep;
pub mod validate;

/// How a command that ran to completion ended.
pub enum Status {
    /// Everything asked for was done (and every check passed).
    Success,
    /// The command ran, but a check it reports failed (exit status 1).
    Failed,
}

/// The progress bar of long commands: permille done, elapsed, time left.
pub fn progress_bar() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}, about {eta} left")
            .expect("valid template"),
    );
    bar
}

/// A stop flag that Ctrl-C sets: a labour run polls it and stops cleanly
/// with everything so far written.
pub fn ctrl_c_flag() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    // A second Ctrl-C is left to the default handler only if this fails to install.
    let _ = ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed));
    stop
}

/// The threads of a command that runs several labours at once: `jobs` of
/// them, by default one per core; also says how many.
pub fn labour_pool(jobs: Option<usize>) -> anyhow::Result<(rayon::ThreadPool, usize)> {
    let jobs = jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start {jobs} threads for the runs: {e}"))?;
    Ok((pool, jobs))
}

/// Prints `value` as one JSON object on standard output (CONVENTIONS.md:
/// with `--json`, nothing else goes to standard output).
pub fn print_json<T: serde::Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

/// The normal scenario made coarse for the commands' tests: a coarser
/// head, sparser contact samples, a small floor, `end_s` simulated, no VTU.
#[cfg(test)]
pub fn coarse_normal(end_s: f64) -> carus_labour::Scenario {
    let mut s = carus_labour::Scenario::builtin("normal").unwrap();
    s.numerics.head_subdivisions = 3;
    s.contact.sample_spacing_mm = 8.0;
    s.floor.mesh.elements_around = 16;
    s.floor.mesh.elements_across = 3;
    s.numerics.end_time_s = end_s;
    s.output.vtu = false;
    s
}
