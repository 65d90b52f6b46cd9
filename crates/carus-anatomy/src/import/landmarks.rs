//! The landmarks file: which mesh, its units and axes, and the pelvis
//! landmarks in the mesh's own coordinates; and the import of a pelvis
//! through it into the pelvis frame.
//!
//! ```toml
//! mesh = "visible-human-female-pelvis.stl"   # relative to this file
//! units = "mm"                               # or "m"
//! [axes]                                     # which mesh axis points where
//! right = "-x"                               # or left = "+x"
//! anterior = "-y"                            # or posterior = "+y"
//! cranial = "+z"                             # or caudal = "-z"
//! [landmarks]                                # every PelvisLandmarks name
//! sacral_promontory = [-6.1, 83.1, 107.7]
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat3, DVec3};
use serde::{Deserialize, Serialize};

use super::formats::{read_raw, RawMesh};
use super::{weld, ImportError, MeshReport, Units};
use crate::pelvis::{Pelvis, PelvisLandmarks, LANDMARK_NAMES, PELVIC_CANAL_DIAMETER_MM};

/// Where the mother's directions point in the mesh: each key takes a
/// signed mesh axis (`"+x"`, `"-y"`, `"z"`). Give one of each pair.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxesDeclaration {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub right: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub left: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anterior: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub posterior: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cranial: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caudal: Option<String>,
}

/// A landmarks file as written on disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarksFile {
    /// Free text: where the mesh and landmarks come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The mesh file, relative to the landmarks file.
    pub mesh: PathBuf,
    pub units: Units,
    pub axes: AxesDeclaration,
    /// Landmark name -> [x, y, z] in the mesh's coordinates and units
    /// (without the table, every landmark is missing and listed as such).
    #[serde(default, deserialize_with = "carus_io::toml_text::xyz_by_name")]
    pub landmarks: BTreeMap<String, [f64; 3]>,
}

/// A pelvis imported through a landmarks file.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedPelvis {
    /// Surface and landmarks in the pelvis frame, with planes and axis.
    pub pelvis: Pelvis,
    /// What the importer found in the mesh.
    pub report: MeshReport,
    /// The mesh file read.
    pub mesh_path: PathBuf,
    /// Maps the mesh file's coordinates (file units) into the pelvis frame (metres).
    pub mesh_to_pelvis: DAffine3,
}

