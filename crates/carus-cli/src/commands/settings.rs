//! `--set KEY=VALUE[,VALUE...]`: a scenario key changed from the command
//! line. `carus run`, `sanity` and `bench labour` take one value per key,
//! `carus sweep` several. A value is a TOML value (a bare word is a
//! string), so the commas between values are only those outside its
//! arrays, inline tables and strings.

use anyhow::bail;

/// One key and the values it takes.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Setting {
    pub(super) key: String,
    pub(super) values: Vec<String>,
}

/// clap's check of a `--set` argument's form: a malformed one is a bad
/// argument (exit status 2), named before anything runs.
pub(super) fn setting_arg(text: &str) -> Result<String, String> {
    parse_setting(text).map(|_| text.to_string()).map_err(|e| e.to_string())
}

/// A key and its one value, for commands that run once with it (`carus
/// run`, `carus sanity`, `carus bench labour`).
pub(super) fn one_setting(text: &str) -> anyhow::Result<(String, String)> {
    one_setting_of("--set", "`carus sweep` runs several", text)
}

/// clap's check of a one-value `--set` argument: a malformed one is a bad
/// argument (exit status 2), named before anything runs.
pub(super) fn one_setting_arg(text: &str) -> Result<String, String> {
    one_setting(text).map(|_| text.to_string()).map_err(|e| e.to_string())
}

/// A key and its one value set in every run of a sweep (`carus sweep
/// --with`), the first run's included.
pub(super) fn fixed_setting(text: &str) -> anyhow::Result<(String, String)> {
    one_setting_of("--with", "sweep a key's values with --set", text)
}

/// clap's check of a `--with` argument.
pub(super) fn fixed_setting_arg(text: &str) -> Result<String, String> {
    fixed_setting(text).map(|_| text.to_string()).map_err(|e| e.to_string())
}

/// One value for a key given to `flag`; `several` says where more go.
fn one_setting_of(flag: &str, several: &str, text: &str) -> anyhow::Result<(String, String)> {
    match text.split_once('=') {
        Some((key, value)) if !key.trim().is_empty() && !value.trim().is_empty() => {}
        // `KEY=` alone (a shell variable that was empty, say): the value is what is missing.
        Some((key, _)) if !key.trim().is_empty() => bail!(
            "{flag} {text}: the value after `=` is empty; give one, e.g. {flag} contact.friction=0.1 \
             (`carus scenarios show normal` lists every key with its value; quote a text, e.g. description=\"\")"
        ),
        _ => bail!("{flag} {text}: write KEY=VALUE, e.g. {flag} contact.friction=0.1"),
    }
    let setting = parse_setting_of(flag, text)?;
    let [value] = setting.values.as_slice() else {
        bail!("{flag} {text}: one value per key here; {several}");
    };
    Ok((setting.key, value.clone()))
}

pub(super) fn parse_setting(text: &str) -> anyhow::Result<Setting> {
    parse_setting_of("--set", text)
}

/// A key and its values as given to `flag`.
fn parse_setting_of(flag: &str, text: &str) -> anyhow::Result<Setting> {
    let Some((key, values)) = text.split_once('=') else {
        bail!("{flag} {text}: write KEY=V1,V2,..., e.g. {flag} expulsion.period_s=8,16,32");
    };
    let values = split_values(values).map_err(|why| anyhow::anyhow!("{flag} {text}: {why}; a value is TOML (quote a string with commas, e.g. description=\"a, b\")"))?;
    let values: Vec<String> = values.into_iter().map(|v| v.trim().to_string()).collect();
    if key.trim().is_empty() {
        bail!("{flag} {text}: no key before `=`; write KEY=V1,V2,..., e.g. {flag} contact.friction=0.1,0.35");
    }
    if let [only] = values.as_slice() {
        if only.is_empty() {
            bail!("{flag} {text}: the value after `=` is empty; give at least one, e.g. {flag} contact.friction=0.1,0.35");
        }
    }
    if let Some(n) = values.iter().position(String::is_empty) {
        bail!(
            "{flag} {text}: value {} of {} is empty (two commas together, or one at an end); \
             list values with one comma between each, e.g. {flag} contact.friction=0.1,0.35",
            n + 1,
            values.len()
        );
    }
    if let Some(twice) = values.iter().enumerate().find_map(|(i, v)| values[..i].iter().any(|u| same_value(u, v)).then_some(v)) {
        bail!("{flag} {text}: the value {twice} is given twice; each value runs once");
    }
    Ok(Setting {
        key: key.trim().to_string(),
        values,
    })
}

