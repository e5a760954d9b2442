//! Parameter sweeps: many independent runs of one scenario or MoorDyn deck with different
//! `--set` values, in parallel (rayon), one output folder each plus a summary table
//! `sweep.csv`. Over a deck, the key `motion` varies the vessel's platform table (a load-case
//! campaign) and `campaign.csv` tabulates the extremes of every line of every run.
//!
//! Each run is single-threaded and deterministic, so results do not depend on the number of
//! threads.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::campaign::csv_field;
use super::run::{self as runner, RunInfo};
use crate::files::num;
use crate::files::{CAMPAIGN_TABLE, SWEEP_TABLE, case_dir_name};
use crate::moordyn::{self, LoadError};
use crate::scenario::{self, ScenarioError, ScenarioFile};

/// The varied key that, over a MoorDyn deck, names the platform table driving its vessel
/// points (`--vary motion=a.csv,b.csv`, as `phstring run DECK --motion a.csv`).
pub const MOTION_KEY: &str = "motion";

/// One varied key with its values (TOML literals as text).
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// Dotted key, e.g. `mesh.elements`.
    pub key: String,
    /// Values, e.g. `["100", "300"]`.
    pub values: Vec<String>,
}

impl Vary {
    /// Parses `key=v1,v2,…`. Commas inside `[…]`, `{…}`, `"…"` (with `\"` and other
    /// backslash escapes) or `'…'` do not split (`body_force.gravity=[0,-9.81],[0,-1.62]`);
    /// an unclosed quote or bracket, or an unmatched closing bracket, is an error that names
    /// its position (in characters of the option, 1-based).
    pub fn parse(option: &str) -> Result<Self, ScenarioError> {
        let err = |reason: &str| ScenarioError::Vary {
            option: option.to_string(),
            reason: reason.to_string(),
        };
        let (key, list) = option
            .split_once('=')
            .ok_or_else(|| err("expected key=v1,v2,…, e.g. mesh.elements=100,300"))?;
        let values = split_values(list, key.chars().count() + 1).map_err(|r| err(&r))?;
        let key = normalize_key(key);
        if key.is_empty() || values.iter().any(|v| v.is_empty()) {
            return Err(err("empty key or value"));
        }
        Ok(Self { key, values })
    }
}

/// A dotted key with the blanks around its segments removed (`mesh . elements` is
/// `mesh.elements`, as `--set` reads it).
fn normalize_key(key: &str) -> String {
    key.split('.').map(str::trim).collect::<Vec<_>>().join(".")
}

/// Splits a `--vary` value list at the commas outside quotes and brackets; `offset` is the
/// number of characters before the list in the option (for positions in messages).
fn split_values(list: &str, offset: usize) -> Result<Vec<String>, String> {
    let mut values = Vec::new();
    let mut brackets: Vec<(char, usize)> = Vec::new();
    let mut quote: Option<(char, usize)> = None;
    let mut escaped = false;
    let mut cur = String::new();
    for (i, ch) in list.chars().enumerate() {
        let pos = offset + i + 1;
        if let Some((q, _)) = quote {
            if escaped {
                escaped = false;
            } else if q == '"' && ch == '\\' {
                escaped = true;
            } else if ch == q {
                quote = None;
            }
            cur.push(ch);
            continue;
        }
        match ch {
            '"' | '\'' => quote = Some((ch, pos)),
            '[' | '{' => brackets.push((ch, pos)),
            ']' | '}' => {
                let open = if ch == ']' { '[' } else { '{' };
                if brackets.pop().map(|(c, _)| c) != Some(open) {
                    return Err(format!("unmatched `{ch}` at character {pos}"));
                }
            }
            ',' if brackets.is_empty() => {
                values.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(ch);
    }
    if let Some((q, pos)) = quote {
        return Err(format!("the quote {q} at character {pos} is not closed"));
    }
    if let Some((b, pos)) = brackets.pop() {
        return Err(format!(
            "the bracket `{b}` at character {pos} is not closed"
        ));
    }
    values.push(cur.trim().to_string());
    Ok(values)
}

/// One run of a sweep: its `--set` options and its outcome.
#[derive(Debug)]
pub struct SweepRun {
    /// Index in the cartesian product.
    pub index: usize,
    /// Output folder.
    pub dir: PathBuf,
    /// `(key, value)` of each varied key.
    pub values: Vec<(String, String)>,
    /// The outcome (without the energy history, which only plots need).
    pub result: Result<RunInfo, String>,
    /// A stop request ended the run (it can be resumed from its checkpoint) or kept it from
    /// starting; `result` is then the error that says which.
    pub interrupted: bool,
}

/// Most runs in one sweep.
pub const MAX_RUNS: usize = 100_000;

/// Errors of a sweep as a whole (a failed run is recorded in its [`SweepRun`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    /// A `--vary` or `--set` option, or a combination of values, is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// More combinations than [`MAX_RUNS`].
    #[error(
        "the sweep has {count} runs (the product of the numbers of values); at most {MAX_RUNS} are allowed"
    )]
    TooManyRuns {
        /// The number of combinations, as text (it may not fit in a `usize`).
        count: String,
    },
    /// A combination was refused before validation (e.g. it does not fit in memory).
    #[error("{0}")]
    Refused(String),
    /// The deck (or scenario file) could not be read, or its first combination is invalid.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The thread pool could not be built.
    #[error("cannot start {jobs} threads: {cause}")]
    Threads {
        /// Threads asked for.
        jobs: usize,
        /// Why not.
        cause: String,
    },
    /// `sweep.csv` or `campaign.csv` could not be written.
    #[error("cannot write {}: {cause}", path.display())]
    Table {
        /// The table.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
}

