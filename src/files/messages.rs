//! The words of the TOML layer's messages: serde's errors rephrased with the field path,
//! what was found and what is expected, and the dotted path of each line of a text that may
//! not parse (for syntax errors).

use super::Hint;

/// A number as messages print it: `1e9`, `1e-9`, `0.035`, `NaN` (never 300 digits).
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x.is_finite() && a != 0.0 && !(1e-4..1e6).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A field path without its array indices (`object[2].center[1]` -> `object.center`): the
/// key of a schema's hints.
pub fn generic_path(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    let mut depth = 0;
    for ch in path.chars() {
        match ch {
            '[' => depth += 1,
            ']' => depth -= 1,
            _ if depth == 0 => out.push(ch),
            _ => {}
        }
    }
    out
}

/// `parent.name` (or `name` at the top).
fn join(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}.{name}")
    }
}

/// The text between the first pair of backquotes of `s`.
fn quoted(s: &str) -> Option<&str> {
    let a = s.find('`')? + 1;
    let b = s[a..].find('`')? + a;
    Some(&s[a..b])
}

/// A serde list of names (`` `a` or `b` ``, `` one of `a`, `b`, `c` ``) as `` `a`, `b` ``.
fn names(list: &str) -> String {
    let list = list.trim().trim_start_matches("one of ");
    list.replace(" or ", ", ")
}

/// The field path and the message of a serde error `raw` at `path`; `found` is the text of
/// the value the error points at. The flag: the error is about an enclosing table, locate
/// it by its path rather than by the error's span.
pub(super) fn describe(
    path: &str,
    raw: &str,
    found: &str,
    hint: Hint<'_>,
) -> (String, String, bool) {
    // A table written as an array of tables (`[[image]]`): serde reads a struct from a
    // sequence positionally, so the error lands on an element of it; name the table.
    let mut prefix = String::new();
    for seg in path.split('.') {
        let key = seg.split('[').next().unwrap_or(seg);
        prefix = join(&prefix, key);
        if seg.contains('[')
            && let Some(h) = hint(&prefix).filter(|h| h.starts_with("a table"))
        {
            let name = prefix.clone();
            return (
                prefix,
                format!("must be {h}, got an array of tables [[{name}]]; write [{name}] once"),
                true,
            );
        }
        if let Some(b) = seg.find('[') {
            prefix.push_str(&seg[b..]);
        }
    }
    if raw.starts_with("data did not match any variant of untagged enum PerChannel") {
        // A per-channel field: one value for every channel, or an array of three.
        let h = hint(path).unwrap_or_else(|| "a value".into());
        return (
            path.to_string(),
            format!("must be {h}, or an array of three such values (R, G, B), got {found}"),
            true,
        );
    }
    if let Some(rest) = raw.strip_prefix("missing field ") {
        let name = quoted(rest).unwrap_or(rest);
        let field = join(path, name);
        let req = hint(&field)
            .map(|h| format!(" (required: {h})"))
            .unwrap_or_default();
        return (field, format!("missing field `{name}`{req}"), false);
    }
    if let Some(rest) = raw.strip_prefix("unknown field ") {
        let name = quoted(rest).unwrap_or(rest);
        let allowed = match rest.split_once(", expected ") {
            Some((_, l)) => format!("; allowed: {}", names(l)),
            None => "; this table has no fields".into(),
        };
        return (
            path.to_string(),
            format!("unknown field `{name}`{allowed} (check the spelling)"),
            false,
        );
    }
    if let Some(rest) = raw.strip_prefix("unknown variant ") {
        let name = quoted(rest).unwrap_or(rest);
        let allowed = rest
            .split_once(", expected ")
            .map(|(_, l)| format!("; allowed: {}", names(l)))
            .unwrap_or_default();
        return (
            path.to_string(),
            format!("unknown value \"{name}\"{allowed}"),
            false,
        );
    }
    let field = path.to_string();
    let expected = |e: &str| hint(&field).unwrap_or_else(|| expected_type(e));
    let (got, want) = if let Some(rest) = raw
        .strip_prefix("invalid type: ")
        .or_else(|| raw.strip_prefix("invalid value: "))
    {
        match rest.rsplit_once(", expected ") {
            Some((f, e)) => (found_value(f, found), e.to_string()),
            None => (rest.to_string(), String::new()),
        }
    } else if let Some(rest) = raw.strip_prefix("invalid length ") {
        match rest.split_once(", expected ") {
            Some((n, e)) => (format!("an array of {n} values"), e.to_string()),
            None => (rest.to_string(), String::new()),
        }
    } else {
        // A custom message (a format string that does not parse, a number out of f64).
        let h = hint(&field)
            .map(|h| format!(" (expected {h})"))
            .unwrap_or_default();
        return (field, format!("{raw}{h}"), false);
    };
    let mut msg = format!("must be {}, got {got}", expected(&want));
    let numeric = |e: &str| {
        e.starts_with('i') || e.starts_with('u') || e.starts_with('f') || e.contains("number")
    };
    let unquoted = found.trim().trim_matches(['"', '\'']);
    if got.starts_with("the string") && numeric(&want) && unquoted.parse::<f64>().is_ok() {
        msg.push_str("; write the number without quotes");
    } else if got.starts_with("a table [") && want == "a sequence" {
        msg.push_str(&format!(
            "; write [[{}]], once per entry",
            generic_path(&field)
        ));
    } else if want == "a boolean" && !msg.contains("true or false") {
        msg.push_str("; write true or false");
    }
    (field, msg, false)
}

