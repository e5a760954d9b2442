//! A bordered solve: the node blocks by any [`LinearSolver`], the few slot unknowns beyond
//! them (rigid bodies) by their Schur complement (docs/method.md §22).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Mat, Par};
use nalgebra::SVector;

use super::{BlockJacobian, LinearSolver};
use crate::error::LinearSolveError;

/// Solves `[A B; C E] [x; u] = [f; g]` with `A` the node blocks of a [`BlockJacobian`]
/// (solved by the inner solver) and `B`, `C`, `E` its [`super::Border`]: `x = A⁻¹f − A⁻¹B u`,
/// `(E − C A⁻¹B) u = g − C A⁻¹f`. Each slot component with couplings costs one more solve
/// with `A`'s factors (kept from the first solve where the inner solver can keep them). The
/// Schur complement's dense LU (faer, partial pivoting) works in buffers sized once, so that a
/// solve does not allocate.
pub struct Bordered<const D: usize> {
    inner: Box<dyn LinearSolver<D>>,
    n: usize,
    slots: usize,
    /// `A⁻¹ B`, one node vector per slot component.
    y: Vec<Vec<SVector<f64, D>>>,
    /// Which columns of `B` have entries.
    used: Vec<bool>,
    /// The Schur complement `S` (overwritten by its LU factors) and the right-hand side `g`
    /// (overwritten by `u`).
    s: Mat<f64>,
    g: Mat<f64>,
    /// The LU's row permutation and its inverse, and the factorization's and solve's scratch.
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    scratch: MemBuffer,
}

impl<const D: usize> std::fmt::Debug for Bordered<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bordered")
            .field("inner", &self.inner.name())
            .field("n", &self.n)
            .field("slots", &self.slots)
            .finish()
    }
}

impl<const D: usize> Bordered<D> {
    /// The solver for `n` nodes (solved by `inner`) and `slots` slots after them.
    pub fn new(mut inner: Box<dyn LinearSolver<D>>, n: usize, slots: usize) -> Self {
        inner.keep_factors();
        let m = slots * D;
        let scratch = MemBuffer::new(
            factor::lu_in_place_scratch::<usize, f64>(m, m, Par::Seq, Default::default())
                .or(solve::solve_in_place_scratch::<usize, f64>(m, 1, Par::Seq)),
        );
        Self {
            inner,
            n,
            slots,
            y: vec![vec![SVector::zeros(); n]; m],
            used: vec![false; m],
            s: Mat::zeros(m, m),
            g: Mat::zeros(m, 1),
            perm: vec![0; m],
            perm_inv: vec![0; m],
            scratch,
        }
    }
}

impl<const D: usize> LinearSolver<D> for Bordered<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let n = self.n;
        let border = &jac.border;
        let (nodes, tail) = rhs.split_at_mut(n);
        self.inner.solve(jac, nodes)?;
        // Y = A⁻¹ B, column by column.
        for (c, (y, used)) in self.y.iter_mut().zip(&mut self.used).enumerate() {
            let (slot, comp) = (c / D, c % D);
            y.iter_mut().for_each(|v| v.fill(0.0));
            *used = false;
            for &(node, s, _, col) in &border.links {
                if s == slot {
                    y[node] += col.column(comp);
                    *used = true;
                }
            }
            if *used {
                self.inner.solve_again(jac, y)?;
            }
        }
        // S = E − C Y, g = rhs_u − C z.
        let (s, g) = (&mut self.s, &mut self.g);
        for a in 0..self.slots {
            for b in 0..self.slots {
                let blk = &border.own[a * self.slots + b];
                for i in 0..D {
                    for j in 0..D {
                        s[(a * D + i, b * D + j)] = blk[(i, j)];
                    }
                }
            }
            for k in 0..D {
                g[(a * D + k, 0)] = tail[a][k];
            }
        }
        for &(node, slot, row, _) in &border.links {
            let cz = row * nodes[node];
            for k in 0..D {
                g[(slot * D + k, 0)] -= cz[k];
            }
            for (c, y) in self.y.iter().enumerate() {
                if self.used[c] {
                    let cy = row * y[node];
                    for k in 0..D {
                        s[(slot * D + k, c)] -= cy[k];
                    }
                }
            }
        }
        let stack = MemStack::new(&mut self.scratch);
        let (_, perm) = factor::lu_in_place(
            s.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            stack,
            Default::default(),
        );
        solve::solve_in_place(s.as_ref(), s.as_ref(), perm, g.as_mut(), Par::Seq, stack);
        let u = g.col(0);
        if !u.iter().all(|x| x.is_finite()) {
            return Err(LinearSolveError::Singular { block: n });
        }
        for (a, t) in tail.iter_mut().enumerate() {
            for k in 0..D {
                t[k] = u[a * D + k];
            }
        }
        for (c, y) in self.y.iter().enumerate() {
            if self.used[c] && u[c] != 0.0 {
                for (x, yi) in nodes.iter_mut().zip(y) {
                    *x -= yi * u[c];
                }
            }
        }
        Ok(())
    }
    fn name(&self) -> &'static str {
        self.inner.name()
    }
}
