//! Error types. Each carries the numbers a user needs to find the cause.

use thiserror::Error;

/// A number for messages: the shortest exact form for ordinary magnitudes, scientific
/// notation (`5e-324`, `1.2e300`) otherwise, so that no message prints hundreds of digits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// An invalid problem definition, found before any time step is taken.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
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
    /// A slot index (an unknown after the nodes, two per rigid body) is not in `0..slots`.
    #[error("{what} refers to slot {slot}, but there are slots 0..{slots}")]
    SlotOutOfRange {
        /// Where the index appeared.
        what: &'static str,
        /// The bad index.
        slot: usize,
        /// Number of slots.
        slots: usize,
    },
    /// An element connects a node to itself.
    #[error("element {element} connects node {node} to itself")]
    DegenerateElement {
        /// Element index.
        element: usize,
        /// Node index.
        node: usize,
    },
    /// A rigid body's definition or initial state is not usable.
    #[error("rigid body {index} ('{name}'): {problem}")]
    Body {
        /// Index of the body.
        index: usize,
        /// Its name.
        name: String,
        /// What is wrong, with the value.
        problem: String,
    },
    /// A winch's definition or its string is not usable.
    #[error("winch {index} ('{name}'): {problem}")]
    Winch {
        /// Index of the winch.
        index: usize,
        /// Its name.
        name: String,
        /// What is wrong, with the value.
        problem: String,
    },
    /// A value that must be positive and finite is not.
    #[error("{what}{} must be positive and finite, got {}", index.map(|i| format!(" [{i}]")).unwrap_or_default(), Num(*value))]
    NonPositive {
        /// Name of the quantity.
        what: &'static str,
        /// Index (element, node), if any.
        index: Option<usize>,
        /// The value given.
        value: f64,
    },
    /// A value that must be finite is not.
    #[error("{what} [{index}] is not finite: {}", Num(*value))]
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
    #[error("initial strain C = {} of element {element} is outside the material's domain", Num(*c))]
    InadmissibleStrain {
        /// Element index.
        element: usize,
        /// Strain value.
        c: f64,
    },
    /// A prescribed position does not start at the node's initial position.
    #[error(
        "prescribed motion {index} (node {node}, component {component}) is at {} m at t = 0, but the node starts at {} m",
        Num(*at_zero), Num(*initial)
    )]
    MotionStart {
        /// Index in the list of motions.
        index: usize,
        /// Node index.
        node: usize,
        /// Component.
        component: usize,
        /// The prescribed position at `t = 0` [m].
        at_zero: f64,
        /// The initial position [m].
        initial: f64,
    },
    /// A parameter is outside its range.
    #[error("{what} must be in {range}, got {}", Num(*value))]
    OutOfRange {
        /// Name of the parameter.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range.
        range: &'static str,
    },
    /// A quantity derived from the problem (a load, an energy) is not finite: the inputs
    /// are too large (or small) for floating point.
    #[error("{what} is not finite ({}): the inputs overflow floating point", Num(*value))]
    DerivedNotFinite {
        /// What was computed, e.g. "initial potential energy" or "body force at node 3".
        what: String,
        /// The value computed.
        value: f64,
    },
    /// The element groups do not cover the elements `0..n_elements` in order, each once.
    #[error(
        "element group {group} covers elements {start}..{end}, but the next uncovered element is {expected} (of {n_elements}); groups must be non-empty, in order and cover every element once"
    )]
    GroupCoverage {
        /// Group index (`n_groups` if elements are left over at the end).
        group: usize,
        /// First element of the group.
        start: usize,
        /// One past the last element of the group.
        end: usize,
        /// The element the group should start at.
        expected: usize,
        /// Number of elements in the mesh.
        n_elements: usize,
    },
    /// A spring group was given a mass or a body force: springs are massless links.
    #[error(
        "element group {group} ({name}) is a spring group: springs are massless, so its rho_a and body force must be 0"
    )]
    MassiveSpring {
        /// Group index.
        group: usize,
        /// Group name.
        name: String,
    },
    /// A damping kind on an element group that does not take it.
    #[error("element group {group} ({name}): {what}")]
    MisplacedDamping {
        /// Group index.
        group: usize,
        /// Group name.
        name: String,
        /// The damping kind and where it belongs.
        what: &'static str,
    },
    /// A parameter of the water, the seabed, the current or a line's or point's
    /// hydrodynamics (docs/method.md §21) is outside its range.
    #[error("{what}{} must be {range}, got {}", index.map(|i| format!(" [{i}]")).unwrap_or_default(), Num(*value))]
    WaterParameter {
        /// Name of the parameter, with its unit.
        what: &'static str,
        /// Index (group, point, profile point), if any.
        index: Option<usize>,
        /// The value given.
        value: f64,
        /// The allowed range.
        range: &'static str,
    },
    /// Water needs a vertical axis (the last component): dimension 2 or 3.
    #[error(
        "water and seabed need a vertical axis: dimension D = {dimension} given, need D = 2 or 3"
    )]
    WaterDimension {
        /// The dimension given.
        dimension: usize,
    },
    /// Line hydrodynamics given for a spring group, or twice for one group.
    #[error("element group {group} ({name}): line hydrodynamics apply to strings, once per group")]
    HydroGroup {
        /// Group index.
        group: usize,
        /// Group name.
        name: String,
    },
    /// Hydrodynamic parameters given but no water.
    #[error("hydrodynamic parameters of lines or points are given, but the network has no water")]
    HydroWithoutWater,
    /// A node with a free component has no mass (only springs, no string and no point mass
    /// attached): its equation of motion would have no inertia.
    #[error(
        "node {node} is free but has no mass: attach a string or a point mass to it, or fix it"
    )]
    MasslessNode {
        /// Node index.
        node: usize,
    },
    /// A feedback law's gain is beyond what double precision resolves against the
    /// structure's stiffness (docs/method.md §18).
    #[error(
        "the feedback port at node {node} has a {what} of {} N/m, beyond {} N/m = (the structure's stiffness {} N/m: the stiffest element's EA/l or a point mass's 2m/h²) / ε: a change of one unit of rounding in a coordinate would change the control force by more than the structure's own forces, so no step could be solved to round-off. Lower the gain",
        Num(*gain), Num(*limit), Num(*stiffness)
    )]
    UnresolvableGain {
        /// The port's node.
        node: usize,
        /// Which gain: position or velocity.
        what: &'static str,
        /// The gain [N/m] (a velocity gain divided by `h`).
        gain: f64,
        /// The structure's stiffness scale [N/m].
        stiffness: f64,
        /// The largest gain accepted [N/m].
        limit: f64,
    },
    /// The requested linear solver cannot handle this mesh.
    #[error("the block-tridiagonal solver needs a chain mesh (element e = [e, e+1])")]
    NotAChain,
}

