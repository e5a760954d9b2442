//! MoorDyn input decks read into a typed [`Deck`]: parsing only; mapping a deck onto a
//! phstring scenario is a separate step.
//!
//! A deck is plain text. The front matter (a title line, notes) runs up to the first
//! dashed header line naming a section (`---- LINE TYPES ----`, any number of dashes,
//! any case). Each table section has two header rows (column names, then units) and then
//! one row per item; fields are separated by spaces or tabs; `#` starts a comment. The
//! OPTIONS section holds `value name [remark]` lines, the OUTPUTS section channel names.
//! A last dashed line (`---- END ----`) closes the file. Both MoorDyn v1 and v2 decks are
//! read; see [`Version`] for how the two are told apart and `docs/moordyn.md` for the
//! format as read.
//!
//! Sections this reader does not read (rods, failures, …) are listed in
//! [`Deck::sections_present`] with their line numbers, so that a later step can refuse
//! them with `deck.dat:LINE`.

mod error;
mod layout;
mod map;
#[cfg(test)]
mod map_tests;
mod options;
mod shape;
mod tables;
#[cfg(test)]
mod tests;

use std::path::Path;

pub use error::DeckError;
pub use map::{
    DEFAULT_DT, DEFAULT_END, DEFAULT_OUTPUT_PERIOD, Feature, MapRow, Mapping, MotionColumnsError,
    VesselMotion, map, map_driven,
};
pub use options::{DeckOption, OPTION_NAMES, Options, WaterDepth};

use layout::{Block, Layout};

/// Largest deck read [bytes] (16 MiB; decks are a few KiB).
pub const MAX_DECK_BYTES: u64 = 16 << 20;

/// The deck format generation.
///
/// The two differ in the column order of LINE TYPES (v1 has no `EI` and writes added
/// mass before drag: `Can Cat Cdn Cdt`; v2 writes `EI Cd Ca CdAx CaAx`) and of LINES
/// (v1: `UnstrLen NumSegs NodeAnch NodeFair`; v2: `AttachA AttachB UnstrLen NumSegs`).
/// The lines section decides: titled `LINES` or `LINE LIST`, the deck is v2; titled
/// `LINE PROPERTIES`, it is v1 unless the third column name names a line end
/// (`AttachA`, `NodeA`, `EndA`, `AnchA`…), as some v2 decks keep the old title. Without
/// a lines section, a v1-only title (`LINE DICTIONARY`, `NODE PROPERTIES`,
/// `CONNECTION PROPERTIES`) makes it v1, anything else v2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Version {
    /// MoorDyn v1 (and MoorDyn-F before v2).
    V1,
    /// MoorDyn v2 (MoorDyn-C and MoorDyn-F alike).
    V2,
}

/// A line type value that MoorDyn accepts either as a number or as the name of a curve
/// file (EA: tension against strain; BA: damping against strain rate; EI: bending
/// moment against curvature).
#[derive(Debug, Clone, PartialEq)]
pub enum LineValue {
    /// A constant, in the column's unit.
    Number(f64),
    /// A file name, as written (relative to the deck, as MoorDyn reads it).
    CurveFile(String),
    /// A bar-separated entry (`EA_s|EA_d` viscoelastic stiffness, `BA_s|BA_d`, or
    /// `SYROPE:…|…|…`), its parts kept raw.
    Parts(Vec<String>),
}

impl LineValue {
    /// The constant, when the value is one.
    pub fn number(&self) -> Option<f64> {
        match self {
            LineValue::Number(x) => Some(*x),
            _ => None,
        }
    }
}

