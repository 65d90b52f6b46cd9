//! VTK input (legacy `.vtk` unstructured grid, XML `.vtu` in ascii, binary
//! or appended encoding) and VTU frame output, through vtkio (pinned
//! `=0.7.0-rc2`, DESIGN.md).
//!
//! Sets in VTK files: VTK has no named sets, so a one-component integer
//! cell-data array `A` turns value `v >= 0` into the element set (volume
//! cells) or surface (triangle and quad cells) `A_v`, and a one-component
//! integer point-data array `A` makes the node set `A` of the points where
//! it is not zero. Node and element ids in messages are 0-based VTK point
//! and cell indices.

use std::collections::BTreeMap;
use std::path::Path;

use carus_fem::{ElementKind, Mesh};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    Piece, ScalarType, UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};
use vtkio::xml::Compressor;

use crate::builder::{MeshBuilder, MeshFile};
use crate::error::{ReadError, WriteError};
use crate::vtk_compat::{
    compressed_size_fault, declared_arrays, legacy_ascii_fault, legacy_type_names, raw_appended_to_base64, with_time_value,
    without_component_ranges,
};

/// Reads a legacy `.vtk` or XML `.vtu` unstructured grid.
pub fn read_vtk(path: &Path) -> Result<MeshFile, ReadError> {
    let piece = load_unstructured(path)?;
    mesh_from_piece(path, &piece)
}

/// A data array read back from a VTK file, as `f64`.
#[derive(Debug, Clone, PartialEq)]
pub struct VtkArray {
    /// Components per point or cell (3 for a vector).
    pub components: usize,
    /// `components` values per point or cell.
    pub values: Vec<f64>,
}

/// The point and cell data arrays of a VTK file by name (for reading
/// results back, and for tests).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct VtkArrays {
    /// The points' x, y, z as the file holds them.
    pub points: Vec<[f64; 3]>,
    pub point: BTreeMap<String, VtkArray>,
    pub cell: BTreeMap<String, VtkArray>,
}

/// Reads every point and cell data array of a `.vtk` or `.vtu` file.
pub fn read_vtk_arrays(path: &Path) -> Result<VtkArrays, ReadError> {
    let piece = load_unstructured(path)?;
    let points = piece.points.cast_into::<f64>().unwrap_or_default();
    Ok(VtkArrays {
        points: points.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        point: arrays(&piece.data.point),
        cell: arrays(&piece.data.cell),
    })
}

fn content_error(path: &Path, problem: impl Into<String>, fix: &str) -> ReadError {
    ReadError::Content {
        path: path.to_path_buf(),
        problem: problem.into(),
        fix: fix.to_string(),
    }
}

/// vtkio's error, in words where its text is known (it names no line,
/// and a size mismatch reads as a Rust struct), with its own text kept.
fn in_words(vtkio: &str) -> String {
    let field = |name: &str| -> Option<&str> {
        let start = vtkio.find(&format!("{name}: "))? + name.len() + 2;
        let rest = &vtkio[start..];
        match rest.strip_prefix('"') {
            // A quoted name runs to its closing quote, spaces and all.
            Some(quoted) => quoted.split('"').next(),
            None => Some(&rest[..rest.find([',', ' ', '}']).unwrap_or(rest.len())]),
        }
    };
    let said = if vtkio.contains("DataArraySizeMismatch") {
        let array = match field("name") {
            Some("") | None => "the points' coordinate array".to_string(),
            Some(name) => format!("the data array `{name}`"),
        };
        format!(
            "{array} holds {} values where the file's counts call for {}",
            field("actual").unwrap_or("?"),
            field("expected").unwrap_or("?")
        )
    } else if vtkio.contains("Base64Decode") {
        "a base64 data array holds a character that is not base64".to_string()
    } else if vtkio.contains("Decompress") || vtkio.contains("deflate") {
        "a compressed data array cannot be decompressed".to_string()
    } else if let Some(code) = vtkio.split("InvalidCellType(").nth(1).and_then(|r| r.split(')').next()) {
        format!("a cell has type {code}, which is no VTK cell type")
    } else if vtkio.contains("DataSetMismatch") {
        "the file holds another kind of VTK data set than an unstructured grid (a PolyData or an image)".to_string()
    } else if vtkio.contains("InvalidDataFormat") {
        "a data array's values do not fit its declared type or format (a negative index, a format it does not name)".to_string()
    } else if vtkio.contains("InvalidXml") || vtkio.contains("IllFormed") {
        "the XML is not well formed (a tag not closed, or closed by another)".to_string()
    } else if vtkio.starts_with("Parse error") {
        "the legacy file stops early or has a line that is not what its header announces".to_string()
    } else {
        return format!("({vtkio})");
    };
    format!("{said} (the VTK reader: {vtkio})")
}

const RESAVE_FIX: &str = "open it in ParaView and save it again as an unstructured grid (.vtu), or check the file is complete";

