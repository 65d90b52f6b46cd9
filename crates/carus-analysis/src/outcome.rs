//! The labour outcome: delivered, or arrested (where, and against what).
//!
//! "No progress" is judged over a final window of the run at least two
//! contraction periods long (the period read off the expulsion force) and
//! at least a quarter of the run: the fetus is arrested when, in that
//! window, the leading part got less than [`ARREST_PROGRESS_MM`] further
//! than it had ever been before the window (and, under a steady push, at
//! less than [`ARREST_PACE_SHARE`] of its pace before). An undelivered fetus that is
//! still progressing is neither delivered nor arrested (`arrest: null`):
//! the run ended too soon to tell.

use crate::history::PoseHistory;
use crate::measures::Series;
use crate::shoulders::from_antero_posterior_deg;
use serde::{Deserialize, Serialize};

/// Less progress than this over the final window is an arrest (detector
/// choice, docs/DETECTOR.md: a few mm, well above contact jitter and well
/// below the ~5-10 mm a head gains per effective contraction in the
/// second stage).
pub const ARREST_PROGRESS_MM: f64 = 3.0;
/// The final window spans at least this many contraction periods (detector
/// choice, docs/DETECTOR.md: one contraction's slip back is not an arrest).
pub const ARREST_WINDOW_PERIODS: f64 = 2.0;
/// The final window spans at least this fraction of the run (detector choice,
/// docs/DETECTOR.md).
pub const ARREST_WINDOW_FRACTION: f64 = 0.25;
/// Under a steady push (a history without contractions), an arrest is a
/// stop, not a short window: a fetus whose pace since its deepest point
/// before the window (its gain over that time) is at least this share of
/// its pace up to that point is still progressing, however few mm a short
/// history's final quarter holds (detector choice, docs/DETECTOR.md). With
/// contractions the window spans two of them and needs no such test.
pub const ARREST_PACE_SHARE: f64 = 0.5;

/// Where the fetus stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ArrestStage {
    /// The head never engaged: both parietal eminences not below the inlet.
    #[serde(rename = "inlet")]
    Inlet,
    /// Engaged, but the head centre (biparietal plane) above the spines.
    #[serde(rename = "mid-pelvis")]
    MidPelvis,
    /// The head centre past the spines but not past the outlet.
    #[serde(rename = "outlet")]
    Outlet,
    /// The head delivered, the trunk not.
    #[serde(rename = "shoulders")]
    Shoulders,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Arrest {
    pub stage: ArrestStage,
    /// Station of the head's leading point where it stopped (the deepest
    /// reached in the final window); for stage `shoulders`, the bisacromial
    /// midpoint's sigma minus the spines' sigma.
    pub station_mm: f64,
    /// The part that carried the largest contact force in the final window
    /// (at its sample of greatest total contact force), or "unknown".
    pub against: String,
    /// The fetal body that bore most of `against`'s force at that sample
    /// ("head" or "trunk"; "trunk" with the head short of the outlet is the
    /// head held back by its shoulders), or "unknown".
    #[serde(default = "unknown")]
    pub part: String,
    /// Station of the bisacromial midpoint at the same sample as
    /// `station_mm` (its sigma minus the spines'), when a trunk is
    /// modelled: where the shoulders stood, which says how high a trunk
    /// that holds the head back is caught.
    #[serde(default)]
    pub shoulders_station_mm: Option<f64>,
    /// The bisacromial line's angle from the antero-posterior diameter at
    /// the same sample, deg (0 with one shoulder behind the symphysis, 90
    /// transverse), when a trunk is modelled.
    #[serde(default)]
    pub shoulders_from_ap_deg: Option<f64>,
}

impl Arrest {
    /// Where the shoulders stood, station mm, when the trunk held the head
    /// short of being born (a shoulder-stage arrest's station is theirs
    /// already).
    pub fn shoulders_holding_head(&self) -> Option<f64> {
        (self.part == "trunk" && self.stage != ArrestStage::Shoulders)
            .then_some(self.shoulders_station_mm)
            .flatten()
    }

    /// How the held shoulders lie, deg from the antero-posterior, for an
    /// arrest at the shoulders stage (the words every report gives it).
    pub fn held_shoulders_from_ap_deg(&self) -> Option<f64> {
        self.shoulders_from_ap_deg.filter(|_| self.stage == ArrestStage::Shoulders)
    }
}

fn unknown() -> String {
    "unknown".to_string()
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    pub delivered: bool,
    pub arrest: Option<Arrest>,
}

/// The expulsion force's lowest and highest values, when it rises and falls
/// at all: a constant force (or a single sample) has no contractions.
fn force_extremes(series: &Series) -> Option<(f64, f64)> {
    let (low, high) = series
        .expulsion_force_n
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &f| {
            (l.min(f), h.max(f))
        });
    (high - low > 1e-9 * high.abs().max(1.0)).then_some((low, high))
}

