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

/// A position signal `t ↦ x(t)` [s ↦ m].
pub type PositionFn = Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// Prescribed motion (paper Remarks 3–4, velocity in / force out): component `component` of
/// `node` follows the absolute position `position(t)` [m], which must equal the initial
/// position at `t = 0`. Its port has the mid-step velocity as input and the reaction force
/// as output, and their power enters the energy balance.
#[derive(Clone)]
pub struct Motion {
    /// Node index.
    pub node: usize,
    /// Component (0 = x, 1 = y, 2 = z).
    pub component: usize,
    /// The absolute position signal.
    pub position: PositionFn,
}

impl Motion {
    /// Component `component` of `node` follows `position(t)` [m].
    pub fn new(
        node: usize,
        component: usize,
        position: impl Fn(f64) -> f64 + Send + Sync + 'static,
    ) -> Self {
        Self {
            node,
            component,
            position: Arc::new(position),
        }
    }
}

impl fmt::Debug for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Motion")
            .field("node", &self.node)
            .field("component", &self.component)
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
    /// Prescribed motions (moving supports).
    pub motions: Vec<Motion>,
}

/// What a port's input is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PortKind {
    /// Force input [N], velocity output [m/s] (a loaded node).
    Force,
    /// Velocity input [m/s], reaction-force output [N] (a fixed node or one whose motion is
    /// prescribed).
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
