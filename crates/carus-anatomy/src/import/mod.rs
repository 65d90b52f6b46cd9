//! Import of real anatomy: surface meshes (STL binary and ASCII, OBJ, PLY,
//! glTF/GLB) and the landmarks files (TOML) that declare a mesh's units and
//! axes and its pelvis landmarks, and place it in the pelvis frame.
//!
//! This is one of the crate's explicit I/O modules: it reads files, nothing
//! else in the crate does. See docs/IMPORT.md for the formats, the landmarks
//! file and the shipped Visible Human Female pelvis.

mod formats;
mod landmarks;
pub mod pick;
mod weld;

#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

pub use formats::{parse_gltf_parts, parse_obj, parse_ply, parse_stl, MeshFormat, NamedPart, RawMesh};
pub use landmarks::{assemble_pelvis, import_pelvis, AxesDeclaration, ImportedPelvis, LandmarksFile};
pub use weld::{weld, MeshReport, MAX_COORDINATE_M};

use serde::{Deserialize, Serialize};

use crate::pelvis::PelvisError;
use crate::surface::{SurfaceDefect, TriSurface};

/// Length unit of a mesh file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    #[serde(rename = "mm")]
    Millimetres,
    #[serde(rename = "m")]
    Metres,
}

impl Units {
    /// The unit as a landmarks file writes it (`units = "mm"`).
    pub fn name(self) -> &'static str {
        match self {
            Units::Millimetres => "mm",
            Units::Metres => "m",
        }
    }

    /// Metres per file unit.
    pub fn to_metres(self) -> f64 {
        match self {
            Units::Millimetres => 1e-3,
            Units::Metres => 1.0,
        }
    }
}

/// Why a mesh leaves no surface, by what was read, and the fix.
fn empty_mesh(triangles_read: usize) -> String {
    match triangles_read {
        0 => "the mesh holds no triangles (0 read): the file has no faces (points or lines only, or an empty \
              export); export the surface itself as triangles or polygons"
            .to_string(),
        n => format!(
            "all {n} triangles read are degenerate (two corners at one point once equal vertices are merged), so \
             no surface is left; export the mesh again at full precision and in its own units (a rounding or \
             scaling export collapses small triangles)"
        ),
    }
}

/// What went wrong importing a mesh or a landmarks file, with the file and
/// the element concerned.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("cannot read {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: unknown mesh format; use a .stl, .obj, .ply, .gltf or .glb file")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: truncated binary STL: the header announces {expected} triangles but the file holds {found}; export the mesh again")]
    TruncatedStl {
        path: PathBuf,
        expected: usize,
        found: usize,
    },
    #[error("{path}: binary STL longer than its header says: the header announces {expected} triangles but the file holds {found} whole ones (and {spare_bytes} bytes over), which would be dropped; the exporter left a wrong count: export the mesh again, or as ASCII STL, OBJ or PLY")]
    OverlongStl {
        path: PathBuf,
        expected: usize,
        found: usize,
        spare_bytes: usize,
    },
    #[error("{path}: not a readable {format} file: {message}; export the mesh again from the tool that made it")]
    Format {
        path: PathBuf,
        format: &'static str,
        message: String,
    },
    #[error("{path}: triangle {} of the file (counting from 1, a polygon as its triangles), its corner {}, has a NaN or infinite coordinate, or a number past the 3.4e38 that the 32-bit floats of STL, OBJ and PLY hold; export the mesh again", .triangle + 1, .corner + 1)]
    NonFinite {
        path: PathBuf,
        triangle: usize,
        corner: usize,
        vertex: usize,
    },
    #[error("{path}: triangle {} of the file (counting from 1, a polygon as its triangles), its corner {}, has a coordinate {coordinate_m:.1e} m from the origin, beyond the {} m within which any anatomy lies; check `units` (mm or m) and export the mesh again", .triangle + 1, .corner + 1, weld::MAX_COORDINATE_M)]
    TooFar {
        path: PathBuf,
        triangle: usize,
        corner: usize,
        vertex: usize,
        coordinate_m: f64,
    },
    #[error("{path}: {}", empty_mesh(*.triangles_read))]
    Empty {
        path: PathBuf,
        /// The triangles the file held, every one degenerate; 0 for none.
        triangles_read: usize,
    },
    #[error("{path}: a closed surface is needed here, but {defect}; close the mesh (e.g. fill holes in MeshLab) and export it again")]
    NotClosed { path: PathBuf, defect: SurfaceDefect },
    #[error("{path}: {message}")]
    LandmarksFile { path: PathBuf, message: String },
    #[error("{path}: missing landmark(s) {}; add each under [landmarks] as `name = [x, y, z]` in the mesh's own coordinates and units", missing.join(", "))]
    MissingLandmarks { path: PathBuf, missing: Vec<String> },
    #[error("{path}: unknown landmark(s) {}; the landmarks are: {}", unknown.join(", "), known.join(", "))]
    UnknownLandmarks {
        path: PathBuf,
        unknown: Vec<String>,
        known: Vec<String>,
    },
    #[error("{path}: [axes]: {message}")]
    Axes { path: PathBuf, message: String },
    #[error("{path}: the landmarks disagree with the declared axes: {message}")]
    Orientation { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Pelvis { path: PathBuf, source: PelvisError },
}