/// One row of the LINE TYPES (v1: LINE DICTIONARY) section.
#[derive(Debug, Clone, PartialEq)]
pub struct LineType {
    /// Name the lines refer to (case-sensitive, as in MoorDyn).
    pub name: String,
    /// Volume-equivalent diameter [m] (`Diam`).
    pub diameter: f64,
    /// Mass per unit length in air [kg/m] (`MassDen`, `Mass/m`).
    pub mass_per_length: f64,
    /// Axial stiffness EA [N], or a tension–strain curve file.
    pub ea: LineValue,
    /// Internal axial damping (`BA/-zeta`): positive, BA [N·s]; negative, minus the
    /// damping ratio as a fraction of critical (-0.8 asks for 80 %); kept as written.
    pub ba: LineValue,
    /// Bending stiffness EI [N·m²] (v2 only; 0 for v1 decks, which have no such column).
    pub ei: LineValue,
    /// Transverse drag coefficient [-], on frontal area d·l (v2 `Cd`, v1 `Cdn`).
    pub cd: f64,
    /// Transverse added mass coefficient [-] (v2 `Ca`, v1 `Can`).
    pub ca: f64,
    /// Tangential drag coefficient [-], on surface area π·d·l (v2 `CdAx`, v1 `Cdt`).
    pub cd_ax: f64,
    /// Tangential added mass coefficient [-] (v2 `CaAx`, v1 `Cat`).
    pub ca_ax: f64,
    /// Further columns (v2 `Cl`, `dF`, `cF`, …) as (header name, raw text), in order; a
    /// column without a header name is called `columnN` (N counted from 1).
    pub extra: Vec<(String, String)>,
    /// 1-based line in the file.
    pub line: usize,
}

/// What a point is attached to (the `Attachment`, v1 `Type`, column).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointKind {
    /// Fixed in space (`Fixed`, `Fix`, `Anchor`).
    Fixed,
    /// Moved by the coupled program (`Vessel`, `Coupled`, `Fairlead`, `Ves`, `Cpld`);
    /// coordinates are relative to the vessel. A number after the word (`Vessel1`) is
    /// ignored, as MoorDyn-C does, and kept in [`Point::kind_text`].
    Coupled,
    /// Free: moved by the forces on it (`Free`, `Connect`, `Con`, `Point`); the position
    /// is the initial guess.
    Free,
    /// Fixed to body N (`Body2`), coordinates relative to that body.
    Body(u32),
    /// Coupled to turbine N of a MoorDyn-F farm (`Turbine3`).
    Turbine(u32),
}

/// One row of the POINTS (v1: NODE / CONNECTION PROPERTIES) section.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Id, 1, 2, 3, … in file order.
    pub id: u32,
    /// What the point is attached to.
    pub kind: PointKind,
    /// The attachment word as written (`Vessel`, `anchor`, `Body1`).
    pub kind_text: String,
    /// Position [m] (x, y, z; z up from the still water line), relative to the vessel or
    /// body for attached points.
    pub position: [f64; 3],
    /// Point mass [kg] (clump weight).
    pub mass: f64,
    /// Displaced volume [m³] (float).
    pub volume: f64,
    /// Steady external force (`FX FY FZ`, 12-column rows only), as written: v1 headers
    /// label them kN while MoorDyn's text says N; the reader does not convert.
    pub force: Option<[f64; 3]>,
    /// Drag coefficient times projected area [m²].
    pub cda: f64,
    /// Added mass coefficient [-], on the displaced volume.
    pub ca: f64,
    /// 1-based line in the file.
    pub line: usize,
}

/// What a body is attached to (the BODIES `Attachment` column).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Fixed in space (`Fixed`, `Fix`, `Anchor`).
    Fixed,
    /// Moved by the coupled program (`Vessel`, `Coupled`, `Ves`, `Cpld`, a number after the
    /// word ignored).
    Coupled,
    /// Free: moved by the forces on it (`Free`).
    Free,
    /// Coupled in translation, free to turn (`CoupledPinned`, `VesselPinned`, `Pinned`).
    Pinned,
}

