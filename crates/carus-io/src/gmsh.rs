//! Gmsh `.msh` ASCII reader, format versions 2.2, 4.0 and 4.1.
//!
//! Hand-written rather than mshio 0.4: mshio reads only 4.1, skips
//! `$PhysicalNames` (the names researchers give their groups), reports no
//! line numbers and still has `unimplemented!`/`expect` paths that panic on
//! malformed input. Versions 2 and 4 share one tokenizer here.
//!
//! Physical groups become sets: 3-D groups element sets, 2-D groups surfaces
//! (triangles, quadrangles split in two) and node sets, 0-D groups node sets.
//! A group without a `$PhysicalNames` entry is named by its number.
//! Points and lines are skipped. Gmsh numbers hexahedron and tetrahedron
//! nodes as VTK does, which is the order of [`carus_fem::Mesh`].

use std::collections::HashMap;
use std::path::Path;

use crate::builder::{MeshBuilder, MeshFile};
use crate::error::ReadError;
use crate::text::{finite_f64, Tokens};

/// Reads a Gmsh `.msh` file (ASCII 2.2, 4.0 or 4.1).
pub fn read_msh(path: &Path) -> Result<MeshFile, ReadError> {
    let bytes = crate::input::read_bytes(path).map_err(|cause| ReadError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    parse_msh(path, &bytes)
}

/// Parses the bytes of a `.msh` file; `path` only names it in errors.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<MeshFile, ReadError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = crate::input::line_at(bytes, e.valid_up_to());
        ReadError::Syntax {
            path: path.to_path_buf(),
            line,
            problem: "the file is not text (binary .msh, or corrupted)".into(),
            fix: BINARY_FIX.into(),
        }
    })?;
    Parser::new(path, text).run()
}

const BINARY_FIX: &str = "save the mesh as ASCII (Gmsh: File > Export, uncheck binary; or gmsh -save -format msh41 -bin 0)";
const ORDER_FIX: &str =
    "mesh with first-order hexahedra or tetrahedra only (Gmsh: Mesh.ElementOrder = 1; no prisms or pyramids)";

#[derive(Clone, Copy, PartialEq)]
enum Version {
    V2,
    V40,
    V41,
}

/// Gmsh element type numbers: node count, dimension, name.
fn element_type(code: u32) -> Option<(usize, u8, &'static str)> {
    Some(match code {
        1 => (2, 1, "2-node line"),
        2 => (3, 2, "3-node triangle"),
        3 => (4, 2, "4-node quadrangle"),
        4 => (4, 3, "4-node tetrahedron"),
        5 => (8, 3, "8-node hexahedron"),
        6 => (6, 3, "6-node prism"),
        7 => (5, 3, "5-node pyramid"),
        8 => (3, 1, "3-node line"),
        9 => (6, 2, "6-node triangle"),
        10 => (9, 2, "9-node quadrangle"),
        11 => (10, 3, "10-node tetrahedron"),
        12 => (27, 3, "27-node hexahedron"),
        13 => (18, 3, "18-node prism"),
        14 => (14, 3, "14-node pyramid"),
        15 => (1, 0, "point"),
        16 => (8, 2, "8-node quadrangle"),
        17 => (20, 3, "20-node hexahedron"),
        18 => (15, 3, "15-node prism"),
        19 => (13, 3, "13-node pyramid"),
        26 => (4, 1, "4-node line"),
        27 => (5, 1, "5-node line"),
        28 => (6, 1, "6-node line"),
        _ => return None,
    })
}

struct Parser<'a> {
    tokens: Tokens<'a>,
    builder: MeshBuilder,
    version: Option<Version>,
    /// (dimension, physical tag) -> name.
    physical_names: HashMap<(u8, i64), String>,
    /// (dimension, entity tag) -> physical tags (version 4).
    entity_physicals: HashMap<(u8, i64), Vec<i64>>,
    /// Elements per physical group, resolved to names at the end because
    /// `$PhysicalNames` may follow `$Elements`: (dim, tag, element id, nodes).
    grouped: Vec<(u8, i64, u64, Vec<u64>)>,
}

