//! Abaqus `.inp` reader: `*NODE`, `*ELEMENT` (C3D8 family, C3D4 family),
//! `*NSET`/`*ELSET` (lists, other sets' names, `GENERATE`), `*SURFACE`
//! (element faces `S1`..`S6`, or nodes). Keywords and parameter names are
//! case-insensitive; set names keep the spelling of their first use and
//! match case-insensitively, as in Abaqus. `**` lines are comments; a data
//! line that ends in a comma, or an element whose nodes are not all given,
//! continues on the next line. Other keywords (materials, steps) are skipped.
//!
//! Hand-written: no maintained Rust crate reads `.inp` (the format is a
//! line-and-comma layout that takes a few hundred lines to read exactly).
//! C3D8 and C3D4 number their nodes as VTK does, the order of
//! [`carus_fem::Mesh`].

use std::collections::HashMap;
use std::path::Path;

use crate::builder::{MeshBuilder, MeshFile};
use crate::error::ReadError;
use crate::text::finite_f64;

/// Reads an Abaqus `.inp` file.
pub fn read_inp(path: &Path) -> Result<MeshFile, ReadError> {
    let bytes = crate::input::read_bytes(path).map_err(|cause| ReadError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    parse_inp(path, &bytes)
}

/// Parses the bytes of an `.inp` file; `path` only names it in errors.
pub fn parse_inp(path: &Path, bytes: &[u8]) -> Result<MeshFile, ReadError> {
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.lines().collect();
    let mut reader = Reader {
        path,
        builder: MeshBuilder::new(path).with_surface_only_fix(
            "export the 3-D mesh as solid elements (C3D8, C3D8R, C3D8H, C3D8I, C3D4, C3D4H), not only shells or faces",
        ),
        set_names: HashMap::new(),
        volume_nodes: HashMap::new(),
        facets: HashMap::new(),
        surface_faces: Vec::new(),
        line: 0,
        line_count: lines.len(),
    };
    reader.run(&lines)?;
    reader.resolve_surfaces()?;
    reader.facet_surfaces();
    reader.builder.finish()
}

/// H8 faces S1..S6 (0-based local nodes), from the Abaqus manual's C3D8 table.
const HEXAHEDRON_FACES: [&[usize]; 6] = [
    &[0, 1, 2, 3],
    &[4, 7, 6, 5],
    &[0, 4, 5, 1],
    &[1, 5, 6, 2],
    &[2, 6, 7, 3],
    &[3, 7, 4, 0],
];
/// T4 faces S1..S4, from the Abaqus manual's C3D4 table.
const TETRAHEDRON_FACES: [&[usize]; 4] = [&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]];

/// A keyword line: upper-case keyword and parameters (upper-case keys).
struct Keyword {
    name: String,
    parameters: Vec<(String, String)>,
    line: usize,
}

impl Keyword {
    fn parameter(&self, key: &str) -> Option<&str> {
        self.parameters
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    fn flag(&self, key: &str) -> bool {
        self.parameters.iter().any(|(k, _)| k == key)
    }
}

enum Block {
    Nodes {
        set: Option<String>,
    },
    Volume {
        per_element: usize,
        set: Option<String>,
    },
    Ignored {
        set: Option<String>,
    },
    NodeSet {
        name: String,
        generate: bool,
    },
    ElementSet {
        name: String,
        generate: bool,
    },
    ElementSurface {
        name: String,
    },
    NodeSurface {
        name: String,
    },
    Skip,
}

struct Reader<'a> {
    path: &'a Path,
    builder: MeshBuilder,
    /// Upper-case set name -> spelling of its first use.
    set_names: HashMap<String, String>,
    volume_nodes: HashMap<u64, Vec<u64>>,
    /// Skipped 3- and 4-node elements (CPS3, S4R, R3D3, ...): an element set
    /// holding them also becomes a surface, as Gmsh's export writes faces.
    facets: HashMap<u64, Vec<u64>>,
    /// (surface, element id or element set, face label, line).
    surface_faces: Vec<(String, String, String, usize)>,
    line: usize,
    /// Lines in the file: no more nodes or elements than this can be
    /// defined, so no GENERATE range longer can be a set of them.
    line_count: usize,
}

