//! General sparse LU (faer) for any mesh; symbolic analysis once, numeric refactor per call.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use nalgebra::SVector;

use super::{BlockJacobian, LinearSolver};
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
    /// CSC value slot of entry `(k, l)` of node `i`'s diagonal block: `diag_slots[i·D² + k·D + l]`.
    diag_slots: Vec<usize>,
    /// Slots of the element blocks `[a→b, b→a]`: `off_slots[(e·2 + s)·D² + k·D + l]`.
    off_slots: Vec<usize>,
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
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut add_block = |i: usize, j: usize| {
            for k in 0..D {
                for l in 0..D {
                    cols[j * D + l].push(i * D + k);
                }
            }
        };
        for i in 0..mesh.n_nodes() {
            add_block(i, i);
        }
        for &[a, b] in mesh.elements() {
            add_block(a, b);
            add_block(b, a);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for c in &mut cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let slot = |i: usize, j: usize| -> usize {
            let (s, e) = (col_ptr[j], col_ptr[j + 1]);
            s + row_idx[s..e]
                .binary_search(&i)
                .expect("entry is in the pattern")
        };
        let block_slots = |i: usize, j: usize, out: &mut Vec<usize>| {
            for k in 0..D {
                for l in 0..D {
                    out.push(slot(i * D + k, j * D + l));
                }
            }
        };
        let mut diag_slots = Vec::with_capacity(mesh.n_nodes() * D * D);
        for i in 0..mesh.n_nodes() {
            block_slots(i, i, &mut diag_slots);
        }
        let mut off_slots = Vec::with_capacity(mesh.n_elements() * 2 * D * D);
        for &[a, b] in mesh.elements() {
            block_slots(a, b, &mut off_slots);
            block_slots(b, a, &mut off_slots);
        }
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
            diag_slots,
            off_slots,
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
            for k in 0..D {
                for l in 0..D {
                    vals[self.diag_slots[i * dd + k * D + l]] += blk[(k, l)];
                }
            }
        }
        for (e, blks) in jac.off.iter().enumerate() {
            for (s, blk) in blks.iter().enumerate() {
                let base = (e * 2 + s) * dd;
                for k in 0..D {
                    for l in 0..D {
                        vals[self.off_slots[base + k * D + l]] += blk[(k, l)];
                    }
                }
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