impl<'a> Parser<'a> {
    fn new(path: &'a Path, text: &'a str) -> Self {
        Parser {
            tokens: Tokens::new(path, text),
            builder: MeshBuilder::new(path),
            version: None,
            physical_names: HashMap::new(),
            entity_physicals: HashMap::new(),
            grouped: Vec::new(),
        }
    }

    fn run(mut self) -> Result<MeshFile, ReadError> {
        while let Some(token) = self.tokens.next_token() {
            if self.version.is_none() && token != "$MeshFormat" {
                return Err(self.tokens.error(
                    format!("expected $MeshFormat at the start, found {token:?}"),
                    "this is not a Gmsh .msh file: check the file, or export from Gmsh as .msh",
                ));
            }
            match token {
                "$MeshFormat" => self.mesh_format()?,
                "$PhysicalNames" => self.physical_names()?,
                "$Entities" => self.entities()?,
                "$Nodes" => self.nodes()?,
                "$Elements" => self.elements()?,
                section if section.starts_with('$') && !section.starts_with("$End") => {
                    self.skip_section(&section[1..])?
                }
                other => {
                    return Err(self.tokens.error(
                        format!("expected a section such as $Nodes, found {other:?}"),
                        "a count in the previous section does not match its entries: export the file again",
                    ))
                }
            }
        }
        if self.version.is_none() {
            return Err(self
                .tokens
                .error("the file is empty", "export the mesh again"));
        }
        let Parser {
            mut builder,
            physical_names,
            grouped,
            ..
        } = self;
        note_shared_names(&mut builder, &physical_names);
        for (dim, tag, id, nodes) in grouped {
            let name = physical_names
                .get(&(dim, tag))
                .cloned()
                .unwrap_or_else(|| tag.to_string());
            match dim {
                3 => builder.add_to_element_set(&name, id),
                2 => builder.add_surface_polygon(&name, &nodes),
                _ => nodes
                    .iter()
                    .for_each(|&n| builder.add_to_node_set(&name, n)),
            }
        }
        builder.finish()
    }

    fn mesh_format(&mut self) -> Result<(), ReadError> {
        let version = self.tokens.expect("the format version")?;
        self.version = Some(match version {
            "2" | "2.0" | "2.1" | "2.2" => Version::V2,
            "4" | "4.0" => Version::V40,
            "4.1" => Version::V41,
            other => {
                return Err(self.tokens.error(
                    format!("Gmsh format version {other} is not supported (2.2, 4.0 and 4.1 are)"),
                    "save as version 4.1 or 2.2 (gmsh -save -format msh41 -bin 0)",
                ))
            }
        });
        let file_type: u32 = self.tokens.parse("the file type (0 = ASCII)")?;
        if file_type != 0 {
            return Err(self.tokens.error("the file is binary .msh", BINARY_FIX));
        }
        self.tokens.parse::<u32>("the data size")?;
        self.tokens.expect_marker("$EndMeshFormat")
    }

    fn physical_names(&mut self) -> Result<(), ReadError> {
        let count: usize = self.tokens.parse("the number of physical names")?;
        for _ in 0..count {
            let dim: u8 = self.tokens.parse("a physical group dimension")?;
            let tag: i64 = self.tokens.parse("a physical group tag")?;
            let name = self.tokens.rest_of_line().trim_matches('"').to_string();
            if name.is_empty() {
                return Err(self.tokens.error(
                    "a physical group has no name",
                    "name it in Gmsh, or remove the entry",
                ));
            }
            self.physical_names.insert((dim, tag), name);
        }
        self.tokens.expect_marker("$EndPhysicalNames")
    }

