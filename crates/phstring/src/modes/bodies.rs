//! Natural modes with rigid bodies (docs/method.md §22, "Modes with rigid bodies"): the
//! generalized eigenproblem on the free node components and each body's translation and
//! turn, the nodes fixed to a body moving with it, solved dense.

use faer::Mat;

use super::{
    Character, DENSE_LIMIT, Mode, Modes, ModesError, classify, lumped_mass, node_tangents,
};
use crate::assembly::{free_dofs, mass_blocks};
use crate::body::{BodyState, Mat3, Vec3, embed, skew};
use crate::eigen;
use crate::material::StoredEnergy;
use crate::statics::{body_coordinates, body_hessian};
use crate::system::{PhSystem, Vector};

/// How each node moves with the coordinates: per node, `(coordinate, its column of the
/// node's displacement)` pairs (a free component: its unit vector; a node fixed to a body:
/// the columns of `[I, −[a×] R₀/ρ]`, `a` its arm at the rest pose).
pub(crate) type NodeMap<const D: usize> = Vec<Vec<(usize, Vector<D>)>>;

/// The unit vector along axis `k`.
fn unit<const D: usize>(k: usize) -> Vector<D> {
    Vector::<D>::from_fn(|i, _| if i == k { 1.0 } else { 0.0 })
}

pub(crate) fn node_map<const D: usize, M>(
    sys: &PhSystem<D, M>,
    poses: &[BodyState],
    n_free: usize,
) -> NodeMap<D> {
    let (dof, _) = free_dofs(sys);
    let per = body_coordinates(D);
    let turn = |a: &Vec3, r0: &Mat3, rho: f64| -skew(a) * r0 / rho;
    (0..sys.mesh.n_nodes())
        .map(|i| {
            let mut cols: Vec<(usize, Vector<D>)> = (0..D)
                .filter_map(|k| dof[i * D + k].map(|j| (j, unit::<D>(k))))
                .collect();
            if let Some((b, k)) = sys.attached.get(i).copied().flatten() {
                let model = &sys.bodies[b];
                let r0: Mat3 = poses[b].orientation.to_rotation_matrix().into_inner();
                let a = r0 * model.attachments[k].1;
                let t = turn(&a, &r0, model.gyration());
                let base = n_free + b * per;
                cols.extend((0..D).map(|m| (base + m, unit::<D>(m))));
                if D == 3 {
                    cols.extend(
                        (0..3).map(|m| (base + 3 + m, Vector::<D>::from_fn(|r, _| t[(r, m)]))),
                    );
                } else {
                    cols.push((base + 2, Vector::<D>::from_fn(|r, _| t[(r, 2)])));
                }
            }
            cols
        })
        .collect()
}

/// The strings' mass matrix [kg] (and the point masses') on the coordinates of `map` (`size`
/// of them).
pub(crate) fn strings_mass<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    map: &NodeMap<D>,
    size: usize,
) -> Mat<f64> {
    let mut m = Mat::<f64>::zeros(size, size);
    add_through(&mut m, map, &mass_blocks(sys), &sys.mesh);
    m
}

/// Adds the node-block matrix `blocks` (over `mesh`) carried through `map` to `m`.
pub(crate) fn add_through<const D: usize>(
    m: &mut Mat<f64>,
    map: &NodeMap<D>,
    blocks: &crate::linsolve::BlockJacobian<D>,
    mesh: &crate::mesh::Mesh,
) {
    let mut add = |a: usize, b: usize, blk: &crate::linsolve::Block<D>| {
        for &(r, u) in &map[a] {
            for &(c, v) in &map[b] {
                m[(r, c)] += u.dot(&(blk * v));
            }
        }
    };
    for (i, d) in blocks.diag.iter().enumerate() {
        add(i, i, d);
    }
    for (&[a, b], off) in mesh.elements().iter().zip(&blocks.off) {
        add(a, b, &off[0]);
        add(b, a, &off[1]);
    }
}

