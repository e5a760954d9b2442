//! `phstring mooring`: the mooring of a rigid body about the static equilibrium of a
//! scenario (docs/method.md, "The mooring stiffness and the offset–tension curve"): its
//! restoring stiffness matrix and its offset–tension curve along one degree of freedom.
//!
//! Files written into the output folder:
//! * `stiffness.csv`: the `6 × 6` (2D: `3 × 3`) matrix `K`, one row per restoring force or
//!   moment component (`dof` column: `x, y, z, rx, ry, rz`), one column per displacement or
//!   turn; units N/m, N/rad, N, N·m/rad (space axes, moments about the centre of mass);
//! * `offset.csv`: per offset [m or rad] of the body held away from its equilibrium, the
//!   strings' force [N] and moment [N·m] on it, the tension [N] at each of its points and
//!   the reaction [N] at each support;
//! * `summary.json`: the body, its equilibrium pose, the matrix, the curve and the solves.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use phstring::statics::{
    self, BodyStiffness, Equilibrium, MooringError, OffsetPoint, StaticsError,
};
use phstring::{Material, PhSystem};
use serde::Serialize;

use crate::files::{SUMMARY_FILE, atomic_write, num};
use crate::output::OutputError;
use crate::scenario::{AnySetup, ScenarioError, ScenarioFile, Setup};

/// The stiffness matrix's file.
pub const STIFFNESS_FILE: &str = "stiffness.csv";
/// The offset–tension curve's file.
pub const OFFSET_FILE: &str = "offset.csv";

/// Why `phstring mooring` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MooringRunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// No equilibrium (or invalid setup).
    #[error(transparent)]
    Statics(#[from] StaticsError),
    /// The stiffness or a point of the curve could not be found.
    #[error(transparent)]
    Mooring(#[from] MooringError),
    /// The request does not fit the scenario (no bodies, an unknown body or degree of
    /// freedom, a bad offset).
    #[error("{0}")]
    Request(String),
    /// Writing outputs failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl MooringRunError {
    /// Whether a stop request (Ctrl-C) ended a solve (nothing is written then).
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            MooringRunError::Statics(StaticsError::Interrupted)
                | MooringRunError::Mooring(MooringError::Offset {
                    source: StaticsError::Interrupted,
                    ..
                })
        )
    }
}

/// What to compute.
#[derive(Debug, Clone, PartialEq)]
pub struct MooringRequest {
    /// The body's name (`None`: the scenario's only body).
    pub body: Option<String>,
    /// The curve's degree of freedom: `x`, `y`, `z`, `rx`, `ry` or `rz` (2D: `x`, `y`, `rz`).
    pub dof: String,
    /// The largest offset [m] or turn [deg] (`None`: 5 % of the largest distance from the
    /// body's centre to a support, or 10°).
    pub max: Option<f64>,
    /// Offsets on each side of the equilibrium (≥ 1).
    pub steps: usize,
}

/// One point of the curve, as written.
#[derive(Debug, Clone, Serialize)]
pub struct CurvePoint {
    /// Offset [m] or turn [rad].
    pub offset: f64,
    /// The strings' force on the body [N].
    pub force: Vec<f64>,
    /// Their moment about its centre [N·m] (2D: about `z` only).
    pub moment: Vec<f64>,
    /// Tension at each of the body's points [N], in the order of `points`.
    pub tensions: Vec<f64>,
    /// Reaction at each support [N], in the order of `supports`.
    pub anchors: Vec<f64>,
    /// Newton iterations of its statics.
    pub iterations: usize,
}

/// What `summary.json` of a mooring analysis holds.
#[derive(Debug, Clone, Serialize)]
pub struct MooringInfo {
    /// Scenario title or file name.
    pub title: String,
    /// Spatial dimension.
    pub dimension: usize,
    /// The body.
    pub body: String,
    /// Its position [m] and orientation (quaternion `[w, x, y, z]`) at the equilibrium.
    pub position: Vec<f64>,
    /// Orientation at the equilibrium.
    pub orientation: [f64; 4],
    /// The degrees of freedom, in the matrix's order.
    pub dofs: Vec<&'static str>,
    /// The stiffness matrix by rows (see `stiffness.csv`).
    pub stiffness: Vec<Vec<f64>>,
    /// The curve's degree of freedom and its unit (`m` or `rad`).
    pub curve_dof: String,
    /// Unit of the offsets.
    pub curve_unit: &'static str,
    /// The body's points (`"BODY.POINT"` or `node N`), in the order of the tensions.
    pub points: Vec<String>,
    /// The supports (named nodes or `node N`), in the order of the reactions.
    pub supports: Vec<String>,
    /// The curve, by increasing offset.
    pub curve: Vec<CurvePoint>,
    /// How the equilibrium was found.
    pub equilibrium_path: &'static str,
    /// Wall time [s].
    pub solve_s: f64,
}