/// The number of combinations of `vary`, refused above [`MAX_RUNS`].
pub fn run_count(vary: &[Vary]) -> Result<usize, SweepError> {
    let n = vary
        .iter()
        .try_fold(1usize, |n, v| n.checked_mul(v.values.len()));
    match n {
        Some(n) if n <= MAX_RUNS => Ok(n),
        _ => {
            // Saturating: a count beyond u128 is only printed, never used.
            let exact = vary
                .iter()
                .fold(1u128, |n, v| n.saturating_mul(v.values.len() as u128));
            Err(SweepError::TooManyRuns {
                count: if exact < 10_000_000_000 {
                    exact.to_string()
                } else {
                    format!("{:.2e}", exact as f64)
                },
            })
        }
    }
}

/// Combination `index` of the varied values, in row-major order (last key fastest).
pub fn combination(vary: &[Vary], mut index: usize) -> Vec<(String, String)> {
    let mut out = vec![(String::new(), String::new()); vary.len()];
    for (k, v) in vary.iter().enumerate().rev() {
        let n = v.values.len().max(1);
        out[k] = (
            v.key.clone(),
            v.values.get(index % n).cloned().unwrap_or_default(),
        );
        index /= n;
    }
    out
}

/// All combinations of the varied values, in row-major order (last key fastest), made one
/// at a time.
pub fn combinations(vary: &[Vary]) -> impl Iterator<Item = Vec<(String, String)>> + '_ {
    let n = vary
        .iter()
        .try_fold(1usize, |n, v| n.checked_mul(v.values.len()))
        .unwrap_or(usize::MAX);
    (0..n).map(move |i| combination(vary, i))
}

/// The options of a sweep over a MoorDyn deck: those of `phstring run DECK`.
#[derive(Debug, Clone, Default)]
pub struct DeckOptions {
    /// `--ignore` words: the deck's features to drop (docs/moordyn.md).
    pub ignore: Vec<String>,
    /// `--motion FILE`: one platform table for every run (not with `--vary motion=…`);
    /// relative to the current directory.
    pub motion: Option<PathBuf>,
}

/// What the runs of a sweep are made from.
#[derive(Debug)]
enum Source {
    /// A scenario file: its text.
    Scenario(String),
    /// A MoorDyn deck, read and mapped again for every run (whose motion table may differ).
    Deck(DeckOptions),
}

