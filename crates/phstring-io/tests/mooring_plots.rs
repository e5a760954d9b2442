//! How runs in water are drawn, on the examples' moorings started from their static
//! equilibrium: the nodes marked "on the seabed" are exactly those below it (the seabed
//! contact of the energy), the grounded length is the catenary's, and a spread mooring is
//! drawn one vertical plane per line, each line at its own horizontal distances, the lines
//! side by side. A dry run draws what it drew before.

use std::path::{Path, PathBuf};

use phstring::{ByDim, Material, Simulation};
use phstring_io::figures::draw_plots;
use phstring_io::history::History;
use phstring_io::moordyn;
use phstring_io::output::Writers;
use phstring_io::plot;
use phstring_io::scenario::ScenarioFile;
use phstring_io::scene::Scene;

/// The example file `name` (relative to `examples/`).
fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// A fresh folder for the outputs of test `name`.
fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "phstring-mooring-plots-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The example `name` with the settings `sets`.
fn read(name: &str, sets: &[&str]) -> ScenarioFile {
    let path = example(name);
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    moordyn::load_scenario(&path, &sets, &[]).unwrap().file
}

/// The simulation of the 2D scenario `file` started from its static equilibrium.
fn started_2d(file: &ScenarioFile) -> Simulation<2, Material> {
    match file.setup().unwrap() {
        ByDim::D2(s) => s.start(true, None).unwrap().0.problem,
        _ => panic!("not a 2D scenario"),
    }
}

/// The simulation of the 3D scenario `file` started from its static equilibrium.
fn started_3d(file: &ScenarioFile) -> Simulation<3, Material> {
    match file.setup().unwrap() {
        ByDim::D3(s) => s.start(true, None).unwrap().0.problem,
        _ => panic!("not a 3D scenario"),
    }
}

