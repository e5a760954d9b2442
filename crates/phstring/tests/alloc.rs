//! The step loop does not allocate (issue 2): a counting global allocator around 50 steps of
//! the paper's benchmark, after one warm-up step, for both linear solvers.
#![allow(unsafe_code)] // a global allocator needs `unsafe impl`

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use phstring::benchmarks::paper_pendulum;
use phstring::{Scheme, Simulation, SolverKind, StepParams};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One test only: the counter is global to the binary.
#[test]
fn step_loop_does_not_allocate() {
    for solver in [SolverKind::BlockTridiagonal, SolverKind::SparseLu] {
        for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
            let params = StepParams {
                h: 0.01,
                scheme,
                solver,
                ..Default::default()
            };
            let mut sim = Simulation::new(paper_pendulum(30), params).unwrap();
            sim.step().unwrap(); // warm-up: lets a backend size internal buffers once
            let before = ALLOCS.load(Ordering::SeqCst);
            let mut iters = 0;
            for _ in 0..50 {
                iters += sim.step().unwrap().newton_iterations;
            }
            let n = ALLOCS.load(Ordering::SeqCst) - before;
            eprintln!(
                "{solver:?} {scheme:?}: {n} allocations in 50 steps ({iters} Newton iterations)"
            );
            assert_eq!(
                n, 0,
                "{solver:?} {scheme:?}: the step loop allocated {n} times"
            );
        }
    }
    // Nonlinear elimination and step-size control on a fine mesh: adaptive steps with local
    // solves and rejected attempts.
    let mut problem = paper_pendulum(1000);
    problem.material = phstring::Material::tension_only_linear(20.0);
    let mut sim = Simulation::new(problem, StepParams::default()).unwrap();
    sim.step().unwrap();
    let before = ALLOCS.load(Ordering::SeqCst);
    let (mut local, mut rejected) = (0, 0);
    for _ in 0..40 {
        let r = sim.step().unwrap();
        local += r.local_iterations;
        rejected += r.rejected;
    }
    let n = ALLOCS.load(Ordering::SeqCst) - before;
    eprintln!(
        "elimination: {n} allocations in 40 steps ({local} local iterations, {rejected} rejected)"
    );
    assert!(local > 0, "elimination never ran");
    assert_eq!(
        n, 0,
        "the adaptive step loop with elimination allocated {n} times"
    );
}