/// One row of the BODIES section (v2): `ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG* I*
/// Volume CdA* Ca*`; the starred columns take one value or several separated by `|`.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Id, 1, 2, 3, … in file order.
    pub id: u32,
    /// What the body is attached to.
    pub kind: BodyKind,
    /// The attachment word as written.
    pub kind_text: String,
    /// The body's reference point [m] (`X0 Y0 Z0`) and orientation [deg] (`r0 p0 y0`,
    /// `R = Rx(r0) Ry(p0) Rz(y0)`).
    pub pose: [f64; 6],
    /// Mass [kg] (`Mass`).
    pub mass: f64,
    /// Centre of gravity relative to the reference point, body axes [m] (`CG`): one value
    /// (along z) or three (`x|y|z`), as written.
    pub cg: Vec<f64>,
    /// Moments of inertia about the centre of gravity, body axes [kg·m²] (`I`): one value
    /// (all three) or three (`Ix|Iy|Iz`), as written.
    pub inertia: Vec<f64>,
    /// Displaced volume [m³] (`Volume`).
    pub volume: f64,
    /// Drag areas [m²] (`CdA`): 1, 2, 3 or 6 values, as written (MoorDyn: one for all six
    /// degrees of freedom; translation|rotation; per axis for both; per degree of freedom;
    /// MoorDyn 2.7.2 reads the first of 3 or 6 values as 0).
    pub cda: Vec<f64>,
    /// Added-mass coefficients [-] (`Ca`): 1, 3 or 6 values, as written (MoorDyn reads 1 or
    /// 3, translational; the mapping refuses 6).
    pub ca: Vec<f64>,
    /// 1-based line in the file.
    pub line: usize,
}

/// Which end of a rod a line is attached to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RodEnd {
    /// End A (the rod's first end).
    A,
    /// End B.
    B,
}

/// What a line end is attached to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attachment {
    /// Point N (checked to exist).
    Point(u32),
    /// End A or B of rod N (not checked: rods are not read).
    Rod(u32, RodEnd),
}

/// One row of the LINES (v1: LINE PROPERTIES) section.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Id, 1, 2, 3, … in file order.
    pub id: u32,
    /// Name of its [`LineType`] (checked to exist).
    pub line_type: String,
    /// First end (MoorDyn's anchor end, node 0): v2 `AttachA`, v1 `NodeAnch`.
    pub attach_a: Attachment,
    /// Last end (fairlead end): v2 `AttachB`, v1 `NodeFair`.
    pub attach_b: Attachment,
    /// Unstretched length [m].
    pub unstretched_length: f64,
    /// Number of segments (the line has one node more).
    pub segments: u32,
    /// Output flags as written (`p` positions, `t` tensions, …; `-` for none).
    pub outputs: String,
    /// 1-based line in the file.
    pub line: usize,
}

/// One channel of the OUTPUTS section (`FairTen1`, `L1N10T`, `Point3PX`), as written.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputChannel {
    /// Channel name.
    pub name: String,
    /// 1-based line in the file.
    pub line: usize,
}

/// What a dashed section header names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SectionKind {
    /// `LINE TYPES`, `LINE DICTIONARY` (read).
    LineTypes,
    /// `POINTS`, `POINT LIST`, `POINT PROPERTIES`, `CONNECTION PROPERTIES`,
    /// `NODE PROPERTIES` (read).
    Points,
    /// `LINES`, `LINE LIST`, `LINE PROPERTIES` (read).
    Lines,
    /// `OPTIONS`, `SOLVER OPTIONS` (read).
    Options,
    /// `OUTPUTS`, `OUTPUT` (read).
    Outputs,
    /// `ROD TYPES`, `ROD DICTIONARY` (not read).
    RodTypes,
    /// `BODIES`, `BODY LIST`, `BODY PROPERTIES` (read).
    Bodies,
    /// `RODS`, `ROD LIST`, `ROD PROPERTIES` (not read).
    Rods,
    /// `FAILURE` (MoorDyn-F; not read).
    Failure,
    /// `CONTROL` (MoorDyn-F; not read).
    Control,
    /// `EXTERNAL LOADS` (MoorDyn-F; not read).
    ExternalLoads,
    /// `SYROPE IC` (not read).
    SyropeIc,
    /// A dashed line with rows under it whose title is none of the above (not read).
    Unknown,
}

