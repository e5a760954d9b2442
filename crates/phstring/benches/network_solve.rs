//! Linear solve of the Newton matrix of a net of strings: [`NetworkSolver`] (block Thomas
//! along the strings, the crate's block sparse LU or faer's simplicial LU on the junctions)
//! against [`SparseLu`] (faer's sparse LU of the whole matrix), with [`BlockTridiagonal`] on
//! a single chain of the same number of elements as the lower bound.
//!
//! `cargo bench -p phstring --bench network_solve` (about 20 s). The net has 50 horizontal
//! and 50 vertical strings of 1000 elements each, crossing at a 50 × 50 grid of shared
//! junction nodes every 20 elements, with free tails of 10 elements (100 000 elements,
//! 97 600 nodes). Each design factors and solves the same random mass-dominated matrix
//! (`diag = 8D·I + random`, off blocks random, not symmetric); times are the median and the
//! minimum of [`REPS`] solves (factor + solve each) after one warm-up solve (on a shared
//! machine the minimum is the steadier measure of the work); `setup` is the construction
//! (decomposition, symbolic analysis). Rows:
//!
//! - `sparse_lu`: the crate's [`SparseLu`] (faer picks the simplicial LU for this net);
//! - `(faer supernodal)`: for reference, faer's supernodal LU of the whole matrix (not a
//!   solver of the crate; it allocates in every factorization);
//! - `network`: [`NetworkSolver::new`], the block sparse LU on the junctions
//!   ([`JunctionLu::Block`]);
//! - `network (simpl.)`: [`JunctionLu::Simplicial`], faer's simplicial LU on the junctions;
//! - `block_tridiagonal` and `network` on a chain of 100 000 elements.
//!
//! All net solutions are checked against `sparse_lu`, and a counting allocator reports the
//! allocations of the first solve after construction (`1st`) and of the timed solves
//! (`allocs`, summed over the repetitions); the bench fails if the network solver (with the
//! block LU or faer's simplicial LU) allocates in a solve.

use std::time::Instant;

use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::LuSymbolicParams;
use nalgebra::SVector;
use phstring::Mesh;
use phstring::linsolve::{
    Block, BlockJacobian, BlockTridiagonal, JunctionLu, LinearSolver, NetworkSolver, SparseLu,
};
use phstring::testing::{CountingAllocator, allocations, grid_net};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Timed repetitions per design (the median and the minimum are reported).
const REPS: usize = 7;

/// SplitMix64 for the random matrices.
struct Rng(u64);

