//! A [`Deck`] mapped onto a phstring network scenario: the scenario's TOML text (so that
//! `--set`, validation and every command work on it unchanged), a table of what each deck
//! entry became, and the record of conversions, unneeded entries and dropped features
//! (the scenario's `[deck]` table). Anything the mapping does not support is refused with
//! the deck's line before any text is made; docs/moordyn.md has the full table.

mod bodies;

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::error::DeckError;
use super::options::OPTION_NAMES;
use super::shape::{Shape, lay_out};
use super::{Attachment, Deck, LineType, LineValue, PointKind, SectionKind, Version};
use crate::scenario::DeckSpec;
use crate::text::num;

/// A deck feature that phstring does not model but that `--ignore WORD` drops on purpose
/// (the run then says so in `summary.json`'s `deck.ignored`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// Bending stiffness `EI > 0` (or an EI curve): phstring's strings have none.
    BendingStiffness,
    /// ROD TYPES / RODS sections.
    Rods,
    /// What phstring's rigid bodies do not take of a deck's body: rotational or per-axis
    /// drag, the mass or water terms of a point fixed to a body.
    Bodies,
    /// FAILURE section (MoorDyn-F).
    Failure,
    /// CONTROL section (MoorDyn-F).
    Control,
    /// EXTERNAL LOADS section (MoorDyn-F).
    ExternalLoads,
    /// `WaveKin` ≠ 0: wave kinematics.
    Waves,
    /// `Currents` ≠ 0: currents read from files.
    Currents,
    /// Vortex-induced vibration: nonzero `Cl`, `dF`, `cF` line type columns.
    Viv,
    /// Steady point forces `FX FY FZ` ≠ 0.
    PointForces,
    /// SYROPE IC section.
    SyropeIc,
    /// Sections with titles MoorDyn's mapping does not know.
    UnknownSections,
    /// Line type columns other than the known ones and the VIV ones.
    ExtraColumns,
    /// Options the mapping does not know.
    UnknownOptions,
}

impl Feature {
    /// Every feature, in the order of docs/moordyn.md.
    pub const ALL: [Feature; 14] = [
        Feature::BendingStiffness,
        Feature::Rods,
        Feature::Bodies,
        Feature::Failure,
        Feature::Control,
        Feature::ExternalLoads,
        Feature::Waves,
        Feature::Currents,
        Feature::Viv,
        Feature::PointForces,
        Feature::SyropeIc,
        Feature::UnknownSections,
        Feature::ExtraColumns,
        Feature::UnknownOptions,
    ];

    /// The `--ignore` word.
    pub fn word(self) -> &'static str {
        match self {
            Feature::BendingStiffness => "EI",
            Feature::Rods => "rods",
            Feature::Bodies => "bodies",
            Feature::Failure => "failure",
            Feature::Control => "control",
            Feature::ExternalLoads => "external_loads",
            Feature::Waves => "waves",
            Feature::Currents => "currents",
            Feature::Viv => "viv",
            Feature::PointForces => "point_forces",
            Feature::SyropeIc => "syrope",
            Feature::UnknownSections => "unknown_sections",
            Feature::ExtraColumns => "extra_columns",
            Feature::UnknownOptions => "unknown_options",
        }
    }

    /// The feature an `--ignore` word names (without case); an error listing the words
    /// otherwise.
    pub fn from_word(word: &str) -> Result<Feature, DeckError> {
        Feature::ALL
            .into_iter()
            .find(|f| f.word().eq_ignore_ascii_case(word.trim()))
            .ok_or_else(|| DeckError::UnknownIgnore {
                word: word.to_string(),
                known: Feature::ALL.map(Feature::word).join(", "),
            })
    }
}

/// One deck entry and what it became (a row of `phstring check DECK`).
#[derive(Debug, Clone, PartialEq)]
pub struct MapRow {
    /// 1-based deck line.
    pub line: usize,
    /// The entry (`line type chain`, `point 4 (Vessel)`, `option dtM = 0.002`).
    pub entry: String,
    /// What it became in the scenario.
    pub became: String,
}

/// A deck mapped onto a scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Mapping {
    /// The scenario's TOML text (with comments naming the deck lines).
    pub scenario: String,
    /// What each deck entry became, in deck order per kind.
    pub rows: Vec<MapRow>,
    /// The `[deck]` record (also in the text).
    pub record: DeckSpec,
}

/// End time [s] of a scenario made from a deck, which has none (rounded up to whole
/// steps); `--set time.end=…` changes it.
pub const DEFAULT_END: f64 = 60.0;
/// Time step [s] when the deck gives no `dtM`.
pub const DEFAULT_DT: f64 = 0.001;
/// Output period [s] of positions and frames when the deck gives no `dtOut` > 0.
pub const DEFAULT_OUTPUT_PERIOD: f64 = 0.1;

/// Options the scenario does not need, with the reason.
const NOT_NEEDED: &[(&str, &str)] = &[
    (
        "TmaxIC",
        "phstring solves the static equilibrium directly ([initial] equilibrium = true) instead of settling the lines in time",
    ),
    ("dtIC", "as TmaxIC: the equilibrium is solved, not settled"),
    (
        "CdScaleIC",
        "as TmaxIC: the equilibrium is solved, not settled",
    ),
    (
        "threshIC",
        "as TmaxIC: the equilibrium is solved, not settled",
    ),
    (
        "tScheme",
        "phstring steps with its own implicit energy-consistent scheme (time.scheme = \"dg\")",
    ),
    (
        "CFL",
        "the implicit scheme has no stability limit; dtM is the largest step",
    ),
    (
        "fileIC",
        "phstring starts from the static equilibrium it solves, not from a saved MoorDyn state",
    ),
    ("writeLog", "phstring records the run in summary.json"),
    (
        "WriteUnits",
        "phstring's outputs carry their units in their column names and docs",
    ),
    (
        "disableOutput",
        "phstring's outputs are switched in [output]",
    ),
    ("disableOutTime", "phstring prints no per-step time stamps"),
    (
        "Echo",
        "phstring echoes nothing; `phstring check` prints the mapping",
    ),
];

/// The deck's option name in its canonical spelling (the first of its
/// [`OPTION_NAMES`] group), or as written.
fn canonical(key: &str) -> &str {
    OPTION_NAMES
        .iter()
        .find(|g| g.iter().any(|n| n.eq_ignore_ascii_case(key)))
        .map_or(key, |g| g[0])
}

/// `x` as a TOML float (shortest exact form).
fn f(x: f64) -> String {
    format!("{x:?}")
}

/// `s` as a TOML string.
fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// Whether `s` is a phstring name (1 to 64 ASCII letters, digits, `_`, `-`, starting with
/// a letter or `_`).
fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 64
        && s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// The state of a mapping under way.