    fn entities(&mut self) -> Result<(), ReadError> {
        let counts: [usize; 4] = [
            self.tokens.parse("the number of points")?,
            self.tokens.parse("the number of curves")?,
            self.tokens.parse("the number of surfaces")?,
            self.tokens.parse("the number of volumes")?,
        ];
        let v41 = self.version == Some(Version::V41);
        for (dim, &count) in counts.iter().enumerate() {
            for _ in 0..count {
                let tag: i64 = self.tokens.parse("an entity tag")?;
                // 4.1 points carry a position, everything else a bounding box.
                let coordinates = if dim == 0 && v41 { 3 } else { 6 };
                for _ in 0..coordinates {
                    self.tokens.parse::<f64>("an entity coordinate")?;
                }
                let physical_count: usize = self.tokens.parse("the number of physical tags")?;
                let mut physicals = Vec::with_capacity(physical_count.min(64));
                for _ in 0..physical_count {
                    physicals.push(self.tokens.parse::<i64>("a physical tag")?);
                }
                if dim > 0 {
                    let bounding: usize = self.tokens.parse("the number of bounding entities")?;
                    for _ in 0..bounding {
                        self.tokens.parse::<i64>("a bounding entity tag")?;
                    }
                }
                if !physicals.is_empty() {
                    self.entity_physicals.insert((dim as u8, tag), physicals);
                }
            }
        }
        self.tokens.expect_marker("$EndEntities")
    }

    fn node(&mut self, id: u64) -> Result<(), ReadError> {
        let mut xyz = [0.0; 3];
        let mut first_line = None;
        for (k, x) in xyz.iter_mut().enumerate() {
            let token = self.tokens.expect("a node coordinate")?;
            // Gmsh writes a node's x y z on one line: one short of them
            // would shift every token after it, and the error would land
            // far away, on the wrong node.
            let line = *first_line.get_or_insert(self.tokens.line());
            if self.tokens.line() != line {
                return Err(self.tokens.error_at(
                    line,
                    format!("node {id} has {k} coordinates on its line; a node needs 3 (x y z)"),
                    "fix or remove the node in the mesh generator and export again",
                ));
            }
            *x = finite_f64(token).ok_or_else(|| {
                self.tokens.error(
                    format!("node {id} has the coordinate {token:?}, which is not a finite number"),
                    "fix or remove the node in the mesh generator and export again",
                )
            })?;
        }
        self.builder.add_node(id, xyz).map_err(|problem| {
            self.tokens.error(
                problem,
                "give every node its own tag and finite coordinates",
            )
        })
    }

    fn nodes(&mut self) -> Result<(), ReadError> {
        match self.version {
            Some(Version::V2) => {
                let count: usize = self.tokens.parse("the number of nodes")?;
                for _ in 0..count {
                    let id: u64 = self.tokens.parse("a node tag")?;
                    self.node(id)?;
                }
            }
            Some(Version::V40) => {
                let blocks: usize = self.tokens.parse("the number of node blocks")?;
                let header_line = self.tokens.line();
                let declared: usize = self.tokens.parse("the number of nodes")?;
                let mut held = 0usize;
                for _ in 0..blocks {
                    self.tokens.parse::<i64>("an entity tag")?;
                    self.tokens.parse::<u8>("an entity dimension")?;
                    let parametric: u8 = self.tokens.parse("the parametric flag")?;
                    let count: usize = self.tokens.parse("the number of nodes in the block")?;
                    self.refuse_parametric(parametric)?;
                    for _ in 0..count {
                        let id: u64 = self.tokens.parse("a node tag")?;
                        self.node(id)?;
                    }
                    held = held.saturating_add(count);
                }
                self.check_total("nodes", declared, held, header_line)?;
            }
            _ => {
                let blocks: usize = self.tokens.parse("the number of node blocks")?;
                let header_line = self.tokens.line();
                let declared: usize = self.tokens.parse("the number of nodes")?;
                for _ in 0..2 {
                    self.tokens.parse::<u64>("a node tag bound")?;
                }
                let mut held = 0usize;
                for _ in 0..blocks {
                    self.tokens.parse::<u8>("an entity dimension")?;
                    self.tokens.parse::<i64>("an entity tag")?;
                    let parametric: u8 = self.tokens.parse("the parametric flag")?;
                    let count: usize = self.tokens.parse("the number of nodes in the block")?;
                    self.refuse_parametric(parametric)?;
                    let mut ids = Vec::with_capacity(count.min(1 << 20));
                    for _ in 0..count {
                        ids.push(self.tokens.parse::<u64>("a node tag")?);
                    }
                    for id in ids {
                        self.node(id)?;
                    }
                    held = held.saturating_add(count);
                }
                self.check_total("nodes", declared, held, header_line)?;
            }
        }
        self.tokens.expect_marker("$EndNodes")
    }

