//! General sparse LU (faer) for any mesh; symbolic analysis once, numeric refactor per call.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use nalgebra::SVector;

use super::{Block, BlockJacobian, LinearSolver};
use crate::error::LinearSolveError;
use crate::mesh::Mesh;

/// A matrix of `D×D` blocks on a fixed pattern as a scalar CSC matrix, with faer's symbolic
/// sparse LU done once and a numeric factorization and solve per call: the block slots, the
/// values, the right-hand side and the work buffers.
pub(crate) struct FaerBlockLu {
    mat: SparseColMat<usize, f64>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    /// The right-hand side, overwritten by the solution.
    pub(crate) rhs: Vec<f64>,
    /// CSC value slots of the blocks, as [`block_pattern`] numbers them (diagonal blocks, then
    /// the pair blocks `[a→b, b→a]`).
    slots: Vec<usize>,
}

impl FaerBlockLu {
    /// Analyses the pattern of `n` diagonal blocks and both coupling blocks of every pair in
    /// `pairs` with faer's symbolic LU under `params`. With `warm_up`, a numeric
    /// factorization of diagonally dominant values on the pattern sizes faer's numeric
    /// storage here rather than in the first solve.
    pub(crate) fn new<const D: usize>(
        n: usize,
        pairs: &[[usize; 2]],
        params: LuSymbolicParams<'_>,
        warm_up: bool,
    ) -> Self {
        let (col_ptr, row_idx, slots) = block_pattern::<D>(n, pairs);
        let mut values = vec![0.0; row_idx.len()];
        if warm_up {
            values.fill(1.0);
            for r in 0..n {
                for k in 0..D {
                    let j = r * D + k;
                    values[slots[r * D * D + k * D + k]] =
                        (col_ptr[j + 1] - col_ptr[j]) as f64 + 1.0;
                }
            }
        }
        let m = n * D;
        let symbolic_mat = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_lu(symbolic_mat.as_ref(), params)
            .expect("symbolic LU of a valid square pattern");
        let mut factor_buf = MemBuffer::new(
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
        );
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let mat = SparseColMat::new(symbolic_mat, values);
        let mut numeric = NumericLu::new();
        if warm_up {
            // A failure here only means that the first solve sizes the storage instead.
            let _ = symbolic.factorize_numeric_lu(
                &mut numeric,
                mat.as_ref(),
                Par::Seq,
                MemStack::new(&mut factor_buf),
                Default::default(),
            );
        }
        Self {
            mat,
            symbolic,
            numeric,
            factor_buf,
            solve_buf,
            rhs: vec![0.0; m],
            slots,
        }
    }

    /// Sets every value to zero.
    pub(crate) fn clear(&mut self) {
        self.mat.val_mut().fill(0.0);
    }

    /// Adds `blk` to the block whose slots start at `base` (block `i`'s at `i·D²`, pair `p`'s
    /// blocks at `(n + 2p + s)·D²`).
    #[inline]
    pub(crate) fn add<const D: usize>(&mut self, base: usize, blk: &Block<D>) {
        add_block(self.mat.val_mut(), &self.slots, base, blk);
    }

    /// Factors the matrix and overwrites `rhs` with the solution.
    pub(crate) fn factor_and_solve(&mut self) -> Result<(), LinearSolveError> {
        let lu = self
            .symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                self.mat.as_ref(),
                Par::Seq,
                MemStack::new(&mut self.factor_buf),
                Default::default(),
            )
            .map_err(|e| LinearSolveError::Sparse(format!("{e:?}")))?;
        let n = self.rhs.len();
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
        Ok(())
    }
}

/// Sparse LU solver (faer) for the Newton matrix of any mesh.
pub struct SparseLu<const D: usize> {
    lu: FaerBlockLu,
}

impl<const D: usize> std::fmt::Debug for SparseLu<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("n", &self.lu.rhs.len())
            .finish_non_exhaustive()
    }
}

