//! Block Thomas algorithm for chain meshes: O(N) factor and solve, no allocation.

use nalgebra::SVector;

use super::{Block, BlockJacobian, LinearSolver};
use crate::error::{LinearSolveError, SetupError};
use crate::mesh::Mesh;

/// Block-tridiagonal solver (block Thomas algorithm) for chain meshes.
///
/// Inverts each `D×D` Schur-complement block in closed form (no pivoting between blocks),
/// which is safe for the mass-dominated Newton matrices of the time stepper;
/// [`super::SparseLu`] is the fallback and the test oracle.
#[derive(Debug, Clone)]
pub struct BlockTridiagonal<const D: usize> {
    /// `C_i = D'_i⁻¹ U_i`.
    c: Vec<Block<D>>,
    /// With [`LinearSolver::keep_factors`]: the pivots' inverses `D'_i⁻¹` (empty otherwise).
    inv: Vec<Block<D>>,
}

impl<const D: usize> BlockTridiagonal<D> {
    /// A solver for the chain `mesh`; fails if the mesh is not a chain.
    pub fn new(mesh: &Mesh) -> Result<Self, SetupError> {
        if !mesh.is_chain() {
            return Err(SetupError::NotAChain);
        }
        let n = mesh.n_nodes();
        Ok(Self {
            c: vec![Block::zeros(); n],
            inv: Vec::new(),
        })
    }
}

/// Solves the block-tridiagonal system with diagonal blocks `diag[i]` and couplings
/// `off[i] = [∂R_i/∂x_{i+1}, ∂R_{i+1}/∂x_i]`, overwriting `rhs`; `c` is workspace of at least
/// `diag.len()` blocks, and `keep`, when given (as long), receives the pivots' inverses for
/// a later solve with the same factors.
///
/// Twisted ("burn at both ends") block Thomas: the chain is eliminated from both ends towards
/// the middle node at once, which halves the length of the dependent chain of small
/// inversions; each Schur-complement block is inverted in closed form.
pub(crate) fn block_thomas<const D: usize>(
    diag: &[Block<D>],
    off: &[[Block<D>; 2]],
    c: &mut [Block<D>],
    rhs: &mut [SVector<f64, D>],
    mut keep: Option<&mut [Block<D>]>,
) -> Result<(), LinearSolveError> {
    let n = rhs.len();
    if n == 0 {
        return Ok(());
    }
    let singular = |i| LinearSolveError::Singular { block: i };
    // With U_i = off[i][0] (row i, column i+1) and L_i = off[i−1][1] (row i, column i−1):
    // top-down for i < m:   D'_i = D_i − L_i C_{i−1}, C_i = D'_i⁻¹ U_i,
    //                       y_i = D'_i⁻¹ (b_i − L_i y_{i−1});
    // bottom-up for i > m:  E'_i = D_i − U_i G_{i+1}, G_i = E'_i⁻¹ L_i,
    //                       z_i = E'_i⁻¹ (b_i − U_i z_{i+1});
    // C_i and G_i share `c`, y_i and z_i share `rhs`.
    let m = n / 2;
    for k in 0..m {
        // Top node i = k and bottom node j = n − 1 − k (> m ≥ k), independent of each other.
        let (i, j) = (k, n - 1 - k);
        let mut d = diag[i];
        let mut b = rhs[i];
        if i > 0 {
            let l = &off[i - 1][1];
            d -= l * c[i - 1];
            b -= l * rhs[i - 1];
        }
        let inv_d = d.try_inverse().ok_or(singular(i))?;
        if let Some(k) = keep.as_deref_mut() {
            k[i] = inv_d;
        }
        rhs[i] = inv_d * b;
        c[i] = inv_d * off[i][0];
        // For even n the bottom sweep has one node fewer than the top one.
        if j > m {
            let mut e = diag[j];
            let mut f = rhs[j];
            if j + 1 < n {
                let u = &off[j][0];
                e -= u * c[j + 1];
                f -= u * rhs[j + 1];
            }
            let inv_e = e.try_inverse().ok_or(singular(j))?;
            if let Some(k) = keep.as_deref_mut() {
                k[j] = inv_e;
            }
            rhs[j] = inv_e * f;
            c[j] = inv_e * off[j - 1][1];
        }
    }
    // Middle node: D_m − L_m C_{m−1} − U_m G_{m+1}.
    let mut d = diag[m];
    let mut b = rhs[m];
    if m > 0 {
        let l = &off[m - 1][1];
        d -= l * c[m - 1];
        b -= l * rhs[m - 1];
    }
    if m + 1 < n {
        let u = &off[m][0];
        d -= u * c[m + 1];
        b -= u * rhs[m + 1];
    }
    let inv_m = d.try_inverse().ok_or(singular(m))?;
    if let Some(k) = keep {
        k[m] = inv_m;
    }
    rhs[m] = inv_m * b;
    // Back substitution outwards: x_i = y_i − C_i x_{i+1}, x_j = z_j − G_j x_{j−1}.
    let mut finite = rhs[m].iter().all(|v| v.is_finite());
    for k in (0..m).rev() {
        let x_next = rhs[k + 1];
        rhs[k] -= c[k] * x_next;
        finite &= rhs[k].iter().all(|v| v.is_finite());
        let j = n - 1 - k;
        if j > m {
            let x_prev = rhs[j - 1];
            rhs[j] -= c[j] * x_prev;
            finite &= rhs[j].iter().all(|v| v.is_finite());
        }
    }
    if !finite {
        let i = rhs
            .iter()
            .position(|x| !x.iter().all(|v| v.is_finite()))
            .unwrap_or(0);
        return Err(singular(i));
    }
    Ok(())
}

impl<const D: usize> LinearSolver<D> for BlockTridiagonal<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let keep = (self.inv.len() == rhs.len()).then_some(&mut self.inv[..]);
        block_thomas(&jac.diag, &jac.off, &mut self.c, rhs, keep)
    }
    fn name(&self) -> &'static str {
        "block_tridiagonal"
    }
    fn keep_factors(&mut self) {
        self.inv = vec![Block::zeros(); self.c.len()];
    }
    fn solve_again(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        if self.inv.len() != rhs.len() {
            return self.solve(jac, rhs);
        }
        let (off, c, inv) = (&jac.off, &self.c, &self.inv);
        let n = rhs.len();
        if n == 0 {
            return Ok(());
        }
        let m = n / 2;
        for k in 0..m {
            let (i, j) = (k, n - 1 - k);
            let mut b = rhs[i];
            if i > 0 {
                b -= off[i - 1][1] * rhs[i - 1];
            }
            rhs[i] = inv[i] * b;
            if j > m {
                let mut f = rhs[j];
                if j + 1 < n {
                    f -= off[j][0] * rhs[j + 1];
                }
                rhs[j] = inv[j] * f;
            }
        }
        let mut b = rhs[m];
        if m > 0 {
            b -= off[m - 1][1] * rhs[m - 1];
        }
        if m + 1 < n {
            b -= off[m][0] * rhs[m + 1];
        }
        rhs[m] = inv[m] * b;
        for k in (0..m).rev() {
            let x_next = rhs[k + 1];
            rhs[k] -= c[k] * x_next;
            let j = n - 1 - k;
            if j > m {
                let x_prev = rhs[j - 1];
                rhs[j] -= c[j] * x_prev;
            }
        }
        match rhs.iter().position(|x| !x.iter().all(|v| v.is_finite())) {
            Some(i) => Err(LinearSolveError::Singular { block: i }),
            None => Ok(()),
        }
    }
}