impl SectionKind {
    /// Whether this reader reads the section's contents.
    pub fn is_read(self) -> bool {
        matches!(
            self,
            SectionKind::LineTypes
                | SectionKind::Points
                | SectionKind::Lines
                | SectionKind::Bodies
                | SectionKind::Options
                | SectionKind::Outputs
        )
    }
}

/// A section header found in the deck.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// What it names.
    pub kind: SectionKind,
    /// The title as written, without the dashes.
    pub title: String,
    /// 1-based line of the header.
    pub line: usize,
}

/// A remark about the deck that is not an error (e.g. no closing dashed line).
#[derive(Debug, Clone, PartialEq)]
pub struct Note {
    /// 1-based line it refers to.
    pub line: usize,
    /// The remark.
    pub text: String,
}

/// A MoorDyn input deck, read but not interpreted.
#[derive(Debug, Clone, PartialEq)]
pub struct Deck {
    /// File name as given (for messages: `deck.dat:14`).
    pub file: String,
    /// The title line (the first text line of the front matter, trimmed; empty if none).
    pub title: String,
    /// The format generation.
    pub version: Version,
    /// Line types in file order.
    pub line_types: Vec<LineType>,
    /// Points in file order (ids 1, 2, 3, …).
    pub points: Vec<Point>,
    /// Lines in file order (ids 1, 2, 3, …).
    pub lines: Vec<Line>,
    /// Bodies in file order (ids 1, 2, 3, …; v2 BODIES).
    pub bodies: Vec<Body>,
    /// Options, raw, with typed getters.
    pub options: Options,
    /// Output channels in order.
    pub outputs: Vec<OutputChannel>,
    /// Every section header, in file order, read or not ([`SectionKind::is_read`]).
    pub sections_present: Vec<Section>,
    /// Remarks: how a file that is not UTF-8 was read ([`load`]), an option given more
    /// than once, a missing closing line; the mapping lists them under `converted`.
    pub notes: Vec<Note>,
}

impl Deck {
    /// The sections present that this reader does not read, with their lines.
    pub fn unsupported_sections(&self) -> impl Iterator<Item = &Section> {
        self.sections_present.iter().filter(|s| !s.kind.is_read())
    }
}

/// Reads the deck at `path` (at most [`MAX_DECK_BYTES`]): UTF-8, or else UTF-16 with a
/// byte-order mark, or else Latin-1 when the text then looks like a deck
/// ([`looks_like_moordyn`]); the first note of [`Deck::notes`] says when it was not UTF-8.
pub fn load(path: &Path) -> Result<Deck, DeckError> {
    let (text, note) = load_text(path)?;
    let mut deck = parse(&text, &path.display().to_string())?;
    deck.notes.splice(0..0, note);
    Ok(deck)
}

/// Whether `text` looks like a MoorDyn deck: its dashed header lines name at least two
/// different MoorDyn sections, one of them describing the structure (line types, points,
/// lines, rod types, rods or bodies), and it is not valid TOML (so that a scenario file
/// whose comments or strings mention those titles is never taken for a deck). The file
/// name plays no part.
pub fn looks_like_moordyn(text: &str) -> bool {
    let l = layout::layout(text);
    let mut kinds: Vec<SectionKind> = Vec::new();
    for b in &l.blocks {
        if b.kind != SectionKind::Unknown && !kinds.contains(&b.kind) {
            kinds.push(b.kind);
        }
    }
    let structure = kinds.iter().any(|k| {
        matches!(
            k,
            SectionKind::LineTypes
                | SectionKind::Points
                | SectionKind::Lines
                | SectionKind::RodTypes
                | SectionKind::Rods
                | SectionKind::Bodies
        )
    });
    kinds.len() >= 2 && structure && text.parse::<toml::Table>().is_err()
}

