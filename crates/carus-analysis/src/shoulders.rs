//! The shoulders' passage, with a trunk: how the bisacromial diameter lay
//! as it came into the inlet, and how long the body took after the head.
//! The time from the head's birth to the body's (the head-to-body
//! interval) is the clinical measure of shoulder dystocia (docs/DETECTOR.md);
//! the lie of the shoulders at the inlet is what decides, in this model,
//! whether large shoulders are held on the side walls or behind the
//! symphysis (docs/LABOUR.md, forty-fifth session). Measures only: nothing
//! here judges the outcome.

use crate::measures::{wrap_deg, Series};
use crate::movements::{HeadBorn, Movement};
use serde::{Deserialize, Serialize};

/// What the shoulders did, read from a history with a trunk.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShoulderPassage {
    /// The first sample with the bisacromial midpoint at or past the inlet
    /// (sigma 0), having started above it, s; `None` when it never came.
    pub inlet_s: Option<f64>,
    /// The bisacromial line's angle from the canal's antero-posterior
    /// diameter at `inlet_s`, degrees: 0 with one shoulder behind the
    /// symphysis, 45 oblique, 90 transverse.
    pub inlet_from_ap_deg: Option<f64>,
    /// The body's birth, s: the end of expulsion (the trunk's centre past
    /// the outlet, after the bisacromial midpoint).
    pub body_born_s: Option<f64>,
    /// From the head's birth to the body's, s; `None` unless both were born.
    pub head_to_body_s: Option<f64>,
    /// `head_to_body_s` in contraction periods: the model's contractions
    /// come every few seconds where a labour's come every few minutes, so
    /// this, not the seconds, is what compares with a delivery room.
    pub head_to_body_periods: Option<f64>,
    /// With the head born and the body not: how long the body had waited
    /// when the history ended, s.
    pub body_not_born_after_s: Option<f64>,
}

/// The bisacromial line's angle from the antero-posterior diameter, deg in
/// [0, 90], from the fetal back's direction on theta's scale (the line is
/// square to the back: a back at -90, LOT, puts it antero-posterior).
pub fn from_antero_posterior_deg(back_theta_deg: f64) -> f64 {
    (wrap_deg(back_theta_deg).abs() - 90.0).abs()
}

/// The shoulders' passage, or `None` for a history without a trunk.
pub fn shoulder_passage(
    series: &Series,
    head_born: Option<HeadBorn>,
    expulsion: &Movement,
    period_s: Option<f64>,
) -> Option<ShoulderPassage> {
    let (sigma, back) = (series.shoulders_sigma_mm.as_ref()?, series.shoulders_theta_deg.as_ref()?);
    let inlet = sigma
        .iter()
        .position(|&s| s >= 0.0)
        .filter(|&i| i > 0);
    let body_born_s = expulsion.observed.then_some(expulsion.end_s).flatten();
    let head_born_s = head_born.map(|h| h.time_s);
    let head_to_body_s = head_born_s.zip(body_born_s).map(|(head, body)| body - head);
    let end_s = series.time_s.last().copied();
    Some(ShoulderPassage {
        inlet_s: inlet.map(|i| series.time_s[i]),
        inlet_from_ap_deg: inlet.map(|i| from_antero_posterior_deg(back[i])),
        body_born_s,
        head_to_body_s,
        head_to_body_periods: head_to_body_s.zip(period_s).map(|(s, p)| s / p),
        body_not_born_after_s: match body_born_s {
            Some(_) => None,
            None => head_born_s.zip(end_s).map(|(head, end)| end - head),
        },
    })
}

/// A lie of the shoulders in words: the nearest of the antero-posterior,
/// oblique and transverse diameters, with the angle.
fn lie(from_ap_deg: f64) -> String {
    match from_ap_deg {
        a if a < 22.5 => format!("near the antero-posterior ({a:.0} deg off it)"),
        a if a <= 67.5 => format!("oblique ({a:.0} deg from the antero-posterior)"),
        a => format!("near the transverse ({a:.0} deg from the antero-posterior)"),
    }
}

impl std::fmt::Display for ShoulderPassage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.inlet_s.zip(self.inlet_from_ap_deg) {
            Some((t, a)) => write!(f, "the shoulders came into the inlet at {t:.1} s, the bisacromial diameter {}", lie(a))?,
            None => write!(f, "the shoulders did not come into the inlet")?,
        }
        let periods = |p: Option<f64>| p.map_or(String::new(), |p| format!(", {p:.1} contraction periods"));
        if let Some(s) = self.head_to_body_s {
            write!(f, "; the body was born {s:.1} s after the head{}", periods(self.head_to_body_periods))?;
        } else if let Some(s) = self.body_not_born_after_s {
            write!(f, "; the body was not born in the {s:.1} s after the head")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A line has no direction: the back turned half a turn, or any
        /// number of whole turns, lies the same; and the angle is in [0, 90].
        #[test]
        fn the_lie_is_a_line_not_a_direction(back in -720.0f64..720.0, turns in -3i32..3) {
            let a = from_antero_posterior_deg(back);
            prop_assert!((0.0..=90.0).contains(&a));
            for other in [back + 180.0, back - 180.0, back + 360.0 * f64::from(turns)] {
                prop_assert!((from_antero_posterior_deg(other) - a).abs() < 1e-9);
            }
            // Mirrored across the sagittal plane (left for right) it lies the same.
            prop_assert!((from_antero_posterior_deg(-back) - a).abs() < 1e-9);
        }
    }

    #[test]
    fn the_back_lateral_puts_the_shoulders_antero_posterior() {
        for (back, expected) in [
            (-90.0, 0.0),
            (90.0, 0.0),
            (0.0, 90.0),
            (180.0, 90.0),
            (-45.0, 45.0),
            (-135.0, 45.0),
            (-25.0, 65.0),
            (-450.0, 0.0),
            (330.0, 60.0),
        ] {
            let got = from_antero_posterior_deg(back);
            assert!((got - expected).abs() < 1e-9, "back {back}: {got}, expected {expected}");
        }
    }

    #[test]
    fn the_angle_names_the_nearest_diameter() {
        assert_eq!(lie(8.0), "near the antero-posterior (8 deg off it)");
        assert_eq!(lie(44.0), "oblique (44 deg from the antero-posterior)");
        assert_eq!(lie(65.0), "oblique (65 deg from the antero-posterior)");
        assert_eq!(lie(80.0), "near the transverse (80 deg from the antero-posterior)");
    }
}
