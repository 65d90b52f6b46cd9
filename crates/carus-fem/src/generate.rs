//! Structured box meshes for verification cases and benchmarks.
//!
//! Nodes lie on a regular grid; node (i, j, k) has index
//! `i + (nx + 1) * (j + (ny + 1) * k)`. Each box mesh carries the node sets
//! `x0`, `x1`, `y0`, `y1`, `z0`, `z1` (the nodes on the faces x = 0, x = Lx,
//! ...) and surfaces of the same names (triangles with outward normals).
//! Every face quad is split along its diagonal from the grid's lower to its
//! upper corner, the diagonal the T4 split produces on the boundary, so the
//! surface triangles of a T4 box are faces of its tetrahedra.

use std::collections::BTreeMap;

use crate::mesh::{ElementKind, Mesh};
use crate::model::{det3, sub};

/// Offsets of the eight hexahedron corners in VTK order (bottom face
/// counter-clockwise seen from above, then the top face).
const HEX_CORNERS: [[usize; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];

/// A box `[0, Lx] x [0, Ly] x [0, Lz]` of `nx * ny * nz` 8-node hexahedra.
///
/// Zero cell counts or non-positive lengths give an empty mesh (no elements);
/// callers validate sizes before asking.
pub fn box_h8(lengths_m: [f64; 3], cells: [usize; 3]) -> Mesh {
    let grid = Grid::new(lengths_m, cells);
    let mut connectivity = Vec::with_capacity(grid.cell_count() * 8);
    for [i, j, k] in grid.cells() {
        for c in HEX_CORNERS {
            connectivity.push(grid.node(i + c[0], j + c[1], k + c[2]));
        }
    }
    grid.into_mesh(ElementKind::H8, connectivity)
}

/// The same box as [`box_h8`], each hexahedron split into 6 tetrahedra around
/// its local (0,0,0)-(1,1,1) diagonal (VALIDATION.md, V3 in detail), each
/// positively oriented. Neighbouring cells share the split of their common
/// face, so the mesh is conforming.
pub fn box_t4(lengths_m: [f64; 3], cells: [usize; 3]) -> Mesh {
    let grid = Grid::new(lengths_m, cells);
    let mut connectivity = Vec::with_capacity(grid.cell_count() * 24);
    for [i, j, k] in grid.cells() {
        for path in DIAGONAL_PATHS {
            // A monotone lattice path (0,0,0) -> (1,1,1) visits four corners;
            // the six paths give the six tetrahedra of the split.
            let mut corner = [0usize; 3];
            let mut tet = [grid.node(i, j, k); 4];
            for (step, axis) in path.iter().enumerate() {
                corner[*axis] = 1;
                tet[step + 1] = grid.node(i + corner[0], j + corner[1], k + corner[2]);
            }
            if signed_volume6(&grid.nodes, tet) < 0.0 {
                tet.swap(1, 2);
            }
            connectivity.extend_from_slice(&tet);
        }
    }
    grid.into_mesh(ElementKind::T4, connectivity)
}

/// The six orders in which a path from (0,0,0) to (1,1,1) can cross the axes.
const DIAGONAL_PATHS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];

/// Six times the signed volume of a tetrahedron.
fn signed_volume6(nodes: &[[f64; 3]], tet: [u32; 4]) -> f64 {
    let p = tet.map(|n| nodes[n as usize]);
    det3(&[sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])])
}

/// The node grid of a box and its face sets.
struct Grid {
    cells: [usize; 3],
    nodes: Vec<[f64; 3]>,
}

