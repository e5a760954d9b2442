//! `phstring modes`: the lowest natural modes about the static equilibrium of a scenario
//! (docs/method.md §17).
//!
//! Files written into the output folder:
//! * `modes.csv`: `mode,omega_rad_s,frequency_hz,period_s,character,axial_share`;
//! * `modes.pvd` and `mode_NNN.vtp`: one ParaView frame per mode (its "time" is the mode
//!   number), positions = equilibrium + `scale · φ`, point data `shape_x`, `shape_y`,
//!   `shape_z` (the unscaled `M`-normalized shape);
//! * `modes.png` / `.svg`: the equilibrium and up to four scaled mode shapes (the snapshot
//!   labelled `t = k s` is mode `k`; the x–y plane in 3D);
//! * `summary.json`: method, solves, frequencies, the equilibrium path and the scale, the
//!   count asked for and a warning if fewer modes exist; with rigid bodies, each mode's
//!   motion of each body.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use phstring::modes::{self, ModesError};
use phstring::statics::StaticsError;
use serde::Serialize;

use crate::files::{MODES_FILE, MODES_PVD_FILE, SUMMARY_FILE, atomic_write, mode_frame_name, num};
use crate::output::OutputError;
use crate::plot::network_plot;
use crate::scenario::{AnySetup, ScenarioError, ScenarioFile, Setup};
use crate::vtk::{FrameData, PvdWriter, write_vtp_frame};

/// Why `phstring modes` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModesRunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// No equilibrium.
    #[error(transparent)]
    Statics(#[from] StaticsError),
    /// No modes.
    #[error(transparent)]
    Modes(#[from] ModesError),
    /// Writing failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl ModesRunError {
    /// Whether a stop request (Ctrl-C) ended it: in the equilibrium solve, the eigensolver
    /// or between the ParaView frames (then `modes.csv` is removed again, and `modes.pvd` and
    /// `summary.json` are not written).
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            ModesRunError::Statics(StaticsError::Interrupted)
                | ModesRunError::Modes(ModesError::Interrupted)
        )
    }
}

/// One mode in `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ModeInfo {
    /// Angular frequency [rad/s].
    pub omega_rad_s: f64,
    /// Frequency [Hz].
    pub frequency_hz: f64,
    /// `longitudinal`, `transverse`, `mixed` or `body` (rigid bodies hold at least half of
    /// its kinetic energy).
    pub character: &'static str,
    /// Per rigid body, its motion in the mode (same normalization as the shapes): the
    /// translation `[x, y, z]` [kg^-½] and the turn about the space axes `[rx, ry, rz]`
    /// [rad·m^-1·kg^-½]; absent without bodies.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<[f64; 6]>,
}

/// `summary.json` of `phstring modes`.
#[derive(Debug, Clone, Serialize)]
pub struct ModesInfo {
    /// `dense` or `lanczos`.
    pub method: &'static str,
    /// Linear solves (Lanczos).
    pub solves: usize,
    /// How the equilibrium was found.
    pub equilibrium_path: &'static str,
    /// Scale of the shapes in the ParaView frames and the plot [m per unit of φ].
    pub shape_scale: f64,
    /// Modes asked for (`--count`).
    pub requested: usize,
    /// What the caller should know: fewer modes exist than were asked for.
    pub warnings: Vec<String>,
    /// The modes, ascending.
    pub modes: Vec<ModeInfo>,
}

/// The warning when `asked` modes were asked for with `option` but only `given` were
/// computed, because the model has `free` free position components (one mode each).
pub fn fewer_modes(option: &str, asked: usize, free: usize, given: usize) -> Option<String> {
    (given < asked).then(|| {
        format!(
            "{option} {asked}: the model has {free} free position components, so only {free} modes exist; {given} are given"
        )
    })
}

