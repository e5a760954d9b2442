//! The layout of a deck: lines without comments, dashed section headers, the rows under
//! each header, and the recognition of section titles.

use super::SectionKind;

/// One non-blank line of the deck, without its comment.
#[derive(Debug, Clone, Copy)]
pub(super) struct Row<'a> {
    /// 1-based line number.
    pub line: usize,
    /// The text before any `#`, trimmed.
    pub text: &'a str,
}

impl<'a> Row<'a> {
    /// The whitespace-separated fields (spaces or tabs).
    pub fn fields(&self) -> Vec<&'a str> {
        self.text.split_whitespace().collect()
    }
}

/// A dashed header line and the rows under it, up to the next dashed line.
#[derive(Debug)]
pub(super) struct Block<'a> {
    /// 1-based line of the header.
    pub line: usize,
    /// The title as written (dashes and outer spaces removed).
    pub title: &'a str,
    /// What the title names.
    pub kind: SectionKind,
    /// The rows under the header.
    pub rows: Vec<Row<'a>>,
}

/// A deck cut into front matter (rows and unknown dashed lines before the first known
/// section) and blocks.
#[derive(Debug)]
pub(super) struct Layout<'a> {
    /// The first text line of the front matter that is not a dashed line nor a comment,
    /// with its line number.
    pub title: Option<(usize, &'a str)>,
    /// The blocks from the first known section on.
    pub blocks: Vec<Block<'a>>,
    /// Line of the last line of the file that holds anything.
    pub last_line: usize,
}

/// `line` without its comment (from the first `#`), trimmed.
fn strip_comment(line: &str) -> &str {
    line.split('#').next().unwrap_or("").trim()
}

/// The title of a dashed header line (`---- LINE TYPES ----` → `LINE TYPES`), or `None`
/// when the line is not a header. MoorDyn takes any line holding `---` for a header; so does
/// this reader, except for a line that is data with a dashed remark (`320 WtrDpth ---
/// water depth (m)`): one whose first field is a number, or whose second field is an option
/// name (`RK4 tScheme --- scheme`).
pub(super) fn header_title(text: &str) -> Option<&str> {
    if !text.contains("---") || dashed_remark(text).is_some() {
        return None;
    }
    Some(text.trim_matches(|c: char| c == '-' || c.is_whitespace()))
}

/// The data before the `---` of a row that holds one but is no header (see
/// [`header_title`]), trimmed; `None` for any other row.
fn dashed_remark(text: &str) -> Option<&str> {
    let at = text.find("---")?;
    let mut fields = text.split_whitespace();
    let first = fields.next()?;
    let option = fields
        .next()
        .is_some_and(|second| !first.contains("---") && super::options::known(second));
    (number(first).is_some() || option).then(|| text[..at].trim_end())
}

/// Section titles and what they name (upper case, single spaces).
const TITLES: &[(&str, SectionKind)] = &[
    ("LINE DICTIONARY", SectionKind::LineTypes),
    ("LINE TYPES", SectionKind::LineTypes),
    ("POINTS", SectionKind::Points),
    ("POINT LIST", SectionKind::Points),
    ("POINT PROPERTIES", SectionKind::Points),
    ("CONNECTION PROPERTIES", SectionKind::Points),
    ("NODE PROPERTIES", SectionKind::Points),
    ("LINES", SectionKind::Lines),
    ("LINE LIST", SectionKind::Lines),
    ("LINE PROPERTIES", SectionKind::Lines),
    ("OPTIONS", SectionKind::Options),
    ("SOLVER OPTIONS", SectionKind::Options),
    ("OUTPUTS", SectionKind::Outputs),
    ("OUTPUT", SectionKind::Outputs),
    ("OUTPUT LIST", SectionKind::Outputs),
    ("ROD TYPES", SectionKind::RodTypes),
    ("ROD DICTIONARY", SectionKind::RodTypes),
    ("BODIES", SectionKind::Bodies),
    ("BODY LIST", SectionKind::Bodies),
    ("BODY PROPERTIES", SectionKind::Bodies),
    ("RODS", SectionKind::Rods),
    ("ROD LIST", SectionKind::Rods),
    ("ROD PROPERTIES", SectionKind::Rods),
    ("FAILURE", SectionKind::Failure),
    ("FAILURES", SectionKind::Failure),
    ("CONTROL", SectionKind::Control),
    ("EXTERNAL LOADS", SectionKind::ExternalLoads),
    ("SYROPE IC", SectionKind::SyropeIc),
];

/// What a header title names. Titles are compared without case, with runs of spaces taken
/// as one; a title may go on after the section's name (`LINE TYPES chain 0.018 m`), so
/// the longest known name that starts the title counts.
pub(super) fn section_kind(title: &str) -> SectionKind {
    let norm = title
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase();
    let starts = |name: &str| {
        norm.strip_prefix(name)
            .is_some_and(|rest| rest.is_empty() || !rest.starts_with(|c: char| c.is_alphanumeric()))
    };
    TITLES
        .iter()
        .filter(|(name, _)| starts(name))
        .max_by_key(|(name, _)| name.len())
        .map_or(SectionKind::Unknown, |(_, kind)| *kind)
}

/// Cuts `text` into front matter and blocks. Line ends may be `\n` or `\r\n`; a leading
/// byte-order mark is skipped.
pub(super) fn layout(text: &str) -> Layout<'_> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut title = None;
    let mut blocks: Vec<Block> = Vec::new();
    let mut last_line = 0;
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let stripped = strip_comment(raw);
        if stripped.is_empty() {
            continue;
        }
        last_line = line;
        if let Some(t) = header_title(stripped) {
            let kind = section_kind(t);
            // Unknown dashed lines before the first section belong to the front matter.
            if kind != SectionKind::Unknown || !blocks.is_empty() {
                blocks.push(Block {
                    line,
                    title: t,
                    kind,
                    rows: Vec::new(),
                });
            }
            continue;
        }
        match blocks.last_mut() {
            Some(b) => b.rows.push(Row {
                line,
                // A dashed remark is dropped, as a comment is.
                text: dashed_remark(stripped).unwrap_or(stripped),
            }),
            None if title.is_none() => title = Some((line, raw.trim())),
            None => {}
        }
    }
    Layout {
        title,
        blocks,
        last_line,
    }
}

/// Whether `field` holds a finite number; see [`number`].
pub(super) fn is_number(field: &str) -> bool {
    number(field).is_some()
}

/// A finite number written the Rust or Fortran way (`3.84e8`, `3.84E+08`, `3.84D8`,
/// `-0.8`, `.5`); `None` for anything else, `inf` and `nan` included.
pub(super) fn number(field: &str) -> Option<f64> {
    let x = match field.parse::<f64>() {
        Ok(x) => x,
        Err(_) if field.contains(['d', 'D']) && !field.contains(['e', 'E']) => {
            field.replace(['d', 'D'], "e").parse::<f64>().ok()?
        }
        Err(_) => return None,
    };
    // `inf`, `nan`, `infinity` parse in Rust; MoorDyn decks never mean them.
    (x.is_finite()
        && !field
            .chars()
            .any(|c| c.is_ascii_alphabetic() && !"eEdD".contains(c)))
    .then_some(x)
}

/// A positive whole number (`1`, `20`, also `20.0` as Fortran decks may write it).
pub(super) fn count(field: &str) -> Option<u32> {
    if let Ok(n) = field.parse::<u32>() {
        return (n >= 1).then_some(n);
    }
    let x = number(field)?;
    (x >= 1.0 && x.fract() == 0.0 && x <= f64::from(u32::MAX)).then_some(x as u32)
}
