//! Turns what a reader found (the file's own node and element ids, sets by
//! name) into a [`Mesh`]: one element kind, compact 0-based indices, nodes
//! that no volume element uses dropped (they would carry no mass), surface
//! triangles turned to face out of the volume.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use carus_fem::{ElementKind, Mesh};

use crate::error::ReadError;
use crate::units::LengthUnit;

/// A mesh read from a file, with the file's own ids kept for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFile {
    /// The mesh, in the file's length unit until [`MeshFile::to_metres`].
    pub mesh: Mesh,
    /// The file it came from.
    pub source: PathBuf,
    /// The file's id of each node of `mesh` (Gmsh node tag, Abaqus node
    /// number, VTK point index).
    pub node_ids: Vec<u64>,
    /// The file's id of each element of `mesh`.
    pub element_ids: Vec<u64>,
    /// What the reader skipped on purpose (lines, points, shells), for the
    /// caller to log.
    pub notes: Vec<String>,
}

impl MeshFile {
    /// Scales the coordinates from `unit` to metres (SI inside the program,
    /// CONVENTIONS.md).
    pub fn to_metres(mut self, unit: LengthUnit) -> Self {
        let scale = unit.metres_per_unit();
        if scale != 1.0 {
            for node in &mut self.mesh.nodes {
                for x in node.iter_mut() {
                    *x *= scale;
                }
            }
        }
        self
    }

    /// The file's id of element `index`, for messages that point into the file.
    pub fn element_id(&self, index: usize) -> Option<u64> {
        self.element_ids.get(index).copied()
    }

    /// The file's id of node `index` of the mesh.
    pub fn node_id(&self, index: usize) -> Option<u64> {
        self.node_ids.get(index).copied()
    }
}

/// The largest coordinate a mesh file may hold, in its own unit: a slip
/// of exponent (1e300) would otherwise read as a degenerate element.
const MAX_COORDINATE: f64 = 1e6;

/// Collects nodes, volume elements and sets under the file's ids.
pub(crate) struct MeshBuilder {
    path: PathBuf,
    node_ids: Vec<u64>,
    coords: Vec<[f64; 3]>,
    node_position: HashMap<u64, usize>,
    hexahedra: Vec<(u64, [u64; 8])>,
    tetrahedra: Vec<(u64, [u64; 4])>,
    /// The line each hexahedron and tetrahedron began on, in the order
    /// added, for messages about an element (None where the format has
    /// none to give).
    hexahedron_lines: Vec<Option<usize>>,
    tetrahedron_lines: Vec<Option<usize>>,
    /// Elements the reader skipped (shells, lines) that sets may still name.
    ignored_elements: HashSet<u64>,
    element_sets: BTreeMap<String, Vec<u64>>,
    node_sets: BTreeMap<String, Vec<u64>>,
    surfaces: BTreeMap<String, Vec<[u64; 3]>>,
    notes: Vec<String>,
    /// What to do about a file with no volume elements, in its format's terms.
    surface_only_fix: &'static str,
}

/// The fix for a file that holds only a surface, where the reader gives none.
const SURFACE_ONLY_FIX: &str =
    "export the 3-D mesh, not only its surface (Gmsh: add a physical volume, or Mesh.SaveAll = 1)";

impl MeshBuilder {
    pub(crate) fn new(path: &Path) -> Self {
        MeshBuilder {
            path: path.to_path_buf(),
            node_ids: Vec::new(),
            coords: Vec::new(),
            node_position: HashMap::new(),
            hexahedra: Vec::new(),
            tetrahedra: Vec::new(),
            hexahedron_lines: Vec::new(),
            tetrahedron_lines: Vec::new(),
            ignored_elements: HashSet::new(),
            element_sets: BTreeMap::new(),
            node_sets: BTreeMap::new(),
            surfaces: BTreeMap::new(),
            notes: Vec::new(),
            surface_only_fix: SURFACE_ONLY_FIX,
        }
    }

    /// The builder with its format's fix for a file without volume elements.
    pub(crate) fn with_surface_only_fix(self, fix: &'static str) -> Self {
        MeshBuilder { surface_only_fix: fix, ..self }
    }

    fn content_error(&self, problem: String, fix: &str) -> ReadError {
        ReadError::Content {
            path: self.path.clone(),
            problem,
            fix: fix.to_string(),
        }
    }

