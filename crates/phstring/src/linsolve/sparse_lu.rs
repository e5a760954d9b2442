//! General sparse LU (faer) for any mesh; symbolic analysis once, numeric refactor per call.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use nalgebra::SVector;

use super::{Block, BlockJacobian, LinearSolver};
use crate::error::LinearSolveError;
use crate::mesh::Mesh;

/// Sparse LU solver (faer) for the Newton matrix of any mesh.
pub struct SparseLu<const D: usize> {
    mat: SparseColMat<usize, f64>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    rhs: Vec<f64>,
    /// CSC value slots of the blocks, as [`block_pattern`] numbers them (diagonal blocks, then
    /// the element blocks `[a→b, b→a]`).
    slots: Vec<usize>,
}

impl<const D: usize> std::fmt::Debug for SparseLu<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("n", &self.rhs.len())
            .finish_non_exhaustive()
    }
}

impl<const D: usize> SparseLu<D> {
    /// Analyses the sparsity pattern of `mesh`'s Newton matrix.
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.n_nodes() * D;
        let (col_ptr, row_idx, slots) = block_pattern::<D>(mesh.n_nodes(), mesh.elements());
        let nnz = row_idx.len();
        let symbolic_mat = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_lu(symbolic_mat.as_ref(), Default::default())
            .expect("symbolic LU of a valid square pattern");
        let factor_buf = MemBuffer::new(
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
        );
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Self {
            mat: SparseColMat::new(symbolic_mat, vec![0.0; nnz]),
            symbolic,
            numeric: NumericLu::new(),
            factor_buf,
            solve_buf,
            rhs: vec![0.0; n],
            slots,
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
pub(crate) fn add_block<const D: usize>(
    vals: &mut [f64],
    slots: &[usize],
    base: usize,
    blk: &Block<D>,
) {
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
        let vals = self.mat.val_mut();
        vals.fill(0.0);
        let dd = D * D;
        for (i, blk) in jac.diag.iter().enumerate() {
            add_block(vals, &self.slots, i * dd, blk);
        }
        let n_nodes = jac.diag.len();
        for (e, blks) in jac.off.iter().enumerate() {
            for (s, blk) in blks.iter().enumerate() {
                add_block(vals, &self.slots, (n_nodes + 2 * e + s) * dd, blk);
            }
        }
        for (i, x) in rhs.iter().enumerate() {
            self.rhs[i * D..(i + 1) * D].copy_from_slice(x.as_slice());
        }
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
        for (i, x) in rhs.iter_mut().enumerate() {
            x.copy_from_slice(&self.rhs[i * D..(i + 1) * D]);
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