fn file_error(path: &Path, message: impl ToString) -> ImportError {
    ImportError::LandmarksFile {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// An error in the landmark `name`, led by its line of `text` (`file:12:`).
fn at_landmark(path: &Path, text: &str, name: &str, message: String) -> ImportError {
    let line = carus_io::toml_text::line_of_key(text, &format!("landmarks.{name}"));
    file_error(Path::new(&carus_io::toml_text::located(path, line)), message)
}

impl AxesDeclaration {
    /// The matrix whose rows are the mother's right, anterior and cranial
    /// directions in mesh coordinates: it maps mesh vectors to the
    /// anatomical frame (x right, y anterior, z cranial). A reflection when
    /// the mesh's axes are left-handed.
    pub fn to_anatomical(&self, path: &Path) -> Result<DMat3, ImportError> {
        let axes_error = |message: String| ImportError::Axes {
            path: path.to_path_buf(),
            message,
        };
        let pick =
            |positive: &Option<String>, negative: &Option<String>, names: (&str, &str)| -> Result<DVec3, ImportError> {
                match (positive, negative) {
                    (Some(p), None) => parse_axis(p).ok_or_else(|| axes_error(bad_axis(names.0, p))),
                    (None, Some(n)) => parse_axis(n)
                        .map(|v| -v)
                        .ok_or_else(|| axes_error(bad_axis(names.1, n))),
                    (Some(_), Some(_)) => Err(axes_error(format!("give `{}` or `{}`, not both", names.0, names.1))),
                    (None, None) => Err(axes_error(format!(
                        "missing `{}` (or `{}`), e.g. {} = \"+x\"",
                        names.0, names.1, names.0
                    ))),
                }
            };
        let right = pick(&self.right, &self.left, ("right", "left"))?;
        let anterior = pick(&self.anterior, &self.posterior, ("anterior", "posterior"))?;
        let cranial = pick(&self.cranial, &self.caudal, ("cranial", "caudal"))?;
        if right.dot(anterior) != 0.0 || right.dot(cranial) != 0.0 || anterior.dot(cranial) != 0.0 {
            return Err(axes_error(
                "the three directions must use three different mesh axes".into(),
            ));
        }
        Ok(DMat3::from_cols(right, anterior, cranial).transpose())
    }
}

fn bad_axis(key: &str, value: &str) -> String {
    format!("{key} = \"{value}\" is not a mesh axis; use one of \"+x\", \"-x\", \"+y\", \"-y\", \"+z\", \"-z\"")
}

fn parse_axis(text: &str) -> Option<DVec3> {
    let text = text.trim();
    let (sign, axis) = match text.as_bytes().first()? {
        b'+' => (1.0, &text[1..]),
        b'-' => (-1.0, &text[1..]),
        _ => (1.0, text),
    };
    let unit = match axis.to_ascii_lowercase().as_str() {
        "x" => DVec3::X,
        "y" => DVec3::Y,
        "z" => DVec3::Z,
        _ => return None,
    };
    Some(sign * unit)
}

impl LandmarksFile {
    /// Reads and checks a landmarks file (names, not yet geometry).
    pub fn read(path: &Path) -> Result<Self, ImportError> {
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
        if ["stl", "obj", "ply", "gltf", "glb"].contains(&extension.as_str()) {
            return Err(file_error(
                path,
                "is a mesh; a pelvis is imported through a landmarks file (TOML) that names its mesh \
                 (`mesh = \"...\"`), its units and axes, and where the landmarks lie on it \
                 (docs/IMPORT.md, \"The landmarks file\")",
            ));
        }
        let text = carus_io::input::read_text(path).map_err(|source| ImportError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, &text)
    }

    /// Parses and checks landmarks text; `path` names it in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Self, ImportError> {
        // Names and required keys first, from the bare table: serde would
        // report an unknown landmark by its value's type, and a missing key
        // at line 1 without saying what it is.
        let table: toml::Table = text.parse().map_err(|e| file_error(path, e))?;
        let unknown: Vec<String> = match table.get("landmarks") {
            Some(toml::Value::Table(landmarks)) => landmarks
                .keys()
                .filter(|k| !LANDMARK_NAMES.contains(&k.as_str()))
                .cloned()
                .collect(),
            _ => Vec::new(),
        };
        if !unknown.is_empty() {
            return Err(ImportError::UnknownLandmarks {
                path: path.to_path_buf(),
                unknown,
                known: LANDMARK_NAMES.iter().map(|s| s.to_string()).collect(),
            });
        }
        for (key, what) in [
            (
                "mesh",
                "missing `mesh`, the mesh file (relative to this file); add e.g. `mesh = \"pelvis.stl\"` above \
                 the first [table]",
            ),
            (
                "units",
                "missing `units`, the unit of the mesh and of the landmarks; add `units = \"mm\"` (or \"m\") \
                 above the first [table]",
            ),
            (
                "axes",
                "missing the [axes] table, which mesh axis points to the mother's right, front and head; add e.g. \
                 `[axes]` with `right = \"-x\"`, `anterior = \"-y\"` and `cranial = \"+z\"` on lines of their own",
            ),
        ] {
            if !table.contains_key(key) {
                return Err(file_error(path, what));
            }
        }
        let file: LandmarksFile = toml::from_str(text).map_err(|e| file_error(path, e))?;
        let missing: Vec<String> = LANDMARK_NAMES
            .iter()
            .filter(|k| !file.landmarks.contains_key(**k))
            .map(|s| s.to_string())
            .collect();
        if !missing.is_empty() {
            return Err(ImportError::MissingLandmarks {
                path: path.to_path_buf(),
                missing,
            });
        }
        // `nan` and `inf` are TOML floats, read without a word.
        if let Some((name, p)) = file.landmarks.iter().find(|(_, p)| p.iter().any(|c| !c.is_finite())) {
            return Err(at_landmark(
                path,
                text,
                name,
                format!(
                    "landmark `{name}` = {p:?} has a coordinate that is not a finite number; give three finite \
                     numbers in {}, the file's `units`, in the mesh's own coordinates",
                    file.units.name()
                ),
            ));
        }
        // As for the mesh's vertices: a slip of exponent, named before it reads as a degenerate plane.
        let beyond = |p: &[f64; 3]| p.iter().any(|c| c.abs() * file.units.to_metres() > super::MAX_COORDINATE_M);
        if let Some((name, p)) = file.landmarks.iter().find(|(_, p)| beyond(p)) {
            return Err(at_landmark(
                path,
                text,
                name,
                format!(
                    "landmark `{name}` = {p:?} lies beyond {} m of the mesh's origin in {}; check its exponent and the file's `units`",
                    super::MAX_COORDINATE_M,
                    file.units.name()
                ),
            ));
        }
        Ok(file)
    }

    /// The landmarks mapped by `map` (applied to mesh coordinates).
    fn landmarks_through(&self, path: &Path, map: impl Fn(DVec3) -> DVec3) -> Result<PelvisLandmarks, ImportError> {
        let table: toml::Table = self
            .landmarks
            .iter()
            .map(|(name, p)| {
                let q = map(DVec3::from_array(*p));
                (
                    name.clone(),
                    toml::Value::Array(q.to_array().iter().map(|&c| toml::Value::Float(c)).collect()),
                )
            })
            .collect();
        toml::Value::Table(table).try_into().map_err(|e| file_error(path, e))
    }
}

/// Checks that left/right, front/back and up/down landmarks fall where the
/// declared axes say (anatomical frame), naming the first contradiction.
fn check_orientation(path: &Path, l: &PelvisLandmarks) -> Result<(), ImportError> {
    let contradiction = |message: String| {
        Err(ImportError::Orientation {
            path: path.to_path_buf(),
            message,
        })
    };
    // The widest pairs first: all three the wrong way is the axes' fault.
    for (left, right, name) in [
        (l.iliopectineal_left, l.iliopectineal_right, "iliopectineal"),
        (l.ischial_spine_left, l.ischial_spine_right, "ischial_spine"),
        (
            l.ischial_tuberosity_left,
            l.ischial_tuberosity_right,
            "ischial_tuberosity",
        ),
    ] {
        if right.x <= left.x {
            return contradiction(format!(
                "{name}_right does not lie to the mother's right of {name}_left; swap the left and right landmarks or fix `right`/`left` in [axes]"
            ));
        }
    }
    // The axes agree with those; a pair the wrong way here is a swap
    // (which would measure the obliques across the wrong corners).
    for (left, right, name) in [
        (l.sacroiliac_left, l.sacroiliac_right, "sacroiliac"),
        (l.iliopubic_eminence_left, l.iliopubic_eminence_right, "iliopubic_eminence"),
        (l.sacral_border_left, l.sacral_border_right, "sacral_border"),
        (l.ischiopubic_left, l.ischiopubic_right, "ischiopubic"),
    ] {
        if right.x <= left.x {
            return Err(ImportError::LandmarksFile {
                path: path.to_path_buf(),
                message: format!(
                    "[landmarks]: {name}_right does not lie to the mother's right of {name}_left, though the \
                     iliopectineal lines, spines and tuberosities do: the two are swapped; swap them back"
                ),
            });
        }
    }
    if l.symphysis_upper.y <= l.sacral_promontory.y {
        return contradiction(
            "symphysis_upper does not lie anterior to sacral_promontory; check those landmarks or fix `anterior`/`posterior` in [axes]".into(),
        );
    }
    if l.sacral_promontory.z <= l.coccyx_tip.z {
        return contradiction(
            "sacral_promontory does not lie cranial to coccyx_tip; check those landmarks or fix `cranial`/`caudal` in [axes]".into(),
        );
    }
    Ok(())
}

/// The closest two landmarks of one pelvis may lie, in metres: they mark
/// different points of the bone, the closest of the shipped Visible Human
/// Female pelvis 16 mm apart (sacral apex and S4-S5), so within a
/// millimetre one is a copy of the other (and a chord between them has no
/// direction: the sacral depth would measure NaN).
pub const MIN_LANDMARK_SEPARATION_M: f64 = 1e-3;

/// Checks that no two landmarks coincide, naming the closest such pair.
fn check_distinct(path: &Path, units: Units, l: &PelvisLandmarks) -> Result<(), ImportError> {
    let named = l.named();
    let mut closest: Option<(f64, &str, &str)> = None;
    for (i, &(a, p)) in named.iter().enumerate() {
        for &(b, q) in &named[i + 1..] {
            let d = p.distance(q);
            if d < MIN_LANDMARK_SEPARATION_M && closest.is_none_or(|(c, _, _)| d < c) {
                closest = Some((d, a, b));
            }
        }
    }
    match closest {
        None => Ok(()),
        Some((d, a, b)) => Err(ImportError::LandmarksFile {
            path: path.to_path_buf(),
            message: format!(
                "[landmarks]: {a} and {b} lie {:.2} {} apart, one point named twice; each marks a different point of the bone \
                 (the closest two of a pelvis lie some 15 mm apart): give {b} its own place",
                d / units.to_metres(),
                units.name()
            ),
        }),
    }
}

/// Imports a pelvis: reads the landmarks file and its mesh, converts units,
/// turns the declared axes into the anatomical frame, checks the landmarks
/// against them, then moves mesh and landmarks into the pelvis frame that
/// the landmarks define (CONVENTIONS.md) and assembles the [`Pelvis`].
///
/// The bone surface may be several parts and may be open (real segmented
/// bone often is): it is checked for finite coordinates and valid,
/// non-degenerate triangles only, and its parts, closed parts and open
/// edges are reported in [`ImportedPelvis::report`].
pub fn import_pelvis(path: &Path) -> Result<ImportedPelvis, ImportError> {
    let file = LandmarksFile::read(path)?;
    let mesh_path = path.parent().unwrap_or(Path::new(".")).join(&file.mesh);
    // A mesh that is not there is the landmarks file's `mesh` key to fix.
    if !mesh_path.exists() {
        return Err(file_error(
            path,
            format!(
                "`mesh = {:?}` names {}, which does not exist; the path is relative to this landmarks \
                 file: correct it, or put the mesh beside the landmarks file",
                file.mesh.display().to_string(),
                mesh_path.display()
            ),
        ));
    }
    let raw = read_raw(&mesh_path)?;
    assemble_pelvis(path, &file, mesh_path, &raw)
}

/// The obstetric conjugate must measure as a pelvis's does: a mesh in mm
/// declared in m (or the other way round) is a thousand times off.
fn check_size(path: &Path, units: Units, landmarks: &PelvisLandmarks) -> Result<(), ImportError> {
    let conjugate_mm = landmarks.sacral_promontory.distance(landmarks.symphysis_upper) * 1e3;
    let (least, most) = PELVIC_CANAL_DIAMETER_MM;
    if (least..=most).contains(&conjugate_mm) {
        return Ok(());
    }
    let declared = units.name();
    Err(file_error(
        path,
        format!(
            "sacral_promontory to symphysis_upper (the obstetric conjugate) measures {conjugate_mm:.4} mm \
             with `units = \"{declared}\"`, outside the {least}-{most} mm of any pelvis; check that `units` \
             is the unit of the mesh and of the landmarks (a mesh in another unit must be rescaled to \
             mm or m), and that the two landmarks lie where their names say"
        ),
    ))
}

/// How far a landmark may lie from the imported bone's surface, mm. Landmarks
/// are points of the bone; one picked by hand in a viewer can sit a few
/// millimetres off, while a mesh in another unit than the landmarks puts
/// them tens of millimetres or more away.
const LANDMARK_SURFACE_GAP_MAX_MM: f64 = 10.0;

/// The landmarks must lie on the mesh: a mesh in another unit, or from
/// another pelvis, leaves them off it, and the canal would not be the one
/// they describe.
/// Checked before the canal is built from them, so that one landmark off
/// the bone (a slip of a digit) is named, not the plane it bends.
fn check_landmarks_on_bone(
    path: &Path,
    mesh_path: &Path,
    units: Units,
    landmarks: &PelvisLandmarks,
    surface: &crate::TriSurface,
) -> Result<(), ImportError> {
    let (name, gap_m) = crate::pelvis::measure::farthest_landmark_from_bone(landmarks, surface);
    let gap_mm = 1e3 * gap_m;
    if gap_mm <= LANDMARK_SURFACE_GAP_MAX_MM {
        return Ok(());
    }
    let declared = units.name();
    Err(file_error(
        path,
        format!(
            "landmark `{name}` lies {gap_mm:.1} mm from the bone of {} (at most {LANDMARK_SURFACE_GAP_MAX_MM} mm \
             allowed): the landmarks are not on this mesh; check that the mesh is in the landmarks' unit \
             (`units = \"{declared}\"` is read for both; rescale the mesh if not), that it is the pelvis \
             they were picked on, and that it has the bone `{name}` lies on (a segmentation can leave out \
             the coccyx or the pubic rami)",
            mesh_path.display()
        ),
    ))
}

/// The least bone surface a pelvis mesh may have, as a multiple of the
/// square of its obstetric conjugate. A whole pelvis has far more: the
/// generated one 10.5, the Visible Human mesh (outer and inner bone) 24.
/// A mesh of a few patches around the landmarks passes every landmark
/// check, but the fetus would pass through the canal where it has no bone.
const BONE_AREA_MIN_PER_CONJUGATE_SQUARED: f64 = 2.0;

/// A mesh with too little bone for a pelvis is refused, naming its area.
fn check_bone_enough(mesh_path: &Path, landmarks: &PelvisLandmarks, surface: &crate::TriSurface) -> Result<(), ImportError> {
    let conjugate = landmarks.sacral_promontory.distance(landmarks.symphysis_upper);
    let least = BONE_AREA_MIN_PER_CONJUGATE_SQUARED * conjugate * conjugate;
    let area = surface.area();
    if area >= least {
        return Ok(());
    }
    Err(file_error(
        mesh_path,
        format!(
            "its bone has {:.1} cm^2 of surface, less than the {:.0} cm^2 any whole pelvis with this \
             {:.1} mm conjugate has: it is a partial or sparse mesh, and the fetus would pass where it has \
             no bone; import the whole bony pelvis (both hip bones, the sacrum and the coccyx)",
            area * 1e4,
            least * 1e4,
            conjugate * 1e3
        ),
    ))
}

/// [`import_pelvis`] for a landmarks file already read and its mesh's
/// triangles (e.g. embedded in the program); `path` names the landmarks
/// file in errors, `mesh_path` the mesh.
pub fn assemble_pelvis(
    path: &Path,
    file: &LandmarksFile,
    mesh_path: PathBuf,
    raw: &RawMesh,
) -> Result<ImportedPelvis, ImportError> {
    let to_anatomical = file.axes.to_anatomical(path)?;
    let scale = file.units.to_metres();

    let anatomical = file.landmarks_through(path, |p| to_anatomical * (p * scale))?;
    check_size(path, file.units, &anatomical)?;
    check_distinct(path, file.units, &anatomical)?;
    check_orientation(path, &anatomical)?;
    let to_pelvis = anatomical.to_pelvis_frame().map_err(|source| ImportError::Pelvis {
        path: path.to_path_buf(),
        source,
    })?;
    let landmarks = anatomical.map(|p| to_pelvis.transform_point3(p));

    let (mut surface, mut report) = weld(&mesh_path, raw, scale)?;
    let mesh_to_pelvis_metres = to_pelvis * DAffine3::from_mat3(to_anatomical);
    surface.transform(&mesh_to_pelvis_metres);
    // Bone facing into itself would draw the fetus into the bone; a part
    // without holes has a certain outside, so it is turned (and noted).
    report.turned_outwards = super::weld::turn_parts_outwards(&mut surface) > 0;
    check_landmarks_on_bone(path, &mesh_path, file.units, &landmarks, &surface)?;
    check_bone_enough(&mesh_path, &landmarks, &surface)?;
    let pelvis = Pelvis::from_landmarks(landmarks, surface).map_err(|source| ImportError::Pelvis {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(ImportedPelvis {
        pelvis,
        report,
        mesh_path,
        mesh_to_pelvis: mesh_to_pelvis_metres * DAffine3::from_scale(DVec3::splat(scale)),
    })
}
