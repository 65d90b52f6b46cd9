//! The key moments of a labour, chosen from the detector's report alone,
//! so that the pictures show what the detector saw: the run's record keeps
//! the floor as it was at each, and the report pictures them, by this one
//! rule.

use crate::{DetectorReport, Movement};

/// Which instant a picture shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MomentKind {
    /// End of engagement: both parietal eminences first below the inlet.
    Engagement,
    /// End of internal rotation: the occiput has turned to the front.
    InternalRotation,
    /// Crowning: the head's widest part (the biparietal plane through the
    /// head centre) first passes the outlet plane.
    Crowning,
    /// End of external rotation (restitution).
    Restitution,
    /// The last sample of a run that ended in arrest.
    Arrest,
}

impl MomentKind {
    /// The moment's name in a run's record (run.json's `key_moments`).
    pub fn name(self) -> &'static str {
        match self {
            MomentKind::Engagement => "engagement",
            MomentKind::InternalRotation => "internal_rotation",
            MomentKind::Crowning => "crowning",
            MomentKind::Restitution => "restitution",
            MomentKind::Arrest => "arrest",
        }
    }

    /// Heading shown over the pictures.
    pub fn label(self) -> &'static str {
        match self {
            MomentKind::Engagement => "Engagement",
            MomentKind::InternalRotation => "Full internal rotation",
            MomentKind::Crowning => "Crowning",
            MomentKind::Restitution => "Restitution",
            MomentKind::Arrest => "Arrest",
        }
    }

    /// Short mark on the plots' time axes.
    pub fn mark(self) -> &'static str {
        match self {
            MomentKind::Engagement => "E",
            MomentKind::InternalRotation => "IR",
            MomentKind::Crowning => "C",
            MomentKind::Restitution => "R",
            MomentKind::Arrest => "A",
        }
    }

    /// How the instant was chosen, for the page.
    pub fn rule(self) -> &'static str {
        match self {
            MomentKind::Engagement => "end of engagement: both parietal eminences below the inlet",
            MomentKind::InternalRotation => "end of internal rotation",
            MomentKind::Crowning => "the biparietal plane (head centre) passes the outlet: the instant the head counts as born",
            MomentKind::Restitution => "end of external rotation (restitution)",
            MomentKind::Arrest => "last sample of the arrested run",
        }
    }
}

/// A key moment: its kind, and the sample it shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyMoment {
    pub kind: MomentKind,
    pub sample: usize,
    pub time_s: f64,
}

/// A moment the run did not reach, with the reason, for the page.
#[derive(Debug, Clone, PartialEq)]
pub struct MissedMoment {
    pub kind: MomentKind,
    pub reason: String,
}

/// The key moments of a run in time order, and those it did not reach.
pub fn key_moments(detector: &DetectorReport) -> (Vec<KeyMoment>, Vec<MissedMoment>) {
    let series = &detector.series;
    let at = |kind: MomentKind, sample: usize| KeyMoment {
        kind,
        sample,
        time_s: series.time_s[sample],
    };
    let from_end = |kind: MomentKind, movement: &Movement, name: &str| {
        movement
            .end_s
            .filter(|_| movement.observed)
            .map(|t| at(kind, nearest_sample(&series.time_s, t)))
            .ok_or_else(|| MissedMoment {
                kind,
                reason: format!("{name} was not observed"),
            })
    };
    let m = &detector.movements;
    let crowning = series
        .head_delivered
        .iter()
        .position(|&d| d)
        .map(|i| at(MomentKind::Crowning, i))
        .ok_or_else(|| MissedMoment {
            kind: MomentKind::Crowning,
            reason: "the head did not pass the outlet".into(),
        });
    let mut found = Vec::new();
    let mut missed = Vec::new();
    for candidate in [
        from_end(MomentKind::Engagement, &m.engagement, "engagement"),
        from_end(
            MomentKind::InternalRotation,
            &m.internal_rotation,
            "internal rotation",
        ),
        crowning,
        from_end(
            MomentKind::Restitution,
            &m.external_rotation,
            "external rotation",
        ),
    ] {
        match candidate {
            Ok(moment) => found.push(moment),
            Err(miss) => missed.push(miss),
        }
    }
    if detector.outcome.arrest.is_some() && !series.time_s.is_empty() {
        found.push(at(MomentKind::Arrest, series.time_s.len() - 1));
    }
    found.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    (found, missed)
}

/// Index of the sample nearest to `time_s` (movement times are sample
/// times, so this finds the sample itself).
pub fn nearest_sample(times: &[f64], time_s: f64) -> usize {
    let after = times.partition_point(|&t| t < time_s);
    match (after.checked_sub(1), times.get(after)) {
        (Some(before), Some(&next)) if time_s - times[before] < next - time_s => before,
        (Some(before), None) => before,
        _ => after,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_sample_time_finds_its_own_sample() {
        let times = [0.0, 0.2, 0.4, 0.6];
        assert_eq!(nearest_sample(&times, 0.4), 2);
        assert_eq!(nearest_sample(&times, 0.0), 0);
        assert_eq!(nearest_sample(&times, 0.6), 3);
    }

    #[test]
    fn times_outside_the_run_take_its_ends() {
        let times = [1.0, 2.0];
        assert_eq!(nearest_sample(&times, -5.0), 0);
        assert_eq!(nearest_sample(&times, 9.0), 1);
    }

    proptest! {
        #[test]
        fn the_chosen_sample_is_a_nearest_one(
            steps in proptest::collection::vec(0.01f64..5.0, 1..40),
            t in -10.0f64..200.0,
        ) {
            let times: Vec<f64> = steps.iter().scan(0.0, |s, d| { *s += d; Some(*s) }).collect();
            let i = nearest_sample(&times, t);
            let best = times.iter().map(|x| (x - t).abs()).fold(f64::INFINITY, f64::min);
            prop_assert!(((times[i] - t).abs() - best).abs() < 1e-12);
        }
    }
}