/// Parses deck `text`; `file` names it in messages.
pub fn parse(text: &str, file: &str) -> Result<Deck, DeckError> {
    let l = layout::layout(text);
    if l.blocks.is_empty() {
        return Err(DeckError::NoSections {
            file: file.to_string(),
        });
    }
    let mut notes = Vec::new();
    let sections = sections(file, &l, &mut notes)?;
    let version = version(&l.blocks);
    let block = |kind| l.blocks.iter().find(|b| b.kind == kind);
    let line_types = match block(SectionKind::LineTypes) {
        Some(b) => {
            let (names, rows) = tables::table(file, b)?;
            tables::line_types(file, version, &names, rows)?
        }
        None => Vec::new(),
    };
    let points = match block(SectionKind::Points) {
        Some(b) => tables::points(file, tables::table(file, b)?.1)?,
        None => Vec::new(),
    };
    let lines = match block(SectionKind::Lines) {
        Some(b) => {
            let rows = tables::table(file, b)?.1;
            tables::lines(file, version, rows, &line_types, &points)?
        }
        None => Vec::new(),
    };
    let bodies = match block(SectionKind::Bodies) {
        Some(b) => tables::bodies(file, tables::table(file, b)?.1)?,
        None => Vec::new(),
    };
    let options = match block(SectionKind::Options) {
        Some(b) => options::read_options(file, &b.rows)?,
        None => options::read_options(file, &[])?,
    };
    let outputs = match block(SectionKind::Outputs) {
        Some(b) => tables::outputs(file, &b.rows)?,
        None => Vec::new(),
    };
    notes.extend(options::repeated(&options));
    Ok(Deck {
        file: file.to_string(),
        title: l.title.map(|(_, t)| t.to_string()).unwrap_or_default(),
        version,
        line_types,
        points,
        lines,
        bodies,
        options,
        outputs,
        sections_present: sections,
        notes,
    })
}

/// The sections present, in order. A known section must not appear twice. A dashed line
/// with an unknown title and no rows is a divider, not a section; the last one closes
/// the deck. When the deck ends without one, a note says so (the deck is read all the
/// same).
fn sections(file: &str, l: &Layout, notes: &mut Vec<Note>) -> Result<Vec<Section>, DeckError> {
    let mut out: Vec<Section> = Vec::new();
    let n = l.blocks.len();
    for (i, b) in l.blocks.iter().enumerate() {
        if b.kind == SectionKind::Unknown && b.rows.is_empty() {
            continue;
        }
        if b.kind != SectionKind::Unknown
            && let Some(first) = out.iter().find(|s| s.kind == b.kind)
        {
            return Err(DeckError::DuplicateSection {
                file: file.to_string(),
                line: b.line,
                title: error::shown(b.title),
                first: first.line,
            });
        }
        if i + 1 == n {
            notes.push(Note {
                line: l.last_line,
                text: "no closing dashed line (`---- END ----`) after the last section; \
                       the deck is read to the end of the file"
                    .to_string(),
            });
        }
        out.push(Section {
            kind: b.kind,
            title: b.title.to_string(),
            line: b.line,
        });
    }
    Ok(out)
}

