//! `phstring linearize`: the linear port-Hamiltonian model about a rest state, written for
//! scipy and pyMOR (docs/method.md §16).
//!
//! Each matrix `E`, `J`, `R`, `Q`, `B` of a form (`full`: the paper's `(r, v, C)`;
//! `reduced`: `(q, v)` on the free position components) is written twice:
//! * `FORM/NAME.mtx`: MatrixMarket coordinate, real, general (`scipy.io.mmread`);
//! * `FORM/NAME.npz`: scipy's sparse CSC layout (`scipy.sparse.load_npz`).
//!
//! `manifest.json` lists the state components, inputs and outputs in order with units, and
//! the state it was linearized at; `at.csv` holds those positions.
//!
//! About the scenario's equilibrium, or (`--at CHECKPOINT`) on the system as a run's
//! checkpoint holds it ([`super::at`]: its winches' meshes, with the nodes paid out since
//! the start free and those hauled in held on the drum), about its positions or (with
//! `--equilibrium`) the equilibrium of that system.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use faer::sparse::SparseColMat;
use phstring::linear::{ForcePort, LinearPh, force_ports, full_model, reduced_model};
use phstring::statics::{StaticsError, StaticsParams};
use phstring::{Material, PhSystem, Vector};
use serde::Serialize;

use super::at::{AnyAt, AtCheckpoint, AtError, CheckpointInfo};
use crate::files::{LINEAR_AT_FILE, MANIFEST_FILE, atomic_write, num};
use crate::output::OutputError;
use crate::scenario::{AnySetup, ScenarioError, ScenarioFile, Setup};

/// Why `phstring linearize` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// No equilibrium to linearize at.
    #[error(transparent)]
    Statics(#[from] StaticsError),
    /// The modes for the modal form could not be computed.
    #[error(transparent)]
    Modes(#[from] phstring::modes::ModesError),
    /// The checkpoint does not fit the scenario, or what it holds is not covered.
    #[error(transparent)]
    At(#[from] AtError),
    /// The state linearized at is not covered (a strain outside its law's domain, rigid
    /// bodies at a checkpoint, the modal form with rigid bodies).
    #[error("{0}")]
    Mismatch(String),
    /// Writing failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl ExportError {
    /// Whether a stop request (Ctrl-C) ended it, in the equilibrium solve or the modes of
    /// the modal form (nothing is written then).
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            ExportError::Statics(StaticsError::Interrupted)
                | ExportError::Modes(phstring::modes::ModesError::Interrupted)
        )
    }
}

/// Where the model is linearized.
#[derive(Debug, Clone)]
pub enum LinearizeAt {
    /// The static equilibrium of the scenario.
    Equilibrium,
    /// The system as a checkpoint (written by `phstring run`) holds it: its mesh (the
    /// winches' lengths), at its positions, or with `equilibrium` at the static equilibrium
    /// of that system from them. Read and checked by [`checkpoint_at`] before the output
    /// folder is touched.
    Checkpoint {
        /// The system and state at the checkpoint.
        at: Box<AnyAt>,
        /// Linearize about the equilibrium at the checkpoint's lengths instead of its state.
        equilibrium: bool,
    },
}

/// Reads the checkpoint at `path` and sets up the system as it holds it
/// ([`read_at`](super::at::read_at): checked as a resume checks it, its positions node count
/// × dimension first), so that `linearize --at` fails on a bad checkpoint before its output
/// folder is prepared. With `equilibrium`, the model is taken about the equilibrium of that
/// system.
pub fn checkpoint_at(
    setup: &AnySetup,
    path: &Path,
    equilibrium: bool,
) -> Result<LinearizeAt, ExportError> {
    let at = super::at::read_at(setup, path)?;
    Ok(LinearizeAt::Checkpoint {
        at: Box::new(at),
        equilibrium,
    })
}

