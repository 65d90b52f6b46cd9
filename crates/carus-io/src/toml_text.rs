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
}
