//! Outputs of a network run: `elements.csv` and `point_masses.csv` match
//! the mesh, `positions.csv` lists every node, the ParaView frames carry the group index and
//! the axial force of every element and the point masses, `ports.csv` has one row per port
//! and step, and the configuration plot and the animation draw the network.

use std::path::{Path, PathBuf};

use phstring::benchmarks::paper_pendulum;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Motion, NetworkBuilder, NodalLoad, PointMass,
    Simulation, StepParams, StringSpec, Vector,
};
use phstring_io::figures::{draw_animation, draw_plots};
use phstring_io::files::{ELEMENTS_FILE, POINT_MASSES_FILE, elements_header};
use phstring_io::history::{read_history, read_topology};
use phstring_io::output::{self, PLOT_POINTS, Writers};
use phstring_io::scene::Scene;
use vtkio::model::{Attribute, DataSet, Piece, Vtk};

/// A fresh, empty directory under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("phstring-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn rows(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn steel(name: &str, rho_a: f64) -> StringSpec<2, Material> {
    StringSpec {
        name: name.into(),
        material: Material::tension_only_linear(2e5),
        rho_a,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -9.81 * rho_a),
        prestretch: 1.001,
    }
}

/// A Y of three strings (`left`, `right` from two supports to a junction, `drop` from the
/// junction to a payload), a spring `brace` between the middles of `left` and `right`, a
/// spring `tie` from the payload to a fixed point, point masses at the junction and the
/// payload, support `right` moving sideways, a load on the payload. Returns the simulation
/// and the nodes (left support, right support, junction, payload).
fn y_network() -> (Simulation<2, Material>, [usize; 4]) {
    let mut b = NetworkBuilder::<2, Material>::new();
    let a = b.node(Vector::<2>::new(0.0, 0.0));
    let c = b.node(Vector::<2>::new(4.0, 0.0));
    let j = b.node(Vector::<2>::new(2.0, -1.5));
    let p = b.node(Vector::<2>::new(2.0, -3.0));
    let left = b.string(steel("left", 1.0), &[a, j], 6).unwrap();
    let right = b.string(steel("right", 1.0), &[c, j], 6).unwrap();
    b.string(steel("drop", 0.5), &[j, p], 4).unwrap();
    let mid = |b: &NetworkBuilder<2, Material>, g: usize| b.group_nodes(g).unwrap()[3];
    let (ml, mr) = (mid(&b, left), mid(&b, right));
    let gap = (b.position(mr).unwrap() - b.position(ml).unwrap()).norm();
    b.spring("brace", ml, mr, 500.0, gap).unwrap();
    b.spring_to_point("tie", p, Vector::<2>::new(3.0, -3.0), 200.0, 1.0)
        .unwrap();
    let net = b
        .build(
            Boundary {
                fixed: vec![
                    Fixed::node(a),
                    Fixed {
                        node: c,
                        components: [false, true],
                    },
                ],
                loads: vec![NodalLoad::new(p, |t| Vector::<2>::new(5.0 * t, 0.0))],
                motions: vec![Motion::new(c, 0, |t| 4.0 + 0.5 * t * t)],
                feedback: vec![],
            },
            vec![
                PointMass {
                    node: j,
                    mass: 2.0,
                    weight: Vector::<2>::new(0.0, -2.0 * 9.81),
                },
                PointMass {
                    node: p,
                    mass: 10.0,
                    weight: Vector::<2>::new(0.0, -10.0 * 9.81),
                },
            ],
        )
        .unwrap();
    let sim = Simulation::new(
        net,
        StepParams {
            h: 1e-3,
            ..StepParams::default()
        },
    )
    .unwrap();
    (sim, [a, c, j, p])
}

/// The single piece of a PolyData file.
fn piece(path: &Path) -> vtkio::model::PolyDataPiece {
    match Vtk::import(path).unwrap().data {
        DataSet::PolyData { mut pieces, .. } => match pieces.remove(0) {
            Piece::Inline(p) => *p,
            other => panic!("unexpected piece {other:?}"),
        },
        other => panic!("not PolyData: {other:?}"),
    }
}

fn array(attrs: &[Attribute], name: &str) -> Vec<f64> {
    match attrs.iter().find(|a| a.name() == name) {
        Some(Attribute::DataArray(d)) => d.data.clone().cast_into::<f64>().unwrap(),
        _ => panic!("no array {name}"),
    }
}

