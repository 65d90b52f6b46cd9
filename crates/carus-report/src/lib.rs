//! `report.html`: one self-contained page that tells a researcher or an
//! obstetric educator at a glance how a labour went (docs/REPORT.md).
//!
//! - [`input`]: what a run hands over ([`ReportInput`]): history, detector
//!   report, floor stretch, meshes, figures, scenario;
//! - the key moments it pictures are chosen from the detector's report by
//!   `carus_analysis::moments` (the run's record keeps the floor at each
//!   by the same rule);
//! - [`movements`]: names and colours of the movements;
//! - [`plots`]: SVG plots against time (plotters);
//! - [`pictures`]: renders of the key moments (carus-render);
//! - [`page`]: the HTML;
//! - [`write_report`], [`write_report_with`]: the page in memory;
//!   [`write_report_file`]: the one function that touches the file system.
//!
//! Pictures never cost the report: without a graphics adapter, or when a
//! picture fails, the page says so in their place and the reason comes
//! back in [`Report::warnings`].

pub mod demo;
pub mod error;
pub mod input;
pub mod movements;
pub mod page;
pub mod pictures;
pub mod plots;

use std::path::Path;

use carus_render::Renderer;

#[cfg(test)]
mod tests;

pub use error::ReportError;
pub use input::{AxialMomentSample, CanalForceSample, FloorFrame, FloorSurface, Fontanelles, ReportInput, ReportScene, RunFigures, SampleForces};
pub use carus_analysis::moments::{key_moments, KeyMoment, MomentKind};

/// A written page and what went wrong with its pictures.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The complete HTML page.
    pub html: String,
    /// Pictures that could not be drawn, and why (the page says so too).
    pub warnings: Vec<String>,
}

/// Builds the page, opening a renderer (a real GPU, else lavapipe) when the
/// input has meshes to draw.
pub fn write_report(input: &ReportInput) -> Result<Report, ReportError> {
    if input.scene.is_none() {
        return write_report_with(input, None);
    }
    match Renderer::new_headless() {
        Ok(mut renderer) => write_report_with(input, Some(&mut renderer)),
        Err(e) => {
            let mut report = compose(input, Some(Err(e.to_string())))?;
            report
                .warnings
                .insert(0, format!("pictures not drawn: {e}"));
            Ok(report)
        }
    }
}

/// Builds the page with a renderer the caller already has (to share one
/// device with other work); `None`: no renderer, pictures replaced by a note.
pub fn write_report_with(
    input: &ReportInput,
    renderer: Option<&mut Renderer>,
) -> Result<Report, ReportError> {
    let pictures = match (renderer, &input.scene) {
        (_, None) => None,
        (None, Some(_)) => Some(Err("no graphics renderer was available".to_string())),
        (Some(r), Some(scene)) => {
            check(input)?;
            let (moments, _) = key_moments(input.detector);
            let range = floor_stretch_range(input);
            Some(Ok(pictures::draw(r, scene, input.history, &moments, range)))
        }
    };
    let mut report = compose(input, pictures.clone())?;
    if matches!(pictures, Some(Err(_))) {
        report.warnings.insert(
            0,
            "pictures not drawn: no graphics renderer was available".into(),
        );
    }
    Ok(report)
}

/// The pictures' floor colour scale: [`pictures::stretch_range`] of the
/// key moments' floor states, up to the first inverted element, reaching
/// up to the floor's peak stretch before then (`floor_peak_stretch`), so
/// that a moment between two pictured ones (a crowning just after the
/// first inversion) is not all past the top.
fn floor_stretch_range(input: &ReportInput) -> Option<[f64; 2]> {
    let floor = input.scene.as_ref()?.floor.as_ref()?;
    let [low, high] = pictures::stretch_range(floor, input.floor_untrusted_from_s)?;
    let trusted = |t: f64| input.floor_untrusted_from_s.is_none_or(|from| t < from);
    let peak = input
        .floor_peak_stretch
        .iter()
        .filter(|&&(t, s)| trusted(t) && s.is_finite())
        .fold(high, |top, &(_, s)| top.max(s));
    Some([low, peak])
}

/// Writes the page to `path`; returns the picture warnings.
pub fn write_report_file(input: &ReportInput, path: &Path) -> Result<Vec<String>, ReportError> {
    let report = write_report(input)?;
    carus_io::output::write_whole(path, report.html.as_bytes())
        .map_err(|source| ReportError::Write { path: path.to_path_buf(), source })?;
    Ok(report.warnings)
}

/// The detector report must belong to the history, and the figures be real.
fn check(input: &ReportInput) -> Result<(), ReportError> {
    let (series, history) = (input.detector.series.len(), input.history.samples.len());
    if series != history || series == 0 {
        return Err(ReportError::SeriesMismatch { series, history });
    }
    let figures = [
        ("run.simulated_s", Some(input.run.simulated_s)),
        ("run.wall_s", input.run.wall_s),
    ];
    for (what, value) in figures {
        if let Some(value) = value.filter(|v| !v.is_finite()) {
            return Err(ReportError::NotFinite { what, value });
        }
    }
    Ok(())
}

fn compose(
    input: &ReportInput,
    pictures: Option<Result<Vec<pictures::MomentPictures>, String>>,
) -> Result<Report, ReportError> {
    check(input)?;
    let (moments, missed) = key_moments(input.detector);
    let warnings = match &pictures {
        Some(Ok(drawn)) => drawn
            .iter()
            .filter_map(|m| {
                m.pictures.as_ref().err().map(|e| {
                    format!(
                        "picture of {} at {:.1} s not drawn: {e}",
                        m.moment.kind.label().to_lowercase(),
                        m.moment.time_s
                    )
                })
            })
            .collect(),
        _ => Vec::new(),
    };
    let stretch_range = floor_stretch_range(input);
    let html = page::page(
        input,
        &page::Parts {
            moments: &moments,
            missed: &missed,
            pictures,
            stretch_range,
        },
    )?;
    Ok(Report { html, warnings })
}