    /// Adds node `id`; the error says why it cannot (taken id, NaN, a
    /// coordinate beyond [`MAX_COORDINATE`]).
    pub(crate) fn add_node(&mut self, id: u64, xyz: [f64; 3]) -> Result<(), String> {
        if !xyz.iter().all(|x| x.is_finite()) {
            return Err(format!("node {id} has a non-finite coordinate {xyz:?}"));
        }
        if let Some(far) = xyz.iter().find(|x| x.abs() > MAX_COORDINATE) {
            return Err(format!(
                "node {id} has the coordinate {far:e}, beyond {MAX_COORDINATE:e} in the file's unit \
                 (a kilometre in mm, a thousand km in m): no tissue model is that large"
            ));
        }
        if self.node_position.insert(id, self.coords.len()).is_some() {
            return Err(format!("node {id} is defined twice"));
        }
        self.node_ids.push(id);
        self.coords.push(xyz);
        Ok(())
    }

    /// Adds hexahedron `id`, written from `line` of the file where known.
    pub(crate) fn add_hexahedron(&mut self, id: u64, nodes: [u64; 8], line: Option<usize>) {
        self.hexahedra.push((id, nodes));
        self.hexahedron_lines.push(line);
    }

    /// Adds tetrahedron `id`, written from `line` of the file where known.
    pub(crate) fn add_tetrahedron(&mut self, id: u64, nodes: [u64; 4], line: Option<usize>) {
        self.tetrahedra.push((id, nodes));
        self.tetrahedron_lines.push(line);
    }

    /// An error about one element: at its line where the file gave one
    /// (a reader that counts lines names every other fault by its line).
    fn element_error(&self, line: Option<usize>, problem: String, fix: &str) -> ReadError {
        match line {
            Some(line) => ReadError::Syntax { path: self.path.clone(), line, problem, fix: fix.to_string() },
            None => self.content_error(problem, fix),
        }
    }

    /// Notes that element `id` exists but has no role in a volume mesh.
    pub(crate) fn ignore_element(&mut self, id: u64) {
        self.ignored_elements.insert(id);
    }

    pub(crate) fn note(&mut self, note: String) {
        if !self.notes.contains(&note) {
            self.notes.push(note);
        }
    }

    pub(crate) fn add_to_element_set(&mut self, name: &str, id: u64) {
        self.element_sets
            .entry(name.to_string())
            .or_default()
            .push(id);
    }

    pub(crate) fn add_to_node_set(&mut self, name: &str, id: u64) {
        self.node_sets.entry(name.to_string()).or_default().push(id);
    }

    pub(crate) fn element_sets(&self) -> impl Iterator<Item = (&String, &Vec<u64>)> {
        self.element_sets.iter()
    }

    pub(crate) fn element_set(&self, name: &str) -> Option<&[u64]> {
        self.element_sets.get(name).map(Vec::as_slice)
    }

    pub(crate) fn node_set(&self, name: &str) -> Option<&[u64]> {
        self.node_sets.get(name).map(Vec::as_slice)
    }

    /// Whether element `id` was skipped on purpose (a shell, a line).
    pub(crate) fn is_ignored(&self, id: u64) -> bool {
        self.ignored_elements.contains(&id)
    }

    /// Adds a triangle or a quadrilateral (split into two triangles along
    /// its 0-2 diagonal) to surface `name`.
    pub(crate) fn add_surface_polygon(&mut self, name: &str, nodes: &[u64]) {
        let surface = self.surfaces.entry(name.to_string()).or_default();
        match *nodes {
            [a, b, c] => surface.push([a, b, c]),
            [a, b, c, d] => {
                surface.push([a, b, c]);
                surface.push([a, c, d]);
            }
            _ => {}
        }
    }

