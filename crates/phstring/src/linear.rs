//! The linearized system about a rest state (docs/method.md §15–§16): tangent stiffness
//! `K_T = ∂(K(r) S(C(r)))/∂r` [N/m] and mass `M_ρ` [kg] on the free position components,
//! their positive-definiteness (stability of an equilibrium), and the sparse matrices of
//! the linear port-Hamiltonian model.

use faer::sparse::{SparseColMat, Triplet};
use nalgebra::SMatrix;

use crate::linsolve::BlockJacobian;
use crate::material::StoredEnergy;
use crate::system::{Law, PhSystem, Vector, element_mass};

pub use crate::assembly::{free_dofs, mass_blocks, positive_definite, restrict, tangent_blocks};
pub use bodies::{BodiesLinearError, reduced_model_with_bodies};

mod bodies;

/// The triplets of `R_v` on the free DOFs `dof` (`n` of them) at positions `r` [m], placed
/// at rows and columns `n …` (the velocity block of both the reduced and the full model).
fn damping_triplets<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    dof: &[Option<usize>],
    n: usize,
) -> Vec<Triplet<usize, usize, f64>> {
    let mut tr = Vec::new();
    triplets(
        &restrict(&sys.mesh, &damping_blocks(sys, r), dof, n),
        n,
        n,
        1.0,
        &mut tr,
    );
    tr
}

