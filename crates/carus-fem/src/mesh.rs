//! Volume meshes of one element kind, with named node, element and surface sets.
//!
//! Node ordering follows VTK, which Gmsh and Abaqus (C3D8, C3D4) share:
//! - H8: nodes 0-1-2-3 form the bottom face, ordered so that their right-hand
//!   normal points towards the top face 4-5-6-7; node 4+i sits above node i.
//! - T4: positive orientation when (x1 - x0) x (x2 - x0) . (x3 - x0) > 0.
//!
//! Coordinates are metres (SI, see CONVENTIONS.md).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The element family of a mesh. One mesh holds one kind, so the solver can
/// lay each kind out as a structure of arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// 8-node hexahedron.
    H8,
    /// 4-node tetrahedron.
    T4,
}

impl ElementKind {
    /// Nodes per element.
    pub const fn nodes_per_element(self) -> usize {
        match self {
            ElementKind::H8 => 8,
            ElementKind::T4 => 4,
        }
    }

    /// Lower-case name as used on the command line (`h8`, `t4`).
    pub const fn name(self) -> &'static str {
        match self {
            ElementKind::H8 => "h8",
            ElementKind::T4 => "t4",
        }
    }
}

/// A volume mesh: node coordinates, element connectivity and named sets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Element family shared by every element.
    pub kind: ElementKind,
    /// Reference (undeformed) node coordinates, metres.
    pub nodes: Vec<[f64; 3]>,
    /// Connectivity, `kind.nodes_per_element()` node indices per element.
    pub connectivity: Vec<u32>,
    /// Named node sets (boundary conditions, landmarks, attachments).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Named element sets (per-set materials).
    pub element_sets: BTreeMap<String, Vec<u32>>,
    /// Named boundary surfaces as triangles (node indices, outward normal by
    /// the right-hand rule), for pressure loads and contact.
    pub surfaces: BTreeMap<String, Vec<[u32; 3]>>,
}

impl Mesh {
    /// A mesh with no sets.
    pub fn new(kind: ElementKind, nodes: Vec<[f64; 3]>, connectivity: Vec<u32>) -> Self {
        Mesh {
            kind,
            nodes,
            connectivity,
            node_sets: BTreeMap::new(),
            element_sets: BTreeMap::new(),
            surfaces: BTreeMap::new(),
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.connectivity.len() / self.kind.nodes_per_element()
    }

    /// Node indices of element `e`.
    pub fn element(&self, e: usize) -> &[u32] {
        let n = self.kind.nodes_per_element();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// Iterator over the elements' node index slices.
    pub fn elements(&self) -> std::slice::ChunksExact<'_, u32> {
        self.connectivity.chunks_exact(self.kind.nodes_per_element())
    }
}
