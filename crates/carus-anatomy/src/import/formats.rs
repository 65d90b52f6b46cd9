//! Readers for the surface mesh formats researchers have: STL (binary and
//! ASCII), OBJ, PLY and glTF/GLB. Each returns the triangles as stored, in
//! the file's own units and axes, for [`super::weld`] to clean up.

use std::io::BufReader;
use std::path::Path;

use base64::Engine;
use glam::{DMat4, DVec3};

use super::ImportError;

/// Triangles as a file stores them: positions (file units) and indices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl RawMesh {
    fn push_triangle(&mut self, corners: [DVec3; 3]) {
        let base = self.positions.len() as u32;
        self.positions.extend(corners);
        self.triangles.push([base, base + 1, base + 2]);
    }
}

/// The mesh formats, told apart by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    Stl,
    Obj,
    Ply,
    Gltf,
}

impl MeshFormat {
    pub fn from_path(path: &Path) -> Result<Self, ImportError> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        extension.as_deref().and_then(MeshFormat::from_extension).ok_or_else(|| ImportError::UnknownFormat {
            path: path.to_path_buf(),
        })
    }

    fn from_extension(extension: &str) -> Option<Self> {
        match extension {
            "stl" => Some(MeshFormat::Stl),
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            "gltf" | "glb" => Some(MeshFormat::Gltf),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            MeshFormat::Stl => "STL",
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Gltf => "glTF",
        }
    }
}

/// What a file's first bytes say it is, where they say it surely, with
/// the extension that format takes: a mesh renamed by mistake (an STL
/// saved as .ply) is then named as what it is, instead of failing deep in
/// the wrong reader. A binary STL is known by its size fitting its
/// triangle count (a text file's bytes 80-83 would count hundreds of
/// millions of triangles); JSON glTF is left to its reader.
fn content_format(bytes: &[u8]) -> Option<(String, &'static str)> {
    let word = |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    // A GLB header: its magic, version 2, and the file's own length.
    if bytes.starts_with(b"glTF") && word(4) == Some(2) && word(8) == Some(bytes.len() as u32) {
        return Some(("a binary glTF (GLB)".into(), "glb"));
    }
    if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        return Some(("a PLY mesh".into(), "ply"));
    }
    if let Some(count) = word(80).map(u64::from).filter(|&n| n > 0 && bytes.len() as u64 == 84 + 50 * n) {
        return Some((format!("a binary STL ({count} triangles)"), "stl"));
    }
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(1024)]).to_ascii_lowercase();
    (head.trim_start().starts_with("solid") && head.contains("facet")).then(|| ("an ASCII STL".into(), "stl"))
}

/// Reads a mesh file of any supported format.
pub fn read_raw(path: &Path) -> Result<RawMesh, ImportError> {
    if path.is_dir() {
        return Err(ImportError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other("a folder, not a mesh file: name the .stl, .obj, .ply, .gltf or .glb file in it"),
        });
    }
    let format = MeshFormat::from_path(path)?;
    let bytes = carus_io::input::read_bytes(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if let Some((content, extension)) = content_format(&bytes).filter(|(_, e)| MeshFormat::from_extension(e) != Some(format)) {
        return Err(format_error(
            path,
            format.name(),
            format!("the file holds {content}, not {}: give it the .{extension} extension", format.name()),
        ));
    }
    match format {
        MeshFormat::Stl => parse_stl(path, &bytes),
        MeshFormat::Obj => parse_obj(path, &bytes),
        MeshFormat::Ply => parse_ply(path, &bytes),
        MeshFormat::Gltf => Ok(merge_parts(parse_gltf_parts(path, &bytes)?)),
    }
}

fn format_error(path: &Path, format: &'static str, message: impl ToString) -> ImportError {
    // gltf ends its list of validation errors with `;`, which the
    // message's own `; export ...` would double.
    let message = message.to_string();
    ImportError::Format {
        path: path.to_path_buf(),
        format,
        message: message.trim_end_matches([';', ' ']).to_string(),
    }
}

/// STL, binary or ASCII. Read here rather than by stl_io, whose ASCII
/// reader stops at the first `endsolid` (a file of several solids loses
/// the rest unsaid), wants `solid ` in lower case and names no line in an
/// error, and whose binary reader reads only the triangles the header
/// counts (docs/ARCHITECTURE.md). A file is binary when its size fits its
/// header's count exactly, or when it is not text: binary triangles hold
/// about two bytes no text has in every 50 (their attribute bytes are
/// zero), while an ASCII file may carry a few stray ones (a Latin-1 letter
/// in its name, a DOS end-of-file mark: up to 4, and one per 1000 bytes).
/// So a binary header that begins `solid`, as some exporters write, is
/// still read as binary.
pub fn parse_stl(path: &Path, bytes: &[u8]) -> Result<RawMesh, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(format_error(path, "STL", "the file is empty"));
    }
    let announced = (bytes.len() >= 84).then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let fits_binary = announced.is_some_and(|n| bytes.len() as u64 == 84 + 50 * n);
    let text = String::from_utf8_lossy(bytes);
    let stray = text.chars().filter(|&c| (c.is_control() && !c.is_whitespace()) || c == char::REPLACEMENT_CHARACTER).count();
    let is_text = !fits_binary && stray <= 4 + bytes.len() / 1000;
    if !is_text {
        return parse_binary_stl(path, bytes);
    }
    // A byte-order mark is no part of the text (Windows editors write one).
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    if !text.trim_start().get(..5).is_some_and(|w| w.eq_ignore_ascii_case("solid")) {
        // No text has a count of bytes no letter is: a binary header cut short.
        let binary_count = bytes.get(80..84).is_some_and(|c| c.iter().any(|&b| b >= 0x80 || (b.is_ascii_control() && !b.is_ascii_whitespace())));
        if binary_count {
            return parse_binary_stl(path, bytes);
        }
        return Err(format_error(
            path,
            "STL",
            format!(
                "the file is text, but an ASCII STL begins with `solid` and line 1 reads `{}`; if it is another \
                 format (OBJ, PLY), give it that extension",
                carus_io::shown_line(text.lines().next().unwrap_or(""))
            ),
        ));
    }
    parse_ascii_stl(path, text)
}