/// A checked sweep: the scenario or deck, the fixed `--set` options and the varied keys,
/// with every combination validated. Building it writes nothing, so an invalid value fails
/// the sweep before any folder is touched.
#[derive(Debug)]
pub struct Sweep {
    path: PathBuf,
    source: Source,
    sets: Vec<String>,
    vary: Vec<Vary>,
    count: usize,
}

/// Refuses a key varied twice, or varied and also set with `--set`.
fn check_keys(sets: &[String], vary: &[Vary]) -> Result<(), SweepError> {
    for (i, v) in vary.iter().enumerate() {
        if vary[..i].iter().any(|w| w.key == v.key) {
            return Err(ScenarioError::Vary {
                option: format!("{}=…", v.key),
                reason: "the key is varied twice; give all its values in one --vary".into(),
            }
            .into());
        }
        if let Some(s) = sets.iter().find(|s| {
            s.split_once('=')
                .is_some_and(|(k, _)| normalize_key(k) == v.key)
        }) {
            return Err(ScenarioError::Vary {
                option: format!("{}=…", v.key),
                reason: format!(
                    "the key is also given with --set {s}, which the varied values would replace"
                ),
            }
            .into());
        }
    }
    Ok(())
}

/// A `--vary motion=…` value as a path: the text, without the quotes around it if quoted
/// (`"a,b.csv"` for a name with a comma).
fn unquote(value: &str) -> &str {
    ['"', '\'']
        .iter()
        .find_map(|q| value.strip_prefix(*q)?.strip_suffix(*q))
        .unwrap_or(value)
}

/// The refusal of `--vary motion=…` for the sweep of `path`: `reason` says why.
fn motion_refused(path: &Path, reason: &str) -> SweepError {
    ScenarioError::Vary {
        option: format!("{MOTION_KEY}=…"),
        reason: format!("{} {reason}", path.display()),
    }
    .into()
}

impl Sweep {
    /// Reads the scenario, refuses a key varied twice (or varied and also set with `--set`)
    /// and more than [`MAX_RUNS`] runs, and validates every combination (one at a time).
    pub fn new(scenario_path: &Path, sets: &[String], vary: Vec<Vary>) -> Result<Self, SweepError> {
        Self::new_with(scenario_path, sets, vary, DeckOptions::default(), |_, _| {
            Ok(())
        })
    }

    /// [`Self::new`] for a scenario file or a MoorDyn deck (told by its content, as `phstring
    /// run` tells them) with the deck's options `deck` (refused for a scenario file, as by
    /// `run`), calling `precheck(index, combination)` on every combination before it is
    /// validated (for checks that must come before validation allocates the mesh, such as a
    /// memory budget); its message is the error. Over a deck, the key [`MOTION_KEY`] varies
    /// the platform table (a campaign): a combination whose table or scenario is refused
    /// then becomes a failed run of the sweep, and only a campaign whose every combination
    /// is refused fails as a whole (with the first refusal).
    pub fn new_with(
        path: &Path,
        sets: &[String],
        vary: Vec<Vary>,
        deck: DeckOptions,
        precheck: impl Fn(usize, &ScenarioFile) -> Result<(), String>,
    ) -> Result<Self, SweepError> {
        check_keys(sets, &vary)?;
        let count = run_count(&vary)?;
        let base = moordyn::load_scenario_driven(path, &[], &deck.ignore, deck.motion.as_deref())?;
        let campaign = vary.iter().any(|v| v.key == MOTION_KEY);
        let source = match base.mapping {
            Some(_) if campaign && deck.motion.is_some() => {
                return Err(motion_refused(
                    path,
                    "is driven by --motion, which gives one table for every run; give the tables with --vary motion=… alone",
                ));
            }
            Some(_) => Source::Deck(deck),
            None if campaign => {
                return Err(motion_refused(
                    path,
                    "is a scenario file, not a MoorDyn deck: --vary motion=… drives a deck's vessel points; vary a scenario's own tables by their keys, e.g. --vary platform.0.motion_table=a.csv,b.csv or boundary.1.motion_table=…",
                ));
            }
            None => Source::Scenario(base.file.text().to_string()),
        };
        let sweep = Self {
            path: path.to_path_buf(),
            source,
            sets: sets.to_vec(),
            vary,
            count,
        };
        sweep.validate(campaign, precheck)?;
        Ok(sweep)
    }

