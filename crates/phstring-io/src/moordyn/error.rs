//! Errors while reading a MoorDyn deck: each names the file and the 1-based line, and,
//! for a bad value, the column and the text found there.

use std::path::PathBuf;

use crate::text::{clip, printable};

/// User text for a message: shortened and with control characters escaped.
pub(super) fn shown(text: &str) -> String {
    printable(&clip(text), false).into_owned()
}

/// Why a MoorDyn deck could not be read. Messages read `deck.dat:14: MassDen `abc` is not a
/// number`, so that an editor can jump to the line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DeckError {
    /// The file could not be read.
    #[error("cannot read MoorDyn deck {}: {cause}", path.display())]
    Read {
        /// File.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
    /// The file is larger than [`super::MAX_DECK_BYTES`].
    #[error("MoorDyn deck {} is larger than {} MiB; is it a MoorDyn input file?", path.display(), super::MAX_DECK_BYTES >> 20)]
    TooLarge {
        /// File.
        path: PathBuf,
    },
    /// The file is not UTF-8 text, nor UTF-16 with a byte-order mark, nor a deck in Latin-1.
    #[error("MoorDyn deck {} is not UTF-8 text (byte {valid_up_to}, on line {line}, is invalid)", path.display())]
    NotText {
        /// File.
        path: PathBuf,
        /// Bytes before the first invalid one.
        valid_up_to: usize,
        /// 1-based line of the first invalid byte.
        line: usize,
    },
    /// No dashed header line names a MoorDyn section.
    #[error(
        "{file}: no MoorDyn section header (a dashed line such as `---- LINE TYPES ----`) was found"
    )]
    NoSections {
        /// File name, as given.
        file: String,
    },
    /// A section appears twice.
    #[error("{file}:{line}: section `{title}` appears a second time (first at line {first})")]
    DuplicateSection {
        /// File name.
        file: String,
        /// Line of the second header.
        line: usize,
        /// The header's title, as written.
        title: String,
        /// Line of the first header.
        first: usize,
    },
    /// A table lacks its two header rows (column names, then units), or a row there
    /// holds a number, so that it is data and a header row is missing.
    #[error(
        "{file}:{line}: section `{title}` needs two header rows (column names, then units) before its data; found `{text}`"
    )]
    MissingHeader {
        /// File name.
        file: String,
        /// Line of the offending row (or of the section header when the section ends).
        line: usize,
        /// The section's title.
        title: String,
        /// The row found instead (empty when the section ended).
        text: String,
    },
    /// A table row has the wrong number of fields.
    #[error("{file}:{line}: a {table} row needs {expected} fields, this one has {found}")]
    FieldCount {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// Table (`LINE TYPES`, `POINTS`, `LINES`).
        table: &'static str,
        /// What is expected, e.g. `9 or 12`.
        expected: String,
        /// Fields found.
        found: usize,
    },
    /// A field that must be a finite number is not.
    #[error("{file}:{line}: {field} `{}` is not a number", shown(text))]
    NotANumber {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// Column name (MoorDyn's, e.g. `MassDen`).
        field: &'static str,
        /// The text found.
        text: String,
    },
    /// A field that must be a positive whole number (an id, a segment count) is not.
    #[error(
        "{file}:{line}: {field} `{}` is not a whole number of at least 1",
        shown(text)
    )]
    NotACount {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// Column name (`ID`, `NumSegs`, …).
        field: &'static str,
        /// The text found.
        text: String,
    },
    /// Points and lines are numbered 1, 2, 3, … in file order.
    #[error(
        "{file}:{line}: {table} id {found} is out of sequence (MoorDyn numbers them 1, 2, 3, …; expected {expected})"
    )]
    OutOfSequence {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// `POINTS` or `LINES`.
        table: &'static str,
        /// The id written.
        found: u32,
        /// The id expected.
        expected: u32,
    },
    /// A point type (`Attachment` column) that is none of MoorDyn's.
    #[error(
        "{file}:{line}: point type `{}` is not one of Fixed/Fix/Anchor, Vessel/Coupled/Fairlead, Free/Connect/Point, Body<N>, Turbine<N>",
        shown(text)
    )]
    UnknownPointKind {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The text found.
        text: String,
    },
    /// A body type (BODIES `Attachment` column) that is none of MoorDyn's.
    #[error(
        "{file}:{line}: body type `{}` is not one of Fixed/Fix/Anchor, Vessel/Coupled, Free, CoupledPinned/VesselPinned/Pinned",
        shown(text)
    )]
    UnknownBodyKind {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The text found.
        text: String,
    },
    /// A line end that names neither a point (`3`, `P3`, `Point3`, `C3`) nor a rod end
    /// (`R1A`, `Rod2B`).
    #[error(
        "{file}:{line}: {field} `{}` names neither a point (e.g. `3`) nor a rod end (e.g. `R1A`)",
        shown(text)
    )]
    BadAttachment {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// Column name (`AttachA`, `NodeFair`, …).
        field: &'static str,
        /// The text found.
        text: String,
    },
    /// A line end refers to a point the deck does not define.
    #[error("{file}:{line}: {field} refers to point {id}, but the deck defines {count} point(s)")]
    UnknownPoint {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// Column name.
        field: &'static str,
        /// The point id referred to.
        id: u32,
        /// Points defined.
        count: usize,
    },
    /// A line refers to a line type the deck does not define (names are case-sensitive,
    /// as in MoorDyn).
    #[error(
        "{file}:{line}: line type `{}` is not defined in the LINE TYPES section",
        shown(name)
    )]
    UnknownLineType {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The name referred to.
        name: String,
    },
    /// Two line types share a name.
    #[error(
        "{file}:{line}: line type `{}` is defined twice (first at line {first})",
        shown(name)
    )]
    DuplicateLineType {
        /// File name.
        file: String,
        /// Line of the second definition.
        line: usize,
        /// The name.
        name: String,
        /// Line of the first definition.
        first: usize,
    },
    /// An option line that is not `value name [comment]`.
    #[error("{file}:{line}: option `{}` {reason}", shown(text))]
    BadOption {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The line's text.
        text: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// An option's value has the wrong form (e.g. `dtM` not a number).
    #[error("{file}:{line}: option {key} `{}` is not a number", shown(value))]
    OptionNotANumber {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The option's name, as written.
        key: String,
        /// The value found.
        value: String,
    },
    /// Text after the `END` line of the OUTPUTS section.
    #[error("{file}:{line}: `{}` follows the END of the OUTPUTS list", shown(text))]
    AfterEnd {
        /// File name.
        file: String,
        /// Line.
        line: usize,
        /// The text found.
        text: String,
    },
    /// The row count declared by a MoorDyn-F v1 count line (`3 NLines`) differs from the
    /// rows of its table.
    #[error("{file}:{line}: `{key}` declares {declared} row(s), but the table has {found}")]
    CountMismatch {
        /// File name.
        file: String,
        /// Line of the count line.
        line: usize,
        /// The count's name (`NTypes`, `NConnects`, `NLines`).
        key: String,
        /// Rows declared.
        declared: usize,
        /// Rows found.
        found: usize,
    },
    /// A deck entry that phstring's mapping does not support (yet): refused rather than run
    /// approximately. Features that can be dropped on purpose name their `--ignore` word.
    #[error(
        "{file}:{line}: {what} is not supported by phstring{}",
        ignore_hint(ignore)
    )]
    Unsupported {
        /// File name.
        file: String,
        /// Line of the entry.
        line: usize,
        /// What the entry is and why it cannot be mapped.
        what: String,
        /// The `--ignore` word that drops it, if it can be dropped.
        ignore: Option<&'static str>,
    },
    /// A deck that cannot be made into a phstring scenario as written (a free point on no
    /// line, a line from a point to itself, no lines at all).
    #[error("{file}:{line}: {reason}")]
    Unmappable {
        /// File name.
        file: String,
        /// Line of the entry (1 for the deck as a whole).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// An `--ignore` word that names no feature.
    #[error(
        "--ignore {}: not a feature that can be dropped (one of: {known})",
        shown(word)
    )]
    UnknownIgnore {
        /// The word given.
        word: String,
        /// The known words, comma-separated.
        known: String,
    },
}

/// `; give --ignore WORD to drop it` for an ignorable feature, nothing otherwise.
fn ignore_hint(ignore: &Option<&'static str>) -> String {
    match ignore {
        Some(w) => format!(" (give `--ignore {w}` to drop it on purpose)"),
        None => String::new(),
    }
}
