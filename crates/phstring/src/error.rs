//! Error types. Each carries the numbers a user needs to find the cause.

use thiserror::Error;

/// An invalid problem definition, found before any time step is taken.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SetupError {
    /// The mesh has no elements.
    #[error("the mesh has no elements (need at least 1)")]
    NoElements,
    /// Element and length lists differ in size.
    #[error("{elements} elements but {lengths} reference lengths")]
    LengthCount {
        /// Number of elements.
        elements: usize,
        /// Number of lengths.
        lengths: usize,
    },
    /// A node index is not in `0..n_nodes`.
    #[error("{what} refers to node {node}, but the mesh has nodes 0..={}", n_nodes.saturating_sub(1))]
    NodeOutOfRange {
        /// Where the index appeared.
        what: &'static str,
        /// The bad index.
        node: usize,
        /// Number of nodes in the mesh.
        n_nodes: usize,
    },
    /// An element connects a node to itself.
    #[error("element {element} connects node {node} to itself")]
    DegenerateElement {
        /// Element index.
        element: usize,
        /// Node index.
        node: usize,
    },
    /// A value that must be positive and finite is not.
    #[error("{what}{} must be positive and finite, got {value}", index.map(|i| format!(" [{i}]")).unwrap_or_default())]
    NonPositive {
        /// Name of the quantity.
        what: &'static str,
        /// Index (element, node), if any.
        index: Option<usize>,
        /// The value given.
        value: f64,
    },
    /// A value that must be finite is not.
    #[error("{what} [{index}] is not finite: {value}")]
    NotFinite {
        /// Name of the quantity.
        what: &'static str,
        /// Index.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// The initial state has the wrong number of entries.
    #[error("initial {what} has {got} entries, the mesh needs {expected}")]
    StateSize {
        /// Which part of the state.
        what: &'static str,
        /// Entries given.
        got: usize,
        /// Entries needed.
        expected: usize,
    },
    /// The initial strain is outside the material's domain.
    #[error("initial strain C = {c} of element {element} is outside the material's domain")]
    InadmissibleStrain {
        /// Element index.
        element: usize,
        /// Strain value.
        c: f64,
    },
    /// The requested linear solver cannot handle this mesh.
    #[error("the block-tridiagonal solver needs a chain mesh (element e = [e, e+1])")]
    NotAChain,
}

/// A failure of the linear solve inside a Newton iteration.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LinearSolveError {
    /// A pivot block was singular (or a pivot was zero/NaN).
    #[error("singular Newton matrix at block {block}")]
    Singular {
        /// Block (node) index where elimination broke down.
        block: usize,
    },
    /// The sparse LU backend reported an error.
    #[error("sparse LU failed: {0}")]
    Sparse(String),
}

impl StepError {
    /// Whether a smaller step size may succeed (all failures of the solve; not a non-finite
    /// load, which does not depend on `h`).
    pub fn is_recoverable(&self) -> bool {
        !matches!(
            self,
            StepError::NonFinite { what: "load", .. } | StepError::StepSizeTooSmall { .. }
        )
    }
}

/// A failure of one time step.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StepError {
    /// Newton's method did not reach the tolerance within the iteration limit.
    #[error(
        "Newton did not converge in step {step} (t = {t} → {t_next}): residual {residual:.3e} N > tolerance {tol:.1e} N after {iterations} iterations; largest residual at node {worst_node}{}",
        if *residual < 1e3 * *tol { " (the residual stagnates near round-off for forces of this size: raise the Newton tolerance)" } else { "" }
    )]
    NewtonDiverged {
        /// Node with the largest residual.
        worst_node: usize,
        /// Index of the step that failed (1 = the first step).
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// End time of the step [s].
        t_next: f64,
        /// Last residual norm [N].
        residual: f64,
        /// Tolerance [N].
        tol: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// The line search found no acceptable step length.
    #[error(
        "line search failed in step {step} (t = {t} → {t_next}): residual {residual:.3e} N could not be reduced after {iterations} iterations; largest residual at node {worst_node}"
    )]
    LineSearchFailed {
        /// Node with the largest residual.
        worst_node: usize,
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// End time of the step [s].
        t_next: f64,
        /// Residual norm at the last accepted iterate [N].
        residual: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// Step-size control halved the step as often as allowed without success.
    #[error(
        "step {step} (t = {t}): no convergence even with h = {h:.3e} s after {halvings} halvings; last failure: {last}"
    )]
    StepSizeTooSmall {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// The last step size tried [s].
        h: f64,
        /// Halvings done.
        halvings: u32,
        /// The failure at the smallest step size.
        last: Box<StepError>,
    },
    /// A Newton iterate produced a strain outside the material's domain (e.g. `C ≤ 0`).
    #[error(
        "step {step} (t = {t}): element {element} reached strain C = {c}, outside the material's domain"
    )]
    InvalidStrain {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// Element index.
        element: usize,
        /// Strain value.
        c: f64,
    },
    /// The residual or the state became NaN or infinite.
    #[error("step {step} (t = {t}): non-finite value in the {what} at node {node}")]
    NonFinite {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// `"residual"`, `"state"` or `"load"`.
        what: &'static str,
        /// Node index.
        node: usize,
    },
    /// The linear solve failed.
    #[error("step {step} (t = {t}): {source}")]
    Linear {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// The cause.
        source: LinearSolveError,
    },
}