    /// Checks and compacts everything into a [`MeshFile`].
    pub(crate) fn finish(self) -> Result<MeshFile, ReadError> {
        let (kind, volume_ids, file_connectivity): (ElementKind, Vec<u64>, Vec<u64>) =
            match (self.hexahedra.len(), self.tetrahedra.len()) {
                (0, 0) => {
                    let skipped = match self.notes.is_empty() {
                        true => String::new(),
                        false => format!(" ({})", self.notes.join("; ")),
                    };
                    return Err(self.content_error(
                        format!("the file holds no volume elements (8-node hexahedra or 4-node tetrahedra){skipped}"),
                        self.surface_only_fix,
                    ));
                }
                (h, t) if h > 0 && t > 0 => {
                    return Err(ReadError::MixedElementKinds {
                        path: self.path,
                        hexahedra: h,
                        tetrahedra: t,
                    })
                }
                (_, 0) => (
                    ElementKind::H8,
                    self.hexahedra.iter().map(|(id, _)| *id).collect(),
                    self.hexahedra.iter().flat_map(|(_, n)| n.iter().copied()).collect(),
                ),
                _ => (
                    ElementKind::T4,
                    self.tetrahedra.iter().map(|(id, _)| *id).collect(),
                    self.tetrahedra.iter().flat_map(|(_, n)| n.iter().copied()).collect(),
                ),
            };
        let element_lines = match kind {
            ElementKind::H8 => &self.hexahedron_lines,
            _ => &self.tetrahedron_lines,
        };
        let line_of = |element: usize| element_lines.get(element).copied().flatten();
        let per_element = kind.nodes_per_element();

        // Compact node numbering: nodes in file order, only those used.
        let mut new_index = vec![u32::MAX; self.coords.len()];
        for (slot, &node_id) in file_connectivity.iter().enumerate() {
            let Some(&position) = self.node_position.get(&node_id) else {
                return Err(self.element_error(
                    line_of(slot / per_element),
                    format!(
                        "element {} names node {node_id}, which the file does not define",
                        volume_ids[slot / per_element]
                    ),
                    "export the mesh again with all its nodes",
                ));
            };
            new_index[position] = 0;
        }
        let mut node_ids = Vec::new();
        let mut nodes = Vec::new();
        for (position, index) in new_index.iter_mut().enumerate() {
            if *index == 0 {
                *index = nodes.len() as u32;
                nodes.push(self.coords[position]);
                node_ids.push(self.node_ids[position]);
            }
        }
        let compact = |node_id: u64| -> Option<u32> {
            let position = *self.node_position.get(&node_id)?;
            Some(new_index[position])
        };
        let connectivity: Vec<u32> = file_connectivity
            .iter()
            .map(|&id| compact(id).unwrap_or(u32::MAX))
            .collect();
        for (e, element) in connectivity.chunks_exact(per_element).enumerate() {
            for (i, a) in element.iter().enumerate() {
                if element[i + 1..].contains(a) {
                    return Err(self.element_error(
                        line_of(e),
                        format!(
                            "element {} uses node {} twice",
                            volume_ids[e], node_ids[*a as usize]
                        ),
                        "the element is degenerate: remesh or remove it",
                    ));
                }
            }
        }

        let mut element_index = HashMap::with_capacity(volume_ids.len());
        for (index, &id) in volume_ids.iter().enumerate() {
            if element_index.insert(id, index as u32).is_some() {
                return Err(self.element_error(
                    line_of(index),
                    format!("element id {id} is used by two volume elements"),
                    "give every element its own id",
                ));
            }
        }

        let mut element_sets = BTreeMap::new();
        for (name, ids) in &self.element_sets {
            let mut members = Vec::with_capacity(ids.len());
            for id in ids {
                match element_index.get(id) {
                    Some(&e) => members.push(e),
                    None if self.ignored_elements.contains(id) => {}
                    None => {
                        return Err(self.content_error(
                            format!("element set {name:?} names element {id}, which the file does not define"),
                            "define the element or remove it from the set",
                        ))
                    }
                }
            }
            // A set of only skipped elements (faces exported as shells) is no element set.
            if members.is_empty() && !ids.is_empty() {
                continue;
            }
            members.sort_unstable();
            members.dedup();
            element_sets.insert(name.clone(), members);
        }

        let mut node_sets = BTreeMap::new();
        for (name, ids) in &self.node_sets {
            let mut members = Vec::with_capacity(ids.len());
            for &id in ids {
                if !self.node_position.contains_key(&id) {
                    return Err(self.content_error(
                        format!(
                            "node set {name:?} names node {id}, which the file does not define"
                        ),
                        "define the node or remove it from the set",
                    ));
                }
                // Nodes of no volume element carry no mass: they leave the set.
                if let Some(n) = compact(id).filter(|&n| n != u32::MAX) {
                    members.push(n);
                }
            }
            members.sort_unstable();
            members.dedup();
            node_sets.insert(name.clone(), members);
        }

        let node_elements = NodeElements::new(nodes.len(), &connectivity, per_element);
        let mut surfaces = BTreeMap::new();
        for (name, triangles) in &self.surfaces {
            let mut compacted = Vec::with_capacity(triangles.len());
            for triangle in triangles {
                if let Some(&undefined) = triangle.iter().find(|&&id| compact(id).is_none()) {
                    return Err(self.content_error(
                        format!("surface {name:?} has a face that names node {undefined}, which the file does not define"),
                        "export the mesh again with all its nodes",
                    ));
                }
                let mapped = triangle.map(|id| compact(id).unwrap_or(u32::MAX));
                let Some(element) = (!mapped.contains(&u32::MAX))
                    .then(|| node_elements.element_with(&connectivity, per_element, &mapped))
                    .flatten()
                else {
                    return Err(self.content_error(
                        format!(
                            "surface {name:?} has the face with nodes {triangle:?}, which lies on no volume element"
                        ),
                        "put only faces of the meshed volume into surface groups",
                    ));
                };
                compacted.push(outward(
                    &nodes,
                    &connectivity[element * per_element..][..per_element],
                    mapped,
                ));
            }
            surfaces.insert(name.clone(), compacted);
        }
        for (name, triangles) in &surfaces {
            if !node_sets.contains_key(name) {
                let mut members: Vec<u32> = triangles.iter().flatten().copied().collect();
                members.sort_unstable();
                members.dedup();
                node_sets.insert(name.clone(), members);
            }
        }

        let mesh = Mesh {
            kind,
            nodes,
            connectivity,
            node_sets,
            element_sets,
            surfaces,
        };
        Ok(MeshFile {
            mesh,
            source: self.path,
            node_ids,
            element_ids: volume_ids,
            notes: self.notes,
        })
    }
}

