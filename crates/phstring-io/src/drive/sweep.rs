//! Parameter sweeps: many independent runs of one scenario with different `--set` values,
//! in parallel (rayon), one output folder each plus a summary table `sweep.csv`.
//!
//! Each run is single-threaded and deterministic, so results do not depend on the number of
//! threads.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::run::{self as runner, RunInfo};
use crate::files::num;
use crate::files::{SWEEP_TABLE, run_dir_name};
use crate::scenario::{self, ScenarioError, ScenarioFile};

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
    /// The thread pool could not be built.
    #[error("cannot start {jobs} threads: {cause}")]
    Threads {
        /// Threads asked for.
        jobs: usize,
        /// Why not.
        cause: String,
    },
    /// `sweep.csv` could not be written.
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

/// A checked sweep: the scenario, the fixed `--set` options and the varied keys, with every
/// combination validated. Building it writes nothing, so an invalid value fails the sweep
/// before any folder is touched.
#[derive(Debug)]
pub struct Sweep {
    path: PathBuf,
    text: String,
    sets: Vec<String>,
    vary: Vec<Vary>,
    count: usize,
}

impl Sweep {
    /// Reads the scenario, refuses a key varied twice (or varied and also set with `--set`)
    /// and more than [`MAX_RUNS`] runs, and validates every combination (one at a time).
    pub fn new(scenario_path: &Path, sets: &[String], vary: Vec<Vary>) -> Result<Self, SweepError> {
        Self::new_with(scenario_path, sets, vary, |_, _| Ok(()))
    }

    /// [`Self::new`], calling `precheck(index, combination)` on every combination before it
    /// is validated (for checks that must come before validation allocates the mesh, such as
    /// a memory budget); its message is the error.
    pub fn new_with(
        scenario_path: &Path,
        sets: &[String],
        vary: Vec<Vary>,
        precheck: impl Fn(usize, &ScenarioFile) -> Result<(), String>,
    ) -> Result<Self, SweepError> {
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
        let count = run_count(&vary)?;
        let base = scenario::load(scenario_path, &[])?;
        let sweep = Self {
            path: scenario_path.to_path_buf(),
            text: base.text().to_string(),
            sets: sets.to_vec(),
            vary,
            count,
        };
        for index in 0..count {
            let file = sweep.file(index)?;
            precheck(index, &file).map_err(SweepError::Refused)?;
            file.check()?;
        }
        Ok(sweep)
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

    /// The scenario of run `index`.
    pub fn file(&self, index: usize) -> Result<ScenarioFile, ScenarioError> {
        let mut all = self.sets.clone();
        all.extend(
            combination(&self.vary, index)
                .iter()
                .map(|(k, v)| format!("{k}={v}")),
        );
        scenario::parse(&self.text, &self.path, &all)
    }

    /// Runs every combination with `jobs` threads into `out/run_NNN/` (`out` must exist), and
    /// writes `out/sweep.csv`. `stop`, when set, stops the runs under way as Ctrl-C stops a
    /// run (with a checkpoint) and starts no further run; those are marked
    /// [`SweepRun::interrupted`] and have the status `interrupted` in the table.
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
                    let dir = out.join(run_dir_name(index));
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

/// CSV field: quoted when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
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