/// A failure of the linear solve inside a Newton iteration.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
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
    /// A nonzero block `(row, col)` (unknowns: the nodes, then the slots) lies outside the
    /// pattern the solver analysed at construction.
    #[error("the Newton matrix has a nonzero block ({row}, {col}) outside the solver's pattern")]
    OutsidePattern {
        /// Row of the block (unknown index).
        row: usize,
        /// Column of the block (unknown index).
        col: usize,
    },
    /// The Newton matrix or vector has another number of unknowns than the solver was built
    /// for.
    #[error("the Newton system has {found} unknowns, the solver was built for {expected}")]
    Unknowns {
        /// Unknowns (nodes and slots) the solver was built for.
        expected: usize,
        /// Unknowns of the system given.
        found: usize,
    },
}

impl StepError {
    /// Whether a smaller step size may succeed (all failures of the solve; not a failing
    /// input, which does not depend on `h`).
    pub fn is_recoverable(&self) -> bool {
        !(self.is_input_failure()
            || matches!(
                self,
                StepError::StepSizeTooSmall { .. }
                    | StepError::Interrupted { .. }
                    | StepError::Winch { .. }
            ))
    }

    /// Whether a port input (a load, a prescribed position or a feedback force) was not
    /// finite: a user's signal failed, not the solve.
    pub fn is_input_failure(&self) -> bool {
        matches!(
            self,
            StepError::NonFinite {
                what: "load"
                    | "prescribed position"
                    | "prescribed velocity"
                    | "feedback force"
                    | "rigid body's wrench (at the body's first attached node)",
                ..
            }
        )
    }
}

