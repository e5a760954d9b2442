//! Fixtures shared by the tests and benchmarks of phstring and of the crates built on it
//! (cargo feature `testing`; not part of the default build).
//!
//! Each fixture is a set-up that more than one test or benchmark uses, written once so that
//! they stay the same problem:
//!
//! * [`hanging_chain`]: a chain hanging from a fixed node under gravity, with a tip mass;
//! * [`between_supports`]: a straight string at rest between two fixed supports;
//! * [`platform`]: a platform hanging from four steel cables, with springs and a heaving
//!   fairlead (the network of `examples/platform_3d.toml`);
//! * [`grid_net`]: the mesh of a net of crossing strings, for the linear solvers;
//! * [`catenary_on_seabed`]: the elastic catenary with a grounded length on a rigid,
//!   frictionless seabed (closed form);
//! * [`CountingAllocator`], [`allocations`] and [`live_bytes`]: a global allocator that counts
//!   the allocations and the live bytes of each thread.
//!
//! Units are SI (m, s, kg, N) as everywhere in the crate; gravity is [`G`] along the last
//! axis, downwards.
#![allow(unsafe_code)] // a global allocator needs `unsafe impl`

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use crate::{
    Boundary, Fixed, MassMatrix, Material, Mesh, Motion, Network, NetworkBuilder, PointMass,
    Problem, State, StringSpec, Vector,
};

/// Standard gravity [m/s²] of the fixtures.
pub const G: f64 = 9.81;

/// The unit vector downwards: `−e_{D−1}` (the last axis points up).
pub fn down<const D: usize>() -> Vector<D> {
    let mut down = Vector::<D>::zeros();
    down[D - 1] = -1.0;
    down
}

/// A chain of `n` elements of reference length `len` [m] hanging from node 0, fixed at the
/// origin, started straight and stress-free along `dir` (its end at `dir · len`), under
/// gravity `G ρA` per metre along [`down`], consistent mass, with a tip mass `tip` [kg] (its
/// weight `G tip` along [`down`]) at the last node when `tip > 0`.
pub fn hanging_chain<const D: usize>(
    n: usize,
    len: f64,
    material: Material,
    rho_a: f64,
    tip: f64,
    dir: Vector<D>,
) -> Problem<D, Material> {
    let mesh = Mesh::uniform_chain(n, len).unwrap();
    let initial = State::straight(&mesh, Vector::zeros(), dir * len);
    Problem {
        mesh,
        initial,
        material,
        rho_a,
        body_force: down::<D>() * (G * rho_a),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            fixed: vec![Fixed::node(0)],
            ..Default::default()
        },
        point_masses: if tip > 0.0 {
            vec![PointMass {
                node: n,
                mass: tip,
                weight: down::<D>() * (G * tip),
            }]
        } else {
            vec![]
        },
    }
}

/// A string of `n` elements of reference length `len` [m], straight and at rest from the
/// origin to `end`, both ends fixed, with the body force `body_force` [N/m] per unit
/// reference length, consistent mass, no loads and no point masses. With `|end| > len` it
/// is taut (stretch `|end|/len`); with `|end| < len` and gravity it sags into a catenary.
pub fn between_supports<const D: usize>(
    n: usize,
    len: f64,
    end: Vector<D>,
    material: Material,
    rho_a: f64,
    body_force: Vector<D>,
) -> Problem<D, Material> {
    let mesh = Mesh::uniform_chain(n, len).unwrap();
    let initial = State::straight(&mesh, Vector::zeros(), end);
    Problem {
        mesh,
        initial,
        material,
        rho_a,
        body_force,
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            fixed: vec![Fixed::node(0), Fixed::node(n)],
            ..Default::default()
        },
        point_masses: vec![],
    }
}

/// The fairlead heave of the [`platform`]'s corner 0 [m]: from 10 m up by 0.3 m and back in
/// a 5 s period, starting at rest.
pub fn platform_heave(t: f64) -> f64 {
    10.0 + 0.15 * (1.0 - (2.0 * std::f64::consts::PI * t / 5.0).cos())
}