/// The mooring analysis of `request` for scenario `file` (validated and built: `setup`),
/// written into `out` (which must exist).
pub fn mooring(
    file: &ScenarioFile,
    setup: &AnySetup,
    request: &MooringRequest,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<MooringInfo, MooringRunError> {
    phstring::by_dim!(setup, s => mooring_dim(file, s, request, out, stop))
}

fn mooring_dim<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    request: &MooringRequest,
    out: &Path,
    stop: Option<&AtomicBool>,
) -> Result<MooringInfo, MooringRunError> {
    let start = Instant::now();
    let sys = &v.problem.system;
    let (body, dof) = resolve(sys, request)?;
    let eq = v.equilibrium(false, stop)?;
    let params = v.statics_params(false);
    let k = statics::body_stiffness(sys, &eq, body, &params)?;
    let turn = dof >= D;
    let max = match request.max {
        Some(m) if turn => m.to_radians(),
        Some(m) => m,
        None if turn => 10f64.to_radians(),
        None => default_reach(sys, &eq, body),
    };
    let step = max / request.steps as f64;
    let side = |sign: f64| -> Vec<f64> {
        (1..=request.steps)
            .map(|i| sign * step * i as f64)
            .collect()
    };
    let mut below = statics::offset_curve(sys, &eq, (body, dof), &side(-1.0), &params, stop)?;
    let above = statics::offset_curve(sys, &eq, (body, dof), &side(1.0), &params, stop)?;
    let at_zero = statics::offset_curve(sys, &eq, (body, dof), &[0.0], &params, stop)?;
    below.reverse();
    let curve: Vec<OffsetPoint> = below.into_iter().chain(at_zero).chain(above).collect();
    let info = summary(
        file,
        v,
        (body, dof),
        &eq,
        &k,
        &curve,
        start.elapsed().as_secs_f64(),
    );
    write_files(out, &info)?;
    Ok(info)
}

