//! Boundary conditions and ports (docs/method.md §2 and §4, paper Remarks 3 and 4).
//!
//! * A **fixed** node keeps (some of) its position components at their initial values
//!   (Dirichlet). Its port has the velocity (zero) as input and the reaction force as output.
//! * A **load** applies a nodal force `F(t)` [N] (Neumann). Its port has the force as input
//!   and the node velocity as output. The discrete-gradient scheme evaluates `F` at the mid
//!   time `t_{n+½}` (docs/method.md §5).

use std::fmt;
use std::sync::Arc;

use nalgebra::SVector;

/// A nodal force signal `t ↦ F(t)` [s ↦ N].
pub type ForceFn<const D: usize> = Arc<dyn Fn(f64) -> SVector<f64, D> + Send + Sync>;

/// A Dirichlet condition: the listed components of `node` stay at their initial position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed<const D: usize> {
    /// Node index.
    pub node: usize,
    /// Which components (x, y, z) are fixed.
    pub components: [bool; D],
}

impl<const D: usize> Fixed<D> {
    /// All components of `node` fixed.
    pub fn node(node: usize) -> Self {
        Self {
            node,
            components: [true; D],
        }
    }
}

/// A Neumann condition: a nodal force `F(t)` [N] acting on `node`.
#[derive(Clone)]
pub struct NodalLoad<const D: usize> {
    /// Node index.
    pub node: usize,
    /// The force signal.
    pub force: ForceFn<D>,
}

impl<const D: usize> NodalLoad<D> {
    /// A load from any function of time.
    pub fn new(
        node: usize,
        force: impl Fn(f64) -> SVector<f64, D> + Send + Sync + 'static,
    ) -> Self {
        Self {
            node,
            force: Arc::new(force),
        }
    }
}

impl<const D: usize> fmt::Debug for NodalLoad<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("NodalLoad")
            .field("node", &self.node)
            .finish_non_exhaustive()
    }
}

/// All boundary conditions of a problem.
#[derive(Debug, Clone, Default)]
pub struct Boundary<const D: usize> {
    /// Dirichlet conditions.
    pub fixed: Vec<Fixed<D>>,
    /// Neumann conditions.
    pub loads: Vec<NodalLoad<D>>,
}

/// What a port's input is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PortKind {
    /// Force input [N], velocity output [m/s] (a loaded node).
    Force,
    /// Velocity input [m/s], reaction-force output [N] (a fixed node).
    Velocity,
}

/// Input and output of one port over the last step, both at the mid time `t_{n+½}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortSample<const D: usize> {
    /// Node index.
    pub node: usize,
    /// Port type.
    pub kind: PortKind,
    /// Input `û_{n+½}`: force [N] or velocity [m/s].
    pub input: SVector<f64, D>,
    /// Output `ŷ_{n+½}`: velocity [m/s] or reaction force [N].
    pub output: SVector<f64, D>,
}

impl<const D: usize> PortSample<D> {
    /// Power `û·ŷ` [W] flowing into the string through this port.
    pub fn power(&self) -> f64 {
        self.input.dot(&self.output)
    }
}
