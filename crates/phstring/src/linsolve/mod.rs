//! Linear solves of the Newton system `J δ = −R` (docs/method.md §8, eqs. (8.4)–(8.6)).
//!
//! The Newton matrix is stored as node blocks ([`BlockJacobian`]): one `D×D` diagonal block
//! per node and two off-diagonal blocks per element. Two solvers implement
//! [`LinearSolver`]: [`BlockTridiagonal`] (block Thomas, O(N), chain meshes only),
//! [`SparseLu`] (faer's sparse LU, any mesh) and [`NetworkSolver`] (block Thomas along the
//! strings between junction nodes, sparse LU on the junctions; any mesh). All analyse the
//! mesh once at construction and refactor new values at every call without allocating.
//!
//! The rigid bodies' slots ([`Border`]) join the network solver's reduced junction system
//! as junctions of their own ([`NetworkSolver::with_border`], O(1) work per body); the other
//! two solvers take them by a Schur complement ([`Bordered`], one more O(N) sweep per slot
//! component).

mod block_lu;
mod block_tridiagonal;
mod bordered;
mod network;
mod sparse_lu;

pub use block_tridiagonal::BlockTridiagonal;
pub(crate) use block_tridiagonal::block_thomas;
pub use bordered::Bordered;
pub use network::{JunctionLu, NetworkSolver};
pub use sparse_lu::SparseLu;

use nalgebra::{SMatrix, SVector};

use crate::error::{LinearSolveError, SetupError};
use crate::mesh::Mesh;

/// A `D×D` block of the Newton matrix.
pub type Block<const D: usize> = SMatrix<f64, D, D>;

/// Newton matrix in node-block form, matching a [`Mesh`], with a border of unknowns beyond
/// the nodes (the rigid bodies' slots, two per body: `Δx` and the Cayley vector `w`).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockJacobian<const D: usize> {
    /// `∂R_i/∂x_i` per node.
    pub diag: Vec<Block<D>>,
    /// Per element `[a, b]`: `[∂R_a/∂x_b, ∂R_b/∂x_a]`.
    pub off: Vec<[Block<D>; 2]>,
    /// The rows and columns of the slots (empty without bodies).
    pub border: Border<D>,
}

/// The slots' part of a [`BlockJacobian`]: unknowns `n_nodes..n_nodes + slots` of the
/// Newton vector, each a `D`-vector.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Border<const D: usize> {
    /// Number of slots.
    pub slots: usize,
    /// `∂R_s/∂u_t` for slots `s, t`, row-major (`slots²` blocks).
    pub own: Vec<Block<D>>,
    /// Couplings of a slot with a node: `(node, slot, ∂R_slot/∂x_node, ∂R_node/∂u_slot)`;
    /// a pair may appear more than once (the blocks add).
    pub links: Vec<(usize, usize, Block<D>, Block<D>)>,
}

/// Where a [`Border`] may have nonzero blocks, known before the first assembly: a solver that
/// takes the slots into its own elimination ([`NetworkSolver::with_border`]) analyses it once.
/// Every slot's diagonal block may be nonzero; the blocks not listed must stay zero.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct BorderPattern {
    /// Number of slots.
    pub slots: usize,
    /// `[node, slot]`: the blocks `∂R_slot/∂x_node` and `∂R_node/∂u_slot` may be nonzero
    /// (repeats allowed).
    pub links: Vec<[usize; 2]>,
    /// `[s, t]`, `s ≠ t`: the blocks `∂R_s/∂u_t` and `∂R_t/∂u_s` may be nonzero (repeats and
    /// either order allowed).
    pub pairs: Vec<[usize; 2]>,
}

impl<const D: usize> BlockJacobian<D> {
    /// A zero matrix for `mesh`.
    pub fn zeros(mesh: &Mesh) -> Self {
        Self::with_slots(mesh, 0)
    }
    /// A zero matrix for `mesh` and `slots` slots beyond its nodes.
    pub fn with_slots(mesh: &Mesh, slots: usize) -> Self {
        Self {
            diag: vec![Block::zeros(); mesh.n_nodes()],
            off: vec![[Block::zeros(); 2]; mesh.n_elements()],
            border: Border {
                slots,
                own: vec![Block::zeros(); slots * slots],
                links: Vec::new(),
            },
        }
    }
    /// Sets all blocks to zero (and drops the slots' links).
    pub fn clear(&mut self) {
        self.diag.iter_mut().for_each(|b| b.fill(0.0));
        self.off.iter_mut().for_each(|b| {
            b[0].fill(0.0);
            b[1].fill(0.0);
        });
        self.border.own.iter_mut().for_each(|b| b.fill(0.0));
        self.border.links.clear();
    }
    /// `out = J x` (`x` and `out` of the nodes' length, or with the slots after them).
    pub fn mul(&self, mesh: &Mesh, x: &[SVector<f64, D>], out: &mut [SVector<f64, D>]) {
        for ((o, d), xi) in out.iter_mut().zip(&self.diag).zip(x) {
            *o = d * xi;
        }
        for (&[a, b], off) in mesh.elements().iter().zip(&self.off) {
            out[a] += off[0] * x[b];
            out[b] += off[1] * x[a];
        }
        let (n, m) = (self.diag.len(), self.border.slots);
        if m == 0 || x.len() < n + m {
            return;
        }
        for s in 0..m {
            out[n + s] = SVector::zeros();
            for t in 0..m {
                out[n + s] += self.border.own[s * m + t] * x[n + t];
            }
        }
        for &(node, slot, row, col) in &self.border.links {
            out[n + slot] += row * x[node];
            out[node] += col * x[n + slot];
        }
    }
}