/// The damping matrix `R_v` [N·s/m] in node-block form at positions `r` [m]: the derivative
/// of the dissipative forces by the velocities at rest (docs/method.md §18). Kelvin–Voigt adds
/// `(2η/l) r' r'ᵀ`, drag `c` times the mass pattern, a dashpot `c I`, to the diagonal blocks
/// of an element's nodes and the negative (drag: the mass pattern's coupling) to its coupling
/// blocks. In water ([`crate::water`]), the derivative at rest of the drag in the current (with
/// the equivalent linear drag of [`crate::Water::linear_drag_amplitude`]), of the seabed
/// damping and of the friction's zero-slip slope where a node lies on the seabed
/// (docs/method.md §21). Symmetric positive semidefinite; zero without damping.
pub fn damping_blocks<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
) -> BlockJacobian<D> {
    let mut j = BlockJacobian::zeros(&sys.mesh);
    let eye = SMatrix::<f64, D, D>::identity();
    for (g, e, [a, b], l) in sys.each_element() {
        let d = g.damping;
        if d.is_none() {
            continue;
        }
        let rp = (r[b] - r[a]) / l;
        let axial = rp * rp.transpose() * (2.0 * d.kelvin_voigt / l) + eye * d.dashpot;
        let (cd, co) = element_mass(g.mass, d.drag, l);
        j.diag[a] += axial + eye * cd;
        j.diag[b] += axial + eye * cd;
        j.off[e] = [eye * co - axial, eye * co - axial];
    }
    if let Some(w) = sys.water.as_deref() {
        for node in &w.nodes {
            j.diag[node.node] += w.node_damping(node, r);
        }
        for el in &w.elements {
            let [a, b] = sys.mesh.elements()[el.e];
            let quarter = w.element_damping(el, (&r[a], &r[b])) * 0.25;
            j.diag[a] += quarter;
            j.diag[b] += quarter;
            j.off[el.e][0] += quarter;
            j.off[el.e][1] += quarter;
        }
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{Boundary, Fixed};
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::network::{NetworkBuilder, StringSpec};
    use crate::system::{MassMatrix, Problem, State};

    /// The tangent blocks equal central differences of the static residual.
    #[test]
    fn tangent_matches_finite_differences() {
        let mesh = Mesh::uniform_chain(4, 4.0).unwrap();
        let mut st = State::straight(&mesh, Vector::<2>::zeros(), Vector::<2>::new(3.0, -2.0));
        st.r[2] += Vector::<2>::new(0.3, 0.1);
        let st = State::at_rest(&mesh, st.r);
        let p = Problem {
            mesh: mesh.clone(),
            initial: st.clone(),
            material: Material::hyperelastic(1e3),
            rho_a: 1.0,
            body_force: Vector::<2>::new(0.0, -9.81),
            mass: MassMatrix::Consistent,
            boundary: Boundary::default(),
            point_masses: vec![],
        };
        let (sys, _) = PhSystem::new(p).unwrap();
        let k = tangent_blocks(&sys, &st.r);
        let force = |r: &[Vector<2>]| {
            let mut f = vec![Vector::<2>::zeros(); r.len()];
            sys.k_mul(r, &sys_stress(&sys, r), &mut f);
            f
        };
        let eps = 1e-6;
        for j in 0..5 {
            for m in 0..2 {
                let (mut rp, mut rm) = (st.r.clone(), st.r.clone());
                rp[j][m] += eps;
                rm[j][m] -= eps;
                let (fp, fm) = (force(&rp), force(&rm));
                for i in 0..5 {
                    let num = (fp[i] - fm[i]) / (2.0 * eps);
                    let blk = if i == j {
                        Some(k.diag[i])
                    } else if j == i + 1 {
                        Some(k.off[i][0])
                    } else if i == j + 1 {
                        Some(k.off[j][1])
                    } else {
                        None
                    };
                    let col = blk.map_or(Vector::<2>::zeros(), |b| b.column(m).into());
                    assert!(
                        (num - col).norm() <= 1e-6 * 1e3,
                        "{i} {j} {m}: {num} vs {col}"
                    );
                }
            }
        }
    }

    fn sys_stress(sys: &PhSystem<2, Material>, r: &[Vector<2>]) -> Vec<f64> {
        let st = State::at_rest(sys.mesh(), r.to_vec());
        let mut s = vec![0.0; st.c.len()];
        sys.stresses(&st.c, &mut s);
        s
    }

    /// A taut string is stable, a compressed straight one is not; the chain's block pivots
    /// and the sparse Cholesky of a network agree.
    #[test]
    fn stability_of_taut_and_compressed_strings() {
        for (stretch, stable) in [(1.1, true), (0.9, false)] {
            let mesh = Mesh::uniform_chain(10, 10.0).unwrap();
            let st = State::straight(
                &mesh,
                Vector::<2>::zeros(),
                Vector::<2>::new(10.0 * stretch, 0.0),
            );
            let p = Problem {
                mesh,
                initial: st.clone(),
                material: Material::linear_elastic(1e6),
                rho_a: 1.0,
                body_force: Vector::<2>::zeros(),
                mass: MassMatrix::Consistent,
                boundary: Boundary {
                    fixed: vec![Fixed::node(0), Fixed::node(10)],
                    ..Default::default()
                },
                point_masses: vec![],
            };
            let (sys, _) = PhSystem::new(p).unwrap();
            assert_eq!(
                positive_definite(&sys, &tangent_blocks(&sys, &st.r)),
                stable
            );
            assert!(positive_definite(&sys, &mass_blocks(&sys)));
            // The same string as a network of two strings meeting at a junction.
            let mut b = NetworkBuilder::<2, Material>::new();
            let a = b.node(Vector::<2>::zeros());
            let m = b.node(Vector::<2>::new(5.0 * stretch, 0.0));
            let c = b.node(Vector::<2>::new(10.0 * stretch, 0.0));
            for (name, from, to) in [("left", a, m), ("right", m, c)] {
                let spec = StringSpec {
                    name: name.into(),
                    material: Material::linear_elastic(1e6),
                    rho_a: 1.0,
                    mass: MassMatrix::Consistent,
                    body_force: Vector::<2>::zeros(),
                    prestretch: stretch,
                };
                b.string(spec, &[from, to], 5).unwrap();
            }
            let boundary = Boundary {
                fixed: vec![Fixed::node(a), Fixed::node(c)],
                ..Default::default()
            };
            let net = b.build(boundary, vec![]).unwrap();
            let (sys, st) = PhSystem::new(net).unwrap();
            assert_eq!(
                positive_definite(&sys, &tangent_blocks(&sys, &st.r)),
                stable
            );
        }
    }
}

/// A sparse linear port-Hamiltonian descriptor model
/// `E ẋ = (J − R) Q x + B u`, `y = Bᵀ Q x`, with Hamiltonian `H = ½ xᵀ Eᵀ Q x`.
#[derive(Debug, Clone)]
pub struct LinearPh {
    /// `E` (symmetric positive definite here).
    pub e: SparseColMat<usize, f64>,
    /// `J = −Jᵀ`.
    pub j: SparseColMat<usize, f64>,
    /// `R = Rᵀ ⪰ 0`: the damping matrix on the velocities (zero without damping).
    pub r: SparseColMat<usize, f64>,
    /// `Q`, with `Eᵀ Q` symmetric (positive semidefinite at a stable equilibrium).
    pub q: SparseColMat<usize, f64>,
    /// `B`: one column per input.
    pub b: SparseColMat<usize, f64>,
    /// Name of every state component, in order, e.g. `r[12].y`, `v[3].x`, `C[7]`, `q[12].y`.
    pub states: Vec<String>,
}

/// One input of the linear model: a force component at a node, with the velocity of that
/// component as its output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ForcePort {
    /// Node index.
    pub node: usize,
    /// Component (0 = x, 1 = y, 2 = z).
    pub component: usize,
}