/// A surface read from a file, in metres (the file's axes), with what the
/// importer found.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedSurface {
    pub surface: TriSurface,
    pub report: MeshReport,
}

/// Reads any supported mesh file into a welded surface in metres, keeping
/// the file's axes. The surface may be open or in several parts.
pub fn read_surface(path: &Path, units: Units) -> Result<ImportedSurface, ImportError> {
    let raw = formats::read_raw(path)?;
    let (surface, report) = weld(path, &raw, units.to_metres())?;
    Ok(ImportedSurface { surface, report })
}

/// Reads a mesh that must be one closed, consistently oriented,
/// outward-facing surface (a fetal head, for instance).
pub fn read_closed_surface(path: &Path, units: Units) -> Result<ImportedSurface, ImportError> {
    let imported = read_surface(path, units)?;
    imported
        .surface
        .check_closed()
        .map_err(|defect| ImportError::NotClosed {
            path: path.to_path_buf(),
            defect,
        })?;
    Ok(imported)
}

/// Reads a glTF/GLB file's meshes as separate named parts (file units and
/// axes, node transforms applied), e.g. to tell the bones of a pelvis apart.
pub fn read_gltf_parts(path: &Path) -> Result<Vec<NamedPart>, ImportError> {
    let bytes = carus_io::input::read_bytes(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_gltf_parts(path, &bytes)
}

/// The shipped assets folder (assets/anatomy in the repository).
pub fn anatomy_assets_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/anatomy")
}

/// The landmarks file of the shipped Visible Human Female pelvis.
pub fn visible_human_female_pelvis_path() -> PathBuf {
    anatomy_assets_dir().join("visible-human-female-pelvis.landmarks.toml")
}

/// The Visible Human Female pelvis (CC BY 4.0, see
/// assets/anatomy/ATTRIBUTION.md) in the pelvis frame. Its mesh and
/// landmarks file are compiled into the program, so it needs no files at
/// run time; [`visible_human_female_pelvis_path`] names the same file on disk.
pub fn visible_human_female_pelvis() -> Result<ImportedPelvis, ImportError> {
    let path = Path::new("assets/anatomy/visible-human-female-pelvis.landmarks.toml");
    let mesh_path = PathBuf::from("assets/anatomy/visible-human-female-pelvis.stl");
    let file = LandmarksFile::parse(path, VISIBLE_HUMAN_LANDMARKS)?;
    let raw = parse_stl(&mesh_path, VISIBLE_HUMAN_STL)?;
    assemble_pelvis(path, &file, mesh_path, &raw)
}

const VISIBLE_HUMAN_LANDMARKS: &str =
    include_str!("../../../../assets/anatomy/visible-human-female-pelvis.landmarks.toml");
const VISIBLE_HUMAN_STL: &[u8] = include_bytes!("../../../../assets/anatomy/visible-human-female-pelvis.stl");

/// Axes of the shipped Visible Human Female GLB (the source meshes' README:
/// metres, x to the body's left, y up, z forward).
pub fn visible_human_glb_axes() -> AxesDeclaration {
    AxesDeclaration {
        right: Some("-x".into()),
        anterior: Some("+z".into()),
        cranial: Some("+y".into()),
        ..Default::default()
    }
}

/// Axes of the shipped Visible Human Female STL (millimetres, x to the
/// body's left, y posterior, z superior).
pub fn visible_human_stl_axes() -> AxesDeclaration {
    AxesDeclaration {
        right: Some("-x".into()),
        anterior: Some("-y".into()),
        cranial: Some("+z".into()),
        ..Default::default()
    }
}
