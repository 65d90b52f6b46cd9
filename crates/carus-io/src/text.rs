//! A whitespace tokenizer that keeps line numbers, shared by the text readers.

use std::path::Path;
use std::str::FromStr;

use crate::error::ReadError;

/// Whitespace-separated tokens of a text file, each with its 1-based line.
pub(crate) struct Tokens<'a> {
    path: &'a Path,
    text: &'a str,
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(path: &'a Path, text: &'a str) -> Self {
        Tokens {
            path,
            text,
            pos: 0,
            line: 1,
        }
    }

    /// Line of the last token returned (or of the end of the file).
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// The next token, or `None` at the end of the file.
    pub(crate) fn next_token(&mut self) -> Option<&'a str> {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && bytes[self.pos].is_ascii_whitespace() {
            if bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < bytes.len() && !bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some(&self.text[start..self.pos])
    }

    /// The rest of the current line (after the last token), trimmed; moves
    /// past it.
    pub(crate) fn rest_of_line(&mut self) -> &'a str {
        let rest = &self.text[self.pos..];
        let end = rest.find('\n').unwrap_or(rest.len());
        self.pos += end;
        rest[..end].trim()
    }

    /// The next token, or an error saying the file ended while reading `what`.
    pub(crate) fn expect(&mut self, what: &str) -> Result<&'a str, ReadError> {
        self.next_token().ok_or_else(|| {
            self.error(
                format!("the file ends while reading {what}"),
                "the file looks truncated: export it again",
            )
        })
    }

    /// The next token parsed as `T`.
    pub(crate) fn parse<T: FromStr>(&mut self, what: &str) -> Result<T, ReadError> {
        let token = self.expect(what)?;
        token.parse().map_err(|_| {
            self.error(
                format!("expected {what}, found {token:?}"),
                "the file is corrupted or not in the format its header states: export it again",
            )
        })
    }

    /// The next token, which must be `marker` (a section end such as `$EndNodes`).
    pub(crate) fn expect_marker(&mut self, marker: &str) -> Result<(), ReadError> {
        let token = self.expect(marker)?;
        if token == marker {
            Ok(())
        } else {
            Err(self.error(
                format!("expected {marker}, found {token:?}"),
                "a count in the section header does not match its entries: export the file again",
            ))
        }
    }

    /// An error at the current line.
    pub(crate) fn error(&self, problem: impl Into<String>, fix: impl Into<String>) -> ReadError {
        self.error_at(self.line, problem, fix)
    }

    /// An error at `line` (one already passed, such as a record's first).
    pub(crate) fn error_at(&self, line: usize, problem: impl Into<String>, fix: impl Into<String>) -> ReadError {
        ReadError::Syntax {
            path: self.path.to_path_buf(),
            line,
            problem: problem.into(),
            fix: fix.into(),
        }
    }
}

/// A finite coordinate parsed from `token`, or `None`.
pub(crate) fn finite_f64(token: &str) -> Option<f64> {
    token.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// A number as a message shows it: plainly, or in exponent form when
/// huge (a slip of exponent, 1e300, would print three hundred digits).
pub fn shown_number(x: f64) -> String {
    match x.abs() < 1e6 {
        true => format!("{x}"),
        false => format!("{x:e}"),
    }
}

/// A line of a file as a message quotes it: trimmed, at most 60
/// characters, and any byte no text has shown escaped (`\u{0}`), so that
/// a binary file read as text does not write control bytes to a terminal.
pub fn shown_line(line: &str) -> String {
    let line = line.trim();
    let mut shown: String = line
        .chars()
        .take(60)
        .map(|c| match c.is_control() && c != '\t' {
            true => c.escape_default().to_string(),
            false => c.to_string(),
        })
        .collect();
    if line.chars().nth(60).is_some() {
        shown.push_str("...");
    }
    shown
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quoted_line_shows_no_control_bytes() {
        assert_eq!(shown_line("  ply\u{0}\u{1}x  "), "ply\\u{0}\\u{1}x");
        assert_eq!(shown_line(&"a".repeat(70)), format!("{}...", "a".repeat(60)));
    }

    #[test]
    fn tokens_carry_their_line_numbers() {
        let path = Path::new("t.txt");
        let mut tokens = Tokens::new(path, "a b\n\n  c\nd \"x y\"\n");
        assert_eq!(tokens.next_token(), Some("a"));
        assert_eq!(tokens.line(), 1);
        assert_eq!(tokens.next_token(), Some("b"));
        assert_eq!(tokens.next_token(), Some("c"));
        assert_eq!(tokens.line(), 3);
        assert_eq!(tokens.next_token(), Some("d"));
        assert_eq!(tokens.rest_of_line(), "\"x y\"");
        assert_eq!(tokens.next_token(), None);
        let err = tokens.parse::<u32>("a node count").unwrap_err().to_string();
        assert!(err.starts_with("t.txt:"), "{err}");
        assert!(err.contains("ends while reading a node count"), "{err}");
    }

    #[test]
    fn bad_numbers_name_what_was_expected() {
        let path = Path::new("t.txt");
        let mut tokens = Tokens::new(path, "\n12x");
        let err = tokens.parse::<u64>("a node id").unwrap_err().to_string();
        assert!(
            err.starts_with("t.txt:2: expected a node id, found \"12x\""),
            "{err}"
        );
    }
}
