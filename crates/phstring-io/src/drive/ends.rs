//! What the outputs of a run in water need of its scenario (validated): for
//! `end_tensions.csv` the hydrodynamic diameter of every string and the water (density,
//! gravity, seabed normal); for the drawings the water surface and the seabed.

use phstring::{Material, PhSystem};

use crate::output::{EndForces, EndWater};
use crate::scenario::{Components, ScenarioFile};
use crate::scene::{Scene, WaterLines};

/// Density of sea water [kg/m³], `water.density`'s default.
const SEA_WATER: f64 = 1025.0;

/// The end forces of the strings of `sys` built from the scenario `file` (validated) and
/// its `components`: each string's `diameter` from its material, the water's density, the
/// magnitude of `body_force.gravity` and the seabed's normal (normalized; vertical for a
/// flat seabed). `None` without strings.
pub fn end_forces<const D: usize>(
    file: &ScenarioFile,
    components: &Components,
    sys: &PhSystem<D, Material>,
) -> Option<EndForces> {
    let s = &file.scenario;
    let diameters: Vec<Option<f64>> = sys
        .groups()
        .iter()
        .map(|g| {
            let st = components
                .strings
                .iter()
                .find(|st| st.elements == [g.elements.start, g.elements.end])?;
            let spec = match &s.material {
                Some(m) if s.materials.is_empty() => Some(m),
                _ => s.materials.get(&st.material),
            }?;
            spec.get_ref().diameter.as_ref().map(|d| *d.get_ref())
        })
        .collect();
    let water = s.water.as_ref().map(|w| {
        let g = s.body_force.gravity.as_ref().map_or(0.0, |g| {
            g.get_ref().iter().map(|x| x * x).sum::<f64>().sqrt()
        });
        let seabed_normal = seabed_plane(file, D).map(|(_, n)| n);
        EndWater {
            density: w
                .get_ref()
                .density
                .as_ref()
                .map_or(SEA_WATER, |d| *d.get_ref()),
            gravity: g,
            seabed_normal,
        }
    });
    EndForces::new(sys, &diameters, water)
}

/// The seabed of the scenario `file` as a point and its unit upward normal, `dimension`
/// components each (the flat seabed at `−water.depth`, or `seabed.point` and
/// `seabed.normal`); `None` without `[seabed]`.
fn seabed_plane(file: &ScenarioFile, dimension: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let s = &file.scenario;
    let sb = s.seabed.as_ref()?.get_ref();
    let depth = s
        .water
        .as_ref()?
        .get_ref()
        .depth
        .as_ref()
        .map(|d| *d.get_ref());
    let mut point = match &sb.point {
        Some(p) => p.get_ref().clone(),
        None => {
            let mut p = vec![0.0; dimension];
            *p.last_mut()? = -depth?;
            p
        }
    };
    point.resize(dimension, 0.0);
    let mut normal = match &sb.normal {
        Some(n) => n.get_ref().clone(),
        None => vec![0.0; dimension],
    };
    normal.resize(dimension, 0.0);
    if normal.iter().all(|x| *x == 0.0) {
        *normal.last_mut()? = 1.0;
    }
    let len = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
    Some((point, normal.iter().map(|x| x / len).collect()))
}

/// How the configuration of a run of `file` is drawn: in the side view `side` of a 3D run
/// (see [`crate::scene`]), with the water surface and the seabed if it is in water.
pub fn scene(file: &ScenarioFile, side: Option<[f64; 2]>) -> Scene {
    let mut scene = Scene { side, water: None };
    if file.scenario.water.is_some() {
        let dimension = usize::try_from(*file.scenario.dimension.get_ref()).unwrap_or(0);
        let seabed = seabed_plane(file, dimension);
        let lines = WaterLines::new(
            &scene,
            seabed.as_ref().map(|(p, n)| (p.as_slice(), n.as_slice())),
        );
        scene.water = Some(lines);
    }
    scene
}
