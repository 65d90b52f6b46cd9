//! Mesh input from the formats researchers already have (Gmsh `.msh`,
//! VTK `.vtk`/`.vtu`, Abaqus `.inp`) and result output (VTU frames, a PVD
//! time series, CSV histories).
//!
//! This is an I/O crate: it touches the file system, but never prints and
//! never panics on bad input; every error names the file, the line (or the
//! file's own node or element id) and the fix.

pub mod abaqus;
mod builder;
pub mod csv;
pub mod error;
pub mod gmsh;
pub mod input;
pub mod job;
pub mod output;
pub mod pvd;
mod text;
pub mod toml_text;
pub mod units;
pub mod vtk;
mod vtk_compat;
mod xml_attr;

use std::path::Path;

pub use builder::MeshFile;
pub use csv::{missing_as_nan, CsvRow, CsvTable, CsvWriter};
pub use error::{ReadError, WriteError};
pub use pvd::PvdCollection;
pub use text::{shown_line, shown_number};
pub use units::LengthUnit;
pub use vtk::{write_triangle_vtu, write_vtu, FrameFields};

/// Reads a volume mesh, choosing the reader by the file's extension:
/// `.msh` (Gmsh), `.vtk`/`.vtu` (VTK), `.inp` (Abaqus). Coordinates are
/// returned as written; see [`MeshFile::to_metres`].
pub fn read_mesh(path: &Path) -> Result<MeshFile, ReadError> {
    if path.is_dir() {
        return Err(ReadError::Io {
            path: path.to_path_buf(),
            cause: std::io::Error::other("a folder, not a mesh file: name the .msh, .vtk, .vtu or .inp file in it"),
        });
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match extension.as_str() {
        "msh" => gmsh::read_msh(path),
        "vtk" | "vtu" => vtk::read_vtk(path),
        "inp" => abaqus::read_inp(path),
        _ => Err(ReadError::UnknownFormat {
            path: path.to_path_buf(),
            extension,
        }),
    }
}

/// A path in a fresh folder that is removed with the returned guard (the
/// tests' scratch files leave nothing behind).
#[cfg(test)]
fn temp(name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    (dir, path)
}

#[cfg(test)]
mod tests {
    /// A folder named for a mesh is said to be one, with the extensions
    /// to look for, whatever its name ends with.
    #[test]
    fn a_folder_is_no_mesh() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["meshes", "cube.msh"] {
            let folder = dir.path().join(name);
            std::fs::create_dir(&folder).unwrap();
            let e = super::read_mesh(&folder).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("a folder, not a mesh file") && e.contains(".msh, .vtk"), "{e}");
        }
    }
}