/// A 1.5 t platform (node returned second) hanging from four steel cables (tension-only,
/// EA = 5e7 N, 2 kg/m, 12 elements each, named `cable0` … `cable3`) from the corners of a
/// 10 m × 8 m frame 10 m above it (nodes 1–4), released stress-free, so that it drops and
/// bounces. Corner 0 heaves ([`platform_heave`], its `z` prescribed, `x` and `y` fixed), the
/// other corners are fixed; a spring `tie` (5e3 N/m, 0.5 m rest length) ties the platform
/// sideways to a fixed point, and a spring `link` (2e4 N/m) links the middles of cables 0 and
/// 1; both springs start relaxed.
pub fn platform() -> (Network<3, Material>, usize) {
    let g = Vector::<3>::new(0.0, 0.0, -G);
    let cable = |name: String| StringSpec {
        name,
        material: Material::tension_only_linear(5e7),
        rho_a: 2.0,
        mass: MassMatrix::Consistent,
        body_force: g * 2.0,
        prestretch: 1.0,
    };
    let mut b = NetworkBuilder::<3, Material>::new();
    let p = b.node(Vector::<3>::new(0.3, -0.2, 0.0));
    let corners: Vec<usize> = [(-5.0, -4.0), (5.0, -4.0), (5.0, 4.0), (-5.0, 4.0)]
        .iter()
        .map(|&(x, y)| b.node(Vector::<3>::new(x, y, 10.0)))
        .collect();
    let cables: Vec<usize> = corners
        .iter()
        .enumerate()
        .map(|(k, &c)| b.string(cable(format!("cable{k}")), &[c, p], 12).unwrap())
        .collect();
    let mid = |b: &NetworkBuilder<3, Material>, g: usize| b.group_nodes(g).unwrap()[6];
    let (m0, m1) = (mid(&b, cables[0]), mid(&b, cables[1]));
    let gap = (b.position(m1).unwrap() - b.position(m0).unwrap()).norm();
    b.spring("link", m0, m1, 2e4, gap).unwrap();
    b.spring_to_point("tie", p, Vector::<3>::new(0.8, -0.2, 0.0), 5e3, 0.5)
        .unwrap();
    let mut fixed: Vec<Fixed<3>> = corners[1..].iter().map(|&c| Fixed::node(c)).collect();
    fixed.push(Fixed {
        node: corners[0],
        components: [true, true, false],
    });
    let net = b
        .build(
            Boundary {
                fixed,
                loads: vec![],
                motions: vec![Motion::new(corners[0], 2, platform_heave)],
                feedback: vec![],
            },
            vec![PointMass {
                node: p,
                mass: 1500.0,
                weight: g * 1500.0,
            }],
        )
        .unwrap();
    (net, p)
}

/// The mesh of a net: `nh` horizontal and `nv` vertical strings crossing at shared nodes
/// every `spacing` elements, with free tails of `tail` elements beyond the outermost
/// crossings; every element has reference length 1. Crossings are nodes `0 … nh·nv − 1`
/// (row by row), the other nodes are numbered string by string, horizontal strings first.
pub fn grid_net(nh: usize, nv: usize, spacing: usize, tail: usize) -> Mesh {
    let mut els = Vec::new();
    let mut next = nh * nv;
    let mut string = |n_cross: usize, crossing: &dyn Fn(usize) -> usize| {
        let len = 2 * tail + spacing * (n_cross - 1);
        let mut prev = None;
        for pos in 0..=len {
            let node = if pos >= tail && (pos - tail).is_multiple_of(spacing) {
                crossing((pos - tail) / spacing)
            } else {
                next += 1;
                next - 1
            };
            if let Some(p) = prev {
                els.push([p, node]);
            }
            prev = Some(node);
        }
    };
    for h in 0..nh {
        string(nv, &|v| h * nv + v);
    }
    for v in 0..nv {
        string(nh, &|h| h * nv + v);
    }
    let n = els.len();
    Mesh::new(next, els, vec![1.0; n]).unwrap()
}

/// A global allocator that counts, per thread, the allocations (`alloc` and `realloc`
/// calls) and the bytes allocated and not yet freed, then lets the system allocator do the
/// work. Install it in a test or bench binary with
/// `#[global_allocator] static GLOBAL: CountingAllocator = CountingAllocator;` and read the
/// counts with [`allocations`] and [`live_bytes`]. Counting per thread means that another
/// thread allocating at the same time (as the test harness does) is not counted.
pub struct CountingAllocator;

thread_local! {
    /// Allocations made by this thread (const-initialized: reading it never allocates).
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
    /// Bytes allocated minus bytes freed by this thread.
    static LIVE: Cell<isize> = const { Cell::new(0) };
}

fn count(grow: isize) {
    // `try_with` fails only while the thread is being torn down; nothing to count then.
    let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
    let _ = LIVE.try_with(|c| c.set(c.get() + grow));
}

/// Allocations made so far by the calling thread (0 unless [`CountingAllocator`] is the
/// global allocator).
pub fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

/// Bytes allocated and not freed so far by the calling thread (0 unless
/// [`CountingAllocator`] is the global allocator).
pub fn live_bytes() -> isize {
    LIVE.with(Cell::get)
}

// SAFETY: every call is passed on unchanged to the system allocator; the counting touches
// only const-initialized thread-locals, which never allocate.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as isize);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        let _ = LIVE.try_with(|c| c.set(c.get() - layout.size() as isize));
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size as isize - layout.size() as isize);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// The elastic catenary of a line of unstretched length `L`, wet weight `w` [N/m] and axial
/// stiffness `EA` from an anchor on a rigid frictionless seabed to a fairlead `X` away and
/// `Hv` above the seabed, with a grounded length `L_b` (docs/method.md eq. (21.8); the
/// statics tests of phstring and of the MoorDyn decks compare with it): returns
/// `(H, V_F, L_b)`, [`crate::catenary::on_seabed`].
pub fn catenary_on_seabed(l: f64, w: f64, ea: f64, x: f64, hv: f64) -> (f64, f64, f64) {
    crate::catenary::on_seabed(l, w, ea, x, hv)
}
