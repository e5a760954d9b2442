//! The reduced linear model with rigid bodies (docs/method.md §22, "The linear model with
//! rigid bodies"): the second-order model on the coordinates of the modal analysis with
//! bodies, with the node force ports and the bodies' wrench ports.

use faer::sparse::Triplet;

use super::{ForcePort, LinearPh, damping_blocks, identity_triplets, sparse};
use crate::body::{BodyState, Mat3};
use crate::material::StoredEnergy;
use crate::modes::bodies::{body_mass, node_map, strings_mass};
use crate::statics::{body_coordinates, body_hessian};
use crate::system::{PhSystem, Vector};

/// Why no linear model with bodies was formed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum BodiesLinearError {
    /// A strain is off its law's domain at the state.
    #[error("an element's strain is outside its law's domain at the state linearized at")]
    Strain,
    /// The poses do not match the bodies.
    #[error("{got} rigid-body poses given for {expected} bodies")]
    Poses {
        /// Poses given.
        got: usize,
        /// Bodies.
        expected: usize,
    },
    /// A body's pose is prescribed (a motion).
    #[error(
        "rigid body '{name}' has a prescribed pose (a motion), which the statics hold: the linear model about a prescribed body is not available yet (give it no motion for the analysis)"
    )]
    Prescribed {
        /// The body's name.
        name: String,
    },
}

/// The reduced second-order model with rigid bodies about the rest state of node positions
/// `r` [m] and body poses `poses`: state `x = (q, v)`, `q` the free node components [m] and
/// per body its translation [m] and its turn times its radius of gyration `ρ w` [m] (the
/// coordinates of [`crate::modes::modes_with_bodies`]), `v` their rates; `E = diag(I, M)`,
/// `J = [[0, I], [−I, 0]]`, `R = diag(0, R_v)`, `Q = diag(K, I)`. `R_v` is the strings'
/// damping of [`damping_blocks`] through the nodes' map, plus a body's linear drag on its
/// translation. The inputs are the node force ports `ports` (in their order), then per body
/// of `wrench_bodies` its force (`D` components [N]) and torque (3 in 3D, the one about `z`
/// in 2D [N·m], space axes); the output of each is the matching velocity [m/s] or angular
/// velocity [rad/s].
pub fn reduced_model_with_bodies<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    poses: &[BodyState],
    ports: &[ForcePort],
    wrench_bodies: &[usize],
) -> Result<LinearPh, BodiesLinearError> {
    if poses.len() != sys.bodies.len() {
        return Err(BodiesLinearError::Poses {
            got: poses.len(),
            expected: sys.bodies.len(),
        });
    }
    if let Some(b) = sys.bodies.iter().position(|b| b.motion.is_some()) {
        return Err(BodiesLinearError::Prescribed {
            name: sys.body_names[b].clone(),
        });
    }
    let (n, tk) = body_hessian(sys, r, poses).ok_or(BodiesLinearError::Strain)?;
    let (dof, n_free) = crate::assembly::free_dofs(sys);
    let map = node_map(sys, poses, n_free);
    let m = strings_mass(sys, &map, n) + body_mass(sys, poses, n_free, n);
    let mut te = Vec::new();
    identity_triplets(n, 0, 0, 1.0, &mut te);
    dense_triplets(&m, n, &mut te);
    let mut tj = Vec::new();
    identity_triplets(n, 0, n, 1.0, &mut tj);
    identity_triplets(n, n, 0, -1.0, &mut tj);
    let mut tq = tk;
    identity_triplets(n, n, n, 1.0, &mut tq);
    let tr = damping(sys, r, &map, n_free, n);
    let per = body_coordinates(D);
    let mut tb = Vec::new();
    for (c, p) in ports.iter().enumerate() {
        if let Some(i) = dof[p.node * D + p.component] {
            tb.push(Triplet::new(n + i, c, 1.0));
        }
    }
    let mut col = ports.len();
    for &b in wrench_bodies {
        let base = n + n_free + b * per;
        for k in 0..D {
            tb.push(Triplet::new(base + k, col + k, 1.0));
        }
        col += D;
        // τ·δθ = τ·R₀ δ(ρw)/ρ.
        let rho = sys.bodies[b].gyration();
        let r0: Mat3 = poses[b].orientation.to_rotation_matrix().into_inner();
        if D == 3 {
            for (j, m) in (0..3).flat_map(|j| (0..3).map(move |m| (j, m))) {
                tb.push(Triplet::new(base + 3 + m, col + j, r0[(j, m)] / rho));
            }
            col += 3;
        } else {
            tb.push(Triplet::new(base + 2, col, 1.0 / rho));
            col += 1;
        }
    }
    let names = state_names(sys, &dof);
    let states = names
        .iter()
        .map(|s| format!("q{s}"))
        .chain(names.iter().map(|s| format!("v{s}")))
        .collect();
    Ok(LinearPh {
        e: sparse(2 * n, 2 * n, &te),
        j: sparse(2 * n, 2 * n, &tj),
        r: sparse(2 * n, 2 * n, &tr),
        q: sparse(2 * n, 2 * n, &tq),
        b: sparse(2 * n, col, &tb),
        states,
    })
}

/// The nonzero entries of the dense `m` (`n × n`) at rows and columns `n …`.
fn dense_triplets(m: &faer::Mat<f64>, n: usize, out: &mut Vec<Triplet<usize, usize, f64>>) {
    for c in 0..n {
        for r in 0..n {
            let v = m[(r, c)];
            if v != 0.0 {
                out.push(Triplet::new(n + r, n + c, v));
            }
        }
    }
}

/// `R_v` through the nodes' map, plus each body's linear drag on its translation, at rows
/// and columns `n …`.
fn damping<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    map: &crate::modes::bodies::NodeMap<D>,
    n_free: usize,
    n: usize,
) -> Vec<Triplet<usize, usize, f64>> {
    let mut rv = faer::Mat::<f64>::zeros(n, n);
    if sys.has_damping() || sys.water.is_some() {
        let blocks = damping_blocks(sys, r);
        crate::modes::bodies::add_through(&mut rv, map, &blocks, &sys.mesh);
    }
    let per = body_coordinates(D);
    for (b, model) in sys.bodies.iter().enumerate() {
        if let Some((linear, _, _)) = model.drag {
            for k in 0..D {
                rv[(n_free + b * per + k, n_free + b * per + k)] += linear;
            }
        }
    }
    let mut t = Vec::new();
    dense_triplets(&rv, n, &mut t);
    t
}

/// `[i].x` for every free component, then `BODY.x`, …, `BODY.rho_wx`, … per body (the scaled
/// turn's components).
fn state_names<const D: usize, M>(sys: &PhSystem<D, M>, dof: &[Option<usize>]) -> Vec<String> {
    const AXES: [&str; 3] = ["x", "y", "z"];
    let mut names: Vec<String> = dof
        .iter()
        .enumerate()
        .filter(|(_, d)| d.is_some())
        .map(|(i, _)| format!("[{}].{}", i / D, AXES[i % D]))
        .collect();
    for name in &sys.body_names {
        names.extend(AXES[..D].iter().map(|a| format!("[{name}].{a}")));
        let turns: &[&str] = if D == 3 { &AXES } else { &AXES[2..] };
        names.extend(turns.iter().map(|a| format!("[{name}].rho_w{a}")));
    }
    names
}
