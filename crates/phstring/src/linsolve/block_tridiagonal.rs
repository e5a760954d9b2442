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
}

impl<const D: usize> BlockTridiagonal<D> {
    /// A solver for the chain `mesh`; fails if the mesh is not a chain.
    pub fn new(mesh: &Mesh) -> Result<Self, SetupError> {
        if !mesh.is_chain() {
            return Err(SetupError::NotAChain);
        }
        let n = mesh.n_nodes();
        Ok(Self {
            c: vec![Block::zeros(); n.saturating_sub(1)],
        })
    }
}

/// Solves the block-tridiagonal system with diagonal blocks `diag[i]` and couplings
/// `off[i] = [∂R_i/∂x_{i+1}, ∂R_{i+1}/∂x_i]`, overwriting `rhs`; `c` is workspace of at least
/// `diag.len() − 1` blocks.
pub(crate) fn block_thomas<const D: usize>(
    diag: &[Block<D>],
    off: &[[Block<D>; 2]],
    c: &mut [Block<D>],
    rhs: &mut [SVector<f64, D>],
) -> Result<(), LinearSolveError> {
    let n = rhs.len();
    // Factor and forward sweep in one pass: D'_0 = D_0, D'_{i+1} = D_{i+1} − L_i C_i,
    // C_i = D'_i⁻¹ U_i, y_i = D'_i⁻¹ (b_i − L_{i−1} y_{i−1}) (stored in rhs).
    for i in 0..n {
        let mut d = diag[i];
        let mut b = rhs[i];
        if i > 0 {
            let l = &off[i - 1][1];
            d -= l * c[i - 1];
            b -= l * rhs[i - 1];
        }
        let inv = d
            .try_inverse()
            .ok_or(LinearSolveError::Singular { block: i })?;
        rhs[i] = inv * b;
        if i + 1 < n {
            c[i] = inv * off[i][0];
        }
    }
    // Back substitution: x_i = y_i − C_i x_{i+1}.
    let mut finite = true;
    for i in (0..n.saturating_sub(1)).rev() {
        let x_next = rhs[i + 1];
        rhs[i] -= c[i] * x_next;
        finite &= rhs[i].iter().all(|v| v.is_finite());
    }
    if !finite || n > 0 && !rhs[n - 1].iter().all(|v| v.is_finite()) {
        let i = rhs
            .iter()
            .position(|x| !x.iter().all(|v| v.is_finite()))
            .unwrap_or(0);
        return Err(LinearSolveError::Singular { block: i });
    }
    Ok(())
}

impl<const D: usize> LinearSolver<D> for BlockTridiagonal<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        block_thomas(&jac.diag, &jac.off, &mut self.c, rhs)
    }
    fn name(&self) -> &'static str {
        "block_tridiagonal"
    }
}
