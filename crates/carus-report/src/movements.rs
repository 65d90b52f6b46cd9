//! How each movement is named and coloured, the same on the timeline and
//! on the plots.

use carus_analysis::{DetectorReport, Movement, Unit};
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
}
