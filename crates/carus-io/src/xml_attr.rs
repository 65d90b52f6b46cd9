//! Attributes of the XML tags in the VTK files read here (`.vtu`, `.pvd`),
//! found by scanning the text rather than parsing it whole: ParaView and
//! other writers may use either quote and any whitespace between them.

/// The value of `name="..."` (or `name='...'`, as XML allows) inside one
/// XML tag.
pub(crate) fn attribute(tag: &str, name: &str) -> Option<String> {
    let &(start, end) = attribute_spans(tag, name).ok()?.first()?;
    Some(tag[start..end].to_string())
}

/// The value spans (start, end) of every `name` attribute in `text`, in
/// either quotes, as whole names only (`offset` inside `xoffset` does not
/// count).
pub(crate) fn attribute_spans(text: &str, name: &str) -> Result<Vec<(usize, usize)>, String> {
    let pattern = format!("{name}=");
    let mut spans = Vec::new();
    let mut search = 0;
    while let Some(at) = text[search..].find(&pattern) {
        let start = search + at;
        let value_start = start + pattern.len();
        search = value_start;
        if start > 0 && !text.as_bytes()[start - 1].is_ascii_whitespace() {
            continue;
        }
        let Some(quote) = text[value_start..].chars().next().filter(|c| matches!(c, '"' | '\'')) else {
            continue;
        };
        let end = text[value_start + 1..]
            .find(quote)
            .map(|e| value_start + 1 + e)
            .ok_or_else(|| format!("a `{name}` attribute is not closed"))?;
        spans.push((value_start + 1, end));
        search = end;
    }
    Ok(spans)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_read_in_either_quotes_and_whole() {
        let tag = r#"<DataArray xName="no" Name='fixed' format="ascii""#;
        assert_eq!(attribute(tag, "Name").as_deref(), Some("fixed"));
        assert_eq!(attribute(tag, "format").as_deref(), Some("ascii"));
        assert_eq!(attribute(tag, "offset"), None);
    }

    #[test]
    fn offsets_are_found_in_either_quotes_and_whole() {
        let text = r#"<DataArray xoffset="9" offset='12'/><DataArray offset="0"/>"#;
        let spans = attribute_spans(text, "offset").unwrap();
        let values: Vec<&str> = spans.iter().map(|&(s, e)| &text[s..e]).collect();
        assert_eq!(values, ["12", "0"]);
        assert!(attribute_spans(r#"<DataArray offset="3/>"#, "offset").unwrap_err().contains("not closed"));
    }
}
