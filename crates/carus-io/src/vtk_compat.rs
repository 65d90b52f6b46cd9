//! Rewrites of VTK files that vtkio 0.7.0-rc2 cannot read as written:
//!
//! - a `.vtu` whose appended data is raw binary (ParaView's default when
//!   saving) becomes base64 appended data, the only appended encoding vtkio
//!   reads. Each array's block is checked against the file's length on the
//!   way, so a truncated file gives an error naming the array instead of an
//!   out-of-range slice inside vtkio;
//! - a legacy `.vtk` of VTK 9 (version 5.1) names data types `vtktypeint64`
//!   and so on in its data arrays, where vtkio knows only the classic names
//!   (`long`); those are renamed (the OFFSETS and CONNECTIVITY lines, which
//!   vtkio reads with the new names, stay).

use std::borrow::Cow;

use base64::engine::general_purpose::STANDARD;
use base64::Engine;

use crate::xml_attr::{attribute, attribute_spans};

/// How a `.vtu`'s `<VTKFile>` tag says its binary arrays begin: the width
/// and byte order of their header words, and the compressor, if any.
struct BinaryLayout {
    header_bytes: usize,
    big_endian: bool,
    compressor: Option<String>,
}

impl BinaryLayout {
    fn of(file_tag: &str) -> BinaryLayout {
        BinaryLayout {
            header_bytes: match attribute(file_tag, "header_type").as_deref() {
                Some("UInt64") => 8,
                _ => 4,
            },
            big_endian: attribute(file_tag, "byte_order").as_deref() == Some("BigEndian"),
            compressor: attribute(file_tag, "compressor"),
        }
    }

    /// The header word held in `field`, `header_bytes` long.
    fn word(&self, field: &[u8]) -> u64 {
        let mut b = [0u8; 8];
        if self.big_endian {
            b[8 - self.header_bytes..].copy_from_slice(field);
            u64::from_be_bytes(b)
        } else {
            b[..self.header_bytes].copy_from_slice(field);
            u64::from_le_bytes(b)
        }
    }
}