/// serde's description of a found value (`string "64"`, ``integer `3` ``, `map`) in words;
/// `text` is the value as written.
fn found_value(f: &str, text: &str) -> String {
    let t = text.trim();
    let inner = quoted(f).map(|v| v.trim_end_matches(" as i128").to_string());
    if let Some(s) = f.strip_prefix("string ") {
        format!("the string {s}")
    } else if f.starts_with("integer") || f.starts_with("floating point") {
        format!("the number {}", inner.unwrap_or_else(|| t.to_string()))
    } else if f.starts_with("boolean") {
        inner.unwrap_or_else(|| t.to_string())
    } else if f == "map" {
        if t.starts_with("[[") {
            format!("an array of tables {}", t.lines().next().unwrap_or(t))
        } else if t.starts_with('[') {
            format!("a table {}", t.lines().next().unwrap_or(t))
        } else if t.starts_with('{') {
            "an inline table".into()
        } else if t.starts_with(|c: char| c.is_ascii_digit()) {
            format!("the date-time {t}")
        } else {
            "a table".into()
        }
    } else if f == "sequence" {
        if t.starts_with("[[") {
            format!("an array of tables {}", t.lines().next().unwrap_or(t))
        } else {
            "an array".into()
        }
    } else {
        f.to_string()
    }
}

/// serde's name of an expected type (`i64`, `struct RawImage`, `a sequence`) in words.
fn expected_type(e: &str) -> String {
    match e {
        "i8" | "i16" | "i32" | "i64" | "i128" | "isize" => "an integer".into(),
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" => "an integer >= 0".into(),
        "f32" | "f64" => "a number".into(),
        "a boolean" => "true or false".into(),
        "a sequence" => "an array".into(),
        _ if e.starts_with("struct ") => "a table".into(),
        _ if e.starts_with("an array of length ") => {
            format!("an array of {} values", &e["an array of length ".len()..])
        }
        _ => e.to_string(),
    }
}

/// What one line of a TOML text is, for locating syntax errors.
#[derive(Clone, Debug, Default)]
pub(super) struct LinePath {
    /// Dotted path of the key or table the line belongs to.
    pub(super) path: String,
    /// The line is a table header (`[a]`, `[[a]]`).
    pub(super) header: bool,
    /// The line defines its path (a header, or `key = ...`), rather than continuing one.
    pub(super) defines: bool,
}

/// The dotted path of each line of a TOML text, found by reading headers and keys as text
/// (the text may not parse): `[[object]]` headers are counted to give `object[k]`; a line
/// that continues a multi-line value, a comment and a blank line belong to the last key.
pub(super) fn line_paths(text: &str) -> Vec<LinePath> {
    let key_of = |k: &str| -> String {
        k.split('.')
            .map(|p| p.trim().trim_matches(['"', '\'']))
            .collect::<Vec<_>>()
            .join(".")
    };
    let is_key = |k: &str| {
        !k.trim().is_empty()
            && k.chars()
                .all(|c| c.is_alphanumeric() || "_-.\"' ".contains(c))
    };
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut table = String::new();
    let mut last = LinePath::default();
    let mut out = Vec::new();
    for line in text.split('\n') {
        let t = line.trim();
        let (body, array) = match t.strip_prefix("[[") {
            Some(b) => (Some(b), true),
            None => (t.strip_prefix('['), false),
        };
        let head = body.map(|b| b.split(']').next().unwrap_or(b));
        let rest_ok = body.is_some_and(|b| {
            let after = b.split_once(']').map_or("", |(_, a)| a);
            let after = after.trim_start_matches(']').trim();
            after.is_empty() || after.starts_with('#')
        });
        if let Some(h) = head.filter(|h| is_key(h) && rest_ok) {
            let name = key_of(h);
            // Resolve every prefix that names an array of tables to its last element.
            let mut path = String::new();
            let parts: Vec<&str> = name.split('.').collect();
            for (k, part) in parts.iter().enumerate() {
                path = join(&path, part);
                let generic = generic_path(&path);
                let last_part = k + 1 == parts.len();
                if last_part && array {
                    let n = counts.entry(generic).or_insert(0);
                    *n += 1;
                    path = format!("{path}[{}]", *n - 1);
                } else if last_part {
                    // `[a]` names a table, even where `a` is an array of tables (an error).
                } else if let Some(n) = counts.get(&generic) {
                    path = format!("{path}[{}]", n - 1);
                }
            }
            table = path.clone();
            last = LinePath {
                path,
                header: true,
                defines: true,
            };
            out.push(last.clone());
            continue;
        }
        let key = t.split_once('=').map(|(k, _)| k).filter(|k| is_key(k));
        let key = key.or_else(|| {
            // `key value` without `=`: the first word, if it reads as a key.
            let w = t.split_whitespace().next().unwrap_or("");
            (!t.starts_with('#') && is_key(w) && !w.starts_with(|c: char| c.is_ascii_digit()))
                .then_some(w)
        });
        match key {
            Some(k) => {
                last = LinePath {
                    path: join(&table, &key_of(k)),
                    header: false,
                    defines: true,
                };
                out.push(last.clone());
            }
            None => out.push(LinePath {
                defines: false,
                ..last.clone()
            }),
        }
    }
    out
}

/// The name of `names` nearest to `word` (a mistyped name: `cone_focus` -> `cone-focus`), by
/// the Damerau-Levenshtein distance ignoring case: `None` when none is within a third of the
/// longer name (at least 2 edits), so an unrelated word gets no suggestion.
pub fn nearest<'a>(word: &str, names: &[&'a str]) -> Option<&'a str> {
    let w = word.to_ascii_lowercase();
    names
        .iter()
        .map(|&n| (strsim::damerau_levenshtein(&w, &n.to_ascii_lowercase()), n))
        .filter(|&(d, n)| d <= (w.len().max(n.len()) / 3).max(2))
        .min_by_key(|&(d, _)| d)
        .map(|(_, n)| n)
}