/// A failure of one time step.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StepError {
    /// Newton's method did not reach the tolerance within the iteration limit.
    #[error(
        "Newton did not converge in step {step} (t = {t0} s → {t1} s): residual {residual:.3e} N > tolerance {tol:.3e} N (force scale {force_scale:.3e} N) after {iterations} iterations; largest residual at node {worst_node}{hint}",
        t0 = Num(*t), t1 = Num(*t_next), hint = if *residual < 1e3 * *tol { " (the residual stagnates close to the tolerance: raise newton.tol or newton.rtol)" } else { "" }
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
        /// Force scale of the step [N] (see `NewtonParams`).
        force_scale: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// The line search found no acceptable step length.
    #[error(
        "line search failed in step {step} (t = {t0} s → {t1} s): residual {residual:.3e} N (tolerance {tol:.3e} N, force scale {force_scale:.3e} N) could not be reduced after {iterations} iterations; largest residual at node {worst_node}",
        t0 = Num(*t), t1 = Num(*t_next)
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
        /// Tolerance [N].
        tol: f64,
        /// Force scale of the step [N].
        force_scale: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// Step-size control reached the step-size floor `time.h / 2^max_halvings` without
    /// success.
    #[error(
        "step {step} (t = {t0} s): the step-size floor h = {floor:.3e} s (time.h / 2^{max_halvings}) was reached without convergence ({halvings} halvings in this step); last failure: {last}",
        t0 = Num(*t)
    )]
    StepSizeTooSmall {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// The last step size tried [s].
        h: f64,
        /// The floor `time.h / 2^max_halvings` [s].
        floor: f64,
        /// `max_halvings`.
        max_halvings: u32,
        /// Halvings done in this step.
        halvings: u32,
        /// The failure at the smallest step size.
        last: Box<StepError>,
    },
    /// The stop flag was set during the step; the state is that of the last good step.
    #[error("step {step} (t = {t0} s): interrupted", t0 = Num(*t))]
    Interrupted {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
    },
    /// A Newton iterate produced a strain outside the material's domain (e.g. `C ≤ 0`).
    #[error(
        "step {step} (t = {t0} s): element {element} reached strain C = {c0}, outside the material's domain",
        t0 = Num(*t), c0 = Num(*c)
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
    #[error("step {step} (t = {t0} s): non-finite value in the {what} at node {node}", t0 = Num(*t))]
    NonFinite {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// `"residual"`, `"residual's norm (it overflows …)"`, `"state"`, `"energy"`, `"load"`
        /// or `"prescribed position"`.
        what: &'static str,
        /// Node index.
        node: usize,
    },
    /// The step equations were solved to Newton's tolerance, but the step's energy balance
    /// misses its bound (an exact scheme only, docs/method.md eq. (9.6)): the equations cannot be
    /// solved to round-off at this step size, typically because a gain, a load or a velocity
    /// dwarfs the structure's own forces.
    #[error(
        "step {step} (t = {t0} s → {t1} s): the energy balance of the step is off by {error:.3e} J, beyond its bound {bound:.3e} J (round-off of the step's energy scale {energy_scale:.3e} J); Newton stopped at residual {residual:.3e} N (force scale {force_scale:.3e} N). The step equations cannot be resolved in double precision here: look for a control gain, load or initial velocity far beyond the structure's own forces",
        t0 = Num(*t), t1 = Num(*t_next)
    )]
    BalanceNotResolved {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// End time of the step [s].
        t_next: f64,
        /// The balance error `Ĥ_{n+1} − Ĥ_n − supplied + dissipated` [J].
        error: f64,
        /// The bound it missed [J].
        bound: f64,
        /// The step's energy scale [J].
        energy_scale: f64,
        /// Newton's final residual [N].
        residual: f64,
        /// Newton's force scale of the step [N].
        force_scale: f64,
    },
    /// A winch cannot follow its payout (docs/method.md §23): its drum is empty, it hauled
    /// in all but half an element, or its payout is not finite. Not retried with a smaller
    /// step.
    #[error("step {step} (t = {t0} s): winch '{winch}' stops at t = {t1} s: {problem}", t0 = Num(*t), t1 = Num(*at))]
    Winch {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// The time whose payout it cannot follow [s].
        at: f64,
        /// The winch's name.
        winch: String,
        /// What limit the payout meets, with the values.
        problem: String,
    },
    /// The linear solve failed.
    #[error("step {step} (t = {t0} s): {cause}", t0 = Num(*t))]
    Linear {
        /// Step index.
        step: usize,
        /// Start time of the step [s].
        t: f64,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: LinearSolveError,
    },
}