/// The force ports of a system: every component of every loaded node that is free, in the
/// order of the loads, then those of the feedback ports (the linear model is the open-loop
/// plant: a feedback law is not applied, its port is an input to close the loop with).
pub fn force_ports<const D: usize, M>(sys: &PhSystem<D, M>) -> Vec<ForcePort> {
    let mut ports = Vec::new();
    let nodes = sys.boundary.loads.iter().map(|l| l.node);
    for node in nodes.chain(sys.boundary.feedback.iter().map(|f| f.node)) {
        for k in 0..D {
            let p = ForcePort { node, component: k };
            if sys.free[node][k] && !ports.contains(&p) {
                ports.push(p);
            }
        }
    }
    ports
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn sparse(n: usize, m: usize, t: &[Triplet<usize, usize, f64>]) -> SparseColMat<usize, f64> {
    SparseColMat::try_new_from_triplets(n, m, t).expect("indices in range by construction")
}

fn triplets(
    a: &SparseColMat<usize, f64>,
    row0: usize,
    col0: usize,
    sign: f64,
    out: &mut Vec<Triplet<usize, usize, f64>>,
) {
    let a = a.as_ref();
    for c in 0..a.ncols() {
        for (r, v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            out.push(Triplet::new(row0 + r, col0 + c, sign * v));
        }
    }
}

fn identity_triplets(
    n: usize,
    row0: usize,
    col0: usize,
    sign: f64,
    out: &mut Vec<Triplet<usize, usize, f64>>,
) {
    out.extend((0..n).map(|i| Triplet::new(row0 + i, col0 + i, sign)));
}

/// The input matrix of `ports` on the free components numbered by `dof` (rows `row0…`).
fn input_matrix<const D: usize>(
    ports: &[ForcePort],
    dof: &[Option<usize>],
    rows: usize,
    row0: usize,
) -> SparseColMat<usize, f64> {
    let t: Vec<_> = ports
        .iter()
        .enumerate()
        .filter_map(|(c, p)| dof[p.node * D + p.component].map(|r| Triplet::new(row0 + r, c, 1.0)))
        .collect();
    sparse(rows, ports.len(), &t)
}

/// The reduced second-order model on the free position components, about the rest state at
/// positions `r` [m]: state `x = (q, v)` (displacements [m] and velocities [m/s] of the free
/// components), `E = diag(I, M)`, `J = [[0, I], [−I, 0]]`, `R = diag(0, R_v)`
/// ([`damping_blocks`]), `Q = diag(K_T, I)`, `B = [0; B_f]`. So
/// `M q̈ + R_v q̇ + K_T q = B_f u` and `y = B_fᵀ v`, `H = ½ qᵀ K_T q + ½ vᵀ M v`.
pub fn reduced_model<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    ports: &[ForcePort],
) -> LinearPh {
    let (dof, n) = free_dofs(sys);
    let k = restrict(&sys.mesh, &tangent_blocks(sys, r), &dof, n);
    let m = restrict(&sys.mesh, &mass_blocks(sys), &dof, n);
    let mut te = Vec::new();
    identity_triplets(n, 0, 0, 1.0, &mut te);
    triplets(&m, n, n, 1.0, &mut te);
    let mut tj = Vec::new();
    identity_triplets(n, 0, n, 1.0, &mut tj);
    identity_triplets(n, n, 0, -1.0, &mut tj);
    let mut tq = Vec::new();
    triplets(&k, 0, 0, 1.0, &mut tq);
    identity_triplets(n, n, n, 1.0, &mut tq);
    let tr = damping_triplets(sys, r, &dof, n);
    let names = free_names(sys, &dof);
    let states = names
        .iter()
        .map(|s| format!("q{s}"))
        .chain(names.iter().map(|s| format!("v{s}")))
        .collect();
    LinearPh {
        e: sparse(2 * n, 2 * n, &te),
        j: sparse(2 * n, 2 * n, &tj),
        r: sparse(2 * n, 2 * n, &tr),
        q: sparse(2 * n, 2 * n, &tq),
        b: input_matrix::<D>(ports, &dof, 2 * n, n),
        states,
    }
}

