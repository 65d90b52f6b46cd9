//! The `[pelvis]` table of an anatomy or scenario file: either diameters
//! (canonical keys; keys left out take the gynecoid defaults) or
//! `import = "path/to/landmarks.toml"` for a real pelvis.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{Pelvis, PelvisDiameters, PelvisError};
use crate::import::{import_pelvis, visible_human_female_pelvis, ImportError, ImportedPelvis, MeshReport};

/// The name an imported pelvis takes to mean the shipped Visible Human
/// Female pelvis, compiled into the program (no file needed at run time).
pub const VISIBLE_HUMAN_FEMALE: &str = "visible-human-female";

/// How a pelvis is made.
#[derive(Debug, Clone, PartialEq)]
pub enum PelvisSpec {
    /// Generated from obstetric diameters.
    Generated(PelvisDiameters),
    /// Imported through a landmarks file (path relative to the file that names it).
    Imported { landmarks_file: PathBuf },
}

impl Default for PelvisSpec {
    fn default() -> Self {
        PelvisSpec::Generated(PelvisDiameters::default())
    }
}

/// Why the pelvis a spec names cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum PelvisBuildError {
    #[error(transparent)]
    Generate(#[from] PelvisError),
    #[error(transparent)]
    Import(#[from] ImportError),
}

impl PelvisBuildError {
    /// Whether the error is about the table's own diameters, not about an
    /// import's files (whose messages quote the landmarks file, not the table).
    pub fn of_diameters(&self) -> bool {
        matches!(self, PelvisBuildError::Generate(_))
    }

    /// The `[pelvis]` key to change, where the diameters name one.
    pub fn diameter_key(&self) -> Option<&'static str> {
        match self {
            PelvisBuildError::Generate(PelvisError::Diameters(e)) => Some(e.key()),
            _ => None,
        }
    }
}

impl PelvisSpec {
    /// Builds the pelvis; an imported one's path is taken relative to `base_dir`
    /// (the folder of the file the spec came from), except the name
    /// [`VISIBLE_HUMAN_FEMALE`], which is the shipped pelvis.
    pub fn build(&self, base_dir: &Path) -> Result<Pelvis, PelvisBuildError> {
        Ok(self.build_with_report(base_dir)?.0)
    }

    /// As [`PelvisSpec::build`], with what the importer found in an
    /// imported pelvis's mesh (holes, dropped triangles), and the mesh file.
    pub fn build_with_report(&self, base_dir: &Path) -> Result<(Pelvis, Option<(MeshReport, PathBuf)>), PelvisBuildError> {
        let imported = match self {
            PelvisSpec::Generated(d) => return Ok((Pelvis::generate(d)?, None)),
            PelvisSpec::Imported { landmarks_file } if landmarks_file.as_os_str() == VISIBLE_HUMAN_FEMALE => {
                visible_human_female_pelvis()?
            }
            PelvisSpec::Imported { landmarks_file } => import_pelvis(&base_dir.join(landmarks_file))?,
        };
        let ImportedPelvis { pelvis, report, mesh_path, .. } = imported;
        Ok((pelvis, Some((report, mesh_path))))
    }
}

impl<'de> Deserialize<'de> for PelvisSpec {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let table = toml::Table::deserialize(deserializer)?;
        match table.get("import") {
            Some(value) => {
                if let Some(other) = table.keys().find(|k| *k != "import") {
                    return Err(D::Error::custom(format!(
                        "`import` and `{other}` cannot be combined: an imported pelvis takes its diameters from its landmarks; remove one"
                    )));
                }
                let path = value
                    .as_str()
                    .ok_or_else(|| D::Error::custom("`import` must be a path in quotes, e.g. import = \"pelvis/landmarks.toml\""))?;
                Ok(PelvisSpec::Imported { landmarks_file: PathBuf::from(path) })
            }
            None => PelvisDiameters::deserialize(toml::Value::Table(table)).map(PelvisSpec::Generated).map_err(D::Error::custom),
        }
    }
}

impl Serialize for PelvisSpec {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            PelvisSpec::Generated(d) => d.serialize(serializer),
            PelvisSpec::Imported { landmarks_file } => {
                let mut map = serializer.serialize_map(Some(1))?;
                map.serialize_entry("import", landmarks_file)?;
                map.end()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct File {
        pelvis: PelvisSpec,
    }

    #[test]
    fn diameters_imports_and_mistakes() {
        let generated: File = toml::from_str("[pelvis]\ninlet_ap_mm = 100.0\n").unwrap();
        let expected = PelvisDiameters { inlet_ap_mm: 100.0, ..Default::default() };
        assert_eq!(generated.pelvis, PelvisSpec::Generated(expected));
        let imported: File = toml::from_str("[pelvis]\nimport = \"real/landmarks.toml\"\n").unwrap();
        assert_eq!(imported.pelvis, PelvisSpec::Imported { landmarks_file: "real/landmarks.toml".into() });
        let typo = toml::from_str::<File>("[pelvis]\ninlet_ap = 100.0\n").err().unwrap().to_string();
        assert!(typo.contains("inlet_ap"), "{typo}");
        let mixed = toml::from_str::<File>("[pelvis]\nimport = \"a.toml\"\nmid_ap_mm = 1.0\n").err().unwrap().to_string();
        assert!(mixed.contains("mid_ap_mm"), "{mixed}");
        let round = toml::to_string(&PelvisSpec::Imported { landmarks_file: "a.toml".into() }).unwrap();
        assert_eq!(round.trim(), "import = \"a.toml\"");
    }
}
