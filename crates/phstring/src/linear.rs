//! The linearized system about a rest state (docs/method.md §15–§16): tangent stiffness
//! `K_T = ∂(K(r) S(C(r)))/∂r` [N/m] and mass `M_ρ` [kg] on the free position components,
//! their positive-definiteness (stability of an equilibrium), and the sparse matrices of
//! the linear port-Hamiltonian model.

use faer::Side;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::SMatrix;

use crate::linsolve::BlockJacobian;
use crate::material::StoredEnergy;
use crate::mesh::Mesh;
use crate::statics::element_tangent;
use crate::system::{Law, PhSystem, Vector, element_mass};

/// The tangent stiffness `K_T(r)` [N/m] in node-block form, at positions `r` [m], over all
/// components (fixed ones included): each element adds its `(S I + 4 W'' r' r'ᵀ)/l` to its two
/// diagonal blocks and subtracts it from its two coupling blocks. Symmetric.
pub fn tangent_blocks<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
) -> BlockJacobian<D> {
    let mut j = BlockJacobian::zeros(&sys.mesh);
    for (g, e, [a, b], l) in sys.each_element() {
        let (_, _, t) = match &g.law {
            Law::String(m) => element_tangent(m, &r[a], &r[b], l),
            Law::Spring(s) => element_tangent(s, &r[a], &r[b], l),
        };
        j.diag[a] += t;
        j.diag[b] += t;
        j.off[e] = [-t, -t];
    }
    j
}

/// The mass matrix `M_ρ` [kg] in node-block form (consistent or lumped per group, point
/// masses on the diagonal).
pub fn mass_blocks<const D: usize, M: StoredEnergy>(sys: &PhSystem<D, M>) -> BlockJacobian<D> {
    let mut j = BlockJacobian::zeros(&sys.mesh);
    let eye = SMatrix::<f64, D, D>::identity();
    for (g, e, [a, b], l) in sys.each_element() {
        let (md, mo) = element_mass(g.mass, g.rho_a, l);
        j.diag[a] += eye * md;
        j.diag[b] += eye * md;
        j.off[e] = [eye * mo, eye * mo];
    }
    for &(i, m) in &sys.point_mass {
        j.diag[i] += eye * m;
    }
    j
}

/// Numbering of the free position components: `dof[i·D + k]` is the index of component `k`
/// of node `i` among the free ones, or `None` where it is fixed or prescribed.
pub fn free_dofs<const D: usize, M>(sys: &PhSystem<D, M>) -> (Vec<Option<usize>>, usize) {
    let mut next = 0;
    let map = sys
        .free
        .iter()
        .flat_map(|f| f.iter().copied())
        .map(|free| {
            free.then(|| {
                next += 1;
                next - 1
            })
        })
        .collect();
    (map, next)
}

/// The matrix of `blocks` restricted to the free components numbered by `dof`, as a sparse
/// column matrix with duplicates summed.
pub fn restrict<const D: usize>(
    mesh: &Mesh,
    blocks: &BlockJacobian<D>,
    dof: &[Option<usize>],
    n_free: usize,
) -> SparseColMat<usize, f64> {
    let mut t = Vec::with_capacity(blocks.diag.len() * D * D + blocks.off.len() * 2 * D * D);
    let mut push = |i: usize, j: usize, blk: &SMatrix<f64, D, D>| {
        for k in 0..D {
            for m in 0..D {
                if let (Some(r), Some(c)) = (dof[i * D + k], dof[j * D + m])
                    && blk[(k, m)] != 0.0
                {
                    t.push(Triplet::new(r, c, blk[(k, m)]));
                }
            }
        }
    };
    for (i, d) in blocks.diag.iter().enumerate() {
        push(i, i, d);
    }
    for (&[a, b], off) in mesh.elements().iter().zip(&blocks.off) {
        push(a, b, &off[0]);
        push(b, a, &off[1]);
    }
    SparseColMat::try_new_from_triplets(n_free, n_free, &t)
        .expect("indices below n_free by construction")
}

/// Whether the symmetric node-block matrix `blocks` is positive definite on the free
/// components of `sys` (Cholesky succeeds): for the tangent stiffness at an equilibrium,
/// whether the equilibrium is stable. A chain is checked by its block pivots in node order,
/// any other mesh by a sparse Cholesky factorization.
pub fn positive_definite<const D: usize, M>(
    sys: &PhSystem<D, M>,
    blocks: &BlockJacobian<D>,
) -> bool {
    let free = &sys.free;
    let mask = |blk: &SMatrix<f64, D, D>, fi: &[bool; D], fj: &[bool; D], diag: bool| {
        let mut b = *blk;
        for k in 0..D {
            for m in 0..D {
                if !fi[k] || !fj[m] {
                    b[(k, m)] = if diag && k == m { 1.0 } else { 0.0 };
                }
            }
        }
        b
    };
    if sys.mesh.is_chain() {
        // Block LDLᵀ: P₀ = D₀, P_i = D_i − L_i P_{i−1}⁻¹ L_iᵀ; K is positive definite iff every
        // pivot is.
        let mut prev: Option<SMatrix<f64, D, D>> = None;
        for i in 0..sys.mesh.n_nodes() {
            let mut p = mask(&blocks.diag[i], &free[i], &free[i], true);
            if let (Some(inv), true) = (prev, i > 0) {
                let low = mask(&blocks.off[i - 1][1], &free[i], &free[i - 1], false);
                p -= low * inv * low.transpose();
            }
            let p = (p + p.transpose()) * 0.5;
            let Some(ch) = p.cholesky() else {
                return false;
            };
            prev = Some(ch.inverse());
        }
        true
    } else {
        let (dof, n) = free_dofs(sys);
        if n == 0 {
            return true;
        }
        let k = restrict(&sys.mesh, blocks, &dof, n);
        k.sp_cholesky(Side::Lower).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{Boundary, Fixed};
    use crate::material::Material;
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