impl Reader<'_> {
    fn error(&self, problem: impl Into<String>, fix: impl Into<String>) -> ReadError {
        ReadError::Syntax {
            path: self.path.to_path_buf(),
            line: self.line,
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    fn set_name(&mut self, name: &str) -> String {
        self.set_names
            .entry(name.to_ascii_uppercase())
            .or_insert_with(|| name.to_string())
            .clone()
    }

    fn run(&mut self, lines: &[&str]) -> Result<(), ReadError> {
        let mut block = Block::Skip;
        let mut pending: Vec<String> = Vec::new();
        // The line an element's values began on, for one that runs over.
        let mut pending_from = 0;
        let mut index = 0;
        while index < lines.len() {
            self.line = index + 1;
            let mut current = lines[index].trim().to_string();
            index += 1;
            if current.is_empty() || current.starts_with("**") {
                continue;
            }
            if current.starts_with('*') {
                if !pending.is_empty() {
                    return Err(self.error(
                        format!(
                            "an element ends early: only {} values before the next keyword",
                            pending.len()
                        ),
                        "give every element all its nodes",
                    ));
                }
                // A keyword line ending in a comma continues on the next line,
                // which then holds parameters (names), never data (numbers).
                let keyword_line = self.line;
                while current.ends_with(',') && index < lines.len() {
                    let next = lines[index].trim();
                    if next.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.')) {
                        self.line = index + 1;
                        return Err(self.error(
                            format!(
                                "the keyword line {keyword_line} ends in a comma, so this line would continue it, \
                                 but it holds data, not parameters: {next:?}"
                            ),
                            format!("remove the comma at the end of line {keyword_line}"),
                        ));
                    }
                    current.push_str(next);
                    index += 1;
                }
                let keyword = self.keyword(&current);
                block = self.open_block(&keyword)?;
                continue;
            }
            let mut fields: Vec<String> = current
                .split(',')
                .map(|f| f.trim().to_string())
                .filter(|f| !f.is_empty())
                .collect();
            match &block {
                Block::Volume { per_element, set } => {
                    if pending.is_empty() {
                        pending_from = self.line;
                    }
                    let given_here = fields.len();
                    pending.append(&mut fields);
                    if pending.len() > per_element + 1 {
                        let continued_on = self.line;
                        let (problem, fix) = match pending_from == continued_on {
                            true => (
                                format!("an element has {} values, more than its id and {per_element} nodes", pending.len()),
                                "check the element type and the node list".to_string(),
                            ),
                            false => (
                                format!(
                                    "the element begun here has {} values over lines {pending_from} to {continued_on} \
                                     ({} on this line, too few for its id and {per_element} nodes, so the next was \
                                     read as its rest, and {given_here} on line {continued_on}), more than its id and \
                                     {per_element} nodes",
                                    pending.len(),
                                    pending.len() - given_here,
                                ),
                                format!(
                                    "give each element its id and {per_element} nodes: nodes missing from this line, \
                                     or a value too many on line {continued_on}"
                                ),
                            ),
                        };
                        // Named at the line to mend, where the element began.
                        self.line = pending_from;
                        return Err(self.error(problem, fix));
                    }
                    if pending.len() == per_element + 1 {
                        let values = self.integers(&pending, "an element or node id")?;
                        pending.clear();
                        self.volume(values, set.clone(), pending_from)?;
                    }
                }
                Block::Nodes { set } => {
                    let set = set.clone();
                    self.node(&fields, set.as_deref())?
                }
                Block::Ignored { set } => {
                    let values: Vec<u64> = fields.iter().filter_map(|f| f.parse().ok()).collect();
                    if let Some((&id, nodes)) = values.split_first() {
                        self.builder.ignore_element(id);
                        if let Some(set) = set {
                            self.builder.add_to_element_set(set, id);
                        }
                        if matches!(nodes.len(), 3 | 4) && !self.facets.contains_key(&id) {
                            self.facets.insert(id, nodes.to_vec());
                        }
                    }
                }
                Block::NodeSet { name, generate } => {
                    let (name, generate) = (name.clone(), *generate);
                    for id in self.members(&fields, generate, false)? {
                        self.builder.add_to_node_set(&name, id);
                    }
                }
                Block::ElementSet { name, generate } => {
                    let (name, generate) = (name.clone(), *generate);
                    for id in self.members(&fields, generate, true)? {
                        self.builder.add_to_element_set(&name, id);
                    }
                }
                Block::ElementSurface { name } => {
                    if fields.len() != 2 {
                        return Err(self.error(
                            format!("expected `element or element set, face` (such as `12, S3`), found {current:?}"),
                            "list one element (or element set) and one face label per line",
                        ));
                    }
                    let face = fields.pop().unwrap_or_default().to_ascii_uppercase();
                    let target = fields.pop().unwrap_or_default();
                    self.surface_faces
                        .push((name.clone(), target, face, self.line));
                }
                Block::NodeSurface { name } => {
                    let name = name.clone();
                    let target = fields.first().cloned().unwrap_or_default();
                    for id in self.members(&[target], false, false)? {
                        self.builder.add_to_node_set(&name, id);
                    }
                }
                Block::Skip => {}
            }
        }
        if !pending.is_empty() {
            return Err(self.error(
                format!(
                    "the file ends inside an element ({} values read)",
                    pending.len()
                ),
                "the file looks truncated: export it again",
            ));
        }
        Ok(())
    }

    fn keyword(&self, line: &str) -> Keyword {
        let mut parts = line[1..].split(',');
        let name = parts
            .next()
            .unwrap_or_default()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_ascii_uppercase();
        let parameters = parts
            .filter(|p| !p.trim().is_empty())
            .map(|p| match p.split_once('=') {
                Some((k, v)) => (
                    k.trim().to_ascii_uppercase(),
                    v.trim().trim_matches('"').to_string(),
                ),
                None => (p.trim().to_ascii_uppercase(), String::new()),
            })
            .collect();
        Keyword {
            name,
            parameters,
            line: self.line,
        }
    }

    fn required(&self, keyword: &Keyword, key: &str) -> Result<String, ReadError> {
        match keyword.parameter(key) {
            Some(value) if !value.is_empty() => Ok(value.to_string()),
            _ => Err(ReadError::Syntax {
                path: self.path.to_path_buf(),
                line: keyword.line,
                problem: format!("*{} has no {key}= parameter", keyword.name),
                fix: format!("write it as *{}, {key}=<name>", keyword.name),
            }),
        }
    }

    fn open_block(&mut self, keyword: &Keyword) -> Result<Block, ReadError> {
        Ok(match keyword.name.as_str() {
            "NODE" => Block::Nodes {
                set: keyword.parameter("NSET").map(|s| self.set_name(s)),
            },
            "ELEMENT" => {
                let kind = self.required(keyword, "TYPE")?.to_ascii_uppercase();
                let set = keyword.parameter("ELSET").map(|s| self.set_name(s));
                match volume_nodes(&kind) {
                    Some(per_element) => Block::Volume { per_element, set },
                    None if kind.starts_with("C3D") => {
                        return Err(self.error(
                            format!("element type {kind} is not supported (C3D8, C3D8R, C3D8H, C3D8I, C3D4, C3D4H are)"),
                            "mesh with first-order 8-node hexahedra or 4-node tetrahedra",
                        ))
                    }
                    None => {
                        self.builder
                            .note(format!("skipped *ELEMENT, TYPE={kind} (not a solid element)"));
                        Block::Ignored { set }
                    }
                }
            }
            "NSET" => Block::NodeSet {
                name: self.required(keyword, "NSET").map(|s| self.set_name(&s))?,
                generate: keyword.flag("GENERATE"),
            },
            "ELSET" => Block::ElementSet {
                name: self.required(keyword, "ELSET").map(|s| self.set_name(&s))?,
                generate: keyword.flag("GENERATE"),
            },
            "SURFACE" => {
                let name = self.required(keyword, "NAME")?;
                match keyword
                    .parameter("TYPE")
                    .map(str::to_ascii_uppercase)
                    .as_deref()
                {
                    None | Some("ELEMENT") => Block::ElementSurface { name },
                    Some("NODE") => Block::NodeSurface {
                        name: self.set_name(&name),
                    },
                    Some(other) => {
                        return Err(self.error(
                            format!(
                                "*SURFACE, TYPE={other} is not supported (ELEMENT and NODE are)"
                            ),
                            "define the surface by element faces (TYPE=ELEMENT)",
                        ))
                    }
                }
            }
            "INCLUDE" => {
                return Err(self.error(
                    "*INCLUDE is not supported",
                    "paste the included file's lines in place of the *INCLUDE line",
                ))
            }
            _ => Block::Skip,
        })
    }

    fn integers(&self, fields: &[String], what: &str) -> Result<Vec<u64>, ReadError> {
        fields
            .iter()
            .map(|f| {
                f.parse::<u64>().map_err(|_| {
                    self.error(
                        format!("expected {what}, found {f:?}"),
                        "write ids as whole numbers",
                    )
                })
            })
            .collect()
    }

    fn node(&mut self, fields: &[String], set: Option<&str>) -> Result<(), ReadError> {
        if fields.len() != 4 {
            return Err(self.error(
                format!(
                    "a node line needs `id, x, y, z`, found {} values",
                    fields.len()
                ),
                "give every node its id and three coordinates (Carus meshes are 3-D)",
            ));
        }
        let id = self.integers(&fields[..1], "a node id")?[0];
        let mut xyz = [0.0; 3];
        for (k, field) in fields[1..].iter().enumerate() {
            xyz[k] = finite_f64(field).ok_or_else(|| {
                self.error(
                    format!("node {id} has the coordinate {field:?}, which is not a finite number"),
                    "fix the node's coordinates",
                )
            })?;
        }
        self.builder.add_node(id, xyz).map_err(|problem| {
            self.error(
                problem,
                "give every node its own number and finite coordinates",
            )
        })?;
        if let Some(set) = set {
            self.builder.add_to_node_set(set, id);
        }
        Ok(())
    }

    /// Element `values[0]` of nodes `values[1..]`, begun on line `from`.
    fn volume(&mut self, values: Vec<u64>, set: Option<String>, from: usize) -> Result<(), ReadError> {
        let id = values[0];
        let nodes = values[1..].to_vec();
        match nodes.len() {
            8 => {
                let mut n = [0; 8];
                n.copy_from_slice(&nodes);
                self.builder.add_hexahedron(id, n, Some(from));
            }
            _ => {
                let mut n = [0; 4];
                n.copy_from_slice(&nodes);
                self.builder.add_tetrahedron(id, n, Some(from));
            }
        }
        if self.volume_nodes.insert(id, nodes).is_some() {
            return Err(self.error(
                format!("element {id} is defined twice"),
                "give every element its own number",
            ));
        }
        if let Some(set) = set {
            self.builder.add_to_element_set(&set, id);
        }
        Ok(())
    }

    /// Ids listed on a set's data line: numbers, other sets' names, or
    /// `first, last[, step]` under `GENERATE`.
    fn members(
        &mut self,
        fields: &[String],
        generate: bool,
        elements: bool,
    ) -> Result<Vec<u64>, ReadError> {
        if generate {
            let values = self.integers(fields, "a GENERATE bound")?;
            let (first, last, step) = match values[..] {
                [a, b] => (a, b, 1),
                [a, b, s] => (a, b, s),
                _ => {
                    return Err(self.error(
                        format!(
                            "GENERATE needs `first, last[, increment]`, found {} values",
                            values.len()
                        ),
                        "write one range per line",
                    ))
                }
            };
            if step == 0 || last < first {
                return Err(self.error(
                    format!("GENERATE range {first}..{last} step {step} is empty or endless"),
                    "use first <= last and a positive increment",
                ));
            }
            let ids = ((last - first) / step).saturating_add(1);
            if ids > self.line_count as u64 {
                let kind = if elements { "elements" } else { "nodes" };
                return Err(self.error(
                    format!(
                        "GENERATE range {first}..{last} step {step} lists {ids} ids, more {kind} than a file of \
                         {} lines can define",
                        self.line_count
                    ),
                    "check the bounds (a typo can add digits)",
                ));
            }
            return Ok((first..=last).step_by(step as usize).collect());
        }
        let mut ids = Vec::new();
        for field in fields {
            if let Ok(id) = field.parse::<u64>() {
                ids.push(id);
                continue;
            }
            let name = self.set_name(field);
            let known = if elements {
                self.builder.element_set(&name)
            } else {
                self.builder.node_set(&name)
            };
            match known {
                Some(members) => ids.extend_from_slice(members),
                None => {
                    return Err(self.error(
                        format!(
                            "{field:?} is neither a number nor a {} set defined above",
                            if elements { "element" } else { "node" }
                        ),
                        "define the set before it is used, or check its spelling",
                    ))
                }
            }
        }
        Ok(ids)
    }

    fn resolve_surfaces(&mut self) -> Result<(), ReadError> {
        let faces = std::mem::take(&mut self.surface_faces);
        for (surface, target, label, line) in faces {
            self.line = line;
            let elements: Vec<u64> = match target.parse::<u64>() {
                Ok(id) => vec![id],
                Err(_) => {
                    let name = self.set_name(&target);
                    self.builder
                        .element_set(&name)
                        .map(<[u64]>::to_vec)
                        .ok_or_else(|| {
                            self.error(
                                format!(
                                    "surface {surface:?} names {target:?}, which is no element set"
                                ),
                                "define the element set, or check its spelling",
                            )
                        })?
                }
            };
            let face: usize = label
                .strip_prefix('S')
                .and_then(|n| n.parse().ok())
                .filter(|n| (1..=6).contains(n))
                .ok_or_else(|| {
                    self.error(
                        format!("face label {label:?} is not S1..S6"),
                        "use S1..S6 (S1..S4 on C3D4)",
                    )
                })?;
            for id in elements {
                let Some(nodes) = self.volume_nodes.get(&id) else {
                    if self.builder.is_ignored(id) {
                        continue;
                    }
                    return Err(self.error(
                        format!("surface {surface:?} names element {id}, which is no solid element of the file"),
                        "name the faces of C3D8 or C3D4 elements",
                    ));
                };
                let local = if nodes.len() == 8 {
                    HEXAHEDRON_FACES.get(face - 1)
                } else {
                    TETRAHEDRON_FACES.get(face - 1)
                };
                let Some(local) = local else {
                    return Err(self.error(
                        format!("element {id} is a tetrahedron, which has faces S1..S4 only, not {label}"),
                        "use S1..S4 on C3D4 elements",
                    ));
                };
                let polygon: Vec<u64> = local.iter().map(|&i| nodes[i]).collect();
                self.builder.add_surface_polygon(&surface, &polygon);
            }
        }
        Ok(())
    }
}