    /// Validates every combination (one at a time) after `precheck`; in a `campaign`, a
    /// refused combination is left to fail as a run unless all are refused.
    fn validate(
        &self,
        campaign: bool,
        precheck: impl Fn(usize, &ScenarioFile) -> Result<(), String>,
    ) -> Result<(), SweepError> {
        let mut first: Option<LoadError> = None;
        let mut valid = 0;
        for index in 0..self.count {
            let refusal = match self.file(index) {
                Err(e) => e,
                Ok(file) => {
                    precheck(index, &file).map_err(SweepError::Refused)?;
                    match file.check() {
                        Ok(()) => {
                            valid += 1;
                            continue;
                        }
                        Err(e) => e.into(),
                    }
                }
            };
            if !campaign {
                return Err(refusal.into());
            }
            first.get_or_insert(refusal);
        }
        match first {
            Some(e) if valid == 0 => Err(e.into()),
            _ => Ok(()),
        }
    }

    /// Number of runs.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether there are no runs (never: every `--vary` has a value).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The varied keys.
    pub fn vary(&self) -> &[Vary] {
        &self.vary
    }

    /// Whether the sweep runs a MoorDyn deck (and writes `campaign.csv`).
    pub fn is_deck(&self) -> bool {
        matches!(self.source, Source::Deck(_))
    }

    /// The platform table of run `index` over a deck as given (`--vary motion=…` or
    /// `--motion`), `None` without one.
    pub fn motion(&self, index: usize) -> Option<String> {
        let Source::Deck(deck) = &self.source else {
            return None;
        };
        combination(&self.vary, index)
            .into_iter()
            .find(|(k, _)| k == MOTION_KEY)
            .map(|(_, v)| unquote(&v).to_string())
            .or_else(|| deck.motion.as_ref().map(|m| m.display().to_string()))
    }

    /// The scenario of run `index`: for a deck, the deck read and mapped with the run's
    /// motion table, as `phstring run DECK --motion TABLE --set …` reads it.
    pub fn file(&self, index: usize) -> Result<ScenarioFile, LoadError> {
        let mut all = self.sets.clone();
        all.extend(
            combination(&self.vary, index)
                .iter()
                .filter(|(k, _)| !(self.is_deck() && k == MOTION_KEY))
                .map(|(k, v)| format!("{k}={v}")),
        );
        match &self.source {
            Source::Scenario(text) => Ok(scenario::parse(text, &self.path, &all)?),
            Source::Deck(deck) => {
                let motion = self.motion(index).map(PathBuf::from);
                let loaded = moordyn::load_scenario_driven(
                    &self.path,
                    &all,
                    &deck.ignore,
                    motion.as_deref(),
                )?;
                Ok(loaded.file)
            }
        }
    }

    /// The folder name of run `index`: `run_NNN`, in a campaign followed by its motion
    /// table's file stem (`run_002_surge10`).
    pub fn dir_name(&self, index: usize) -> String {
        let varied = self.is_deck() && self.vary.iter().any(|v| v.key == MOTION_KEY);
        let stem = self
            .motion(index)
            .filter(|_| varied)
            .and_then(|m| Some(Path::new(&m).file_stem()?.to_string_lossy().into_owned()));
        case_dir_name(index, stem.as_deref().unwrap_or(""))
    }