struct Mapper<'d> {
    deck: &'d Deck,
    ignore: &'d [Feature],
    /// The vessel motion (`--motion`), if given.
    motion: Option<&'d VesselMotion>,
    /// The coupled points' node names, for the motion's `[[platform]]`.
    vessels: Vec<String>,
    /// The OUTPUTS channels that are written (`output.channels`).
    channels: Vec<String>,
    /// The points on bodies: per point id, its node reference (`bodyN.pK`, or `pointK` on a
    /// fixed body) and its place [m].
    placed: BTreeMap<u32, (String, [f64; 3])>,
    /// Per free or coupled body id, its points on lines: id and deck coordinates [m].
    members: BTreeMap<u32, Vec<(u32, [f64; 3])>>,
    /// The coupled bodies mapped (ids).
    coupled_bodies: Vec<u32>,
    rows: Vec<MapRow>,
    record: DeckSpec,
    /// The scenario text, table by table.
    text: String,
}

impl Mapper<'_> {
    /// `deck.dat:LINE`.
    fn at(&self, line: usize) -> String {
        format!("{}:{line}", self.deck.file)
    }
    fn row(&mut self, line: usize, entry: impl Into<String>, became: impl Into<String>) {
        self.rows.push(MapRow {
            line,
            entry: entry.into(),
            became: became.into(),
        });
    }
    fn converted(&mut self, line: usize, note: impl AsRef<str>) {
        let note = format!("{}: {}", self.at(line), note.as_ref());
        self.record.converted.push(note);
    }
    /// Refuses `what` at `line`, unless `feature` is ignored: then records it.
    fn unsupported(
        &mut self,
        line: usize,
        what: String,
        feature: Feature,
    ) -> Result<(), DeckError> {
        if self.ignore.contains(&feature) {
            let note = format!("{}: {what} (--ignore {})", self.at(line), feature.word());
            self.record.ignored.push(note);
            self.row(line, what, format!("dropped (--ignore {})", feature.word()));
            return Ok(());
        }
        Err(DeckError::Unsupported {
            file: self.deck.file.clone(),
            line,
            what,
            ignore: Some(feature.word()),
        })
    }
    /// Refuses `what` at `line`; no `--ignore` drops it.
    fn refuse<T>(&self, line: usize, what: String) -> Result<T, DeckError> {
        Err(DeckError::Unsupported {
            file: self.deck.file.clone(),
            line,
            what,
            ignore: None,
        })
    }
    fn unmappable<T>(&self, line: usize, reason: String) -> Result<T, DeckError> {
        Err(DeckError::Unmappable {
            file: self.deck.file.clone(),
            line,
            reason,
        })
    }
}

/// Maps `deck` onto a scenario, dropping the features in `ignore`. Refuses (with the deck
/// line) every entry that the mapping does not support and that is not ignored.
pub fn map(deck: &Deck, ignore: &[Feature]) -> Result<Mapping, DeckError> {
    map_driven(deck, ignore, None)
}

/// A vessel motion for a deck's coupled points (`--motion FILE`): a platform table of the
/// seven columns `t, x, y, z, roll, pitch, yaw` [s, m, m, m, rad, rad, rad]
/// (`[[platform]]` in docs/scenario.md, MoorDyn's angle convention), or a per-point table
/// `t, x1, y1, z1, x2, …` [s, m] with three columns of absolute position per coupled point
/// in point-ID order (MoorDyn's coupled points driven one by one).
#[derive(Debug, Clone)]
pub struct VesselMotion {
    /// The table file (absolute, so that the generated scenario finds it).
    pub path: std::path::PathBuf,
    /// The platform's position [m] and rotation at `t = 0` (the identity for a per-point
    /// table).
    pub start: (phstring::Vector<3>, phstring::linsolve::Block<3>),
    /// The per-point form: per coupled point in ID order, its id, its three columns
    /// (1-based, the time is column 1) and its position at `t = 0` [m]; `None` for a
    /// platform table.
    pub points: Option<Vec<PointColumns>>,
    /// The table's last time [s].
    pub end: f64,
}

/// A coupled point of a per-point `--motion` table: its id, its three columns (1-based,
/// the time is column 1) and its position at `t = 0` [m].
pub type PointColumns = (u32, [usize; 3], [f64; 3]);

/// A `--motion` table whose number of columns fits neither form for the deck, or whose
/// header names platform motions (`surge` … `yaw`, OpenFAST's `PtfmSurge` …) with other than
/// the platform table's 7 columns.
#[derive(Debug, thiserror::Error)]
#[error(
    "--motion {}: has {got} columns{}; the deck's {coupled} coupled point(s) take a platform table of 7 (t, x, y, z, roll, pitch, yaw) or a per-point table of {} (t, then the absolute x, y, z of each coupled point in ID order)",
    path.display(),
    platform_names.as_ref().map_or(String::new(), |n| format!(" and its header names platform motions ({n})")),
    1 + 3 * coupled
)]
pub struct MotionColumnsError {
    /// The table file.
    pub path: std::path::PathBuf,
    /// Its columns.
    pub got: usize,
    /// The deck's coupled points.
    pub coupled: usize,
    /// The header's names of platform motions, if any.
    pub platform_names: Option<String>,
}

/// Whether a table's column name `h` names a platform degree of freedom: `surge`, `sway`,
/// `heave`, `roll`, `pitch` or `yaw` (any case), also with OpenFAST's `Ptfm` prefix
/// (`PtfmRoll`).
fn names_platform_motion(h: &str) -> bool {
    let h = h.trim().to_ascii_lowercase();
    let h = h.strip_prefix("ptfm").unwrap_or(&h);
    ["surge", "sway", "heave", "roll", "pitch", "yaw"].contains(&h)
}

/// Whether `h` names the platform's roll (`roll`, `PtfmRoll`, any case).
fn names_roll(h: &str) -> bool {
    let h = h.trim().to_ascii_lowercase();
    h == "roll" || h == "ptfmroll"
}

impl VesselMotion {
    /// The platform form of the 7-column `table` read from `path`.
    fn platform(path: &std::path::Path, table: &crate::tables::Table) -> Self {
        let start = table
            .platform()
            .unwrap_or_else(|| unreachable!("a table of 7 columns"))
            .pose(0.0);
        let end = *table.times.last().unwrap_or(&0.0);
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        Self {
            path,
            start,
            points: None,
            end,
        }
    }

