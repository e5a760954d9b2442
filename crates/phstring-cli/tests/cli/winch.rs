//! Winches through the command line (docs/method.md §23): the gantry crane that hoists
//! while its trolley travels, its `winches.csv` and summary, a resumed run, and the
//! scenario's refusals.

use std::path::Path;

use crate::{numeric_rows, phstring, run_with, summary, temp_dir};

const CRANE: &str = "examples/crane_hoisting_2d.toml";

/// The rows of `winches.csv` in `dir`: `(t, payout, length, speed, tension, power, energy,
/// mass)`.
fn winch_rows(dir: &Path) -> Vec<[f64; 8]> {
    let text = std::fs::read_to_string(dir.join("winches.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("t,winch,payout,length,speed,tension,power,energy,mass,motor_energy,drum_dissipated")
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f[1], "hoist");
            let x = |i: usize| f[i].parse::<f64>().unwrap();
            [x(0), x(2), x(3), x(4), x(5), x(6), x(7), x(8)]
        })
        .collect()
}

/// The crane hauls in 15 m of its 25 m rope: the last row has 10 m off the drum and its
/// mass `ρA · 10 m`; the winch's energy in `summary.json` is the change of `Ĥ` (no other
/// port supplies) and `energy.csv`'s supplied energy; and while it hauls at about 0.7 m/s
/// (12–18 s) its mean power is the static line tension `g (m + ρA ℓ)` times the speed and
/// the rope's stretch, within 1 % (the swing and the payload's acceleration make the rest).
#[test]
fn the_crane_hoists_through_its_winch_with_the_static_tension_times_the_speed() {
    let dir = temp_dir("winch-crane");
    let out = dir.join("run");
    let o = run_with(
        CRANE,
        &out,
        &["output.plots=false", "output.animation=false"],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = winch_rows(&out);
    let last = rows.last().unwrap();
    assert_eq!(rows.len(), 4501);
    assert!((last[0] - 45.0).abs() < 1e-9 && (last[1] + 15.0).abs() < 1e-12);
    assert!((last[2] - 10.0).abs() < 1e-9 && (last[7] - 41.0).abs() < 1e-9);
    let s = summary(&out);
    let energy = s["winches"][0]["energy"].as_f64().unwrap();
    let dh = s["hamiltonian_final"].as_f64().unwrap() - s["hamiltonian_initial"].as_f64().unwrap();
    assert!(
        (energy - dh).abs() < 1e-9 * dh.abs(),
        "{energy} against ΔĤ {dh}"
    );
    assert!((energy - last[6]).abs() < 1e-9 * energy.abs());
    let window: Vec<&[f64; 8]> = rows
        .iter()
        .filter(|r| (12.0..=18.0).contains(&r[0]))
        .collect();
    let n = window.len() as f64;
    let power = window.iter().map(|r| r[5]).sum::<f64>() / n;
    let stretch = 1.00116;
    let static_power = window
        .iter()
        .map(|r| 9.81 * (5000.0 + 4.1 * r[2]) * -r[3] * stretch)
        .sum::<f64>()
        / n;
    eprintln!(
        "mean power {power:.1} W against the static tension times the speed {static_power:.1} W; winch {energy:.1} J"
    );
    assert!((power / static_power - 1.0).abs() < 0.01);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run stopped after 862 steps (mid-hoist, the mesh cut four times, the last on that very
/// step) and resumed from its checkpoint writes the same `winches.csv`, `energy.csv` and `winch_arclength.csv` as an
/// uninterrupted one.
#[test]
fn a_resumed_winch_run_writes_what_an_uninterrupted_one_writes() {
    let dir = temp_dir("winch-resume");
    let sets = [
        "time.end=20",
        "output.plots=false",
        "output.animation=false",
    ];
    let (whole, parts) = crate::run_whole_and_resumed(CRANE, &dir, &sets, 862);
    for f in ["winches.csv", "energy.csv", "winch_arclength.csv"] {
        let read = |d: &Path| std::fs::read_to_string(d.join(f)).unwrap();
        assert_eq!(read(&whole), read(&parts), "{f} differs");
    }
    assert_eq!(summary(&whole)["winches"], summary(&parts)["winches"]);
    assert!(whole.join("winch_arclength.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A winch whose payout speed is an FMU input (`external = true`) runs in `phstring run` at
/// speed 0: `check` says so, and over 1 s the payout and the speed stay exactly 0 and the
/// length off the drum 25 m in every row of `winches.csv` (the drum holds the cable).
#[test]
fn an_external_winch_runs_at_speed_zero_without_a_master() {
    let dir = temp_dir("winch-external");
    let text = std::fs::read_to_string(crate::workspace_root().join(CRANE)).unwrap();
    let path = dir.join("external.toml");
    std::fs::write(
        &path,
        text.replace(
            "payout = \"-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)\"",
            "external = true",
        ),
    )
    .unwrap();
    let o = phstring(&["check", path.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        said.contains("payout speed an input (external: the FMU's winch.hoist.speed; `run` holds the payout at 0)"),
        "{said}"
    );
    let out = dir.join("run");
    let sets = ["time.end=1", "output.plots=false", "output.animation=false"];
    let o = run_with(path.to_str().unwrap(), &out, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = winch_rows(&out);
    assert_eq!(rows.len(), 101);
    // 25 elements of 25.029 m / 1.00116 / 25 = 1 m (to rounding).
    assert!(
        rows.iter()
            .all(|r| r[1] == 0.0 && (r[2] - 25.0).abs() < 1e-9 && r[3] == 0.0)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `winch_arclength.csv` of the crane hauling in (12 s: 5.28 m hauled in, five elements put
/// on the drum, the trolley travelling): at every frame of `positions.csv` one row per node
/// of the rope in path order; the last node's arc length is the length off the drum of
/// `winches.csv` at that time (the same number: to 1e-12 relative, round-off), each node's
/// arc length is its arc length at `t = 0` plus the payout (a node keeps its place on the
/// cable through the cuts), consecutive
/// nodes differ by their element's reference length in `elements.csv` (1 m, to 1e-12 of the
/// arc length, the rounding of `(j − drum) L − b`), the drum node (the last with `s ≤ 0`)
/// lies within an element behind the drum point, and at the end the five nodes before it are
/// parked on the drum.
#[test]
fn the_arc_length_of_a_winch_strings_nodes_runs_from_the_drum_point() {
    let dir = temp_dir("winch-arclength");
    let out = dir.join("run");
    let sets = [
        "time.end=12",
        "output.plots=false",
        "output.animation=false",
    ];
    let o = run_with(CRANE, &out, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("winch_arclength.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,winch,node,s"));
    let rows: Vec<(f64, usize, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f[1], "hoist");
            (
                f[0].parse().unwrap(),
                f[2].parse().unwrap(),
                f[3].parse().unwrap(),
            )
        })
        .collect();
    let lengths: std::collections::HashMap<(usize, usize), f64> =
        numeric_rows(&out.join("elements.csv"))
            .iter()
            .map(|r| ((r[1] as usize, r[2] as usize), r[5]))
            .collect();
    let winches = winch_rows(&out);
    let nodes = 26;
    assert_eq!(rows.len() % nodes, 0);
    assert_eq!(
        rows.len() / nodes,
        121,
        "a frame every 10 steps over 12 s, and t = 0"
    );
    let mut on_drum_seen = 0;
    let start = &rows[..nodes];
    for frame in rows.chunks(nodes) {
        let t = frame[0].0;
        assert!(frame.iter().all(|r| r.0 == t));
        let w = winches.iter().find(|r| r[0] == t).unwrap();
        // A node keeps its place on the cable through the cuts: its s moves with the payout.
        for (r, r0) in frame.iter().zip(start) {
            assert_eq!(r.1, r0.1);
            assert!(
                (r.2 - (r0.2 + w[1])).abs() <= 1e-12 * w[2],
                "t = {t}: node {}",
                r.1
            );
        }
        let last = frame[nodes - 1].2;
        assert!(
            (last - w[2]).abs() <= 1e-12 * w[2],
            "t = {t}: {last} against {}",
            w[2]
        );
        for pair in frame.windows(2) {
            let l = lengths[&(pair[0].1, pair[1].1)];
            let ds = pair[1].2 - pair[0].2;
            assert!((ds - l).abs() <= 1e-12 * w[2], "t = {t}: {ds} against {l}");
        }
        // The drum node: the last with s ≤ 0, within an element behind the drum point.
        let d = frame.iter().rposition(|r| r.2 <= 0.0).unwrap();
        let l = lengths[&(frame[0].1, frame[1].1)];
        assert!(
            frame[d].2 >= -l * (1.0 + 1e-12),
            "t = {t}: drum node at {}",
            frame[d].2
        );
        on_drum_seen += d;
    }
    let end = &rows[rows.len() - nodes..];
    let parked = end.iter().rposition(|r| r.2 <= 0.0).unwrap();
    eprintln!(
        "at t = 12 s: {parked} nodes on the drum, the drum node at s = {:.6} m, the last at {:.6} m",
        end[parked].2,
        end[nodes - 1].2
    );
    assert_eq!(parked, 5);
    assert!(on_drum_seen > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a winch table cannot be is refused with its key: a string the file lacks, a second
/// winch on one string, a payout that is not 0 at `t = 0`, a drum held by a support, a
/// payout given with `external = true` or neither of them, a name used twice or with a
/// comma (winches.csv names its rows by it), and a haul
/// beyond the rope (at run time, by name).
#[test]
fn winch_tables_that_cannot_work_are_refused_by_key() {
    let dir = temp_dir("winch-refusals");
    let text = std::fs::read_to_string(crate::workspace_root().join(CRANE)).unwrap();
    let cases: Vec<(String, &str)> = vec![
        (
            text.replace("string = \"rope\"\npayout", "string = \"cable\"\npayout"),
            "winch.0.string",
        ),
        (
            text.replace(
                "payout = \"-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)\"",
                "payout = \"1 - t\"",
            ),
            "winch.0.payout",
        ),
        (
            format!("{text}\n[[boundary]]\nnode = \"trolley\"\nfixed = true\n"),
            "winch 0 ('hoist')",
        ),
        (
            format!("{text}\n[[winch]]\nname = \"second\"\nstring = \"rope\"\npayout = \"0\"\n"),
            "winch.1.string",
        ),
        (
            text.replace(
                "string = \"rope\"\npayout",
                "string = \"rope\"\nexternal = true\npayout",
            ),
            "winch.0.payout` cannot be given with `external = true`",
        ),
        (
            text.replace("payout = \"-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)\"", ""),
            "winch.0.payout` is missing",
        ),
        (
            format!("{text}\n[[winch]]\nname = \"hoist\"\nstring = \"rope\"\npayout = \"0\"\n"),
            "winch.1.name",
        ),
        // A comma or a newline in the name would split winches.csv's rows.
        (
            text.replace("name = \"hoist\"", "name = \"a,b\""),
            "winch.0.name` = \"a,b\" is not a valid name",
        ),
    ];
    // A drum with dynamics: refused with a payout, a torque or inertia without a radius,
    // both a tension and a torque, a negative damping, a negative or infinite derivative
    // time, a derivative time with `dg4`.
    let heave = std::fs::read_to_string(
        crate::workspace_root().join("examples/heave_compensated_winch_2d.toml"),
    )
    .unwrap();
    let drum = |old: &str, new: &str| {
        assert!(heave.contains(old), "{old}");
        (heave.replace(old, new), "")
    };
    let mut cases = cases;
    for ((scenario, _), key) in [
        drum("reserve = 30.0", "reserve = 30.0\npayout = \"0\""),
        drum("radius = 0.5 ", "# no radius "),
        drum(
            "tension = \"51020\"",
            "tension = \"51020\"\ntorque = \"1000\"",
        ),
        drum("damping = 1000.0", "damping = -1000.0"),
        drum(
            "damping = 1000.0",
            "damping = 1000.0\nderivative_time = -0.5",
        ),
        drum(
            "damping = 1000.0",
            "damping = 1000.0\nderivative_time = inf",
        ),
        (
            drum(
                "damping = 1000.0",
                "damping = 1000.0\nderivative_time = 0.5",
            )
            .0
            .replace("h = 0.01 ", "scheme = \"dg4\"\nh = 0.01 "),
            "",
        ),
    ]
    .into_iter()
    .zip([
        "`winch.0.payout` and [winch.drum] exclude each other",
        "`winch.0.drum.inertia` needs the drum's radius",
        "`winch.0.drum.torque` and winch.drum.tension exclude each other",
        "`winch.0.drum.damping` = -1000 must be finite and ≥ 0",
        "`winch.0.drum.derivative_time` = -0.5 must be finite and ≥ 0",
        "`winch.0.drum.derivative_time` = inf must be finite and ≥ 0",
        "`winch.0.drum.derivative_time` = 0.5 s is not supported with time.scheme = \"dg4\"",
    ]) {
        cases.push((scenario, key));
    }
    for (k, (scenario, key)) in cases.iter().enumerate() {
        let path = dir.join(format!("case{k}.toml"));
        std::fs::write(&path, scenario).unwrap();
        let o = phstring(&["check", path.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(key), "case {k}: {err}");
    }
    let path = dir.join("too_far.toml");
    std::fs::write(
        &path,
        text.replace(
            "payout = \"-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)\"",
            "payout = \"-t\"",
        ),
    )
    .unwrap();
    let o = run_with(
        path.to_str().unwrap(),
        &dir.join("too_far"),
        &["output.plots=false"],
        &[],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("winch 'hoist'")
            && err.contains("hauls in more than the string has off the drum"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The final row of `bodies.csv` in `dir`: `(x, y, z, tilt [deg])` of the platform, and its
/// first `z`.
fn platform_end(dir: &Path) -> ([f64; 4], f64) {
    let rows = numeric_rows(&dir.join("bodies.csv"));
    let last = rows.last().unwrap();
    assert_eq!(last[0], 4.0);
    let tilt = 2.0 * last[7].abs().asin().to_degrees();
    ([last[2], last[3], last[4], tilt], rows[0][4])
}

/// The cable robot driven by eight winches that follow the inverse kinematics of a 0.5 m
/// move: the platform ends within 2 mm and 0.2° of the command (its open-loop accuracy,
/// measured 0.95 mm short and 0.10° of pitch), and within 0.5 mm and 0.05° of the same robot
/// whose cables slide through their pulleys as prescribed motions (cable_robot_3d.toml: the
/// same free cable lengths by another route). The winches' energies sum to the change of
/// `Ĥ` (they are its only ports), and each step's balance holds to round-off.
#[test]
fn the_cable_robot_follows_its_winches_to_the_inverse_kinematics() {
    let dir = temp_dir("winch-robot");
    let sets = ["output.plots=false", "output.animation=false"];
    let winched = dir.join("winches");
    let o = run_with("examples/cable_robot_winches_3d.toml", &winched, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sliding = dir.join("sliding");
    let o = run_with("examples/cable_robot_3d.toml", &sliding, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ([x, y, z, tilt], z0) = platform_end(&winched);
    let ([xs, _, zs, tilts], _) = platform_end(&sliding);
    eprintln!(
        "winches: x {x:.6} m (error {:.3e} m), y {y:.1e} m, z {:.3e} m off, tilt {tilt:.4}°; sliding cables: x {xs:.6} m, z {:.3e} m off, tilt {tilts:.4}°",
        x - 0.5,
        z - z0,
        zs - z0
    );
    assert!((x - 0.5).abs() < 2e-3 && y.abs() < 1e-9 && (z - z0).abs() < 1e-3);
    assert!(tilt < 0.2, "{tilt}");
    assert!((x - xs).abs() < 5e-4 && (tilt - tilts).abs() < 0.05);
    let s = summary(&winched);
    let winches = s["winches"].as_array().unwrap();
    assert_eq!(winches.len(), 8);
    let total: f64 = winches.iter().map(|w| w["energy"].as_f64().unwrap()).sum();
    let scale: f64 = winches
        .iter()
        .map(|w| w["energy"].as_f64().unwrap().abs())
        .sum();
    let dh = s["hamiltonian_final"].as_f64().unwrap() - s["hamiltonian_initial"].as_f64().unwrap();
    eprintln!(
        "winch energies sum to {total:.6} J, ΔĤ {dh:.6} J (each about {:.0} J)",
        scale / 8.0
    );
    assert!((total - dh).abs() < 1e-9 * scale);
    let err = s["max_relative_balance_error"].as_f64().unwrap();
    assert!(err < 1e-12, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `scenario` into a fresh folder (`tag`) with `sets` and no plots, animation or frames,
/// checks that it succeeded and returns the output folder.
fn run_ok(scenario: &str, tag: &str, sets: &[&str]) -> crate::TestDir {
    let out = temp_dir(tag).inside("run");
    let mut all = vec![
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    all.extend_from_slice(sets);
    let o = run_with(scenario, &out, &all, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// The constant-tension winch on the heaving vessel (`heave_compensated_winch_2d.toml`):
/// over the last two heave periods (48–64 s) the drum's payout speed, fitted as a quadratic
/// drift plus a sine at the heave's frequency, swings with the amplitude the rigid-rope law
/// gives, `|iωm/(d + iω(m + I))|` times the vessel's heave speed (0.71), within 2 % (the rope's
/// axial stretch and the payload's growing rope make the rest); the damping is the only
/// dissipation and equals `drum_dissipated`, and `Ĥ(T) − Ĥ(0)` is the winch's energy less it;
/// `energy.csv` carries both in its winch columns.
#[test]
fn the_heave_compensating_winch_swings_its_payout_as_the_rigid_rope_law_asks() {
    let out = run_ok(
        "examples/heave_compensated_winch_2d.toml",
        "winch-heave",
        &[],
    );
    let text = std::fs::read_to_string(out.join("winches.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != 1)
                .map(|(_, x)| x.parse::<f64>().unwrap())
                .collect()
        })
        .collect();
    // Columns now: t, payout, length, speed, tension, power, energy, mass, motor, dissipated.
    let window: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] >= 48.0 - 1e-9).collect();
    let w = 2.0 * std::f64::consts::PI / 8.0;
    let basis = |t: f64| [1.0, t, t * t, (w * t).sin(), (w * t).cos()];
    let a = nalgebra::DMatrix::from_fn(window.len(), 5, |i, j| basis(window[i][0])[j]);
    let y = nalgebra::DVector::from_fn(window.len(), |i, _| window[i][3]);
    let c = a.svd(true, true).solve(&y, 1e-12).unwrap();
    let swing = c[3].hypot(c[4]) / w;
    let length = window.iter().map(|r| r[2]).sum::<f64>() / window.len() as f64;
    let (m, inertia, d) = (5000.0 + 4.1 * length, 500.0 / 0.25, 1000.0);
    let law = w * m / (d * d + (w * (m + inertia)).powi(2)).sqrt();
    let last = rows.last().unwrap();
    let s = summary(&out);
    let dh = s["hamiltonian_final"].as_f64().unwrap() - s["hamiltonian_initial"].as_f64().unwrap();
    let dissipated = s["dissipated_energy"].as_f64().unwrap();
    eprintln!(
        "payout swing {swing:.4} of the heave speed (rigid rope {law:.4}, {length:.2} m off the drum); winch {:.1} J (motor {:.1} J), damping {dissipated:.1} J = {:.1} J, ΔĤ {dh:.1} J",
        last[6], last[8], last[9]
    );
    assert!((swing - law).abs() < 0.02 * law, "{swing} against {law}");
    assert!((last[9] - dissipated).abs() < 1e-9 * dissipated && dissipated > 0.0);
    assert!((last[6] - dissipated - dh).abs() < 1e-9 * dh.abs());
    // energy.csv carries the winch's supply and its drum's dissipation at every row.
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    let header: Vec<&str> = energy.lines().next().unwrap().split(',').collect();
    assert_eq!(header[10..], ["winch0_supplied", "winch0_dissipated"]);
    let e_last = numeric_rows(&out.join("energy.csv")).pop().unwrap();
    assert_eq!((e_last[10], e_last[11]), (last[6], last[9]));
    assert_eq!(e_last[9], dissipated);
}

/// The tension [N] at the top of 195 m of the anchor-handling chain (`anchor_handling_2d.toml`)
/// at rest and the length [m] on the seabed: a catenary from the touchdown with the weight in
/// water up the 50 m of water and the weight in air up the 5 m to the drum, the rest lying on
/// the seabed to the anchor 143.99 m from the drum, the unstretched length stretched by the
/// mean tension (bisection on the horizontal tension).
fn anchor_chain_at_rest() -> (f64, f64) {
    let (w_water, w_air, ea) = (979.924_170_830_316_4, 115.0 * 9.81, 5e8);
    let (anchor_x, length) = (143.991869, 195.0);
    let shape = |h: f64| {
        let x1 = h / w_water * (1.0 + 50.0 * w_water / h).acosh();
        let v1 = h * (w_water * x1 / h).sinh();
        let top = (h * h + v1 * v1).sqrt() + 5.0 * w_air;
        let vt = (top * top - h * h).sqrt();
        let x2 = h / w_air * ((vt / h).asinh() - (v1 / h).asinh());
        let hanging = v1 / w_water + (vt - v1) / w_air;
        (x1 + x2, hanging, top)
    };
    let (mut lo, mut hi) = (1e3, 1e6);
    for _ in 0..200 {
        let h = 0.5 * (lo + hi);
        let (x, hanging, top) = shape(h);
        if hanging + anchor_x - x > length * (1.0 + 0.5 * top / ea) {
            lo = h;
        } else {
            hi = h;
        }
    }
    let (x, _, top) = shape(0.5 * (lo + hi));
    (top, anchor_x - x)
}

/// Anchor handling: the winch pays out 30 m of chain onto the seabed in 30 s; 15 s after
/// the stop the drum tension is the static tension of the longer chain (a piecewise
/// catenary, 55.7 kN) within 5 %: the model's drum element hangs up to an element (2.5 m,
/// 2.8 kN of chain in air) behind the drum point, and the chain still swings by ±1 kN. The
/// chain on the seabed grows from 62.5 m to the catenary's 139 m within an element (the
/// grounded length counts whole nodes), and the winch's energy is the run's whole supply.
#[test]
fn anchor_handling_pays_chain_out_to_the_catenary_of_the_longer_chain() {
    let out = run_ok("examples/anchor_handling_2d.toml", "winch-anchor", &[]);
    let text = std::fs::read_to_string(out.join("winches.csv")).unwrap();
    let tension = |l: &str| l.split(',').nth(5).unwrap().parse::<f64>().unwrap();
    let rows: Vec<&str> = text.lines().skip(1).collect();
    let settled: Vec<f64> = rows[rows.len() - 501..]
        .iter()
        .map(|l| tension(l))
        .collect();
    let mean = settled.iter().sum::<f64>() / settled.len() as f64;
    let (top, grounded) = anchor_chain_at_rest();
    let s = summary(&out);
    let chain = &s["water"]["strings"][0];
    let (g_final, g_min) = (
        chain["grounded_length_final"].as_f64().unwrap(),
        chain["grounded_length_min"].as_f64().unwrap(),
    );
    let energy = s["winches"][0]["energy"].as_f64().unwrap();
    // Ĥ(T) − Ĥ(0) = supplied − dissipated, and the winch is the only supply.
    let supplied = s["hamiltonian_final"].as_f64().unwrap()
        - s["hamiltonian_initial"].as_f64().unwrap()
        + s["dissipated_energy"].as_f64().unwrap();
    eprintln!(
        "drum tension over the last 5 s {mean:.0} N (catenary {top:.0} N); on the seabed {g_min:.1} → {g_final:.1} m (catenary {grounded:.1} m); winch {energy:.0} J of {supplied:.0} J supplied"
    );
    assert!((mean - top).abs() < 0.05 * top, "{mean} N against {top} N");
    assert!(
        (g_final - grounded).abs() < 2.5,
        "{g_final} m against {grounded} m"
    );
    assert!(g_min < 65.0);
    assert!(
        (energy - supplied).abs() < 1e-9 * energy.abs(),
        "{energy} J of {supplied} J"
    );
}

/// Winches are listed, written and numbered in the order of their `[[winch]]` tables, not of
/// their strings: two hoists whose tables come in the reverse order of their strings.
#[test]
fn winches_follow_the_order_of_their_tables() {
    let dir = temp_dir("winch-order");
    let text = r#"
dimension = 2
[[node]]
name = "a_top"
position = [0.0, 0.0]
[[node]]
name = "a_hook"
position = [0.0, -10.0]
[[node]]
name = "b_top"
position = [5.0, 0.0]
[[node]]
name = "b_hook"
position = [5.0, -10.0]
[materials.rope]
law = "tension_only_linear"
ea = 4.3e7
rho_a = 4.1
[[string]]
name = "a"
path = ["a_top", "a_hook"]
elements = 10
material = "rope"
[[string]]
name = "b"
path = ["b_top", "b_hook"]
elements = 10
material = "rope"
[[winch]]
name = "second_string"
string = "b"
payout = "0.1 * t"
reserve = 2.0
[[winch]]
name = "first_string"
string = "a"
payout = "0"
[[point_mass]]
node = "a_hook"
kg = 500.0
[[point_mass]]
node = "b_hook"
kg = 500.0
[body_force]
gravity = [0.0, -9.81]
[time]
h = 0.01
end = 0.5
"#;
    let path = dir.join("two.toml");
    std::fs::write(&path, text).unwrap();
    let out = run_ok(path.to_str().unwrap(), "winch-order-run", &[]);
    let csv = std::fs::read_to_string(out.join("winches.csv")).unwrap();
    let names: Vec<&str> = csv
        .lines()
        .skip(1)
        .take(2)
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    assert_eq!(names, ["second_string", "first_string"]);
    let s = summary(&out);
    assert_eq!(s["winches"][0]["name"], "second_string");
    // energy.csv's winch0 is the paying-out winch (the first table).
    let last = numeric_rows(&out.join("energy.csv")).pop().unwrap();
    let w0 = s["winches"][0]["energy"].as_f64().unwrap();
    assert_eq!(last[10], w0);
    assert!(w0 < 0.0, "lowering takes energy: {w0}");
}

/// A 5 t payload on 20 m of a steel wire (EA = 1e8 N, 6.5 kg/m, elements of 1 m, 20 m on the
/// drum), lowered 12 m in 10 s by a smooth payout; `h` = 10 ms.
const LOWERING: &str = r#"
title = "A 5 t payload lowered 12 m on a steel wire"
dimension = 2

[[node]]
name = "drum"
position = [0.0, 0.0]

[[node]]
name = "hook"
position = [0.0, -20.01]                # m: 20 m of wire and its static stretch

[materials.wire]
law = "tension_only_linear"
ea = 1.0e8                              # N
rho_a = 6.5                             # kg/m

[[string]]
name = "wire"
path = ["drum", "hook"]
elements = 20
material = "wire"
prestretch = 1.0005                     # about the static strain: 50.3 kN / EA

[[winch]]
name = "hoist"
string = "wire"
reserve = 20.0                          # m on the drum
payout = "12 * (3*min(t/10,1)^2 - 2*min(t/10,1)^3)"

[[point_mass]]
node = "hook"
kg = 5000.0

[body_force]
gravity = [0.0, -9.81]

[time]
h = 0.01
end = 20.0

[output]
stride = 10
plots = false
animation = false
"#;

const PAYLOAD: f64 = 5000.0;
const RHO_A: f64 = 6.5;
const EA: f64 = 1.0e8;
const G: f64 = 9.81;

/// Writes the scenario `text` (the lowering, [`LOWERING`], or a variant) into `dir` and
/// runs it for 1200 steps (to `t` = 12 s, the 12 m paid out at 10 s), a checkpoint every 400
/// steps; returns the scenario and the last checkpoint, the one written at the stop.
fn lowered_checkpoint(dir: &Path, text: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let scenario = dir.join("lowering.toml");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("run");
    let extra = ["--checkpoint-every", "400", "--stop-after-steps", "1200"];
    let o = run_with(scenario.to_str().unwrap(), &out, &[], &extra);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    (scenario, out.join("checkpoint.json"))
}

/// `phstring statics SCENARIO --at CHECKPOINT --out OUT`, which must succeed; returns `OUT`.
pub(crate) fn statics_at(
    scenario: &std::path::Path,
    cp: &std::path::Path,
    out: &std::path::Path,
) -> std::path::PathBuf {
    let o = phstring(&[
        "statics",
        scenario.to_str().unwrap(),
        "--at",
        cp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.to_path_buf()
}

/// `statics --at` the checkpoint of a winch that has paid out 12 m (20 m → 32 m off the
/// drum, 12 elements brought off it): the equilibrium is that of the checkpoint's mesh, the
/// 32 elements from the drum node down, not the scenario's 20. `equilibrium.csv` has the
/// checkpoint's node count; `summary.json` names the checkpoint, its time (12 s) and the
/// winch's payout (12 m) and length off the drum (32 m, to 1e-9 m); the drum's reaction is
/// the weight hanging from the drum node, `g (m + ρA ℓ)` with `ℓ` the elements' length off
/// it, and the drum element's tension `g (m + ρA (ℓ − L/2))` (its node carries half of its
/// weight), both to the statics' residual (the reaction balances the loads less the free
/// components' residual: at most `√(free components)` × the tolerance, and rounding); the
/// payload hangs the closed-form static length `ℓ + g ((m + ρA ℓ) ℓ − ρA ℓ²/2)/EA` below
/// the drum node (to 1e-9 m: the residual moves it by at most about `√(free components)` ×
/// the tolerance × `ℓ/EA`, 2e-11 m). The plain
/// `statics` still solves at the scenario's 20 m.
#[test]
fn statics_at_a_winch_checkpoint_hangs_the_paid_out_length() {
    let dir = temp_dir("winch-statics-at");
    let (scenario, cp) = lowered_checkpoint(&dir, LOWERING);
    let out = statics_at(&scenario, &cp, &dir.join("statics"));
    let s = summary(&out);
    let from = &s["started_from"];
    assert_eq!(from["checkpoint"].as_str().unwrap(), cp.to_str().unwrap());
    assert!(
        (from["time"].as_f64().unwrap() - 12.0).abs() < 1e-9,
        "{from}"
    );
    let w = &from["winches"][0];
    assert_eq!(w["name"], "hoist");
    assert!((w["payout"].as_f64().unwrap() - 12.0).abs() < 1e-12, "{w}");
    assert!((w["length"].as_f64().unwrap() - 32.0).abs() < 1e-9, "{w}");
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cp).unwrap()).unwrap();
    let nodes = checkpoint["sim"]["r"].as_array().unwrap().len() / 2;
    let rows = numeric_rows(&out.join("equilibrium.csv"));
    assert_eq!(rows.len(), nodes);
    assert_eq!(s["nodes"].as_u64().unwrap() as usize, nodes);
    let drum = w["drum_node"].as_u64().unwrap() as usize;
    let drum_element = w["drum_element"].as_u64().unwrap() as usize;
    let ell = w["elements_length"].as_f64().unwrap();
    assert!(
        (ell - 32.0).abs() <= 1.0,
        "{ell}: within an element of the length off"
    );
    // The nodes below the drum node, one per element off it, are the free ones.
    let free = 2.0 * ell.round();
    let tol = free.sqrt() * s["tolerance"].as_f64().unwrap();
    let weight = G * (PAYLOAD + RHO_A * ell);
    let lift = rows[drum][4];
    let tension = numeric_rows(&out.join("tension.csv"))[drum_element][6];
    let hang = ell + G * ((PAYLOAD + RHO_A * ell) * ell - 0.5 * RHO_A * ell * ell) / EA;
    // The payload hangs lowest.
    let hook = rows.iter().map(|r| r[2]).fold(f64::INFINITY, f64::min);
    let drop = rows[drum][2] - hook;
    eprintln!(
        "statics at the checkpoint: drum reaction {lift:.6} N against {weight:.6} N ({:.1e} N), drum element tension {tension:.6} N ({:.1e} N), payload {drop:.9} m below the drum node against {hang:.9} m ({:.1e} m; tolerance {tol:.3e} N)",
        lift - weight,
        tension - (weight - G * RHO_A * 0.5),
        drop - hang
    );
    assert!((lift - weight).abs() <= tol + 1e-12 * weight, "{lift}");
    // Elements of L = 1 m: the drum node carries half of the drum element's weight.
    let half = G * RHO_A * 0.5;
    assert!((tension - (weight - half)).abs() <= tol + 1e-12 * weight);
    assert!((drop - hang).abs() < 1e-9, "{drop} against {hang}");
    // The summary's extremes are those of the rope off the drum (the elements on the drum,
    // N = 0, left out): the largest at the drum element, the smallest above the payload.
    assert_eq!(
        s["max_tension_element"].as_u64().unwrap() as usize,
        drum_element
    );
    let least = s["min_tension"].as_f64().unwrap();
    assert!(
        least > G * PAYLOAD && least < G * (PAYLOAD + RHO_A),
        "smallest tension {least} N"
    );
    // The scenario's own equilibrium hangs its 20 m.
    let start = dir.join("start");
    let o = phstring(&[
        "statics",
        scenario.to_str().unwrap(),
        "--out",
        start.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(summary(&start).get("started_from").is_none());
    let start_lift = summary(&start)["total_reaction"][1].as_f64().unwrap();
    let start_weight = G * (PAYLOAD + RHO_A * 20.0);
    assert!((start_lift - start_weight).abs() < 1e-6 * start_weight);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The smallest root `β` of `β tan β = μ`: the axial mode of a rod fixed at one end with a
/// tip mass `m`, `μ` its mass over `m`, is `ω = β c/ℓ` (`c = √(EA/ρA)`).
fn rod_with_tip_mass(mu: f64) -> f64 {
    let mut b = mu.sqrt();
    for _ in 0..50 {
        let f = b * b.tan() - mu;
        let df = b.tan() + b / b.cos().powi(2);
        b -= f / df;
    }
    b
}

/// `linearize --at` the same checkpoint (12 m paid out): the model is on the checkpoint's
/// mesh, its reduced form's states the free components of the 32 nodes below the drum node
/// (the 20 nodes still on the drum and the drum node held), and the manifest names the
/// checkpoint and the winch's length. The vertical rope's vertical and horizontal components
/// decouple in the tangent stiffness (to 1e-9 of its largest entry), and the lowest
/// eigenvalue of the vertical part, `K_yy φ = ω² M_yy φ`, is the axial mode of the payload on
/// the rope at its new length: `ω = β √(EA/ρA)/ℓ` with `β tan β = ρA ℓ/m` (24.83 rad/s
/// here; at the scenario's 20 m it is 31.49 rad/s). The axial tangent of the linear law is
/// exactly `EA/L` per element at any stretch, so the remaining difference is the chain's
/// discretization, of the order of `(β L/ℓ)²/24` ≈ 2e-6 relative; asserted: 1e-4. With
/// `--equilibrium` the model is taken about the equilibrium of that mesh: its static
/// residual is within the statics' tolerance and its positions are those of `statics --at`.
#[test]
fn linearize_at_a_winch_checkpoint_has_the_axial_mode_of_the_paid_out_length() {
    let dir = temp_dir("winch-linearize-at");
    let (scenario, cp) = lowered_checkpoint(&dir, LOWERING);
    let lin = |tag: &str, extra: &[&str]| {
        let out = dir.join(tag);
        let mut args = vec![
            "linearize",
            scenario.to_str().unwrap(),
            "--at",
            cp.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = phstring(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap())
                .unwrap();
        (out, m)
    };
    let (out, m) = lin("state", &[]);
    assert_eq!(m["linearized_at"].as_str().unwrap(), cp.to_str().unwrap());
    assert!((m["time"].as_f64().unwrap() - 12.0).abs() < 1e-9);
    let w = &m["started_from"]["winches"][0];
    assert!((w["length"].as_f64().unwrap() - 32.0).abs() < 1e-9, "{w}");
    let ell = w["elements_length"].as_f64().unwrap();
    let drum = w["drum_node"].as_u64().unwrap() as usize;
    let nodes = m["nodes"].as_u64().unwrap() as usize;
    let states: Vec<&str> = m["forms"]["reduced"]["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    // The free nodes: one below each element off the drum node (the payload's the last).
    let free_nodes = ell.round() as usize;
    assert_eq!(
        states.len(),
        2 * 2 * free_nodes,
        "q and v of each free component"
    );
    let held = format!("q[{drum}].");
    assert!(
        !states.iter().any(|s| s.starts_with(&held)),
        "drum node held"
    );
    assert!(nodes > free_nodes + 1, "parked nodes held");
    let q = crate::mooring::read_mtx(&out.join("reduced/Q.mtx"));
    let e = crate::mooring::read_mtx(&out.join("reduced/E.mtx"));
    let n = 2 * free_nodes;
    let ys: Vec<usize> = (0..n).filter(|&i| states[i].ends_with(".y")).collect();
    let xs: Vec<usize> = (0..n).filter(|&i| states[i].ends_with(".x")).collect();
    let k = q.view((0, 0), (n, n));
    let largest = k.amax();
    for &i in &xs {
        for &j in &ys {
            assert!(
                k[(i, j)].abs() <= 1e-9 * largest,
                "K[{i},{j}] = {}",
                k[(i, j)]
            );
        }
    }
    let pick = |a: nalgebra::DMatrixView<f64>| {
        nalgebra::DMatrix::from_fn(ys.len(), ys.len(), |i, j| a[(ys[i], ys[j])])
    };
    let k_yy = pick(k);
    let m_yy = pick(e.view((n, n), (n, n)));
    let l = m_yy.cholesky().expect("mass positive definite").l();
    let l_inv = l.clone().try_inverse().unwrap();
    let a = &l_inv * k_yy * l_inv.transpose();
    let lowest = a.symmetric_eigenvalues().min().sqrt();
    let mu = RHO_A * ell / PAYLOAD;
    let axial = rod_with_tip_mass(mu) * (EA / RHO_A).sqrt() / ell;
    let at_start = rod_with_tip_mass(RHO_A * 20.0 / PAYLOAD) * (EA / RHO_A).sqrt() / 20.0;
    eprintln!(
        "axial mode at the checkpoint: {lowest:.9} rad/s against the rod with a tip mass at {ell} m, {axial:.9} rad/s ({:.1e} relative; at the start's 20 m: {at_start:.6} rad/s)",
        lowest / axial - 1.0
    );
    assert!((lowest / axial - 1.0).abs() < 1e-4);
    // About the equilibrium at the checkpoint's length: that of `statics --at`.
    let (out, m) = lin("equilibrium", &["--equilibrium"]);
    assert_eq!(
        m["linearized_at"].as_str().unwrap(),
        format!("equilibrium at {}", cp.to_str().unwrap())
    );
    let st = statics_at(&scenario, &cp, &dir.join("statics"));
    let tol = summary(&st)["tolerance"].as_f64().unwrap();
    assert!(m["static_residual"].as_f64().unwrap() <= tol, "{m}");
    let at = numeric_rows(&out.join("at.csv"));
    let eq = numeric_rows(&st.join("equilibrium.csv"));
    assert_eq!(at.len(), eq.len());
    for (a, b) in at.iter().zip(&eq) {
        assert!((a[1] - b[1]).abs() < 1e-9 && (a[2] - b[2]).abs() < 1e-9);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `statics --at` and `linearize --at` refuse a checkpoint of another scenario by name and
/// counts, before the output folder is made: the crane's (26 nodes in 2D, against the
/// lowering's 41), and the lowering's own checkpoint against the same scenario with the drum
/// 1 m to the side (the same counts, but its drum node is not where that winch's path puts
/// it: not a mesh that winch produced).
#[test]
fn analyses_at_a_checkpoint_of_another_scenario_are_refused() {
    let dir = temp_dir("winch-at-refused");
    let (scenario, cp) = lowered_checkpoint(&dir, LOWERING);
    let crane = dir.join("crane");
    let o = run_with(
        CRANE,
        &crane,
        &["output.plots=false"],
        &["--stop-after-steps", "3"],
    );
    assert_eq!(o.status.code(), Some(130));
    let crane_cp = crane.join("checkpoint.json");
    let moved = dir.join("moved.toml");
    std::fs::write(
        &moved,
        LOWERING
            .replace("position = [0.0, 0.0]", "position = [1.0, 0.0]")
            .replace("position = [0.0, -20.01]", "position = [1.0, -20.01]"),
    )
    .unwrap();
    let size = format!(
        "{} holds 52 position values, but the scenario has 41 nodes in 2D (82 values)",
        crane_cp.display()
    );
    let off_path = format!(
        "checkpoint {} is damaged or does not belong to this scenario: sim.winches[0] (winch \"hoist\"): its drum node",
        cp.display()
    );
    for command in ["statics", "linearize"] {
        for (s, at, expect) in [(&scenario, &crane_cp, &size), (&moved, &cp, &off_path)] {
            let out = dir.join(format!("{command}-refused"));
            let o = phstring(&[
                command,
                s.to_str().unwrap(),
                "--at",
                at.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ]);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{err}");
            assert!(err.contains(expect.as_str()), "{command}: {err}");
            assert!(!out.exists(), "{command}: the folder was made");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The lowering in water (the drum 5 m below the surface, 200 m deep; the wire 40 mm in
/// diameter, the payload displacing 0.6 m³): `statics --at` the checkpoint at 12 m paid out
/// hangs the wet weight of the paid-out length, the water lumped again over the elements
/// that came off the drum: the drum's reaction is `g (m − ρ_w V + (ρA − ρ_w π d²/4) ℓ)`, ℓ
/// the elements' length off the drum node (32 m), to `√(free components)` × the statics'
/// tolerance (the dry weight is 6.4 kN more).
#[test]
fn statics_at_a_winch_checkpoint_in_water_hangs_the_wet_weight() {
    let dir = temp_dir("winch-statics-at-wet");
    let wet = LOWERING
        .replace("position = [0.0, 0.0]", "position = [0.0, -5.0]")
        .replace("position = [0.0, -20.01]", "position = [0.0, -25.01]")
        .replace("rho_a = 6.5 ", "diameter = 0.04\nrho_a = 6.5 ")
        .replace("kg = 5000.0", "kg = 5000.0\nvolume = 0.6")
        .replace(
            "[body_force]",
            "[water]\ndensity = 1025.0\ndepth = 200.0\n\n[body_force]",
        );
    let (scenario, cp) = lowered_checkpoint(&dir, &wet);
    let out = statics_at(&scenario, &cp, &dir.join("statics"));
    let s = summary(&out);
    let w = &s["started_from"]["winches"][0];
    assert!((w["length"].as_f64().unwrap() - 32.0).abs() < 1e-9, "{w}");
    let ell = w["elements_length"].as_f64().unwrap();
    let drum = w["drum_node"].as_u64().unwrap() as usize;
    let rho_w = 1025.0;
    let area = std::f64::consts::PI * 0.04 * 0.04 / 4.0;
    let wet_weight = G * (PAYLOAD - rho_w * 0.6 + (RHO_A - rho_w * area) * ell);
    let tol = (2.0 * ell.round()).sqrt() * s["tolerance"].as_f64().unwrap();
    let lift = numeric_rows(&out.join("equilibrium.csv"))[drum][4];
    eprintln!(
        "statics at the wet checkpoint: drum reaction {lift:.6} N against the wet weight {wet_weight:.6} N ({:.1e} N; dry {:.1} N)",
        lift - wet_weight,
        G * (PAYLOAD + RHO_A * ell)
    );
    assert!(
        (lift - wet_weight).abs() <= tol + 1e-12 * wet_weight,
        "{lift}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The crane scenario with `time.scheme = "dg4"`, with error control (`time.rtol = time.atol
/// = 1e-3`) and with both, to 12 s (5.3 m hauled in, five elements onto the drum while the
/// trolley travels): each run from the command line completes with the balance within 1e-12
/// of every step's energy scale, the payout the scenario's expression at 12 s (1e-12 m), the
/// mass off the drum `ρA` times the length, and the winch's energy `ΔĤ` (no other port
/// supplies); the controlled runs put the hook within the tolerance asked of a position,
/// `atol + rtol |r|`, of the `dg4` run at the fixed `h` = 0.01 s.
#[test]
fn the_crane_runs_with_dg4_and_with_error_control() {
    let p12 = {
        let x: f64 = 12.0 / 30.0;
        -15.0 * (3.0 * x * x - 2.0 * x * x * x)
    };
    // The hook (mesh node 1, the second `[[node]]`) in the final state.
    let hook = |dir: &Path| -> [f64; 2] {
        let rows = numeric_rows(&dir.join("positions.csv"));
        let r = rows.iter().rev().find(|r| r[1] == 1.0).unwrap();
        assert!((r[0] - 12.0).abs() < 1e-9, "the final state is written");
        [r[2], r[3]]
    };
    let (end, tol) = ("time.end=12", 1e-3);
    let dg4 = "time.scheme=\"dg4\"";
    let runs: [(&str, &[&str]); 3] = [
        ("winch-dg4", &[dg4, end]),
        ("winch-tol", &["time.rtol=1e-3", "time.atol=1e-3", end]),
        (
            "winch-dg4-tol",
            &[dg4, "time.rtol=1e-3", "time.atol=1e-3", end],
        ),
    ];
    let mut base = [0.0; 2];
    for (k, (tag, sets)) in runs.into_iter().enumerate() {
        let out = run_ok(CRANE, tag, sets);
        let s = summary(&out);
        let err = s["max_relative_balance_error"].as_f64().unwrap();
        let rows = winch_rows(&out);
        let last = rows.last().unwrap();
        let energy = s["winches"][0]["energy"].as_f64().unwrap();
        let dh =
            s["hamiltonian_final"].as_f64().unwrap() - s["hamiltonian_initial"].as_f64().unwrap();
        let r = hook(&out);
        if k == 0 {
            base = r;
        }
        let off = ((r[0] - base[0]).powi(2) + (r[1] - base[1]).powi(2)).sqrt();
        let allowed = tol * (1.0 + (base[0].powi(2) + base[1].powi(2)).sqrt());
        eprintln!(
            "{tag}: {} steps, {} rejected, balance/scale {err:.1e}, payout {:.9} m, winch {energy:.3} J = ΔĤ {dh:.3} J, hook {off:.2e} m from dg4 (allowed {allowed:.2e})",
            s["steps"], s["rejected_steps"], last[1]
        );
        assert!(err < 1e-12, "{tag}: {err}");
        assert!((last[0] - 12.0).abs() < 1e-9 && (last[1] - p12).abs() < 1e-12);
        assert!((last[7] - 4.1 * last[2]).abs() < 1e-9 * last[7]);
        assert!((energy - dh).abs() < 1e-9 * dh.abs(), "{tag}: {energy} J");
        assert!(off < allowed, "{tag}: hook {off} m from the dg4 run");
        let _ = std::fs::remove_dir_all(out.parent().unwrap());
    }
}

/// The heave-compensating winch (`heave_compensated_winch_2d.toml`) with a derivative part
/// in its tension controller (`--set winch.0.drum.derivative_time=0.5`), over 6 s: `check`
/// lists it with the drum; the run completes, and its winch's energy less the damping's
/// dissipation is `Ĥ(T) − Ĥ(0)` to 1e-9 (the derivative part's work is the motor's, part of
/// the winch's energy); stopped after 237 steps and resumed from its checkpoint file, it writes
/// the same `winches.csv` and `energy.csv` as the uninterrupted run (the previous pull is in
/// the checkpoint); and its payout differs from the run without the key.
#[test]
fn a_drum_with_a_derivative_time_runs_resumes_and_reports() {
    let dir = temp_dir("winch-pd");
    let scenario = "examples/heave_compensated_winch_2d.toml";
    let tau = "winch.0.drum.derivative_time=0.5";
    let sets = [
        "time.end=6",
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
        tau,
    ];
    let path = crate::workspace_root().join(scenario);
    let o = phstring(&["check", path.to_str().unwrap(), "--set", tau]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && text.contains("derivative time 0.5 s"),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (whole, parts) = crate::run_whole_and_resumed(scenario, &dir, &sets, 237);
    for f in ["winches.csv", "energy.csv"] {
        let read = |d: &Path| std::fs::read_to_string(d.join(f)).unwrap();
        assert_eq!(read(&whole), read(&parts), "{f} differs");
    }
    let s = summary(&whole);
    let dh = s["hamiltonian_final"].as_f64().unwrap() - s["hamiltonian_initial"].as_f64().unwrap();
    let dissipated = s["dissipated_energy"].as_f64().unwrap();
    let last = numeric_rows(&whole.join("winches.csv")).pop().unwrap();
    let (energy, motor) = (last[7], last[9]);
    eprintln!(
        "derivative time 0.5 s: winch {energy:.1} J (motor {motor:.1} J), damping {dissipated:.1} J, ΔĤ {dh:.1} J; payout {:.4} m",
        last[2]
    );
    assert!(
        (energy - dissipated - dh).abs() < 1e-9 * dh.abs().max(energy.abs()),
        "winch {energy} J − damping {dissipated} J against ΔĤ {dh} J"
    );
    let plain = run_ok(scenario, "winch-pd-plain", &sets[..4]);
    let plain_last = numeric_rows(&plain.join("winches.csv")).pop().unwrap();
    assert!(
        (plain_last[2] - last[2]).abs() > 1e-6,
        "payout {} m with and without the derivative part",
        last[2]
    );
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(plain.parent().unwrap());
}
