//! The clinical diameters of the fetal head and their validation.

use serde::{Deserialize, Serialize};

/// The six diameters a clinician quotes for a fetal head, in millimetres,
/// under the canonical names of CONVENTIONS.md. Keys left out of a file take
/// the defaults: an average term fetus (REFERENCE_DATA.md, "Term fetal head
/// and body").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeadDiameters {
    /// Between the parietal eminences, the widest transverse diameter.
    /// REFERENCE_DATA.md: biparietal 95 mm.
    pub biparietal_mm: f64,
    /// Between the temples (lower ends of the coronal sutures).
    /// REFERENCE_DATA.md: bitemporal 80-82 mm; 81 mm taken.
    pub bitemporal_mm: f64,
    /// Glabella to occiput, presenting when the head is deflexed.
    /// REFERENCE_DATA.md: occipitofrontal 115-120 mm; 117.5 mm taken.
    pub occipitofrontal_mm: f64,
    /// Suboccipital point to the centre of the bregma, presenting when well flexed.
    /// REFERENCE_DATA.md: suboccipitobregmatic 95 mm.
    pub suboccipitobregmatic_mm: f64,
    /// Chin (menton) to the vertex, presenting in a brow presentation.
    /// REFERENCE_DATA.md: mentovertical 135-140 mm; 137.5 mm taken.
    pub mentovertical_mm: f64,
    /// Submental point (junction of neck and jaw) to the bregma, presenting
    /// in a face presentation. REFERENCE_DATA.md: submentobregmatic 95 mm.
    pub submentobregmatic_mm: f64,
}

impl Default for HeadDiameters {
    fn default() -> Self {
        HeadDiameters {
            biparietal_mm: 95.0,
            bitemporal_mm: 81.0,
            occipitofrontal_mm: 117.5,
            suboccipitobregmatic_mm: 95.0,
            mentovertical_mm: 137.5,
            submentobregmatic_mm: 95.0,
        }
    }
}

/// Why a fetal head cannot be built from the requested diameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeadError {
    #[error("{name} = {value} mm: every head diameter must be a positive, finite length")]
    NotPositive { name: &'static str, value: f64 },
    #[error("{smaller} ({smaller_mm} mm) must be shorter than {larger} ({larger_mm} mm): {why}")]
    Conflict {
        smaller: &'static str,
        smaller_mm: f64,
        larger: &'static str,
        larger_mm: f64,
        why: &'static str,
    },
    #[error(
        "these six diameters cannot shape one convex head: along the {region} the landmarks miss the \
         1 mm clearance a convex outline needs by {shortfall_mm:.1} mm; bring suboccipitobregmatic_mm, \
         submentobregmatic_mm, mentovertical_mm and occipitofrontal_mm closer to their usual proportions \
         (95, 95, 137.5, 117.5)"
    )]
    Unshapeable { region: &'static str, shortfall_mm: f64 },
    #[error(
        "atlanto-occipital pivot {name} = {value} is out of range: use {least} to {most} \
         (the defaults, 15 deg behind straight down and 0.15 in from the skull, keep it under the skull base)"
    )]
    Pivot {
        name: &'static str,
        value: f64,
        least: f64,
        most: f64,
    },
    #[error("surface resolution {0} is out of range: use 3 to 6 sphere subdivisions")]
    Resolution(u32),
}

impl HeadError {
    /// The `[head]` diameter to change, where the error names one (the
    /// smaller of two in conflict).
    pub fn diameter_key(&self) -> Option<&'static str> {
        match self {
            HeadError::NotPositive { name, .. } => Some(name),
            HeadError::Conflict { smaller, .. } => Some(smaller),
            HeadError::Unshapeable { .. } | HeadError::Pivot { .. } | HeadError::Resolution(_) => None,
        }
    }
}

