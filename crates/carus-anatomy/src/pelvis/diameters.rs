//! The obstetric diameters a pelvis is generated from (canonical names of
//! CONVENTIONS.md), their gynecoid defaults and the checks that refuse
//! impossible combinations before any geometry is built.

use serde::{Deserialize, Serialize};

/// Diameters of a maternal pelvis, millimetres and degrees as clinicians
/// quote them (converted to metres and radians inside the generator).
/// Definitions as measured are in docs/ANATOMY.md and
/// [`crate::pelvis::measure()`]. Keys left out of a file take the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PelvisDiameters {
    /// Obstetric conjugate: sacral promontory to the upper inner border of the
    /// symphysis. REFERENCE_DATA.md: gynecoid 110 mm (105-115).
    pub inlet_ap_mm: f64,
    /// Widest inlet transverse, between the iliopectineal lines.
    /// REFERENCE_DATA.md: 130-135 mm.
    pub inlet_transverse_mm: f64,
    /// Sacroiliac joint to the opposite iliopubic eminence.
    /// REFERENCE_DATA.md: 120-127 mm.
    pub inlet_oblique_mm: f64,
    /// Lower border of the symphysis to the S4-S5 junction.
    /// REFERENCE_DATA.md: about 115 mm.
    pub mid_ap_mm: f64,
    /// Between the ischial spines. REFERENCE_DATA.md: 100-105 mm.
    pub interspinous_mm: f64,
    /// Lower border of the symphysis to the coccyx tip. REFERENCE_DATA.md: 115 mm.
    pub outlet_ap_mm: f64,
    /// Intertuberous diameter. REFERENCE_DATA.md: 105-110 mm.
    pub outlet_transverse_mm: f64,
    /// Midpoint of one sacrotuberous ligament (its sacral end to the
    /// tuberosity) to the opposite junction of the ischial and pubic rami.
    /// REFERENCE_DATA.md gives no figure: 115 mm is an engineering value that
    /// puts the ligament's sacral end at the S3 level of the sacrum's lateral
    /// border, within the 110-120 mm often quoted for it (no source checked;
    /// docs/ANATOMY.md gives the range the generator reaches).
    pub outlet_oblique_mm: f64,
    /// Length of the inner surface of the symphysis, upper to lower border.
    /// REFERENCE_DATA.md: 40-50 mm.
    pub symphysis_length_mm: f64,
    /// Straight length of the sacrum's anterior surface, promontory to apex.
    /// REFERENCE_DATA.md: 100-110 mm.
    pub sacral_length_mm: f64,
    /// Angle of the pubic arch at the lower border of the symphysis, between
    /// the lines to the ischial tuberosities. REFERENCE_DATA.md: MRI mean 104.9 deg.
    pub subpubic_angle_deg: f64,
    /// Sacral concavity: distance of the S2-S3 junction (the middle of the
    /// sacrum's anterior curve) behind the promontory-apex chord. REFERENCE_DATA.md only says "concave": 20 mm is an engineering
    /// value (a sacral curve turning about 40 degrees over its length).
    pub sacral_depth_mm: f64,
    /// Where the widest inlet transverse crosses the obstetric conjugate:
    /// the inlet's posterior sagittal diameter (promontory to that crossing)
    /// as a share of the conjugate. 0.45, an engineering choice: a gynecoid
    /// inlet is widest slightly behind its centre; the pelvis types of
    /// Caldwell and Moloy differ in it (an android inlet is widest far back,
    /// with a short posterior sagittal). The greatest-dimensions plane takes
    /// the same share. `carus measure` gives the diameter in mm.
    pub inlet_posterior_share: f64,
    /// Where the interspinous line crosses the mid-pelvis AP diameter: the
    /// mid-pelvis posterior sagittal diameter (S4-S5 to that crossing) as a
    /// share of `mid_ap_mm`. 0.4, an engineering choice (about 45-50 mm of
    /// 115, the posterior sagittal of the mid-pelvis often quoted). It sets
    /// how far forward the ischial spines stand, and with them the
    /// sacrospinous ligaments and the floor's attachment.
    pub mid_posterior_share: f64,
}

impl Default for PelvisDiameters {
    fn default() -> Self {
        PelvisDiameters {
            inlet_ap_mm: 110.0,
            inlet_transverse_mm: 130.0,
            inlet_oblique_mm: 124.0,
            mid_ap_mm: 115.0,
            interspinous_mm: 102.0,
            outlet_ap_mm: 115.0,
            outlet_transverse_mm: 108.0,
            outlet_oblique_mm: 115.0,
            symphysis_length_mm: 45.0,
            sacral_length_mm: 105.0,
            subpubic_angle_deg: 105.0,
            sacral_depth_mm: 20.0,
            inlet_posterior_share: 0.45,
            mid_posterior_share: 0.4,
        }
    }
}