    fn refuse_parametric(&self, parametric: u8) -> Result<(), ReadError> {
        if parametric == 0 {
            Ok(())
        } else {
            Err(self.tokens.error(
                "node block with parametric coordinates",
                "save without parametric coordinates (Gmsh: Mesh.SaveParametric = 0)",
            ))
        }
    }

    /// Records one element of Gmsh type `code`, written on `line`, in the
    /// given physical groups.
    fn element(
        &mut self,
        id: u64,
        code: u32,
        nodes: Vec<u64>,
        physicals: &[i64],
        line: usize,
    ) -> Result<(), ReadError> {
        let (_, dim, name) = element_type(code).unwrap_or((0, 0, ""));
        match code {
            5 => {
                let mut n = [0; 8];
                n.copy_from_slice(&nodes);
                self.builder.add_hexahedron(id, n, Some(line));
            }
            4 => {
                let mut n = [0; 4];
                n.copy_from_slice(&nodes);
                self.builder.add_tetrahedron(id, n, Some(line));
            }
            2 | 3 | 15 => {}
            1 | 8 | 26 | 27 | 28 => {
                self.builder.note(format!(
                    "skipped {name} elements (only volumes, surfaces and points are read)"
                ));
                return Ok(());
            }
            _ => {
                return Err(self.tokens.error(
                    format!("element {id} is a {name}, which Carus does not solve"),
                    ORDER_FIX,
                ))
            }
        }
        for &tag in physicals {
            self.grouped.push((dim, tag, id, nodes.clone()));
        }
        Ok(())
    }

    /// The node tags of element `id`, whose record began on `line`: Gmsh
    /// writes one element a line, so a record that runs onto the next
    /// line, or past its count, has the wrong number of nodes.
    fn element_nodes(&mut self, id: u64, code: u32, line: usize) -> Result<Vec<u64>, ReadError> {
        let Some((count, _, name)) = element_type(code) else {
            return Err(self
                .tokens
                .error(format!("unknown Gmsh element type {code}"), ORDER_FIX));
        };
        let wrong_count = |tokens: &crate::text::Tokens, listed: &str| {
            tokens.error_at(
                line,
                format!("element {id} (type {code}: {name}) lists {listed} nodes, needs {count}"),
                "the element's line is damaged: export the mesh again",
            )
        };
        let mut nodes = Vec::with_capacity(count);
        for k in 0..count {
            let tag = self.tokens.parse::<u64>("an element node tag");
            if self.tokens.line() != line {
                return Err(wrong_count(&self.tokens, &k.to_string()));
            }
            nodes.push(tag?);
        }
        if !self.tokens.rest_of_line().is_empty() {
            return Err(wrong_count(&self.tokens, &format!("more than {count}")));
        }
        Ok(nodes)
    }

    /// The tag of entry `read` (from 0) of a section or block whose header
    /// on `header_line` declares `declared` `noun`s: the section's end
    /// marker found in its place is a count larger than the entries.
    fn entry_tag(&mut self, noun: &str, end: &str, declared: usize, read: usize, header_line: usize) -> Result<u64, ReadError> {
        let what = format!("an {noun} tag");
        let token = self.tokens.expect(&what)?;
        if token == end {
            return Err(self.tokens.error_at(
                header_line,
                format!("the count here declares {declared} {noun}s, but {end} comes after {read} (line {})", self.tokens.line()),
                format!("set the count to {read}, or export the mesh again"),
            ));
        }
        token.parse().map_err(|_| {
            self.tokens.error(
                format!("expected {what}, found {token:?}"),
                "the file is corrupted or not in the format its header states: export it again",
            )
        })
    }

