//! Rigid bodies end to end: the hook block example against the compound pendulum and the
//! conservation of angular momentum about the vertical, `bodies.csv` with a wrench port,
//! resume, `check`, and the commands that refuse bodies.

use std::path::Path;

use crate::{phstring, run_with, summary, temp_dir};

/// A CSV row: its fields as numbers (text as NaN) and as text.
type Row = (Vec<f64>, Vec<String>);

/// The rows of a CSV file: header, then each row's fields (numbers parsed, text as NaN) and
/// its text fields.
fn table(p: &Path) -> (Vec<String>, Vec<Row>) {
    let mut r = csv::Reader::from_path(p).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| {
            let x = x.unwrap();
            let nums = x.iter().map(|f| f.parse().unwrap_or(f64::NAN)).collect();
            (nums, x.iter().map(String::from).collect())
        })
        .collect();
    (header, rows)
}

type M3 = [[f64; 3]; 3];

/// The rotation matrix of the unit quaternion `(w, x, y, z)`.
fn rotation(q: &[f64]) -> M3 {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

fn mul(a: &M3, v: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|j| a[i][j] * v[j]).sum())
}

/// `R diag(j) Rᵀ ω`: the angular momentum [kg·m²/s] of principal moments `j` turned by `r`.
fn spin(r: &M3, j: &[f64; 3], w: &[f64; 3]) -> [f64; 3] {
    let rt: M3 = [0, 1, 2].map(|i| [0, 1, 2].map(|k| r[k][i]));
    let body = mul(&rt, w);
    mul(r, &[j[0] * body[0], j[1] * body[1], j[2] * body[2]])
}

