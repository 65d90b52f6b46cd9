//! How each movement is named and coloured, the same on the timeline and
//! on the plots.

use carus_analysis::{DetectorReport, Movement, Series, Unit, THETA_ILL_CONDITIONED_TILT_DEG};
use plotters::style::RGBColor;

/// A movement as the page shows it.
pub struct Shown<'a> {
    /// Canonical key of CONVENTIONS.md ("internal_rotation").
    pub key: &'static str,
    /// Name for the reader ("Internal rotation").
    pub label: &'static str,
    pub colour: RGBColor,
    pub movement: &'a Movement,
}

/// Tableau 10 colours (Stone, Tableau Software): distinct for the seven
/// movements and legible as pale bands and as bars.
const PALETTE: [RGBColor; 8] = [
    RGBColor(78, 121, 167),
    RGBColor(89, 161, 79),
    RGBColor(156, 117, 95),
    RGBColor(242, 142, 43),
    RGBColor(225, 87, 89),
    RGBColor(118, 183, 178),
    RGBColor(176, 122, 161),
    RGBColor(186, 176, 172),
];

/// The seven movements in textbook order, then the posterior rotation,
/// which the detector reports apart (never as internal rotation).
pub fn shown(detector: &DetectorReport) -> Vec<Shown<'_>> {
    let labels = [
        "Engagement",
        "Descent",
        "Flexion",
        "Internal rotation",
        "Extension",
        "External rotation (restitution)",
        "Expulsion",
    ];
    let mut rows: Vec<Shown> = detector
        .movements
        .by_key()
        .into_iter()
        .zip(labels)
        .zip(PALETTE)
        .map(|(((key, movement), label), colour)| Shown {
            key,
            label,
            colour,
            movement,
        })
        .collect();
    rows.push(Shown {
        key: "posterior_rotation",
        label: "Posterior rotation (to OP)",
        colour: PALETTE[7],
        movement: &detector.posterior_rotation,
    });
    rows
}

/// The reader's name of the movement keyed `key` among `rows`, or the key.
pub fn label_of<'a>(rows: &[Shown], key: &'a str) -> &'a str {
    rows.iter().find(|r| r.key == key).map_or(key, |r| r.label)
}

/// The observed rotations (read from theta) during which the occiput was
/// tilted out of the canal's cross-section past the angle where theta is
/// ill-conditioned: each row's label and the steepest tilt, degrees.
pub fn ill_conditioned_rotations(rows: &[Shown], series: &Series) -> Vec<(&'static str, f64)> {
    const ROTATIONS: [&str; 3] = ["internal_rotation", "external_rotation", "posterior_rotation"];
    rows.iter()
        .filter(|row| ROTATIONS.contains(&row.key) && row.movement.observed)
        .filter_map(|row| {
            let (start, end) = (row.movement.start_s?, row.movement.end_s?);
            let tilt = series.steepest_occiput_tilt_deg(start, end)?;
            (tilt > THETA_ILL_CONDITIONED_TILT_DEG).then_some((row.label, tilt))
        })
        .collect()
}

/// "12.3 mm" or "85 deg": a size with its unit, to the resolution a
/// clinician reads.
pub fn size_text(size: f64, unit: Unit) -> String {
    match unit {
        Unit::Mm => format!("{size:.1} mm"),
        Unit::Deg => format!("{size:.0}\u{b0}"),
    }
}

/// CSS colour of an RGB triple.
pub fn css(colour: RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", colour.0, colour.1, colour.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_carry_their_units() {
        assert_eq!(size_text(12.345, Unit::Mm), "12.3 mm");
        assert_eq!(size_text(84.6, Unit::Deg), "85\u{b0}");
        assert_eq!(css(RGBColor(255, 0, 16)), "#ff0010");
    }

    /// The textbook's rotations are read from a well-conditioned theta; the
    /// same rotations with the occiput pointing steeply down the canal are
    /// flagged, each with its steepest tilt.
    #[test]
    fn rotations_read_at_a_steep_occiput_are_flagged() {
        let canal = carus_analysis::synthetic::reference_canal();
        let mut report = carus_analysis::detect(&carus_analysis::synthetic::textbook(&canal)).unwrap();
        assert!(ill_conditioned_rotations(&shown(&report), &report.series).is_empty());
        report.series.occiput_tilt_deg.iter_mut().for_each(|t| *t = -80.0);
        let flagged = ill_conditioned_rotations(&shown(&report), &report.series);
        let labels: Vec<&str> = flagged.iter().map(|(label, _)| *label).collect();
        assert_eq!(labels, ["Internal rotation", "External rotation (restitution)"]);
        assert!(flagged.iter().all(|(_, tilt)| *tilt == 80.0));
    }
}