    /// Reads the table at `path` for the coupled points of `deck`: a platform table (7
    /// columns) or a per-point table (`1 + 3K` columns for `K` coupled points). With two
    /// coupled points both have 7 columns: a header naming `roll` makes it a platform
    /// table; otherwise a v1 deck's (whose Vessel points are fixed to the platform) is one
    /// and a v2 deck's (whose Coupled points move on their own) is a per-point table.
    pub fn for_deck(path: &std::path::Path, deck: &Deck) -> Result<Self, super::LoadError> {
        let table = crate::tables::read_table_any(path)?;
        let coupled: Vec<u32> = deck
            .points
            .iter()
            .filter(|p| p.kind == PointKind::Coupled)
            .map(|p| p.id)
            .collect();
        let columns = table.values.len() + 1;
        let named_roll = table.header.iter().any(|h| names_roll(h));
        let platform_names: Vec<&str> = table
            .header
            .iter()
            .map(|h| h.trim())
            .filter(|h| names_platform_motion(h))
            .collect();
        let refuse = |platform_names: Option<String>| MotionColumnsError {
            path: path.to_path_buf(),
            got: columns,
            coupled: coupled.len(),
            platform_names,
        };
        if !platform_names.is_empty() && columns != 7 {
            return Err(refuse(Some(platform_names.join(", "))).into());
        }
        let per_point = columns == 1 + 3 * coupled.len()
            && !(columns == 7
                && (named_roll || !platform_names.is_empty() || deck.version == Version::V1));
        if per_point {
            let points = coupled
                .iter()
                .enumerate()
                .map(|(m, &id)| {
                    let cols = [2 + 3 * m, 3 + 3 * m, 4 + 3 * m];
                    let at = cols.map(|c| table.signal(c - 2).value(0.0));
                    (id, cols, at)
                })
                .collect();
            let end = *table.times.last().unwrap_or(&0.0);
            return Ok(Self {
                path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
                start: (
                    phstring::Vector::<3>::zeros(),
                    phstring::linsolve::Block::<3>::identity(),
                ),
                points: Some(points),
                end,
            });
        }
        if columns == 7 {
            return Ok(Self::platform(path, &table));
        }
        Err(refuse(None).into())
    }
}

/// The warnings for the coupled points that a per-point `motion` table puts at `t = 0`
/// farther from their deck positions than 1 % of the span of their shortest line (and 1 m):
/// most likely a table of platform offsets read as absolute positions.
fn far_table_starts(deck: &Deck, motion: &VesselMotion) -> Vec<String> {
    let Some(points) = &motion.points else {
        return Vec::new();
    };
    let at = |id: u32| {
        deck.points
            .iter()
            .find(|p| p.id == id)
            .map(|p| phstring::Vector::<3>::from(p.position))
    };
    let span = |id: u32| {
        deck.lines
            .iter()
            .filter_map(|l| match (&l.attach_a, &l.attach_b) {
                (Attachment::Point(a), Attachment::Point(b)) if *a == id || *b == id => {
                    Some((at(*a)? - at(*b)?).norm())
                }
                _ => None,
            })
            .fold(f64::INFINITY, f64::min)
    };
    let mut out = Vec::new();
    for (id, _, start) in points {
        let (Some(deck_at), start) = (at(*id), phstring::Vector::<3>::from(*start)) else {
            continue;
        };
        let off = (start - deck_at).norm();
        let limit = (0.01 * span(*id)).max(1.0);
        if off > limit {
            out.push(format!(
                "--motion {}: the table puts point {id} at ({}, {}, {}) m at t = 0, {:.1} m from its deck position ({}, {}, {}): a per-point table (t, then x, y, z of each coupled point) holds absolute positions; a platform's offsets and rotations take a table of 7 columns whose header names the roll (t, x, y, z, roll, pitch, yaw, or OpenFAST's PtfmSurge … PtfmYaw)",
                motion.path.display(),
                num(start[0]),
                num(start[1]),
                num(start[2]),
                off,
                num(deck_at[0]),
                num(deck_at[1]),
                num(deck_at[2])
            ));
        }
    }
    out
}

/// [`map`] with the deck's coupled points carried by `motion`: they become the supports of
/// one `[[platform]]` driven by its table, their deck positions the body coordinates (so a
/// point starts at `p(0) + R(0) b`), and the run ends at the table's last time.
pub fn map_driven(
    deck: &Deck,
    ignore: &[Feature],
    motion: Option<&VesselMotion>,
) -> Result<Mapping, DeckError> {
    let far = motion.map_or_else(Vec::new, |mv| far_table_starts(deck, mv));
    let moved;
    let deck = match motion {
        Some(mv) => {
            let mut d = deck.clone();
            let (p, r) = &mv.start;
            for pt in d
                .points
                .iter_mut()
                .filter(|pt| pt.kind == PointKind::Coupled)
            {
                pt.position = match &mv.points {
                    Some(list) => list
                        .iter()
                        .find(|(id, _, _)| *id == pt.id)
                        .map_or(pt.position, |(_, _, at)| *at),
                    None => {
                        let b = phstring::Vector::<3>::from(pt.position);
                        let at = p + r * b;
                        [at[0], at[1], at[2]]
                    }
                };
            }
            moved = d;
            &moved
        }
        None => deck,
    };
    let mut m = Mapper {
        deck,
        ignore,
        motion,
        vessels: Vec::new(),
        channels: Vec::new(),
        placed: BTreeMap::new(),
        members: BTreeMap::new(),
        coupled_bodies: Vec::new(),
        rows: Vec::new(),
        record: DeckSpec {
            path: deck.file.clone(),
            version: match deck.version {
                Version::V1 => "v1".into(),
                Version::V2 => "v2".into(),
            },
            warnings: far,
            ..DeckSpec::default()
        },
        text: String::new(),
    };
    // The reader's remarks (how the file was decoded, an option given twice, …).
    for n in &deck.notes {
        m.converted(n.line, &n.text);
    }
    sections(&mut m)?;
    let settings = options(&mut m)?;
    if deck.lines.is_empty() {
        return m.unmappable(
            1,
            "the deck has no lines: there is nothing to simulate".into(),
        );
    }
    let materials = materials(&mut m)?;
    points(&mut m, settings.depth)?;
    bodies::bodies(&mut m, settings.density)?;
    platform(&mut m)?;
    lines(&mut m, &materials, settings.depth)?;
    outputs(&mut m)?;
    settings_text(&mut m, &settings);
    let mut scenario = header(&m);
    scenario.push_str(&m.text);
    scenario.push_str(&record_text(&m.record));
    // In deck order; the rows about the deck as a whole (line 0) last.
    m.rows
        .sort_by_key(|r| if r.line == 0 { usize::MAX } else { r.line });
    Ok(Mapping {
        scenario,
        rows: m.rows,
        record: m.record,
    })
}

