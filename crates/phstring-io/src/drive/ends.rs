//! What the outputs of a run in water need of its scenario (validated): for
//! `end_tensions.csv` the hydrodynamic diameter of every string and the water (density,
//! gravity, seabed normal); for the drawings the water surface and the seabed.

use phstring::{Material, PhSystem};

use crate::files::CHANNELS_FILE;
use crate::output::{ChannelString, ChannelTable, EndForces, EndWater};
use crate::scenario::{Components, ScenarioError, ScenarioFile};
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

/// The channel table of `output.channels` of the scenario `file` (validated) and its file
/// name, over the strings and named nodes of `components` and the end forces `ends`;
/// `None` without channels. A channel naming a line, node or point the run does not have
/// is an error at its entry.
pub fn channel_table(
    file: &ScenarioFile,
    components: &Components,
    ends: Option<&EndForces>,
) -> Result<Option<(ChannelTable, String)>, ScenarioError> {
    let out = &file.scenario.output;
    if out.channels.is_empty() {
        return Ok(None);
    }
    let channels = out
        .channels
        .iter()
        .enumerate()
        .map(|(i, c)| crate::channels::parse(c.get_ref()).map_err(|e| file.channel_error(i, e)))
        .collect::<Result<Vec<_>, _>>()?;
    let Some(ends) = ends else {
        return Err(file.channel_error(0, "reads lines, but the run has no strings".into()));
    };
    // Node j of line i is the j-th node along the string; from a deck (a `[deck]`
    // record), MoorDyn's node j: the j-th node of its path, also on a refined mesh.
    let deck = file.scenario.deck.is_some();
    let strings: Vec<ChannelString> = components
        .strings
        .iter()
        .map(|s| ChannelString {
            path_nodes: if deck { s.path_nodes.clone() } else { along(s) },
            first_element: s.elements[0],
            elements_per_span: if deck { s.elements_per_span } else { 1 },
        })
        .collect();
    let point = |k: u32| {
        let name = format!("point{k}");
        components
            .nodes
            .iter()
            .find(|n| n.name == name)
            .map(|n| n.node)
    };
    let table = ChannelTable::new(&channels, &strings, point, ends.clone())
        .map_err(|(i, e)| file.channel_error(i, e))?;
    let name = out
        .channels_file
        .as_ref()
        .map_or_else(|| CHANNELS_FILE.to_string(), |f| f.get_ref().clone());
    Ok(Some((table, name)))
}

/// The mesh nodes along string `s`, from its first path node to its last.
fn along(s: &crate::scenario::StringComponent) -> Vec<usize> {
    // Span k's interior nodes are the k-th run of `elements_per_span − 1` consecutive
    // indices from `interior_nodes[0]`.
    let per = s.elements_per_span.saturating_sub(1);
    let mut nodes = Vec::with_capacity(s.nodes);
    for (k, &start) in s.path_nodes.iter().enumerate() {
        nodes.push(start);
        if k + 1 < s.path_nodes.len() {
            let first = s.interior_nodes[0] + k * per;
            nodes.extend(first..first + per);
        }
    }
    nodes
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

/// How the configuration of a run of `file` is drawn: in the view its `writers` chose (the
/// side view of a 3D run or one plane per line, see [`crate::scene`]), with the water
/// surface and the seabed if it is in water, and the nodes on the seabed at the snapshots
/// `writers` took. The contact test for the animation's frames is left to the caller
/// ([`Scene::contact`]).
pub fn scene(file: &ScenarioFile, writers: &crate::output::Writers) -> Scene {
    let mut scene = Scene {
        side: writers.side(),
        lines: writers.lines().cloned(),
        grounded: writers.grounded().to_vec(),
        ..Scene::default()
    };
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

/// Adds the rigid bodies of `sim` to `scene` (their boxes, [`crate::body_shape`]) with their
/// poses at the configuration `snapshots` read back from `dir/bodies.csv`; returns the
/// warning if those cannot be read (the bodies are then left out of the configuration
/// plot). Nothing for a run without bodies.
pub fn add_bodies<const D: usize>(
    scene: &mut Scene,
    sim: &phstring::Simulation<D, Material>,
    dir: &std::path::Path,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> Option<String> {
    scene.bodies = crate::body_shape::BodyBox::of(sim);
    if scene.bodies.is_empty() || snapshots.is_empty() {
        return None;
    }
    let times: Vec<f64> = snapshots.iter().map(|s| s.0).collect();
    let path = dir.join(crate::files::BODIES_FILE);
    match crate::body_shape::read_poses(&path, scene.bodies.len(), &times) {
        Ok(poses) => {
            scene.body_poses = poses;
            None
        }
        Err(e) => Some(format!(
            "rigid bodies not drawn in the configuration plot: {e}"
        )),
    }
}