    /// Runs every combination with `jobs` threads into `out/run_NNN/` ([`Self::dir_name`];
    /// `out` must exist), and writes `out/sweep.csv` and, over a deck, `out/campaign.csv`.
    /// `stop`, when set, stops the runs under way as Ctrl-C stops a run (with a checkpoint)
    /// and starts no further run; those are marked [`SweepRun::interrupted`] and have the
    /// status `interrupted` in the tables.
    pub fn run(
        &self,
        out: &Path,
        jobs: usize,
        on_done: &(dyn Fn(&SweepRun) + Sync),
        stop: Option<Arc<AtomicBool>>,
    ) -> Result<Vec<SweepRun>, SweepError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs.max(1))
            .build()
            .map_err(|e| SweepError::Threads {
                jobs,
                cause: e.to_string(),
            })?;
        let runs: Vec<SweepRun> = pool.install(|| {
            (0..self.count)
                .into_par_iter()
                .map(|index| {
                    let dir = out.join(self.dir_name(index));
                    let (result, interrupted) = self.run_one(index, &dir, stop.as_ref());
                    let run = SweepRun {
                        index,
                        dir,
                        values: combination(&self.vary, index),
                        result,
                        interrupted,
                    };
                    on_done(&run);
                    run
                })
                .collect()
        });
        write_table(out, &self.vary, &runs).map_err(|cause| SweepError::Table {
            path: out.join(SWEEP_TABLE),
            cause,
        })?;
        if self.is_deck() {
            let keys: Vec<&str> = self
                .vary
                .iter()
                .map(|v| v.key.as_str())
                .filter(|k| *k != MOTION_KEY)
                .collect();
            let case = |r: &SweepRun| self.motion(r.index).unwrap_or_default();
            super::campaign::write_table(out, &keys, &case, &runs).map_err(|cause| {
                SweepError::Table {
                    path: out.join(CAMPAIGN_TABLE),
                    cause,
                }
            })?;
        }
        Ok(runs)
    }

    /// Run `index` into `dir` (created), unless `stop` is set; whether a stop request ended
    /// it or kept it from starting.
    fn run_one(
        &self,
        index: usize,
        dir: &Path,
        stop: Option<&Arc<AtomicBool>>,
    ) -> (Result<RunInfo, String>, bool) {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return (
                Err("not started: the sweep was interrupted".to_string()),
                true,
            );
        }
        let file = match self.file(index) {
            Ok(f) => f,
            Err(e) => return (Err(e.to_string()), false),
        };
        if let Err(e) = std::fs::create_dir_all(dir) {
            return (Err(format!("cannot create {}: {e}", dir.display())), false);
        }
        let opts = runner::RunOptions {
            stop: stop.cloned(),
            ..Default::default()
        };
        // Every run was validated before the first started (refused early); it is validated
        // again here rather than holding every run's system in memory.
        let setup = match file.setup() {
            Ok(s) => s,
            Err(e) => return (Err(e.to_string()), false),
        };
        match runner::run_setup(&file, setup, dir, &mut (), opts) {
            Ok(mut info) => {
                info.history = Default::default();
                (Ok(info), false)
            }
            Err(e) => (Err(e.to_string()), e.is_interrupted()),
        }
    }
}