/// The deck's [`Version`], from the lines section (see there).
fn version(blocks: &[Block]) -> Version {
    let upper = |t: &str| {
        t.split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_uppercase()
    };
    if let Some(b) = blocks.iter().find(|b| b.kind == SectionKind::Lines) {
        if !upper(b.title).starts_with("LINE PROPERTIES") {
            return Version::V2;
        }
        let mut rows = b.rows.iter();
        let mut names = rows.next();
        if names.is_some_and(|r| tables::count_line(r).is_some()) {
            names = rows.next();
        }
        let third = names
            .and_then(|r| r.fields().get(2).map(|f| f.to_ascii_lowercase()))
            .unwrap_or_default();
        let end = ["attach", "node", "end", "anch", "fair", "point", "con"]
            .iter()
            .any(|p| third.starts_with(p));
        return if end { Version::V2 } else { Version::V1 };
    }
    let v1 = blocks.iter().any(|b| {
        let t = upper(b.title);
        [
            "LINE DICTIONARY",
            "NODE PROPERTIES",
            "CONNECTION PROPERTIES",
        ]
        .iter()
        .any(|k| t.starts_with(k))
    });
    if v1 { Version::V1 } else { Version::V2 }
}

/// Why a scenario or deck could not be loaded by [`load_scenario`].
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The deck could not be read or mapped.
    #[error(transparent)]
    Deck(#[from] DeckError),
    /// The scenario (the file, or the one generated from the deck) is invalid.
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// `--ignore` was given for a scenario file, which has nothing to drop.
    #[error(
        "--ignore {0}: {1} is a scenario file, not a MoorDyn deck; --ignore applies to decks only"
    )]
    IgnoreWithoutDeck(String, String),
    /// The vessel motion of `--motion` could not be read.
    #[error("--motion: {0}")]
    Motion(#[from] crate::tables::TableError),
    /// The `--motion` table fits neither form for the deck's coupled points.
    #[error(transparent)]
    MotionColumns(#[from] MotionColumnsError),
    /// `--motion` was given for a scenario file, whose supports name their own motions.
    #[error(
        "--motion {0}: {1} is a scenario file, not a MoorDyn deck; a scenario moves its supports with position or motion_table keys"
    )]
    MotionWithoutDeck(String, String),
}

/// A scenario read by [`load_scenario`], and the mapping when it came from a deck.
pub struct Loaded {
    /// The scenario (for a deck: the generated one, named [`generated_name`]).
    pub file: crate::scenario::ScenarioFile,
    /// The deck's mapping, for a deck.
    pub mapping: Option<Mapping>,
}

/// The name under which the scenario generated from the deck at `path` appears in
/// messages: `deck.dat (generated scenario)`; its line numbers are those of the text that
/// `phstring check deck.dat --print-scenario` prints.
pub fn generated_name(path: &Path) -> std::path::PathBuf {
    format!("{} (generated scenario)", path.display()).into()
}

/// Reads `path` as a scenario file or, when its content is a MoorDyn deck
/// ([`looks_like_moordyn`]), reads the deck, maps it ([`map`], dropping the features named
/// in `ignore`, `--ignore` words) and parses the generated scenario; then applies the
/// `--set` overrides `sets` either way.
pub fn load_scenario(path: &Path, sets: &[String], ignore: &[String]) -> Result<Loaded, LoadError> {
    load_scenario_driven(path, sets, ignore, None)
}

/// [`load_scenario`] with the deck's coupled points moved by the platform table at `motion`
/// (`--motion FILE`, [`map_driven`]); refused for a scenario file.
pub fn load_scenario_driven(
    path: &Path,
    sets: &[String],
    ignore: &[String],
    motion: Option<&Path>,
) -> Result<Loaded, LoadError> {
    let refuse_motion = || match motion {
        Some(mv) => Err(LoadError::MotionWithoutDeck(
            mv.display().to_string(),
            path.display().to_string(),
        )),
        None => Ok(()),
    };
    let (text, note) = match load_text(path) {
        Ok(t) => t,
        // Let the scenario reader report what is wrong with the file.
        Err(_) => {
            refuse_motion()?;
            return plain(path, sets, ignore);
        }
    };
    if !looks_like_moordyn(&text) {
        refuse_motion()?;
        return plain(path, sets, ignore);
    }
    let features = ignore
        .iter()
        .map(|w| Feature::from_word(w))
        .collect::<Result<Vec<_>, _>>()?;
    let mut deck = parse(&text, &path.display().to_string())?;
    deck.notes.splice(0..0, note);
    let vessel = motion
        .map(|p| VesselMotion::for_deck(p, &deck))
        .transpose()?;
    let mapping = map_driven(&deck, &features, vessel.as_ref())?;
    let file = crate::scenario::parse(&mapping.scenario, &generated_name(path), sets)?;
    Ok(Loaded {
        file,
        mapping: Some(mapping),
    })
}

