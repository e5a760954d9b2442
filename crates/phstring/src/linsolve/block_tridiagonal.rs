//! Block Thomas algorithm for chain meshes: O(N) factor and solve, no allocation.

use nalgebra::SVector;

use super::{Block, BlockJacobian, LinearSolver};
use crate::error::{LinearSolveError, SetupError};
use crate::mesh::Mesh;

/// Block-tridiagonal solver (block Thomas algorithm) for chain meshes.
///
/// Pivots within each `D×D` block (partial pivoting) but not between blocks, which is safe
/// for the mass-dominated Newton matrices of the time stepper; [`super::SparseLu`] is the
/// fallback and the test oracle.
#[derive(Debug, Clone)]
pub struct BlockTridiagonal<const D: usize> {
    /// LU factors of the Schur-complement diagonal blocks `D'_i`.
    lu: Vec<Block<D>>,
    piv: Vec<[usize; D]>,
    /// `C_i = D'_i⁻¹ U_i`.
    c: Vec<Block<D>>,
}

impl<const D: usize> BlockTridiagonal<D> {
    /// A solver for the chain `mesh`; fails if the mesh is not a chain.
    pub fn new(mesh: &Mesh) -> Result<Self, SetupError> {
        if !mesh.is_chain() {
            return Err(SetupError::NotAChain);
        }
        let n = mesh.n_nodes();
        Ok(Self {
            lu: vec![Block::zeros(); n],
            piv: vec![[0; D]; n],
            c: vec![Block::zeros(); n.saturating_sub(1)],
        })
    }
}

/// In-place LU with partial pivoting of a small block; `false` if singular.
#[inline]
fn lu_in_place<const D: usize>(a: &mut Block<D>, piv: &mut [usize; D]) -> bool {
    for k in 0..D {
        let mut p = k;
        let mut best = a[(k, k)].abs();
        for i in k + 1..D {
            if a[(i, k)].abs() > best {
                best = a[(i, k)].abs();
                p = i;
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return false;
        }
        if p != k {
            a.swap_rows(k, p);
        }
        let inv = 1.0 / a[(k, k)];
        for i in k + 1..D {
            let f = a[(i, k)] * inv;
            a[(i, k)] = f;
            for j in k + 1..D {
                a[(i, j)] -= f * a[(k, j)];
            }
        }
    }
    true
}

/// Solves with the factors of [`lu_in_place`].
#[inline]
fn lu_solve<const D: usize>(lu: &Block<D>, piv: &[usize; D], b: &mut SVector<f64, D>) {
    for k in 0..D {
        b.swap_rows(k, piv[k]);
    }
    for i in 0..D {
        for j in 0..i {
            b[i] -= lu[(i, j)] * b[j];
        }
    }
    for i in (0..D).rev() {
        for j in i + 1..D {
            b[i] -= lu[(i, j)] * b[j];
        }
        b[i] /= lu[(i, i)];
    }
}

impl<const D: usize> LinearSolver<D> for BlockTridiagonal<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let n = self.lu.len();
        // Factor: D'_0 = D_0, C_i = D'_i⁻¹ U_i, D'_{i+1} = D_{i+1} − L_i C_i.
        // Forward: y_i = D'_i⁻¹ (b_i − L_{i−1} y_{i−1}), stored in rhs.
        for i in 0..n {
            let mut d = jac.diag[i];
            if i > 0 {
                let l = &jac.off[i - 1][1];
                d -= l * self.c[i - 1];
                let y_prev = rhs[i - 1];
                rhs[i] -= l * y_prev;
            }
            if !lu_in_place(&mut d, &mut self.piv[i]) {
                return Err(LinearSolveError::Singular { block: i });
            }
            self.lu[i] = d;
            lu_solve(&d, &self.piv[i], &mut rhs[i]);
            if i + 1 < n {
                let mut c = jac.off[i][0];
                for j in 0..D {
                    let mut col = c.column(j).into_owned();
                    lu_solve(&d, &self.piv[i], &mut col);
                    c.set_column(j, &col);
                }
                self.c[i] = c;
            }
        }
        // Back substitution: x_i = y_i − C_i x_{i+1}.
        for i in (0..n.saturating_sub(1)).rev() {
            let x_next = rhs[i + 1];
            rhs[i] -= self.c[i] * x_next;
        }
        if let Some(i) = rhs.iter().position(|x| !x.iter().all(|v| v.is_finite())) {
            return Err(LinearSolveError::Singular { block: i });
        }
        Ok(())
    }
    fn name(&self) -> &'static str {
        "block_tridiagonal"
    }
}
