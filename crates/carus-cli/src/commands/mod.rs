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

/// Prints `value` as one JSON object on standard output (CONVENTIONS.md:
/// with `--json`, nothing else goes to standard output).
pub fn print_json<T: serde::Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}
