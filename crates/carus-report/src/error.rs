//! Why a report could not be written. Pictures that fail are never an
//! error: they become warnings and a note on the page.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The detector's series and the history disagree (a report built from
    /// another run's history).
    #[error("the detector report has {series} samples but the pose history has {history}; pass the DetectorReport that carus_analysis::detect returned for this history")]
    SeriesMismatch { series: usize, history: usize },
    /// A number the page needs is not finite.
    #[error("{what} is not finite ({value}); the run's figures must be real values")]
    NotFinite { what: &'static str, value: f64 },
    /// The plotting library refused a plot.
    #[error("plot `{plot}` could not be drawn: {message}")]
    Plot { plot: &'static str, message: String },
    /// The demonstration's anatomy or detector run failed.
    #[error("the demonstration report could not be built: {0}")]
    Demo(String),
    /// Writing the page failed.
    #[error("cannot write the report `{path}`: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}
