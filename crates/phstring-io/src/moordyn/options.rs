//! The OPTIONS (v1: SOLVER OPTIONS) section: `value name [comment]` lines, kept raw, with
//! typed getters that know MoorDyn's alternative names.

use super::error::DeckError;
use super::layout::{Row, is_number, number};

/// One option line, as written.
#[derive(Debug, Clone, PartialEq)]
pub struct DeckOption {
    /// The option's name as written (`dtM`, `kb`, `WtrDnsty`, …).
    pub key: String,
    /// The value as written (MoorDyn puts it first on the line).
    pub value: String,
    /// Whatever follows the name on the line (MoorDyn's description), joined by spaces.
    pub remark: String,
    /// 1-based line in the file.
    pub line: usize,
}

/// The water depth option: a number [m] or, in MoorDyn-F, the name of a bathymetry file.
#[derive(Debug, Clone, PartialEq)]
pub enum WaterDepth {
    /// Depth [m], positive down to the seabed.
    Depth(f64),
    /// A bathymetry file name, as written.
    File(String),
}

/// The options of a deck in file order. Names are compared without case, and each getter
/// also answers to MoorDyn's older names (`kb` for `kBot`, `ICDfac` for `CdScaleIC`, …).
/// When an option is given twice the later line counts, as in MoorDyn.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Options {
    /// File name for messages.
    pub(super) file: String,
    /// The option lines, in file order.
    pub entries: Vec<DeckOption>,
}

/// MoorDyn's names for each option that has a typed getter, the preferred one first.
pub const OPTION_NAMES: &[&[&str]] = &[
    &["dtM", "dt"],
    &["g", "gravity"],
    &["WtrDnsty", "rho", "rhoW"],
    &["WtrDpth"],
    &["kBot", "kb"],
    &["cBot", "cb"],
    &["FrictionCoefficient"],
    &["mu_kT"],
    &["mu_kA"],
    &["FricDamp", "CV"],
    &["StatDynFricScale", "MC"],
    &["TmaxIC", "ICTmax"],
    &["dtIC", "ICdt"],
    &["CdScaleIC", "ICDfac"],
    &["threshIC", "ICthresh"],
    &["tScheme"],
    &["dtOut"],
    &["CFL"],
    &["writeLog"],
    &["WaveKin"],
    &["Currents"],
    &["SeafloorFile"],
    &["fileIC", "ICfile"],
];

/// Whether `key` is one of the names of [`OPTION_NAMES`].
pub(super) fn known(key: &str) -> bool {
    OPTION_NAMES
        .iter()
        .flat_map(|names| names.iter())
        .any(|n| n.eq_ignore_ascii_case(key))
}

impl Options {
    /// The last line that sets the option `name` or one of its other names (see
    /// [`OPTION_NAMES`]); names are compared without case.
    pub fn get(&self, name: &str) -> Option<&DeckOption> {
        let group = OPTION_NAMES
            .iter()
            .find(|names| names.iter().any(|n| n.eq_ignore_ascii_case(name)));
        let matches = |k: &str| match group {
            Some(names) => names.iter().any(|n| n.eq_ignore_ascii_case(k)),
            None => k.eq_ignore_ascii_case(name),
        };
        self.entries.iter().rev().find(|o| matches(&o.key))
    }

    /// The option `name` as a number, `None` when absent; an error naming the line when
    /// its value is not a number.
    pub fn number(&self, name: &str) -> Result<Option<f64>, DeckError> {
        let Some(o) = self.get(name) else {
            return Ok(None);
        };
        number(&o.value)
            .map(Some)
            .ok_or_else(|| DeckError::OptionNotANumber {
                file: self.file.clone(),
                line: o.line,
                key: o.key.clone(),
                value: o.value.clone(),
            })
    }