/// Binary STL: an 80-byte header, a triangle count, then per triangle a
/// normal, three corners (little-endian f32) and two attribute bytes. A
/// file whose size does not fit its count, cut short or with triangles
/// the count leaves out, is refused with both counts.
fn parse_binary_stl(path: &Path, bytes: &[u8]) -> Result<RawMesh, ImportError> {
    const HEADER: usize = 84;
    const RECORD: usize = 50;
    if bytes.len() < HEADER {
        return Err(format_error(path, "STL", "the file is shorter than a binary STL header (84 bytes)"));
    }
    let expected = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let body = bytes.len() - HEADER;
    if body < RECORD * expected {
        return Err(ImportError::TruncatedStl { path: path.to_path_buf(), expected, found: body / RECORD });
    }
    if body > RECORD * expected {
        return Err(ImportError::OverlongStl {
            path: path.to_path_buf(),
            expected,
            found: body / RECORD,
            spare_bytes: body % RECORD,
        });
    }
    let mut mesh = RawMesh::default();
    for record in bytes[HEADER..].chunks_exact(RECORD) {
        // The stored normal (12 bytes) is not read: the corners' order is the truth.
        let f32_at = |at: usize| f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]) as f64;
        let corner = |c: usize| DVec3::new(f32_at(12 + 12 * c), f32_at(16 + 12 * c), f32_at(20 + 12 * c));
        mesh.push_triangle([corner(0), corner(1), corner(2)]);
    }
    Ok(mesh)
}

/// ASCII STL: `solid`, then `facet normal`, `outer loop`, three `vertex x
/// y z`, `endloop`, `endfacet` per triangle, then `endsolid`; keywords in
/// any case, several solids one after another. Errors name the line.
fn parse_ascii_stl(path: &Path, text: &str) -> Result<RawMesh, ImportError> {
    let at_line = |line: usize, problem: String| format_error(path, "STL", format!("line {line}: {problem}"));
    let mut mesh = RawMesh::default();
    let mut corners: Vec<DVec3> = Vec::with_capacity(3);
    // The line of the `outer loop` and of the `solid` still open.
    let mut open_loop: Option<usize> = None;
    let mut open_solid: Option<usize> = None;
    for (number, line) in text.lines().enumerate().map(|(k, l)| (k + 1, l)) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(keyword) = words.first().map(|w| w.to_ascii_lowercase()) else { continue };
        // A DOS end-of-file mark, or a byte no text has, on a line of its own.
        if keyword.chars().all(|c| c.is_control() || c == char::REPLACEMENT_CHARACTER) {
            continue;
        }
        match (keyword.as_str(), open_loop) {
            ("solid" | "endsolid" | "facet" | "endfacet" | "outer", Some(opened)) => {
                return Err(at_line(number, format!("`{keyword}` comes before the `endloop` of the loop opened on line {opened}")));
            }
            ("solid", None) => open_solid = Some(number),
            ("endsolid", None) => open_solid = None,
            ("facet" | "endfacet", None) => {}
            ("outer", None) => {
                open_loop = Some(number);
                corners.clear();
            }
            ("vertex", Some(_)) => {
                let [x, y, z] = words[1..] else {
                    return Err(at_line(number, format!("`{}` should be `vertex` and three numbers", line.trim())));
                };
                let mut p = [0.0; 3];
                for (value, word) in p.iter_mut().zip([x, y, z]) {
                    *value = word.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                        at_line(number, format!("`{word}` is not a finite number (a corner's coordinate)"))
                    })?;
                }
                corners.push(DVec3::from_array(p));
            }
            ("endloop", Some(_)) => {
                let &[a, b, c] = corners.as_slice() else {
                    return Err(at_line(number, format!("a facet's loop has {} corners; a triangle has 3", corners.len())));
                };
                mesh.push_triangle([a, b, c]);
                open_loop = None;
            }
            _ => {
                return Err(at_line(
                    number,
                    format!("`{}` is not a line of an ASCII STL where it stands", line.trim().chars().take(60).collect::<String>()),
                ))
            }
        }
    }
    if let Some(opened) = open_loop.or(open_solid) {
        return Err(format_error(
            path,
            "STL",
            format!(
                "the file ends inside the {} opened on line {opened} (no `{}`), after {} whole triangles: it was cut short",
                if open_loop.is_some() { "facet" } else { "solid" },
                if open_loop.is_some() { "endloop" } else { "endsolid" },
                mesh.triangles.len()
            ),
        ));
    }
    Ok(mesh)
}