/// Elements around each node (compressed rows).
struct NodeElements {
    offsets: Vec<usize>,
    elements: Vec<u32>,
}

impl NodeElements {
    fn new(node_count: usize, connectivity: &[u32], per_element: usize) -> Self {
        let mut offsets = vec![0usize; node_count + 1];
        for &n in connectivity {
            offsets[n as usize + 1] += 1;
        }
        for i in 0..node_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut elements = vec![0u32; connectivity.len()];
        for (slot, &n) in connectivity.iter().enumerate() {
            elements[fill[n as usize]] = (slot / per_element) as u32;
            fill[n as usize] += 1;
        }
        NodeElements { offsets, elements }
    }

    /// An element holding all three nodes.
    fn element_with(
        &self,
        connectivity: &[u32],
        per_element: usize,
        triangle: &[u32; 3],
    ) -> Option<usize> {
        let a = triangle[0] as usize;
        self.elements[self.offsets[a]..self.offsets[a + 1]]
            .iter()
            .map(|&e| e as usize)
            .find(|&e| {
                let element = &connectivity[e * per_element..][..per_element];
                element.contains(&triangle[1]) && element.contains(&triangle[2])
            })
    }
}

/// `triangle` ordered so its right-hand normal points away from the
/// element's centroid (out of the volume).
fn outward(nodes: &[[f64; 3]], element: &[u32], triangle: [u32; 3]) -> [u32; 3] {
    let p = triangle.map(|n| nodes[n as usize]);
    let mut centroid = [0.0; 3];
    for &n in element {
        for k in 0..3 {
            centroid[k] += nodes[n as usize][k] / element.len() as f64;
        }
    }
    let u = sub(p[1], p[0]);
    let v = sub(p[2], p[0]);
    let normal = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let to_centroid = sub(centroid, p[0]);
    let side: f64 = (0..3).map(|k| normal[k] * to_centroid[k]).sum();
    if side > 0.0 {
        [triangle[0], triangle[2], triangle[1]]
    } else {
        triangle
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet(builder: &mut MeshBuilder) {
        for (id, xyz) in [
            (10, [0.0, 0.0, 0.0]),
            (11, [1.0, 0.0, 0.0]),
            (12, [0.0, 1.0, 0.0]),
            (13, [0.0, 0.0, 1.0]),
        ] {
            builder.add_node(id, xyz).unwrap();
        }
    }

    #[test]
    fn unused_nodes_are_dropped_and_ids_kept() {
        let mut b = MeshBuilder::new(Path::new("m.inp"));
        b.add_node(99, [5.0, 5.0, 5.0]).unwrap();
        unit_tet(&mut b);
        b.add_tetrahedron(7, [10, 11, 12, 13], None);
        b.add_to_node_set("base", 99);
        b.add_to_node_set("base", 10);
        let file = b.finish().unwrap();
        assert_eq!(file.mesh.kind, ElementKind::T4);
        assert_eq!(file.mesh.nodes.len(), 4);
        assert_eq!(file.node_ids, vec![10, 11, 12, 13]);
        assert_eq!(file.element_ids, vec![7]);
        assert_eq!(file.mesh.node_sets["base"], vec![0]);
    }

    #[test]
    fn surface_triangles_are_turned_outward_and_give_node_sets() {
        let mut b = MeshBuilder::new(Path::new("m.inp"));
        unit_tet(&mut b);
        b.add_tetrahedron(1, [10, 11, 12, 13], None);
        // Bottom face z = 0 given with its normal pointing into the tet (+z).
        b.add_surface_polygon("bottom", &[10, 11, 12]);
        let file = b.finish().unwrap();
        assert_eq!(file.mesh.surfaces["bottom"], vec![[0, 2, 1]]);
        assert_eq!(file.mesh.node_sets["bottom"], vec![0, 1, 2]);
    }

    #[test]
    fn mixed_kinds_and_unknown_nodes_are_refused() {
        let mut b = MeshBuilder::new(Path::new("m.msh"));
        unit_tet(&mut b);
        b.add_tetrahedron(1, [10, 11, 12, 13], None);
        b.add_hexahedron(2, [10, 11, 12, 13, 10, 11, 12, 13], None);
        let err = b.finish().unwrap_err().to_string();
        assert!(err.contains("1 hexahedra and 1 tetrahedra"), "{err}");

        let mut b = MeshBuilder::new(Path::new("m.msh"));
        unit_tet(&mut b);
        b.add_tetrahedron(4, [10, 11, 12, 14], None);
        let err = b.finish().unwrap_err().to_string();
        assert!(err.contains("element 4 names node 14"), "{err}");

        // A surface face that names a node the file lacks is named so, not
        // as a face of no volume element.
        let mut b = MeshBuilder::new(Path::new("m.msh"));
        unit_tet(&mut b);
        b.add_tetrahedron(1, [10, 11, 12, 13], None);
        b.add_surface_polygon("x0", &[10, 11, 9999]);
        let err = b.finish().unwrap_err().to_string();
        assert!(err.contains("surface \"x0\" has a face that names node 9999, which the file does not define"), "{err}");
    }

    #[test]
    fn a_node_out_of_any_tissue_s_reach_is_refused() {
        let mut b = MeshBuilder::new(Path::new("m.msh"));
        assert!(b.add_node(1, [0.0, -1e6, 0.0]).is_ok());
        let err = b.add_node(2, [0.01, 1e300, 0.0]).unwrap_err();
        assert!(err.contains("node 2 has the coordinate 1e300, beyond 1e6"), "{err}");
        assert!(b.add_node(3, [f64::NAN, 0.0, 0.0]).unwrap_err().contains("non-finite"));
    }

    #[test]
    fn sets_naming_unknown_elements_are_refused_but_skipped_ones_pass() {
        let mut b = MeshBuilder::new(Path::new("m.inp"));
        unit_tet(&mut b);
        b.add_tetrahedron(1, [10, 11, 12, 13], None);
        b.ignore_element(2);
        b.add_to_element_set("all", 1);
        b.add_to_element_set("all", 2);
        assert_eq!(b.finish().unwrap().mesh.element_sets["all"], vec![0]);

        let mut b = MeshBuilder::new(Path::new("m.inp"));
        unit_tet(&mut b);
        b.add_tetrahedron(1, [10, 11, 12, 13], None);
        b.add_to_element_set("all", 3);
        let err = b.finish().unwrap_err().to_string();
        assert!(err.contains("element set \"all\" names element 3"), "{err}");
    }
}