/// `[i].x` for every free component, in free-DOF order.
fn free_names<const D: usize, M>(sys: &PhSystem<D, M>, dof: &[Option<usize>]) -> Vec<String> {
    let _ = sys;
    dof.iter()
        .enumerate()
        .filter(|(_, d)| d.is_some())
        .map(|(i, _)| format!("[{}].{}", i / D, AXES[i % D]))
        .collect()
}

/// The paper's mixed model linearized about the rest state at positions `r` [m]: state
/// `x = (δr, δv, δC)` (free position and velocity components, every element strain),
/// `E = diag(I, M_ρ, M_S)`, `J = [[0, I, 0], [−I, 0, −2K], [0, 2Kᵀ, 0]]` with `K = K(r)`,
/// `R = diag(0, R_v, 0)` ([`damping_blocks`]: the Kelvin–Voigt stress acts through `Ċ`, which
/// is `2 M_S⁻¹ Kᵀ v`), `Q = diag(K_G, I, diag(W''(C_e)))` with the geometric stiffness `K_G` (the
/// `S_e I/l_e` part of the tangent stiffness), `B = [0; B_f; 0]`. `Eᵀ Q = diag(K_G, M_ρ,
/// diag(l_e W''))` is symmetric, and positive semidefinite where every element is in tension.
pub fn full_model<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    ports: &[ForcePort],
) -> LinearPh {
    let (dof, n) = free_dofs(sys);
    let n_el = sys.mesh.n_elements();
    let m = restrict(&sys.mesh, &mass_blocks(sys), &dof, n);
    // Geometric stiffness, the coupling K(r) (rows: free components, columns: elements) and
    // W''(C_e).
    let mut kg = BlockJacobian::zeros(&sys.mesh);
    let mut tk = Vec::new();
    let mut w2 = Vec::with_capacity(n_el);
    for (g, e, [a, b], l) in sys.each_element() {
        let rp = (r[b] - r[a]) / l;
        let c = rp.norm_squared();
        let (s, d2w) = match &g.law {
            Law::String(m) => (2.0 * m.dw(c), m.d2w(c)),
            Law::Spring(sp) => (2.0 * sp.dw(c), sp.d2w(c)),
        };
        let blk = SMatrix::<f64, D, D>::identity() * (s / l);
        kg.diag[a] += blk;
        kg.diag[b] += blk;
        kg.off[e] = [-blk, -blk];
        for k in 0..D {
            if let Some(i) = dof[a * D + k] {
                tk.push(Triplet::new(i, e, -rp[k]));
            }
            if let Some(i) = dof[b * D + k] {
                tk.push(Triplet::new(i, e, rp[k]));
            }
        }
        w2.push(d2w);
    }
    let kg = restrict(&sys.mesh, &kg, &dof, n);
    let kc = sparse(n, n_el, &tk);
    let size = 2 * n + n_el;
    let mut te = Vec::new();
    identity_triplets(n, 0, 0, 1.0, &mut te);
    triplets(&m, n, n, 1.0, &mut te);
    te.extend((0..n_el).map(|e| Triplet::new(2 * n + e, 2 * n + e, sys.mesh.lengths()[e])));
    let mut tj = Vec::new();
    identity_triplets(n, 0, n, 1.0, &mut tj);
    identity_triplets(n, n, 0, -1.0, &mut tj);
    triplets(&kc, n, 2 * n, -2.0, &mut tj);
    let kct = kc
        .as_ref()
        .transpose()
        .to_col_major()
        .expect("transpose of a valid matrix");
    triplets(&kct, 2 * n, n, 2.0, &mut tj);
    let mut tq = Vec::new();
    triplets(&kg, 0, 0, 1.0, &mut tq);
    identity_triplets(n, n, n, 1.0, &mut tq);
    tq.extend(
        w2.iter()
            .enumerate()
            .map(|(e, &w)| Triplet::new(2 * n + e, 2 * n + e, w)),
    );
    let tr = damping_triplets(sys, r, &dof, n);
    let names = free_names(sys, &dof);
    let states = names
        .iter()
        .map(|s| format!("r{s}"))
        .chain(names.iter().map(|s| format!("v{s}")))
        .chain((0..n_el).map(|e| format!("C[{e}]")))
        .collect();
    LinearPh {
        e: sparse(size, size, &te),
        j: sparse(size, size, &tj),
        r: sparse(size, size, &tr),
        q: sparse(size, size, &tq),
        b: input_matrix::<D>(ports, &dof, size, n),
        states,
    }
}