/// The contraction period, read off the expulsion force as the median time
/// between the peaks of its excursions above the mid-level between its
/// extremes; `None` for a force with fewer than three such peaks.
pub fn contraction_period_s(series: &Series) -> Option<f64> {
    let force = &series.expulsion_force_n;
    let (low, high) = force_extremes(series)?;
    let mid = 0.5 * (low + high);
    let mut peaks = Vec::new();
    let mut current: Option<usize> = None;
    for (i, &f) in force.iter().enumerate() {
        if f > mid {
            current = Some(match current {
                Some(best) if force[best] >= f => best,
                _ => i,
            });
        } else if let Some(best) = current.take() {
            peaks.push(series.time_s[best]);
        }
    }
    // An excursion still open at the end of the run has no known peak.
    let mut gaps: Vec<f64> = peaks.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.len() < 2 {
        return None;
    }
    gaps.sort_by(f64::total_cmp);
    Some(gaps[gaps.len() / 2])
}

/// Judges the outcome of the run that `series` was measured from;
/// `period_s` is its [`contraction_period_s`].
pub fn outcome(history: &PoseHistory, series: &Series, spines_sigma_mm: f64, period_s: Option<f64>) -> Outcome {
    let last = series.len() - 1;
    let delivered = series.head_delivered[last]
        && series
            .trunk_below_outlet_mm
            .as_ref()
            .is_none_or(|trunk| trunk[last] > 0.0);
    if delivered {
        return Outcome {
            delivered,
            arrest: None,
        };
    }
    // Contractions too few to time (a run stopped in its first ones): no
    // window of two periods fits, and a pause between two pushes is not an
    // arrest. Nor is a fetus that nothing has pushed down yet (a run of a
    // step or two, before its force rose from zero). Too soon to tell.
    let never_pushed = series.expulsion_force_n.iter().all(|&f| f <= 0.0);
    if never_pushed || (period_s.is_none() && force_extremes(series).is_some()) {
        return Outcome {
            delivered,
            arrest: None,
        };
    }
    let duration = series.time_s[last] - series.time_s[0];
    let span = (ARREST_WINDOW_FRACTION * duration).max(period_s.map_or(0.0, |p| ARREST_WINDOW_PERIODS * p));
    let window_start = series
        .time_s
        .iter()
        .position(|&t| t >= series.time_s[last] - span)
        .unwrap_or(0);
    // A head born at the height of each contraction that slips back between
    // them (the turtle sign of shoulder dystocia) is out: the last sample's
    // phase of the contraction must not decide it.
    let head_out = series.head_delivered[window_start..=last].iter().any(|&h| h);
    // The part whose progress counts: the shoulders once the head is out.
    let progress: Vec<f64> = match (head_out, &series.shoulders_sigma_mm) {
        (true, Some(shoulders)) => shoulders.iter().map(|s| s - spines_sigma_mm).collect(),
        _ => series.station_mm.clone(),
    };
    let deepest = |range: std::ops::RangeInclusive<usize>| {
        range
            .max_by(|&a, &b| progress[a].total_cmp(&progress[b]))
            .unwrap_or(last)
    };
    // Where the fetus got stuck: the window's deepest sample, which both the
    // station and the stage describe.
    let stuck_at = deepest(window_start..=last);
    let reached = progress[stuck_at];
    let deepest_before = if window_start == 0 { 0 } else { deepest(0..=window_start - 1) };
    let before = progress[deepest_before];
    // Under a steady push (no contractions to time a window by), a short
    // window is no stop while the fetus keeps the pace it had; with
    // contractions, two of them are window enough.
    let t = &series.time_s;
    let pace = |gain: f64, from: usize, to: usize| (t[to] > t[from]).then(|| gain / (t[to] - t[from]));
    let still_going = period_s.is_none()
        && pace(before - progress[0], 0, deepest_before)
            .filter(|&p| p > 0.0)
            .zip(pace(reached - before, deepest_before, last))
            .is_some_and(|(p_before, p_window)| p_window >= ARREST_PACE_SHARE * p_before);
    if reached - before >= ARREST_PROGRESS_MM || still_going {
        return Outcome {
            delivered,
            arrest: None,
        };
    }
    let stage = if head_out {
        ArrestStage::Shoulders
    } else if series.left_parietal_below_inlet_mm[stuck_at]
        .min(series.right_parietal_below_inlet_mm[stuck_at])
        <= 0.0
    {
        ArrestStage::Inlet
    } else if series.head_sigma_mm[stuck_at] < spines_sigma_mm {
        ArrestStage::MidPelvis
    } else {
        ArrestStage::Outlet
    };
    let hardest = (window_start..=last)
        .max_by(|&a, &b| series.contact_force_n[a].total_cmp(&series.contact_force_n[b]))
        .unwrap_or(last);
    let against = history.samples[hardest]
        .dominant_contact
        .map_or("unknown", |site| site.name())
        .to_string();
    let part = history.samples[hardest]
        .dominant_part
        .map_or("unknown", |part| part.name())
        .to_string();
    Outcome {
        delivered,
        arrest: Some(Arrest {
            stage,
            station_mm: reached,
            against,
            part,
            shoulders_station_mm: series
                .shoulders_sigma_mm
                .as_ref()
                .map(|shoulders| shoulders[stuck_at] - spines_sigma_mm),
            shoulders_from_ap_deg: series
                .shoulders_theta_deg
                .as_ref()
                .map(|back| from_antero_posterior_deg(back[stuck_at])),
        }),
    }
}
