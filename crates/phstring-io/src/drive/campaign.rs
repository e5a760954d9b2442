//! Load-case campaigns: the extremes of every line sampled at every state of a run
//! (`summary.json`'s `lines`), and the campaign table `campaign.csv` that a sweep over a
//! MoorDyn deck gathers from its runs (docs/moordyn.md, "Campaigns").

use std::ops::Range;
use std::path::Path;

use phstring::{Material, PhSystem, Simulation};

use super::sweep::SweepRun;
use super::water::WaterSummary;
use crate::extremes::LineExtremes;
use crate::files::{CAMPAIGN_TABLE, num};
use crate::output::EndForces;

/// How the extremes of a run's lines are sampled: the end forces of `end_tensions.csv`,
/// and per line its elements and its place among the water summary's strings.
#[derive(Debug, Clone)]
pub struct LineWatch {
    ends: EndForces,
    /// Per line (in the columns' order): its elements, and its index in
    /// [`WaterSummary::strings`].
    lines: Vec<(Range<usize>, Option<usize>)>,
}

impl LineWatch {
    /// The watch of the lines of `sys` whose end forces `ends` computes.
    pub fn new<const D: usize>(ends: EndForces, sys: &PhSystem<D, Material>) -> Self {
        let strings: Vec<&str> = sys
            .groups()
            .iter()
            .filter(|g| matches!(g.law, phstring::Law::String(_)))
            .map(|g| g.name.as_str())
            .collect();
        let lines = ends
            .names()
            .map(|name| {
                let elements = sys
                    .groups()
                    .iter()
                    .find(|g| g.name == name)
                    .map_or(0..0, |g| g.elements.clone());
                (elements, strings.iter().position(|s| *s == name))
            })
            .collect();
        Self { ends, lines }
    }

    /// The records of the lines with the state of `sim` sampled (a fresh run, `t = 0`).
    pub fn start<const D: usize>(
        &self,
        sim: &Simulation<D, Material>,
        water: Option<&WaterSummary>,
    ) -> Vec<LineExtremes> {
        let mut records: Vec<LineExtremes> = self.ends.names().map(LineExtremes::new).collect();
        self.observe(sim, &mut records, water, &self.tensions(sim));
        records
    }

    /// The end tensions of the state of `sim`: the values of the row of `end_tensions.csv`.
    pub fn tensions<const D: usize>(&self, sim: &Simulation<D, Material>) -> Vec<f64> {
        self.ends.tensions(sim)
    }

    /// Samples the state of `sim` into `records`: its end tensions `tensions` (from
    /// [`Self::tensions`]), the grounded length of the water summary `water` sampled in the
    /// same state (0 without water), the smallest stretch of each line's elements.
    pub fn observe<const D: usize>(
        &self,
        sim: &Simulation<D, Material>,
        records: &mut [LineExtremes],
        water: Option<&WaterSummary>,
        tensions: &[f64],
    ) {
        let c = &sim.state().c;
        for (k, (rec, (elements, wet))) in records.iter_mut().zip(&self.lines).enumerate() {
            let grounded = match (water, wet) {
                (Some(w), Some(i)) => w.strings.get(*i).map_or(0.0, |s| s.grounded_length_final),
                _ => 0.0,
            };
            let c_min = c[elements.clone()]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            let pair = (tensions[2 * k], tensions[2 * k + 1]);
            rec.sample(sim.time(), pair, grounded, c_min.max(0.0).sqrt());
        }
    }

    /// The number of lines.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// Whether there are no lines (never: a watch needs end forces, which need a string).
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }
}

/// The `lines` of `summary.json`: the records, or for more than
/// [`SUMMARY_COMPONENTS`](super::run::SUMMARY_COMPONENTS) of them their count
/// (`{"count": N}`), so that the summary of a large network stays small.
pub fn summary_lines<S: serde::Serializer>(
    lines: &Option<Vec<LineExtremes>>,
    s: S,
) -> Result<S::Ok, S::Error> {
    use serde::Serialize as _;
    match lines {
        Some(l) if l.len() > super::run::SUMMARY_COMPONENTS => {
            serde_json::json!({ "count": l.len() }).serialize(s)
        }
        _ => lines.serialize(s),
    }
}