/// The file with raw appended data re-encoded, or unchanged when it has none.
pub(crate) fn raw_appended_to_base64(bytes: &[u8]) -> Result<Cow<'_, [u8]>, String> {
    let Some(appended_tag) = find(bytes, b"<AppendedData", 0) else {
        return Ok(Cow::Borrowed(bytes));
    };
    let tag_end = find(bytes, b">", appended_tag).ok_or("the <AppendedData> tag is not closed")?;
    let tag = &bytes[appended_tag..tag_end];
    if attribute(&String::from_utf8_lossy(tag), "encoding").as_deref() != Some("raw") {
        return Ok(Cow::Borrowed(bytes));
    }
    let underscore = find(bytes, b"_", tag_end).ok_or("the appended data has no leading `_`")?;
    let data_end = rfind(bytes, b"</AppendedData>")
        .unwrap_or(bytes.len())
        .max(underscore + 1);
    let data = &bytes[underscore + 1..data_end];

    let head = &bytes[..appended_tag];
    let file_tag_start = find(head, b"<VTKFile", 0).ok_or("there is no <VTKFile> tag")?;
    let file_tag = String::from_utf8_lossy(&head[file_tag_start..find(head, b">", file_tag_start).unwrap_or(head.len())]);
    let layout = BinaryLayout::of(&file_tag);
    let header_bytes = layout.header_bytes;
    let compressed = layout.compressor.is_some();
    let read_header = |at: usize| -> Result<usize, String> {
        let field = data
            .get(at..at + header_bytes)
            .ok_or_else(|| format!("the appended data ends inside an array header at byte {at}"))?;
        usize::try_from(layout.word(field)).map_err(|_| format!("array header at byte {at} is too large"))
    };

    // Every array's offset, re-encoded block by block.
    let head = String::from_utf8_lossy(head);
    let spans = attribute_spans(&head, "offset")?;
    let offsets = spans
        .iter()
        .map(|&(start, end)| {
            let value = &head[start..end];
            value.trim().parse().map_err(|_| format!("offset {value:?} is not a number"))
        })
        .collect::<Result<Vec<usize>, String>>()?;
    let mut unique = offsets.clone();
    unique.sort_unstable();
    unique.dedup();
    let mut encoded = String::new();
    let mut new_offsets = Vec::with_capacity(unique.len());
    for (k, &offset) in unique.iter().enumerate() {
        new_offsets.push(encoded.len());
        let overflow = || format!("the array at appended offset {offset} is larger than the file");
        if compressed {
            let blocks = read_header(offset)?;
            let header_len = blocks
                .checked_add(3)
                .and_then(|n| n.checked_mul(header_bytes))
                .ok_or_else(overflow)?;
            let mut payload = 0usize;
            for b in 0..blocks {
                let size = read_header(offset + (3 + b) * header_bytes)?;
                payload = payload.checked_add(size).ok_or_else(overflow)?;
            }
            let header = data.get(offset..offset + header_len).ok_or_else(overflow)?;
            let body_start = offset + header_len;
            let body = data
                .get(body_start..body_start.checked_add(payload).ok_or_else(overflow)?)
                .ok_or_else(overflow)?;
            encoded.push_str(&STANDARD.encode(header));
            encoded.push_str(&STANDARD.encode(body));
            check_tiling(data, &unique, k, body_start + payload)?;
        } else {
            let size = read_header(offset)?;
            let end = (offset + header_bytes)
                .checked_add(size)
                .ok_or_else(overflow)?;
            let block = data.get(offset..end).ok_or_else(overflow)?;
            encoded.push_str(&STANDARD.encode(block));
            check_tiling(data, &unique, k, end)?;
        }
    }
    // Rewrite the offsets in order of appearance.
    let mut text = String::with_capacity(head.len() + encoded.len() + 64);
    let mut written = 0;
    for (&(start, end), offset) in spans.iter().zip(&offsets) {
        let index = unique.binary_search(offset).unwrap_or(0);
        text.push_str(&head[written..start]);
        text.push_str(&new_offsets[index].to_string());
        written = end;
    }
    text.push_str(&head[written..]);
    text.push_str("<AppendedData encoding=\"base64\">_");
    text.push_str(&encoded);
    text.push_str("</AppendedData></VTKFile>\n");
    Ok(Cow::Owned(text.into_bytes()))
}

/// The largest size a block can have for each byte of it compressed, by
/// VTK's compressors: deflate's limit of 1032 to 1 (zlib's technical
/// details), LZ4's 255 to 1 (one length byte per 255 repeated bytes;
/// 256 for the block's own header), and for LZMA a bound well above what
/// it reaches on runs of zeros.
fn most_expansion(compressor: &str) -> u64 {
    match compressor {
        "vtkZLibDataCompressor" => 1032,
        "vtkLZ4DataCompressor" => 256,
        _ => 1 << 16,
    }
}

