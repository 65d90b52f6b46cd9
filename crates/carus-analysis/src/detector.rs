//! The detector's one entry point: pose history in, [`DetectorReport`] out.

use crate::history::{HistoryError, PoseHistory};
use crate::measures::Series;
use crate::movements::{detect_movements, HeadBorn, Movement, Movements, NotHeldAtBirth, RotationOutsideWindow};
use crate::outcome::{contraction_period_s, outcome, Outcome};
use crate::shoulders::{shoulder_passage, ShoulderPassage};
use serde::{Deserialize, Serialize};

/// Everything the detector found, as `carus run --json` and the report use
/// it: the seven movements under their canonical keys, the posterior
/// rotation (reported apart, never as internal rotation), the shoulders'
/// passage, the outcome, the contraction period it read off the force, and the per-sample series.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectorReport {
    pub movements: Movements,
    pub posterior_rotation: Movement,
    /// Where the head turned to occiput anterior outside internal
    /// rotation's station window, when the rule saw no internal rotation.
    #[serde(default)]
    pub internal_rotation_outside_window: Option<RotationOutsideWindow>,
    /// The head's position and attitude at its first delivered sample.
    #[serde(default)]
    pub head_born: Option<HeadBorn>,
    /// The counted internal rotation or extension the head had lost by its
    /// birth (empty when both lasted, or the head was not born).
    #[serde(default)]
    pub not_held_at_birth: Vec<NotHeldAtBirth>,
    /// The shoulders' lie at the inlet and the head-to-body interval
    /// (`None` without a trunk).
    #[serde(default)]
    pub shoulders: Option<ShoulderPassage>,
    pub outcome: Outcome,
    pub contraction_period_s: Option<f64>,
    pub series: Series,
}

/// Validates the history, measures every sample and applies the rules.
/// Deterministic: the same history gives the same report, bit for bit.
pub fn detect(history: &PoseHistory) -> Result<DetectorReport, HistoryError> {
    history.validate()?;
    let series = Series::from_history(history);
    let spines_sigma_mm = history.canal.spines_sigma() * 1000.0;
    let detected = detect_movements(&series, spines_sigma_mm);
    let period_s = contraction_period_s(&series);
    Ok(DetectorReport {
        movements: detected.movements,
        posterior_rotation: detected.posterior_rotation,
        internal_rotation_outside_window: detected.rotation_outside_window,
        head_born: detected.head_born,
        not_held_at_birth: detected.not_held_at_birth,
        shoulders: shoulder_passage(&series, detected.head_born, &detected.movements.expulsion, period_s),
        outcome: outcome(history, &series, spines_sigma_mm, period_s),
        contraction_period_s: period_s,
        series,
    })
}