    /// Mooring time step `dtM` (or `dt`) [s].
    pub fn dt_m(&self) -> Result<Option<f64>, DeckError> {
        self.number("dtM")
    }
    /// Gravity `g` (or `gravity`) [m/s²].
    pub fn gravity(&self) -> Result<Option<f64>, DeckError> {
        self.number("g")
    }
    /// Water density `WtrDnsty` (or `rho`, `rhoW`) [kg/m³].
    pub fn water_density(&self) -> Result<Option<f64>, DeckError> {
        self.number("WtrDnsty")
    }
    /// Water depth `WtrDpth` [m], or the bathymetry file named there.
    pub fn water_depth(&self) -> Result<Option<WaterDepth>, DeckError> {
        let Some(o) = self.get("WtrDpth") else {
            return Ok(None);
        };
        if let Some(x) = number(&o.value) {
            return Ok(Some(WaterDepth::Depth(x)));
        }
        if looks_numeric(&o.value) {
            return Err(DeckError::OptionNotANumber {
                file: self.file.clone(),
                line: o.line,
                key: o.key.clone(),
                value: o.value.clone(),
            });
        }
        Ok(Some(WaterDepth::File(o.value.clone())))
    }
    /// Seabed stiffness `kBot` (or `kb`) [Pa/m].
    pub fn k_bot(&self) -> Result<Option<f64>, DeckError> {
        self.number("kBot")
    }
    /// Seabed damping `cBot` (or `cb`) [Pa·s/m].
    pub fn c_bot(&self) -> Result<Option<f64>, DeckError> {
        self.number("cBot")
    }
    /// Seabed friction coefficient `FrictionCoefficient` [-].
    pub fn friction_coefficient(&self) -> Result<Option<f64>, DeckError> {
        self.number("FrictionCoefficient")
    }
    /// Transverse kinetic seabed friction coefficient `mu_kT` (MoorDyn-F) [-].
    pub fn friction_transverse(&self) -> Result<Option<f64>, DeckError> {
        self.number("mu_kT")
    }
    /// Axial kinetic seabed friction coefficient `mu_kA` (MoorDyn-F) [-].
    pub fn friction_axial(&self) -> Result<Option<f64>, DeckError> {
        self.number("mu_kA")
    }
    /// Seabed friction damping `FricDamp` (MoorDyn-F `CV`) [-]: scales friction from none
    /// at rest to full at large sliding speed.
    pub fn fric_damp(&self) -> Result<Option<f64>, DeckError> {
        self.number("FricDamp")
    }
    /// Static over dynamic friction ratio `StatDynFricScale` (MoorDyn-F `MC`) [-].
    pub fn stat_dyn_fric_scale(&self) -> Result<Option<f64>, DeckError> {
        self.number("StatDynFricScale")
    }
    /// Longest initial-condition search `TmaxIC` (or `ICTmax`) [s].
    pub fn tmax_ic(&self) -> Result<Option<f64>, DeckError> {
        self.number("TmaxIC")
    }
    /// Convergence window of the initial-condition search `dtIC` (or `ICdt`) [s].
    pub fn dt_ic(&self) -> Result<Option<f64>, DeckError> {
        self.number("dtIC")
    }
    /// Drag scale during the initial-condition search `CdScaleIC` (or `ICDfac`) [-].
    pub fn cd_scale_ic(&self) -> Result<Option<f64>, DeckError> {
        self.number("CdScaleIC")
    }
    /// Relative tension change taken as converged `threshIC` (or `ICthresh`) [-].
    pub fn thresh_ic(&self) -> Result<Option<f64>, DeckError> {
        self.number("threshIC")
    }
    /// Output period `dtOut` [s] (0: every coupling step).
    pub fn dt_out(&self) -> Result<Option<f64>, DeckError> {
        self.number("dtOut")
    }
    /// Time scheme name `tScheme` as written (`RK2`, `RK4`, `BEuler5`, …).
    pub fn t_scheme(&self) -> Option<&str> {
        self.get("tScheme").map(|o| o.value.as_str())
    }
}

/// Whether `text` starts like a number (a digit, or a sign or point before one) and is
/// no file name (no `/` or `\\`, no extension such as `.txt`), so that it is a mistyped
/// number (`5O0`, `1e8.5`, `300kN`) rather than a curve or bathymetry file.
pub(super) fn looks_numeric(text: &str) -> bool {
    let starts = text
        .trim_start_matches(['+', '-', '.'])
        .starts_with(|c: char| c.is_ascii_digit());
    let extension = text
        .rsplit_once('.')
        .is_some_and(|(_, ext)| ext.starts_with(|c: char| c.is_ascii_alphabetic()));
    starts && !extension && !text.contains(['/', '\\'])
}

/// Reads the option rows: `value name [remark…]`. A row with a single field is refused,
/// and so is a row written name first (`dtM 0.001`), which MoorDyn would misread.
pub(super) fn read_options(file: &str, rows: &[Row]) -> Result<Options, DeckError> {
    let mut entries = Vec::with_capacity(rows.len());
    for row in rows {
        let f = row.fields();
        let bad = |reason| DeckError::BadOption {
            file: file.to_string(),
            line: row.line,
            text: row.text.to_string(),
            reason,
        };
        if f.len() < 2 {
            return Err(bad("needs a value and a name (`0.001 dtM`)"));
        }
        if is_number(f[1]) && known(f[0]) && !known(f[1]) {
            return Err(bad(
                "is written name first; MoorDyn reads the value first (`0.001 dtM`)",
            ));
        }
        entries.push(DeckOption {
            key: f[1].to_string(),
            value: f[0].to_string(),
            remark: f[2..].join(" "),
            line: row.line,
        });
    }
    Ok(Options {
        file: file.to_string(),
        entries,
    })
}

/// A note for every option given more than once (under one name or several of its names,
/// [`OPTION_NAMES`]): it names each line and the value used, the last one's (as MoorDyn
/// does); at the line of the last, in line order.
pub(super) fn repeated(options: &Options) -> Vec<super::Note> {
    let group = |key: &str| {
        OPTION_NAMES
            .iter()
            .find(|names| names.iter().any(|n| n.eq_ignore_ascii_case(key)))
            .map_or_else(|| key.to_ascii_lowercase(), |names| names[0].to_string())
    };
    let mut seen: Vec<(String, Vec<&DeckOption>)> = Vec::new();
    for o in &options.entries {
        let g = group(&o.key);
        match seen.iter_mut().find(|(k, _)| *k == g) {
            Some((_, list)) => list.push(o),
            None => seen.push((g, vec![o])),
        }
    }
    let mut notes: Vec<super::Note> = seen
        .into_iter()
        .filter(|(_, list)| list.len() > 1)
        .map(|(g, list)| {
            let name = if known(&g) { g } else { list[0].key.clone() };
            let at: Vec<String> = list
                .iter()
                .map(|o| format!("line {} (`{} {}`)", o.line, o.value, o.key))
                .collect();
            let (init, last) = at.split_at(at.len() - 1);
            let used = list[list.len() - 1];
            let (times, which) = match list.len() {
                2 => ("twice".to_string(), "later"),
                n => (format!("{n} times"), "last"),
            };
            super::Note {
                line: used.line,
                text: format!(
                    "option {name} is given {times}, on {} and {}: the {which}, {}, is used",
                    init.join(", "),
                    last[0],
                    used.value
                ),
            }
        })
        .collect();
    notes.sort_by_key(|n| n.line);
    notes
}