fn load_unstructured(path: &Path) -> Result<UnstructuredGridPiece, ReadError> {
    let bytes = crate::input::read_bytes(path).map_err(|cause| ReadError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let bytes = match extension.as_str() {
        "vtk" => legacy_type_names(&bytes).into_owned(),
        "vtu" => {
            let bytes = raw_appended_to_base64(&bytes).map_err(|problem| content_error(path, problem, RESAVE_FIX))?;
            if let Some(problem) = compressed_size_fault(&bytes) {
                return Err(content_error(path, problem, RESAVE_FIX));
            }
            bytes.into_owned()
        }
        _ => {
            return Err(ReadError::UnknownFormat {
                path: path.to_path_buf(),
                extension,
            })
        }
    };
    // vtkio 0.7.0-rc2 still slices and unwraps on some malformed input;
    // a panic there becomes this file's error instead of ending the program.
    let parsed = catch_quietly(|| {
        if extension == "vtk" {
            Vtk::parse_legacy_be(&bytes[..])
        } else {
            Vtk::parse_xml(&bytes[..])
        }
    });
    let vtk = match parsed {
        Ok(Ok(vtk)) => vtk,
        Ok(Err(e)) => {
            let problem = format!("not a readable VTK file: {}", in_words(&e.to_string()));
            return Err(match legacy_ascii_fault(&bytes).filter(|_| extension == "vtk") {
                Some((line, fault)) => ReadError::Syntax {
                    path: path.to_path_buf(),
                    line,
                    problem: format!("{fault} ({problem})"),
                    fix: "correct that line, or export the mesh again".into(),
                },
                None => content_error(path, problem, RESAVE_FIX),
            });
        }
        Err(_) => {
            return Err(content_error(
                path,
                "not a readable VTK file (malformed data arrays)",
                RESAVE_FIX,
            ))
        }
    };
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(content_error(
            path,
            format!(
                "the data set is {}, not an unstructured grid",
                data_set_name(&vtk.data)
            ),
            // Converted, a surface would be triangles, which hold no volume to simulate.
            match vtk.data {
                DataSet::PolyData { .. } => "mesh the volume the surface encloses with tetrahedra (Gmsh, TetGen) and save that as .vtu",
                _ => "convert it to an unstructured grid (ParaView: Append Datasets, then save as .vtu)",
            },
        ));
    };
    let piece_count = pieces.len();
    match pieces.into_iter().next() {
        Some(Piece::Inline(piece)) if piece_count == 1 => {
            if extension == "vtu" {
                check_nothing_dropped(path, &bytes, &piece)?;
            }
            Ok(*piece)
        }
        Some(Piece::Inline(_)) => Err(content_error(
            path,
            format!("the grid has {piece_count} pieces"),
            "merge them into one (ParaView: Merge Blocks) and save again",
        )),
        _ => Err(content_error(
            path,
            "the grid's data lives in other files (a parallel or empty data set)",
            "save it as one serial .vtu file (ParaView: Merge Blocks, then Save Data)",
        )),
    }
}

/// Every point and cell data array the `.vtu` declares must have been
/// read: vtkio drops one it cannot read, and a set array lost that way
/// would read as a set the mesh does not have.
fn check_nothing_dropped(
    path: &Path,
    bytes: &[u8],
    piece: &UnstructuredGridPiece,
) -> Result<(), ReadError> {
    let [point, cell] = declared_arrays(bytes);
    let kept = |attributes: &[Attribute], name: &str| {
        attributes.iter().any(|a| match a {
            Attribute::DataArray(array) => array.name == name,
            Attribute::Field { data_array, .. } => data_array.iter().any(|f| f.name == name),
        })
    };
    let sections = [
        ("point", "points", piece.num_points(), point, &piece.data.point),
        ("cell", "cells", piece.cells.types.len(), cell, &piece.data.cell),
    ];
    for (kind, counted, count, declared, attributes) in sections {
        let Some(lost) = declared.iter().find(|a| !kept(attributes, &a.name)) else {
            continue;
        };
        let expected = count * lost.components;
        let problem = match lost.ascii_values {
            Some(found) if found != expected => format!(
                "the {kind} data array `{}` holds {found} values for {count} {counted} ({expected} expected with {} per {kind})",
                lost.name, lost.components
            ),
            _ => format!(
                "the {kind} data array `{}` cannot be read: its data is damaged or does not hold {} values per {kind} for the {count} {counted}",
                lost.name, lost.components
            ),
        };
        return Err(content_error(path, problem, RESAVE_FIX));
    }
    Ok(())
}

fn data_set_name(data: &DataSet) -> &'static str {
    match data {
        DataSet::ImageData { .. } => "image data",
        DataSet::StructuredGrid { .. } => "a structured grid",
        DataSet::RectilinearGrid { .. } => "a rectilinear grid",
        DataSet::UnstructuredGrid { .. } => "an unstructured grid",
        DataSet::PolyData { .. } => "poly data (a surface)",
        DataSet::Field { .. } => "a field",
    }
}

fn arrays(attributes: &[Attribute]) -> BTreeMap<String, VtkArray> {
    let mut out = BTreeMap::new();
    for attribute in attributes {
        match attribute {
            Attribute::DataArray(array) => {
                if let Some(values) = array.data.cast_into::<f64>() {
                    let components = array.elem.num_comp().max(1) as usize;
                    out.insert(array.name.clone(), VtkArray { components, values });
                }
            }
            Attribute::Field { data_array, .. } => {
                for array in data_array {
                    if let Some(values) = array.data.cast_into::<f64>() {
                        let components = array.elem.max(1) as usize;
                        out.insert(array.name.clone(), VtkArray { components, values });
                    }
                }
            }
        }
    }
    out
}

/// One-component integer arrays (the ones that can name sets).
fn integer_arrays(attributes: &[Attribute]) -> Vec<(String, Vec<i64>)> {
    let is_integer = |t: ScalarType| {
        matches!(
            t,
            ScalarType::U8
                | ScalarType::I8
                | ScalarType::U16
                | ScalarType::I16
                | ScalarType::U32
                | ScalarType::I32
                | ScalarType::U64
                | ScalarType::I64
        )
    };
    let mut out = Vec::new();
    let mut take = |name: &str, components: u32, data: &IOBuffer| {
        if components == 1 && is_integer(data.scalar_type()) {
            if let Some(values) = data.cast_into::<i64>() {
                out.push((name.to_string(), values));
            }
        }
    };
    for attribute in attributes {
        match attribute {
            Attribute::DataArray(array) => take(&array.name, array.elem.num_comp(), &array.data),
            Attribute::Field { data_array, .. } => {
                for array in data_array {
                    take(&array.name, array.elem, &array.data);
                }
            }
        }
    }
    out
}