/// One input or output of the model.
#[derive(Debug, Clone, Serialize)]
pub struct PortEntry {
    /// Name, e.g. `F[30].y` (input) or `v[30].y` (output); a rigid body's `F[hook].x`,
    /// `T[hook].z` (torque) and `v[hook].x`, `w[hook].z` (angular velocity).
    pub name: String,
    /// Node index (absent for a rigid body's port).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// The rigid body (absent for a node's port).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Component `x`, `y` or `z`.
    pub component: &'static str,
    /// Unit.
    pub unit: &'static str,
}

/// One matrix file pair.
#[derive(Debug, Clone, Serialize)]
pub struct MatrixEntry {
    /// Rows, columns.
    pub shape: [usize; 2],
    /// Stored non-zeros.
    pub nnz: usize,
    /// MatrixMarket file, relative to the output folder.
    pub mtx: String,
    /// scipy sparse `.npz` file, relative to the output folder.
    pub npz: String,
}

/// One form of the model in the manifest.
#[derive(Debug, Clone, Serialize)]
pub struct FormEntry {
    /// The equations in words.
    pub equations: &'static str,
    /// State components in order (`r[i].x` [m], `q[i].x` [m], `v[i].x` [m/s], `C[e]` [1]).
    pub states: Vec<String>,
    /// Unit of each state component, in order.
    pub state_units: Vec<&'static str>,
    /// Matrices by name: `E`, `J`, `R`, `Q`, `B`.
    pub matrices: std::collections::BTreeMap<&'static str, MatrixEntry>,
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Manifest {
    /// Format tag.
    pub format: &'static str,
    /// Scenario file.
    pub scenario: String,
    /// Spatial dimension.
    pub dimension: usize,
    /// Nodes.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// `E ẋ = (J − R) Q x + B u, y = Bᵀ Q x, H = ½ xᵀ Eᵀ Q x`.
    pub model: &'static str,
    /// Inputs `u` in order: force components [N] at the loaded nodes.
    pub inputs: Vec<PortEntry>,
    /// Outputs `y` in order: the velocities [m/s] conjugate to the inputs.
    pub outputs: Vec<PortEntry>,
    /// Where it was linearized: `equilibrium`, the checkpoint file, or `equilibrium at`
    /// the checkpoint file.
    pub linearized_at: String,
    /// Time of that state [s] (0 for the scenario's equilibrium; the checkpoint's time from
    /// a checkpoint).
    pub time: f64,
    /// Norm of the static residual `K(r)S − F` over the free components there [N] (0 up to
    /// the tolerance at an equilibrium; the linear model leaves this constant force out).
    pub static_residual: f64,
    /// Whether the tangent stiffness is positive definite there.
    pub stable: bool,
    /// The positions linearized at (node, x, y, z), relative to the output folder.
    pub positions: &'static str,
    /// With `--modes K`: the modes asked for (the modal form may have fewer, see `warnings`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub requested_modes: Option<usize>,
    /// What the caller should know: fewer modes exist than `--modes` asked for.
    pub warnings: Vec<String>,
    /// The forms written.
    pub forms: std::collections::BTreeMap<&'static str, FormEntry>,
    /// With `--at CHECKPOINT`: the checkpoint, its time and its winches' lengths (the mesh
    /// linearized on); absent for the scenario's equilibrium.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub started_from: Option<CheckpointInfo>,
}

const FULL_EQUATIONS: &str = "x = (dr, dv, dC) on the free position and velocity components and every element strain; E = diag(I, M_rho, M_S), J = [[0, I, 0], [-I, 0, -2K(r)], [0, 2K(r)^T, 0]], R = diag(0, R_v, 0) with R_v the damping matrix (zero without damping), Q = diag(K_G, I, diag(W''(C_e))); strain components not generated by positions are conserved (zero-frequency modes)";
const MODAL_EQUATIONS: &str = "x = (eta, nu): modal coordinates of the k lowest M-orthonormal natural modes Phi and their rates; E = I, J = [[0, I], [-I, 0]], R = diag(0, Phi^T R_v Phi), Q = diag(omega_1^2 .. omega_k^2, I), B = [0; Phi^T B_f]";
const REDUCED_EQUATIONS: &str = "x = (q, v) on the free position components: E = diag(I, M), J = [[0, I], [-I, 0]], R = diag(0, R_v), Q = diag(K_T, I), so M q'' + R_v q' + K_T q = B_f u (R_v: the damping matrix, zero without damping)";

/// Linearizes the scenario of `file` at `at` and writes the model into `out` (which must
/// exist). Returns the manifest.
///
/// With `modal = Some(k)`, a third form `modal` is written: the structure-preserving modal
/// truncation to the `k` lowest natural modes (docs/method.md §17).
///
/// `stop`, when set, ends it between Newton iterations or Lanczos steps, before anything is
/// written ([`ExportError::is_interrupted`]).
pub fn linearize(
    file: &ScenarioFile,
    setup: &AnySetup,
    at: &LinearizeAt,
    modal: Option<usize>,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<Manifest, ExportError> {
    let run = Run { modal, out, stop };
    match at {
        LinearizeAt::Equilibrium => {
            phstring::by_dim!(setup, s => linearize_equilibrium(file, s, &run))
        }
        LinearizeAt::Checkpoint { at, equilibrium } => {
            phstring::by_dim!(at.as_ref(), a => linearize_checkpoint(file, a, *equilibrium, &run))
        }
    }
}

/// What every form of `linearize` is asked for: the modal form's mode count, the output
/// folder and the stop request.
struct Run<'a> {
    modal: Option<usize>,
    out: &'a Path,
    stop: Option<&'a AtomicBool>,
}

/// The state a model is linearized at: the positions [m], the time [s], what they are (the
/// manifest's `linearized_at`) and, from a checkpoint, where it started.
struct LinearState<const D: usize> {
    r: Vec<Vector<D>>,
    time: f64,
    source: String,
    started_from: Option<CheckpointInfo>,
}

fn linearize_equilibrium<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    run: &Run,
) -> Result<Manifest, ExportError> {
    let sys = &v.problem.system;
    if !sys.bodies().is_empty() {
        return linearize_bodies(file, v, run);
    }
    let eq = v.equilibrium(true, run.stop)?;
    let state = LinearState {
        r: eq.state.r,
        time: 0.0,
        source: "equilibrium".to_string(),
        started_from: None,
    };
    linearize_state(file, sys, v.settings.step.solver, state, run)
}

