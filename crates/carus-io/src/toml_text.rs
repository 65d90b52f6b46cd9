//! Reading TOML's errors against the text they came from, for messages
//! that name what the parser leaves out; and vectors read whole, which
//! the parser's arrays do not check.

use std::collections::BTreeMap;
use std::fmt;

use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

/// A key or table written twice: the parser says "duplicate key" and names
/// neither, but its span covers the name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WrittenTwice {
    pub name: String,
    /// A `[table]` header given a second time, not a key in a table.
    pub table: bool,
}

impl WrittenTwice {
    /// The message for it, and the fix.
    pub fn message_and_fix(&self) -> (String, &'static str) {
        match self.table {
            true => (format!("the table `{}` is given a second time", self.name), "put the keys of both into one table"),
            false => (format!("duplicate key `{}`: given a second time in its table", self.name), "keep one of the two lines"),
        }
    }
}

/// What `error` found written twice in `text`, if that is the error.
pub fn written_twice(text: &str, error: &toml::de::Error) -> Option<WrittenTwice> {
    if !error.message().trim().starts_with("duplicate key") {
        return None;
    }
    let span = error.span()?;
    let name = text.get(span.clone())?.trim();
    if name.is_empty() || name.contains('\n') {
        return None;
    }
    let line_start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
    let table = text[line_start..].trim_start().starts_with('[');
    Some(WrittenTwice { name: name.to_string(), table })
}

/// The line of the value of a dotted key as a check names it
/// (`solver.end_time_s`, `displacement[0].node_set`: the key in the first
/// `[[displacement]]` table); None where the text does not write it (a
/// default taken). Job files and labour scenarios point their value errors
/// at it.
pub fn line_of_key(text: &str, key: &str) -> Option<std::num::NonZeroUsize> {
    use toml::de::{DeTable, DeValue};
    let root = DeTable::parse(text).ok()?;
    let mut table = root.get_ref();
    let parts: Vec<&str> = key.split('.').collect();
    for (n, part) in parts.iter().enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((name, rest)) => (name, Some(rest.strip_suffix(']')?.parse::<usize>().ok()?)),
            None => (*part, None),
        };
        let mut value = table.get(name)?;
        if let Some(i) = index {
            let DeValue::Array(items) = value.get_ref() else { return None };
            value = items.get(i)?;
        }
        if n + 1 == parts.len() {
            return std::num::NonZeroUsize::new(crate::input::line_at(text.as_bytes(), value.span().start));
        }
        let DeValue::Table(inner) = value.get_ref() else { return None };
        table = inner;
    }
    None
}

/// Whether the dotted key `outer` is `key` or a table or list holding it
/// (`floor.mesh` holds `floor.mesh.sag_mm`, `trajectory.waypoints` holds
/// `trajectory.waypoints[2].phi_deg`).
pub fn holds_key(outer: &str, key: &str) -> bool {
    key.strip_prefix(outer).is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

/// `file.toml:12`, or the file's name alone where there is no line: how a
/// key's place in a file leads an error message.
pub fn located(path: &std::path::Path, line: Option<std::num::NonZeroUsize>) -> String {
    match line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}

/// `[x, y, z]`, three numbers and no more. A `[f64; 3]` read through
/// toml takes the first three numbers of a longer array and drops the
/// rest unread (toml's arrays do not check that they were read to their
/// end), so a stray fourth number would pass without a word; read
/// through this, it is refused where it stands with "give [x, y, z]".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Xyz(pub [f64; 3]);

impl<'de> Deserialize<'de> for Xyz {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        XyzVisitor { key: None }.deserialize(deserializer)
    }
}

/// Reads an [`Xyz`]; `key`, where known, leads its message (the name of
/// a map entry, which the error's path would not give).
struct XyzVisitor<'a> {
    key: Option<&'a str>,
}

impl<'de> DeserializeSeed<'de> for XyzVisitor<'_> {
    type Value = Xyz;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Xyz, D::Error> {
        deserializer.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for XyzVisitor<'_> {
    type Value = Xyz;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("[x, y, z], three numbers")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Xyz, A::Error> {
        let mut xyz = [0.0; 3];
        let mut count = 0;
        // Read to the end, so that the count said is the count written.
        while let Some(value) = seq.next_element::<f64>()? {
            if let Some(slot) = xyz.get_mut(count) {
                *slot = value;
            }
            count += 1;
        }
        if count != 3 {
            let key = self.key.map_or(String::new(), |k| format!("`{k}`: "));
            let numbers = if count == 1 { "number" } else { "numbers" };
            return Err(de::Error::custom(format!("{key}{count} {numbers} where a vector has 3; give [x, y, z]")));
        }
        Ok(Xyz(xyz))
    }
}

/// `#[serde(deserialize_with = "carus_io::toml_text::xyz")]` on a
/// `[f64; 3]`: see [`Xyz`].
pub fn xyz<'de, D: Deserializer<'de>>(deserializer: D) -> Result<[f64; 3], D::Error> {
    Xyz::deserialize(deserializer).map(|v| v.0)
}