/// A scenario file, refusing `--ignore`.
fn plain(path: &Path, sets: &[String], ignore: &[String]) -> Result<Loaded, LoadError> {
    if let Some(w) = ignore.first() {
        return Err(LoadError::IgnoreWithoutDeck(
            w.clone(),
            path.display().to_string(),
        ));
    }
    Ok(Loaded {
        file: crate::scenario::load(path, sets)?,
        mapping: None,
    })
}

/// The text of `path` (at most [`MAX_DECK_BYTES`]) and, when it is not UTF-8, a note saying
/// how it was read: as UTF-16 when it starts with a UTF-16 byte-order mark (`FF FE` little
/// endian, `FE FF` big endian), else as Latin-1 (one character per byte; decks exported on
/// Windows carry `°` or `²` in titles and unit rows) when the text then looks like a deck.
/// A file that is none of these is refused naming the byte and its line.
fn load_text(path: &Path) -> Result<(String, Option<Note>), DeckError> {
    use std::io::Read as _;
    let read_err = |cause| DeckError::Read {
        path: path.to_path_buf(),
        cause,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(read_err)?
        .take(MAX_DECK_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_err)?;
    if bytes.len() as u64 > MAX_DECK_BYTES {
        return Err(DeckError::TooLarge {
            path: path.to_path_buf(),
        });
    }
    let e = match String::from_utf8(bytes) {
        Ok(text) => return Ok((text, None)),
        Err(e) => e,
    };
    let valid_up_to = e.utf8_error().valid_up_to();
    let bytes = e.into_bytes();
    if let Some((text, order)) = utf16(&bytes) {
        let text_note =
            format!("the file is UTF-16 ({order}, with its byte-order mark); read as UTF-16");
        return Ok((
            text,
            Some(Note {
                line: 1,
                text: text_note,
            }),
        ));
    }
    let line = crate::text::line_of_byte(&bytes, valid_up_to);
    let latin1: String = bytes.iter().map(|&b| char::from(b)).collect();
    if looks_like_moordyn(&latin1) {
        let text = format!(
            "the file is not UTF-8 (byte 0x{:02X}, offset {valid_up_to}, is the first that is not); read as Latin-1, one character per byte",
            bytes[valid_up_to]
        );
        return Ok((latin1, Some(Note { line, text })));
    }
    Err(DeckError::NotText {
        path: path.to_path_buf(),
        valid_up_to,
        line,
    })
}

/// `bytes` decoded as UTF-16 when they start with a byte-order mark (`FF FE`: little endian,
/// `FE FF`: big endian) and the rest is valid UTF-16 of whole code units; the text (without
/// the mark) and the byte order in words.
fn utf16(bytes: &[u8]) -> Option<(String, &'static str)> {
    let (big, order) = match bytes {
        [0xFF, 0xFE, ..] => (false, "little endian"),
        [0xFE, 0xFF, ..] => (true, "big endian"),
        _ => return None,
    };
    let body = &bytes[2..];
    if !body.len().is_multiple_of(2) {
        return None;
    }
    let units: Vec<u16> = body
        .chunks_exact(2)
        .map(|p| {
            let pair = [p[0], p[1]];
            if big {
                u16::from_be_bytes(pair)
            } else {
                u16::from_le_bytes(pair)
            }
        })
        .collect();
    String::from_utf16(&units).ok().map(|t| (t, order))
}