    /// The end marker of a section whose header on `header_line` declared
    /// `declared` (`3 elements`), all read: anything else there is more.
    fn section_end(&mut self, end: &str, declared: &str, header_line: usize) -> Result<(), ReadError> {
        let token = self.tokens.expect(end)?;
        if token == end {
            return Ok(());
        }
        Err(self.tokens.error_at(
            header_line,
            format!(
                "the count here declares {declared}, but more follow them (from line {}, {token:?}) before {end}",
                self.tokens.line()
            ),
            "set the count to what the section holds, or export the mesh again",
        ))
    }

    /// Refuses a version 4 section whose header on `header_line` declares
    /// `declared` entries in all where its blocks hold `held`: Gmsh writes
    /// them equal, so one differs in an edited or damaged file.
    fn check_total(&self, what: &str, declared: usize, held: usize, header_line: usize) -> Result<(), ReadError> {
        if declared == held {
            return Ok(());
        }
        Err(self.tokens.error_at(
            header_line,
            format!("the header declares {declared} {what} in all, but its blocks hold {held}"),
            format!("set the count on this line to {held}, or export the mesh again"),
        ))
    }

    fn elements(&mut self) -> Result<(), ReadError> {
        let end = "$EndElements";
        match self.version {
            Some(Version::V2) => {
                let count: usize = self.tokens.parse("the number of elements")?;
                let header_line = self.tokens.line();
                for read in 0..count {
                    let id = self.entry_tag("element", end, count, read, header_line)?;
                    let line = self.tokens.line();
                    let code: u32 = self.tokens.parse("an element type")?;
                    let tag_count: usize = self.tokens.parse("the number of element tags")?;
                    let mut tags = Vec::with_capacity(tag_count.min(16));
                    for _ in 0..tag_count {
                        tags.push(self.tokens.parse::<i64>("an element tag value")?);
                    }
                    // The first tag is the physical group (0: none).
                    let physical: Vec<i64> = tags
                        .first()
                        .copied()
                        .filter(|&t| t != 0)
                        .into_iter()
                        .collect();
                    let nodes = self.element_nodes(id, code, line)?;
                    self.element(id, code, nodes, &physical, line)?;
                }
                self.section_end(end, &format!("{count} elements"), header_line)
            }
            version => {
                let blocks: usize = self.tokens.parse("the number of element blocks")?;
                let header_line = self.tokens.line();
                let declared: usize = self.tokens.parse("the number of elements")?;
                if version == Some(Version::V41) {
                    for _ in 0..2 {
                        self.tokens.parse::<u64>("an element tag bound")?;
                    }
                }
                let mut held = 0usize;
                for _ in 0..blocks {
                    let (dim, tag) = if version == Some(Version::V41) {
                        let dim: u8 = self.tokens.parse("an entity dimension")?;
                        (dim, self.tokens.parse::<i64>("an entity tag")?)
                    } else {
                        let tag: i64 = self.tokens.parse("an entity tag")?;
                        (self.tokens.parse::<u8>("an entity dimension")?, tag)
                    };
                    let code: u32 = self.tokens.parse("an element type")?;
                    let count: usize = self.tokens.parse("the number of elements in the block")?;
                    let block_line = self.tokens.line();
                    let physicals = self
                        .entity_physicals
                        .get(&(dim, tag))
                        .cloned()
                        .unwrap_or_default();
                    for read in 0..count {
                        let id = self.entry_tag("element", end, count, read, block_line)?;
                        let line = self.tokens.line();
                        let nodes = self.element_nodes(id, code, line)?;
                        self.element(id, code, nodes, &physicals, line)?;
                    }
                    held = held.saturating_add(count);
                }
                self.section_end(end, &format!("{blocks} element blocks"), header_line)?;
                self.check_total("elements", declared, held, header_line)
            }
        }
    }

    fn skip_section(&mut self, name: &str) -> Result<(), ReadError> {
        let end = format!("$End{name}");
        let start = self.tokens.line();
        while let Some(token) = self.tokens.next_token() {
            if token == end {
                return Ok(());
            }
        }
        Err(self.tokens.error(
            format!("section ${name} opened on line {start} is never closed by {end}"),
            "the file looks truncated: export it again",
        ))
    }
}