/// Refuses (or drops) the sections the mapping does not read.
fn sections(m: &mut Mapper) -> Result<(), DeckError> {
    for s in m.deck.unsupported_sections() {
        let feature = match s.kind {
            SectionKind::RodTypes | SectionKind::Rods => Feature::Rods,
            SectionKind::Bodies => Feature::Bodies,
            SectionKind::Failure => Feature::Failure,
            SectionKind::Control => Feature::Control,
            SectionKind::ExternalLoads => Feature::ExternalLoads,
            SectionKind::SyropeIc => Feature::SyropeIc,
            _ => Feature::UnknownSections,
        };
        let what = format!("section `{}`", super::error::shown(&s.title));
        m.unsupported(s.line, what, feature)?;
    }
    Ok(())
}

/// The settings the options give (time, water, seabed, gravity, output).
#[derive(Debug, Clone, PartialEq)]
struct Settings {
    h: f64,
    g: f64,
    density: f64,
    depth: Option<f64>,
    k_bot: f64,
    c_bot: f64,
    friction: f64,
    fric_damp: f64,
    /// MoorDyn-F's `mu_kA`, if given.
    friction_axial: Option<f64>,
    /// `StatDynFricScale` (1 when not given).
    static_scale: f64,
    stride: u64,
}

/// The transverse (or isotropic) friction coefficient: `FrictionCoefficient` or MoorDyn-F's
/// `mu_kT`, refused when both are given (0 when neither is).
fn friction_coefficient(m: &Mapper) -> Result<f64, DeckError> {
    let o = &m.deck.options;
    match (o.friction_coefficient()?, o.friction_transverse()?) {
        (Some(_), Some(_)) => {
            let line = o.get("mu_kT").map_or(1, |x| x.line);
            m.refuse(
                line,
                "both FrictionCoefficient and mu_kT (two names for the transverse friction coefficient)".into(),
            )
        }
        (a, b) => Ok(a.or(b).unwrap_or(0.0)),
    }
}

/// Reads the options: the mapped ones into [`Settings`], the others recorded as not needed
/// or refused.
fn options(m: &mut Mapper) -> Result<Settings, DeckError> {
    let o = &m.deck.options;
    let h = o.dt_m()?.unwrap_or(DEFAULT_DT);
    let depth = match o.water_depth()? {
        Some(super::WaterDepth::Depth(d)) => Some(d),
        Some(super::WaterDepth::File(name)) => {
            let line = o.get("WtrDpth").map_or(1, |x| x.line);
            return m.refuse(
                line,
                format!(
                    "WtrDpth `{}` (a bathymetry file: phstring's seabed is a plane)",
                    super::error::shown(&name)
                ),
            );
        }
        None => None,
    };
    let positive = |name: &str, x: f64| {
        let line = o.get(name).map_or(1, |x| x.line);
        let reason = format!("option {name} = {x} must be positive");
        if x > 0.0 {
            Ok(())
        } else {
            m.unmappable(line, reason)
        }
    };
    positive("dtM", h)?;
    if let Some(d) = depth {
        positive("WtrDpth", d)?;
    }
    let dt_out = o.dt_out()?.filter(|t| *t > 0.0);
    let period = dt_out.unwrap_or(DEFAULT_OUTPUT_PERIOD);
    let s = Settings {
        h,
        g: o.gravity()?.unwrap_or(9.80665),
        density: o.water_density()?.unwrap_or(1025.0),
        depth,
        k_bot: o.k_bot()?.unwrap_or(3.0e6),
        c_bot: o.c_bot()?.unwrap_or(3.0e5),
        friction: friction_coefficient(m)?,
        fric_damp: o.fric_damp()?.unwrap_or(200.0),
        friction_axial: o.friction_axial()?,
        static_scale: o.stat_dyn_fric_scale()?.unwrap_or(1.0),
        stride: ((period / h).round() as u64).max(1),
    };
    positive("StatDynFricScale", s.static_scale)?;
    let entries = m.deck.options.entries.clone();
    for e in &entries {
        option_entry(m, e, &s)?;
    }
    Ok(s)
}

/// One option line: a row saying what it became, or a record of why it is not needed, or
/// a refusal.
fn option_entry(m: &mut Mapper, e: &super::DeckOption, s: &Settings) -> Result<(), DeckError> {
    let entry = format!("option {} = {}", e.key, e.value);
    let became = match canonical(&e.key) {
        "dtM" => format!("time.h = {} s (the largest step)", s.h),
        "g" => format!("body_force.gravity = [0, 0, -{}] m/s²", s.g),
        "WtrDnsty" => format!("water.density = {} kg/m³", s.density),
        "WtrDpth" => "water.depth (a flat seabed at z = -WtrDpth)".into(),
        "kBot" => format!("seabed.stiffness = {} Pa/m", s.k_bot),
        "cBot" => format!("seabed.damping = {} Pa·s/m", s.c_bot),
        "FrictionCoefficient" => format!("seabed.friction = {}", s.friction),
        "FricDamp" => format!("seabed.friction_damping = {} N·s/m", s.fric_damp),
        "StatDynFricScale" => format!("seabed.friction_static_scale = {}", s.static_scale),
        "mu_kT" => format!("seabed.friction = {} (transverse)", s.friction),
        "mu_kA" => format!(
            "seabed.friction_axial = {}",
            s.friction_axial.unwrap_or(0.0)
        ),
        "dtOut" => format!("output.stride = {} steps", s.stride),
        name @ ("WaveKin" | "Currents") => {
            if super::layout::number(&e.value) == Some(0.0) {
                "nothing (off)".into()
            } else {
                let feature = if name == "WaveKin" {
                    Feature::Waves
                } else {
                    Feature::Currents
                };
                return m.unsupported(e.line, format!("{entry} ({name} from files)"), feature);
            }
        }
        "SeafloorFile" => {
            return m.refuse(
                e.line,
                format!("{entry} (a bathymetry file: phstring's seabed is a plane)"),
            );
        }
        key => match NOT_NEEDED.iter().find(|(n, _)| n.eq_ignore_ascii_case(key)) {
            Some((name, why)) => {
                m.record
                    .not_needed
                    .insert(name.to_string(), why.to_string());
                format!("not needed: {why}")
            }
            None => {
                let what = format!("option `{}` (unknown to the mapping)", e.key);
                return m.unsupported(e.line, what, Feature::UnknownOptions);
            }
        },
    };
    m.row(e.line, entry, became);
    Ok(())
}