/// Writes `sweep.csv`: one row per run with the varied values and the run's totals.
fn write_table(out: &Path, vary: &[Vary], runs: &[SweepRun]) -> std::io::Result<()> {
    let mut text = String::from("run,dir");
    for v in vary {
        text.push(',');
        text.push_str(&csv_field(&v.key));
    }
    text.push_str(",status,steps,rejected_steps,total_newton_iterations,hamiltonian_initial,hamiltonian_final,max_balance_error,time_loop_s,error\n");
    for r in runs {
        let dir = r
            .dir
            .file_name()
            .map_or(String::new(), |d| d.to_string_lossy().into_owned());
        text.push_str(&format!("{},{dir}", r.index));
        for (_, val) in &r.values {
            text.push_str(&format!(",\"{}\"", val.replace('"', "\"\"")));
        }
        match &r.result {
            Ok(i) => text.push_str(&format!(
                ",{},{},{},{},{},{},{},{},\n",
                i.status,
                i.steps,
                i.rejected_steps,
                i.total_newton_iterations,
                num(i.hamiltonian_initial),
                num(i.hamiltonian_final),
                num(i.max_balance_error),
                num(i.time_loop_s)
            )),
            Err(e) => text.push_str(&format!(
                ",{},,,,,,,,\"{}\"\n",
                if r.interrupted {
                    "interrupted"
                } else {
                    "failed"
                },
                e.replace('"', "'")
            )),
        }
    }
    std::fs::write(out.join(SWEEP_TABLE), text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_parsing_respects_brackets_and_quotes() {
        let v = Vary::parse("body_force.gravity=[0,-9.81],[0, -1.62]").unwrap();
        assert_eq!(v.key, "body_force.gravity");
        assert_eq!(v.values, vec!["[0,-9.81]", "[0, -1.62]"]);
        let v = Vary::parse("material.law=\"a,b\",hyperelastic").unwrap();
        assert_eq!(v.values, vec!["\"a,b\"", "hyperelastic"]);
        assert!(Vary::parse("nokey").is_err());
        assert!(Vary::parse("k=1,,2").is_err());
    }

    /// `\"` inside a quoted value does not end it, `'…'` quotes too, and an
    /// unbalanced quote or bracket is an error naming its position.
    #[test]
    fn vary_splitter_handles_escapes_and_unbalanced_quotes() {
        let v = Vary::parse(r#"title="a \",b",'c,d',"e\\",f"#).unwrap();
        assert_eq!(v.values, vec![r#""a \",b""#, "'c,d'", r#""e\\""#, "f"]);
        let v = Vary::parse("boundary.1.force=[\"0\", \"-1\"],[\"0\", \"t,2\"]").unwrap();
        assert_eq!(v.values.len(), 2);
        let e = Vary::parse(r#"title="abc,def"#).unwrap_err().to_string();
        assert!(
            e.contains("the quote \" at character 7 is not closed"),
            "{e}"
        );
        let e = Vary::parse(r#"title="a\",b"#).unwrap_err().to_string();
        assert!(e.contains("character 7 is not closed"), "{e}");
        let e = Vary::parse("g=[0,1],[0,2").unwrap_err().to_string();
        assert!(
            e.contains("the bracket `[` at character 9 is not closed"),
            "{e}"
        );
        let e = Vary::parse("g=0,1]").unwrap_err().to_string();
        assert!(e.contains("unmatched `]` at character 6"), "{e}");
        assert_eq!(
            Vary::parse(" mesh . elements =1").unwrap().key,
            "mesh.elements"
        );
    }

    /// A sweep of 6.6e12 combinations is refused with its count, without making
    /// the combinations.
    #[test]
    fn sweep_run_count_is_capped() {
        let v = |n: usize| Vary {
            key: "k".into(),
            values: (0..n).map(|i| i.to_string()).collect(),
        };
        assert_eq!(run_count(&[v(10), v(30)]).unwrap(), 300);
        let e = run_count(&[v(100_000), v(100_000), v(660)]).unwrap_err();
        assert!(e.to_string().contains("6.60e12 runs"), "{e}");
        let huge: Vec<Vary> = (0..8).map(|_| v(1000)).collect();
        let e = run_count(&huge).unwrap_err();
        assert!(e.to_string().contains("1.00e24 runs"), "{e}");
        assert_eq!(
            combination(&[v(3), v(5)], 7),
            vec![("k".into(), "1".into()), ("k".into(), "2".into())]
        );
    }

    /// A motion table's path may be quoted (for a comma in it); the quotes are not part
    /// of the path.
    #[test]
    fn motion_values_lose_their_quotes() {
        assert_eq!(unquote("\"a,b.csv\""), "a,b.csv");
        assert_eq!(unquote("'sea state 1.csv'"), "sea state 1.csv");
        assert_eq!(unquote("surge2.csv"), "surge2.csv");
        assert_eq!(unquote("\"half.csv"), "\"half.csv");
        let v = Vary::parse("motion=\"a,b.csv\",c.csv").unwrap();
        assert_eq!(v.values, ["\"a,b.csv\"", "c.csv"]);
    }

    #[test]
    fn combinations_are_the_cartesian_product() {
        let a = Vary {
            key: "a".into(),
            values: vec!["1".into(), "2".into()],
        };
        let b = Vary {
            key: "b".into(),
            values: vec!["x".into(), "y".into(), "z".into()],
        };
        let c: Vec<_> = combinations(&[a, b]).collect();
        assert_eq!(c.len(), 6);
        assert_eq!(
            c[1],
            vec![("a".into(), "1".into()), ("b".into(), "y".into())]
        );
        assert_eq!(
            c[5],
            vec![("a".into(), "2".into()), ("b".into(), "z".into())]
        );
    }
}