/// The hook block example (`examples/hook_block_3d.toml`, 2000 steps of 10 ms):
///
/// * the energy balance of every step is at round-off: `|balance_error| ≤ 1e-12 |Ĥ(0)|`
///   (measured: 4.7e-10 J of 1.3e6 J, 3.6e-16);
/// * the swing period is that of the whole suspension as one rigid compound pendulum about
///   the trolley, `T = 2π √(I_O / (g Σ m d))` (hook, beam, the hoist rope as a rod, the
///   slings as rods; 9.756 s), to 0.5 %: the beam's yaw turns its pitch inertia (15037.5
///   kg·m² → 75 kg·m² at 90°, which would make 9.733 s: 0.24 %), the amplitude of 4° adds
///   θ₀²/16 = 3e-4, the ropes' stretch 2e-4, the hook's swing against the beam about 1e-4
///   (measured 9.7550 s, 0.014 % short);
/// * the beam twists: it turns about the vertical by more than half of `ω₀ T` (measured:
///   0.94 rad of 1.0), and gravity and the trolley exert no torque about the trolley's
///   vertical, so the angular momentum `L_z` of the bodies changes only by what the strings
///   carry: `|ΔL_z| ≤ R √m_s (√(2 T_s(t)) + √(2 T_s(0)))` (Cauchy–Schwarz in the mass
///   matrix; `m_s` the strings' mass, `R` the largest distance of a body point from the
///   axis, `T_s` the strings' kinetic energy, the total of `energy.csv` less the bodies').
#[test]
fn hook_block_swings_at_the_compound_pendulum_period_and_twists() {
    let out = temp_dir("hook-block");
    let o = run_with(
        "examples/hook_block_3d.toml",
        &out,
        &["output.plots=false", "output.animation=false"],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, energy) = table(&out.join("energy.csv"));
    let h0 = energy[0].0[3].abs();
    for (row, _) in &energy {
        assert!(
            row[5].abs() <= 1e-12 * h0,
            "balance error {} at t = {}",
            row[5],
            row[0]
        );
    }
    let s = summary(&out);
    assert!(
        s["max_relative_balance_error"].as_f64().unwrap() <= s["balance_bound"].as_f64().unwrap()
    );

    let (_, rows) = table(&out.join("bodies.csv"));
    assert_eq!(rows.len(), 2 * energy.len());
    let hook: Vec<&Vec<f64>> = rows
        .iter()
        .filter(|r| r.1[1] == "hook")
        .map(|r| &r.0)
        .collect();
    let beam: Vec<&Vec<f64>> = rows
        .iter()
        .filter(|r| r.1[1] == "beam")
        .map(|r| &r.0)
        .collect();

    // Swing: the zero crossings of the beam's x (it starts at rest at x < 0).
    let mut crossings = Vec::new();
    for w in beam.windows(2) {
        let (a, b) = (w[0][2], w[1][2]);
        if (a < 0.0) != (b < 0.0) {
            crossings.push(w[0][0] + (w[1][0] - w[0][0]) * (-a) / (b - a));
        }
    }
    assert_eq!(crossings.len(), 4, "{crossings:?}");
    let measured = 2.0 * (crossings[3] - crossings[0]) / 3.0;
    let g = 9.81;
    let dz = (16.0f64 - 2.7 * 2.7).sqrt();
    let (d_hook, d_beam) = (20.4, 20.8 + dz + 0.15);
    // The hoist rope (2.3 kg/m over its reference length) as a rod from the trolley to
    // 20 m, each sling (1 kg/m) as a rod from (0.3, 20.8) to (3, 20.8 + dz).
    let m_rope = 2.3 * 19.990764266908684;
    let m_sling = 3.9973417677244636;
    let (a, b) = ([0.3, 20.8], [3.0, 20.8 + dz]);
    let rod = (a[0] * a[0] + a[1] * a[1])
        + (a[0] * (b[0] - a[0]) + a[1] * (b[1] - a[1]))
        + ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)) / 3.0;
    let i_o = 600.0 * d_hook * d_hook
        + 50.0
        + 5000.0 * d_beam * d_beam
        + 15037.5
        + m_rope * 20.0 * 20.0 / 3.0
        + 2.0 * m_sling * rod;
    let moment =
        600.0 * d_hook + 5000.0 * d_beam + m_rope * 10.0 + 2.0 * m_sling * (a[1] + b[1]) / 2.0;
    let closed = 2.0 * std::f64::consts::PI * (i_o / (g * moment)).sqrt();
    assert!(
        (measured / closed - 1.0).abs() < 5e-3,
        "swing period {measured} s, compound pendulum {closed} s"
    );

    // Twist: the beam's yaw (its x axis in the horizontal plane), unwrapped.
    let mut yaw = 0.0;
    let mut last = 0.0;
    for r in &beam {
        let e1 = mul(&rotation(&r[5..9]), &[1.0, 0.0, 0.0]);
        let a = e1[1].atan2(e1[0]);
        let d = (a - last + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        yaw += d;
        last = a;
    }
    assert!(yaw > 0.5 * 0.05 * 20.0, "the beam turned {yaw} rad");

    // L_z of the bodies against the strings' share.
    let bodies = [
        ("hook", 600.0, [40.0, 50.0, 26.0]),
        ("beam", 5000.0, [75.0, 15037.5, 15037.5]),
    ];
    let points: [Vec<[f64; 3]>; 2] = [
        vec![[0.0, 0.0, 0.4], [-0.3, 0.0, -0.4], [0.3, 0.0, -0.4]],
        vec![[-3.0, 0.0, 0.15], [3.0, 0.0, 0.15]],
    ];
    let m_s = m_rope + 2.0 * m_sling;
    let mut lz = Vec::new();
    let mut t_s = Vec::new();
    let mut radius: f64 = 0.0;
    for (k, (e, _)) in energy.iter().enumerate() {
        let (mut l, mut kin) = (0.0, 0.0);
        for (b, r) in [hook[k], beam[k]].into_iter().enumerate() {
            let (_, m, j) = bodies[b];
            assert_eq!(r[0], e[0]);
            let (x, v, w) = (
                [r[2], r[3], r[4]],
                [r[9], r[10], r[11]],
                [r[12], r[13], r[14]],
            );
            let rot = rotation(&r[5..9]);
            let s = spin(&rot, &j, &w);
            l += m * (x[0] * v[1] - x[1] * v[0]) + s[2];
            kin += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                + 0.5 * (w[0] * s[0] + w[1] * s[1] + w[2] * s[2]);
            for p in &points[b] {
                let q = mul(&rot, p);
                radius = radius.max((x[0] + q[0]).hypot(x[1] + q[1]));
            }
        }
        lz.push(l);
        t_s.push((e[1] - kin).max(0.0));
    }
    for k in 0..lz.len() {
        let bound = radius * m_s.sqrt() * ((2.0 * t_s[k]).sqrt() + (2.0 * t_s[0]).sqrt());
        assert!(
            (lz[k] - lz[0]).abs() <= bound,
            "L_z {} vs {} at t = {}: more than the strings' {bound}",
            lz[k],
            lz[0],
            energy[k].0[0]
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A 1 t box on a 10 m steel rope in 2D, pushed by its wrench port.
const PUSHED_BOX: &str = r#"
dimension = 2

[[node]]
name = "top"
position = [0.0, 0.0]

[bodies.box]
mass = 1000.0
inertia = [100.0, 100.0, 200.0]
position = [0.0, -10.5]
points = { hook = [0.0, 0.5] }
wrench = { force = ["2000*sin(t)", "0"], torque = ["500"] }

[materials.rope]
law = "tension_only_linear"
ea = 1.0e8
rho_a = 1.5

[[string]]
name = "rope"
path = ["top", "box.hook"]
elements = 8
material = "rope"

[body_force]
gravity = [0.0, -9.81]

[[boundary]]
node = "top"
fixed = true

[time]
h = 0.01
end = 2.0

[output]
plots = false
animation = false
vtk = false
"#;

/// `bodies.csv` of a body with a wrench port: the header with the port's columns, one row
/// per step (and `t = 0`), a unit quaternion, the inputs of each step at its mid time
/// (`2000 sin(t − h/2)` N, 500 N·m about z, to 1e-12 relative), and the supplied energy of
/// `energy.csv` equal to the sum of the port's mean power times `h` (to 1e-12 of the work).
#[test]
fn bodies_csv_has_the_wrench_port_and_its_work_is_the_supplied_energy() {
    let dir = temp_dir("pushed-box");
    let scenario = dir.join("box.toml");
    std::fs::write(&scenario, PUSHED_BOX).unwrap();
    let out = dir.join("out");
    let o = run_with(scenario.to_str().unwrap(), &out, &[], &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = table(&out.join("bodies.csv"));
    assert_eq!(
        header.join(","),
        "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz,power"
    );
    assert_eq!(rows.len(), 201);
    let h = 0.01;
    let mut work = 0.0;
    for (k, (r, text)) in rows.iter().enumerate() {
        assert_eq!(text[1], "box");
        let norm = r[5..9].iter().map(|q| q * q).sum::<f64>();
        assert!((norm - 1.0).abs() < 1e-14, "|q|² = {norm}");
        // In 2D: z, the quaternion's x and y and the angular velocity's x and y are 0.
        assert_eq!([r[4], r[6], r[7], r[12], r[13]], [0.0; 5]);
        if k == 0 {
            assert_eq!(&r[15..22], &[0.0; 7]);
            continue;
        }
        let f = 2000.0 * (r[0] - 0.5 * h).sin();
        assert!((r[15] - f).abs() <= 1e-12 * 2000.0, "fx {} vs {f}", r[15]);
        assert_eq!(&r[16..20], &[0.0, 0.0, 0.0, 0.0]);
        assert_eq!(r[20], 500.0);
        work += r[21] * h;
    }
    let (_, energy) = table(&out.join("energy.csv"));
    let supplied = energy.last().unwrap().0[4];
    assert!(work.abs() > 1.0, "the port did work: {work} J");
    assert!(
        (supplied - work).abs() <= 1e-12 * work.abs(),
        "supplied {supplied} J, port work {work} J"
    );
    let s = summary(&out);
    assert_eq!(s["bodies"][0]["name"], "box");
    let last = rows.last().unwrap();
    assert_eq!(s["bodies"][0]["position"][0].as_f64().unwrap(), last.0[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run stopped after 150 steps and resumed from its checkpoint writes the same
/// `bodies.csv` (and the same final bodies in `summary.json`) as an uninterrupted one.
#[test]
fn a_resumed_run_writes_the_bodies_of_an_uninterrupted_one() {
    let dir = temp_dir("bodies-resume");
    let sets = ["time.end=4", "output.plots=false", "output.animation=false"];
    let scenario = "examples/hook_block_3d.toml";
    let (whole, parts) = crate::run_whole_and_resumed(scenario, &dir, &sets, 150);
    let read = |d: &Path| std::fs::read_to_string(d.join("bodies.csv")).unwrap();
    assert_eq!(read(&whole).lines().count(), 1 + 2 * 401);
    assert_eq!(read(&whole), read(&parts));
    assert_eq!(summary(&whole)["bodies"], summary(&parts)["bodies"]);
    // The bodies' ParaView collection continues after the checkpoint's frames.
    let pvd = |d: &Path| std::fs::read_to_string(d.join("paraview/bodies.pvd")).unwrap();
    assert_eq!(pvd(&whole), pvd(&parts));
    assert_eq!(pvd(&whole).matches("<DataSet").count(), 9);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `check` describes each body: mass, weight, inertia, its points and what holds them.
#[test]
fn check_describes_the_bodies() {
    let o = phstring(&["check", "examples/hook_block_3d.toml"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    for line in [
        "body:      hook: 600 kg, weight [0, 0, -5886] N, inertia [[40, 0, 0], [0, 50, 0], [0, 0, 26]] kg·m²",
        "body:      beam: 5000 kg, weight [0, 0, -49050] N",
        "point:     hook.top (node 1) at [0, 0, 0.4] m in body axes",
        "holds string hoist",
        "point:     beam.right (node 5) at [3, 0, 0.15] m in body axes",
        "holds string sling_right",
    ] {
        assert!(text.contains(line), "missing {line:?} in\n{text}");
    }
}

/// The commands that do not cover rigid bodies yet refuse with the library's message,
/// naming the first body; an equilibrium start refuses a body given a velocity (it would
/// start at rest). The FMU takes bodies: their states are its outputs.
#[test]
fn error_control_and_the_linear_models_modal_form_refuse_bodies() {
    let dir = temp_dir("bodies-refused");
    let e = "examples/hook_block_3d.toml";
    let o = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let hook = "rigid body 0 ('hook'): ";
    let cases: [(Vec<String>, String); 3] = [
        (
            vec!["linearize".into(), e.into(), "--out".into(), o("l"), "--modes".into(), "4".into()],
            "the modal form (--modes) does not cover rigid bodies yet".into(),
        ),
        (
            vec!["run".into(), e.into(), "--out".into(), o("r"), "--set".into(), "time.rtol=1e-6".into(), "--set".into(), "time.atol=1e-6".into()],
            format!("{hook}error control (rtol, atol) does not cover"),
        ),
        (
            vec!["run".into(), e.into(), "--out".into(), o("q"), "--set".into(), "initial.equilibrium=true".into()],
            "`initial.equilibrium` = true starts every body at rest at its rest pose, but body \"beam\" is given a velocity or angular velocity".into(),
        ),
    ];
    for (args, says) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = phstring(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(&says), "{args:?}: {err}");
    }
    let out = phstring(&["fmu", e, "-o", &o("x.fmu")]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("body1.q.w") && dir.join("x.fmu").is_file(),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `statics` finds the hook block's rest state (the library's statics with bodies) and
/// writes it; a run from that equilibrium (the beam's twist removed) stays there: every
/// body speed stays below 1e-9 m/s and 1e-9 rad/s over 0.5 s (the statics tolerance of
/// 4.3e-6 N over stiffnesses of 1e6 N/m and more leaves offsets of ~4e-12 m, at most
/// ~4e-10 m/s at the ropes' ~100 rad/s).
#[test]
fn statics_and_an_equilibrium_start_take_bodies() {
    let dir = temp_dir("bodies-statics");
    let e = "examples/hook_block_3d.toml";
    let s = dir.join("s");
    let o = phstring(&["statics", e, "--out", s.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let vtp = std::fs::read_to_string(s.join("equilibrium.vtp")).unwrap();
    assert!(vtp.contains("reaction_x"));
    let r = dir.join("r");
    let sets = [
        "initial.equilibrium=true",
        "bodies.beam.angular_velocity=[0.0, 0.0, 0.0]",
        "time.end=0.5",
        "output.plots=false",
        "output.animation=false",
    ];
    let o = run_with(e, &r, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, rows) = table(&r.join("bodies.csv"));
    assert_eq!(rows.len(), 2 * 51);
    for (row, _) in &rows {
        let speed = row[9..12].iter().map(|v| v * v).sum::<f64>().sqrt();
        let spin = row[12..15].iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            speed < 1e-9 && spin < 1e-9,
            "t = {}: {speed} m/s, {spin} rad/s",
            row[0]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The hook block example drawn (0.5 s, a frame every 10 steps): `configuration` has the
/// legend entry of the bodies and, at the last snapshot (full colour), the 12 edges of each
/// of the two boxes; `animation.gif` is written; `paraview/bodies.pvd` lists one bodies frame
/// per strings frame (steps 0, 10, …, 50), each with 12 points, 3 lines and 6 faces per body.
#[test]
fn hook_block_bodies_are_drawn_in_plots_animation_and_paraview() {
    let out = temp_dir("hook-block-drawn");
    let o = run_with(
        "examples/hook_block_3d.toml",
        &out,
        &["time.end=0.5", "output.stride=10"],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let plots: Vec<&str> = s["plots"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|p| p.as_str())
        .collect();
    assert!(
        plots.contains(&"configuration") && plots.contains(&"animation"),
        "{plots:?}"
    );
    assert!(
        s["warnings"].as_array().unwrap().is_empty(),
        "{}",
        s["warnings"]
    );
    let svg = std::fs::read_to_string(out.join("configuration.svg")).unwrap();
    assert!(svg.contains("rigid bodies"), "no legend entry");
    // The last snapshot's edges in the full body colour, plus the legend's line.
    assert_eq!(svg.matches("stroke=\"#5A3C1E\"").count(), 2 * 12 + 1);
    assert!(out.join("animation.gif").is_file());
    let pvd = std::fs::read_to_string(out.join("paraview/bodies.pvd")).unwrap();
    let strings = std::fs::read_to_string(out.join("paraview/string.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 6);
    assert_eq!(strings.matches("<DataSet").count(), 6);
    for step in [0, 10, 20, 30, 40, 50] {
        let name = format!("bodies_{step:06}.vtp");
        assert!(pvd.contains(&name), "{name} not listed");
        let vtp = std::fs::read_to_string(out.join("paraview").join(&name)).unwrap();
        for count in [
            "NumberOfPoints=\"24\"",
            "NumberOfLines=\"6\"",
            "NumberOfPolys=\"12\"",
        ] {
            assert!(vtp.contains(count), "{name} lacks {count}");
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A 2D crane vessel (500 t, 40 m³ of it submerged, a 20 m² waterplane, 30 m² drag area)
/// held by a prescribed motion, heaving `1.5 sin(0.6 t)` m and rolling `2 sin(0.6 t)` deg,
/// with a 30 m wire (EA 1e8 N, 8 kg/m) from a point 10 m off its centre down to a 2 t clump
/// of 0.25 m³ in 150 m of sea water.
const HEAVING_VESSEL: &str = r#"
dimension = 2

[[node]]
name = "clump"
position = [10.0, -32.0]

[bodies.vessel]
mass = 5.0e5
inertia = [1.0e7, 1.0e7, 4.0e7]
position = [0.0, 0.0]
points = { crane = [10.0, -2.0] }
volume = 40.0
centre_of_buoyancy = [0.0, -1.0]
cda = 30.0
waterplane_area = 20.0
waterline = [0.0, 0.0]
motion = { position = ["0", "1.5*sin(0.6*t)"], orientation = ["2*sin(0.6*t)"] }

[materials.wire]
law = "tension_only_linear"
ea = 1.0e8
rho_a = 8.0

[[string]]
name = "wire"
path = ["vessel.crane", "clump"]
elements = 10
material = "wire"

[[point_mass]]
node = "clump"
kg = 2000.0
volume = 0.25
cda = 0.5

[body_force]
gravity = [0.0, -9.81]

[water]
density = 1025.0

[time]
h = 0.01
end = 4.0

[output]
plots = false
animation = false
vtk = false
"#;

/// A prescribed body's run: `bodies.csv` has the port's columns (the reaction force and
/// torque of every step and the motion's mean power), every step's energy balance closes to
/// 1e-9 of the largest energy, and the motion's work `Σ power · h` is the run's supplied
/// energy to 1e-9 of the largest energy (the clump's wire the only other port-free part).
/// The body follows the motion: its height is `1.5 sin(0.6 t)` to 1e-12 m. `check` lists the
/// motion and the vessel's weight in water `(5e5 − 1025 · 40) · 9.81 = 4 502 790 N`.
#[test]
fn a_prescribed_body_reports_its_reaction_and_its_work_is_supplied() {
    let dir = temp_dir("heaving-vessel");
    let scenario = dir.join("vessel.toml");
    std::fs::write(&scenario, HEAVING_VESSEL).unwrap();
    let out = dir.join("out");
    let o = run_with(scenario.to_str().unwrap(), &out, &[], &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = table(&out.join("bodies.csv"));
    assert_eq!(
        header.join(","),
        "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz,power"
    );
    let (eh, energy) = table(&out.join("energy.csv"));
    let col = |name: &str| eh.iter().position(|h| h == name).unwrap();
    let scale = energy
        .iter()
        .map(|(r, _)| {
            r[col("hamiltonian")]
                .abs()
                .max(r[col("supplied_energy")].abs())
        })
        .fold(0.0, f64::max);
    for (r, _) in &energy {
        assert!(
            r[col("balance_error")].abs() <= 1e-9 * scale,
            "t = {}: {}",
            r[0],
            r[col("balance_error")]
        );
    }
    let h = 0.01;
    let (mut work, mut lift) = (0.0, 0.0f64);
    for (r, _) in &rows {
        assert!(
            (r[3] - 1.5 * (0.6 * r[0]).sin()).abs() < 1e-12,
            "t = {}: y = {}",
            r[0],
            r[3]
        );
        work += r[21] * h;
        lift = lift.max(r[16].abs());
    }
    let supplied = energy.last().unwrap().0[col("supplied_energy")];
    println!(
        "motion's work {work} J, supplied {supplied} J, largest energy {scale} J, largest reaction {lift} N"
    );
    assert!(work.abs() > 1e3, "the motion did work: {work} J");
    assert!(
        (supplied - work).abs() <= 1e-9 * scale,
        "supplied {supplied} J, motion's work {work} J"
    );
    // The reaction holds the vessel's weight in water and the clump's: of order 4.5 MN.
    assert!(lift > 4.0e6 && lift < 6.0e6, "{lift}");
    let o = phstring(&["check", scenario.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    for line in [
        "motion:    vessel: prescribed [0, 1.5*sin(0.6*t), 2*sin(0.6*t)]",
        "in water:  body vessel: volume 40 m³ at [0, -1] m (body axes), CdA = 30 m²",
        "weight in water 4502790 N",
    ] {
        assert!(text.contains(line), "missing {line:?} in\n{text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The spar example (`examples/spar_buoy_3d.toml`: an OC3-like spar of 8066 t on three
/// catenary chains in 320 m of water, from its static equilibrium, set heaving by a 1 MN
/// Gaussian heave force at t = 8 s; 1600 steps of 0.1 s):
///
/// * the heave period, between up-crossings of the rest height after the pulse, is the
///   closed form `2π √(m / (ρ_w g A_w)) = 30.895 s` of a floater of mass `m` and waterplane
///   `A_w`, to 1 % (measured 30.72–30.73 s, −0.55 %: the chains' vertical stiffness, about
///   1 % of `ρ_w g A_w`, and the chain mass they carry are not in the closed form; the
///   scheme's period error `(ω h)²/12` is 3e-5);
/// * the energy balance of every step closes to 1e-12 of `|Ĥ|` (measured 7.6e-15);
/// * the rest state holds the spar on the axis (within 1e-4 m) at its heave equilibrium.
#[test]
fn the_spar_heaves_at_its_waterplane_period() {
    let out = temp_dir("spar-buoy");
    let o = run_with(
        "examples/spar_buoy_3d.toml",
        &out,
        &["output.plots=false", "output.animation=false"],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (eh, energy) = table(&out.join("energy.csv"));
    let col = |name: &str| eh.iter().position(|h| h == name).unwrap();
    let scale = energy
        .iter()
        .map(|(r, _)| r[col("hamiltonian")].abs())
        .fold(0.0, f64::max);
    for (r, _) in &energy {
        assert!(
            r[col("balance_error")].abs() <= 1e-12 * scale,
            "t = {}: {}",
            r[0],
            r[col("balance_error")]
        );
    }
    let (_, rows) = table(&out.join("bodies.csv"));
    let (t, z): (Vec<f64>, Vec<f64>) = rows.iter().map(|(r, _)| (r[0], r[4])).unzip();
    let rest = z[0];
    assert!(rows[0].0[2].abs() < 1e-4 && rows[0].0[3].abs() < 1e-4);
    let up: Vec<f64> = (1..t.len())
        .filter(|&i| t[i] > 16.0 && z[i - 1] < rest && z[i] >= rest)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * (rest - z[i - 1]) / (z[i] - z[i - 1]))
        .collect();
    assert!(up.len() >= 3, "{up:?}");
    let amplitude = z.iter().map(|x| (x - rest).abs()).fold(0.0, f64::max);
    assert!(amplitude > 1.0, "heave amplitude {amplitude} m");
    let closed = 2.0 * std::f64::consts::PI * (8.06633e6_f64 / (1025.0 * 9.81 * 33.18)).sqrt();
    for w in up.windows(2) {
        let period = w[1] - w[0];
        println!("heave period {period} s, closed form {closed} s");
        assert!(
            (period - closed).abs() <= 0.01 * closed,
            "{period} s vs {closed} s"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