impl<const D: usize> SparseLu<D> {
    /// Analyses the sparsity pattern of `mesh`'s Newton matrix (faer chooses between its
    /// simplicial and supernodal LU).
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_symbolic_params(mesh, Default::default())
    }

    /// Like [`Self::new`], with faer's symbolic LU parameters `params` (e.g. to force the
    /// supernodal or the simplicial factorization, for comparisons).
    pub fn with_symbolic_params(mesh: &Mesh, params: LuSymbolicParams<'_>) -> Self {
        Self {
            lu: FaerBlockLu::new::<D>(mesh.n_nodes(), mesh.elements(), params, false),
        }
    }
}

/// The scalar CSC pattern (column pointers, row indices) of a matrix of `n × n` blocks of size
/// `D×D` with every diagonal block and both coupling blocks `a→b`, `b→a` of every pair
/// `[a, b]`, and the CSC value slot of every block entry: diagonal block `i`'s entry `(k, l)`
/// at `i·D² + k·D + l`, then pair `p`'s blocks `a→b` (`s = 0`) and `b→a` (`s = 1`) at
/// `(n + 2p + s)·D² + k·D + l`.
pub(crate) fn block_pattern<const D: usize>(
    n: usize,
    pairs: &[[usize; 2]],
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let blocks = || {
        (0..n)
            .map(|i| (i, i))
            .chain(pairs.iter().flat_map(|&[a, b]| [(a, b), (b, a)]))
    };
    let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n * D];
    for (i, j) in blocks() {
        for k in 0..D {
            for l in 0..D {
                cols[j * D + l].push(i * D + k);
            }
        }
    }
    let mut col_ptr = Vec::with_capacity(n * D + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for c in &mut cols {
        c.sort_unstable();
        c.dedup();
        row_idx.extend_from_slice(c);
        col_ptr.push(row_idx.len());
    }
    let slot = |i: usize, j: usize| -> usize {
        let (s, e) = (col_ptr[j], col_ptr[j + 1]);
        s + row_idx[s..e]
            .binary_search(&i)
            .expect("entry is in the pattern")
    };
    let mut slots = Vec::with_capacity((n + 2 * pairs.len()) * D * D);
    for (i, j) in blocks() {
        for k in 0..D {
            for l in 0..D {
                slots.push(slot(i * D + k, j * D + l));
            }
        }
    }
    (col_ptr, row_idx, slots)
}

/// Adds `blk` to the CSC values `vals` at its slots `slots[base..base + D²]` (row-major).
#[inline]
fn add_block<const D: usize>(vals: &mut [f64], slots: &[usize], base: usize, blk: &Block<D>) {
    for k in 0..D {
        for l in 0..D {
            vals[slots[base + k * D + l]] += blk[(k, l)];
        }
    }
}

impl<const D: usize> LinearSolver<D> for SparseLu<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        self.lu.clear();
        let dd = D * D;
        for (i, blk) in jac.diag.iter().enumerate() {
            self.lu.add(i * dd, blk);
        }
        let n_nodes = jac.diag.len();
        for (e, blks) in jac.off.iter().enumerate() {
            for (s, blk) in blks.iter().enumerate() {
                self.lu.add((n_nodes + 2 * e + s) * dd, blk);
            }
        }
        for (i, x) in rhs.iter().enumerate() {
            self.lu.rhs[i * D..(i + 1) * D].copy_from_slice(x.as_slice());
        }
        self.lu.factor_and_solve()?;
        for (i, x) in rhs.iter_mut().enumerate() {
            x.copy_from_slice(&self.lu.rhs[i * D..(i + 1) * D]);
            if !x.iter().all(|v| v.is_finite()) {
                return Err(LinearSolveError::Singular { block: i });
            }
        }
        Ok(())
    }
    fn name(&self) -> &'static str {
        "sparse_lu"
    }
}
