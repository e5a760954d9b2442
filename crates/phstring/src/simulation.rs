//! The time loop: [`Simulation::step`] advances one step and reports; the caller owns the
//! loop, [`Simulation::run_until`] is a thin convenience over it.

use crate::boundary::{PortKind, PortSample};
use crate::error::{SetupError, StepError};
use crate::integrator::{Scheme, StepEquations, element_step};
use crate::linsolve::{LinearSolver, SolverKind, make_solver};
use crate::material::StoredEnergy;
use crate::newton::{self, NewtonError, NewtonParams, NewtonWorkspace};
use crate::observe::{Observer, RunSummary, StepReport};
use crate::system::{Energies, PhSystem, Problem, State, Vector};

/// Parameters of the time stepper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Time step `h` [s].
    pub h: f64,
    /// Scheme (DG or MP).
    pub scheme: Scheme,
    /// Newton parameters.
    pub newton: NewtonParams,
    /// Linear solver.
    pub solver: SolverKind,
}

impl Default for StepParams {
    fn default() -> Self {
        Self {
            h: 0.01,
            scheme: Scheme::DiscreteGradient,
            newton: NewtonParams::default(),
            solver: SolverKind::Auto,
        }
    }
}

/// A running simulation: system, state, time and all workspaces.
pub struct Simulation<const D: usize, M> {
    sys: PhSystem<D, M>,
    params: StepParams,
    state: State<D>,
    t0: f64,
    step: usize,
    energies: Energies,
    supplied_total: f64,
    // Workspaces (allocated once).
    x: Vec<Vector<D>>,
    f_ext: Vec<Vector<D>>,
    reaction: Vec<Vector<D>>,
    ports: Vec<PortSample<D>>,
    newton_ws: NewtonWorkspace<D>,
    solver: Box<dyn LinearSolver<D>>,
    total_newton: usize,
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Validates `problem`, sets up the solver and starts at time `t = 0`.
    pub fn new(problem: Problem<D, M>, params: StepParams) -> Result<Self, SetupError> {
        if !(params.h > 0.0 && params.h.is_finite()) {
            return Err(SetupError::NonPositive {
                what: "time step h",
                index: None,
                value: params.h,
            });
        }
        if params.newton.tol.is_nan() || params.newton.tol <= 0.0 {
            return Err(SetupError::NonPositive {
                what: "Newton tolerance",
                index: None,
                value: params.newton.tol,
            });
        }
        let (sys, state) = PhSystem::new(problem)?;
        let n = sys.mesh.n_nodes();
        let solver = make_solver::<D>(params.solver, &sys.mesh)?;
        let mut ports: Vec<PortSample<D>> = sys
            .boundary
            .loads
            .iter()
            .map(|l| PortSample {
                node: l.node,
                kind: PortKind::Force,
                input: Vector::zeros(),
                output: Vector::zeros(),
            })
            .collect();
        ports.extend(sys.constrained.iter().map(|&node| PortSample {
            node,
            kind: PortKind::Velocity,
            input: Vector::zeros(),
            output: Vector::zeros(),
        }));
        let energies = sys.energies(&state);
        Ok(Self {
            newton_ws: NewtonWorkspace::new(&sys.mesh),
            sys,
            params,
            state,
            t0: 0.0,
            step: 0,
            energies,
            supplied_total: 0.0,
            x: vec![Vector::zeros(); n],
            f_ext: vec![Vector::zeros(); n],
            reaction: vec![Vector::zeros(); n],
            ports,
            solver,
            total_newton: 0,
        })
    }