impl Reader<'_> {
    /// Element sets holding triangles or quadrilaterals become surfaces.
    fn facet_surfaces(&mut self) {
        if self.facets.is_empty() {
            return;
        }
        let mut found: Vec<(String, Vec<u64>)> = Vec::new();
        for (name, members) in self.builder.element_sets() {
            for id in members {
                if let Some(nodes) = self.facets.get(id) {
                    found.push((name.clone(), nodes.clone()));
                }
            }
        }
        for (name, nodes) in found {
            self.builder.add_surface_polygon(&name, &nodes);
        }
    }
}

/// Nodes per element for the solid types Carus reads.
fn volume_nodes(kind: &str) -> Option<usize> {
    let suffix_ok = |rest: &str| rest.chars().all(|c| c.is_ascii_alphabetic());
    if let Some(rest) = kind.strip_prefix("C3D8") {
        suffix_ok(rest).then_some(8)
    } else if let Some(rest) = kind.strip_prefix("C3D4") {
        suffix_ok(rest).then_some(4)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use carus_fem::ElementKind;

    const TWO_HEX: &str = include_str!("../tests/data/two_hex.inp");

    fn read(text: &str) -> Result<MeshFile, ReadError> {
        parse_inp(Path::new("m.inp"), text.as_bytes())
    }

    #[test]
    fn reads_nodes_elements_sets_and_surfaces() {
        let file = read(TWO_HEX).unwrap();
        let mesh = &file.mesh;
        assert_eq!(mesh.kind, ElementKind::H8);
        assert_eq!(mesh.element_count(), 2);
        assert_eq!(mesh.node_count(), 12);
        assert_eq!(file.element_ids, vec![1, 2]);
        assert_eq!(mesh.element_sets["Tissue"], vec![0, 1]);
        assert_eq!(mesh.element_sets["first"], vec![0]);
        // GENERATE 1..10 step 3 -> 1, 4, 7, 10 (the x = 0 face).
        assert_eq!(mesh.node_sets["Fixed"], vec![0, 3, 6, 9]);
        // A set made of other sets' names, matched case-insensitively.
        assert_eq!(mesh.node_sets["both"].len(), 8);
        assert_eq!(mesh.surfaces["pull"].len(), 2);
        for triangle in &mesh.surfaces["pull"] {
            let [a, b, c] = triangle.map(|n| mesh.nodes[n as usize]);
            assert!(a[0] == 2.0 && b[0] == 2.0 && c[0] == 2.0);
            let normal_x = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
            assert!(normal_x > 0.0, "x = 2 face must point towards +x");
        }
        assert!(
            file.notes.iter().any(|n| n.contains("S4R")),
            "{:?}",
            file.notes
        );
        // The shell element 3 was in a set: dropped, not an error.
        assert_eq!(mesh.element_sets["with_shell"], vec![1]);
        // ... and, being a quadrilateral in an element set, a surface.
        assert_eq!(mesh.surfaces["with_shell"].len(), 2);
    }

    #[test]
    fn tetrahedra_with_continuation_lines() {
        let text = "*Node\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*element,\n type=c3d4\n7, 1, 2,\n 3, 4\n*Surface, name=base\n7, S1\n";
        let mesh = read(text).unwrap().mesh;
        assert_eq!(mesh.kind, ElementKind::T4);
        assert_eq!(mesh.connectivity, vec![0, 1, 2, 3]);
        assert_eq!(mesh.surfaces["base"], vec![[0, 2, 1]]);
    }

    #[test]
    fn errors_name_the_line_and_the_fix() {
        let cases = [
            (
                "*NODE\n1, 0, 0\n",
                "m.inp:2: a node line needs `id, x, y, z`",
            ),
            (
                "*NODE\n1, 0, 0, x\n",
                "m.inp:2: node 1 has the coordinate \"x\"",
            ),
            (
                "*ELEMENT, TYPE=C3D10\n",
                "m.inp:1: element type C3D10 is not supported",
            ),
            ("*ELEMENT\n", "m.inp:1: *ELEMENT has no TYPE= parameter"),
            (
                "*NSET, NSET=a\nmissing\n",
                "m.inp:2: \"missing\" is neither a number nor a node set",
            ),
            (
                "*NSET, NSET=a, GENERATE\n5, 1\n",
                "m.inp:2: GENERATE range 5..1",
            ),
            (
                "*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D4\n1, 1, 1\n",
                "m.inp:4: the file ends inside an element",
            ),
            (
                "*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D4\n1, 1, 1\n2, 1, 1, 1, 1\n",
                "m.inp:4: the element begun here has 8 values over lines 4 to 5 (3 on this line, too few for its id and 4 nodes, so the next was read as its rest, and 5 on line 5)",
            ),
            (
                "*NODE\n1,0,0,0\n*ELEMENT, TYPE=S4\n1, 1, 1, 1, 1\n",
                "m.inp: the file holds no volume elements (8-node hexahedra or 4-node tetrahedra) (skipped *ELEMENT, TYPE=S4",
            ),
            // An element naming a node the file lacks, or one node twice: at its (first) line.
            (
                "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n*ELEMENT, TYPE=C3D4\n1, 1, 2,\n3, 9\n",
                "m.inp:6: element 1 names node 9, which the file does not define",
            ),
            (
                "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 3\n",
                "m.inp:6: element 1 uses node 3 twice",
            ),
            (
                "*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D4,\n1, 1, 1, 1, 1\n",
                "m.inp:4: the keyword line 3 ends in a comma, so this line would continue it, but it holds data",
            ),
        ];
        for (text, expected) in cases {
            let err = read(text).unwrap_err().to_string();
            assert!(err.starts_with(expected), "{err}\n  expected: {expected}");
            assert!(err.contains("; fix: "), "{err}");
        }
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_text_never_panics(text in "[*,0-9a-zA-Z=\n .-]{0,300}") {
            let _ = read(&text);
        }

        #[test]
        fn spliced_fixtures_never_panic(at in 0usize..2000, junk in "[*,0-9A-Z=\n .-]{0,40}") {
            let at = at.min(TWO_HEX.len());
            let text = format!("{}{junk}{}", &TWO_HEX[..at], &TWO_HEX[at..]);
            let _ = read(&text);
        }
    }

    #[test]
    fn huge_generate_ranges_are_refused_not_allocated() {
        let err = read("*NSET, NSET=a, GENERATE\n1, 99999999999999, 1\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("lists 99999999999999 ids, more nodes than a file of 2 lines can define"), "{err}");
        // A slip of digits within memory but past what the file can define
        // is refused before its ids are listed.
        let err = parse_inp(Path::new("g.inp"), b"*NSET, NSET=A, GENERATE\n1, 400000000\n*NODE\n1, 0, 0, 0\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("lists 400000000 ids, more nodes than a file of 4 lines"), "{err}");
    }

    #[test]
    fn every_truncation_gives_an_error_or_a_smaller_mesh_never_a_panic() {
        for cut in 0..TWO_HEX.len() {
            if let Ok(file) = read(&TWO_HEX[..cut]) {
                assert!(file.mesh.element_count() <= 2);
            }
        }
    }

    #[test]
    fn corrupted_bytes_give_errors_not_panics() {
        let mut bytes = TWO_HEX.as_bytes().to_vec();
        for i in 0..bytes.len() {
            let saved = bytes[i];
            for replacement in [b',', b'*', b'x', b'\n', 0xff] {
                bytes[i] = replacement;
                let _ = parse_inp(Path::new("c.inp"), &bytes);
            }
            bytes[i] = saved;
        }
    }
}