impl Grid {
    fn new(lengths_m: [f64; 3], cells: [usize; 3]) -> Grid {
        let [nx, ny, nz] = cells;
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        // A zero count leaves no cells; the coordinate divisor only needs to
        // stay non-zero.
        let h = [0, 1, 2].map(|a| lengths_m[a] / cells[a].max(1) as f64);
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    nodes.push([i as f64 * h[0], j as f64 * h[1], k as f64 * h[2]]);
                }
            }
        }
        Grid { cells, nodes }
    }

    fn cell_count(&self) -> usize {
        self.cells.iter().product()
    }

    fn node(&self, i: usize, j: usize, k: usize) -> u32 {
        (i + (self.cells[0] + 1) * (j + (self.cells[1] + 1) * k)) as u32
    }

    fn cells(&self) -> impl Iterator<Item = [usize; 3]> {
        let [nx, ny, nz] = self.cells;
        (0..nz).flat_map(move |k| (0..ny).flat_map(move |j| (0..nx).map(move |i| [i, j, k])))
    }

    /// Builds the mesh with the six face node sets and surfaces.
    fn into_mesh(self, kind: ElementKind, connectivity: Vec<u32>) -> Mesh {
        let mut node_sets = BTreeMap::new();
        let mut surfaces = BTreeMap::new();
        if self.cell_count() > 0 {
            for axis in 0..3 {
                for (side, name_end) in [(0usize, '0'), (1, '1')] {
                    let name = format!("{}{}", ['x', 'y', 'z'][axis], name_end);
                    node_sets.insert(name.clone(), self.face_nodes(axis, side));
                    surfaces.insert(name, self.face_triangles(axis, side));
                }
            }
        }
        let mut mesh = Mesh::new(kind, self.nodes, connectivity);
        mesh.node_sets = node_sets;
        mesh.surfaces = surfaces;
        mesh
    }

    /// Grid index of a node on the face normal to `axis` at `side` (0: low,
    /// 1: high), from its two in-plane grid indices (u along the next axis,
    /// v along the one after).
    fn face_node(&self, axis: usize, side: usize, u: usize, v: usize) -> u32 {
        let mut ijk = [0usize; 3];
        ijk[axis] = side * self.cells[axis];
        ijk[(axis + 1) % 3] = u;
        ijk[(axis + 2) % 3] = v;
        self.node(ijk[0], ijk[1], ijk[2])
    }

    fn face_nodes(&self, axis: usize, side: usize) -> Vec<u32> {
        let (nu, nv) = (self.cells[(axis + 1) % 3], self.cells[(axis + 2) % 3]);
        let mut nodes: Vec<u32> = (0..=nv)
            .flat_map(|v| (0..=nu).map(move |u| (u, v)))
            .map(|(u, v)| self.face_node(axis, side, u, v))
            .collect();
        nodes.sort_unstable();
        nodes
    }

    fn face_triangles(&self, axis: usize, side: usize) -> Vec<[u32; 3]> {
        let (nu, nv) = (self.cells[(axis + 1) % 3], self.cells[(axis + 2) % 3]);
        let mut triangles = Vec::with_capacity(2 * nu * nv);
        for v in 0..nv {
            for u in 0..nu {
                let a = self.face_node(axis, side, u, v);
                let b = self.face_node(axis, side, u + 1, v);
                let c = self.face_node(axis, side, u + 1, v + 1);
                let d = self.face_node(axis, side, u, v + 1);
                // (u, v, axis) is right-handed, so a-b-c turns towards +axis;
                // the low face needs the opposite turn to point outwards.
                if side == 1 {
                    triangles.push([a, b, c]);
                    triangles.push([a, c, d]);
                } else {
                    triangles.push([a, c, b]);
                    triangles.push([a, d, c]);
                }
            }
        }
        triangles
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::cross;
    use proptest::prelude::*;
    use std::collections::HashSet;

    fn hex_volume(mesh: &Mesh, e: usize) -> f64 {
        // Bounding box volume: the structured hexahedra are axis-aligned boxes.
        let el = mesh.element(e);
        let p0 = mesh.nodes[el[0] as usize];
        let p6 = mesh.nodes[el[6] as usize];
        (p6[0] - p0[0]) * (p6[1] - p0[1]) * (p6[2] - p0[2])
    }

    #[test]
    fn h8_counts_ordering_and_sets() {
        let mesh = box_h8([2.0, 1.0, 0.5], [4, 3, 2]);
        assert_eq!(mesh.kind, ElementKind::H8);
        assert_eq!(mesh.node_count(), 5 * 4 * 3);
        assert_eq!(mesh.element_count(), 24);
        for e in 0..mesh.element_count() {
            let el = mesh.element(e);
            let p = |i: usize| mesh.nodes[el[i] as usize];
            // Bottom face normal (right-hand rule) points to the top face.
            let n = cross(sub(p(1), p(0)), sub(p(3), p(0)));
            let up = sub(p(4), p(0));
            assert!(n[0] * up[0] + n[1] * up[1] + n[2] * up[2] > 0.0);
            assert!((hex_volume(&mesh, e) - 0.5 * (1.0 / 3.0) * 0.25).abs() < 1e-12);
        }
        assert_eq!(mesh.node_sets["x0"].len(), 4 * 3);
        assert_eq!(mesh.node_sets["z1"].len(), 5 * 4);
        for node in &mesh.node_sets["x1"] {
            assert_eq!(mesh.nodes[*node as usize][0], 2.0);
        }
        for node in &mesh.node_sets["y0"] {
            assert_eq!(mesh.nodes[*node as usize][1], 0.0);
        }
    }

    #[test]
    fn t4_split_is_six_positive_tets_filling_the_box() {
        let mesh = box_t4([1.0, 2.0, 3.0], [2, 3, 4]);
        assert_eq!(mesh.kind, ElementKind::T4);
        assert_eq!(mesh.element_count(), 6 * 24);
        let mut total = 0.0;
        for el in mesh.elements() {
            let v6 = signed_volume6(&mesh.nodes, [el[0], el[1], el[2], el[3]]);
            assert!(v6 > 0.0);
            total += v6 / 6.0;
        }
        assert!((total - 6.0).abs() < 1e-12);
    }

    #[test]
    fn t4_every_tet_contains_its_cell_diagonal() {
        let mesh = box_t4([1.0, 1.0, 1.0], [3, 3, 3]);
        let h = 1.0 / 3.0;
        for el in mesh.elements() {
            let p: Vec<[f64; 3]> = el.iter().map(|n| mesh.nodes[*n as usize]).collect();
            let lo = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).fold(f64::MAX, f64::min));
            let has = |c: [f64; 3]| p.iter().any(|q| (0..3).all(|a| (q[a] - c[a]).abs() < 1e-12));
            assert!(has(lo));
            assert!(has([lo[0] + h, lo[1] + h, lo[2] + h]));
        }
    }

    /// Every interior triangle is shared by exactly two tetrahedra with
    /// opposite orientation, and the boundary faces are exactly the six
    /// surfaces: the split is conforming and the surfaces are tet faces.
    #[test]
    fn t4_is_conforming_and_surfaces_are_tet_faces() {
        let mesh = box_t4([1.0, 1.0, 1.0], [2, 3, 2]);
        let mut open: HashSet<[u32; 3]> = HashSet::new();
        let canonical = |t: [u32; 3]| {
            // Rotate so the smallest index comes first, keeping orientation.
            let m = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
            [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
        };
        for el in mesh.elements() {
            // Outward faces of a positive tet (a, b, c, d).
            let [a, b, c, d] = [el[0], el[1], el[2], el[3]];
            for face in [[a, c, b], [a, b, d], [b, c, d], [a, d, c]] {
                let reversed = canonical([face[0], face[2], face[1]]);
                if !open.remove(&reversed) {
                    open.insert(canonical(face));
                }
            }
        }
        let surface: HashSet<[u32; 3]> =
            mesh.surfaces.values().flatten().map(|t| canonical(*t)).collect();
        assert_eq!(open, surface);
    }

    #[test]
    fn surfaces_point_outwards_and_cover_each_face() {
        for mesh in [box_h8([1.0, 2.0, 3.0], [2, 2, 3]), box_t4([1.0, 2.0, 3.0], [2, 2, 3])] {
            let lengths = [1.0, 2.0, 3.0];
            for (name, triangles) in &mesh.surfaces {
                let axis = "xyz".find(&name[0..1]).unwrap_or(3);
                let outward = if name.ends_with('0') { -1.0 } else { 1.0 };
                let mut area = 0.0;
                for t in triangles {
                    let p = t.map(|n| mesh.nodes[n as usize]);
                    let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                    assert!(n[axis] * outward > 0.0, "{name} triangle {t:?} points inwards");
                    area += 0.5 * n[axis].abs();
                    assert!(t.iter().all(|v| mesh.node_sets[name].binary_search(v).is_ok()));
                }
                let expected = lengths.iter().product::<f64>() / lengths[axis];
                assert!((area - expected).abs() < 1e-12, "{name}: {area} != {expected}");
            }
        }
    }

    #[test]
    fn zero_cells_give_an_empty_mesh() {
        let mesh = box_h8([1.0, 1.0, 1.0], [0, 2, 2]);
        assert_eq!(mesh.element_count(), 0);
        assert!(mesh.node_sets.is_empty());
    }

    proptest! {
        #[test]
        fn node_sets_hold_exactly_the_face_nodes(nx in 1usize..5, ny in 1usize..5, nz in 1usize..5) {
            let lengths = [1.5, 0.7, 2.0];
            let mesh = box_t4(lengths, [nx, ny, nz]);
            for axis in 0..3 {
                for (side, end) in [(0.0, '0'), (lengths[axis], '1')] {
                    let name = format!("{}{}", ['x', 'y', 'z'][axis], end);
                    let expected: Vec<u32> = (0..mesh.node_count() as u32)
                        .filter(|n| (mesh.nodes[*n as usize][axis] - side).abs() < 1e-12)
                        .collect();
                    prop_assert_eq!(&mesh.node_sets[&name], &expected);
                }
            }
        }
    }
}