/// Gmsh itself gives one name one tag, so two tags of one dimension with
/// one name come from an edited file; their groups are joined under the
/// name, and the note says so in case two different regions were meant.
fn note_shared_names(builder: &mut MeshBuilder, physical_names: &HashMap<(u8, i64), String>) {
    let mut tags_by_name: HashMap<(u8, &str), Vec<i64>> = HashMap::new();
    for ((dim, tag), name) in physical_names {
        tags_by_name.entry((*dim, name)).or_default().push(*tag);
    }
    let mut shared: Vec<_> = tags_by_name.into_iter().filter(|(_, tags)| tags.len() > 1).collect();
    shared.sort();
    for ((dim, name), mut tags) in shared {
        tags.sort_unstable();
        let tags: Vec<String> = tags.iter().map(i64::to_string).collect();
        builder.note(format!(
            "the {dim}-D physical groups {} are all named \"{name}\": they are read as one group; rename them in Gmsh if they are different regions",
            tags.join(", ")
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use carus_fem::ElementKind;

    const CUBE_V22: &str = include_str!("../tests/data/two_hex_v22.msh");
    const CUBE_V41: &str = include_str!("../tests/data/two_hex_v41.msh");
    const CUBE_V40: &str = include_str!("../tests/data/two_hex_v40.msh");

    fn read(name: &str, text: &str) -> Result<MeshFile, ReadError> {
        parse_msh(Path::new(name), text.as_bytes())
    }

    #[test]
    fn the_three_versions_give_the_same_mesh() {
        let v22 = read("a.msh", CUBE_V22).unwrap();
        let v41 = read("a.msh", CUBE_V41).unwrap();
        let v40 = read("a.msh", CUBE_V40).unwrap();
        assert_eq!(v22.mesh, v41.mesh);
        assert_eq!(v22.mesh, v40.mesh);
        let mesh = &v22.mesh;
        assert_eq!(mesh.kind, ElementKind::H8);
        assert_eq!(mesh.element_count(), 2);
        assert_eq!(mesh.node_count(), 12);
        assert_eq!(mesh.element_sets["tissue"], vec![0, 1]);
        // The x = 0 quadrangle becomes two outward triangles and a node set.
        assert_eq!(mesh.surfaces["fixed"].len(), 2);
        assert_eq!(mesh.node_sets["fixed"].len(), 4);
        for triangle in &mesh.surfaces["fixed"] {
            let [a, b, c] = triangle.map(|n| mesh.nodes[n as usize]);
            let normal_x = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
            assert!(normal_x < 0.0, "x = 0 face must point towards -x");
        }
        // The unnamed physical point group 7 keeps its number as its name.
        assert_eq!(mesh.node_sets["7"].len(), 1);
    }

    #[test]
    fn groups_sharing_a_name_are_joined_with_a_note() {
        // Tag 1 (the two hexahedra) and a new tag 4 both named "tissue".
        let text = CUBE_V22
            .replacen("$PhysicalNames\n2\n", "$PhysicalNames\n3\n3 4 \"tissue\"\n", 1)
            .replacen("2 5 2 1 1 2 3", "2 5 2 4 1 2 3", 1);
        let file = read("shared.msh", &text).unwrap();
        assert_eq!(file.mesh.element_sets["tissue"], vec![0, 1]);
        let note = file.notes.iter().find(|n| n.contains("physical groups")).expect("a note");
        assert!(note.contains("3-D physical groups 1, 4"), "{note}");
        assert!(note.contains("\"tissue\""), "{note}");
        // One name per tag, as Gmsh writes it: no note.
        assert!(read("a.msh", CUBE_V22).unwrap().notes.iter().all(|n| !n.contains("physical groups")));
    }

    #[test]
    fn binary_and_unknown_versions_are_refused_with_the_fix() {
        let binary = CUBE_V41.replacen("4.1 0 8", "4.1 1 8", 1);
        let err = read("b.msh", &binary).unwrap_err().to_string();
        assert!(err.starts_with("b.msh:2: the file is binary"), "{err}");
        assert!(err.contains("-bin 0"), "{err}");
        let v3 = CUBE_V22.replacen("2.2 0 8", "3.0 0 8", 1);
        assert!(read("c.msh", &v3)
            .unwrap_err()
            .to_string()
            .contains("version 3.0"));
    }

    #[test]
    fn second_order_elements_are_refused_naming_the_element() {
        let quadratic = CUBE_V22.replacen("\n1 5 2 1 1 1 2 5 4 7 8 11 10", "\n1 11 2 1 1 1 2 5 4 7 8 11 10 3 6", 1);
        let err = read("q.msh", &quadratic).unwrap_err().to_string();
        assert!(err.contains("element 1 is a 10-node tetrahedron"), "{err}");
    }

    /// Gmsh writes an element a line: one with a node too few or too many
    /// is named at its own line, not where the count runs out.
    #[test]
    fn an_element_with_the_wrong_node_count_is_named_at_its_line() {
        let short = CUBE_V22.replacen("\n1 5 2 1 1 1 2 5 4 7 8 11 10", "\n1 5 2 1 1 1 2 5 4 7 8 11", 1);
        let err = read("s.msh", &short).unwrap_err().to_string();
        assert!(err.starts_with("s.msh:26: element 1 (type 5: 8-node hexahedron) lists 7 nodes, needs 8"), "{err}");
        let long = CUBE_V22.replacen("\n2 5 2 1 1 2 3 6 5 8 9 12 11", "\n2 5 2 1 1 2 3 6 5 8 9 12 11 4", 1);
        let err = read("l.msh", &long).unwrap_err().to_string();
        assert!(err.starts_with("l.msh:27: element 2 (type 5: 8-node hexahedron) lists more than 8 nodes"), "{err}");
    }

    #[test]
    fn every_truncation_gives_an_error_not_a_panic() {
        for text in [CUBE_V22, CUBE_V41, CUBE_V40] {
            for cut in (0..text.len()).step_by(7) {
                let result = read("t.msh", &text[..cut]);
                assert!(result.is_err(), "a file cut at byte {cut} was accepted");
            }
        }
    }

    #[test]
    fn corrupted_bytes_give_errors_not_panics() {
        for text in [CUBE_V22, CUBE_V41, CUBE_V40] {
            let mut bytes = text.as_bytes().to_vec();
            for i in (3..bytes.len()).step_by(5) {
                let saved = bytes[i];
                for replacement in [b'x', b'-', b'9', 0xff] {
                    bytes[i] = replacement;
                    // Either parses (a changed coordinate) or errors; never panics.
                    let _ = parse_msh(Path::new("c.msh"), &bytes);
                }
                bytes[i] = saved;
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let _ = parse_msh(Path::new("a.msh"), &bytes);
        }

        #[test]
        fn spliced_fixtures_never_panic(at in 0usize..1500, junk in "[$0-9a-zA-Z\n .\"-]{0,40}") {
            for text in [CUBE_V22, CUBE_V41, CUBE_V40] {
                let at = at.min(text.len());
                let spliced = format!("{}{junk}{}", &text[..at], &text[at..]);
                let _ = read("s.msh", &spliced);
            }
        }
    }

    #[test]
    fn huge_counts_end_at_the_end_of_the_file() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 18446744073709551615 1 2\n3 1 0 18446744073709551615\n1\n";
        let err = read("h.msh", text).unwrap_err().to_string();
        assert!(err.contains("ends while reading"), "{err}");
    }

    #[test]
    fn mixed_hexahedra_and_tetrahedra_are_refused_with_the_counts() {
        let mixed = CUBE_V22.replacen("$Elements\n5\n", "$Elements\n6\n6 4 2 1 1 1 2 4 7\n", 1);
        let err = read("m.msh", &mixed).unwrap_err().to_string();
        assert!(err.contains("mixes 2 hexahedra and 1 tetrahedra"), "{err}");
        assert!(err.contains("fix:"), "{err}");
    }

    /// An element naming a node the file lacks, or one node twice, is
    /// named at its own line, as every other fault of the file is.
    #[test]
    fn an_element_with_a_missing_or_repeated_node_is_named_at_its_line() {
        let missing = CUBE_V22.replacen("\n2 5 2 1 1 2 3 6 5 8 9 12 11", "\n2 5 2 1 1 2 3 6 5 8 9 12 99", 1);
        let err = read("m.msh", &missing).unwrap_err().to_string();
        assert!(err.starts_with("m.msh:27: element 2 names node 99, which the file does not define; fix:"), "{err}");
        let twice = CUBE_V22.replacen("\n2 5 2 1 1 2 3 6 5 8 9 12 11", "\n2 5 2 1 1 2 3 6 5 8 9 12 2", 1);
        let err = read("t.msh", &twice).unwrap_err().to_string();
        assert!(err.starts_with("t.msh:27: element 2 uses node 2 twice"), "{err}");
    }

    /// A header whose count differs from the entries that follow is
    /// refused at the header's line with both counts, not read short or
    /// passed over.
    #[test]
    fn a_count_that_does_not_match_its_entries_is_named_with_both() {
        // Version 4: the total over the blocks (the cube's 175 in examples/).
        let cube = include_str!("../../../examples/cube_n5.msh");
        let claimed = cube.replacen("$Elements\n3 175 1 175\n", "$Elements\n3 176 1 175\n", 1);
        assert_ne!(claimed, cube);
        let line = cube.lines().position(|l| l == "$Elements").unwrap() + 2;
        let err = read("c.msh", &claimed).unwrap_err().to_string();
        assert!(err.starts_with(&format!("c.msh:{line}: the header declares 176 elements in all, but its blocks hold 175; fix: set the count on this line to 175")), "{err}");
        let nodes = CUBE_V41.lines().position(|l| l == "$Nodes").unwrap() + 2;
        let header = CUBE_V41.lines().nth(nodes - 1).unwrap();
        let (blocks, rest) = header.split_once(' ').unwrap();
        let (count, bounds) = rest.split_once(' ').unwrap();
        let more = count.parse::<usize>().unwrap() + 1;
        let edited = CUBE_V41.replacen(&format!("$Nodes\n{header}\n"), &format!("$Nodes\n{blocks} {more} {bounds}\n"), 1);
        let err = read("n.msh", &edited).unwrap_err().to_string();
        assert!(err.starts_with(&format!("n.msh:{nodes}: the header declares {more} nodes in all, but its blocks hold {count}")), "{err}");
        // Version 2: a count one over, or one short, of the elements.
        let over = CUBE_V22.replacen("$Elements\n5\n", "$Elements\n6\n", 1);
        let err = read("o.msh", &over).unwrap_err().to_string();
        assert!(err.starts_with("o.msh:25: the count here declares 6 elements, but $EndElements comes after 5 (line 31); fix: set the count to 5"), "{err}");
        let short = CUBE_V22.replacen("$Elements\n5\n", "$Elements\n4\n", 1);
        let err = read("s.msh", &short).unwrap_err().to_string();
        assert!(err.starts_with("s.msh:25: the count here declares 4 elements, but more follow them (from line 30"), "{err}");
    }

    #[test]
    fn a_bad_coordinate_names_the_node_and_line() {
        let bad = CUBE_V22.replacen("\n3 2 0 0\n", "\n3 2 nan 0\n", 1);
        let err = read("n.msh", &bad).unwrap_err().to_string();
        assert!(err.contains("node 3 has the coordinate \"nan\""), "{err}");
        assert!(err.starts_with("n.msh:"), "{err}");
        // A node short of a coordinate is named at its own line, not where
        // the shifted tokens run out (4.1: the fourth node's x y z on line 34).
        let short = CUBE_V41.replacen("\n0 1 0\n", "\n0 1\n", 1);
        let err = read("s.msh", &short).unwrap_err().to_string();
        assert!(err.starts_with("s.msh:34:") && err.contains("node 4 has 2 coordinates on its line"), "{err}");
    }
}