/// Solves the equilibrium of `file` (validated and built: `setup`), then its `count` lowest modes, and writes the outputs
/// into `out` (which must exist). `stop`, when set, ends it between Newton iterations,
/// Lanczos steps or ParaView frames ([`ModesRunError::is_interrupted`]); `modes.csv`,
/// `modes.pvd` and `summary.json` are then not left behind (`modes.csv`, written before the
/// frames so that a full disk keeps it, is removed again).
pub fn modes(
    file: &ScenarioFile,
    setup: &AnySetup,
    count: usize,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<ModesInfo, ModesRunError> {
    phstring::by_dim!(setup, s => modes_dim(file, s, count, out, stop))
}

fn write(out: &Path, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
    let path = out.join(name);
    atomic_write(&path, bytes).map_err(|cause| OutputError::Io { path, cause })
}

fn modes_dim<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    count: usize,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<ModesInfo, ModesRunError> {
    let eq = v.equilibrium(true, stop)?;
    let sys = &v.problem.system;
    let r = &eq.state.r;
    let bodies = sys.bodies().len();
    let found = if bodies == 0 {
        modes::modes(sys, r, count, v.settings.step.solver, stop)?
    } else {
        modes::modes_with_bodies(sys, r, &eq.state.bodies, count, stop)?
    };
    let (_, free) = phstring::linear::free_dofs(sys);
    // Each rigid body adds its translation and its turn.
    let free = free + bodies * if D == 3 { 6 } else { 3 };
    let warnings = fewer_modes("--count", count, free, found.modes.len())
        .into_iter()
        .collect();
    // The shapes are drawn with their largest nodal amplitude at 5 % of the largest extent.
    let extent = (0..D)
        .map(|k| {
            let (lo, hi) = r
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[k]), hi.max(p[k]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    let mut csv = String::from("mode,omega_rad_s,frequency_hz,period_s,character,axial_share\n");
    let mut infos = Vec::new();
    for (i, m) in found.modes.iter().enumerate() {
        let period = if m.omega > 0.0 {
            num(1.0 / m.hertz())
        } else {
            "inf".into()
        };
        let _ = writeln!(
            csv,
            "{},{},{},{period},{},{}",
            i + 1,
            num(m.omega),
            num(m.hertz()),
            m.character.name(),
            num(m.axial_share)
        );
        infos.push(ModeInfo {
            omega_rad_s: m.omega,
            frequency_hz: m.hertz(),
            character: m.character.name(),
            bodies: m
                .bodies
                .iter()
                .map(|(x, w)| [x.x, x.y, x.z, w.x, w.y, w.z])
                .collect(),
        });
    }
    let amax = |m: &modes::Mode<D>| m.shape.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let scale_of = |m: &modes::Mode<D>| {
        let a = amax(m);
        if a > 0.0 && extent > 0.0 {
            0.05 * extent / a
        } else {
            0.0
        }
    };
    // The table first: on a full disk the frequencies are kept even when the frames fail.
    write(out, MODES_FILE, csv.as_bytes())?;
    let mut pvd = PvdWriter::new(&out.join(MODES_PVD_FILE));
    let zero = vec![[0.0; 3]; r.len()];
    let names = ["shape_x", "shape_y", "shape_z"];
    let mut snapshots = vec![(0.0, r.iter().map(plane).collect::<Vec<_>>())];
    for (i, m) in found.modes.iter().enumerate() {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            // An interrupted run leaves no table that looks complete.
            let _ = std::fs::remove_file(out.join(MODES_FILE));
            return Err(ModesError::Interrupted.into());
        }
        let s = scale_of(m);
        let points: Vec<[f64; 3]> = r
            .iter()
            .zip(&m.shape)
            .map(|(p, f)| pad(&(p + f * s)))
            .collect();
        let comps: Vec<Vec<f64>> = (0..D)
            .map(|k| m.shape.iter().map(|f| f[k]).collect())
            .collect();
        let point_data: Vec<(&str, &[f64])> = comps
            .iter()
            .enumerate()
            .map(|(k, c)| (names[k], c.as_slice()))
            .collect();
        let name = mode_frame_name(i + 1);
        write_vtp_frame(
            &out.join(&name),
            &FrameData {
                points: &points,
                segments: sys.mesh().elements(),
                velocity: &zero,
                cell_data: &[],
                cell_ints: &[],
                point_data: &point_data,
            },
        )
        .map_err(OutputError::from)?;
        pvd.add((i + 1) as f64, &name);
        if i < 4 && D >= 2 {
            snapshots.push((
                (i + 1) as f64,
                r.iter()
                    .zip(&m.shape)
                    .map(|(p, f)| plane(&(p + f * s)))
                    .collect(),
            ));
        }
    }
    pvd.write().map_err(OutputError::from)?;
    let shape_scale = found.modes.first().map_or(0.0, scale_of);
    if D >= 2 {
        let topology = crate::output::system_topology(sys);
        let title = format!(
            "{}: equilibrium (t = 0) and modes 1–{} (t = k)",
            file.scenario.title.clone().unwrap_or_default(),
            snapshots.len() - 1
        );
        network_plot(&out.join("modes"), &title, &topology, &snapshots)
            .map_err(OutputError::from)?;
    }
    let info = ModesInfo {
        method: found.method,
        solves: found.solves,
        equilibrium_path: eq.path.name(),
        shape_scale,
        requested: count,
        warnings,
        modes: infos,
    };
    let json = serde_json::to_string_pretty(&info).expect("plain data serializes");
    write(out, SUMMARY_FILE, json.as_bytes())?;
    Ok(info)
}

fn pad<const D: usize>(r: &phstring::Vector<D>) -> [f64; 3] {
    let mut p = [0.0; 3];
    for k in 0..D {
        p[k] = r[k];
    }
    p
}

/// The first two components (the plot's plane).
fn plane<const D: usize>(r: &phstring::Vector<D>) -> [f64; 2] {
    [r[0], if D > 1 { r[1] } else { 0.0 }]
}