/// Which linear solver a simulation uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolverKind {
    /// Block-tridiagonal for chain meshes, [`NetworkSolver`] otherwise (measured 3× faster than
    /// [`SparseLu`] on a 100-string net); with rigid bodies' slots, [`make_border_solver`]
    /// picks [`NetworkSolver`] for a chain too (it takes the slots into its junction system).
    #[default]
    Auto,
    /// [`BlockTridiagonal`] (fails at setup for a mesh that is not a chain).
    BlockTridiagonal,
    /// [`SparseLu`].
    SparseLu,
    /// [`NetworkSolver`].
    Network,
}

impl SolverKind {
    /// Name as in scenario files: `auto`, `block_tridiagonal`, `sparse_lu`, `network`.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Auto => "auto",
            SolverKind::BlockTridiagonal => "block_tridiagonal",
            SolverKind::SparseLu => "sparse_lu",
            SolverKind::Network => "network",
        }
    }
}

/// A solver for `J x = b` with `J` in [`BlockJacobian`] form.
pub trait LinearSolver<const D: usize>: Send {
    /// Factors `jac` and overwrites `rhs` with the solution of `jac · x = rhs`.
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError>;
    /// Name for reports: `block_tridiagonal`, `sparse_lu` or `network`.
    fn name(&self) -> &'static str;
    /// Asks the solver to keep what [`Self::solve_again`] needs from each factorization
    /// (more memory per node; the default keeps nothing).
    fn keep_factors(&mut self) {}
    /// Solves `jac · x = rhs` again with the factorization of the last successful
    /// [`Self::solve`] of the same `jac` (after [`Self::keep_factors`]); the default factors
    /// again.
    fn solve_again(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        self.solve(jac, rhs)
    }
}

/// Builds the solver `kind` for `mesh` (with `slots` bordering unknowns, the solver of `kind`
/// inside a [`Bordered`] one).
pub fn make_bordered_solver<const D: usize>(
    kind: SolverKind,
    mesh: &Mesh,
    slots: usize,
) -> Result<Box<dyn LinearSolver<D>>, SetupError> {
    let inner = make_solver::<D>(kind, mesh)?;
    Ok(if slots == 0 {
        inner
    } else {
        Box::new(Bordered::new(inner, mesh.n_nodes(), slots))
    })
}

/// Builds the solver `kind` for `mesh` with the slots of `border` (the rigid bodies'): the
/// network solver (`Auto` or `Network`, chain or not) takes the slots into its reduced
/// junction system ([`NetworkSolver::with_border`]); `BlockTridiagonal` and `SparseLu` solve
/// the nodes inside a [`Bordered`] solver. Without slots, as [`make_solver`].
pub fn make_border_solver<const D: usize>(
    kind: SolverKind,
    mesh: &Mesh,
    border: &BorderPattern,
) -> Result<Box<dyn LinearSolver<D>>, SetupError> {
    match kind {
        _ if border.slots == 0 => make_solver::<D>(kind, mesh),
        SolverKind::Auto | SolverKind::Network => Ok(Box::new(NetworkSolver::with_border(
            mesh,
            border,
            JunctionLu::Block,
        )?)),
        SolverKind::BlockTridiagonal | SolverKind::SparseLu => {
            make_bordered_solver::<D>(kind, mesh, border.slots)
        }
    }
}

/// Builds the solver `kind` for `mesh`.
pub fn make_solver<const D: usize>(
    kind: SolverKind,
    mesh: &Mesh,
) -> Result<Box<dyn LinearSolver<D>>, SetupError> {
    Ok(match kind {
        SolverKind::Auto if mesh.is_chain() => Box::new(BlockTridiagonal::new(mesh)?),
        SolverKind::BlockTridiagonal => Box::new(BlockTridiagonal::new(mesh)?),
        SolverKind::SparseLu => Box::new(SparseLu::new(mesh)),
        SolverKind::Auto | SolverKind::Network => Box::new(NetworkSolver::new(mesh)),
    })
}

/// SplitMix64: a small deterministic generator for the solvers' test matrices, patterns and
/// permutations.
#[cfg(test)]
pub(crate) mod test_rng {
    /// Generator state.
    pub(crate) struct Rng(pub(crate) u64);

    impl Rng {
        pub(crate) fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// Uniform in `[−1, 1)`.
        pub(crate) fn sym(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        /// Uniform in `0..n`.
        pub(crate) fn below(&mut self, n: usize) -> usize {
            (self.next_u64() % n as u64) as usize
        }
    }
}