/// The nodes of `sim` below the flat seabed `depth` [m] down, those exactly on it (the
/// anchors), and the smallest distance from it of any other node [m] (how far the test is
/// from a node on the edge).
fn below<const D: usize>(sim: &Simulation<D, Material>, depth: f64) -> (Vec<usize>, usize, f64) {
    let z = |i: usize| sim.state().r[i][D - 1];
    let n = sim.state().r.len();
    let nodes = (0..n).filter(|&i| z(i) < -depth).collect();
    let on = (0..n).filter(|&i| z(i) == -depth).count();
    let margin = (0..n)
        .map(|i| (z(i) + depth).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    (nodes, on, margin)
}

/// Horizontal tension `H` [N] of an inextensible catenary of length `l` [m] and wet weight
/// `w` [N/m] from a flat seabed (anchor on it) to a fairlead `h` [m] above it and `x` [m]
/// away: suspended length `l_s = √(h² + 2 h H / w)`, span `l − l_s + (H/w) asinh(w l_s/H)`
/// (bisection on `H`).
fn catenary_h(l: f64, w: f64, h: f64, x: f64) -> f64 {
    let span = |t: f64| {
        let ls = (h * h + 2.0 * h * t / w).sqrt();
        l - ls + t / w * (w * ls / t).asinh()
    };
    let (mut lo, mut hi) = (1.0, 1e7);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if span(mid) < x { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

#[test]
fn the_nodes_marked_on_the_seabed_are_those_below_it() {
    // 180 m of wire rope (25 kg/m, d = 76 mm, EA = 5e8 N) from an anchor on a seabed 60 m
    // down to a fairlead 5 m below the surface, 150 m away; 180 elements of 1 m.
    let file = read("mooring_line.toml", &["time.h=0.01"]);
    let mut sim = started_2d(&file);
    let dir = temp("grounded");
    let mut w = Writers::start(&dir, &sim, 1, false, false, vec![0.0, 0.05]).unwrap();
    for _ in 0..5 {
        let r = sim.step().unwrap();
        w.step(&sim, &r).unwrap();
    }
    let (t1, _) = w.snapshots()[1];
    assert!((t1 - 0.05).abs() < 1e-9, "{t1}");
    // The last snapshot is the state now.
    let (nodes, on, margin) = below(&sim, 60.0);
    let g = w.grounded()[1].clone();
    println!(
        "{} of {} nodes below the seabed, {on} on it, the nearest other {margin:.3e} m from it; grounded {} m",
        g.nodes.len(),
        sim.state().r.len(),
        g.lengths[0]
    );
    assert_eq!(g.nodes, nodes);
    // Every other node is at least 0.1 mm off the seabed (the grounded ones sink by
    // w/(k d) ≈ 0.9 mm): the count is that of z ≤ −depth − 1e-6 m, not a knife edge.
    assert!(margin > 1e-4, "{margin}");
    let deep = (0..sim.state().r.len()).filter(|&i| sim.state().r[i][1] <= -60.0 - 1e-6);
    assert_eq!(deep.count(), g.nodes.len());
    assert!(nodes.len() > 50, "{}", nodes.len());
    // The grounded length is the catenary's `l − l_s` to about an element (1 m): the mesh
    // lumps the touchdown on a node, and the line stretches by T/EA ≈ 3e-5.
    let wet = (25.0 - 1025.0 * std::f64::consts::PI * 0.076 * 0.076 / 4.0) * 9.81;
    let h = catenary_h(180.0, wet, 55.0, 150.0);
    let ls = (55.0f64 * 55.0 + 2.0 * 55.0 * h / wet).sqrt();
    println!("catenary: grounded {} m", 180.0 - ls);
    assert!(
        (g.lengths[0] - (180.0 - ls)).abs() < 114.583333 / 90.0,
        "{} vs {}",
        g.lengths[0],
        180.0 - ls
    );
    // Drawn: a triangle at every such node of every snapshot, where the node is drawn.
    let drawn = plot::grounded_points(w.snapshots(), w.grounded());
    let expected: Vec<(f64, f64)> = w
        .snapshots()
        .iter()
        .zip(w.grounded())
        .flat_map(|((_, pts), g)| g.nodes.iter().map(|&i| (pts[i][0], pts[i][1])))
        .collect();
    assert_eq!(drawn, expected);
    let last: Vec<(f64, f64)> = nodes
        .iter()
        .map(|&i| (sim.state().r[i][0], sim.state().r[i][1]))
        .collect();
    assert_eq!(drawn[drawn.len() - last.len()..], last[..]);
    // The figure names them, with the grounded length at the last snapshot.
    w.finish(&sim).unwrap();
    let scene = phstring_io::drive::ends::scene(&file, &w);
    assert_eq!(scene.grounded, w.grounded());
    let svg = configuration_svg(&dir, &w, &scene);
    // Its topology is a network (nodes numbered by the named points first): the length
    // follows the string's name.
    let label = format!("line: {:.1} m on the seabed", g.lengths[0]);
    assert!(svg.contains(&label), "{label}");
    assert!(svg.contains("on the seabed (lengths at t = 0.05 s)"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The configuration plot of the run in `dir` drawn in `scene` (its SVG).
fn configuration_svg(dir: &Path, w: &Writers, scene: &Scene) -> String {
    let h = History {
        t: vec![0.0, 1.0],
        kinetic: vec![0.0, 1.0],
        potential: vec![1.0, 0.0],
        hamiltonian: vec![1.0, 1.0],
        increment_t: vec![1.0],
        increment: vec![1e-15],
        snapshots: w.snapshots().to_vec(),
        water: None,
    };
    let r = draw_plots(dir, 3, ("t", scene), None, Ok(&h), None);
    assert!(r.written.contains(&"configuration".to_string()), "{r:?}");
    std::fs::read_to_string(dir.join("configuration.svg")).unwrap()
}

#[test]
fn the_spar_lines_are_drawn_one_plane_each_side_by_side() {
    // The OC3 spar's three lines (902.2 m, 77.7 kg/m, EA = 384.243e6 N) from anchors
    // 853.87 m out on a seabed 320 m down to fairleads 5.2 m out, 70 m down, 120° apart.
    let file = read("moordyn/spar_oc3_v2.dat", &[]);
    let mut sim = started_3d(&file);
    let dir = temp("spar");
    let mut w = Writers::start(&dir, &sim, 1, false, false, vec![0.0, 0.004]).unwrap();
    for _ in 0..2 {
        let r = sim.step().unwrap();
        w.step(&sim, &r).unwrap();
    }
    let view = w
        .lines()
        .expect("a spread mooring is drawn one plane per line")
        .clone();
    // 1.1 × 848.67 m rounds up to strips of 1000 m.
    assert_eq!(view.width, 1000.0);
    let anchors: [[f64; 2]; 3] = [[853.87, 0.0], [-426.935, 739.47], [-426.935, -739.47]];
    let fairleads: [[f64; 2]; 3] = [[5.2, 0.0], [-2.6, 4.5033], [-2.6, -4.5033]];
    let sys = sim.system();
    let mut ranges = Vec::new();
    for (k, group) in sys.groups().iter().enumerate() {
        let els = &sys.mesh().elements()[group.elements.clone()];
        let (first, last) = (els[0][0], els[els.len() - 1][1]);
        for (_, pts) in w.snapshots() {
            // Anchor at path start (AttachA), fairlead at its end (AttachB).
            let d = (anchors[k][0] - fairleads[k][0]).hypot(anchors[k][1] - fairleads[k][1]);
            let (pa, pf) = (pts[first], pts[last]);
            assert!((pf[0] - 1000.0 * k as f64).abs() < 1e-6, "line {k}: {pf:?}");
            assert!(
                (pa[0] - pf[0] - d).abs() < 1e-6,
                "line {k}: {pa:?} {pf:?} {d}"
            );
            assert!((pa[1] + 320.0).abs() < 0.05 && (pf[1] + 70.0).abs() < 1e-6);
            let nodes: Vec<usize> = els.iter().map(|e| e[0]).chain([last]).collect();
            let xs = nodes.iter().map(|&i| pts[i][0]);
            let lo = xs.clone().fold(f64::INFINITY, f64::min);
            let hi = xs.fold(f64::NEG_INFINITY, f64::max);
            ranges.push((k, lo, hi));
            // Each node at its horizontal distance from the fairlead along the line.
            for &i in &nodes {
                let r = sim.state().r[i];
                let s = (r[0] - fairleads[k][0]).hypot(r[1] - fairleads[k][1]);
                let p = view.point(i, r.as_slice());
                assert!(
                    (p[0] - 1000.0 * k as f64 - s).abs() < 1e-3 * s.max(1.0),
                    "{p:?} {s}"
                );
            }
        }
    }
    println!("drawn x ranges (line, min, max) [m]: {ranges:?}");
    // No two lines overlap in any snapshot.
    for a in &ranges {
        for b in ranges.iter().filter(|b| b.0 > a.0) {
            assert!(a.2 < b.1, "{a:?} {b:?}");
        }
    }
    // The seabed is drawn under each line, the grounded nodes marked.
    w.finish(&sim).unwrap();
    let scene = phstring_io::drive::ends::scene(&file, &w);
    let water = scene.water.as_ref().unwrap();
    assert_eq!(water.seabed_segments((-100.0, 2900.0)).len(), 3);
    assert_eq!(water.seabed_at(2500.0), Some(-320.0));
    let g = w.grounded().last().unwrap();
    let (nodes, on, margin) = below(&sim, 320.0);
    println!(
        "{} nodes below the seabed, {on} on it, the nearest other {margin:.3e} m from it",
        nodes.len()
    );
    assert_eq!(g.nodes, nodes);
    let svg = configuration_svg(&dir, &w, &scene);
    for text in [
        "distance from each line",
        "line k from k × 1000 m",
        "m on the seabed",
    ] {
        assert!(svg.contains(text), "{text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_dry_run_is_drawn_as_before() {
    // The dry 3D platform network: one plane, no seabed, nothing marked; its figure is the
    // one the side view alone draws.
    let file = read("platform_3d.toml", &["time.end=0.02"]);
    let mut sim = started_3d(&file);
    let dir = temp("dry");
    let mut w = Writers::start(&dir, &sim, 1, false, false, vec![0.0, 0.01]).unwrap();
    for _ in 0..2 {
        let r = sim.step().unwrap();
        w.step(&sim, &r).unwrap();
    }
    w.finish(&sim).unwrap();
    assert!(w.lines().is_none() && w.grounded().is_empty());
    let scene = phstring_io::drive::ends::scene(&file, &w);
    assert!(scene.lines.is_none() && scene.grounded.is_empty());
    assert!(phstring_io::scene::ContactTest::of(sim.system()).is_none());
    let svg = configuration_svg(&dir, &w, &scene);
    let png = std::fs::read(dir.join("configuration.png")).unwrap();
    let plain = Scene {
        side: w.side(),
        ..Scene::default()
    };
    assert_eq!(configuration_svg(&dir, &w, &plain), svg);
    assert_eq!(std::fs::read(dir.join("configuration.png")).unwrap(), png);
    assert!(!svg.contains("seabed"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shallow_chain_marks_its_grounded_nodes() {
    // MoorDyn's shallow chain deck: a chain in 50 m of water, most of it on the seabed.
    let file = read("moordyn/chain_shallow_50m_v2.dat", &[]);
    let sim = started_3d(&file);
    let dir = temp("shallow");
    let w = Writers::start(&dir, &sim, 1, false, false, vec![0.0]).unwrap();
    let (nodes, on, margin) = below(&sim, 50.0);
    println!(
        "{} nodes below the seabed, {on} on it, the nearest other {margin:.3e} m from it",
        nodes.len()
    );
    assert_eq!(w.grounded()[0].nodes, nodes);
    assert!(!nodes.is_empty());
    // The animation's test on positions read back agrees.
    let contact = scenario_contact(&sim);
    let pts: Vec<[f64; 3]> = sim.state().r.iter().map(|r| [r[0], r[1], r[2]]).collect();
    assert_eq!(contact.grounded(&pts), nodes);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The seabed contact test of `sim` for positions read back.
fn scenario_contact(sim: &Simulation<3, Material>) -> phstring_io::scene::ContactTest {
    phstring_io::scene::ContactTest::of(sim.system()).expect("a seabed")
}
