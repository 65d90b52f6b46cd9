//! `carus solve`: a soft-tissue model described by a TOML job file (mesh
//! file, materials per element set, boundary conditions on named sets,
//! time stepping, output), run with the TLED solver of carus-fem and
//! written as VTU frames, a PVD series, a CSV history and a summary.
//!
//! The command-line module only parses flags and prints; everything else
//! lives here so that it is testable without the binary.

mod load;
mod run;
pub mod spec;

use std::num::NonZeroUsize;
use std::path::PathBuf;

use crate::toml_text::located;

pub use load::{load_job, mesh_path, parse_job};
pub use run::{
    is_frame_name, prepare_job, run_job, JobReport, PreparedJob, Progress, RunOptions, FRAMES_DIR, HISTORY_FILE,
    SOLUTION_PVD, SUMMARY_FILE,
};
pub use spec::JobSpec;

use crate::error::{ReadError, WriteError};

/// The fix for a job file that could not be read, by why.
fn read_fix(cause: &std::io::Error) -> &'static str {
    match cause.kind() {
        std::io::ErrorKind::InvalidData => {
            "save it as a UTF-8 text file (TOML, as examples/cube_extension.toml; an editor may have saved it as UTF-16)"
        }
        _ => "check the path",
    }
}

/// The fix for an output folder that could not be made.
fn out_dir_fix(dir: &std::path::Path) -> &'static str {
    match dir.is_file() {
        true => "it is a file, not a folder; choose another --out",
        false => "check the path and its permissions",
    }
}

/// Why a job could not run (a solver failure mid-run is not one of these:
/// it ends in a [`JobReport`] whose `failure` says what happened).
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The job file could not be read.
    #[error("{}: cannot read the job file: {cause}; fix: {}", path.display(), read_fix(cause))]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// TOML syntax, an unknown key or a value of the wrong type or unit.
    #[error("{}:{line}:{column}: {}{message}; hint: {hint}", path.display(), if key.is_empty() { String::new() } else { format!("`{key}`: ") })]
    Syntax {
        path: PathBuf,
        line: usize,
        column: usize,
        /// Dotted path of the key (`solver.time_step_s`, `material[1].law`).
        key: String,
        message: String,
        hint: String,
    },
    /// A value that cannot be right (a negative modulus, a missing pair).
    #[error("{}: `{key}`: {problem}; fix: {fix}", located(path, *line))]
    Invalid {
        path: PathBuf,
        /// The key's line in the job file; None where it writes no such key
        /// (non-zero: keeps every `Result<_, JobError>` small).
        line: Option<NonZeroUsize>,
        key: String,
        problem: String,
        fix: String,
    },
    /// A set the job names is not in the mesh.
    #[error("{}: `{key}` names the {kind} {name:?}, which the mesh does not have; fix: use one of: {}", located(path, *line), if available.is_empty() { "(the mesh has none; define it in the mesh file)".to_string() } else { available.join(", ") })]
    UnknownSet {
        path: PathBuf,
        line: Option<NonZeroUsize>,
        key: String,
        kind: &'static str,
        name: String,
        available: Vec<String>,
    },
    /// The mesh file could not be read.
    #[error(transparent)]
    Mesh(#[from] ReadError),
    /// The solver refused the model or its loads (message names the
    /// element by index and by the mesh file's own id).
    #[error("{}: {message}", path.display())]
    Model { path: PathBuf, message: String },
    /// The output folder holds something: [`run_job`] writes only into a
    /// new or empty one.
    #[error("{}: the output folder exists and is not empty; fix: choose another output folder, or empty this one", dir.display())]
    OutDirExists { dir: PathBuf },
    /// The output folder could not be prepared.
    #[error("{}: cannot prepare the output folder: {cause}; fix: {}", dir.display(), out_dir_fix(dir))]
    OutDir { dir: PathBuf, cause: std::io::Error },
    /// A result file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

impl JobError {
    /// This error with the line of its key in the job file's `text`, or
    /// failing that of the table holding it (`material[0]` for a check of
    /// `c10_pa + c01_pa`): value checks run on the parsed job, which keeps
    /// no lines.
    fn at_line_in(mut self, text: &str) -> Self {
        if let JobError::Invalid { line, key, .. } | JobError::UnknownSet { line, key, .. } = &mut self {
            let holder = key.rsplit_once('.').map(|(holder, _)| holder);
            let found = crate::toml_text::line_of_key(text, key).or_else(|| holder.and_then(|h| crate::toml_text::line_of_key(text, h)));
            *line = found;
        }
        self
    }
}