/// A compressed array whose block header declares more bytes than its
/// compressed blocks can hold: vtkio allocates what the header declares
/// before reading a block, so a damaged header (or an empty array's, which
/// vtkio miscounts) would end the program for want of memory instead of
/// giving this file's error. Reads base64 data (inline, or appended after
/// [`raw_appended_to_base64`]); `None` when every header is within bounds
/// or cannot be read (vtkio then gives its own error).
pub(crate) fn compressed_size_fault(bytes: &[u8]) -> Option<String> {
    let appended_tag = find(bytes, b"<AppendedData", 0);
    let head = String::from_utf8_lossy(&bytes[..appended_tag.unwrap_or(bytes.len())]);
    let file_tag = &head[head.find("<VTKFile")?..];
    let file_tag = &file_tag[..file_tag.find('>')?];
    let layout = BinaryLayout::of(file_tag);
    let expansion = most_expansion(layout.compressor.as_deref()?);
    let appended = appended_tag.and_then(|at| find(bytes, b"_", at)).map(|u| &bytes[u + 1..]);
    let mut search = 0;
    while let Some(at) = head[search..].find("<DataArray") {
        let start = search + at;
        let end = start + head[start..].find('>')? + 1;
        search = end;
        // vtkio does not read field data (a grid's TimeValue, say).
        let before = &head[..start];
        if before.rfind("<FieldData").is_some_and(|open| before.rfind("</FieldData>").is_none_or(|close| close < open)) {
            continue;
        }
        let tag = &head[start..end];
        let offset = || attribute(tag, "offset")?.trim().parse::<usize>().ok();
        let data = match attribute(tag, "format").as_deref() {
            Some("binary") => Some(head[end..].trim_start().as_bytes()),
            Some("appended") => appended.zip(offset()).and_then(|(appended, offset)| appended.get(offset..)),
            _ => None,
        };
        // An array that cannot be found is vtkio's to name.
        let Some(data) = data else {
            continue;
        };
        if let Some(fault) = block_sizes_fault(data, &layout, expansion) {
            return Some(format!("the data array `{}` {fault}", attribute(tag, "Name").unwrap_or_default()));
        }
    }
    None
}

/// [`compressed_size_fault`] for one array's base64 data, read as vtkio
/// reads it: `[blocks][block size][last block size][compressed sizes...]`.
fn block_sizes_fault(data: &[u8], layout: &BinaryLayout, expansion: u64) -> Option<String> {
    let header_bytes = layout.header_bytes;
    let base64_len = |n: usize| n.div_ceil(3) * 4;
    let words = |count: usize| -> Option<Vec<u64>> {
        let decoded = STANDARD.decode(data.get(..base64_len(count * header_bytes))?).ok()?;
        Some(decoded.chunks_exact(header_bytes).take(count).map(|w| layout.word(w)).collect())
    };
    let blocks = *words(1)?.first()?;
    // The header's words must fit in the data, or vtkio counts past it.
    let header_words = usize::try_from(blocks).ok().and_then(|b| b.checked_add(3)).filter(|w| {
        w.checked_mul(header_bytes).is_some_and(|n| base64_len(n) <= data.len())
    });
    let Some(header_words) = header_words else {
        return Some(format!("declares {blocks} compressed blocks, more than its data can hold: the file is damaged"));
    };
    let header = words(header_words)?;
    let (block_size, last_size) = (header[1], header[2]);
    let compressed = header[3..].iter().try_fold(0u64, |sum, &n| sum.checked_add(n));
    // What vtkio allocates, wrapping as it does.
    let declared = block_size.wrapping_mul(blocks.wrapping_sub(1)).wrapping_add(last_size);
    // VTK writes an empty array as no blocks of its usual block size,
    // which vtkio counts as minus one block.
    if blocks == 0 && declared != 0 {
        return Some(
            "is empty (no compressed blocks), which this reader cannot read: leave the empty array out, or \
             save the file uncompressed"
                .to_string(),
        );
    }
    match compressed {
        Some(compressed) if declared <= expansion.saturating_mul(compressed) => None,
        _ => Some(format!(
            "declares {declared} bytes in {blocks} compressed blocks of {} bytes, more than they can hold: the file is damaged",
            compressed.map_or("too many".to_string(), |c| c.to_string())
        )),
    }
}

/// Writers lay the arrays end to end, so array `k` of the appended data
/// must end where the next begins (or, the last, where the data ends): an
/// offset or byte count out by even one byte would otherwise be read as
/// shifted numbers, a mesh that looks inverted rather than damaged.
fn check_tiling(data: &[u8], offsets: &[usize], k: usize, end: usize) -> Result<(), String> {
    let offset = offsets[k];
    if k == 0 && offset != 0 {
        return Err(format!(
            "the first array begins at byte {offset} of the appended data, not at its start: an offset is wrong"
        ));
    }
    match offsets.get(k + 1) {
        Some(&next) if next != end => Err(format!(
            "the array at appended offset {offset} ends at byte {end}, but the next array begins at byte {next}: an offset or an array's byte count is wrong"
        )),
        None if !data[end..].iter().all(u8::is_ascii_whitespace) => Err(format!(
            "the last array (appended offset {offset}) ends at byte {end}, {} bytes before the end of the appended data: its byte count is wrong",
            data.len() - end
        )),
        _ => Ok(()),
    }
}

