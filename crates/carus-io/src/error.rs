//! Errors of the readers and writers. Each names the file, the place in it
//! (line, or the file's own node or element id) and the fix.

use std::path::PathBuf;

/// A file could not be read: a mesh that cannot become a
/// [`carus_fem::Mesh`], or a table.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("{}: cannot read the file: {cause}; fix: check the path and its permissions", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// The extension names no format Carus reads.
    #[error("{}: unknown mesh format {extension:?}; fix: use .msh (Gmsh), .vtk or .vtu (VTK) or .inp (Abaqus)", path.display())]
    UnknownFormat { path: PathBuf, extension: String },
    /// Malformed text at a known line (1-based).
    #[error("{}:{line}: {problem}; fix: {fix}", path.display())]
    Syntax {
        path: PathBuf,
        line: usize,
        problem: String,
        fix: String,
    },
    /// Inconsistent content; `problem` names the node, element or set.
    #[error("{}: {problem}; fix: {fix}", path.display())]
    Content {
        path: PathBuf,
        problem: String,
        fix: String,
    },
    /// Both hexahedra and tetrahedra: the solver lays out one kind per mesh.
    #[error(
        "{}: the mesh mixes {hexahedra} hexahedra and {tetrahedra} tetrahedra, but a Carus mesh holds one element kind; \
         fix: mesh the whole volume with one kind (for example split the hexahedra into tetrahedra, \
         Gmsh: Mesh.SubdivisionAlgorithm = 1 gives all hexahedra, or drop Recombine for all tetrahedra)",
        path.display()
    )]
    MixedElementKinds {
        path: PathBuf,
        hexahedra: usize,
        tetrahedra: usize,
    },
}

/// A result file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The operating system refused the write.
    #[error("{}: cannot write the file: {cause}; fix: check that the folder exists, is writable and the disk has room", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// The data do not fit the mesh (a caller's bug, reported rather than panicking).
    #[error("{}: {problem}", path.display())]
    Shape { path: PathBuf, problem: String },
    /// The VTK library refused the data set.
    #[error("{}: the VTK writer failed: {message}", path.display())]
    Vtk { path: PathBuf, message: String },
}