/// The first line of an OBJ file whose vertex or face tobj would refuse
/// (its errors name no line): a coordinate that is not a number, or
/// a face corner that names no vertex read so far (1-based, or negative
/// counting back); and a face of fewer than 3 corners, which tobj drops
/// unsaid, leaving a hole where a face was.
fn obj_line_at_fault(bytes: &[u8]) -> Option<String> {
    let (mut vertices, mut texture, mut normals): (i64, i64, i64) = (0, 0, 0);
    // tobj reads 32-bit floats: a larger number would become infinite.
    let number_in = |w: &str| w.parse::<f64>().is_ok_and(|x| x.is_finite() && x.abs() <= f32::MAX as f64);
    let in_range = |i: i64, count: i64| (1..=count).contains(&i) || (-count..0).contains(&i);
    for (number, line) in String::from_utf8_lossy(bytes).lines().enumerate() {
        let mut words = line.split_whitespace();
        // The first three words after the keyword (what follows, a vertex's
        // weight or colour, tobj reads or skips).
        let needs = |what: &str, at_least: usize, words: std::str::SplitWhitespace| {
            let read: Vec<&str> = words.take(3).collect();
            match read.iter().find(|w| !number_in(w)) {
                Some(w) => Some(format!(
                    "line {}: `{w}` in `{}` is not a number a 32-bit float holds (finite, within 3.4e38)",
                    number + 1,
                    line.trim()
                )),
                None => (read.len() < at_least).then(|| format!("line {}: {what}: `{}`", number + 1, line.trim())),
            }
        };
        match words.next() {
            Some("v") => {
                if let Some(fault) = needs("a vertex needs three numbers", 3, words) {
                    return Some(fault);
                }
                vertices += 1;
            }
            Some("vt") => {
                if let Some(fault) = needs("a texture coordinate needs one to three numbers", 1, words) {
                    return Some(fault);
                }
                texture += 1;
            }
            Some("vn") => {
                if let Some(fault) = needs("a normal needs three numbers", 3, words) {
                    return Some(fault);
                }
                normals += 1;
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Some(format!(
                        "line {}: the face has {} corners; a face needs 3 or more (an edge belongs in an `l` line)",
                        number + 1,
                        corners.len()
                    ));
                }
                for corner in corners {
                    let mut parts = corner.split('/');
                    let index = parts.next().and_then(|i| i.parse::<i64>().ok());
                    if index.is_none() {
                        return Some(format!(
                            "line {}: face corner `{corner}` is not a number; a corner is a vertex's number, from 1 \
                             (or from -1 counting back), with `/` and its texture coordinate's and normal's after it, \
                             e.g. `f 1 2 3` or `f 1/1/1 2/2/2 3/3/3`",
                            number + 1
                        ));
                    }
                    if !index.is_some_and(|i| in_range(i, vertices)) {
                        return Some(format!(
                            "line {}: face corner `{corner}` names no vertex; {vertices} are defined above it",
                            number + 1
                        ));
                    }
                    // `v/vt/vn`, either of the last two may be left empty.
                    for (part, (what, count)) in parts.zip([("texture coordinate", texture), ("normal", normals)]) {
                        if !part.is_empty() && !part.parse::<i64>().is_ok_and(|i| in_range(i, count)) {
                            let said = match part.parse::<i64>() {
                                Ok(_) => "names no",
                                Err(_) => "is not a number: no number names a",
                            };
                            return Some(format!(
                                "line {}: face corner `{corner}` {said} {what}; {count} are defined above it",
                                number + 1
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Wavefront OBJ, polygons fan-triangulated by tobj; polylines (`l`),
/// points (`p`) and materials ignored.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<RawMesh, ImportError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    // tobj reads a polyline of three or more vertices as a face; polylines
    // and points are no surface, so they are blanked (the lines keep their
    // numbers for the errors below).
    let surface_only = String::from_utf8_lossy(bytes)
        .lines()
        .map(|line| match line.split_whitespace().next() {
            Some("l" | "p") => "",
            _ => line,
        })
        .collect::<Vec<_>>()
        .join("\n");
    if let Some(at) = obj_line_at_fault(bytes) {
        return Err(format_error(path, "OBJ", at));
    }
    let (models, _materials) = tobj::load_obj_buf(&mut BufReader::new(surface_only.as_bytes()), &options, |_| {
        Ok((Vec::new(), Default::default()))
    })
    .map_err(|e| format_error(path, "OBJ", e))?;
    let mut mesh = RawMesh::default();
    for model in models {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)),
        );
        mesh.triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    Ok(mesh)
}

/// What a PLY file's header declares, as far as telling a fault needs:
/// each element's name, count and properties (name, list or not, integer
/// or not), and where its data starts.
struct PlyLayout {
    ascii: bool,
    /// The 1-based line number of the first data line.
    data_line: usize,
    /// Each element's name, count and properties.
    elements: Vec<(String, usize, Vec<PlyProperty>)>,
}

/// A PLY property: its name, whether it is a list, whether its values
/// are integers.
type PlyProperty = (String, bool, bool);

/// Reads a PLY header, or says which line of it is wrong.
fn ply_layout(text: &str) -> Result<PlyLayout, String> {
    let mut layout = PlyLayout { ascii: false, data_line: 0, elements: Vec::new() };
    let integer = |t: &str| -> Option<bool> {
        match t {
            "char" | "uchar" | "short" | "ushort" | "int" | "uint" | "int8" | "uint8" | "int16" | "uint16"
            | "int32" | "uint32" => Some(true),
            "float" | "double" | "float32" | "float64" => Some(false),
            _ => None,
        }
    };
    for (number, line) in text.lines().enumerate().map(|(i, l)| (i + 1, l)) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |what: &str| Err(format!("line {number}: `{}` {what}", carus_io::shown_line(line)));
        match words.as_slice() {
            ["ply"] if number == 1 => {}
            _ if number == 1 => return bad("is not `ply`, the first line of every PLY file"),
            ["format", format, _] => layout.ascii = *format == "ascii",
            ["comment" | "obj_info", ..] => {}
            ["element", name, count] => match count.parse() {
                Ok(count) => layout.elements.push((name.to_string(), count, Vec::new())),
                Err(_) => return bad("needs a whole number of elements, e.g. `element vertex 8`"),
            },
            ["property", kind, name] | ["property", "list", _, kind, name] => {
                let Some(integer) = integer(kind) else {
                    return bad("names an unknown type; use char, uchar, short, ushort, int, uint, float or double");
                };
                let Some(element) = layout.elements.last_mut() else {
                    return bad("comes before any `element` line");
                };
                element.2.push((name.to_string(), words.len() == 5, integer));
            }
            ["end_header"] => {
                layout.data_line = number + 1;
                return Ok(layout);
            }
            _ => return bad("is not a PLY header line (format, element, property, comment or end_header)"),
        }
    }
    Err("the header has no `end_header` line: the file is truncated or not a PLY file".into())
}

/// Why ply-rs refused a file, in the file's terms: the header line at
/// fault, data that ends before the elements the header announces, or the
/// data line and element whose values do not fit their properties. The
/// library's own message (its internals) is the last resort.
fn ply_fault(bytes: &[u8], error: &std::io::Error) -> String {
    let library = || error.to_string().lines().next().unwrap_or_default().trim().to_string();
    let text = String::from_utf8_lossy(bytes);
    let layout = match ply_layout(&text) {
        Ok(layout) => layout,
        Err(fault) => return fault,
    };
    let announced: Vec<String> =
        layout.elements.iter().map(|(name, count, _)| format!("{count} `{name}`")).collect();
    let announced = announced.join(" and ");
    let fix = "make the counts of the header's `element` lines match the data";
    if !layout.ascii {
        // Binary values are always numbers: after a sound header, data that
        // ends early is the usual fault (the library runs out of bytes, or of
        // a list's items); any other keeps the library's words.
        let ran_out = error.kind() == std::io::ErrorKind::UnexpectedEof
            || ["fill whole buffer", "Couldn't find"].iter().any(|m| library().contains(m));
        if ran_out {
            return format!("the binary data ends before the {announced} elements the header announces; {fix}");
        }
        return library();
    }
    let data: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .skip(layout.data_line - 1)
        .map(|(i, l)| (i + 1, l))
        .collect();
    let needed = layout.elements.iter().fold(0usize, |sum, (_, count, _)| sum.saturating_add(*count));
    let written = data.iter().filter(|(_, l)| !l.trim().is_empty()).count();
    if written < needed {
        return format!(
            "the header announces {announced} elements, {needed} lines of data, but the file has {written} \
             (from line {}); {fix}",
            layout.data_line
        );
    }
    let mut lines = data.into_iter();
    let mut previous: Option<&str> = None;
    for (name, count, properties) in &layout.elements {
        // A first line that does not read as this element is often one of
        // the previous, whose count in the header fell short.
        let said = |index: usize, fault: String| match previous.filter(|_| index == 0) {
            Some(p) => format!("{fault} (if the line holds a `{p}`, the header's `element {p}` count is smaller than the file's)"),
            None => fault,
        };
        for index in 0..*count {
            let Some((number, line)) = lines.next() else {
                return library();
            };
            let mut values = line.split_whitespace();
            for (property, is_list, integer) in properties {
                let items = if *is_list {
                    match values.next().map(|n| n.parse::<usize>()) {
                        Some(Ok(n)) => n,
                        _ => {
                            return said(index, format!(
                                "line {number} (`{name}` {index}): the list `{property}` does not start with its \
                                 length"
                            ))
                        }
                    }
                } else {
                    1
                };
                for item in 0..items {
                    let Some(value) = values.next() else {
                        if *is_list {
                            return said(index, format!(
                                "line {number} (`{name}` {index}): the list `{property}` announces {items} values \
                                 but holds {item}"
                            ));
                        }
                        return said(index, format!(
                            "line {number} (`{name}` {index}): `{property}` is missing; each `{name}` line holds \
                             the values of its {} properties in the header's order",
                            properties.len()
                        ));
                    };
                    let plain = value.chars().all(|c| c.is_ascii_digit() || "+-.eE".contains(c));
                    let fits = plain
                        && if *integer { value.parse::<i64>().is_ok() } else { value.parse::<f64>().is_ok() };
                    if !fits {
                        let kind = if *integer { "an integer" } else { "a finite number" };
                        return said(index, format!(
                            "line {number} (`{name}` {index}): `{value}` is not {kind}, as `{property}` must be"
                        ));
                    }
                }
            }
        }
        previous = Some(name.as_str());
    }
    library()
}

/// The parser reads as many elements as the header's `element` lines
/// count and stops: data past them (a count the exporter left short) would
/// be dropped without a word, so it is refused, by line in ASCII.
fn check_nothing_past_the_counts(path: &Path, bytes: &[u8], rest: &[u8], header: &ply_rs::ply::Header) -> Result<(), ImportError> {
    let ascii = header.encoding == ply_rs::ply::Encoding::Ascii;
    let past = match ascii {
        // Blank lines and comments after the data are no data.
        true => {
            let start = bytes.len() - rest.len();
            let mut offset = start;
            let first = String::from_utf8_lossy(rest).split_inclusive('\n').find_map(|line| {
                let at = offset;
                offset += line.len();
                let word = line.split_whitespace().next()?;
                (word != "comment").then_some(at)
            });
            let Some(first) = first else { return Ok(()) };
            format!("line {} holds data", carus_io::input::line_at(bytes, first))
        }
        // A line end some writers add after the binary data is no data.
        false if rest.iter().all(u8::is_ascii_whitespace) && rest.len() <= 2 => return Ok(()),
        false => format!("{} byte{} of data remain", rest.len(), if rest.len() == 1 { "" } else { "s" }),
    };
    let announced: Vec<String> = header.elements.values().map(|e| format!("{} `{}`", e.count, e.name)).collect();
    Err(format_error(
        path,
        "PLY",
        format!(
            "{past} after the {} elements the header announces, which would be dropped; make the counts of \
             the header's `element` lines match the data",
            announced.join(" and ")
        ),
    ))
}

/// The `index`th face (from 0) of a PLY file as messages name it: its
/// line in an ASCII file, and counted from 1 as STL's triangles are; its
/// corners' vertex indices stay the file's own, from 0.
fn ply_face(bytes: &[u8], index: usize) -> String {
    let counted = format!("face {} of the file (counting from 1)", index + 1);
    match ply_data_line(bytes, "face", index) {
        Some(line) => format!("line {line}, {counted},"),
        None => counted,
    }
}

/// The 1-based line of item `index` of `element` in an ASCII PLY file
/// (one item a line, blank lines skipped); None in a binary one.
fn ply_data_line(bytes: &[u8], element: &str, index: usize) -> Option<usize> {
    let text = String::from_utf8_lossy(bytes);
    let layout = ply_layout(&text).ok().filter(|l| l.ascii)?;
    let at = layout.elements.iter().position(|(name, _, _)| name == element)?;
    let before = layout.elements[..at].iter().try_fold(0usize, |sum, (_, count, _)| sum.checked_add(*count))?;
    let (number, _) = text.lines().enumerate().skip(layout.data_line - 1).filter(|(_, l)| !l.trim().is_empty()).nth(before.checked_add(index)?)?;
    Some(number + 1)
}

/// PLY (ASCII or binary): the `vertex` element's x, y, z and the `face`
/// element's `vertex_indices` (or `vertex_index`) lists, fan-triangulated.
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<RawMesh, ImportError> {
    use ply_rs::ply::Property;
    let parser = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new();
    // Read from the slice itself, which then holds what the parser left.
    let mut rest = bytes;
    let fault = |e: std::io::Error| format_error(path, "PLY", ply_fault(bytes, &e));
    let mut ply = ply_rs::ply::Ply::new();
    ply.header = parser.read_header(&mut rest).map_err(fault)?;
    // An element of no properties reads no data, so the library would make
    // as many empty items as it announces, however many that is.
    if let Some(e) = ply.header.elements.values().find(|e| e.count > 0 && e.properties.is_empty()) {
        return Err(format_error(
            path,
            "PLY",
            format!(
                "the header's `element {} {}` has no `property` lines, so none of its {} items has any data; \
                 give it its properties or remove the line",
                e.name, e.count, e.count
            ),
        ));
    }
    ply.payload = parser.read_payload(&mut rest, &ply.header).map_err(fault)?;
    check_nothing_past_the_counts(path, bytes, rest, &ply.header)?;
    let scalar = |p: &Property| -> Option<f64> {
        Some(match *p {
            Property::Char(v) => v as f64,
            Property::UChar(v) => v as f64,
            Property::Short(v) => v as f64,
            Property::UShort(v) => v as f64,
            Property::Int(v) => v as f64,
            Property::UInt(v) => v as f64,
            Property::Float(v) => v as f64,
            Property::Double(v) => v,
            _ => return None,
        })
    };
    let list = |p: &Property| -> Option<Vec<i64>> {
        Some(match p {
            Property::ListChar(v) => v.iter().map(|&i| i as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&i| i as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&i| i as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&i| i as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&i| i as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&i| i as i64).collect(),
            _ => return None,
        })
    };
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| format_error(path, "PLY", "no `vertex` element"))?;
    let mut mesh = RawMesh::default();
    for (index, vertex) in vertices.iter().enumerate() {
        let mut xyz = [0.0; 3];
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            xyz[axis] = vertex
                .get(*name)
                .and_then(scalar)
                .ok_or_else(|| {
                    format_error(path, "PLY", format!("vertex {} of the file (counting from 1) has no numeric `{name}` property", index + 1))
                })?;
        }
        mesh.positions.push(DVec3::from_array(xyz));
    }
    let faces = ply
        .payload
        .get("face")
        .ok_or_else(|| format_error(path, "PLY", "no `face` element"))?;
    // The index list's declaration, checked once rather than per face.
    let declared = ply.header.elements.get("face").and_then(|face| {
        ["vertex_indices", "vertex_index"]
            .iter()
            .find_map(|name| face.properties.get(*name).map(|p| (*name, p.data_type.clone())))
    });
    let example = "e.g. `property list uchar int vertex_indices`";
    match declared {
        None => {
            return Err(format_error(
                path,
                "PLY",
                format!("the `face` element has no `vertex_indices` (or `vertex_index`) property; declare the corners, {example}"),
            ))
        }
        Some((name, ply_rs::ply::PropertyType::List(_, item)))
            if matches!(item, ply_rs::ply::ScalarType::Float | ply_rs::ply::ScalarType::Double) =>
        {
            return Err(format_error(
                path,
                "PLY",
                format!(
                    "the header declares `{name}` a list of {}; vertex indices are integers, {example}",
                    format!("{item:?}").to_lowercase()
                ),
            ))
        }
        Some((name, ply_rs::ply::PropertyType::Scalar(_))) => {
            return Err(format_error(
                path,
                "PLY",
                format!("the header declares `{name}` a single number; a face's corners are a list, {example}"),
            ))
        }
        Some(_) => {}
    }
    let count = mesh.positions.len() as i64;
    for (index, face) in faces.iter().enumerate() {
        let corners = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .and_then(list)
            .ok_or_else(|| format_error(path, "PLY", format!("{} has no `vertex_indices` list", ply_face(bytes, index))))?;
        if let Some(&bad) = corners.iter().find(|&&i| i < 0 || i >= count) {
            return Err(format_error(
                path,
                "PLY",
                format!(
                    "{} refers to vertex index {bad}, but there are {count} vertices, indexed 0 to {}",
                    ply_face(bytes, index),
                    count - 1
                ),
            ));
        }
        // Dropped unsaid, an edge or a point would leave a hole where a face was.
        if corners.len() < 3 {
            return Err(format_error(
                path,
                "PLY",
                format!("{} has {} corners; a face needs 3 or more (edges and points belong in other elements)", ply_face(bytes, index), corners.len()),
            ));
        }
        for k in 1..corners.len() - 1 {
            mesh.triangles
                .push([corners[0] as u32, corners[k] as u32, corners[k + 1] as u32]);
        }
    }
    Ok(mesh)
}

/// One named mesh of a glTF scene, with its node transform applied.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedPart {
    /// The glTF mesh name (or the node name, or `mesh N`).
    pub name: String,
    pub mesh: RawMesh,
}

/// Reads and validates a glTF or GLB file. gltf-json 1.4's validation
/// indexes a primitive's POSITION accessor without a bounds check, so a
/// file naming a missing accessor would panic there: that one reference is
/// checked first and named.
fn parse_gltf(path: &Path, bytes: &[u8]) -> Result<gltf::Gltf, ImportError> {
    let unchecked = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| {
        use gltf::binary::Error as Glb;
        let said = match &e {
            // Otherwise "could not completely read the object".
            gltf::Error::Binary(Glb::Length { .. } | Glb::ChunkLength { .. } | Glb::Io(_)) | gltf::Error::Io(_)
                if bytes.starts_with(b"glTF") =>
            {
                format!("the GLB ends before the length its header declares (a truncated copy, or a wrong length field: {e})")
            }
            gltf::Error::Binary(Glb::Version(v)) => {
                format!("it is binary glTF version {v}, and Carus reads glTF 2.0; export it as glTF 2.0 (.glb or .gltf)")
            }
            _ => e.to_string(),
        };
        format_error(path, "glTF", said)
    })?;
    let root = unchecked.document.as_json();
    if !root.asset.version.starts_with("2.") {
        return Err(format_error(
            path,
            "glTF",
            format!("it is glTF {}, and Carus reads glTF 2.0; export it as glTF 2.0 (.glb or .gltf)", root.asset.version),
        ));
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
            if let Some(accessor) = primitive.attributes.get(&position) {
                if accessor.value() >= root.accessors.len() {
                    return Err(format_error(
                        path,
                        "glTF",
                        format!(
                            "primitive {p} of mesh {m}: POSITION names accessor {}, but the file has {} \
                             accessors",
                            accessor.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let blob = unchecked.blob;
    let document = gltf::Document::from_json(unchecked.document.into_json())
        .map_err(|e| format_error(path, "glTF", e.to_string().replace("Index out of bounds", "names an item past the end of its list")))?;
    Ok(gltf::Gltf { document, blob })
}

/// glTF 2.0 (`.gltf` JSON with embedded or neighbouring buffers, or `.glb`):
/// every triangle primitive of every mesh reached from the default scene,
/// each transformed by its node's world transform. Parts keep their names.
pub fn parse_gltf_parts(path: &Path, bytes: &[u8]) -> Result<Vec<NamedPart>, ImportError> {
    let gltf = parse_gltf(path, bytes)?;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for buffer in gltf.document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or_else(|| format_error(path, "glTF", "buffer refers to a GLB binary chunk that is missing"))?,
            gltf::buffer::Source::Uri(uri) => read_uri(path, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(format_error(
                path,
                "glTF",
                format!(
                    "buffer {} holds {} bytes, fewer than the {} declared",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }

    let parents = check_node_graph(path, &gltf.document)?;
    let mut parts = Vec::new();
    let scene = gltf.document.default_scene().or_else(|| gltf.document.scenes().next());
    let roots: Vec<gltf::Node> = match scene {
        Some(scene) => scene.nodes().collect(),
        None => gltf.document.nodes().filter(|n| parents[n.index()].is_none()).collect(),
    };
    // The graph is a forest (checked above), so each node is met once and
    // the stack holds at most one entry per node.
    let mut reached = vec![false; parents.len()];
    let mut stack: Vec<(gltf::Node, DMat4)> = roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[node.index()], true) {
            return Err(format_error(
                path,
                "glTF",
                format!(
                    "node {} is reached twice from the scene: list only root nodes in the scene's `nodes`",
                    node.index()
                ),
            ));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(|v| v as f64)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            let name = mesh
                .name()
                .or(node.name())
                .map(str::to_owned)
                .unwrap_or_else(|| format!("mesh {}", mesh.index()));
            let mut raw = RawMesh::default();
            let mirrored = world.determinant() < 0.0;
            for primitive in mesh.primitives() {
                let (m, p) = (mesh.index(), primitive.index());
                // Strips and fans are surfaces this reader would drop; points and lines are none.
                match primitive.mode() {
                    gltf::mesh::Mode::Triangles => {}
                    mode @ (gltf::mesh::Mode::TriangleStrip | gltf::mesh::Mode::TriangleFan) => {
                        return Err(format_error(
                            path,
                            "glTF",
                            format!("primitive {p} of mesh {m} is drawn as {mode:?}, and Carus reads triangle lists; export with the mesh triangulated (e.g. Blender's glTF exporter does)"),
                        ))
                    }
                    _ => continue,
                }
                // gltf's reader yields nothing for an accessor of the wrong
                // type or outside its buffer: check them first, and name them.
                let position = primitive.get(&gltf::Semantic::Positions);
                if let Some(accessor) = &position {
                    let named = format!("POSITION of primitive {p} of mesh {m}");
                    check_accessor(path, accessor, AccessorRole::Positions, &named)?;
                }
                if let Some(accessor) = &primitive.indices() {
                    check_accessor(path, accessor, AccessorRole::Indices, &format!("indices of primitive {p} of mesh {m}"))?;
                }
                let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let unreadable = |what: &str| {
                    format_error(path, "glTF", format!("the {what} of primitive {p} of mesh {m} cannot be read"))
                };
                let positions = match (reader.read_positions(), position) {
                    (Some(positions), _) => positions,
                    (None, None) => continue,
                    (None, Some(_)) => return Err(unreadable("POSITION")),
                };
                let base = raw.positions.len() as u32;
                raw.positions.extend(
                    positions.map(|p| world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))),
                );
                let count = raw.positions.len() as u32 - base;
                let indices: Vec<u32> = match (reader.read_indices(), primitive.indices()) {
                    (Some(indices), _) => indices.into_u32().collect(),
                    (None, None) => (0..count).collect(),
                    (None, Some(_)) => return Err(unreadable("indices")),
                };
                if !indices.len().is_multiple_of(3) {
                    return Err(format_error(
                        path,
                        "glTF",
                        format!(
                            "primitive {p} of mesh {m} has {} corners, not a whole number of triangles \
                             (a multiple of 3)",
                            indices.len()
                        ),
                    ));
                }
                if let Some(&bad) = indices.iter().find(|&&i| i >= count) {
                    return Err(format_error(
                        path,
                        "glTF",
                        format!("mesh `{name}` refers to vertex {bad} of {count}"),
                    ));
                }
                raw.triangles.extend(indices.chunks_exact(3).map(|t| {
                    let t = [base + t[0], base + t[1], base + t[2]];
                    if mirrored {
                        [t[0], t[2], t[1]]
                    } else {
                        t
                    }
                }));
            }
            parts.push(NamedPart { name, mesh: raw });
        }
        stack.extend(node.children().map(|child| (child, world)));
    }
    // Scene order, not stack order.
    parts.reverse();
    Ok(parts)
}

/// The parent of each node, after checking that the node graph is a forest:
/// a node with two parents, or one that is its own ancestor, would have the
/// scene walked without end (a cycle) or exponentially often (shared
/// children), so both are refused with the nodes named.
fn check_node_graph(path: &Path, document: &gltf::Document) -> Result<Vec<Option<usize>>, ImportError> {
    let count = document.nodes().len();
    let mut parents: Vec<Option<usize>> = vec![None; count];
    for node in document.nodes() {
        for child in node.children() {
            let c = child.index();
            if let Some(other) = parents[c].replace(node.index()) {
                let message = if other == node.index() {
                    format!("node {other} lists node {c} twice among its `children`")
                } else {
                    format!("node {c} is a child of both node {other} and node {}; a node has one parent", node.index())
                };
                return Err(format_error(path, "glTF", message));
            }
        }
    }
    // Walk up from every node; with one parent each, a walk that comes back
    // to a node of its own path has found a cycle. O(nodes).
    const UNSEEN: usize = usize::MAX;
    let mut walked_from = vec![UNSEEN; count];
    for start in 0..count {
        let mut node = Some(start);
        while let Some(n) = node {
            if walked_from[n] == start {
                let mut cycle = vec![n];
                let mut up = parents[n];
                while let Some(u) = up.filter(|&u| u != n) {
                    cycle.push(u);
                    up = parents[u];
                }
                cycle.push(n);
                // Written from ancestor to descendant, as `children` go.
                let cycle: Vec<String> = cycle.iter().rev().map(usize::to_string).collect();
                return Err(format_error(
                    path,
                    "glTF",
                    format!(
                        "node {n} is its own ancestor: the scene graph has a cycle ({}); remove the child that \
                         leads back",
                        cycle.join(" -> ")
                    ),
                ));
            }
            if walked_from[n] != UNSEEN {
                break;
            }
            walked_from[n] = start;
            node = parents[n];
        }
    }
    Ok(parents)
}

/// The glTF names of a component type and an element type.
fn gltf_type_name(accessor: &gltf::Accessor) -> String {
    use gltf::accessor::{DataType, Dimensions};
    let component = match accessor.data_type() {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    };
    let element = match accessor.dimensions() {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    };
    format!("{element} of {component}")
}

/// What a primitive reads an accessor for.
#[derive(Clone, Copy, PartialEq)]
enum AccessorRole {
    Positions,
    Indices,
}

/// Checks an accessor a primitive reads (`named` in messages, e.g.
/// "POSITION of primitive 0 of mesh 0"): the type its role needs (POSITION
/// a VEC3 of FLOAT, indices a SCALAR of unsigned integers), and its
/// elements inside its bufferView and the view inside its buffer (declared
/// `byteLength`, which the buffer's data was checked to hold).
fn check_accessor(path: &Path, accessor: &gltf::Accessor, role: AccessorRole, named: &str) -> Result<(), ImportError> {
    use gltf::accessor::{DataType, Dimensions};
    let a = accessor.index();
    let refuse = |message: String| Err(format_error(path, "glTF", format!("accessor {a} ({named}) {message}")));
    let position = role == AccessorRole::Positions;
    let fits = if position {
        accessor.dimensions() == Dimensions::Vec3 && accessor.data_type() == DataType::F32
    } else {
        accessor.dimensions() == Dimensions::Scalar
            && matches!(accessor.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
    };
    if !fits {
        let needed = if position {
            "a VEC3 of FLOAT (componentType 5126)"
        } else {
            "a SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT"
        };
        return refuse(format!("is a {}, but it must be {needed}", gltf_type_name(accessor)));
    }
    let size = accessor.size();
    let mut ranges: Vec<(gltf::buffer::View, usize, usize, usize, usize, &str)> = Vec::new();
    if let Some(view) = accessor.view() {
        ranges.push((view.clone(), accessor.offset(), view.stride().unwrap_or(size), accessor.count(), size, ""));
    }
    if let Some(sparse) = accessor.sparse() {
        let (indices, values) = (sparse.indices(), sparse.values());
        let index_size = match indices.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        ranges.push((indices.view(), indices.offset(), index_size, sparse.count(), index_size, "sparse indices "));
        ranges.push((values.view(), values.offset(), size, sparse.count(), size, "sparse values "));
    }
    for (view, offset, stride, count, size, which) in ranges {
        let v = view.index();
        if stride < size {
            return refuse(format!(
                "reads {size}-byte elements, but bufferView {v} has a byteStride of {stride}; fix `byteStride`"
            ));
        }
        let end = match count {
            0 => offset,
            _ => offset.saturating_add(stride.saturating_mul(count - 1)).saturating_add(size),
        };
        if end > view.length() {
            return refuse(format!(
                "runs past its bufferView {v}: its {which}{count} elements from byteOffset {offset} need {end} \
                 bytes, the view holds {}; fix the accessor's `count` or `byteOffset`, or the view's `byteLength`",
                view.length()
            ));
        }
        let buffer = view.buffer();
        let view_end = view.offset().saturating_add(view.length());
        if view_end > buffer.length() {
            return Err(format_error(
                path,
                "glTF",
                format!(
                    "bufferView {v} runs past buffer {}: it ends at byte {view_end} (byteOffset {} + byteLength {}), \
                     the buffer's byteLength is {}; fix the view's `byteOffset` or `byteLength`",
                    buffer.index(),
                    view.offset(),
                    view.length(),
                    buffer.length()
                ),
            ));
        }
    }
    Ok(())
}

/// All parts as one mesh.
fn merge_parts(parts: Vec<NamedPart>) -> RawMesh {
    let mut mesh = RawMesh::default();
    for part in parts {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(part.mesh.positions);
        mesh.triangles
            .extend(part.mesh.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    mesh
}

/// A buffer URI: embedded base64 data, or a file beside the glTF.
fn read_uri(path: &Path, uri: &str) -> Result<Vec<u8>, ImportError> {
    if let Some(data) = uri.strip_prefix("data:") {
        let (_, encoded) = data
            .split_once(";base64,")
            .ok_or_else(|| format_error(path, "glTF", "only base64 data URIs are supported"))?;
        return base64::engine::general_purpose::STANDARD
            .decode(encoded)
            .map_err(|e| format_error(path, "glTF", format!("embedded buffer: {e}")));
    }
    if uri.contains("://") {
        return Err(format_error(
            path,
            "glTF",
            format!("buffer `{uri}` is on the network, which Carus does not fetch; download it beside the glTF and name it by its file name, or export a .glb"),
        ));
    }
    let file = path.parent().unwrap_or(Path::new(".")).join(uri);
    carus_io::input::read_bytes(&file).map_err(|source| {
        format_error(
            path,
            "glTF",
            format!("its buffer `{uri}` ({}) cannot be read: {source}; keep the .bin beside the .gltf, or export a .glb", file.display()),
        )
    })
}