impl HeadDiameters {
    /// The diameters with their canonical names.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("biparietal_mm", self.biparietal_mm),
            ("bitemporal_mm", self.bitemporal_mm),
            ("occipitofrontal_mm", self.occipitofrontal_mm),
            ("suboccipitobregmatic_mm", self.suboccipitobregmatic_mm),
            ("mentovertical_mm", self.mentovertical_mm),
            ("submentobregmatic_mm", self.submentobregmatic_mm),
        ]
    }

    /// Checks each diameter and the orderings every head obeys. The shape
    /// itself may still refuse a set (see [`HeadError::Unshapeable`]).
    pub fn validate(&self) -> Result<(), HeadError> {
        for (name, value) in self.named() {
            if !(value.is_finite() && value > 0.0) {
                return Err(HeadError::NotPositive { name, value });
            }
        }
        let ordered = [
            (
                ("bitemporal_mm", self.bitemporal_mm),
                ("biparietal_mm", self.biparietal_mm),
                "the temples lie in front of and below the parietal eminences, where the head is narrower",
            ),
            (
                ("suboccipitobregmatic_mm", self.suboccipitobregmatic_mm),
                ("occipitofrontal_mm", self.occipitofrontal_mm),
                "flexion brings a smaller diameter than the occipitofrontal into the presenting plane",
            ),
            (
                ("occipitofrontal_mm", self.occipitofrontal_mm),
                ("mentovertical_mm", self.mentovertical_mm),
                "the mentovertical, chin to vertex, is the longest diameter of the head",
            ),
            (
                ("suboccipitobregmatic_mm", self.suboccipitobregmatic_mm),
                ("mentovertical_mm", self.mentovertical_mm),
                "the mentovertical, chin to vertex, is the longest diameter of the head",
            ),
            (
                ("submentobregmatic_mm", self.submentobregmatic_mm),
                ("mentovertical_mm", self.mentovertical_mm),
                "the mentovertical, chin to vertex, is the longest diameter of the head",
            ),
        ];
        for ((smaller, smaller_mm), (larger, larger_mm), why) in ordered {
            if smaller_mm >= larger_mm {
                return Err(HeadError::Conflict {
                    smaller,
                    smaller_mm,
                    larger,
                    larger_mm,
                    why,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_keys_are_canonical() {
        let d = HeadDiameters::default();
        d.validate().unwrap();
        let text = toml::to_string(&d).unwrap();
        for (name, _) in d.named() {
            assert!(text.contains(name), "{name} missing from {text}");
        }
        let partial: HeadDiameters = toml::from_str("biparietal_mm = 92.5").unwrap();
        assert_eq!(partial.biparietal_mm, 92.5);
        assert_eq!(partial.occipitofrontal_mm, d.occipitofrontal_mm);
        assert!(toml::from_str::<HeadDiameters>("biparietal = 92.5").is_err());
    }

    #[test]
    fn impossible_orderings_name_the_conflict() {
        let d = HeadDiameters {
            bitemporal_mm: 96.0,
            ..Default::default()
        };
        let message = d.validate().unwrap_err().to_string();
        assert!(
            message.contains("bitemporal_mm") && message.contains("biparietal_mm"),
            "{message}"
        );

        let d = HeadDiameters {
            suboccipitobregmatic_mm: 120.0,
            ..Default::default()
        };
        let message = d.validate().unwrap_err().to_string();
        assert!(
            message.contains("suboccipitobregmatic_mm") && message.contains("occipitofrontal_mm"),
            "{message}"
        );

        let d = HeadDiameters {
            biparietal_mm: -1.0,
            ..Default::default()
        };
        assert_eq!(
            d.validate(),
            Err(HeadError::NotPositive {
                name: "biparietal_mm",
                value: -1.0
            })
        );
        let d = HeadDiameters {
            mentovertical_mm: f64::NAN,
            ..Default::default()
        };
        assert!(matches!(
            d.validate(),
            Err(HeadError::NotPositive {
                name: "mentovertical_mm",
                ..
            })
        ));
    }
}
