//! The step loop does not allocate (issue 2): a counting global allocator around 50 steps of
//! the paper's benchmark, after one warm-up step, for both linear solvers.
//!
//! Allocations are counted per thread (issue 10: a global counter also counted the test
//! harness's allocations on other threads and failed on a busy machine), so only the
//! allocations of the thread that runs the steps are measured.
#![allow(unsafe_code)] // a global allocator needs `unsafe impl`

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use phstring::benchmarks::{paper_params, paper_pendulum};
use phstring::{Scheme, Simulation, SolverKind, StepParams};

struct Counting;

thread_local! {
    /// Allocations made by this thread (const-initialized: reading it never allocates).
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // `try_with` fails only while the thread is being torn down; nothing to count then.
    let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
}

/// Allocations made so far by the calling thread.
fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The counting allocator sees allocations of the calling thread only, so another thread
/// allocating at the same time (as the test harness does on a busy machine) is not counted.
#[test]
fn allocation_counter_ignores_other_threads() {
    let before = allocations();
    let other = std::thread::spawn(|| {
        let v: Vec<Vec<u8>> = (0..1000).map(|i| vec![0; i + 1]).collect();
        v.len()
    });
    assert_eq!(other.join().unwrap(), 1000);
    // Spawning and joining allocate on this thread too; the 1000 vectors must not show.
    let here = allocations() - before;
    assert!(here < 100, "{here} allocations counted on this thread");
    let before = allocations();
    let v = vec![1u8; 10];
    assert_eq!(allocations() - before, 1);
    drop(v);
}

#[test]
fn step_loop_does_not_allocate() {
    for solver in [SolverKind::BlockTridiagonal, SolverKind::SparseLu] {
        for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
            let params = StepParams {
                scheme,
                solver,
                ..paper_params()
            };
            let mut sim = Simulation::new(paper_pendulum(30), params).unwrap();
            sim.step().unwrap(); // warm-up: lets a backend size internal buffers once
            let before = allocations();
            let mut iters = 0;
            for _ in 0..50 {
                iters += sim.step().unwrap().newton_iterations;
            }
            let n = allocations() - before;
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
    let before = allocations();
    let (mut local, mut rejected) = (0, 0);
    for _ in 0..40 {
        let r = sim.step().unwrap();
        local += r.local_iterations;
        rejected += r.rejected;
    }
    let n = allocations() - before;
    eprintln!(
        "elimination: {n} allocations in 40 steps ({local} local iterations, {rejected} rejected)"
    );
    assert!(local > 0, "elimination never ran");
    assert_eq!(
        n, 0,
        "the adaptive step loop with elimination allocated {n} times"
    );
}
