//! `phstring statics`: the static equilibrium of a scenario under its loads at `t = 0`
//! (docs/method.md §15), or of the system as a run's checkpoint holds it (`--at`: its
//! winches' lengths, its supports and loads at its time; docs/method.md §23), written as
//! CSV, JSON, ParaView and a plot.
//!
//! Files written into the output folder:
//! * `equilibrium.csv`: per node, the position [m] and the support reaction [N] (the force
//!   the support exerts on the string; zero at free components);
//! * `tension.csv`: per element, its string (group), nodes, strain `C`, stress `S = 2W'(C)`
//!   [N], tension `N = S·|r'|` [N] (force in the deformed element) and deformed length [m];
//! * `equilibrium.vtp`: ParaView, cell data `C`, `S`, `N`, `string`; point data the
//!   reaction components;
//! * `equilibrium.png` / `.svg`: the equilibrium (the two axes of largest extent in 3D);
//! * `summary.json`: path, what became of the catenary first guess, iterations, residual,
//!   tolerance, stability, energies, reactions; with `--at`, `started_from`: the
//!   checkpoint, its time and its winches' lengths.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use phstring::statics::{Equilibrium, StaticsError};
use phstring::{Material, PhSystem, Vector};
use serde::Serialize;

use super::at::{AnyAt, AtCheckpoint, AtError, CheckpointInfo};
use crate::files::{
    EQUILIBRIUM_FILE, EQUILIBRIUM_FRAME, SUMMARY_FILE, TENSION_FILE, atomic_write, num,
};
use crate::output::OutputError;
use crate::plot::network_plot;
use crate::scenario::{AnySetup, ScenarioError, ScenarioFile, Setup};
use crate::vtk::{FrameData, write_vtp_frame};