    /// The system.
    pub fn system(&self) -> &PhSystem<D, M> {
        &self.sys
    }
    /// The current state.
    pub fn state(&self) -> &State<D> {
        &self.state
    }
    /// Step parameters.
    pub fn params(&self) -> &StepParams {
        &self.params
    }
    /// Current time `t_n = n h` [s].
    pub fn time(&self) -> f64 {
        self.t0 + self.step as f64 * self.params.h
    }
    /// Number of steps taken.
    pub fn steps(&self) -> usize {
        self.step
    }
    /// Energies of the current state [J].
    pub fn energies(&self) -> Energies {
        self.energies
    }
    /// Cumulative supplied energy `Σ h û·ŷ` [J].
    pub fn supplied_energy(&self) -> f64 {
        self.supplied_total
    }
    /// Total Newton iterations so far.
    pub fn total_newton_iterations(&self) -> usize {
        self.total_newton
    }
    /// Name of the linear solver in use.
    pub fn solver_name(&self) -> &'static str {
        self.solver.name()
    }
    /// Port inputs and outputs of the last step (loads first, in the order given, then
    /// constrained nodes in increasing order). Before the first step both are zero.
    pub fn ports(&self) -> &[PortSample<D>] {
        &self.ports
    }

    /// Advances one step of size `h` from `t_n` to `t_{n+1}` (METHOD §3, paper eq. (32)).
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        let h = self.params.h;
        let t = self.time();
        let t_next = self.t0 + (self.step + 1) as f64 * h;
        let t_mid = t + 0.5 * h;
        let step_no = self.step + 1;

        // External forces F_b + F_N(t_{n+½}); load ports get their inputs here.
        self.f_ext.copy_from_slice(&self.sys.f_body);
        for (port, load) in self.ports.iter_mut().zip(&self.sys.boundary.loads) {
            let f = (load.force)(t_mid);
            if !f.iter().all(|x| x.is_finite()) {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "load",
                    node: load.node,
                });
            }
            port.input = f;
            self.f_ext[load.node] += f;
        }
        // Predictor: Δ = h v_n on free components.
        for ((x, v), free) in self.x.iter_mut().zip(&self.state.v).zip(&self.sys.free) {
            *x = v * h;
            for k in 0..D {
                if !free[k] {
                    x[k] = 0.0;
                }
            }
        }
        let mut eqs = StepEquations {
            sys: &self.sys,
            scheme: self.params.scheme,
            h,
            r0: &self.state.r,
            v0: &self.state.v,
            c0: &self.state.c,
            f_ext: &self.f_ext,
            reaction: &mut self.reaction,
        };
        let stats = newton::solve(
            &mut eqs,
            &mut self.x,
            &mut self.newton_ws,
            self.solver.as_mut(),
            &self.params.newton,
        )
        .map_err(|e| match e {
            NewtonError::Eval(s) => StepError::InvalidStrain {
                step: step_no,
                t,
                element: s.element,
                c: s.c,
            },
            NewtonError::Linear(source) => StepError::Linear {
                step: step_no,
                t,
                source,
            },
            NewtonError::NonFinite { node } => StepError::NonFinite {
                step: step_no,
                t,
                what: "residual",
                node,
            },
            NewtonError::MaxIterations(s) => StepError::NewtonDiverged {
                step: step_no,
                t,
                t_next,
                residual: s.residual,
                tol: self.params.newton.tol,
                iterations: s.iterations,
            },
        })?;

        // Update: strains first (they need r_n), then r and v.
        let mesh = &self.sys.mesh;
        for (e, (&[a, b], &l)) in mesh.elements().iter().zip(mesh.lengths()).enumerate() {
            let (_, _, dc) = element_step(
                &self.state.r[a],
                &self.state.r[b],
                &self.x[a],
                &self.x[b],
                l,
            );
            self.state.c[e] += dc;
        }
        let inv_h = 1.0 / h;
        for ((r, v), x) in self.state.r.iter_mut().zip(&mut self.state.v).zip(&self.x) {
            *r += x;
            *v = x * (2.0 * inv_h) - *v;
        }
        // Port outputs at t_{n+½}: velocity v_{n+½} = Δ/h, reaction forces.
        let n_loads = self.sys.boundary.loads.len();
        for (i, port) in self.ports.iter_mut().enumerate() {
            let v_mid = self.x[port.node] * inv_h;
            if i < n_loads {
                port.output = v_mid;
            } else {
                let free = &self.sys.free[port.node];
                for k in 0..D {
                    let fixed = !free[k];
                    port.input[k] = if fixed { v_mid[k] } else { 0.0 };
                    port.output[k] = if fixed {
                        self.reaction[port.node][k]
                    } else {
                        0.0
                    };
                }
            }
        }
        let supplied = h * self.ports.iter().map(|p| p.power()).sum::<f64>();
        let before = self.energies;
        let after = self.sys.energies(&self.state);
        self.energies = after;
        self.supplied_total += supplied;
        self.step += 1;
        self.total_newton += stats.iterations;
        if let Some(node) = self.state.r.iter().zip(&self.state.v).position(|(r, v)| {
            !(r.iter().all(|x| x.is_finite()) && v.iter().all(|x| x.is_finite()))
        }) {
            return Err(StepError::NonFinite {
                step: step_no,
                t,
                what: "state",
                node,
            });
        }
        Ok(StepReport {
            step: step_no,
            t: t_next,
            h,
            newton_iterations: stats.iterations,
            residual: stats.residual,
            before,
            after,
            supplied,
            balance_error: after.hamiltonian() - before.hamiltonian() - supplied,
        })
    }

    /// Steps until `t_end` (the number of steps is `round((t_end − t)/h)`), calling the
    /// observer at the start, after every step and at the end.
    pub fn run_until(
        &mut self,
        t_end: f64,
        observer: &mut dyn Observer<D, M>,
    ) -> Result<RunSummary, StepError> {
        let n = ((t_end - self.time()) / self.params.h).round().max(0.0) as usize;
        observer.on_start(self);
        let mut summary = RunSummary::default();
        for _ in 0..n {
            let report = self.step()?;
            summary.record(&report);
            observer.on_step(self, &report);
        }
        observer.on_end(self);
        Ok(summary)
    }
}
