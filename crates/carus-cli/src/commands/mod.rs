//! One module per subcommand; each owns its clap arguments and its `run`.

pub mod bench;
pub mod detect;
pub mod measure;
pub mod mesh;
pub mod render;
pub mod run;
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
