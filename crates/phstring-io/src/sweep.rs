//! Parameter sweeps: many independent runs of one scenario with different `--set` values,
//! in parallel (rayon), one output folder each plus a summary table `sweep.csv`.
//!
//! Each run is single-threaded and deterministic, so results do not depend on the number of
//! threads.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::output::num;
use crate::runner::{self, RunInfo};
use crate::scenario::{self, ScenarioError};

/// One varied key with its values (TOML literals as text).
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// Dotted key, e.g. `mesh.elements`.
    pub key: String,
    /// Values, e.g. `["100", "300"]`.
    pub values: Vec<String>,
}

impl Vary {
    /// Parses `key=v1,v2,…`; commas inside brackets or quotes do not split
    /// (`body_force.gravity=[0,-9.81],[0,-1.62]`).
    pub fn parse(option: &str) -> Result<Self, ScenarioError> {
        let err = |reason: &str| ScenarioError::Vary {
            option: option.to_string(),
            reason: reason.to_string(),
        };
        let (key, list) = option
            .split_once('=')
            .ok_or_else(|| err("expected key=v1,v2,…, e.g. mesh.elements=100,300"))?;
        let mut values = Vec::new();
        let (mut depth, mut quote, mut cur) = (0i32, false, String::new());
        for ch in list.chars() {
            match ch {
                '"' => quote = !quote,
                '[' | '{' if !quote => depth += 1,
                ']' | '}' if !quote => depth -= 1,
                ',' if !quote && depth == 0 => {
                    values.push(std::mem::take(&mut cur).trim().to_string());
                    continue;
                }
                _ => {}
            }
            cur.push(ch);
        }
        values.push(cur.trim().to_string());
        if key.trim().is_empty() || values.iter().any(|v| v.is_empty()) {
            return Err(err("empty key or value"));
        }
        Ok(Self {
            key: key.trim().to_string(),
            values,
        })
    }
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
    /// The outcome.
    pub result: Result<RunInfo, String>,
}

/// All combinations of the varied values, in row-major order (last key fastest).
pub fn combinations(vary: &[Vary]) -> Vec<Vec<(String, String)>> {
    let mut out: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for v in vary {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                v.values.iter().map(move |val| {
                    let mut p = prefix.clone();
                    p.push((v.key.clone(), val.clone()));
                    p
                })
            })
            .collect();
    }
    out
}

/// Runs every combination of `vary` (on top of the fixed `sets`) with `jobs` threads into
/// `out/run_NNN/`, and writes `out/sweep.csv`. Scenario errors of any combination are
/// reported before anything runs.
pub fn run(
    scenario_path: &Path,
    sets: &[String],
    vary: &[Vary],
    out: &Path,
    jobs: usize,
    on_done: &(dyn Fn(&SweepRun) + Sync),
) -> Result<Vec<SweepRun>, ScenarioError> {
    let combos = combinations(vary);
    // Validate all combinations first: a bad value fails the sweep before any run.
    let mut files = Vec::with_capacity(combos.len());
    for combo in &combos {
        let mut all: Vec<String> = sets.to_vec();
        all.extend(combo.iter().map(|(k, v)| format!("{k}={v}")));
        let file = scenario::load(scenario_path, &all)?;
        file.check()?;
        files.push(file);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| ScenarioError::Set {
            option: format!("--jobs {jobs}"),
            reason: e.to_string(),
        })?;
    let runs: Vec<SweepRun> = pool.install(|| {
        files
            .par_iter()
            .zip(combos.par_iter())
            .enumerate()
            .map(|(index, (file, combo))| {
                let dir = out.join(format!("run_{index:03}"));
                let result = std::fs::create_dir_all(&dir)
                    .map_err(|e| format!("cannot create {}: {e}", dir.display()))
                    .and_then(|_| {
                        runner::run(file, &dir, &mut (), runner::RunOptions::default())
                            .map_err(|e| e.to_string())
                    });
                let run = SweepRun {
                    index,
                    dir,
                    values: combo.clone(),
                    result,
                };
                on_done(&run);
                run
            })
            .collect()
    });
    write_table(out, vary, &runs).map_err(|e| ScenarioError::Read {
        path: out.join("sweep.csv"),
        source: e,
    })?;
    Ok(runs)
}

/// Writes `sweep.csv`: one row per run with the varied values and the run's totals.
fn write_table(out: &Path, vary: &[Vary], runs: &[SweepRun]) -> std::io::Result<()> {
    let mut text = String::from("run,dir");
    for v in vary {
        text.push(',');
        text.push_str(&v.key);
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
            Err(e) => text.push_str(&format!(",failed,,,,,,,,\"{}\"\n", e.replace('"', "'"))),
        }
    }
    std::fs::write(out.join("sweep.csv"), text)
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
        let c = combinations(&[a, b]);
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