/// The canal diameters a pelvis may have, mm: a wide band around the
/// gynecoid 100-135 mm (REFERENCE_DATA.md), below the contracted inlet of
/// CARDINAL_MOVEMENTS.md (85 mm) and up to twice the gynecoid, so that a
/// diameter in cm, or a mesh in mm declared in m, is refused.
pub const PELVIC_CANAL_DIAMETER_MM: (f64, f64) = (50.0, 250.0);

/// A diameter set that no pelvis can have, with the keys in conflict.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiameterError {
    #[error("{key} = {value} must be a positive, finite size")]
    NotPositive { key: &'static str, value: f64 },
    #[error("subpubic_angle_deg = {value} is outside 60-150 degrees, the range a pubic arch can have")]
    SubpubicAngle { value: f64 },
    #[error("{oblique_key} = {oblique} is shorter than both {ap_key} = {ap} and {transverse_key} = {transverse} it lies between; an oblique diameter lies between them")]
    ObliqueTooShort {
        oblique_key: &'static str,
        oblique: f64,
        ap_key: &'static str,
        ap: f64,
        transverse_key: &'static str,
        transverse: f64,
    },
    #[error("{key} = {value} cannot be built with the other diameters: {reason}; with them it must lie between {min:.1} and {max:.1}")]
    OutOfReach { key: &'static str, value: f64, reason: &'static str, min: f64, max: f64 },
    #[error("interspinous_mm = {interspinous} is not smaller than inlet_transverse_mm = {inlet_transverse}: the ischial spines narrow the mid-pelvis below the inlet")]
    InterspinousWiderThanInlet { interspinous: f64, inlet_transverse: f64 },
    #[error("sacral_depth_mm = {depth} must be less than half of sacral_length_mm = {length} (the sacrum is at most a half circle)")]
    SacrumTooDeep { depth: f64, length: f64 },
    #[error("symphysis_length_mm = {symphysis} must be shorter than inlet_ap_mm = {inlet_ap} and outlet_ap_mm = {outlet_ap}")]
    SymphysisTooLong { symphysis: f64, inlet_ap: f64, outlet_ap: f64 },
    #[error("{key} = {value:?} is outside {least} to {most}: a share of the AP diameter, not a length or a percentage (the default is {default})")]
    ShareOutOfRange { key: &'static str, value: f64, least: f64, most: f64, default: f64 },
}

impl DiameterError {
    /// The key to change (the first named, where two are in conflict).
    pub fn key(&self) -> &'static str {
        match self {
            DiameterError::NotPositive { key, .. } | DiameterError::OutOfReach { key, .. } | DiameterError::ShareOutOfRange { key, .. } => key,
            DiameterError::SubpubicAngle { .. } => "subpubic_angle_deg",
            DiameterError::ObliqueTooShort { oblique_key, .. } => oblique_key,
            DiameterError::InterspinousWiderThanInlet { .. } => "interspinous_mm",
            DiameterError::SacrumTooDeep { .. } => "sacral_depth_mm",
            DiameterError::SymphysisTooLong { .. } => "symphysis_length_mm",
        }
    }
}