/// [`xyz`] on an `Option<[f64; 3]>` (with `#[serde(default)]`, which
/// `deserialize_with` needs for a key left out).
pub fn optional_xyz<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<[f64; 3]>, D::Error> {
    Option::<Xyz>::deserialize(deserializer).map(|v| v.map(|v| v.0))
}

/// [`xyz`] on each value of a table of named points, its message led by
/// the point's name.
pub fn xyz_by_name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<BTreeMap<String, [f64; 3]>, D::Error> {
    struct Points;
    impl<'de> Visitor<'de> for Points {
        type Value = BTreeMap<String, [f64; 3]>;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a table of name = [x, y, z]")
        }

        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            let mut points = BTreeMap::new();
            while let Some(name) = map.next_key::<String>()? {
                let Xyz(point) = map.next_value_seed(XyzVisitor { key: Some(&name) })?;
                points.insert(name, point);
            }
            Ok(points)
        }
    }
    deserializer.deserialize_map(Points)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn twice(text: &str) -> Option<WrittenTwice> {
        let error = text.parse::<toml::Table>().unwrap_err();
        written_twice(text, &error)
    }

    #[test]
    fn keys_and_tables_written_twice_are_named() {
        assert_eq!(twice("[a]\nx = 1\nx = 2\n"), Some(WrittenTwice { name: "x".into(), table: false }));
        assert_eq!(twice("[a]\nx = 1\n[a]\ny = 2\n"), Some(WrittenTwice { name: "a".into(), table: true }));
        assert_eq!(twice("x = \n"), None);
        let (message, fix) = twice("[solver]\nend_time_s = 1\nend_time_s = 2\n").unwrap().message_and_fix();
        assert_eq!((message.as_str(), fix), ("duplicate key `end_time_s`: given a second time in its table", "keep one of the two lines"));
    }

    /// A vector takes three numbers, no more and no fewer, whole numbers
    /// too; a table of points names the point whose count is wrong.
    #[test]
    fn a_vector_is_three_numbers() {
        #[derive(Debug, Deserialize)]
        struct Holder {
            #[serde(deserialize_with = "xyz")]
            v: [f64; 3],
            #[serde(default, deserialize_with = "optional_xyz")]
            o: Option<[f64; 3]>,
            #[serde(default, deserialize_with = "xyz_by_name")]
            points: BTreeMap<String, [f64; 3]>,
        }
        let read = |text: &str| toml::from_str::<Holder>(text).map_err(|e| e.to_string());
        let held = read("v = [0, 0.5, -1]\n").unwrap();
        assert_eq!((held.v, held.o, held.points.len()), ([0.0, 0.5, -1.0], None, 0));
        assert_eq!(read("v = [1, 2, 3]\no = [4, 5, 6]\n").unwrap().o, Some([4.0, 5.0, 6.0]));
        for (text, count) in [("v = [0.0, 0.0, -9.81, 5.0]\n", "4 numbers"), ("v = [1, 2, 3]\no = [1.0]\n", "1 number")] {
            let e = read(text).unwrap_err();
            assert!(e.contains(&format!("{count} where a vector has 3; give [x, y, z]")), "{e}");
        }
        let e = read("v = [1, 2, 3]\n\n[points]\na = [1, 2, 3]\nb = [1, 2, 3, 999.0]\n").unwrap_err();
        assert!(e.contains("line 5") && e.contains("`b`: 4 numbers where a vector has 3; give [x, y, z]"), "{e}");
        let e = read("v = 9.81\n").unwrap_err();
        assert!(e.contains("expected [x, y, z], three numbers"), "{e}");
    }

    #[test]
    fn a_key_is_held_by_itself_and_the_tables_and_lists_over_it() {
        for outer in ["floor.mesh.sag_mm", "floor.mesh", "floor", "trajectory.waypoints"] {
            let key = if outer.starts_with("trajectory") { "trajectory.waypoints[2].phi_deg" } else { "floor.mesh.sag_mm" };
            assert!(holds_key(outer, key), "{outer} holds {key}");
        }
        assert!(!holds_key("floor.mesh.sag", "floor.mesh.sag_mm"));
        assert!(!holds_key("floor.mesh.sag_mm", "floor.mesh"));
    }

    #[test]
    fn a_key_is_found_on_its_own_line() {
        let text = "[solver]\nend_time_s = 1.0\n\n[[fixed]]\nnode_set = \"a\"\n\n[[fixed]]\n\nnode_set = \"b\"\nload = { shape = \"ramp\", duration_s = -1 }\n";
        let line = |key| line_of_key(text, key).map(std::num::NonZeroUsize::get);
        assert_eq!(line("solver.end_time_s"), Some(2));
        assert_eq!(line("fixed[0].node_set"), Some(5));
        assert_eq!(line("fixed[1].node_set"), Some(9));
        assert_eq!(line("fixed[1].load.duration_s"), Some(10));
        assert_eq!(line("fixed[1]"), Some(7));
        assert_eq!(line("fixed[2].node_set"), None);
        assert_eq!(line("solver.time_step_s"), None);
    }
}
