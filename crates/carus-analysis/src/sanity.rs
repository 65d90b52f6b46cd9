//! The clinical sanity cases of CARDINAL_MOVEMENTS.md ("A simulator that
//! always delivers is wrong"): each case's expected outcome, and whether a
//! detector report meets it. Judged from the report alone, as the movements
//! are, so an imposed or hybrid history is judged the same way.

use serde::{Deserialize, Serialize};

use crate::detector::DetectorReport;
use crate::history::FetalPart;
use crate::outcome::ArrestStage;

/// CARDINAL_MOVEMENTS.md: a contracted inlet arrests with "no engagement,
/// or no descent past station -20 mm".
pub const INLET_ARREST_STATION_MM: f64 = -20.0;

/// How far above the outlet plane's crossing of the pelvic axis the leading
/// point of an arrested face may stop and still be "near the outlet"
/// (CARDINAL_MOVEMENTS.md gives no figure; this tool's reading: a
/// centimetre, about the clinical resolution of station).
pub const NEAR_OUTLET_MM: f64 = 10.0;

/// One clinical sanity case: the built-in scenario that poses it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SanityCase {
    Normal,
    ContractedInlet,
    Face,
    LargeShoulders,
}

/// Whether a report meets its case's expected outcome, and what decided it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub met: bool,
    pub why: String,
}

impl SanityCase {
    pub const ALL: [SanityCase; 4] = [
        SanityCase::Normal,
        SanityCase::ContractedInlet,
        SanityCase::Face,
        SanityCase::LargeShoulders,
    ];

    /// The built-in scenario of this case (`carus scenarios`).
    pub fn scenario(self) -> &'static str {
        match self {
            SanityCase::Normal => "normal",
            SanityCase::ContractedInlet => "contracted-inlet",
            SanityCase::Face => "face",
            SanityCase::LargeShoulders => "large-shoulders",
        }
    }

    /// The expected outcome, in CARDINAL_MOVEMENTS.md's words.
    pub fn expected(self) -> &'static str {
        match self {
            SanityCase::Normal => "delivery, with all seven movements observed",
            SanityCase::ContractedInlet => "arrest: no engagement, or no descent past station -20 mm",
            SanityCase::Face => "arrest near the outlet",
            SanityCase::LargeShoulders => {
                "head delivered, then arrest with the anterior shoulder against the symphysis"
            }
        }
    }

    /// Judges `report`; `outlet_station_mm` is the station of the outlet
    /// plane's crossing of the pelvic axis (its sigma minus the spines').
    pub fn judge(self, report: &DetectorReport, outlet_station_mm: f64) -> Verdict {
        let outcome = &report.outcome;
        let verdict = |met: bool, why: String| Verdict { met, why };
        match self {
            SanityCase::Normal => {
                let missing: Vec<&str> = report
                    .movements
                    .by_key()
                    .iter()
                    .filter(|(_, m)| !m.observed)
                    .map(|(key, _)| *key)
                    .collect();
                match (outcome.delivered, missing.is_empty()) {
                    (true, true) => verdict(true, "delivered, all seven movements observed".into()),
                    (true, false) => verdict(false, format!("delivered, but not observed: {}", missing.join(", "))),
                    (false, _) => verdict(false, "not delivered".into()),
                }
            }
            SanityCase::ContractedInlet => {
                let deepest = report.series.station_mm.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let engaged = report.movements.engagement.observed;
                let arrested = outcome.arrest.is_some();
                let met = arrested && (!engaged || deepest <= INLET_ARREST_STATION_MM);
                let state = match (outcome.delivered, arrested) {
                    (true, _) => "delivered",
                    (false, true) => "arrested",
                    (false, false) => "neither delivered nor arrested",
                };
                verdict(
                    met,
                    format!(
                        "{state}; {}; deepest station {deepest:+.1} mm",
                        if engaged { "engaged" } else { "not engaged" },
                    ),
                )
            }
            SanityCase::Face => match &outcome.arrest {
                // A head born and held by its shoulders is no face arrest.
                Some(arrest) if arrest.stage == ArrestStage::Shoulders => verdict(
                    false,
                    "the head was born; arrested at the shoulders stage".into(),
                ),
                Some(arrest) => {
                    let short = outlet_station_mm - arrest.station_mm;
                    let met = short <= NEAR_OUTLET_MM;
                    let place = if short <= 0.0 {
                        format!("{:.1} mm past", -short)
                    } else {
                        format!("{short:.1} mm short of")
                    };
                    verdict(
                        met,
                        format!(
                            "arrested with the leading point at station {:+.1} mm, {place} the outlet plane's \
                             crossing of the axis (station {outlet_station_mm:+.1} mm; near: within {NEAR_OUTLET_MM:.0} mm)",
                            arrest.station_mm
                        ),
                    )
                }
                None => verdict(false, if outcome.delivered { "delivered" } else { "neither delivered nor arrested" }.into()),
            },
            SanityCase::LargeShoulders => {
                let head_out = report.series.head_delivered.iter().any(|&d| d);
                match &outcome.arrest {
                    Some(arrest) => {
                        let at_shoulders = arrest.stage == ArrestStage::Shoulders;
                        // The shoulders ride on the trunk: a head still
                        // pressed on the symphysis is no shoulder arrest.
                        let on_symphysis = arrest.against == "symphysis" && arrest.part == FetalPart::Trunk.name();
                        verdict(
                            head_out && at_shoulders && on_symphysis,
                            format!(
                                "{}; arrested at the {} stage, {} the {}{}",
                                if head_out { "head delivered" } else { "head not delivered" },
                                stage_name(arrest.stage),
                                match arrest.part.as_str() {
                                    "unknown" => "against".to_string(),
                                    part => format!("the {part} against"),
                                },
                                arrest.against.replace('_', " "),
                                arrest
                                    .held_shoulders_from_ap_deg()
                                    .map_or(String::new(), |deg| format!(
                                        ", the bisacromial diameter {deg:.0} deg from the antero-posterior"
                                    ))
                            ),
                        )
                    }
                    None => verdict(false, if outcome.delivered { "delivered" } else { "neither delivered nor arrested" }.into()),
                }
            }
        }
    }
}

fn stage_name(stage: ArrestStage) -> String {
    serde_json::to_value(stage)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}