/// Each cell's point indices, checked against the cell count.
fn cell_points(path: &Path, cells: &Cells) -> Result<Vec<Vec<u64>>, ReadError> {
    let count = cells.types.len();
    let mut out = Vec::with_capacity(count);
    match &cells.cell_verts {
        VertexNumbers::Legacy { vertices, .. } => {
            let mut i = 0;
            while i < vertices.len() {
                let n = vertices[i] as usize;
                let Some(points) = vertices.get(i + 1..i + 1 + n) else {
                    return Err(content_error(
                        path,
                        format!(
                            "cell {} lists more points than the CELLS section holds",
                            out.len()
                        ),
                        RESAVE_FIX,
                    ));
                };
                out.push(points.iter().map(|&p| p as u64).collect());
                i += 1 + n;
            }
        }
        VertexNumbers::XML {
            connectivity,
            offsets,
        } => {
            // Offsets end each cell; some writers add a leading zero.
            let offsets = if offsets.len() == count + 1 && offsets.first() == Some(&0) {
                &offsets[1..]
            } else {
                &offsets[..]
            };
            let mut start = 0usize;
            for &end in offsets {
                let end = end as usize;
                let Some(points) = connectivity.get(start..end) else {
                    let problem = match end < start {
                        true => format!("cell {} has offset {end}, before the previous cell's end ({start}): the offsets must not decrease", out.len()),
                        false => format!(
                            "cell {} has offset {end}, outside the connectivity array ({} entries)",
                            out.len(),
                            connectivity.len()
                        ),
                    };
                    return Err(content_error(path, problem, RESAVE_FIX));
                };
                out.push(points.to_vec());
                start = end;
            }
        }
    }
    if out.len() != count {
        return Err(content_error(
            path,
            format!(
                "{} cells have point lists but {count} have types",
                out.len()
            ),
            RESAVE_FIX,
        ));
    }
    Ok(out)
}

fn mesh_from_piece(path: &Path, piece: &UnstructuredGridPiece) -> Result<MeshFile, ReadError> {
    let Some(points) = piece.points.cast_into::<f64>().filter(|p| p.len() % 3 == 0) else {
        return Err(content_error(
            path,
            "the points are not x, y, z numbers",
            RESAVE_FIX,
        ));
    };
    let mut builder = MeshBuilder::new(path);
    for (i, p) in points.chunks_exact(3).enumerate() {
        builder
            .add_node(i as u64, [p[0], p[1], p[2]])
            .map_err(|problem| content_error(path, problem, "fix the point's coordinates"))?;
    }
    let cells = cell_points(path, &piece.cells)?;
    let point_count = (points.len() / 3) as u64;
    let mut is_surface = vec![false; cells.len()];
    let mut is_volume = vec![false; cells.len()];
    for (c, (cell_type, nodes)) in piece.cells.types.iter().zip(&cells).enumerate() {
        if let Some(&p) = nodes.iter().find(|&&p| p >= point_count) {
            return Err(content_error(
                path,
                format!("cell {c} names point {p}, but the file has {point_count} points"),
                RESAVE_FIX,
            ));
        }
        let expected = match cell_type {
            CellType::Hexahedron | CellType::Voxel => 8,
            CellType::Tetra | CellType::Quad | CellType::Pixel => 4,
            CellType::Triangle => 3,
            CellType::Vertex | CellType::PolyVertex | CellType::Line | CellType::PolyLine => {
                builder.note(format!(
                    "skipped {cell_type:?} cells (only volumes and surfaces are read)"
                ));
                continue;
            }
            other => {
                return Err(content_error(
                    path,
                    format!("cell {c} is a {other:?}, which Carus does not solve"),
                    "mesh with first-order hexahedra or tetrahedra only",
                ))
            }
        };
        if nodes.len() != expected {
            return Err(content_error(
                path,
                format!(
                    "cell {c} ({cell_type:?}) has {} points instead of {expected}",
                    nodes.len()
                ),
                RESAVE_FIX,
            ));
        }
        let id = c as u64;
        match cell_type {
            CellType::Hexahedron => {
                is_volume[c] = true;
                builder.add_hexahedron(id, std::array::from_fn(|i| nodes[i]), None)
            }
            // A voxel numbers its top and bottom faces in x-y raster order.
            CellType::Voxel => {
                is_volume[c] = true;
                builder.add_hexahedron(id, [0, 1, 3, 2, 4, 5, 7, 6].map(|i| nodes[i]), None)
            }
            CellType::Tetra => {
                is_volume[c] = true;
                builder.add_tetrahedron(id, std::array::from_fn(|i| nodes[i]), None)
            }
            _ => {
                is_surface[c] = true;
                builder.ignore_element(id);
            }
        }
    }
    // An array of the wrong length is a damaged file, not an array to skip:
    // skipped, its sets would be reported missing from a file that has them.
    let wrong_length = |what: &str, name: &str, found: usize, expected: u64| {
        content_error(
            path,
            format!("the {what} data array `{name}` holds {found} values for {expected} {what}s"),
            RESAVE_FIX,
        )
    };
    for (name, values) in integer_arrays(&piece.data.cell) {
        if values.len() != cells.len() {
            return Err(wrong_length("cell", &name, values.len(), cells.len() as u64));
        }
        for (c, &value) in values.iter().enumerate() {
            if value < 0 {
                continue;
            }
            let set = format!("{name}_{value}");
            if is_volume[c] {
                builder.add_to_element_set(&set, c as u64);
            } else if is_surface[c] {
                let nodes = &cells[c];
                let polygon: Vec<u64> = if piece.cells.types[c] == CellType::Pixel {
                    [0, 1, 3, 2].map(|i| nodes[i]).to_vec()
                } else {
                    nodes.clone()
                };
                builder.add_surface_polygon(&set, &polygon);
            }
        }
    }
    for (name, values) in integer_arrays(&piece.data.point) {
        if values.len() as u64 != point_count {
            return Err(wrong_length("point", &name, values.len(), point_count));
        }
        for (p, &value) in values.iter().enumerate() {
            if value != 0 {
                builder.add_to_node_set(&name, p as u64);
            }
        }
    }
    builder.finish()
}

/// The fields of one output frame: per node and per element.
#[derive(Debug, Clone, Copy)]
pub struct FrameFields<'a> {
    /// Nodal displacement from the reference configuration, metres.
    pub displacement_m: &'a [[f64; 3]],
    /// Von Mises equivalent Cauchy stress per element, Pa.
    pub von_mises_pa: &'a [f64],
    /// Largest principal stretch per element.
    pub max_principal_stretch: &'a [f64],
    /// Volume ratio J = det F per element.
    pub jacobian: &'a [f64],
    /// The simulated time of the frame, s, written as the `TimeValue`
    /// field data ParaView reads when a frame is opened without its PVD;
    /// `None` for a mesh at rest.
    pub time_s: Option<f64>,
}