impl PelvisDiameters {
    /// Every size with its canonical key (the angle is checked apart).
    pub fn sizes(&self) -> [(&'static str, f64); 11] {
        [
            ("inlet_ap_mm", self.inlet_ap_mm),
            ("inlet_transverse_mm", self.inlet_transverse_mm),
            ("inlet_oblique_mm", self.inlet_oblique_mm),
            ("mid_ap_mm", self.mid_ap_mm),
            ("interspinous_mm", self.interspinous_mm),
            ("outlet_ap_mm", self.outlet_ap_mm),
            ("outlet_transverse_mm", self.outlet_transverse_mm),
            ("outlet_oblique_mm", self.outlet_oblique_mm),
            ("symphysis_length_mm", self.symphysis_length_mm),
            ("sacral_length_mm", self.sacral_length_mm),
            ("sacral_depth_mm", self.sacral_depth_mm),
        ]
    }

    /// The checks that need no geometry. The generator adds those that do
    /// (reach of the sacrum, coccyx and ligaments) with the same error type.
    pub fn validate(&self) -> Result<(), DiameterError> {
        for (key, value) in self.sizes() {
            if !(value.is_finite() && value > 0.0) {
                return Err(DiameterError::NotPositive { key, value });
            }
        }
        let d = PelvisDiameters::default();
        for (key, value, default, (least, most)) in [
            ("inlet_posterior_share", self.inlet_posterior_share, d.inlet_posterior_share, POSTERIOR_SHARE_RANGE),
            ("mid_posterior_share", self.mid_posterior_share, d.mid_posterior_share, POSTERIOR_SHARE_RANGE),
        ] {
            if !(least..=most).contains(&value) {
                return Err(DiameterError::ShareOutOfRange { key, value, least, most, default });
            }
        }
        let angle = self.subpubic_angle_deg;
        if !(angle.is_finite() && (60.0..=150.0).contains(&angle)) {
            return Err(DiameterError::SubpubicAngle { value: angle });
        }
        if self.inlet_oblique_mm < self.inlet_ap_mm.min(self.inlet_transverse_mm) {
            return Err(DiameterError::ObliqueTooShort {
                oblique_key: "inlet_oblique_mm",
                oblique: self.inlet_oblique_mm,
                ap_key: "inlet_ap_mm",
                ap: self.inlet_ap_mm,
                transverse_key: "inlet_transverse_mm",
                transverse: self.inlet_transverse_mm,
            });
        }
        if self.outlet_oblique_mm < self.outlet_ap_mm.min(self.outlet_transverse_mm) * OUTLET_OBLIQUE_MIN_RATIO {
            return Err(DiameterError::ObliqueTooShort {
                oblique_key: "outlet_oblique_mm",
                oblique: self.outlet_oblique_mm,
                ap_key: "outlet_ap_mm",
                ap: self.outlet_ap_mm,
                transverse_key: "outlet_transverse_mm",
                transverse: self.outlet_transverse_mm,
            });
        }
        if self.interspinous_mm >= self.inlet_transverse_mm {
            return Err(DiameterError::InterspinousWiderThanInlet {
                interspinous: self.interspinous_mm,
                inlet_transverse: self.inlet_transverse_mm,
            });
        }
        if self.sacral_depth_mm >= 0.5 * self.sacral_length_mm {
            return Err(DiameterError::SacrumTooDeep { depth: self.sacral_depth_mm, length: self.sacral_length_mm });
        }
        if self.symphysis_length_mm >= self.inlet_ap_mm.min(self.outlet_ap_mm) {
            return Err(DiameterError::SymphysisTooLong {
                symphysis: self.symphysis_length_mm,
                inlet_ap: self.inlet_ap_mm,
                outlet_ap: self.outlet_ap_mm,
            });
        }
        Ok(())
    }
}

/// The posterior shares a pelvis may have: a band wide enough for the
/// Caldwell-Moloy types as described (an android inlet widest far back,
/// near the sacrum) that keeps the transverse off the promontory and the
/// symphysis (engineering choice).
pub(crate) const POSTERIOR_SHARE_RANGE: (f64, f64) = (0.2, 0.7);

/// The outlet oblique runs from a ligament midpoint behind the tuberosities to
/// the opposite pubic arch, so it can be shorter than both outlet diameters;
/// below this fraction of the smaller one it would cross the arch itself.
pub(crate) const OUTLET_OBLIQUE_MIN_RATIO: f64 = 0.7;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_round_trip_through_toml_keys() {
        let d = PelvisDiameters::default();
        d.validate().unwrap();
        let json = serde_json::to_value(d).unwrap();
        for (key, value) in d.sizes() {
            assert_eq!(json[key].as_f64(), Some(value));
        }
        assert_eq!(json["subpubic_angle_deg"].as_f64(), Some(105.0));
    }

    #[test]
    fn impossible_sets_name_the_conflict() {
        let bad = PelvisDiameters { mid_ap_mm: -3.0, ..Default::default() };
        assert!(bad.validate().unwrap_err().to_string().contains("mid_ap_mm"));
        let short = PelvisDiameters { inlet_oblique_mm: 100.0, ..Default::default() };
        let message = short.validate().unwrap_err().to_string();
        assert!(message.contains("inlet_oblique_mm") && message.contains("inlet_ap_mm") && message.contains("inlet_transverse_mm"));
        let wide = PelvisDiameters { interspinous_mm: 140.0, ..Default::default() };
        assert!(matches!(wide.validate(), Err(DiameterError::InterspinousWiderThanInlet { .. })));
        let nan = PelvisDiameters { sacral_length_mm: f64::NAN, ..Default::default() };
        assert!(nan.validate().unwrap_err().to_string().contains("sacral_length_mm"));
        let angle = PelvisDiameters { subpubic_angle_deg: 10.0, ..Default::default() };
        assert!(angle.validate().unwrap_err().to_string().contains("subpubic_angle_deg"));
        let length = PelvisDiameters { inlet_posterior_share: 49.5, ..Default::default() };
        let message = length.validate().unwrap_err().to_string();
        assert!(message.contains("inlet_posterior_share = 49.5 is outside 0.2 to 0.7") && message.contains("default is 0.45"), "{message}");
        let forward = PelvisDiameters { mid_posterior_share: 0.1, ..Default::default() };
        assert!(forward.validate().unwrap_err().to_string().contains("mid_posterior_share = 0.1"));
    }

    #[test]
    fn unknown_keys_are_refused() {
        let error = serde_json::from_str::<PelvisDiameters>(r#"{"inlet_ap_mm": 100.0, "inlet_app_mm": 3.0}"#);
        assert!(error.unwrap_err().to_string().contains("inlet_app_mm"));
        let partial: PelvisDiameters = serde_json::from_str(r#"{"inlet_ap_mm": 100.0}"#).unwrap();
        assert_eq!(partial.inlet_ap_mm, 100.0);
        assert_eq!(partial.interspinous_mm, PelvisDiameters::default().interspinous_mm);
    }
}