/// The header of `campaign.csv` after the run's columns (`run,dir,case` and the other
/// varied keys).
const LINE_COLUMNS: &str = "line,name,status,fair_ten_max,fair_ten_max_t,fair_ten_min,anch_ten_max,anch_ten_min,grounded_length_min,slack,slack_steps,slack_first_t,stretch_min,error";

/// A CSV field: quoted when it holds a comma, a quote or a line break.
pub(super) fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The values of one line's row of `campaign.csv` from `line` on (without the run's
/// columns): its number `k` (1-based, as in `FairTen<k>`), name, status and extremes.
fn line_fields(k: usize, x: &LineExtremes) -> String {
    format!(
        "{k},{},completed,{},{},{},{},{},{},{},{},{},{},",
        csv_field(&x.name),
        num(x.fair_ten_max),
        num(x.fair_ten_max_t),
        num(x.fair_ten_min),
        num(x.anch_ten_max),
        num(x.anch_ten_min),
        num(x.grounded_length_min),
        x.slack,
        x.slack_steps,
        x.slack_first_t.map(num).unwrap_or_default(),
        num(x.stretch_min),
    )
}

/// Writes `out/campaign.csv`: for every run of a sweep over a deck one row per line with
/// its extremes (`summary.json`'s `lines`), in run order then line order; a run that failed
/// or was interrupted is one row with its status and reason and no values. `case` is the
/// run's motion table (`case(run)`, empty without one), `keys` the other varied keys whose
/// values follow it.
pub fn write_table(
    out: &Path,
    keys: &[&str],
    case: &dyn Fn(&SweepRun) -> String,
    runs: &[SweepRun],
) -> std::io::Result<()> {
    let mut text = String::from("run,dir,case");
    for k in keys {
        text.push(',');
        text.push_str(&csv_field(k));
    }
    text.push(',');
    text.push_str(LINE_COLUMNS);
    text.push('\n');
    let empty = ",".repeat(LINE_COLUMNS.matches(',').count() - 3);
    for r in runs {
        let dir = r
            .dir
            .file_name()
            .map_or(String::new(), |d| d.to_string_lossy().into_owned());
        let mut head = format!("{},{},{}", r.index, csv_field(&dir), csv_field(&case(r)));
        for (k, v) in &r.values {
            if keys.contains(&k.as_str()) {
                head.push(',');
                head.push_str(&csv_field(v));
            }
        }
        match &r.result {
            Ok(info) => {
                for (k, x) in info.lines.iter().flatten().enumerate() {
                    text.push_str(&format!("{head},{}\n", line_fields(k + 1, x)));
                }
            }
            Err(e) => {
                let status = if r.interrupted {
                    "interrupted"
                } else {
                    "failed"
                };
                text.push_str(&format!("{head},,,{status}{empty},{}\n", csv_field(e)));
            }
        }
    }
    crate::files::atomic_write(&out.join(CAMPAIGN_TABLE), text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::EndWater;
    use crate::test_util::wet_line;
    use phstring::{Boundary, Fixed, MassMatrix, Mesh, Problem, Scheme, State, StepParams, Vector};

    /// A 10 m tension-only string (EA = 1e8 N, 50 kg/m, no gravity) held at node 0, whose
    /// free end starts at 1 m/s towards the held one: a slack string carries no force, so
    /// the end moves at 1 m/s and the stretch is `(10 − t)/10` exactly, 0.95 at t = 0.5 s.
    /// The line is slack from the first step on (50 states), with no tension at either
    /// end, and not at `t = 0` (stress-free, `√C = 1`).
    #[test]
    fn a_string_whose_end_moves_in_goes_slack_with_the_stretch_of_its_motion() {
        let mesh = Mesh::uniform_chain(1, 10.0).unwrap();
        let r = vec![Vector::<2>::zeros(), Vector::<2>::new(10.0, 0.0)];
        let v = vec![Vector::<2>::zeros(), Vector::<2>::new(-1.0, 0.0)];
        let problem = Problem {
            initial: State::consistent(&mesh, r, v),
            mesh,
            material: phstring::Material::tension_only_linear(1e8),
            rho_a: 50.0,
            body_force: Vector::zeros(),
            mass: MassMatrix::Lumped,
            boundary: Boundary {
                fixed: vec![Fixed::node(0)],
                ..Default::default()
            },
            point_masses: vec![],
        };
        let params = StepParams {
            h: 0.01,
            scheme: Scheme::DiscreteGradient,
            ..Default::default()
        };
        let mut sim = Simulation::new(problem, params).unwrap();
        let ends = EndForces::new(sim.system(), &[], None).unwrap();
        let watch = LineWatch::new(ends, sim.system());
        assert_eq!(watch.len(), 1);
        let mut rec = watch.start(&sim, None);
        assert!(!rec[0].slack && rec[0].stretch_min == 1.0);
        for _ in 0..50 {
            sim.step().unwrap();
            watch.observe(&sim, &mut rec, None, &watch.tensions(&sim));
        }
        let x = &rec[0];
        assert!((sim.time() - 0.5).abs() < 1e-12);
        assert!((x.stretch_min - 0.95).abs() < 1e-12, "{x:?}");
        assert!(x.slack && x.slack_steps == 50, "{x:?}");
        assert!((x.slack_first_t.unwrap() - 0.01).abs() < 1e-15, "{x:?}");
        assert_eq!([x.fair_ten_max, x.anch_ten_max], [0.0, 0.0]);
        assert_eq!(x.grounded_length_min, 0.0);
        assert_eq!(x.check(sim.time()), Ok(()));
    }

    /// On the wet line laid on its seabed (it sinks in and sways in the current), the
    /// records are the extremes of the end tensions computed state by state and of the
    /// water summary's grounded length: exactly its `grounded_length_min`.
    #[test]
    fn the_records_of_a_wet_line_are_the_extremes_of_its_states() {
        let mut sim = wet_line();
        let water = EndWater {
            density: 1025.0,
            gravity: phstring::water::STANDARD_GRAVITY,
            seabed_normal: Some(vec![0.0, 1.0]),
        };
        let ends = EndForces::new(sim.system(), &[Some(0.1)], Some(water)).unwrap();
        let watch = LineWatch::new(ends.clone(), sim.system());
        let mut w = WaterSummary::start(&sim).unwrap();
        let mut rec = watch.start(&sim, Some(&w));
        let first = ends.tensions(&sim);
        let (mut fair, mut anch) = ([first[0]; 2], [first[1]; 2]);
        let mut at = 0.0;
        for _ in 0..30 {
            sim.step().unwrap();
            w.observe(&sim);
            watch.observe(&sim, &mut rec, Some(&w), &watch.tensions(&sim));
            let t = ends.tensions(&sim);
            if t[0] > fair[1] {
                at = sim.time();
            }
            fair = [fair[0].min(t[0]), fair[1].max(t[0])];
            anch = [anch[0].min(t[1]), anch[1].max(t[1])];
        }
        let x = &rec[0];
        assert_eq!([x.fair_ten_min, x.fair_ten_max], fair);
        assert_eq!([x.anch_ten_min, x.anch_ten_max], anch);
        assert_eq!(x.fair_ten_max_t, at);
        assert_eq!(x.grounded_length_min, w.strings[0].grounded_length_min);
        assert!(fair[1] > 1e4 && anch[1] > 0.0, "{x:?}");
        assert_eq!(x.check(sim.time()), Ok(()));
    }
}
