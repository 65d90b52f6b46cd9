//! Reading TOML's errors against the text they came from, for messages
//! that name what the parser leaves out.

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