/// The `.vtu` text vtkio wrote, without `RangeMin`/`RangeMax` on arrays
/// of more than one component: vtkio writes the range of all their
/// components, where VTK reads these as the range of the magnitude (never
/// negative); left out, VTK computes the range itself.
pub(crate) fn without_component_ranges(xml: String) -> String {
    let mut out = String::with_capacity(xml.len());
    let mut rest = xml.as_str();
    while let Some(at) = rest.find("<DataArray") {
        let tag_len = rest[at..].find('>').map_or(rest.len() - at, |e| e + 1);
        let tag = &rest[at..at + tag_len];
        out.push_str(&rest[..at]);
        let components: usize = attribute(tag, "NumberOfComponents")
            .and_then(|c| c.trim().parse().ok())
            .unwrap_or(1);
        if components > 1 {
            out.push_str(&without_attribute(&without_attribute(tag, "RangeMin"), "RangeMax"));
        } else {
            out.push_str(tag);
        }
        rest = &rest[at + tag_len..];
    }
    out.push_str(rest);
    out
}

/// The `.vtu` text vtkio wrote (it has no dataset-level field data) with
/// a `FieldData` block holding `TimeValue`, the name ParaView and VTK read
/// a dataset's time from, first in its `UnstructuredGrid`.
pub(crate) fn with_time_value(xml: String, time_s: f64) -> String {
    let Some(grid_end) = xml.find("<UnstructuredGrid").and_then(|at| xml[at..].find('>').map(|e| at + e + 1)) else {
        return xml;
    };
    let field = format!(
        "<FieldData><DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time_s:?}</DataArray></FieldData>"
    );
    format!("{}{field}{}", &xml[..grid_end], &xml[grid_end..])
}

/// `tag` without its ` name="..."` attribute.
fn without_attribute(tag: &str, name: &str) -> String {
    let pattern = format!(" {name}=\"");
    match tag.find(&pattern) {
        Some(start) => {
            let value_start = start + pattern.len();
            let end = tag[value_start..].find('"').map_or(tag.len(), |e| value_start + e + 1);
            format!("{}{}", &tag[..start], &tag[end..])
        }
        None => tag.to_string(),
    }
}

/// A data array a `.vtu` declares in its `PointData` or `CellData`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DeclaredArray {
    pub name: String,
    pub components: usize,
    /// How many numbers its text holds, for an ascii array.
    pub ascii_values: Option<usize>,
}

/// The arrays of the first piece's `PointData` and `CellData`, read from
/// the XML text: vtkio skips an attribute array it cannot read (a wrong
/// length, undecodable data) without a word, so the caller compares these
/// with what vtkio kept. Reads only the text before `<AppendedData>`.
pub(crate) fn declared_arrays(bytes: &[u8]) -> [Vec<DeclaredArray>; 2] {
    let text_end = find(bytes, b"<AppendedData", 0).unwrap_or(bytes.len());
    let text = String::from_utf8_lossy(&bytes[..text_end]);
    ["PointData", "CellData"].map(|section| {
        let open = format!("<{section}");
        let Some(start) = text
            .match_indices(&open)
            .map(|(at, _)| at)
            .find(|&at| matches!(text.as_bytes().get(at + open.len()), Some(b'>' | b'/' | b' ' | b'\t' | b'\n' | b'\r')))
        else {
            return Vec::new();
        };
        let Some(tag_len) = text[start..].find('>') else { return Vec::new() };
        if text[..start + tag_len].ends_with('/') {
            return Vec::new();
        }
        let close = format!("</{section}>");
        let end = text[start..].find(&close).map_or(text.len(), |e| start + e);
        let mut arrays = Vec::new();
        let mut search = start;
        while let Some(at) = text[search..end].find("<DataArray") {
            let tag_start = search + at;
            let Some(tag_len) = text[tag_start..end].find('>') else { break };
            let tag = &text[tag_start..tag_start + tag_len];
            let self_closing = tag.ends_with('/');
            let body_start = tag_start + tag_len + 1;
            let body_end = if self_closing {
                body_start
            } else {
                text[body_start..end].find("</DataArray>").map_or(end, |e| body_start + e)
            };
            let ascii = attribute(tag, "format").as_deref() == Some("ascii");
            arrays.push(DeclaredArray {
                name: attribute(tag, "Name").unwrap_or_default(),
                components: attribute(tag, "NumberOfComponents")
                    .and_then(|c| c.trim().parse().ok())
                    .unwrap_or(1),
                ascii_values: ascii.then(|| text[body_start..body_end].split_ascii_whitespace().count()),
            });
            search = body_end;
        }
        arrays
    })
}