/// A line type's material as mapped: the name and the TOML keys other than damping.
#[derive(Debug, Clone)]
struct TypeMaterial {
    name: String,
    keys: String,
    ea: f64,
    rho_a: f64,
    /// BA [N·s] (≥ 0), or the damping ratio ζ (> 0) when BA was negative.
    damping: Damping,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Damping {
    Ba(f64),
    Ratio(f64),
}

/// The materials of the line types that lines use, by line type name.
fn materials(m: &mut Mapper) -> Result<BTreeMap<String, TypeMaterial>, DeckError> {
    let mut out = BTreeMap::new();
    let types = m.deck.line_types.clone();
    for (i, t) in types.iter().enumerate() {
        if !m.deck.lines.iter().any(|l| l.line_type == t.name) {
            m.row(
                t.line,
                format!("line type {}", t.name),
                "nothing (no line uses it)",
            );
            continue;
        }
        let name = if is_name(&t.name) && !types[..i].iter().any(|u| u.name == t.name) {
            t.name.clone()
        } else {
            format!("type{}", i + 1)
        };
        let mat = line_type(m, t, name)?;
        out.insert(t.name.clone(), mat);
    }
    Ok(out)
}

/// One line type: checks and converts its values.
fn line_type(m: &mut Mapper, t: &LineType, name: String) -> Result<TypeMaterial, DeckError> {
    let ea = match &t.ea {
        LineValue::Number(x) if *x > 0.0 => *x,
        LineValue::Number(x) => {
            return m.unmappable(t.line, format!("EA = {x} N must be positive"));
        }
        LineValue::CurveFile(c) => {
            return m.refuse(
                t.line,
                format!(
                    "EA from the curve file `{}` (a tabulated tension–strain law)",
                    super::error::shown(c)
                ),
            );
        }
        LineValue::Parts(p) => {
            return m.refuse(
                t.line,
                format!("viscoelastic EA `{}`", super::error::shown(&p.join("|"))),
            );
        }
    };
    let damping = match &t.ba {
        LineValue::Number(b) if *b >= 0.0 => Damping::Ba(*b),
        LineValue::Number(b) => Damping::Ratio(-b),
        LineValue::CurveFile(c) => {
            return m.refuse(
                t.line,
                format!(
                    "BA from the curve file `{}` (tabulated damping)",
                    super::error::shown(c)
                ),
            );
        }
        LineValue::Parts(p) => {
            return m.refuse(
                t.line,
                format!("viscoelastic BA `{}`", super::error::shown(&p.join("|"))),
            );
        }
    };
    match &t.ei {
        LineValue::Number(x) if *x == 0.0 => {}
        other => {
            let what = match other {
                LineValue::Number(x) => {
                    format!("bending stiffness EI = {x} N·m² of line type {}", t.name)
                }
                _ => format!("a bending stiffness curve of line type {}", t.name),
            };
            m.unsupported(t.line, what, Feature::BendingStiffness)?;
        }
    }
    for (col, value) in &t.extra {
        let zero = super::layout::number(value) == Some(0.0);
        let lower = col.to_ascii_lowercase();
        if ["cl", "df", "cf"].contains(&lower.as_str()) {
            if !zero {
                let what = format!(
                    "vortex-induced vibration ({col} = {value}) of line type {}",
                    t.name
                );
                m.unsupported(t.line, what, Feature::Viv)?;
            }
        } else {
            let what = format!(
                "line type column `{}` = {}",
                super::error::shown(col),
                super::error::shown(value)
            );
            m.unsupported(t.line, what, Feature::ExtraColumns)?;
        }
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !positive(t.diameter) || !positive(t.mass_per_length) {
        return m.unmappable(
            t.line,
            format!(
                "line type {} needs Diam > 0 and MassDen > 0 (found {} m, {} kg/m)",
                t.name, t.diameter, t.mass_per_length
            ),
        );
    }
    let keys = format!(
        "law = \"tension_only_linear\"\nea = {}\nrho_a = {}\nmass = \"lumped\"\ndiameter = {}\ncd = {}\nca = {}\ncd_axial = {}\nca_axial = {}\n",
        f(ea),
        f(t.mass_per_length),
        f(t.diameter),
        f(t.cd),
        f(t.ca),
        f(t.cd_ax),
        f(t.ca_ax)
    );
    let (damp, material) = match damping {
        Damping::Ba(b) => (
            format!("kelvin_voigt = BA/2 = {} N·s", b / 2.0),
            format!("material {name}"),
        ),
        Damping::Ratio(z) => (
            format!("kelvin_voigt from the damping ratio ζ = {z} and each line's segment length"),
            format!("materials {name}_lineN, one per line"),
        ),
    };
    m.row(
        t.line,
        format!("line type {}", t.name),
        format!(
            "{material}: tension_only_linear, EA = {ea} N, rho_a = {} kg/m (in air), lumped mass, diameter {} m, cd {}, ca {}, cd_axial {}, ca_axial {}, {damp}",
            t.mass_per_length, t.diameter, t.cd, t.ca, t.cd_ax, t.ca_ax
        ),
    );
    Ok(TypeMaterial {
        name,
        keys,
        ea,
        rho_a: t.mass_per_length,
        damping,
    })
}

/// The points on lines (none below the seabed at `depth` [m]): named nodes; fixed and vessel points held (`[[boundary]]`), free
/// points with mass as point masses.
fn points(m: &mut Mapper, depth: Option<f64>) -> Result<(), DeckError> {
    let points = m.deck.points.clone();
    for p in &points {
        let entry = format!("point {} ({})", p.id, p.kind_text);
        if let Some(depth) = depth
            && p.position[2] < -depth * (1.0 + 1e-9)
        {
            let z = p.position[2];
            return m.unmappable(
                p.line,
                format!("{entry} at z = {z} m lies below the seabed at WtrDpth = {depth} m"),
            );
        }
        match p.kind {
            PointKind::Body(n) => {
                let on_line = m.deck.lines.iter().any(|l| {
                    l.attach_a == Attachment::Point(p.id) || l.attach_b == Attachment::Point(p.id)
                });
                let became = if on_line {
                    bodies::body_point(m, p, n)?
                } else {
                    "nothing (no line is attached to it)".to_string()
                };
                m.row(p.line, entry, became);
                continue;
            }
            PointKind::Turbine(n) => {
                return m.refuse(p.line, format!("{entry}, attached to turbine {n}"));
            }
            _ => {}
        }
        if let Some(force) = p.force
            && force.iter().any(|x| *x != 0.0)
        {
            let what = format!("the steady force FX FY FZ = {force:?} on {entry}");
            m.unsupported(p.line, what, Feature::PointForces)?;
        }
        let on_line = m.deck.lines.iter().any(|l| {
            l.attach_a == Attachment::Point(p.id) || l.attach_b == Attachment::Point(p.id)
        });
        if !on_line {
            m.row(p.line, entry, "nothing (no line is attached to it)");
            continue;
        }
        let name = format!("point{}", p.id);
        let _ = write!(
            m.text,
            "# {}: {entry}\n[[node]]\nname = {}\nposition = [{}, {}, {}]\n\n",
            m.at(p.line),
            q(&name),
            f(p.position[0]),
            f(p.position[1]),
            f(p.position[2])
        );
        let became = match p.kind {
            PointKind::Coupled if m.motion.is_some() => {
                m.vessels.push(name.clone());
                format!("node {name}, a support moved by the vessel motion (--motion)")
            }
            PointKind::Fixed | PointKind::Coupled => {
                let _ = write!(
                    m.text,
                    "[[boundary]]\nnode = {}\nfixed = true\n\n",
                    q(&name)
                );
                if p.kind == PointKind::Coupled {
                    m.converted(p.line, format!("{entry} is held at its deck position: without a vessel motion a coupled point is a fixed support"));
                    format!("node {name}, a support held at its deck position (no vessel motion)")
                } else {
                    format!("node {name}, a fixed support")
                }
            }
            _ => free_point(m, p, &name)?,
        };
        m.row(p.line, entry, became);
    }
    Ok(())
}

/// The vessel motion's `[[platform]]` over the coupled points (none without `--motion`).
fn platform(m: &mut Mapper) -> Result<(), DeckError> {
    let Some(mv) = m.motion else {
        return Ok(());
    };
    if m.vessels.is_empty() && !m.coupled_bodies.is_empty() {
        return Ok(());
    }
    if m.vessels.is_empty() {
        return m.unmappable(
            1,
            format!(
                "--motion {} moves the deck's Vessel/Coupled points, but no line ends at one",
                mv.path.display()
            ),
        );
    }
    if let Some(points) = &mv.points {
        let table = q(&mv.path.display().to_string());
        let _ = writeln!(
            m.text,
            "# --motion: each coupled point follows its own three columns of the table."
        );
        for (id, cols, _) in points {
            let name = format!("point{id}");
            if !m.vessels.contains(&name) {
                continue;
            }
            let _ = write!(
                m.text,
                "[[boundary]]\nnode = {}\nmotion_table = {table}\nmotion_columns = [{}, {}, {}]\n\n",
                q(&name),
                cols[0],
                cols[1],
                cols[2]
            );
        }
        m.record.converted.push(format!(
            "--motion {}: each coupled point follows its three columns (absolute positions)",
            mv.path.display()
        ));
        return Ok(());
    }
    let nodes: Vec<String> = m.vessels.iter().map(|n| q(n)).collect();
    let _ = write!(
        m.text,
        "# --motion: the vessel's platform table moves the coupled points rigidly.\n[[platform]]\nname = \"vessel\"\nnodes = [{}]\nmotion_table = {}\n\n",
        nodes.join(", "),
        q(&mv.path.display().to_string())
    );
    m.record.converted.push(format!(
        "--motion {}: the coupled points follow the platform table (deck positions are body coordinates)",
        mv.path.display()
    ));
    Ok(())
}

/// A free point: a junction node, with a point mass when it has mass.
fn free_point(m: &mut Mapper, p: &super::Point, name: &str) -> Result<String, DeckError> {
    let has_hydro = p.volume != 0.0 || p.cda != 0.0 || p.ca != 0.0;
    if p.mass < 0.0 {
        return m.unmappable(
            p.line,
            format!("point {} has a negative Mass {} kg", p.id, p.mass),
        );
    }
    if p.mass == 0.0 {
        if has_hydro {
            return m.refuse(
                p.line,
                format!("point {} with Volume, CdA or Ca but no Mass (phstring's point masses need a mass)", p.id),
            );
        }
        return Ok(format!("node {name}, a free junction of its lines"));
    }
    let _ = write!(
        m.text,
        "[[point_mass]]\nnode = {}\nkg = {}\nvolume = {}\ncda = {}\nca = {}\n\n",
        q(name),
        f(p.mass),
        f(p.volume),
        f(p.cda),
        f(p.ca)
    );
    Ok(format!(
        "node {name}, free, with a point mass of {} kg, volume {} m³, CdA {} m², Ca {}",
        p.mass, p.volume, p.cda, p.ca
    ))
}

/// The point a line end is attached to, or a refusal for a rod end.
fn end_point(m: &Mapper, line: &super::Line, end: Attachment) -> Result<super::Point, DeckError> {
    match end {
        Attachment::Point(id) => {
            let mut p = m.deck.points[id as usize - 1].clone();
            if let Some((_, at)) = m.placed.get(&id) {
                p.position = *at;
            }
            Ok(p)
        }
        Attachment::Rod(n, e) => m.refuse(
            line.line,
            format!("line {} attached to end {e:?} of rod {n}", line.id),
        ),
    }
}

/// The strain beyond which a line that starts straight between its ends is taken for a
/// typing error (10 %: steel ropes and chains break near 2 %, fibre ropes near 15–20 %).
const OVERSTRETCH: f64 = 0.1;

/// A warning for line `l` of unstretched `length` [m] between the points at `ends`, one of
/// them on the seabed at the water depth `depth` [m], when it is longer than their
/// horizontal plus vertical distance: its extra length lies slack on the seabed, where
/// (without friction in the statics) its rest state is not unique, so that the starting
/// equilibrium may not be found.
fn slack_on_the_seabed(
    m: &mut Mapper,
    l: &super::Line,
    (a, b): ([f64; 3], [f64; 3]),
    depth: Option<f64>,
    length: f64,
) {
    // Only a line with an end on the seabed (within 1 % of the depth): a slack line between
    // two points in the water hangs as a catenary, whose rest state is unique.
    if !depth.is_some_and(|d| a[2].min(b[2]) <= -0.99 * d) {
        return;
    }
    let path = (b[0] - a[0]).hypot(b[1] - a[1]) + (b[2] - a[2]).abs();
    if length > path * (1.0 + 1e-9) {
        m.record.warnings.push(format!(
            "{}:{}: line {} ({} m) is longer than its ends' horizontal plus vertical distance ({:.1} m): its extra length lies slack on the seabed, where its rest state is not unique; if the starting equilibrium (or `statics`) is not found, run from the deck's layout with `--set initial.equilibrium=false`",
            m.deck.file,
            l.line,
            l.id,
            num(length),
            path
        ));
    }
}

/// The lines: one string each, of `NumSegs` elements through named nodes laid out by
/// [`lay_out`], with its material; `depth` [m] the deck's water depth, if any.
fn lines(
    m: &mut Mapper,
    materials: &BTreeMap<String, TypeMaterial>,
    depth: Option<f64>,
) -> Result<(), DeckError> {
    let mut written: Vec<String> = Vec::new();
    let lines = m.deck.lines.clone();
    for l in &lines {
        let (a, b) = (end_point(m, l, l.attach_a)?, end_point(m, l, l.attach_b)?);
        if a.id == b.id {
            return m.unmappable(
                l.line,
                format!("line {} runs from point {} to itself", l.id, a.id),
            );
        }
        let span = {
            let d = [0, 1, 2].map(|k| b.position[k] - a.position[k]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        };
        let length = if l.unstretched_length < 0.0 {
            let len = -l.unstretched_length * span;
            m.converted(l.line, format!("UnstrLen = {} of line {}: MoorDyn's factor on the distance between the ends, {len} m", l.unstretched_length, l.id));
            len
        } else if l.unstretched_length > 0.0 {
            l.unstretched_length
        } else {
            return m.unmappable(l.line, format!("line {} has UnstrLen 0", l.id));
        };
        slack_on_the_seabed(m, l, (a.position, b.position), depth, length);
        let n = l.segments;
        let shape = lay_out(a.position, b.position, length, n);
        if shape.stretch > 1.0 + OVERSTRETCH {
            m.record.warnings.push(format!(
                "{}:{}: line {} ({} m) starts stretched by {:.1} % to reach its ends {:.1} m apart, more than any rope or chain takes: check its UnstrLen",
                m.deck.file,
                l.line,
                l.id,
                num(length),
                100.0 * (shape.stretch - 1.0),
                span
            ));
        }
        let mat = &materials[&l.line_type];
        let (material, damping) = line_material(m, l, mat, length, &mut written);
        string_text(m, l, &shape, &material, [a.id, b.id]);
        let start = if shape.stretch > 1.0 {
            format!("starts straight, stretched {:.6}", shape.stretch)
        } else if shape.stretch < 1.0 {
            format!("starts straight and slack ({:.6})", shape.stretch)
        } else {
            "starts stress-free along the horizontal from its lower end, then on an arc".into()
        };
        m.row(
            l.line,
            format!("line {} ({}, {} m, {} segments)", l.id, l.line_type, l.unstretched_length, n),
            format!(
                "string line{}: {n} elements of {} m from point{} to point{}, material {material}{damping}; {start}",
                l.id,
                length / f64::from(n),
                a.id,
                b.id
            ),
        );
    }
    Ok(())
}

/// The material of line `l` of type `mat` and unstretched length `length`: the type's
/// (written once, in `written`) or, for a damping ratio, the line's own; and the
/// damping's description.
fn line_material(
    m: &mut Mapper,
    l: &super::Line,
    mat: &TypeMaterial,
    length: f64,
    written: &mut Vec<String>,
) -> (String, String) {
    let seg = length / f64::from(l.segments);
    let type_line = m
        .deck
        .line_types
        .iter()
        .find(|t| t.name == l.line_type)
        .map_or(l.line, |t| t.line);
    match mat.damping {
        Damping::Ba(ba) => {
            if !written.contains(&mat.name) {
                written.push(mat.name.clone());
                let mut keys = mat.keys.clone();
                if ba > 0.0 {
                    let _ = writeln!(keys, "kelvin_voigt = {}", f(ba / 2.0));
                    m.converted(type_line, format!("BA = {ba} N·s of line type {} → kelvin_voigt η = BA/2 = {} N·s: phstring's viscous tension 2ην²ν̇ (ν = 1 + ε) equals MoorDyn's BA·ε̇ at small strain only (2 % more at 1 % strain)", l.line_type, ba / 2.0));
                }
                let _ = write!(
                    m.text,
                    "# {}: line type {}\n[materials.{}]\n{keys}\n",
                    m.at(type_line),
                    l.line_type,
                    mat.name
                );
            }
            let damping = if ba > 0.0 {
                format!(", kelvin_voigt {} N·s", ba / 2.0)
            } else {
                String::new()
            };
            (mat.name.clone(), damping)
        }
        Damping::Ratio(z) => {
            let ba = z * seg * (mat.ea * mat.rho_a).sqrt();
            let name = format!("{}_line{}", mat.name, l.id);
            m.converted(l.line, format!("BA/-zeta = {} of line type {} on line {}: BA = ζ·l_seg·√(EA·ρA) = {ba} N·s with the segment length l_seg = {seg} m (it depends on the mesh, as in MoorDyn: another NumSegs changes it) → kelvin_voigt η = BA/2 = {} N·s, equal to MoorDyn's damping at small strain only", -z, l.line_type, l.id, ba / 2.0));
            let _ = write!(
                m.text,
                "# {}: line type {} with the damping ratio of line {}\n[materials.{name}]\n{}kelvin_voigt = {}\n\n",
                m.at(l.line),
                l.line_type,
                l.id,
                mat.keys,
                f(ba / 2.0)
            );
            (name, format!(", kelvin_voigt {} N·s (ζ = {z})", ba / 2.0))
        }
    }
}

/// The `[[node]]`s inside line `l` and its `[[string]]`.
fn string_text(m: &mut Mapper, l: &super::Line, shape: &Shape, material: &str, ends: [u32; 2]) {
    let n = shape.nodes.len() - 1;
    let _ = writeln!(m.text, "# {}: line {}", m.at(l.line), l.id);
    let node = |id: u32| {
        m.placed
            .get(&id)
            .map_or_else(|| format!("point{id}"), |(name, _)| name.clone())
    };
    let (first, last) = (node(ends[0]), node(ends[1]));
    let mut path = vec![q(&first)];
    for (j, p) in shape.nodes.iter().enumerate().take(n).skip(1) {
        let name = format!("line{}_{j}", l.id);
        let _ = write!(
            m.text,
            "[[node]]\nname = {}\nposition = [{}, {}, {}]\n",
            q(&name),
            f(p[0]),
            f(p[1]),
            f(p[2])
        );
        path.push(q(&name));
    }
    path.push(q(&last));
    let _ = write!(
        m.text,
        "\n[[string]]\nname = \"line{}\"\npath = [{}]\nelements = 1\nmaterial = {}\n",
        l.id,
        path.join(", "),
        q(material)
    );
    if shape.stretch != 1.0 {
        let _ = writeln!(m.text, "prestretch = {}", f(shape.stretch));
    }
    m.text.push('\n');
}

/// The OUTPUTS section: the channels phstring writes go to `output.channels` (a
/// MoorDyn-style table named after the deck); a channel naming a line, node or point the
/// deck does not have is refused with its line, as MoorDyn refuses it; a channel phstring
/// does not write is dropped with a warning (which the run prints). The lines' output flags
/// are not needed.
fn outputs(m: &mut Mapper) -> Result<(), DeckError> {
    let table = out_file_name(&m.deck.file);
    for o in m.deck.outputs.clone() {
        let entry = format!("output {}", o.name);
        let written = match crate::channels::parse(&o.name) {
            Err(why) => Err(why),
            Ok(c) => match deck_channel(m, &c) {
                Ok(w) => w,
                Err(e) => return m.unmappable(o.line, e),
            },
        };
        match written {
            Ok(()) => {
                m.channels.push(o.name.clone());
                m.row(o.line, entry, format!("column {} of {table}", o.name));
            }
            Err(why) => {
                let warning = format!("{}: channel {} is not written: {why}", m.at(o.line), o.name);
                m.record.warnings.push(warning);
                m.row(o.line, entry, format!("not written: {why}"));
            }
        }
    }
    if m.deck.lines.iter().any(|l| l.outputs != "-") {
        let why = "phstring writes every node's position in positions.csv; MoorDyn's per-line files are not written";
        m.record
            .not_needed
            .insert("line output flags".into(), why.into());
    }
    Ok(())
}

/// Whether channel `c` can be written for the deck of `m`: `Ok(Ok(()))` if so,
/// `Ok(Err(why))` if phstring does not write it, `Err` if it names a line, node or point
/// the deck does not have.
fn deck_channel(m: &Mapper, c: &crate::channels::Channel) -> Result<Result<(), String>, String> {
    use crate::channels::{LineNode, Object, Quantity};
    if let Quantity::NotWritten(why) = c.quantity {
        return Ok(Err(why.to_string()));
    }
    match c.object {
        Object::Line(i, node) => {
            let Some(line) = m.deck.lines.get(i as usize - 1) else {
                return Err(format!(
                    "output channel {} reads line {i}, but the deck has {} lines",
                    c.name,
                    m.deck.lines.len()
                ));
            };
            let j = match node {
                LineNode::EndB => line.segments,
                LineNode::Index(j) => j,
            };
            if j > line.segments {
                return Err(format!(
                    "output channel {} reads node {j} of line {i}, which has nodes 0 to {}",
                    c.name, line.segments
                ));
            }
            if matches!(c.quantity, Quantity::Force(_)) && j != 0 && j != line.segments {
                return Ok(Err(crate::channels::INTERIOR_FORCE.into()));
            }
            Ok(Ok(()))
        }
        Object::Point(k) => {
            if k as usize > m.deck.points.len() {
                return Err(format!(
                    "output channel {} reads point {k}, but the deck has {} points",
                    c.name,
                    m.deck.points.len()
                ));
            }
            let attached =
                m.deck.lines.iter().any(|l| {
                    l.attach_a == Attachment::Point(k) || l.attach_b == Attachment::Point(k)
                });
            if !attached {
                return Ok(Err(format!("point {k} has no line and is not simulated")));
            }
            if matches!(c.quantity, Quantity::TensionA | Quantity::TensionB) {
                return Ok(Err("TA and TB are line channels".into()));
            }
            Ok(Ok(()))
        }
    }
}

/// The channel table's file name for the deck `file`: its stem with `.out`, as MoorDyn
/// names its main output file.
fn out_file_name(file: &str) -> String {
    let stem = std::path::Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| crate::files::is_channel_table(&format!("{s}.out")))
        .unwrap_or_else(|| "moordyn".into());
    format!("{stem}.out")
}

/// `[body_force]`, `[water]`, `[seabed]`, `[initial]`, `[time]`, `[output]`.
fn settings_text(m: &mut Mapper, s: &Settings) {
    let span = m.motion.map_or(DEFAULT_END, |mv| mv.end);
    let end = (span / s.h - 1e-9).ceil().max(1.0) * s.h;
    let _ = write!(
        m.text,
        "[body_force]\ngravity = [0.0, 0.0, {}]\n\n[water]\ndensity = {}\n",
        f(-s.g),
        f(s.density)
    );
    match s.depth {
        Some(depth) => {
            let _ = write!(
                m.text,
                "depth = {}\n\n[seabed]\nstiffness = {}\ndamping = {}\nfriction = {}\nfriction_damping = {}\n",
                f(depth),
                f(s.k_bot),
                f(s.c_bot),
                f(s.friction),
                f(s.fric_damp)
            );
            if let Some(a) = s.friction_axial {
                let _ = writeln!(m.text, "friction_axial = {}", f(a));
            }
            if s.static_scale != 1.0 {
                let _ = writeln!(m.text, "friction_static_scale = {}", f(s.static_scale));
            }
            m.text.push('\n');
        }
        None => {
            m.text.push('\n');
            m.record.converted.push(format!(
                "{}: the deck gives no WtrDpth: no seabed",
                m.deck.file
            ));
        }
    }
    let _ = write!(
        m.text,
        "# A deck has no initial shape: the run starts from the static equilibrium.\n[initial]\nequilibrium = true\n\n\
         # A deck has no end time: {span} s (whole steps) unless --set time.end=… is given.\n\
         [time]\nh = {}\nend = {}\n\n[output]\nstride = {}\n",
        f(s.h),
        f(end),
        s.stride
    );
    if !m.channels.is_empty() {
        let names: Vec<String> = m.channels.iter().map(|c| q(c)).collect();
        let _ = write!(
            m.text,
            "# The OUTPUTS channels, in MoorDyn's .out layout.\nchannels = [{}]\nchannels_file = {}\n",
            names.join(", "),
            q(&out_file_name(&m.deck.file))
        );
    }
    m.text.push('\n');
    m.row(
        0,
        "(no end time in a deck)",
        match m.motion {
            Some(_) => format!(
                "time.end = {end} s: the vessel motion's last time; --set time.end=… changes it"
            ),
            None => format!(
                "time.end = {end} s: phstring's default for decks; --set time.end=… changes it"
            ),
        },
    );
    m.row(
        0,
        "(no initial shape in a deck)",
        "[initial] equilibrium = true: the run starts from the static equilibrium",
    );
}

/// The scenario's first lines: where it comes from, title and dimension.
fn header(m: &Mapper) -> String {
    let title = if m.deck.title.is_empty() {
        m.deck.file.clone()
    } else {
        m.deck.title.clone()
    };
    format!(
        "# Scenario generated by phstring from the MoorDyn {} deck {}; each table names the\n# deck line it comes from (docs/moordyn.md has the mapping).\ntitle = {}\ndimension = 3\n\n",
        m.record.version,
        m.deck.file,
        q(&title)
    )
}

/// The `[deck]` table.
fn record_text(r: &DeckSpec) -> String {
    let list = |v: &[String]| {
        let items: Vec<String> = v.iter().map(|s| format!("  {},\n", q(s))).collect();
        format!("[\n{}]", items.concat())
    };
    let mut out = format!(
        "[deck]\npath = {}\nversion = {}\n",
        q(&r.path),
        q(&r.version)
    );
    if !r.converted.is_empty() {
        let _ = writeln!(out, "converted = {}", list(&r.converted));
    }
    if !r.warnings.is_empty() {
        let _ = writeln!(out, "warnings = {}", list(&r.warnings));
    }
    if !r.ignored.is_empty() {
        let _ = writeln!(out, "ignored = {}", list(&r.ignored));
    }
    if !r.not_needed.is_empty() {
        out.push_str("\n[deck.not_needed]\n");
        for (k, v) in &r.not_needed {
            let _ = writeln!(out, "{} = {}", q(k), q(v));
        }
    }
    out
}