/// Writes one frame as a `.vtu` ([`write_piece`]'s encoding): the reference
/// points with point data `displacement` (so ParaView's Warp By Vector
/// shows the deformed shape) and cell data `von_mises_pa`,
/// `max_principal_stretch`, `jacobian`, and, when the mesh has element
/// sets, `element_set` (index into the set names in sorted order, -1 for
/// none; the first set in that order where sets overlap).
pub fn write_vtu(path: &Path, mesh: &Mesh, frame: &FrameFields) -> Result<(), WriteError> {
    let shape_error = |problem: String| WriteError::Shape {
        path: path.to_path_buf(),
        problem,
    };
    let elements = mesh.element_count();
    if frame.displacement_m.len() != mesh.node_count() {
        return Err(shape_error(format!(
            "{} displacements for {} nodes",
            frame.displacement_m.len(),
            mesh.node_count()
        )));
    }
    for (name, values) in [
        ("von_mises_pa", frame.von_mises_pa),
        ("max_principal_stretch", frame.max_principal_stretch),
        ("jacobian", frame.jacobian),
    ] {
        if values.len() != elements {
            return Err(shape_error(format!(
                "{} values of {name} for {elements} elements",
                values.len()
            )));
        }
    }
    let per_element = mesh.kind.nodes_per_element();
    let cell_type = match mesh.kind {
        ElementKind::H8 => CellType::Hexahedron,
        ElementKind::T4 => CellType::Tetra,
    };
    let points: Vec<f64> = mesh.nodes.iter().flatten().copied().collect();
    let displacement: Vec<f64> = frame.displacement_m.iter().flatten().copied().collect();
    let scalar = |name: &str, values: Vec<f64>| {
        Attribute::DataArray(DataArray {
            name: name.to_string(),
            elem: ElementType::Scalars {
                num_comp: 1,
                lookup_table: None,
            },
            data: IOBuffer::F64(values),
        })
    };
    let mut cell_data = vec![
        scalar("von_mises_pa", frame.von_mises_pa.to_vec()),
        scalar(
            "max_principal_stretch",
            frame.max_principal_stretch.to_vec(),
        ),
        scalar("jacobian", frame.jacobian.to_vec()),
    ];
    if !mesh.element_sets.is_empty() {
        let mut set_index = vec![-1i32; elements];
        for (index, members) in mesh.element_sets.values().enumerate() {
            for &e in members {
                if let Some(slot) = set_index.get_mut(e as usize).filter(|s| **s < 0) {
                    *slot = index as i32;
                }
            }
        }
        cell_data.push(Attribute::DataArray(DataArray {
            name: "element_set".into(),
            elem: ElementType::Scalars {
                num_comp: 1,
                lookup_table: None,
            },
            data: IOBuffer::I32(set_index),
        }));
    }
    write_piece(
        path,
        UnstructuredGridPiece {
            points: IOBuffer::F64(points),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: mesh.connectivity.iter().map(|&n| n as u64).collect(),
                    offsets: (1..=elements).map(|e| (e * per_element) as u64).collect(),
                },
                types: vec![cell_type; elements],
            },
            data: Attributes {
                point: vec![Attribute::DataArray(DataArray {
                    name: "displacement".into(),
                    elem: ElementType::Vectors,
                    data: IOBuffer::F64(displacement),
                })],
                cell: cell_data,
            },
        },
        frame.time_s,
    )
}

/// Writes a triangle surface as a `.vtu` of triangle cells, with no data
/// arrays: a rigid body's shape where it is, at `time_s` when it is a
/// frame of a series ([`FrameFields::time_s`]).
pub fn write_triangle_vtu(
    path: &Path,
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    time_s: Option<f64>,
) -> Result<(), WriteError> {
    if let Some(t) = triangles.iter().position(|t| t.iter().any(|&n| n as usize >= points.len())) {
        return Err(WriteError::Shape {
            path: path.to_path_buf(),
            problem: format!("triangle {t} names a point past the {} given", points.len()),
        });
    }
    write_piece(
        path,
        UnstructuredGridPiece {
            points: IOBuffer::F64(points.iter().flatten().copied().collect()),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: triangles.iter().flatten().map(|&n| u64::from(n)).collect(),
                    offsets: (1..=triangles.len()).map(|t| 3 * t as u64).collect(),
                },
                types: vec![CellType::Triangle; triangles.len()],
            },
            data: Attributes::new(),
        },
        time_s,
    )
}

/// Writes one unstructured grid as a `.vtu`: binary, zlib-compressed,
/// base64 inline, which ParaView, VTK and meshio read, at a fraction of
/// the size of ascii (a run writes one per body per frame), with its
/// `TimeValue` when it has a time.
fn write_piece(path: &Path, piece: UnstructuredGridPiece, time_s: Option<f64>) -> Result<(), WriteError> {
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(piece),
    };
    let vtk_error = |e: vtkio::Error| WriteError::Vtk {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let xml = vtk
        .try_into_xml_format(Compressor::ZLib, 6)
        .map_err(|e| vtk_error(e.into()))?;
    let mut bytes = Vec::new();
    xml.write(&mut bytes).map_err(|e| vtk_error(e.into()))?;
    // vtkio writes text (base64 inline), so this is always UTF-8.
    let bytes = match String::from_utf8(bytes) {
        Ok(text) => {
            let text = without_component_ranges(text);
            match time_s {
                Some(t) => with_time_value(text, t),
                None => text,
            }
            .into_bytes()
        }
        Err(not_text) => not_text.into_bytes(),
    };
    let io_error = |cause| WriteError::Io {
        path: path.to_path_buf(),
        cause,
    };
    crate::output::write_whole(path, &bytes).map_err(io_error)
}