/// The model of the system as checkpoint `at` holds it (its winches' meshes), about its
/// positions or, with `equilibrium`, about the equilibrium of that system from them (open
/// loop, as the scenario's equilibrium is taken).
fn linearize_checkpoint<const D: usize>(
    file: &ScenarioFile,
    at: &AtCheckpoint<D>,
    equilibrium: bool,
    run: &Run,
) -> Result<Manifest, ExportError> {
    if !at.system.bodies().is_empty() {
        return Err(ExportError::Mismatch(
            "the linear model with rigid bodies is taken about the static equilibrium only, not at a checkpoint's state (yet): drop --at".into(),
        ));
    }
    let (r, source) = if equilibrium {
        let params = StaticsParams {
            open_loop: true,
            ..at.statics
        };
        let eq = phstring::statics::solve_from(&at.system, &at.state, &params, run.stop)?;
        let source = format!("equilibrium at {}", at.info.checkpoint);
        (eq.state.r, source)
    } else {
        (at.state.r.clone(), at.info.checkpoint.clone())
    };
    let state = LinearState {
        r,
        time: at.info.time,
        source,
        started_from: Some(at.info.clone()),
    };
    linearize_state(file, &at.system, at.statics.solver, state, run)
}

/// Linearizes `sys` at `at` (node forces only, no rigid bodies) and writes the forms, the
/// positions and the manifest.
fn linearize_state<const D: usize>(
    file: &ScenarioFile,
    sys: &PhSystem<D, Material>,
    solver: phstring::SolverKind,
    at: LinearState<D>,
    run: &Run,
) -> Result<Manifest, ExportError> {
    let Run { modal, out, stop } = *run;
    let r = at.r;
    let (res, _) = phstring::statics::static_residual(sys, &r).map_err(|e| {
        ExportError::Mismatch(format!(
            "element {e}'s strain is outside its law's domain at the state linearized at"
        ))
    })?;
    let static_residual = res.iter().map(|f| f.norm_squared()).sum::<f64>().sqrt();
    let stable =
        phstring::linear::positive_definite(sys, &phstring::linear::tangent_blocks(sys, &r));
    let ports = force_ports(sys);
    // Everything is computed before the first file is written: a stop request leaves the
    // folder as it was.
    let mut warnings = Vec::new();
    let modal_model = match modal {
        Some(k) => {
            let found = phstring::modes::modes(sys, &r, k, solver, stop)?;
            let (_, free) = phstring::linear::free_dofs(sys);
            warnings.extend(super::modes::fewer_modes(
                "--modes",
                k,
                free,
                found.modes.len(),
            ));
            Some(phstring::linear::modal_model(sys, &r, &found.modes, &ports))
        }
        None => None,
    };
    let full = full_model(sys, &r, &ports);
    let reduced = reduced_model(sys, &r, &ports);
    if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
        return Err(StaticsError::Interrupted.into());
    }
    let mut forms = std::collections::BTreeMap::new();
    for (name, model, eqs) in [
        ("full", Some(full), FULL_EQUATIONS),
        ("reduced", Some(reduced), REDUCED_EQUATIONS),
        ("modal", modal_model, MODAL_EQUATIONS),
    ] {
        if let Some(model) = model {
            forms.insert(name, write_form(out, name, &model, eqs)?);
        }
    }
    write_positions(out, &r)?;
    let entry = |p: &ForcePort, sym: &str, unit: &'static str| node_entry(p, sym, unit);
    let manifest = Manifest {
        format: "phstring-linear-ph-1",
        scenario: file.path.display().to_string(),
        dimension: D,
        nodes: sys.mesh().n_nodes(),
        elements: sys.mesh().n_elements(),
        model: "E x' = (J - R) Q x + B u, y = B^T Q x, H = 1/2 x^T E^T Q x",
        inputs: ports.iter().map(|p| entry(p, "F", "N")).collect(),
        outputs: ports.iter().map(|p| entry(p, "v", "m/s")).collect(),
        linearized_at: at.source,
        time: at.time,
        static_residual,
        stable,
        positions: LINEAR_AT_FILE,
        requested_modes: modal,
        warnings,
        forms,
        started_from: at.started_from,
    };
    let json = serde_json::to_string_pretty(&manifest).expect("plain data serializes");
    write(out, MANIFEST_FILE, json.as_bytes())?;
    Ok(manifest)
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Writes the positions linearized at (`LINEAR_AT_FILE`: `node,x,y,z` [m]).
fn write_positions<const D: usize>(out: &Path, r: &[Vector<D>]) -> Result<(), OutputError> {
    let mut pos = String::from("node,x,y,z\n");
    for (i, p) in r.iter().enumerate() {
        let c = |k: usize| if k < D { num(p[k]) } else { "0".into() };
        let _ = writeln!(pos, "{i},{},{},{}", c(0), c(1), c(2));
    }
    write(out, LINEAR_AT_FILE, pos.as_bytes())
}