/// VTK 9 type names and their classic legacy names (as vtkio reads them).
const VTK9_TYPES: [(&[u8], &[u8]); 9] = [
    (b"vtktypeint8", b"char"),
    (b"vtktypeuint8", b"unsigned_char"),
    (b"vtktypeint16", b"short"),
    (b"vtktypeint32", b"int"),
    (b"vtktypeuint32", b"unsigned_int"),
    (b"vtktypeint64", b"long"),
    (b"vtktypeuint64", b"unsigned_long"),
    (b"vtktypefloat32", b"float"),
    (b"vtktypefloat64", b"double"),
];

/// The legacy file with VTK 9 data type names in data-array header lines
/// replaced by their classic names; unchanged when there are none.
pub(crate) fn legacy_type_names(bytes: &[u8]) -> Cow<'_, [u8]> {
    let mut out: Option<Vec<u8>> = None;
    let mut copied = 0;
    let mut search = 0;
    while let Some(at) = find(bytes, b" vtktype", search) {
        let token_start = at + 1;
        let token_end = bytes[token_start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .map_or(bytes.len(), |p| token_start + p);
        search = token_end;
        let line_start = bytes[..at]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        let line = &bytes[line_start..at];
        if line.starts_with(b"OFFSETS") || line.starts_with(b"CONNECTIVITY") {
            continue;
        }
        let token = &bytes[token_start..token_end];
        let classic = VTK9_TYPES
            .iter()
            .find(|(new, _)| *new == token)
            .map(|(_, old)| *old);
        if let Some(classic) = classic {
            let buffer = out.get_or_insert_with(Vec::new);
            buffer.extend_from_slice(&bytes[copied..token_start]);
            buffer.extend_from_slice(classic);
            copied = token_end;
        }
    }
    match out {
        Some(mut buffer) => {
            buffer.extend_from_slice(&bytes[copied..]);
            Cow::Owned(buffer)
        }
        None => Cow::Borrowed(bytes),
    }
}

