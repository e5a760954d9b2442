//! Parsing helpers and `--set` overrides: the brace limit, TOML error positions, and
//! applying `key.path=value` options to the document before it is parsed.

use std::ops::Range;
use std::path::Path;

use super::{Origin, ScenarioError};
use crate::text::clip;

/// Most `{` characters in a scenario file or a `--set` option. The TOML parser recurses once
/// per `{` in some malformed inline tables (about 1 KB of stack each in release builds, more
/// in debug builds); real scenarios have a handful.
pub const MAX_BRACES: usize = 256;

/// Refuses `text` with more than [`MAX_BRACES`] `{` (see [`ScenarioError::TooManyBraces`]).
pub(super) fn check_braces(text: &str, what: impl FnOnce() -> String) -> Result<(), ScenarioError> {
    let count = text.bytes().filter(|&b| b == b'{').count();
    if count > MAX_BRACES {
        return Err(ScenarioError::TooManyBraces {
            what: what(),
            count,
        });
    }
    Ok(())
}

pub(super) fn toml_error(
    path: &Path,
    text: &str,
    span: Option<Range<usize>>,
    message: &str,
    shifted: bool,
) -> ScenarioError {
    let start = span.map_or(0, |s| s.start);
    let (line, column) = line_col(text, start);
    let origin = Origin::File {
        path: path.to_path_buf(),
        line,
        column,
        shifted,
    };
    let excerpt = match &origin {
        Origin::File { line, .. } => text
            .lines()
            .nth(line - 1)
            .map(|l| format!("\n  | {}", clip(l)))
            .unwrap_or_default(),
        _ => String::new(),
    };
    ScenarioError::Toml {
        origin,
        message: format!("{}{excerpt}", message.trim_end()),
    }
}

/// `message` with each line shortened by [`clip`] (a parser message quotes the offending
/// line, which may be megabytes long).
pub(super) fn clip_lines(message: &str) -> String {
    message.lines().map(clip).collect::<Vec<_>>().join("\n")
}

/// 1-based line and column of byte offset `pos` in `text`.
pub(super) fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let before = &text[..text.floor_char_boundary(pos)];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Most planned steps (`time.end / time.h`) of a run: 1e10 steps take days even on the
/// Most segments of a `--set` key (the deepest scenario key has three, `boundary.0.force`).
pub const MAX_KEY_SEGMENTS: usize = 32;
/// Longest `--set` key [bytes].
pub const MAX_KEY_BYTES: usize = 256;

/// Applies one `key.path=value` to the document; returns the dotted key (array indices
/// counted from the start, as validation names keys) and the value text.
pub(super) fn apply_set(
    doc: &mut toml_edit::DocumentMut,
    option: &str,
) -> Result<(String, String), ScenarioError> {
    let err = |reason: &str| ScenarioError::Set {
        option: option.to_string(),
        reason: reason.to_string(),
    };
    let (key, value) = option
        .split_once('=')
        .ok_or_else(|| err("expected key=value, e.g. mesh.elements=300"))?;
    let key = key.trim();
    if key.len() > MAX_KEY_BYTES {
        return Err(err(&format!(
            "the key is {} bytes long; scenario keys have at most {MAX_KEY_BYTES}",
            key.len()
        )));
    }
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    if parts.len() > MAX_KEY_SEGMENTS {
        return Err(err(&format!(
            "the key has {} segments; scenario keys have at most {MAX_KEY_SEGMENTS}",
            parts.len()
        )));
    }
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err("empty key segment"));
    }
    let parsed = set_value(value).map_err(&err)?;
    // Walk down the tables; `path` is the key as validation names it.
    let mut table: &mut dyn toml_edit::TableLike = doc.as_table_mut();
    let mut path: Vec<String> = Vec::new();
    let mut i = 0;
    loop {
        let part = parts[i];
        path.push(part.to_string());
        if i + 1 == parts.len() {
            table.insert(part, toml_edit::Item::Value(parsed));
            return Ok((path.join("."), value.to_string()));
        }
        if table.get(part).is_none() {
            // Implicit: a table that only holds other tables gets no `[a.b]` header line of
            // its own.
            let mut t = toml_edit::Table::new();
            t.set_implicit(true);
            table.insert(part, toml_edit::Item::Table(t));
        }
        let here = path.join(".");
        let item = table
            .get_mut(part)
            .ok_or_else(|| err(&format!("no key `{here}`")))?;
        i += 1;
        table = match item {
            toml_edit::Item::ArrayOfTables(arr) => {
                let len = arr.len();
                let idx: i64 = parts[i].parse().map_err(|_| {
                    let rest = match parts.get(i + 1..) {
                        Some(r) if !r.is_empty() => r.join("."),
                        _ => "node".to_string(),
                    };
                    err(&format!(
                        "`{here}` is an array of tables: address an entry by its 0-based index, e.g. {here}.0.{rest} (negative indices count from the end)"
                    ))
                })?;
                let k = if idx < 0 { idx + len as i64 } else { idx };
                if !(0..len as i64).contains(&k) {
                    return Err(err(&format!("index {idx} out of range ({len} entries)")));
                }
                if i + 1 == parts.len() {
                    return Err(err("cannot replace a whole table"));
                }
                path.push(k.to_string());
                i += 1;
                arr.get_mut(k as usize)
                    .ok_or_else(|| err(&format!("index {idx} out of range ({len} entries)")))?
            }
            other => other
                .as_table_like_mut()
                .ok_or_else(|| err(&format!("`{here}` is not a table")))?,
        };
    }
}

/// The value of a `--set` option: one TOML value (which may span lines, like an array), or
/// else the text as a string. A string cannot span lines: such text is refused instead of
/// being cut at the line break.
fn set_value(value: &str) -> Result<toml_edit::Value, &'static str> {
    match value.trim().parse::<toml_edit::Value>() {
        Ok(v) => Ok(v.decorated(" ", "")),
        Err(_) if value.contains(['\n', '\r']) => Err(
            "the value has a line break but is not one TOML value (text that is not TOML is taken as a string, which must fit on one line)",
        ),
        Err(_) => Ok(toml_edit::Value::from(value.trim())),
    }
}