/// Why `phstring statics` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StaticsRunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// No equilibrium (or invalid setup).
    #[error(transparent)]
    Statics(#[from] StaticsError),
    /// Writing outputs failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The checkpoint of `--at` could not be read, does not fit, or is not covered.
    #[error(transparent)]
    At(#[from] AtError),
}

impl StaticsRunError {
    /// Whether a stop request (Ctrl-C) ended the equilibrium solve (nothing is written then).
    pub fn is_interrupted(&self) -> bool {
        matches!(self, StaticsRunError::Statics(StaticsError::Interrupted))
    }
}

/// What `summary.json` of a statics run holds.
#[derive(Debug, Clone, Serialize)]
pub struct StaticsInfo {
    /// Scenario title or file name.
    pub title: String,
    /// Spatial dimension.
    pub dimension: usize,
    /// Nodes and elements.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// `catenary_guess`, `newton`, `load_continuation` or `pseudo_transient`.
    pub path: &'static str,
    /// What became of the catenary first guess: `used`, `failed: WHY` or
    /// `not applicable: WHY` (docs/method.md §15).
    pub first_guess: String,
    /// Steps of that path (load or pseudo-time steps; 1 for Newton).
    pub path_steps: usize,
    /// Newton iterations over all paths.
    pub newton_iterations: usize,
    /// Residual norm over the free components [N].
    pub residual: f64,
    /// Tolerance [N].
    pub tolerance: f64,
    /// Force scale [N].
    pub force_scale: f64,
    /// Ended at the round-off floor.
    pub at_roundoff: bool,
    /// Tangent stiffness positive definite (stable equilibrium).
    pub stable: bool,
    /// Internal energy [J].
    pub internal_energy: f64,
    /// External potential energy of the body forces [J].
    pub external_energy: f64,
    /// Sum of all support reactions [N] (balances the total load).
    pub total_reaction: Vec<f64>,
    /// Largest tension `N` [N] and its element.
    pub max_tension: f64,
    /// Element of the largest tension.
    pub max_tension_element: usize,
    /// Smallest tension `N` [N] (negative: compression) and its element (both leave out
    /// the elements on a winch's drum).
    pub min_tension: f64,
    /// Element of the smallest tension.
    pub min_tension_element: usize,
    /// Wall time of the solve [s].
    pub solve_s: f64,
    /// For a scenario generated from a MoorDyn deck, its `[deck]` record (as in a run's
    /// `summary.json`); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deck: Option<crate::scenario::DeckSpec>,
    /// With `--at CHECKPOINT`: the checkpoint it started from, its time and its winches'
    /// lengths; absent for the scenario's own equilibrium.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub started_from: Option<CheckpointInfo>,
}

/// Solves the equilibrium of scenario `file` (validated and built: `setup`, from
/// [`ScenarioFile::setup`](crate::scenario::ScenarioFile::setup)) and writes the outputs
/// into `out` (which must exist).
pub fn statics(
    file: &ScenarioFile,
    setup: &AnySetup,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<StaticsInfo, StaticsRunError> {
    phstring::by_dim!(setup, s => statics_dim(file, s, out, stop))
}

fn statics_dim<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<StaticsInfo, StaticsRunError> {
    let start = Instant::now();
    let eq = v.equilibrium(false, stop)?;
    let solve_s = start.elapsed().as_secs_f64();
    write_all(file, &v.problem.system, &eq, solve_s, None, out)
}

/// The equilibrium of the system as checkpoint `at` holds it ([`read_at`](super::at::read_at):
/// its winches' meshes, its supports where the run had them, its loads held at their values
/// at its time), from its positions, written into `out` (which must exist) as [`statics`]
/// writes the scenario's, with `summary.json` saying where it started. A scenario with
/// feedback ports is refused: their check at rest takes their reference at `t = 0`.
pub fn statics_at(
    file: &ScenarioFile,
    at: &AnyAt,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<StaticsInfo, StaticsRunError> {
    phstring::by_dim!(at, a => statics_at_dim(file, a, out, stop))
}

fn statics_at_dim<const D: usize>(
    file: &ScenarioFile,
    at: &AtCheckpoint<D>,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<StaticsInfo, StaticsRunError> {
    let feedback = at.system.boundary().feedback.len();
    if feedback > 0 {
        return Err(StaticsRunError::At(AtError::Unsupported {
            path: at.info.checkpoint.clone().into(),
            reason: format!(
                "the scenario has {feedback} feedback port(s): statics --at does not cover them yet (their check at rest takes the reference at t = 0); use linearize --at, which leaves them open"
            ),
        }));
    }
    let start = Instant::now();
    let eq = phstring::statics::solve_from(&at.system, &at.state, &at.statics, stop)?;
    let solve_s = start.elapsed().as_secs_f64();
    write_all(file, &at.system, &eq, solve_s, Some(at.info.clone()), out)
}

/// Writes the files of equilibrium `eq` of `sys` (found in `solve_s` seconds; from a
/// checkpoint: `started_from`) into `out` and returns the summary.
fn write_all<const D: usize>(
    file: &ScenarioFile,
    sys: &PhSystem<D, Material>,
    eq: &Equilibrium<D>,
    solve_s: f64,
    started_from: Option<CheckpointInfo>,
    out: &Path,
) -> Result<StaticsInfo, StaticsRunError> {
    let tension = tensions(sys, eq);
    write_files(out, sys, eq, &tension)?;
    let (mut max, mut min) = ((f64::NEG_INFINITY, 0), (f64::INFINITY, 0));
    // Elements on a winch's drum are in no group's range: they carry nothing.
    let active = |e: usize| sys.groups().iter().any(|g| g.elements.contains(&e));
    for (e, t) in tension.iter().enumerate().filter(|(e, _)| active(*e)) {
        if t.n > max.0 {
            max = (t.n, e);
        }
        if t.n < min.0 {
            min = (t.n, e);
        }
    }
    let mut total = vec![0.0; D];
    for r in &eq.reactions {
        for k in 0..D {
            total[k] += r[k];
        }
    }
    let title = file
        .scenario
        .title
        .clone()
        .unwrap_or_else(|| file.path.display().to_string());
    let info = StaticsInfo {
        title: title.clone(),
        dimension: D,
        nodes: sys.mesh().n_nodes(),
        elements: sys.mesh().n_elements(),
        path: eq.path.name(),
        first_guess: eq.guess.describe(),
        path_steps: eq.path.steps(),
        newton_iterations: eq.iterations,
        residual: eq.residual,
        tolerance: eq.tolerance,
        force_scale: eq.force_scale,
        at_roundoff: eq.at_roundoff,
        stable: eq.stable,
        internal_energy: eq.energies.internal,
        external_energy: eq.energies.external,
        total_reaction: total,
        max_tension: max.0,
        max_tension_element: max.1,
        min_tension: min.0,
        min_tension_element: min.1,
        solve_s,
        deck: file.scenario.deck.clone(),
        started_from,
    };
    let json = serde_json::to_string_pretty(&info).expect("plain data serializes");
    write(out, SUMMARY_FILE, json.as_bytes())?;
    plot(out, &title, sys, eq)?;
    Ok(info)
}

/// Strain, stress, tension and deformed length of one element.
struct Tension {
    c: f64,
    s: f64,
    n: f64,
    length: f64,
}

fn tensions<const D: usize>(sys: &PhSystem<D, Material>, eq: &Equilibrium<D>) -> Vec<Tension> {
    let mut s = vec![0.0; sys.mesh().n_elements()];
    sys.stresses(&eq.state.c, &mut s);
    sys.mesh()
        .elements()
        .iter()
        .zip(sys.mesh().lengths())
        .zip(eq.state.c.iter().zip(&s))
        .map(|((&[a, b], &l), (&c, &s))| {
            let length = (eq.state.r[b] - eq.state.r[a]).norm();
            Tension {
                c,
                s,
                n: s * length / l,
                length,
            }
        })
        .collect()
}

fn write(out: &Path, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
    let path = out.join(name);
    atomic_write(&path, bytes).map_err(|cause| OutputError::Io { path, cause })
}

/// Each element's group: its string's for the elements on a winch's drum too (outside the
/// group's range, with N = 0).
fn group_of<const D: usize>(sys: &PhSystem<D, Material>) -> Vec<usize> {
    let mut g = vec![0; sys.mesh().n_elements()];
    for (k, els) in sys.winch_elements() {
        g[els].iter_mut().for_each(|x| *x = k);
    }
    for (k, grp) in sys.groups().iter().enumerate() {
        g[grp.elements.clone()].iter_mut().for_each(|x| *x = k);
    }
    g
}

fn write_files<const D: usize>(
    out: &Path,
    sys: &PhSystem<D, Material>,
    eq: &Equilibrium<D>,
    tension: &[Tension],
) -> Result<(), OutputError> {
    const AX: [&str; 3] = ["x", "y", "z"];
    let mut csv = String::from("node");
    for a in &AX[..D] {
        let _ = write!(csv, ",{a}");
    }
    for a in &AX[..D] {
        let _ = write!(csv, ",reaction_{a}");
    }
    csv.push('\n');
    for (i, (r, f)) in eq.state.r.iter().zip(&eq.reactions).enumerate() {
        let _ = write!(csv, "{i}");
        for k in 0..D {
            let _ = write!(csv, ",{}", num(r[k]));
        }
        for k in 0..D {
            let _ = write!(csv, ",{}", num(f[k]));
        }
        csv.push('\n');
    }
    write(out, EQUILIBRIUM_FILE, csv.as_bytes())?;

    let groups = group_of(sys);
    let mut csv = String::from("element,string,node_a,node_b,C,S,N,length\n");
    for (e, (t, &[a, b])) in tension.iter().zip(sys.mesh().elements()).enumerate() {
        let name = &sys.groups()[groups[e]].name;
        let name = if name.contains([',', '"']) {
            format!("\"{}\"", name.replace('"', "\"\""))
        } else {
            name.clone()
        };
        let _ = writeln!(
            csv,
            "{e},{name},{a},{b},{},{},{},{}",
            num(t.c),
            num(t.s),
            num(t.n),
            num(t.length)
        );
    }
    write(out, TENSION_FILE, csv.as_bytes())?;

    let points: Vec<[f64; 3]> = eq.state.r.iter().map(pad).collect();
    let zero = vec![[0.0; 3]; points.len()];
    let c: Vec<f64> = tension.iter().map(|t| t.c).collect();
    let s: Vec<f64> = tension.iter().map(|t| t.s).collect();
    let n: Vec<f64> = tension.iter().map(|t| t.n).collect();
    let g: Vec<i32> = groups.iter().map(|&x| x as i32).collect();
    // One per node (the equilibrium's list may go on with its rigid bodies' slots).
    let at_nodes = &eq.reactions[..points.len().min(eq.reactions.len())];
    let reaction: Vec<Vec<f64>> = (0..D)
        .map(|k| at_nodes.iter().map(|f| f[k]).collect())
        .collect();
    let names = ["reaction_x", "reaction_y", "reaction_z"];
    let point_data: Vec<(&str, &[f64])> = reaction
        .iter()
        .enumerate()
        .map(|(k, v)| (names[k], v.as_slice()))
        .collect();
    let path = out.join(EQUILIBRIUM_FRAME);
    write_vtp_frame(
        &path,
        &FrameData {
            points: &points,
            segments: sys.mesh().elements(),
            velocity: &zero,
            cell_data: &[("C", &c), ("S", &s), ("N", &n)],
            cell_ints: &[("string", &g)],
            point_data: &point_data,
        },
    )
    .map_err(OutputError::from)
}

fn pad<const D: usize>(r: &Vector<D>) -> [f64; 3] {
    let mut p = [0.0; 3];
    for k in 0..D {
        p[k] = r[k];
    }
    p
}

/// The plot of the equilibrium: in 3D on the two axes along which it extends most.
fn plot<const D: usize>(
    out: &Path,
    title: &str,
    sys: &PhSystem<D, Material>,
    eq: &Equilibrium<D>,
) -> Result<(), OutputError> {
    if D == 1 {
        return Ok(());
    }
    let extent = |k: usize| {
        let (lo, hi) = eq
            .state
            .r
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                (lo.min(r[k]), hi.max(r[k]))
            });
        hi - lo
    };
    let (a, b) = if D == 3 {
        let mut axes = [0, 1, 2];
        axes.sort_by(|&i, &j| extent(j).total_cmp(&extent(i)));
        (axes[0].min(axes[1]), axes[0].max(axes[1]))
    } else {
        (0, 1)
    };
    let topology = crate::output::system_topology(sys);
    let nodes: Vec<[f64; 2]> = eq.state.r.iter().map(|r| [r[a], r[b]]).collect();
    let axes = ["x", "y", "z"];
    let title = format!(
        "{title}: static equilibrium ({}–{} plane)",
        axes[a], axes[b]
    );
    network_plot(&out.join("equilibrium"), &title, &topology, &[(0.0, nodes)])?;
    Ok(())
}
