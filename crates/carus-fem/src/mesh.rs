//! Volume meshes of one element kind, with named node, element and surface sets.
//!
//! Node ordering follows VTK, which Gmsh and Abaqus (C3D8, C3D4) share:
//! - H8: nodes 0-1-2-3 form the bottom face, ordered so that their right-hand
//!   normal points towards the top face 4-5-6-7; node 4+i sits above node i.
//! - T4: positive orientation when (x1 - x0) x (x2 - x0) . (x3 - x0) > 0.
//!
//! Coordinates are metres (SI, see CONVENTIONS.md).

use std::collections::{BTreeMap, HashMap};

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

/// H8 faces in VTK node order, wound counter-clockwise seen from outside.
pub const H8_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// T4 faces, wound counter-clockwise seen from outside a positive tetrahedron.
pub const T4_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];

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
        self.connectivity
            .chunks_exact(self.kind.nodes_per_element())
    }

    /// Each node's mean of a per-element value over the elements that hold
    /// it (a node in no element gets 0): element results drawn smoothly on
    /// a surface, as ParaView's Cell Data to Point Data does.
    pub fn nodal_mean(&self, element_values: &[f64]) -> Vec<f64> {
        let mut sum = vec![0.0; self.node_count()];
        let mut count = vec![0u32; self.node_count()];
        for (nodes, &value) in self.elements().zip(element_values) {
            for &n in nodes {
                sum[n as usize] += value;
                count[n as usize] += 1;
            }
        }
        sum.iter()
            .zip(&count)
            .map(|(&s, &c)| if c == 0 { 0.0 } else { s / f64::from(c) })
            .collect()
    }

    /// The outside of the part of the mesh made of `elements`: the faces only
    /// one of them has, as triangles wound outwards (H8 quads split in two).
    pub fn boundary_triangles(&self, elements: &[u32]) -> Vec<[u32; 3]> {
        let faces: Vec<Vec<u32>> = elements
            .iter()
            .flat_map(|&e| {
                let nodes = self.element(e as usize);
                let local: Vec<&[usize]> = match self.kind {
                    ElementKind::H8 => H8_FACES.iter().map(|f| &f[..]).collect(),
                    ElementKind::T4 => T4_FACES.iter().map(|f| &f[..]).collect(),
                };
                local
                    .into_iter()
                    .map(|f| f.iter().map(|&k| nodes[k]).collect::<Vec<u32>>())
                    .collect::<Vec<_>>()
            })
            .collect();
        let key = |f: &[u32]| {
            let mut k = f.to_vec();
            k.sort_unstable();
            k
        };
        let mut count: HashMap<Vec<u32>, u32> = HashMap::new();
        for f in &faces {
            *count.entry(key(f)).or_default() += 1;
        }
        faces
            .iter()
            .filter(|f| count[&key(f)] == 1)
            .flat_map(|f| match f.as_slice() {
                [a, b, c, d] => vec![[*a, *b, *c], [*a, *c, *d]],
                [a, b, c] => vec![[*a, *b, *c]],
                _ => Vec::new(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume enclosed by triangles (divergence theorem).
    fn enclosed_volume(mesh: &Mesh, triangles: &[[u32; 3]]) -> f64 {
        triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.nodes[i as usize]);
                let cross = [
                    b[1] * c[2] - b[2] * c[1],
                    b[2] * c[0] - b[0] * c[2],
                    b[0] * c[1] - b[1] * c[0],
                ];
                (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
            })
            .sum()
    }

    fn two_hexes() -> Mesh {
        let mut nodes = Vec::new();
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..3 {
                    nodes.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let id = |x: u32, y: u32, z: u32| x + 3 * y + 6 * z;
        let hex = |x: u32| {
            [
                id(x, 0, 0),
                id(x + 1, 0, 0),
                id(x + 1, 1, 0),
                id(x, 1, 0),
                id(x, 0, 1),
                id(x + 1, 0, 1),
                id(x + 1, 1, 1),
                id(x, 1, 1),
            ]
        };
        Mesh::new(ElementKind::H8, nodes, [hex(0), hex(1)].concat())
    }

    #[test]
    fn a_nodes_mean_is_over_the_elements_that_hold_it() {
        let mesh = two_hexes();
        let mean = mesh.nodal_mean(&[1.0, 3.0]);
        // Node x + 3 y + 6 z: x = 0 only in the first hex, x = 2 only in
        // the second, x = 1 on the face they share.
        for (node, expected) in [(0, 1.0), (1, 2.0), (2, 3.0), (3, 1.0), (4, 2.0), (11, 3.0)] {
            assert_eq!(mean[node], expected, "node {node}");
        }
        assert_eq!(mesh.nodal_mean(&[5.0, 5.0]), vec![5.0; mesh.node_count()]);
    }

    #[test]
    fn boundary_of_two_hexes_drops_the_shared_face_and_faces_outwards() {
        let mesh = two_hexes();
        let outside = mesh.boundary_triangles(&[0, 1]);
        assert_eq!(outside.len(), 2 * 10, "10 outer quads");
        assert!((enclosed_volume(&mesh, &outside) - 2.0).abs() < 1e-12);
        let one = mesh.boundary_triangles(&[1]);
        assert_eq!(one.len(), 12);
        assert!((enclosed_volume(&mesh, &one) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn boundary_of_a_tetrahedron_faces_outwards() {
        let mesh = Mesh::new(
            ElementKind::T4,
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![0, 1, 2, 3],
        );
        let outside = mesh.boundary_triangles(&[0]);
        assert_eq!(outside.len(), 4);
        assert!((enclosed_volume(&mesh, &outside) - 1.0 / 6.0).abs() < 1e-12);
    }
}
