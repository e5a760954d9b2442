//! Node-block assembly shared by the time step and the analyses (docs/method.md §8, §15–§17):
//! the tangent stiffness `K_T(r)` [N/m] and the mass `M_ρ` [kg] in node-block form, the
//! numbering of the free position components, restriction to them, masking of the fixed
//! ones, and positive definiteness on the free components.

use faer::Side;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::SMatrix;

use crate::linsolve::BlockJacobian;
use crate::material::StoredEnergy;
use crate::mesh::Mesh;
use crate::system::{Law, PhSystem, Vector, element_mass};

/// The tangent stiffness `K_T(r)` [N/m] in node-block form, at positions `r` [m], over all
/// components (fixed ones included): each element adds its `(S I + 4 W'' r' r'ᵀ)/l` to its two
/// diagonal blocks and subtracts it from its two coupling blocks; in water, the stiffness of
/// buoyancy and seabed contact on the diagonal blocks. Symmetric.
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
    if let Some(w) = sys.water.as_deref() {
        // The stiffness of buoyancy and seabed contact (docs/method.md §21).
        w.add_potential_stiffness(r, &mut j.diag);
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

/// Zeroes the rows and columns of fixed components and puts 1 on their diagonal.
pub fn mask_fixed<const D: usize, M>(sys: &PhSystem<D, M>, j: &mut BlockJacobian<D>) {
    let mask = |blk: &mut SMatrix<f64, D, D>, row: &[bool; D], col: &[bool; D]| {
        for k in 0..D {
            for m in 0..D {
                if !row[k] || !col[m] {
                    blk[(k, m)] = 0.0;
                }
            }
        }
    };
    for &i in &sys.constrained {
        let fi = &sys.free[i];
        mask(&mut j.diag[i], fi, fi);
        for k in 0..D {
            if !fi[k] {
                j.diag[i][(k, k)] = 1.0;
            }
        }
    }
    for &e in &sys.constrained_elements {
        let [a, b] = sys.mesh.elements()[e];
        let (fa, fb) = (&sys.free[a], &sys.free[b]);
        mask(&mut j.off[e][0], fa, fb);
        mask(&mut j.off[e][1], fb, fa);
    }
}

/// The tangent stiffness of one element, `∂(S r')/∂r_b = (S I + 4 W'' r' r'ᵀ)/l` [N/m], and
/// its internal force `S r'` [N], at the positions `ra`, `rb`.
#[inline]
pub fn element_tangent<const D: usize, L: StoredEnergy>(
    law: &L,
    ra: &Vector<D>,
    rb: &Vector<D>,
    l: f64,
) -> (f64, Vector<D>, SMatrix<f64, D, D>) {
    let rp = (rb - ra) / l;
    let c = rp.norm_squared();
    let s = 2.0 * law.dw(c);
    let g = (SMatrix::<f64, D, D>::identity() * s + rp * rp.transpose() * (4.0 * law.d2w(c))) / l;
    (c, rp * s, g)
}
