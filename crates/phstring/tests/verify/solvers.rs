//! The two linear solvers agree on random well-posed block-tridiagonal systems,
//! and the sparse LU solves non-chain meshes.

use nalgebra::{SMatrix, SVector};
use phstring::Mesh;
use phstring::linsolve::{BlockJacobian, BlockTridiagonal, LinearSolver, SparseLu};
use proptest::prelude::*;

fn random_system<const D: usize>(
    mesh: &Mesh,
    vals: &[f64],
) -> (BlockJacobian<D>, Vec<SVector<f64, D>>) {
    let mut it = vals.iter().copied().cycle();
    let mut next = move || it.next().unwrap();
    let mut jac = BlockJacobian::<D>::zeros(mesh);
    for off in &mut jac.off {
        off[0] = SMatrix::from_fn(|_, _| next());
        off[1] = SMatrix::from_fn(|_, _| next());
    }
    // Block diagonal dominance makes the system well posed.
    for d in &mut jac.diag {
        *d = SMatrix::from_fn(|_, _| next()) + SMatrix::identity() * (4.0 * D as f64 + 4.0);
    }
    let b = (0..mesh.n_nodes())
        .map(|_| SVector::from_fn(|_, _| next()))
        .collect();
    (jac, b)
}

fn check<const D: usize>(n_el: usize, vals: &[f64]) {
    let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
    let (jac, b) = random_system::<D>(&mesh, vals);
    let mut x1 = b.clone();
    let mut x2 = b.clone();
    BlockTridiagonal::<D>::new(&mesh)
        .unwrap()
        .solve(&jac, &mut x1)
        .unwrap();
    SparseLu::<D>::new(&mesh).solve(&jac, &mut x2).unwrap();
    let norm = |x: &[SVector<f64, D>]| x.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
    let diff: Vec<_> = x1.iter().zip(&x2).map(|(a, b)| a - b).collect();
    let rel = norm(&diff) / norm(&x1);
    assert!(
        rel <= 1e-12,
        "D = {D}, n = {n_el}: relative difference {rel:e}"
    );
    // And x solves the system.
    let mut ax = vec![SVector::<f64, D>::zeros(); mesh.n_nodes()];
    jac.mul(&mesh, &x1, &mut ax);
    let res: Vec<_> = ax.iter().zip(&b).map(|(a, b)| a - b).collect();
    assert!(norm(&res) <= 1e-12 * norm(&b), "residual {:e}", norm(&res));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn block_tridiagonal_agrees_with_sparse_lu(
        n_el in 1usize..60,
        vals in proptest::collection::vec(-1.0f64..1.0, 64..256),
    ) {
        check::<1>(n_el, &vals);
        check::<2>(n_el, &vals);
        check::<3>(n_el, &vals);
    }
}

/// The twisted elimination meets in the middle: short chains of both parities, where the
/// top and bottom sweeps are empty or one node long.
#[test]
fn block_tridiagonal_short_chains() {
    let vals: Vec<f64> = (0..97)
        .map(|k| ((k * 37 % 101) as f64 / 50.0) - 1.0)
        .collect();
    for n_el in 1..=6 {
        check::<1>(n_el, &vals);
        check::<2>(n_el, &vals);
        check::<3>(n_el, &vals);
    }
}

/// A star of three strings sharing node 0 is not a chain: the block solver refuses it and the
/// sparse LU solves it.
#[test]
fn sparse_lu_solves_a_star_network() {
    let mesh = Mesh::new(4, vec![[0, 1], [0, 2], [0, 3]], vec![1.0; 3]).unwrap();
    assert!(!mesh.is_chain());
    assert!(BlockTridiagonal::<2>::new(&mesh).is_err());
    let vals: Vec<f64> = (0..97)
        .map(|i| ((i * 37 % 101) as f64 / 50.0) - 1.0)
        .collect();
    let (jac, b) = random_system::<2>(&mesh, &vals);
    let mut x = b.clone();
    SparseLu::<2>::new(&mesh).solve(&jac, &mut x).unwrap();
    let mut ax = vec![SVector::<f64, 2>::zeros(); 4];
    jac.mul(&mesh, &x, &mut ax);
    for (a, bi) in ax.iter().zip(&b) {
        assert!((a - bi).norm() <= 1e-13, "{a} vs {bi}");
    }
}