impl Rng {
    fn sym(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn random_jac<const D: usize>(mesh: &Mesh, rng: &mut Rng) -> BlockJacobian<D> {
    let mut jac = BlockJacobian::<D>::zeros(mesh);
    for d in &mut jac.diag {
        *d = Block::from_fn(|_, _| rng.sym()) + Block::identity() * (8.0 * D as f64);
    }
    for off in &mut jac.off {
        for b in off.iter_mut() {
            *b = Block::from_fn(|_, _| rng.sym());
        }
    }
    jac
}

/// Reference only: faer's *supernodal* sparse LU of the whole matrix (the crate's
/// [`SparseLu`] lets faer choose, and faer chooses the simplicial LU for this net): the
/// crate's `SparseLu` with the supernodal factorization forced.
fn whole_supernodal<const D: usize>(mesh: &Mesh) -> SparseLu<D> {
    let params = LuSymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    SparseLu::with_symbolic_params(mesh, params)
}

/// What one design did on one matrix.
struct Timing<const D: usize> {
    setup: f64,
    median: f64,
    min: f64,
    /// Allocations in the first solve after construction.
    first_allocs: usize,
    /// Allocations in the timed solves (all repetitions).
    allocs: usize,
    x: Vec<SVector<f64, D>>,
}

/// Builds a solver (timed), warms it up and times `REPS` solves of `jac · x = b`.
fn time<const D: usize, S: LinearSolver<D>>(
    build: impl FnOnce() -> S,
    jac: &BlockJacobian<D>,
    b: &[SVector<f64, D>],
) -> Timing<D> {
    let t = Instant::now();
    let mut solver = build();
    let setup = t.elapsed().as_secs_f64();
    let mut x = b.to_vec();
    let a0 = allocations();
    solver.solve(jac, &mut x).expect("warm-up solve");
    let first_allocs = allocations() - a0;
    let mut times = Vec::with_capacity(REPS);
    let mut allocs = 0;
    for _ in 0..REPS {
        x.copy_from_slice(b);
        let a0 = allocations();
        let t = Instant::now();
        solver.solve(jac, &mut x).expect("solve");
        times.push(t.elapsed().as_secs_f64());
        allocs += allocations() - a0;
    }
    times.sort_by(f64::total_cmp);
    Timing {
        setup,
        median: times[REPS / 2],
        min: times[0],
        first_allocs,
        allocs,
        x,
    }
}

/// `‖J x − b‖ / ‖b‖`.
fn residual<const D: usize>(
    mesh: &Mesh,
    jac: &BlockJacobian<D>,
    x: &[SVector<f64, D>],
    b: &[SVector<f64, D>],
) -> f64 {
    let mut jx = vec![SVector::zeros(); x.len()];
    jac.mul(mesh, x, &mut jx);
    let r: f64 = jx.iter().zip(b).map(|(a, c)| (a - c).norm_squared()).sum();
    let n: f64 = b.iter().map(|c| c.norm_squared()).sum();
    (r / n).sqrt()
}

fn rel_diff<const D: usize>(x: &[SVector<f64, D>], y: &[SVector<f64, D>]) -> f64 {
    let d: f64 = x.iter().zip(y).map(|(a, c)| (a - c).norm_squared()).sum();
    let n: f64 = y.iter().map(|c| c.norm_squared()).sum();
    (d / n).sqrt()
}

fn row<const D: usize>(design: &str, mesh: &str, n_el: usize, t: &Timing<D>) {
    println!(
        "{design:>17} {mesh:>6} {D:>2} {n_el:>8} {:>11.3e} {:>10.3e} {:>10.1} {:>9.3} {:>7} {:>7}",
        t.median,
        t.min,
        t.median * 1e9 / n_el as f64,
        t.setup,
        t.first_allocs,
        t.allocs
    );
}

fn run<const D: usize>(net: &Mesh, chain: &Mesh) {
    let mut rng = Rng(0x5EED + D as u64);
    let jac = random_jac::<D>(net, &mut rng);
    let b: Vec<SVector<f64, D>> = (0..net.n_nodes())
        .map(|_| SVector::from_fn(|_, _| rng.sym()))
        .collect();
    let n_el = net.n_elements();
    let lu = time(|| SparseLu::<D>::new(net), &jac, &b);
    row("sparse_lu", "net", n_el, &lu);
    let ws = time(|| whole_supernodal::<D>(net), &jac, &b);
    row("(faer supernodal)", "net", n_el, &ws);
    let nw = time(|| NetworkSolver::<D>::new(net), &jac, &b);
    row("network", "net", n_el, &nw);
    let nf = time(
        || NetworkSolver::<D>::with_junction_lu(net, JunctionLu::Simplicial),
        &jac,
        &b,
    );
    row("network (simpl.)", "net", n_el, &nf);
    for (name, t) in [
        ("whole supernodal", &ws),
        ("network", &nw),
        ("network (simpl.)", &nf),
    ] {
        let diff = rel_diff(&t.x, &lu.x);
        let res = residual(net, &jac, &t.x, &b);
        println!(
            "{:>17} {name}: ‖x − x_sparse_lu‖/‖x_sparse_lu‖ = {diff:.1e}, ‖Jx − b‖/‖b‖ = {res:.1e}",
            ""
        );
        assert!(diff <= 1e-10, "{name} and sparse LU disagree: {diff:e}");
    }
    println!(
        "{:>17} sparse_lu: ‖Jx − b‖/‖b‖ = {:.1e}",
        "",
        residual(net, &jac, &lu.x, &b)
    );
    for (name, t) in [("network", &nw), ("network (simpl.)", &nf)] {
        assert_eq!(t.first_allocs + t.allocs, 0, "the {name} solve allocated");
    }

    let cjac = random_jac::<D>(chain, &mut rng);
    let cb: Vec<SVector<f64, D>> = (0..chain.n_nodes())
        .map(|_| SVector::from_fn(|_, _| rng.sym()))
        .collect();
    let bt = time(
        || BlockTridiagonal::<D>::new(chain).expect("chain"),
        &cjac,
        &cb,
    );
    row("block_tridiagonal", "chain", chain.n_elements(), &bt);
    let nc = time(|| NetworkSolver::<D>::new(chain), &cjac, &cb);
    row("network", "chain", chain.n_elements(), &nc);
    assert!(
        rel_diff(&nc.x, &bt.x) <= 1e-10,
        "network and block Thomas disagree"
    );
}

fn main() {
    let net = grid_net(50, 50, 20, 10);
    let chain = Mesh::uniform_chain(net.n_elements(), 1.0).expect("chain");
    let probe = NetworkSolver::<1>::new(&net);
    println!(
        "net: {} elements, {} nodes; {} junctions, {} segments, {} interior nodes",
        net.n_elements(),
        net.n_nodes(),
        probe.n_junctions(),
        probe.n_segments(),
        probe.n_interior()
    );
    println!(
        "median and minimum of {REPS} solves (factor + solve) after one warm-up; ns/elem of \
         the median; setup = new()"
    );
    println!(
        "{:>17} {:>6} {:>2} {:>8} {:>11} {:>10} {:>10} {:>9} {:>7} {:>7}",
        "design",
        "mesh",
        "D",
        "elements",
        "s/solve",
        "min s",
        "ns/elem",
        "setup s",
        "1st",
        "allocs"
    );
    run::<3>(&net, &chain);
    run::<2>(&net, &chain);
}