thread_local! {
    static QUIET_PANICS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, turning a panic into `Err` without the panic's message and
/// backtrace reaching the user: the caller reports the file's error
/// instead. The process-wide hook is wrapped once and stays silent only
/// on this thread, only while `f` runs; every other panic prints as before.
fn catch_quietly<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    static WRAP_HOOK: std::sync::Once = std::sync::Once::new();
    WRAP_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET_PANICS.with(std::cell::Cell::get) {
                previous(info);
            }
        }));
    });
    QUIET_PANICS.with(|q| q.set(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET_PANICS.with(|q| q.set(false));
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::temp;


    const ASCII_VTU: &str = include_str!("../tests/data/tet_ascii.vtu");
    const LEGACY_VTK: &str = include_str!("../tests/data/tet_surface.vtk");

    #[test]
    fn reads_an_ascii_vtu_with_sets() {
        let (_dir, path) = temp("tet_ascii.vtu");
        std::fs::write(&path, ASCII_VTU).unwrap();
        let file = read_vtk(&path).unwrap();
        assert_eq!(file.mesh.kind, ElementKind::T4);
        assert_eq!(file.mesh.element_count(), 1);
        assert_eq!(file.mesh.element_sets["region_3"], vec![0]);
        assert_eq!(file.mesh.surfaces["region_5"].len(), 1);
        assert_eq!(file.mesh.node_sets["fixed"], vec![0, 1]);
    }

    /// A set array with a value too few or too many is the damaged file
    /// named, not a set silently missing.
    #[test]
    fn a_set_array_of_the_wrong_length_is_the_files_error() {
        let (_dir, path) = temp("short_sets.vtk");
        for (from, to, expected) in [
            ("CELL_DATA 3\nSCALARS tag int 1\nLOOKUP_TABLE default\n0 1 -1", "CELL_DATA 2\nSCALARS tag int 1\nLOOKUP_TABLE default\n0 1", "the cell data array `tag` holds 2 values for 3 cells"),
            ("CELL_DATA 3", "POINT_DATA 2\nSCALARS fixed int 1\nLOOKUP_TABLE default\n1 1\nCELL_DATA 3", "the point data array `fixed` holds 2 values for 4 points"),
        ] {
            assert!(LEGACY_VTK.contains(from));
            std::fs::write(&path, LEGACY_VTK.replace(from, to)).unwrap();
            let e = read_vtk(&path).expect_err("refused").to_string();
            assert!(e.contains("short_sets.vtk") && e.contains(expected) && e.contains("save it again"), "{e}");
        }
    }

    /// vtkio's parse errors name no line; in an ASCII legacy file the
    /// geometry's first bad value or short section is found and named.
    #[test]
    fn a_bad_value_in_a_legacy_file_is_named_by_its_line() {
        let (_dir, path) = temp("bad.vtk");
        for (from, to, expected) in [
            ("1 0 0\n", "nan 0 0\n", "bad.vtk:7: \"nan\" in POINTS (line 5) is not a finite number"),
            ("3 0 1 2\n", "3 0 -1 2\n", "bad.vtk:12: \"-1\" in CELLS (line 10) is not a whole number of 0 or more"),
            ("POINTS 4 double", "POINTS 1000000000 double", "bad.vtk:10: POINTS (line 5) declares 3000000000 values, but 12 come before this line"),
            ("CELL_TYPES 3\n10\n5\n3\n", "CELL_TYPES 3\n10\n5\nx\n", "bad.vtk:17: \"x\" in CELL_TYPES (line 14) is not a whole number"),
            ("CELL_TYPES 3\n10\n5\n3\n", "CELL_TYPES 3\n10\n999\n3\n", "bad.vtk:16: \"999\" in CELL_TYPES (line 14) is not a VTK cell type"),
            ("CELLS 3 12", "CELLS 3 10", "bad.vtk:14: CELLS (line 10) declares 10 values, but 12 come before this line"),
            ("0 1 -1", "0 1 99999999999", "bad.vtk:21: \"99999999999\" in SCALARS (line 19) is not a value int holds"),
            ("0 1 -1", "0 nan -1", "bad.vtk:21: \"nan\" in SCALARS (line 19) is not a whole number, as int is"),
        ] {
            assert!(LEGACY_VTK.contains(from), "{from}");
            std::fs::write(&path, LEGACY_VTK.replace(from, to)).unwrap();
            let e = read_vtk(&path).expect_err("refused").to_string();
            assert!(e.contains(expected) && e.contains("fix: correct that line"), "{e}\n  expected: {expected}");
        }
    }

    /// Offsets that run back, or past the connectivity, are named as such.
    #[test]
    fn offsets_out_of_order_or_range_are_named() {
        let (_dir, path) = temp("offsets.vtu");
        // A third cell, an edge, so that an offset can fall back mid-array.
        let three = ASCII_VTU
            .replace("NumberOfCells=\"2\"", "NumberOfCells=\"3\"")
            .replace(">3 5<", ">3 5 5<")
            .replace(">0 1 2 3 0 1 3<", ">0 1 2 3 0 1 3 0 1<")
            .replace(">10 5<", ">10 5 3<");
        for (offsets, said) in [
            ("4 2 9", "cell 1 has offset 2, before the previous cell's end (4): the offsets must not decrease"),
            ("4 12 9", "cell 1 has offset 12, outside the connectivity array (9 entries)"),
        ] {
            std::fs::write(&path, three.replace(">4 7<", &format!(">{offsets}<"))).unwrap();
            let e = read_vtk(&path).expect_err("refused").to_string();
            assert!(e.contains(said), "{e}");
        }
    }

    /// vtkio drops a data array of the wrong length without a word; the
    /// reader names it instead of reporting a set the mesh lacks.
    #[test]
    fn a_dropped_vtu_array_is_the_files_error() {
        let (_dir, path) = temp("dropped.vtu");
        for (from, to, expected) in [
            (">1 1 0 0<", ">1 1 0<", "the point data array `fixed` holds 3 values for 4 points (4 expected with 1 per point)"),
            (">3 5<", ">3 5 7<", "the cell data array `region` holds 3 values for 2 cells"),
            (
                r#"<DataArray type="Int32" Name="region" format="ascii">3 5</DataArray>"#,
                r#"<DataArray type="Int32" Name="region" format="binary">!!!!</DataArray>"#,
                "the cell data array `region` cannot be read: its data is damaged",
            ),
        ] {
            assert!(ASCII_VTU.contains(from));
            std::fs::write(&path, ASCII_VTU.replace(from, to)).unwrap();
            let e = read_vtk(&path).expect_err("refused").to_string();
            assert!(e.contains("dropped.vtu") && e.contains(expected) && e.contains("save it again"), "{e}");
        }
    }

    #[test]
    fn vtkio_errors_are_put_in_words() {
        let mismatch = "XML error: Validation error: DataArraySizeMismatch { name: \"types\", expected: 5, actual: 3 }";
        assert_eq!(in_words(mismatch), format!("the data array `types` holds 3 values where the file's counts call for 5 (the VTK reader: {mismatch})"));
        let points = "XML error: Validation error: DataArraySizeMismatch { name: \"\", expected: 27, actual: 24 }";
        assert!(in_words(points).starts_with("the points' coordinate array holds 24 values where the file's counts call for 27"));
        assert!(in_words("Parse error: Complete").starts_with("the legacy file stops early"));
        assert_eq!(in_words("something new"), "(something new)");
        for (vtkio, said) in [
            ("XML error: Validation error: InvalidCellType(99)", "a cell has type 99, which is no VTK cell type"),
            ("XML error: Validation error: DataSetMismatch", "another kind of VTK data set"),
            ("XML error: Validation error: InvalidDataFormat", "do not fit its declared type"),
            ("IO(Custom { kind: InvalidInput, error: \"corrupt deflate stream\" })", "cannot be decompressed"),
            ("XML error: InvalidXml(IllFormed(MismatchedEndTag { expected: \"Piece\", found: \"Cells\" }))", "not well formed"),
        ] {
            assert!(in_words(vtkio).starts_with(said) || in_words(vtkio).contains(said), "{}", in_words(vtkio));
            assert!(in_words(vtkio).ends_with(&format!("(the VTK reader: {vtkio})")));
        }
        let spaced = "DataArraySizeMismatch { name: \"tissue id, left\", expected: 2, actual: 1 }";
        assert!(in_words(spaced).starts_with("the data array `tissue id, left` holds 1 values"), "{}", in_words(spaced));
    }

    /// vtkio panics on a binary array shorter than its header; that is the
    /// file's error, and the program goes on.
    #[test]
    fn a_truncated_binary_array_is_the_files_error() {
        let (_dir, path) = temp("short.vtu");
        let vtu = r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"><UnstructuredGrid><Piece NumberOfPoints="1" NumberOfCells="0"><Points><DataArray type="Float32" NumberOfComponents="3" format="binary">AAAA</DataArray></Points><Cells><DataArray type="Int64" Name="connectivity" format="ascii"></DataArray><DataArray type="Int64" Name="offsets" format="ascii"></DataArray><DataArray type="UInt8" Name="types" format="ascii"></DataArray></Cells></Piece></UnstructuredGrid></VTKFile>"#;
        std::fs::write(&path, vtu).unwrap();
        let e = read_vtk(&path).expect_err("refused").to_string();
        assert!(e.contains("short.vtu") && e.contains("malformed data arrays"), "{e}");
    }

    #[test]
    fn reads_a_legacy_vtk_and_skips_lines() {
        let (_dir, path) = temp("tet_surface.vtk");
        std::fs::write(&path, LEGACY_VTK).unwrap();
        let file = read_vtk(&path).unwrap();
        assert_eq!(file.mesh.kind, ElementKind::T4);
        assert_eq!(file.mesh.connectivity, vec![0, 1, 2, 3]);
        assert_eq!(file.mesh.surfaces["tag_1"], vec![[0, 2, 1]]);
        assert!(
            file.notes.iter().any(|n| n.contains("Line")),
            "{:?}",
            file.notes
        );
    }

    /// Four points and one tetrahedron as (name, VTK type, bytes) arrays.
    fn tet_arrays() -> Vec<(&'static str, &'static str, u32, Vec<u8>)> {
        let points: [f64; 12] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.];
        vec![
            (
                "",
                "Float64",
                3,
                points.iter().flat_map(|v| v.to_le_bytes()).collect(),
            ),
            (
                "connectivity",
                "Int64",
                1,
                [0i64, 1, 2, 3]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
            ),
            ("offsets", "Int64", 1, 4i64.to_le_bytes().to_vec()),
            ("types", "UInt8", 1, vec![10u8]),
        ]
    }

    /// A `.vtu` with raw appended data as ParaView writes it, compressed
    /// (VTK's block header: count, block size, last size, compressed sizes).
    fn appended_raw_vtu(compress: bool) -> Vec<u8> {
        let arrays = tet_arrays();
        let mut offsets = Vec::new();
        let mut appended = Vec::new();
        for (_, _, _, block) in &arrays {
            offsets.push(appended.len());
            if compress {
                use std::io::Write as _;
                let mut encoder =
                    flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
                encoder.write_all(block).unwrap();
                let packed = encoder.finish().unwrap();
                for header in [
                    1u64,
                    block.len() as u64,
                    block.len() as u64,
                    packed.len() as u64,
                ] {
                    appended.extend_from_slice(&header.to_le_bytes());
                }
                appended.extend_from_slice(&packed);
            } else {
                appended.extend_from_slice(&(block.len() as u64).to_le_bytes());
                appended.extend_from_slice(block);
            }
        }
        let array = |i: usize| {
            let (name, kind, components, _) = &arrays[i];
            format!(
                r#"<DataArray type="{kind}" Name="{name}" NumberOfComponents="{components}" format="appended" offset="{}"/>"#,
                offsets[i]
            )
        };
        let compressor = if compress {
            r#" compressor="vtkZLibDataCompressor""#
        } else {
            ""
        };
        let mut bytes = format!(
            r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"{compressor}>
<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
<Points>{}</Points>
<Cells>{}{}{}</Cells></Piece></UnstructuredGrid>
<AppendedData encoding="raw">
   _"#,
            array(0),
            array(1),
            array(2),
            array(3)
        )
        .into_bytes();
        bytes.extend_from_slice(&appended);
        bytes.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
        bytes
    }

    #[test]
    fn reads_appended_raw_vtu_plain_and_zlib_compressed() {
        for compress in [false, true] {
            let (_dir, path) = temp(&format!("appended_{compress}.vtu"));
            std::fs::write(&path, appended_raw_vtu(compress)).unwrap();
            let file = read_vtk(&path).unwrap();
            assert_eq!(file.mesh.kind, ElementKind::T4);
            assert_eq!(file.mesh.nodes[3], [0.0, 0.0, 1.0]);
        }
    }

    /// XML allows single quotes: ParaView's own files use double ones, a
    /// script's may not, and the offsets are rewritten either way.
    #[test]
    fn reads_appended_raw_vtu_with_single_quoted_offsets() {
        for compress in [false, true] {
            let bytes = appended_raw_vtu(compress);
            let text_end = bytes.windows(4).position(|w| w == b"   _").unwrap();
            let head = String::from_utf8(bytes[..text_end].to_vec()).unwrap();
            let mut single = String::new();
            let mut rest = head.as_str();
            while let Some(at) = rest.find("offset=\"") {
                let value = at + "offset=\"".len();
                let end = value + rest[value..].find('"').unwrap();
                single.push_str(&format!("{}offset='{}'", &rest[..at], &rest[value..end]));
                rest = &rest[end + 1..];
            }
            single.push_str(rest);
            assert!(single.matches("offset='").count() >= 2, "{single}");
            let mut quoted = single.into_bytes();
            quoted.extend_from_slice(&bytes[text_end..]);
            let (_dir, path) = temp(&format!("appended_single_{compress}.vtu"));
            std::fs::write(&path, &quoted).unwrap();
            let (_dir2, plain) = temp(&format!("appended_double_{compress}.vtu"));
            std::fs::write(&plain, &bytes).unwrap();
            let (a, b) = (read_vtk(&path).unwrap(), read_vtk(&plain).unwrap());
            assert_eq!(a.mesh.nodes, b.mesh.nodes);
            assert_eq!(a.mesh.connectivity, b.mesh.connectivity);
        }
    }

    /// Cut anywhere, the file is named with the fix; cut in its raw data,
    /// the message says it is the appended data that ends short.
    #[test]
    fn truncated_raw_appended_data_is_an_error() {
        let bytes = appended_raw_vtu(true);
        let raw = bytes.windows(4).position(|w| w == b"   _").unwrap() + 4;
        let (_dir, path) = temp("appended_cut.vtu");
        let stride = (bytes.len() / 60).max(1);
        let mut in_raw = 0;
        for cut in (0..bytes.len() - 30).step_by(stride) {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            let err = read_vtk(&path).map(|_| ()).unwrap_err().to_string();
            let problem = err
                .strip_prefix(&format!("{}: ", path.display()))
                .and_then(|e| e.strip_suffix(&format!("; fix: {RESAVE_FIX}")))
                .unwrap_or_else(|| panic!("cut at {cut}: {err}"));
            if cut > raw {
                in_raw += 1;
                assert!(problem.to_lowercase().contains("appended"), "cut at {cut}: {err}");
            }
        }
        assert!(in_raw >= 10, "{in_raw} cuts in the raw data");
    }

    /// An offset or a byte count out by one byte is the damaged file named,
    /// not shifted numbers read as a mesh.
    #[test]
    fn appended_data_out_by_a_byte_is_an_error() {
        let (_dir, path) = temp("appended_shifted.vtu");
        for compress in [false, true] {
            let bytes = appended_raw_vtu(compress);
            let text_end = bytes.windows(4).position(|w| w == b"   _").unwrap();
            let head = String::from_utf8(bytes[..text_end].to_vec()).unwrap();
            // The second array's offset one byte either way.
            let at = head.match_indices("offset=\"").nth(1).unwrap().0 + "offset=\"".len();
            let len = head[at..].find('"').unwrap();
            let offset: usize = head[at..at + len].parse().unwrap();
            for moved in [offset - 1, offset + 1] {
                let mut shifted = format!("{}{moved}{}", &head[..at], &head[at + len..]).into_bytes();
                shifted.extend_from_slice(&bytes[text_end..]);
                std::fs::write(&path, &shifted).unwrap();
                let e = read_vtk(&path).expect_err("refused").to_string();
                assert!(e.contains("appended_shifted.vtu") && e.contains("is wrong"), "{e}");
            }
            // The first array's byte count (its last header field) one short.
            let data = text_end + 4;
            let field = if compress { data + 24 } else { data };
            let mut short = bytes.clone();
            short[field] -= 1;
            std::fs::write(&path, &short).unwrap();
            let e = read_vtk(&path).expect_err("refused").to_string();
            assert!(e.contains("byte count is wrong"), "{e}");
        }
    }

    #[test]
    fn reads_binary_legacy_vtk() {
        let mesh = carus_fem::generate::box_t4([1.0, 2.0, 3.0], [1, 1, 1]);
        let vtk = Vtk {
            version: Version::new_legacy(4, 2),
            title: "binary".into(),
            byte_order: ByteOrder::BigEndian,
            file_path: None,
            data: DataSet::inline(UnstructuredGridPiece {
                points: IOBuffer::F64(mesh.nodes.iter().flatten().copied().collect()),
                cells: Cells {
                    cell_verts: VertexNumbers::Legacy {
                        num_cells: mesh.element_count() as u32,
                        vertices: mesh
                            .elements()
                            .flat_map(|e| std::iter::once(4).chain(e.iter().copied()))
                            .collect(),
                    },
                    types: vec![CellType::Tetra; mesh.element_count()],
                },
                data: Attributes::new(),
            }),
        };
        let mut bytes = Vec::new();
        vtk.write_legacy(&mut bytes).unwrap();
        let (_dir, path) = temp("binary.vtk");
        std::fs::write(&path, &bytes).unwrap();
        let back = read_vtk(&path).unwrap().mesh;
        assert_eq!(back.nodes, mesh.nodes);
        assert_eq!(back.connectivity, mesh.connectivity);
    }

    #[test]
    fn frames_round_trip_through_the_reader() {
        let mut mesh = carus_fem::generate::box_h8([0.1, 0.1, 0.1], [2, 2, 2]);
        mesh.element_sets.insert("tissue".into(), (0..8).collect());
        let displacement: Vec<[f64; 3]> = mesh
            .nodes
            .iter()
            .map(|p| [0.3 * p[0], -1e-7, p[2] * p[1]])
            .collect();
        let von_mises: Vec<f64> = (0..8).map(|e| 1000.0 + e as f64 / 3.0).collect();
        let stretch: Vec<f64> = (0..8).map(|e| 1.0 + e as f64 * 1e-3).collect();
        let jacobian = vec![0.999; 8];
        let frame = FrameFields {
            displacement_m: &displacement,
            von_mises_pa: &von_mises,
            max_principal_stretch: &stretch,
            jacobian: &jacobian,
            time_s: Some(0.125),
        };
        let (_dir, path) = temp("frame.vtu");
        write_vtu(&path, &mesh, &frame).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().contains(r#"Name="TimeValue" NumberOfTuples="1" format="ascii">0.125<"#));
        let back = read_vtk(&path).unwrap().mesh;
        assert_eq!(back.nodes, mesh.nodes);
        assert_eq!(back.connectivity, mesh.connectivity);
        assert_eq!(
            back.element_sets["element_set_0"],
            mesh.element_sets["tissue"]
        );
        let arrays = read_vtk_arrays(&path).unwrap();
        let d = &arrays.point["displacement"];
        assert_eq!(d.components, 3);
        assert_eq!(
            d.values,
            displacement.iter().flatten().copied().collect::<Vec<_>>()
        );
        assert_eq!(arrays.cell["von_mises_pa"].values, von_mises);
        assert_eq!(arrays.cell["max_principal_stretch"].values, stretch);
        assert_eq!(arrays.cell["jacobian"].values, jacobian);
    }

    /// A rigid body's surface comes back point for point, compressed; a
    /// triangle past the points is refused before anything is written.
    #[test]
    fn triangle_surfaces_round_trip_through_the_reader() {
        let points = [[0.0, 0.0, 0.0], [0.1, 0.0, 1e-9], [0.0, -0.1, 0.3]];
        let (_dir, path) = temp("surface.vtu");
        write_triangle_vtu(&path, &points, &[[0, 1, 2]], Some(3.5)).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().contains("compressor=\"vtkZLibDataCompressor\""));
        let piece = load_unstructured(&path).unwrap();
        assert_eq!(piece.cells.types, vec![CellType::Triangle]);
        assert_eq!(read_vtk_arrays(&path).unwrap().points, points);
        let (_dir, bad) = temp("bad_surface.vtu");
        let e = write_triangle_vtu(&bad, &points, &[[0, 1, 3]], None).unwrap_err().to_string();
        assert!(e.contains("bad_surface.vtu") && e.contains("triangle 0 names a point past the 3 given"), "{e}");
        assert!(!bad.exists());
    }

    #[test]
    fn wrong_lengths_are_refused_not_written() {
        let mesh = carus_fem::generate::box_t4([1.0, 1.0, 1.0], [1, 1, 1]);
        let frame = FrameFields {
            displacement_m: &[[0.0; 3]; 2],
            von_mises_pa: &[],
            max_principal_stretch: &[],
            jacobian: &[],
            time_s: None,
        };
        let (_dir, bad) = temp("bad.vtu");
        let err = write_vtu(&bad, &mesh, &frame)
            .unwrap_err()
            .to_string();
        assert!(err.contains("2 displacements for 8 nodes"), "{err}");
    }

    #[test]
    fn truncated_and_corrupted_files_give_errors_not_panics() {
        let mesh = carus_fem::generate::box_t4([1.0, 1.0, 1.0], [1, 1, 1]);
        let zeros = vec![0.0; mesh.element_count()];
        let (_dir, frame_path) = temp("binary_frame.vtu");
        let frame = FrameFields {
            displacement_m: &vec![[0.0; 3]; mesh.node_count()],
            von_mises_pa: &zeros,
            max_principal_stretch: &zeros,
            jacobian: &zeros,
            time_s: Some(1.0),
        };
        write_vtu(&frame_path, &mesh, &frame).unwrap();
        let binary = std::fs::read_to_string(&frame_path).unwrap();
        for (name, text) in [
            ("t.vtu", ASCII_VTU),
            ("t.vtk", LEGACY_VTK),
            ("b.vtu", binary.as_str()),
        ] {
            let (_dir, path) = temp(name);
            // Every byte of the compressed frame: a damaged block header
            // must not make vtkio allocate what it declares.
            let stride = if name == "b.vtu" { 1 } else { (text.len() / 60).max(1) };
            for cut in (0..text.len()).step_by(stride) {
                std::fs::write(&path, &text.as_bytes()[..cut]).unwrap();
                if let Ok(file) = read_vtk(&path) {
                    assert!(file.mesh.element_count() <= mesh.element_count());
                }
            }
            let mut bytes = text.as_bytes().to_vec();
            for i in (0..bytes.len()).step_by(stride) {
                let saved = bytes[i];
                bytes[i] = b'9';
                std::fs::write(&path, &bytes).unwrap();
                let _ = read_vtk(&path);
                bytes[i] = saved;
            }
        }
    }

    #[test]
    fn other_data_sets_are_refused_with_the_fix() {
        let (_dir, path) = temp("poly.vtk");
        std::fs::write(&path, "# vtk DataFile Version 2.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n").unwrap();
        let err = read_vtk(&path).unwrap_err().to_string();
        let expected = format!(
            "{}: the data set is poly data (a surface), not an unstructured grid; fix: mesh the volume the surface encloses with tetrahedra (Gmsh, TetGen) and save that as .vtu",
            path.display()
        );
        assert_eq!(err, expected);
        // A volume of another kind is converted.
        let (_dir, path) = temp("image.vtk");
        std::fs::write(&path, "# vtk DataFile Version 2.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nORIGIN 0 0 0\nSPACING 1 1 1\n").unwrap();
        let err = read_vtk(&path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: the data set is image data, not an unstructured grid; fix: convert it to an unstructured grid (ParaView", path.display())), "{err}");
    }
}
