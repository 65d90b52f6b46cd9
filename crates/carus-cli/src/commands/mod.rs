//! One module per subcommand; each owns its clap arguments and its `run`.

pub mod bench;
pub mod measure;
pub mod mesh;
pub mod render;
pub mod run;
pub mod scenarios;
pub mod solve;
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