/// Where an ASCII legacy file first goes wrong, for vtkio's parse errors,
/// which name no line: a value in `POINTS` (or a float data array) that is
/// not a finite number, one in `CELLS`, `CELL_TYPES` (or version 5's
/// `OFFSETS`, `CONNECTIVITY`) that is not a whole number of 0 or more, a
/// cell type VTK does not have, an integer data array's value that its
/// type cannot hold, or a section with fewer or more values than its
/// header declares. (line, problem), or `None` for a binary file, one that
/// reads well, or a fault in a section not checked here (`FIELD`,
/// `TENSORS`, a colour table...), which vtkio's own message has to name.
pub(crate) fn legacy_ascii_fault(bytes: &[u8]) -> Option<(usize, String)> {
    /// What the values of a section must be.
    #[derive(Clone, Copy)]
    enum Values {
        Real,
        Count,
        CellType,
        Integer { least: i128, most: i128, of: &'static str },
    }
    struct Section<'a> {
        name: &'a str,
        line: usize,
        /// None where the header gives no count (version 5's sections).
        declared: Option<usize>,
        found: usize,
        values: Values,
    }
    let miscounted = |s: &Section, at: usize| {
        let declared = s.declared?;
        (s.found != declared).then(|| {
            (at, format!("{} (line {}) declares {declared} values, but {} come before this line", s.name, s.line, s.found))
        })
    };
    let integer = |of: &str| -> Option<Values> {
        let (of, least, most): (&'static str, i128, i128) = match of {
            "bit" => ("bit", 0, 1),
            "char" => ("char", i8::MIN.into(), i8::MAX.into()),
            "unsigned_char" => ("unsigned_char", 0, u8::MAX.into()),
            "short" => ("short", i16::MIN.into(), i16::MAX.into()),
            "unsigned_short" => ("unsigned_short", 0, u16::MAX.into()),
            "int" => ("int", i32::MIN.into(), i32::MAX.into()),
            "unsigned_int" => ("unsigned_int", 0, u32::MAX.into()),
            "long" => ("long", i64::MIN.into(), i64::MAX.into()),
            "vtktypeint64" => ("vtktypeint64", i64::MIN.into(), i64::MAX.into()),
            "unsigned_long" => ("unsigned_long", 0, u64::MAX.into()),
            "vtktypeuint64" => ("vtktypeuint64", 0, u64::MAX.into()),
            _ => return None,
        };
        Some(Values::Integer { least, most, of })
    };
    let text = std::str::from_utf8(bytes).ok()?;
    if !text.lines().nth(2)?.trim().eq_ignore_ascii_case("ascii") {
        return None;
    }
    let is_keyword = |w: &str| w.chars().all(|c| c.is_ascii_uppercase() || c == '_') && !matches!(w, "NAN" | "INF" | "INFINITY");
    let mut section: Option<Section> = None;
    // The count of the POINT_DATA or CELL_DATA the arrays belong to.
    let mut data_count: Option<usize> = None;
    let mut last = 0;
    for (i, line) in text.lines().enumerate().skip(3) {
        last = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(&first) = words.first() else { continue };
        if is_keyword(first) {
            // A scalar array's table line belongs to its header.
            if first == "LOOKUP_TABLE" && words.len() == 2 && section.as_ref().is_some_and(|s| s.name == "SCALARS" && s.found == 0) {
                continue;
            }
            if let Some(fault) = section.as_ref().and_then(|s| miscounted(s, i + 1)) {
                return Some(fault);
            }
            let count = |k: usize| words.get(k).and_then(|w| w.parse::<usize>().ok());
            let array = |components: Option<usize>| -> Option<(Option<usize>, Values)> {
                let of = words.get(2)?.to_ascii_lowercase();
                let values = match of.as_str() {
                    "float" | "double" => Values::Real,
                    other => integer(other)?,
                };
                Some((data_count?.checked_mul(components?), values))
            };
            let (declared, values) = match first {
                "DATASET" => continue,
                "POINT_DATA" | "CELL_DATA" => {
                    data_count = count(1);
                    section = None;
                    continue;
                }
                "POINTS" => (count(1).and_then(|n| n.checked_mul(3)), Values::Real),
                // Version 2's `CELLS n size`: size values follow; version 5's
                // `CELLS offsets connectivity` heads two sections of their own.
                "CELLS" if words.len() == 3 && text.lines().nth(i + 1).is_some_and(|l| l.trim_start().starts_with("OFFSETS")) => {
                    section = None;
                    continue;
                }
                "CELLS" => (count(2), Values::Count),
                "CELL_TYPES" => (count(1), Values::CellType),
                "OFFSETS" | "CONNECTIVITY" => {
                    section = Some(Section { name: first, line: i + 1, declared: None, found: 0, values: Values::Count });
                    continue;
                }
                "SCALARS" => match array(words.get(3).map_or(Some(1), |w| w.parse().ok())) {
                    Some((declared, values)) => (declared, values),
                    None => return None,
                },
                "VECTORS" | "NORMALS" => match array(Some(3)) {
                    Some((declared, values)) => (declared, values),
                    None => return None,
                },
                // FIELD arrays, tensors, colour tables: vtkio's own message.
                _ => return None,
            };
            let Some(declared) = declared else {
                return Some((i + 1, format!("{first} needs its count{}: {line:?}", if matches!(values, Values::Real) { " and type" } else { "s" })));
            };
            section = Some(Section { name: first, line: i + 1, declared: Some(declared), found: 0, values });
            continue;
        }
        let Some(s) = section.as_mut() else { continue };
        for word in words {
            let wanted = match s.values {
                Values::Real => (!word.parse::<f64>().is_ok_and(f64::is_finite)).then(|| "a finite number".to_string()),
                Values::Count => word.parse::<u64>().is_err().then(|| "a whole number of 0 or more".to_string()),
                Values::CellType => match word.parse::<u64>() {
                    Err(_) => Some("a whole number".to_string()),
                    // The cell types vtkio 0.7 reads (its CellType).
                    Ok(t) => (!matches!(t, 1..=14 | 21..=35 | 41 | 42 | 51..=56 | 60..=81))
                        .then(|| "a VTK cell type this reader knows (10 is a tetrahedron, 12 a hexahedron, 5 a triangle)".to_string()),
                },
                Values::Integer { least, most, of } => match word.parse::<i128>() {
                    Ok(v) if (least..=most).contains(&v) => None,
                    Ok(_) => Some(format!("a value {of} holds ({least} to {most})")),
                    Err(_) => Some(format!("a whole number, as {of} is")),
                },
            };
            if let Some(wanted) = wanted {
                return Some((i + 1, format!("{word:?} in {} (line {}) is not {wanted}", s.name, s.line)));
            }
            s.found += 1;
        }
    }
    section.as_ref().and_then(|s| miscounted(s, last + 1))
}