/// Whether two values as written are the same value for a key: equal as
/// TOML, numbers by value (so `1`, `1.0` and `1e0` are one number, in an
/// array too), and a bare word the string it stands for (`LOT` is `"LOT"`).
fn same_value(a: &str, b: &str) -> bool {
    let read = |v: &str| normalised(v.parse::<toml::Value>().unwrap_or_else(|_| toml::Value::String(v.to_string())));
    read(a) == read(b)
}

/// A TOML value with its integers made floats, at any depth.
fn normalised(value: toml::Value) -> toml::Value {
    match value {
        toml::Value::Integer(i) => toml::Value::Float(i as f64),
        toml::Value::Array(items) => toml::Value::Array(items.into_iter().map(normalised).collect()),
        toml::Value::Table(table) => toml::Value::Table(table.into_iter().map(|(k, v)| (k, normalised(v))).collect()),
        other => other,
    }
}

/// The values of a list split at its commas, but not at those inside a
/// TOML array, inline table or string (`fetal_spine,[0.0,0.2,-1.0]` is
/// two values; `{time_s=1.0, station_mm=0.0}` and `"slow, steady"` one).
/// A quote opens a string only where a value starts (so `o'brien.stl` is
/// a bare word); brackets must pair and strings close.
fn split_values(list: &str) -> Result<Vec<&str>, String> {
    let mut values = Vec::new();
    let mut open: Vec<char> = Vec::new();
    let (mut quote, mut escaped, mut start, mut prev) = (None::<char>, false, 0, None::<char>);
    // Only blanks since the last `,`, `[`, `{` or `=` (or the start).
    let mut value_starts = true;
    for (i, c) in list.char_indices() {
        match quote {
            Some(_) if escaped => escaped = false,
            Some('"') if c == '\\' => escaped = true,
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None => {
                match c {
                    // A quote right after a closing one goes on a """ or ''' string.
                    '"' | '\'' if value_starts || prev == Some(c) => quote = Some(c),
                    '[' | '{' => open.push(c),
                    ']' | '}' => {
                        let opener = if c == ']' { '[' } else { '{' };
                        if open.pop() != Some(opener) {
                            return Err(format!("`{c}` closes no `{opener}`"));
                        }
                    }
                    ',' if open.is_empty() => {
                        values.push(&list[start..i]);
                        start = i + 1;
                    }
                    _ => {}
                }
                value_starts = matches!(c, ',' | '[' | '{' | '=') || (value_starts && c.is_whitespace());
            }
        }
        prev = Some(c);
    }
    if let Some(q) = quote {
        return Err(format!("a string opened with {q} is never closed"));
    }
    if let Some(b) = open.last() {
        return Err(format!("`{b}` is never closed"));
    }
    values.push(&list[start..]);
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_parse_into_keys_and_values() {
        assert_eq!(
            parse_setting("expulsion.period_s=8, 16,32").unwrap(),
            Setting {
                key: "expulsion.period_s".into(),
                values: vec!["8".into(), "16".into(), "32".into()]
            }
        );
        assert_eq!(
            parse_setting("expulsion.direction=fetal_spine,[0.0, 0.2,-1.0]").unwrap().values,
            vec!["fetal_spine".to_string(), "[0.0, 0.2,-1.0]".to_string()]
        );
        for bad in ["expulsion.period_s", "=8", "contact.friction=0.1,", "x=", "contact.friction=0.1,0.1"] {
            assert!(parse_setting(bad).is_err(), "{bad}");
        }
        // The same value written two ways runs once too.
        for twice in [
            "numerics.end_time_s=0.3,0.30",
            "expulsion.force_max_n=1,1.0",
            "contact.friction=1e-1,0.1",
            "floor.coupling=\"held\",\"held\"",
            "start.position=LOT,\"LOT\"",
            "expulsion.direction=[0,0,-1],[0.0,0.0,-1.0]",
        ] {
            let e = parse_setting(twice).err().unwrap_or_else(|| panic!("{twice} ran twice")).to_string();
            assert!(e.contains("is given twice"), "{e}");
        }
        assert!(parse_setting("expulsion.direction=fetal_spine,pivot").is_ok());
        // An empty value is said to be one, with an example.
        let e = one_setting("contact.friction=").unwrap_err().to_string();
        assert!(e.contains("--set contact.friction=: the value after `=` is empty; give one, e.g. --set contact.friction=0.1"), "{e}");
        let e = fixed_setting("output.vtu= ").unwrap_err().to_string();
        assert!(e.contains("--with output.vtu= : the value after `=` is empty"), "{e}");
        let e = parse_setting("contact.friction=").unwrap_err().to_string();
        assert!(e.contains("the value after `=` is empty; give at least one, e.g. --set contact.friction=0.1,0.35"), "{e}");
        let e = parse_setting("contact.friction=0.1,,0.2").unwrap_err().to_string();
        assert!(e.contains("value 2 of 3 is empty"), "{e}");
        assert!(parse_setting("=8").unwrap_err().to_string().contains("no key before `=`"));
        assert!(one_setting("=8").unwrap_err().to_string().contains("write KEY=VALUE"));
        assert!(parse_setting("expulsion.force_max_n=1,1.5").is_ok());
    }

    /// Commas inside an inline table or a string belong to the one value.
    #[test]
    fn commas_inside_a_value_do_not_split_it() {
        let waypoint = "{time_s=0.1, station_mm=-55.0, theta_deg=-1.5, phi_deg=0.1}";
        assert_eq!(one_setting(&format!("trajectory.waypoints[0]={waypoint}")).unwrap().1, waypoint);
        assert_eq!(one_setting("description=\"labour, slow\"").unwrap().1, "\"labour, slow\"");
        assert_eq!(one_setting("description='a, b'").unwrap().1, "'a, b'");
        assert_eq!(one_setting(r#"description="say \"a, b\"""#).unwrap().1, r#""say \"a, b\"""#);
        assert_eq!(
            parse_setting("trajectory.waypoints=[{time_s=1.0, station_mm=0.0}],[{time_s=2.0, station_mm=1.0}]").unwrap().values.len(),
            2
        );
        assert_eq!(parse_setting("description=\"a, b\",\"c\"").unwrap().values, ["\"a, b\"", "\"c\""]);
        assert!(one_setting("contact.friction=0.1,0.35").unwrap_err().to_string().contains("carus sweep"));
        // Triple-quoted strings, and a quote inside a bare word.
        assert_eq!(one_setting(r#"description="""a, b""""#).unwrap().1, r#""""a, b""""#);
        assert_eq!(parse_setting("pelvis.import=o'brien.toml,b.toml").unwrap().values, ["o'brien.toml", "b.toml"]);
    }

    /// Values that are not whole (a string left open, brackets that do not
    /// pair) are refused with what is wrong, not taken as one value.
    #[test]
    fn unbalanced_values_are_refused() {
        for (bad, why) in [
            ("description=\"abc,def", "never closed"),
            ("x=a],b", "`]` closes no `[`"),
            ("expulsion.direction=[0,0,-1]],pivot", "`]` closes no `[`"),
            ("x=[1,2},3", "`}` closes no `{`"),
            ("x=[1,2", "`[` is never closed"),
        ] {
            let e = parse_setting(bad).expect_err(bad).to_string();
            assert!(e.contains(why) && e.contains("a value is TOML"), "{bad}: {e}");
        }
    }
}