/// The body's index and the degree of freedom's, or the request's error.
fn resolve<const D: usize>(
    sys: &PhSystem<D, Material>,
    request: &MooringRequest,
) -> Result<(usize, usize), MooringRunError> {
    let bodies = sys.bodies();
    let names: Vec<&str> = bodies.iter().map(|(n, _)| *n).collect();
    let body = match &request.body {
        None if names.len() == 1 => 0,
        None if names.is_empty() => {
            return Err(MooringRunError::Request(
                "the scenario has no rigid body ([bodies.NAME]): the mooring analysis is that of a body".into(),
            ));
        }
        None => {
            return Err(MooringRunError::Request(format!(
                "the scenario has {} rigid bodies: name one with --body (known: {})",
                names.len(),
                names.join(", ")
            )));
        }
        Some(name) => names.iter().position(|n| n == name).ok_or_else(|| {
            MooringRunError::Request(format!(
                "--body {name}: no such rigid body (known: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ))
        })?,
    };
    let dofs = statics::body_dofs(D);
    let dof = dofs.iter().position(|d| *d == request.dof).ok_or_else(|| {
        MooringRunError::Request(format!(
            "--dof {}: a body in {D}D has the degrees of freedom {}",
            request.dof,
            dofs.join(", ")
        ))
    })?;
    if let Some(m) = request.max
        && !(m > 0.0 && m.is_finite())
    {
        return Err(MooringRunError::Request(format!(
            "--max {m}: the largest offset must be positive and finite"
        )));
    }
    if request.steps == 0 {
        return Err(MooringRunError::Request(
            "--steps 0: at least one offset on each side".into(),
        ));
    }
    Ok((body, dof))
}

/// 5 % of the largest distance from the body's centre to a support [m] (1 m without
/// supports).
fn default_reach<const D: usize>(
    sys: &PhSystem<D, Material>,
    eq: &Equilibrium<D>,
    body: usize,
) -> f64 {
    let centre = eq.state.bodies[body].position;
    let far = sys
        .support_nodes()
        .map(|i| {
            let r = &eq.state.r[i];
            (0..D)
                .map(|k| (r[k] - centre[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    if far > 0.0 { 0.05 * far } else { 1.0 }
}

fn summary<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
    (body, dof): (usize, usize),
    eq: &Equilibrium<D>,
    k: &BodyStiffness,
    curve: &[OffsetPoint],
    solve_s: f64,
) -> MooringInfo {
    let sys = &v.problem.system;
    let name_of = |node: usize| {
        v.components
            .nodes
            .iter()
            .find(|n| n.node == node)
            .map_or_else(|| format!("node {node}"), |n| n.name.clone())
    };
    let pose = &eq.state.bodies[body];
    let q = pose.orientation.quaternion();
    let dofs = statics::body_dofs(D);
    MooringInfo {
        title: file
            .scenario
            .title
            .clone()
            .unwrap_or_else(|| file.path.display().to_string()),
        dimension: D,
        body: sys.bodies()[body].0.to_string(),
        position: pose.position.iter().take(D).copied().collect(),
        orientation: [q.w, q.i, q.j, q.k],
        dofs: dofs.to_vec(),
        stiffness: k
            .matrix
            .row_iter()
            .map(|r| r.iter().copied().collect())
            .collect(),
        curve_dof: dofs[dof].to_string(),
        curve_unit: if dof >= D { "rad" } else { "m" },
        points: sys
            .body_attachments(body)
            .iter()
            .map(|&n| name_of(n))
            .collect(),
        supports: sys.support_nodes().map(name_of).collect(),
        curve: curve
            .iter()
            .map(|p| CurvePoint {
                offset: p.offset,
                force: p.force.iter().take(D).copied().collect(),
                moment: if D == 2 {
                    vec![p.moment.z]
                } else {
                    p.moment.iter().copied().collect()
                },
                tensions: p.tensions.clone(),
                anchors: p.anchors.iter().map(|a| a.1).collect(),
                iterations: p.iterations,
            })
            .collect(),
        equilibrium_path: eq.path.name(),
        solve_s,
    }
}

fn write(out: &Path, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
    let path = out.join(name);
    atomic_write(&path, bytes).map_err(|cause| OutputError::Io { path, cause })
}

/// A CSV field: quoted when it holds a comma or a quote.
fn field(s: &str) -> String {
    if s.contains([',', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn write_files(out: &Path, info: &MooringInfo) -> Result<(), OutputError> {
    let mut csv = String::from("dof");
    for d in &info.dofs {
        let _ = write!(csv, ",{d}");
    }
    csv.push('\n');
    for (d, row) in info.dofs.iter().zip(&info.stiffness) {
        csv.push_str(d);
        for x in row {
            let _ = write!(csv, ",{}", num(*x));
        }
        csv.push('\n');
    }
    write(out, STIFFNESS_FILE, csv.as_bytes())?;
    let axes = ["x", "y", "z"];
    let mut csv = format!("offset_{}", info.curve_dof);
    for a in &axes[..info.dimension] {
        let _ = write!(csv, ",force_{a}");
    }
    if info.dimension == 2 {
        csv.push_str(",moment_z");
    } else {
        csv.push_str(",moment_x,moment_y,moment_z");
    }
    for p in &info.points {
        let _ = write!(csv, ",{}", field(&format!("tension {p}")));
    }
    for s in &info.supports {
        let _ = write!(csv, ",{}", field(&format!("reaction {s}")));
    }
    csv.push('\n');
    for p in &info.curve {
        csv.push_str(&num(p.offset));
        for x in p
            .force
            .iter()
            .chain(&p.moment)
            .chain(&p.tensions)
            .chain(&p.anchors)
        {
            let _ = write!(csv, ",{}", num(*x));
        }
        csv.push('\n');
    }
    write(out, OFFSET_FILE, csv.as_bytes())?;
    let json = serde_json::to_string_pretty(info).expect("plain data serializes");
    write(out, SUMMARY_FILE, json.as_bytes())
}
