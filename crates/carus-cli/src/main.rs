//! `carus`: forward simulation of human childbirth from physics.
//!
//! Exit status (CONVENTIONS.md): 0 on success, 1 on a failed validation or an
//! error the user can fix, 2 on bad arguments (clap's own code).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod commands;

use commands::Status;

#[derive(Parser)]
#[command(name = "carus", version, about = "Forward simulation of human childbirth from physics")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a verification case of docs/VALIDATION.md and print PASS/FAIL (`cube`: the V3 cube's figures, without a verdict; `v3` judges them).
    Validate(commands::validate::ValidateArgs),
    /// Measure speed and print figures.
    #[command(subcommand)]
    Bench(commands::bench::BenchCommand),
    /// Solve a soft-tissue model (mesh file + loads) and write VTU/PVD results.
    Solve(commands::solve::SolveArgs),
    /// Build or import anatomy and print every diameter, plane and landmark.
    Measure(commands::measure::MeasureArgs),
    /// Write anatomy surfaces (STL in mm, VTU in m) and volume meshes (VTU) for inspection.
    Mesh(commands::mesh::MeshArgs),
    /// Draw anatomy from standard views into a PNG contact sheet.
    Render(commands::render::RenderArgs),
    /// Run a labour scenario (forward from physics, or along an imposed or hybrid trajectory) and detect the cardinal movements.
    Run(commands::run::RunArgs),
    /// List the built-in scenarios, or print one as TOML.
    Scenarios(commands::scenarios::ScenariosArgs),
    /// Run a scenario at every combination of the values given, and tabulate the outcomes.
    Sweep(commands::sweep::SweepArgs),
    /// Detect the cardinal movements and the outcome in a recorded pose history.
    Detect(commands::detect::DetectArgs),
    /// Run the clinical sanity cases (normal, contracted inlet, face, large shoulders) and judge each against its expected outcome.
    Sanity(commands::sanity::SanityArgs),
    /// Replay a run in a window (time slider, play, orbiting camera), or draw one of its frames to a PNG.
    View(commands::view::ViewArgs),
}

fn main() -> ExitCode {
    end_quietly_on_a_closed_pipe();
    let cli = Cli::parse();
    quiet_headless_vulkan();
    // The main thread joins the pool as one of its workers: a labour run
    // calls dozens of small parallel passes per millisecond of simulated
    // time, and from a thread outside the pool each would be handed to a
    // worker and waited for (a wake-up and a sleep per pass).
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    let result = match &cli.command {
        Command::Validate(args) => commands::validate::run(args),
        Command::Bench(cmd) => commands::bench::run(cmd),
        Command::Solve(args) => commands::solve::run(args),
        Command::Measure(args) => commands::measure::run(args),
        Command::Mesh(args) => commands::mesh::run(args),
        Command::Render(args) => commands::render::run(args),
        Command::Run(args) => commands::run::run(args),
        Command::Scenarios(args) => commands::scenarios::run(args),
        Command::Sweep(args) => commands::sweep::run(args),
        Command::Detect(args) => commands::detect::run(args),
        Command::Sanity(args) => commands::sanity::run(args),
        Command::View(args) => commands::view::run(args),
    };
    match result {
        Ok(Status::Success) => ExitCode::SUCCESS,
        Ok(Status::Failed) => ExitCode::from(1),
        Err(error) => {
            eprintln!("error: {}", error_text(&error));
            ExitCode::from(error_status(&error))
        }
    }
}

/// 2 for a bad argument, 1 for any other error (CONVENTIONS.md).
fn error_status(error: &anyhow::Error) -> u8 {
    // A scenario's refusal of a `--set KEY=VALUE` (a key it lacks, a value
    // it refuses), and a picture size over the adapter's limit (`--size`),
    // are bad arguments too.
    let refused_setting = error.chain().any(|e| {
        matches!(e.downcast_ref::<carus_labour::ScenarioError>(), Some(carus_labour::ScenarioError::Setting { .. }))
            || matches!(e.downcast_ref::<carus_render::RenderError>(), Some(carus_render::RenderError::InvalidSize { .. }))
            || matches!(
                e.downcast_ref::<carus_view::ViewError>(),
                Some(carus_view::ViewError::Render(carus_render::RenderError::InvalidSize { .. }))
            )
    });
    match error.downcast_ref::<commands::BadArgument>().is_some() || refused_setting {
        true => 2,
        false => 1,
    }
}