fn find(haystack: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    haystack
        .get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|p| p + from)
}

fn rfind(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).rposition(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_without_raw_data_pass_unchanged() {
        let text = b"<VTKFile><AppendedData encoding=\"base64\">_AAAA</AppendedData></VTKFile>";
        assert!(matches!(
            raw_appended_to_base64(text).unwrap(),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn vtk9_type_names_are_renamed_outside_cell_lines() {
        let text =
            b"OFFSETS vtktypeint64\nx\ngmsh:physical 1 3 vtktypeint64\nA 1 2 vtktypefloat64\n";
        let renamed = legacy_type_names(text);
        assert_eq!(
            &renamed[..],
            &b"OFFSETS vtktypeint64\nx\ngmsh:physical 1 3 long\nA 1 2 double\n"[..]
        );
        assert!(matches!(
            legacy_type_names(b"POINTS 3 float\n"),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn declared_arrays_are_read_from_point_and_cell_data_only() {
        let text = br#"<VTKFile><Piece><PointData Scalars="t"><DataArray type="Int32" Name="t" format="ascii"> 1 2
 3 </DataArray><DataArray type="Float32" Name="v" NumberOfComponents="3" format="appended" offset="0"/></PointData>
<CellData/><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0</DataArray></Points></Piece>
<AppendedData encoding="raw">_<PointData><DataArray Name="inside"/></AppendedData></VTKFile>"#;
        let [point, cell] = declared_arrays(text);
        assert_eq!(
            point,
            vec![
                DeclaredArray { name: "t".into(), components: 1, ascii_values: Some(3) },
                DeclaredArray { name: "v".into(), components: 3, ascii_values: None },
            ]
        );
        assert!(cell.is_empty());
    }

    #[test]
    fn component_ranges_are_left_out_of_vector_arrays_only() {
        let xml = r#"<Points><DataArray type="Float64" Name="Points" NumberOfComponents="3" format="binary" RangeMin="-0.13" RangeMax="0.07">AAAA</DataArray></Points><DataArray type="Float64" Name="j" format="binary" RangeMin="1" RangeMax="2">"#;
        assert_eq!(
            without_component_ranges(xml.to_string()),
            r#"<Points><DataArray type="Float64" Name="Points" NumberOfComponents="3" format="binary">AAAA</DataArray></Points><DataArray type="Float64" Name="j" format="binary" RangeMin="1" RangeMax="2">"#
        );
    }

    /// A header declaring more than its blocks can hold is named before
    /// vtkio allocates it; a true one passes.
    #[test]
    fn a_compressed_header_past_its_blocks_is_refused() {
        let file = |words: &[u64], compressed: usize| {
            let header: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
            format!(
                r#"<VTKFile type="UnstructuredGrid" header_type="UInt64" compressor="vtkZLibDataCompressor"><DataArray type="Float64" Name="v" format="binary">{}{}</DataArray>"#,
                STANDARD.encode(header),
                STANDARD.encode(vec![0u8; compressed])
            )
        };
        assert_eq!(compressed_size_fault(file(&[1, 800, 800, 20], 20).as_bytes()), None);
        let e = compressed_size_fault(file(&[1, 1 << 40, 1 << 40, 20], 20).as_bytes()).unwrap();
        assert!(e.starts_with("the data array `v` declares 1099511627776 bytes in 1 compressed blocks of 20 bytes"), "{e}");
        let e = compressed_size_fault(file(&[1 << 62, 800, 800, 20], 20).as_bytes()).unwrap();
        assert!(e.contains("declares 4611686018427387904 compressed blocks, more than its data can hold"), "{e}");
        // An empty array with a block size (as VTK writes one): vtkio would
        // count -1 blocks, so it is named as empty, not as damaged.
        let e = compressed_size_fault(file(&[0, 32768, 0], 0).as_bytes()).unwrap();
        assert!(e.starts_with("the data array `v` is empty (no compressed blocks)"), "{e}");
        assert_eq!(compressed_size_fault(file(&[0, 0, 0], 0).as_bytes()), None);
        // Field data, which vtkio does not read, is not judged.
        let field = file(&[0, 32768, 0], 0).replace("<DataArray", "<FieldData><DataArray") + "</FieldData>";
        assert_eq!(compressed_size_fault(field.as_bytes()), None);
        // An appended array whose offset cannot be read is left to vtkio,
        // and the arrays after it are still judged.
        let after = file(&[1, 1 << 40, 1 << 40, 20], 20).replace("<VTKFile type=\"UnstructuredGrid\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">", "");
        let both = file(&[1, 800, 800, 20], 20).replace("format=\"binary\">", "format=\"appended\" offset=\"x\">") + &after;
        assert!(compressed_size_fault(both.as_bytes()).is_some_and(|e| e.contains("1099511627776 bytes")));
        assert_eq!(compressed_size_fault(b"<VTKFile type=\"UnstructuredGrid\"><DataArray format=\"binary\">AAAA"), None);
    }

    #[test]
    fn the_time_value_is_the_grid_s_first_child() {
        let xml = r#"<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="1">"#;
        assert_eq!(
            with_time_value(xml.to_string(), 22.95),
            r#"<VTKFile type="UnstructuredGrid"><UnstructuredGrid><FieldData><DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">22.95</DataArray></FieldData><Piece NumberOfPoints="1">"#
        );
    }

    #[test]
    fn a_block_running_past_the_end_is_an_error() {
        let mut bytes = b"<VTKFile header_type=\"UInt32\"><DataArray format=\"appended\" offset=\"0\"/>\n<AppendedData encoding=\"raw\">_".to_vec();
        bytes.extend_from_slice(&100u32.to_le_bytes());
        bytes.extend_from_slice(&[0u8; 10]);
        let err = raw_appended_to_base64(&bytes).unwrap_err();
        assert!(err.contains("offset 0 is larger than the file"), "{err}");
    }
}