/// The manifest entry of node port `p` as `sym` (`F` or `v`) in `unit`.
fn node_entry(p: &ForcePort, sym: &str, unit: &'static str) -> PortEntry {
    PortEntry {
        name: format!("{sym}[{}].{}", p.node, AXES[p.component]),
        node: Some(p.node),
        body: None,
        component: AXES[p.component],
        unit,
    }
}

const BODY_EQUATIONS: &str = "x = (q, v): q the free position components and per rigid body its translation and its turn times its radius of gyration (rho w, w the body-axes Cayley vector), v their rates: E = diag(I, M), J = [[0, I], [-I, 0]], R = diag(0, R_v), Q = diag(K, I), so M q'' + R_v q' + K q = B u; inputs: the node force ports, then each body wrench's force and torque (space axes)";

/// [`linearize_equilibrium`] with rigid bodies: the reduced form about the equilibrium only.
fn linearize_bodies<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    run: &Run,
) -> Result<Manifest, ExportError> {
    let Run { modal, out, stop } = *run;
    let sys = &v.problem.system;
    if modal.is_some() {
        return Err(ExportError::Mismatch(
            "the modal form (--modes) does not cover rigid bodies yet: drop --modes (the reduced form has the bodies)".into(),
        ));
    }
    let eq = v.equilibrium(true, stop)?;
    let ports = force_ports(sys);
    let names: Vec<&str> = sys.bodies().iter().map(|b| b.0).collect();
    let wrenches: Vec<usize> = (0..names.len())
        .filter(|&b| sys.body_has_wrench(b))
        .collect();
    let model = phstring::linear::reduced_model_with_bodies(
        sys,
        &eq.state.r,
        &eq.state.bodies,
        &ports,
        &wrenches,
    )
    .map_err(|e| ExportError::Mismatch(e.to_string()))?;
    if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
        return Err(StaticsError::Interrupted.into());
    }
    let mut forms = std::collections::BTreeMap::new();
    forms.insert(
        "reduced",
        write_form(out, "reduced", &model, BODY_EQUATIONS)?,
    );
    write_positions(out, &eq.state.r)?;
    let body_entries = |force: (&str, &'static str), turn: (&str, &'static str)| {
        let turns: &[&'static str] = if D == 3 { &AXES } else { &AXES[2..] };
        let mut all = Vec::new();
        for &b in &wrenches {
            let n = names[b];
            let at = |(sym, unit): (&str, &'static str), a: &'static str| PortEntry {
                name: format!("{sym}[{n}].{a}"),
                node: None,
                body: Some(n.to_string()),
                component: a,
                unit,
            };
            all.extend(AXES[..D].iter().map(|a| at(force, a)));
            all.extend(turns.iter().map(|a| at(turn, a)));
        }
        all
    };
    let inputs = ports
        .iter()
        .map(|p| node_entry(p, "F", "N"))
        .chain(body_entries(("F", "N"), ("T", "N·m")))
        .collect();
    let outputs = ports
        .iter()
        .map(|p| node_entry(p, "v", "m/s"))
        .chain(body_entries(("v", "m/s"), ("w", "rad/s")))
        .collect();
    let manifest = Manifest {
        format: "phstring-linear-ph-1",
        scenario: file.path.display().to_string(),
        dimension: D,
        nodes: sys.mesh().n_nodes(),
        elements: sys.mesh().n_elements(),
        model: "E x' = (J - R) Q x + B u, y = B^T Q x, H = 1/2 x^T E^T Q x",
        inputs,
        outputs,
        linearized_at: "equilibrium".into(),
        time: 0.0,
        static_residual: eq.residual,
        stable: eq.stable,
        positions: LINEAR_AT_FILE,
        requested_modes: None,
        warnings: vec!["with rigid bodies only the reduced form is written (the full mixed form does not cover them yet)".into()],
        forms,
        started_from: None,
    };
    let json = serde_json::to_string_pretty(&manifest).expect("plain data serializes");
    write(out, MANIFEST_FILE, json.as_bytes())?;
    Ok(manifest)
}

fn write(out: &Path, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
    let path = out.join(name);
    atomic_write(&path, bytes).map_err(|cause| OutputError::Io { path, cause })
}

fn write_form(
    out: &Path,
    form: &'static str,
    model: &LinearPh,
    equations: &'static str,
) -> Result<FormEntry, OutputError> {
    let dir = out.join(form);
    std::fs::create_dir_all(&dir).map_err(|cause| OutputError::Io {
        path: dir.clone(),
        cause,
    })?;
    let mut matrices = std::collections::BTreeMap::new();
    for (name, m) in [
        ("E", &model.e),
        ("J", &model.j),
        ("R", &model.r),
        ("Q", &model.q),
        ("B", &model.b),
    ] {
        let comment = format!("phstring linear port-Hamiltonian model, {form} form, matrix {name}");
        write(&dir, &format!("{name}.mtx"), &matrix_market(m, &comment))?;
        write(&dir, &format!("{name}.npz"), &scipy_npz(m))?;
        matrices.insert(
            name,
            MatrixEntry {
                shape: [m.nrows(), m.ncols()],
                nnz: m.compute_nnz(),
                mtx: format!("{form}/{name}.mtx"),
                npz: format!("{form}/{name}.npz"),
            },
        );
    }
    let state_units = model
        .states
        .iter()
        .map(|s| match s.as_bytes().first() {
            Some(b'v') => "m/s",
            Some(b'C') => "1",
            Some(b'e') => "kg^(1/2) m",
            Some(b'n') => "kg^(1/2) m/s",
            _ => "m",
        })
        .collect();
    Ok(FormEntry {
        equations,
        states: model.states.clone(),
        state_units,
        matrices,
    })
}

/// A sparse matrix as MatrixMarket coordinate text (1-based indices, values round-trip).
pub fn matrix_market(m: &SparseColMat<usize, f64>, comment: &str) -> Vec<u8> {
    let a = m.as_ref();
    let mut s = String::from("%%MatrixMarket matrix coordinate real general\n");
    for line in comment.lines() {
        let _ = writeln!(s, "% {line}");
    }
    let _ = writeln!(s, "{} {} {}", a.nrows(), a.ncols(), a.compute_nnz());
    for c in 0..a.ncols() {
        for (r, v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            let _ = writeln!(s, "{} {} {:e}", r + 1, c + 1, v);
        }
    }
    s.into_bytes()
}

/// A sparse matrix as an `.npz` in the layout of `scipy.sparse.save_npz` (CSC: `format`,
/// `shape`, `data`, `indices`, `indptr`), readable by `scipy.sparse.load_npz`.
pub fn scipy_npz(m: &SparseColMat<usize, f64>) -> Vec<u8> {
    let a = m.as_ref();
    let mut data = Vec::new();
    let mut indices = Vec::new();
    let mut indptr = vec![0i64];
    for c in 0..a.ncols() {
        for (r, v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            data.push(*v);
            indices.push(r as i64);
        }
        indptr.push(indices.len() as i64);
    }
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    let entries: [(&str, Vec<u8>); 5] = [
        ("format.npy", npy("|S3", "()", b"csc")),
        ("shape.npy", npy_i64(&[a.nrows() as i64, a.ncols() as i64])),
        ("data.npy", npy_f64(&data)),
        ("indices.npy", npy_i64(&indices)),
        ("indptr.npy", npy_i64(&indptr)),
    ];
    for (name, bytes) in entries {
        zip.start_file(name, opts).expect("in-memory zip");
        zip.write_all(&bytes).expect("in-memory zip");
    }
    zip.finish().expect("in-memory zip").into_inner()
}

/// A `.npy` file (format 1.0) of dtype `descr`, shape `shape` (Python tuple text), little
/// endian payload `raw`.
fn npy(descr: &str, shape: &str, raw: &[u8]) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + raw.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(raw);
    out
}

fn npy_f64(v: &[f64]) -> Vec<u8> {
    let raw: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    npy("<f8", &format!("({},)", v.len()), &raw)
}

fn npy_i64(v: &[i64]) -> Vec<u8> {
    let raw: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    npy("<i8", &format!("({},)", v.len()), &raw)
}