#[cfg(test)]
mod model_tests {
    use super::*;
    use crate::boundary::{Boundary, Fixed, NodalLoad};
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::statics::{StaticsParams, solve_system};
    use crate::system::{MassMatrix, Problem, State};
    use faer::Mat;

    fn dense(a: &SparseColMat<usize, f64>) -> Mat<f64> {
        a.as_ref().to_dense()
    }

    /// A 2D steel rope hanging from node 0 with a tip load port, at its equilibrium.
    fn hanging() -> (PhSystem<2, Material>, Vec<Vector<2>>) {
        let mesh = Mesh::uniform_chain(6, 30.0).unwrap();
        let initial = State::straight(&mesh, Vector::<2>::zeros(), Vector::<2>::new(0.0, -30.0));
        let p = Problem {
            mesh,
            initial,
            material: Material::hyperelastic(1e7),
            rho_a: 1.5,
            body_force: Vector::<2>::new(0.0, -9.81 * 1.5),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                fixed: vec![Fixed::node(0)],
                loads: vec![NodalLoad::new(6, |_| Vector::<2>::zeros())],
                motions: vec![],
                feedback: vec![],
            },
            point_masses: vec![],
        };
        let (sys, init) = PhSystem::new(p).unwrap();
        let eq = solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
        (sys, eq.state.r)
    }

    /// `J = −Jᵀ`, `R = 0`, `Eᵀ Q` symmetric and positive semidefinite, `B` picks the port, in
    /// both forms; and the full form's momentum row applied to a consistent strain
    /// `δC = 2 M_S⁻¹ Kᵀ δr` gives the reduced form's `−K_T δr`.
    #[test]
    fn full_and_reduced_forms_agree() {
        let (sys, r) = hanging();
        let ports = force_ports(&sys);
        assert_eq!(ports.len(), 2);
        let full = full_model(&sys, &r, &ports);
        let red = reduced_model(&sys, &r, &ports);
        for model in [&full, &red] {
            let (j, e, q) = (dense(&model.j), dense(&model.e), dense(&model.q));
            let n = j.nrows();
            assert_eq!(model.states.len(), n);
            let eq = e.transpose() * &q;
            let mut scale = 0.0f64;
            for a in 0..n {
                for b in 0..n {
                    scale = scale.max(eq[(a, b)].abs());
                }
            }
            for a in 0..n {
                for b in 0..n {
                    assert_eq!(j[(a, b)], -j[(b, a)]);
                    assert!((eq[(a, b)] - eq[(b, a)]).abs() <= 1e-12 * scale);
                }
            }
            let ev = eq.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
            assert!(ev.iter().all(|&x| x >= -1e-9 * scale), "{ev:?}");
            assert_eq!(model.r.compute_nnz(), 0);
        }
        let nf = 12; // 6 free nodes × 2
        let n_el = 6;
        let jq = dense(&full.j) * dense(&full.q);
        let kt = dense(&red.q);
        let mut x = Mat::<f64>::zeros(2 * nf + n_el, 1);
        for i in 0..nf {
            x[(i, 0)] = (i as f64 * 0.37).sin();
        }
        // δC_e = 2 r'_e·(δr_b − δr_a)/l_e.
        let dr = |node: usize, k: usize| {
            if node == 0 {
                0.0
            } else {
                x[((node - 1) * 2 + k, 0)]
            }
        };
        let mut dc = vec![0.0; n_el];
        for (e, dc) in dc.iter_mut().enumerate() {
            let l = sys.mesh.lengths()[e];
            let rp = (r[e + 1] - r[e]) / l;
            let d: f64 = (0..2).map(|k| rp[k] * (dr(e + 1, k) - dr(e, k))).sum();
            *dc = 2.0 * d / l;
        }
        for (e, dc) in dc.into_iter().enumerate() {
            x[(2 * nf + e, 0)] = dc;
        }
        let y = &jq * &x;
        for i in 0..nf {
            let want: f64 = -(0..nf).map(|c| kt[(i, c)] * x[(c, 0)]).sum::<f64>();
            assert!(
                (y[(nf + i, 0)] - want).abs() <= 1e-8 * kt[(i, i)].abs(),
                "{i}: {} vs {want}",
                y[(nf + i, 0)]
            );
        }
        // The port: the tip's x and y velocity.
        let b = dense(&red.b);
        assert_eq!(b[(nf + 10, 0)], 1.0);
        assert_eq!(b[(nf + 11, 1)], 1.0);
    }
}