/// Each body's mass matrix at its rest pose `poses` (with its added mass, and an added-mass
/// matrix's couplings, [`crate::body::BodyModel::rest_mass`]) on its translation and its
/// scaled turn `ρ w` (the turn's rows and columns divided by `ρ`), on the `size` coordinates.
pub(crate) fn body_mass<const D: usize, M>(
    sys: &PhSystem<D, M>,
    poses: &[BodyState],
    n_free: usize,
    size: usize,
) -> Mat<f64> {
    let mut m = Mat::<f64>::zeros(size, size);
    let per = body_coordinates(D);
    for (b, model) in sys.bodies.iter().enumerate() {
        let base = n_free + b * per;
        let rho = model.gyration();
        let rot: Mat3 = poses[b].orientation.to_rotation_matrix().into_inner();
        let blocks = model.rest_mass(&rot);
        // The coordinates of the body: translation components, then turn components, as
        // (index among the body's coordinates, index in the 3-vector, row scale).
        let coords: Vec<(usize, usize, usize, f64)> = if D == 3 {
            (0..3)
                .map(|k| (k, 0, k, 1.0))
                .chain((0..3).map(|k| (3 + k, 1, k, 1.0 / rho)))
                .collect()
        } else {
            vec![(0, 0, 0, 1.0), (1, 0, 1, 1.0), (2, 1, 2, 1.0 / rho)]
        };
        for &(i, bi, ki, si) in &coords {
            for &(j, bj, kj, sj) in &coords {
                m[(base + i, base + j)] += blocks[bi][bj][(ki, kj)] * si * sj;
            }
        }
    }
    m
}

/// The `count` lowest modes about the rest state of node positions `r` [m] and body poses
/// `poses`, with the bodies: dense, up to [`DENSE_LIMIT`] coordinates.
pub(super) fn modes_with_bodies<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    poses: &[BodyState],
    count: usize,
) -> Result<Modes<D>, ModesError> {
    let (size, triplets) = body_hessian(sys, r, poses).ok_or(ModesError::NotStable)?;
    if size > DENSE_LIMIT {
        return Err(ModesError::TooLarge {
            size,
            limit: DENSE_LIMIT,
        });
    }
    let (_, n_free) = free_dofs(sys);
    let mut k = Mat::<f64>::zeros(size, size);
    for t in &triplets {
        k[(t.row, t.col)] += t.val;
    }
    // A stable rest state: the potential's Hessian is positive definite.
    if k.llt(faer::Side::Lower).is_err() {
        return Err(ModesError::NotStable);
    }
    let map = node_map(sys, poses, n_free);
    let m = strings_mass(sys, &map, size);
    let bm = body_mass(sys, poses, n_free, size);
    let (values, vecs) = eigen::dense_generalized(&k, &(&m + &bm))?;
    let tangents = node_tangents(sys, r);
    let node_mass = lumped_mass(sys);
    if values.first().is_none_or(|&v| v <= 0.0) {
        return Err(ModesError::NotStable);
    }
    let count = count.min(size);
    let per = body_coordinates(D);
    let modes = (0..count)
        .map(|c| {
            let x: Vec<f64> = (0..size).map(|i| vecs[(i, c)]).collect();
            let shape: Vec<Vector<D>> = map
                .iter()
                .map(|cols| {
                    cols.iter()
                        .fold(Vector::<D>::zeros(), |s, (j, v)| s + v * x[*j])
                })
                .collect();
            let bodies: Vec<(Vec3, Vec3)> = sys
                .bodies
                .iter()
                .enumerate()
                .map(|(b, model)| {
                    let base = n_free + b * per;
                    let dx = embed(&Vector::<D>::from_fn(|k, _| x[base + k]));
                    let w = if D == 3 {
                        Vec3::new(x[base + 3], x[base + 4], x[base + 5])
                    } else {
                        Vec3::new(0.0, 0.0, x[base + 2])
                    } / model.gyration();
                    (dx, poses[b].orientation * w)
                })
                .collect();
            // The bodies' share of the mode's kinetic energy xᵀ M x = 1 (their own masses
            // and inertias).
            let body_energy: f64 = (n_free..size)
                .map(|i| {
                    (n_free..size)
                        .map(|j| x[i] * bm[(i, j)] * x[j])
                        .sum::<f64>()
                })
                .sum();
            let (axial_share, character) = classify(&shape, &tangents, &node_mass);
            Mode {
                omega: values[c].max(0.0).sqrt(),
                shape,
                axial_share,
                character: if body_energy >= 0.5 {
                    Character::Body
                } else {
                    character
                },
                bodies,
            }
        })
        .collect();
    Ok(Modes {
        modes,
        method: "dense",
        solves: 0,
    })
}