#[test]
fn network_outputs_describe_every_element_node_and_port() {
    let dir = temp_dir("network");
    let (mut sim, [a, c, j, p]) = y_network();
    let sys = sim.system();
    let n_nodes = sys.mesh().n_nodes();
    let n_el = sys.mesh().n_elements();
    assert_eq!(sys.groups().len(), 5);
    let mesh_elements = sys.mesh().elements().to_vec();
    let lengths = sys.mesh().lengths().to_vec();
    let group_of: Vec<usize> = (0..n_el)
        .map(|e| {
            sys.groups()
                .iter()
                .position(|g| g.elements.contains(&e))
                .unwrap()
        })
        .collect();
    let anchor = n_nodes - 1;

    let (steps, stride) = (20, 2);
    let mut w = Writers::start(&dir, &sim, stride, true, true, vec![0.0, 0.01, 0.02]).unwrap();
    for _ in 0..steps {
        let r = sim.step().unwrap();
        w.step(&sim, &r).unwrap();
    }
    w.finish(&sim).unwrap();

    // elements.csv: the mesh, element by element.
    let (header, el) = rows(&dir.join(ELEMENTS_FILE));
    assert_eq!(header, elements_header());
    assert_eq!(
        header,
        "element,node_a,node_b,group,kind,reference_length,group_name"
    );
    assert_eq!(el.len(), n_el);
    let names = ["left", "right", "drop", "brace", "tie"];
    for (e, row) in el.iter().enumerate() {
        assert_eq!(row[0], e.to_string());
        assert_eq!(row[1], mesh_elements[e][0].to_string());
        assert_eq!(row[2], mesh_elements[e][1].to_string());
        assert_eq!(row[3], group_of[e].to_string());
        let spring = group_of[e] >= 3;
        assert_eq!(row[4], if spring { "spring" } else { "string" });
        assert_eq!(row[5].parse::<f64>().unwrap(), lengths[e], "exact");
        assert_eq!(row[6], names[group_of[e]]);
    }
    let (header, pm) = rows(&dir.join(POINT_MASSES_FILE));
    assert_eq!(header, "node,mass");
    let pm: Vec<(usize, f64)> = pm
        .iter()
        .map(|r| (r[0].parse().unwrap(), r[1].parse().unwrap()))
        .collect();
    assert_eq!(pm, [(j, 2.0), (p, 10.0)]);
    let topology = read_topology(&dir).unwrap().unwrap();
    assert_eq!(topology, output::topology(&sim));
    assert!(!topology.is_chain());

    // positions.csv: every node of every frame (t = 0 and every `stride` steps).
    let frames = steps / stride + 1;
    let (header, pos) = rows(&dir.join("positions.csv"));
    assert_eq!(header, "t,node,x,y");
    assert_eq!(pos.len(), frames * n_nodes);
    for (k, row) in pos.iter().enumerate() {
        assert_eq!(row[1], (k % n_nodes).to_string());
    }

    // The last ParaView frame: one cell per element with its group and axial force, the
    // point masses as point data.
    let last = piece(&dir.join(format!("paraview/frame_{steps:06}.vtp")));
    assert_eq!(last.num_points(), n_nodes);
    assert_eq!(last.num_cells(), n_el);
    let cells: Vec<&str> = last.data.cell.iter().map(|a| a.name()).collect();
    assert_eq!(cells, ["C", "S", "tension", "string"]);
    let string = array(&last.data.cell, "string");
    assert_eq!(
        string,
        group_of.iter().map(|&g| g as f64).collect::<Vec<_>>()
    );
    let (cc, s, tension) = (
        array(&last.data.cell, "C"),
        array(&last.data.cell, "S"),
        array(&last.data.cell, "tension"),
    );
    assert_eq!(tension.len(), n_el);
    for e in 0..n_el {
        assert_eq!(tension[e], s[e] * cc[e].sqrt(), "element {e}");
    }
    // The strings start taut (prestretch); the tie spring's force is k (|d| − L0).
    assert!(tension[..16].iter().all(|&t| t > 0.0), "{tension:?}");
    let tie = n_el - 1;
    let d = {
        let pts = last.points.clone().cast_into::<f64>().unwrap();
        let (x0, y0) = (pts[3 * p], pts[3 * p + 1]);
        let (x1, y1) = (pts[3 * anchor], pts[3 * anchor + 1]);
        ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt()
    };
    assert!((tension[tie] - 200.0 * (d - 1.0)).abs() < 1e-9 * 200.0);
    let mass = array(&last.data.point, "mass");
    assert_eq!(mass.len(), n_nodes);
    assert_eq!(
        (mass[j], mass[p], mass.iter().sum::<f64>()),
        (2.0, 10.0, 12.0)
    );
    assert_eq!(array(&last.data.point, "velocity").len(), 3 * n_nodes);

    // ports.csv: per step the load, then every constrained node (fixed or moving), with
    // its kind, node, input, output and power u·y.
    let (header, ports) = rows(&dir.join("ports.csv"));
    assert_eq!(header, "t_mid,port,node,kind,u_x,u_y,y_x,y_y,power");
    assert_eq!(sim.ports().len(), 4);
    assert_eq!(ports.len(), steps * 4);
    let expected = [
        (p, "force"),
        (a, "velocity"),
        (c, "velocity"),
        (anchor, "velocity"),
    ];
    for (i, row) in ports.iter().enumerate() {
        let k = i % 4;
        assert_eq!(row[1], k.to_string());
        assert_eq!(
            (row[2].as_str(), row[3].as_str()),
            (&*expected[k].0.to_string(), expected[k].1)
        );
        let v: Vec<f64> = row[4..].iter().map(|x| x.parse().unwrap()).collect();
        let power = v[0] * v[2] + v[1] * v[3];
        let scale = (v[0] * v[2]).abs() + (v[1] * v[3]).abs();
        // The moving support's power also carries the kinetic energy its held velocity
        // imposes beyond the work of its impulse (docs/method.md eq. (14.5)): second order in
        // h for a smooth motion.
        let held = if k == 2 { 1e-6 } else { 0.0 };
        assert!((v[4] - power).abs() <= (1e-14 + held) * scale, "{row:?}");
    }
    // The moving support takes in work; the fixed ones none.
    let last_step = &ports[ports.len() - 4..];
    assert!(
        last_step[2][8].parse::<f64>().unwrap() != 0.0,
        "{last_step:?}"
    );
    assert_eq!(last_step[1][8], "0");

    // The configuration plot draws the network, the animation every frame.
    w.flush().unwrap();
    let history = read_history(w.energy_path(), PLOT_POINTS, w.snapshots().to_vec(), None)
        .unwrap()
        .unwrap();
    let report = draw_plots(
        &dir,
        2,
        ("Y network", &Scene::default()),
        None,
        Ok(&history),
        None,
    );
    assert_eq!(
        report.written,
        ["energy", "configuration", "increments"],
        "{report:?}"
    );
    let svg = std::fs::read_to_string(dir.join("configuration.svg")).unwrap();
    for text in [
        "left",
        "right",
        "drop",
        "springs (2)",
        "point masses",
        "t = 0.02 s",
    ] {
        assert!(svg.contains(text), "configuration.svg lacks {text:?}");
    }
    let report = draw_animation(&dir, 2, ("Y network", &Scene::default()), None);
    assert_eq!(report.written, ["animation"], "{report:?}");
    let gif = std::fs::read(dir.join("animation.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    let mut decoder = gif::DecodeOptions::new()
        .read_info(std::io::Cursor::new(gif))
        .unwrap();
    let mut n = 0;
    while decoder.read_next_frame().unwrap().is_some() {
        n += 1;
    }
    assert_eq!(n, frames);
    if std::env::var_os("PHSTRING_KEEP_TEST_PLOTS").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// A single string: the new files describe it as one chain group, its frames gain the
/// group index (all 0) and axial force, and no `point_masses.csv` is written.
#[test]
fn single_string_outputs_gain_elements_and_vtk_arrays_only() {
    let dir = temp_dir("single");
    let mut sim = Simulation::new(
        paper_pendulum(10),
        StepParams {
            h: 0.01,
            ..StepParams::default()
        },
    )
    .unwrap();
    let mut w = Writers::start(&dir, &sim, 1, true, true, vec![0.0]).unwrap();
    let r = sim.step().unwrap();
    w.step(&sim, &r).unwrap();
    w.finish(&sim).unwrap();
    let (_, el) = rows(&dir.join(ELEMENTS_FILE));
    assert_eq!(el.len(), 10);
    assert_eq!(el[3][..5], ["3", "3", "4", "0", "string"]);
    assert_eq!(el[3][6], "string");
    assert!(!dir.join(POINT_MASSES_FILE).exists());
    let topology = read_topology(&dir).unwrap().unwrap();
    assert!(topology.is_chain());
    let frame = piece(&dir.join("paraview/frame_000001.vtp"));
    let cells: Vec<&str> = frame.data.cell.iter().map(|a| a.name()).collect();
    assert_eq!(cells, ["C", "S", "tension", "string"]);
    assert_eq!(array(&frame.data.cell, "string"), vec![0.0; 10]);
    let points: Vec<&str> = frame.data.point.iter().map(|a| a.name()).collect();
    assert_eq!(points, ["velocity"]);
    let _ = std::fs::remove_dir_all(&dir);
}