/// Structure-preserving modal truncation: the reduced model projected onto the natural modes
/// `φ_1 … φ_k` ([`crate::modes::modes`], `M`-orthonormal), state `x = (η, ν)` (modal
/// coordinates [kg^½·m] and their rates), `E = I`, `J = [[0, I], [−I, 0]]`,
/// `R = diag(0, Φᵀ R_v Φ)` (the damping projected on the modes; dense, zero without damping),
/// `Q = diag(ω_1², …, ω_k², I)`, `B = [0; Φᵀ B_f]`, so `η̈_i + ω_i² η_i = φ_iᵀ B_f u` and
/// `y = B_fᵀ Φ η̇`. It is again port-Hamiltonian (`H = ½ Σ (ω_i² η_i² + ν_i²)`), and with every
/// mode kept it has the transfer function of the reduced model.
pub fn modal_model<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    modes: &[crate::modes::Mode<D>],
    ports: &[ForcePort],
) -> LinearPh {
    let k = modes.len();
    // Φᵀ R_v Φ, from the node blocks (the shapes are zero at fixed components).
    let mut tr = Vec::new();
    if sys.has_damping() || sys.water.is_some() {
        let rv = damping_blocks(sys, r);
        let rv_phi: Vec<Vec<Vector<D>>> = modes
            .iter()
            .map(|m| {
                let mut out = vec![Vector::<D>::zeros(); m.shape.len()];
                rv.mul(&sys.mesh, &m.shape, &mut out);
                out
            })
            .collect();
        // Upper triangle, mirrored: exactly symmetric.
        for (i, mi) in modes.iter().enumerate() {
            for (j, rj) in rv_phi.iter().enumerate().skip(i) {
                let v: f64 = mi.shape.iter().zip(rj).map(|(a, b)| a.dot(b)).sum();
                if v != 0.0 {
                    tr.push(Triplet::new(k + i, k + j, v));
                    if j != i {
                        tr.push(Triplet::new(k + j, k + i, v));
                    }
                }
            }
        }
    }
    let mut te = Vec::new();
    identity_triplets(2 * k, 0, 0, 1.0, &mut te);
    let mut tj = Vec::new();
    identity_triplets(k, 0, k, 1.0, &mut tj);
    identity_triplets(k, k, 0, -1.0, &mut tj);
    let mut tq: Vec<_> = modes
        .iter()
        .enumerate()
        .map(|(i, m)| Triplet::new(i, i, m.omega * m.omega))
        .collect();
    identity_triplets(k, k, k, 1.0, &mut tq);
    let mut tb = Vec::new();
    for (c, p) in ports.iter().enumerate() {
        if !sys.free[p.node][p.component] {
            continue;
        }
        for (i, m) in modes.iter().enumerate() {
            let v = m.shape[p.node][p.component];
            if v != 0.0 {
                tb.push(Triplet::new(k + i, c, v));
            }
        }
    }
    let states = (0..k)
        .map(|i| format!("eta[{i}]"))
        .chain((0..k).map(|i| format!("nu[{i}]")))
        .collect();
    LinearPh {
        e: sparse(2 * k, 2 * k, &te),
        j: sparse(2 * k, 2 * k, &tj),
        r: sparse(2 * k, 2 * k, &tr),
        q: sparse(2 * k, 2 * k, &tq),
        b: sparse(2 * k, ports.len(), &tb),
        states,
    }
}