/// On a machine without a display (no `XDG_RUNTIME_DIR`), Mesa's
/// device-select layer, which ranks GPUs by the display they drive, has
/// nothing to rank by and prints an error for every Vulkan instance; it is
/// turned off there, before any thread starts, unless the user chose.
fn quiet_headless_vulkan() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() && std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

/// The error and its causes, each once: many of the crates' errors already
/// print their cause (`cannot read F: No such file`), which `{:#}` would
/// repeat after them.
pub(crate) fn error_text(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    for cause in error.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

/// Rust ignores SIGPIPE, so printing into a pipe whose reader has gone
/// (`carus scenarios | head -1`) panics; with the default action restored
/// the process ends quietly, as other command-line tools do. Everything a
/// run writes to files is written before its summary is printed.
fn end_quietly_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first in main, before any other thread exists; it
    // only sets the signal's disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(test)]
mod tests {
    /// A cause the message already quotes is not repeated; one it does not is added.
    #[test]
    fn each_cause_is_printed_once() {
        #[derive(Debug)]
        struct Read {
            source: std::io::Error,
        }
        impl std::fmt::Display for Read {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "cannot read x.stl: {}", self.source)
            }
        }
        impl std::error::Error for Read {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.source)
            }
        }
        let missing = || std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        let e = anyhow::Error::from(Read { source: missing() }).context("[pelvis] import");
        assert_eq!(super::error_text(&e), "[pelvis] import: cannot read x.stl: No such file");
        let e = anyhow::Error::from(missing()).context("scenario my.toml");
        assert_eq!(super::error_text(&e), "scenario my.toml: No such file");
    }

    /// A flag's value refused after parsing is a bad argument too (exit
    /// status 2), with context or without; any other error is 1.
    #[test]
    fn a_value_refused_after_parsing_exits_2() {
        use clap::Parser;
        let cli = super::Cli::try_parse_from(["carus", "validate", "cube", "--n", "3"]).unwrap();
        let super::Command::Validate(args) = &cli.command else { panic!("validate") };
        let e = super::commands::validate::run(args).err().unwrap();
        assert_eq!(super::error_status(&e), 2, "{e}");
        assert_eq!(super::error_status(&e.context("in context")), 2);
        assert_eq!(super::error_status(&anyhow::anyhow!("cannot read f")), 1);
        // A `--set` whose key or value the scenario refuses, as well.
        for setting in ["numerics.end_time_s=abc", "contact.fiction=0.3"] {
            let e = super::commands::run::load_changed(None, &[setting.to_string()]).err().unwrap();
            assert_eq!(super::error_status(&e), 2, "{setting}: {e}");
        }
        // And a picture size past the adapter's limit, however it comes.
        let size = || carus_render::RenderError::InvalidSize { width: 100_000, height: 10, max: 16_384 };
        assert_eq!(super::error_status(&size().into()), 2);
        assert_eq!(super::error_status(&anyhow::Error::from(carus_view::ViewError::from(size())).context("picture")), 2);
    }

    /// A malformed `--set` (or sweep's `--with`) is a bad argument (clap's
    /// exit status 2), named with the form to write, for every command that
    /// takes one.
    #[test]
    fn a_malformed_setting_is_a_bad_argument() {
        use clap::Parser;
        for args in [
            &["carus", "sweep", "--set", "contact.friction"][..],
            &["carus", "sweep", "--set", "contact.friction=0.1,0.1"],
            &["carus", "sanity", "--set", "contact.friction=0.1,0.2"],
            &["carus", "run", "--set", "contact.friction=0.1,0.2"],
            &["carus", "bench", "labour", "--set", "contact.friction"],
            &["carus", "sweep", "--set", "contact.friction=0.1,0.2", "--with", "output.vtu"],
            &["carus", "sweep", "--set", "contact.friction=0.1,0.2", "--with", "output.vtu=true,false"],
        ] {
            let e = super::Cli::try_parse_from(args).err().expect("refused");
            assert_eq!(e.exit_code(), 2, "{args:?}");
            let flag = if args.contains(&"--with") { "--with output.vtu" } else { "--set" };
            assert!(e.to_string().contains(flag), "{e}");
        }
        assert!(super::Cli::try_parse_from(["carus", "sweep", "--set", "contact.friction=0.1,0.2"]).is_ok());
    }
}

