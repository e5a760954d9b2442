//! Winches through the command line (docs/method.md §23): the gantry crane that hoists
//! while its trolley travels, its `winches.csv` and summary, a resumed run, and the
//! scenario's refusals.

use std::path::Path;

use crate::{phstring, run_with, summary, temp_dir};

const CRANE: &str = "examples/crane_hoisting_2d.toml";

/// The rows of `winches.csv` in `dir`: `(t, payout, length, speed, tension, power, energy,
/// mass)`.
fn winch_rows(dir: &Path) -> Vec<[f64; 8]> {
    let text = std::fs::read_to_string(dir.join("winches.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("t,winch,payout,length,speed,tension,power,energy,mass")
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

/// A run stopped after 1234 steps (mid-hoist, the mesh cut many times) and resumed from its
/// checkpoint writes the same `winches.csv` and `energy.csv` as an uninterrupted one.
#[test]
fn a_resumed_winch_run_writes_what_an_uninterrupted_one_writes() {
    let dir = temp_dir("winch-resume");
    let sets = [
        "time.end=20",
        "output.plots=false",
        "output.animation=false",
    ];
    let (whole, parts) = crate::run_whole_and_resumed(CRANE, &dir, &sets, 1234);
    for f in ["winches.csv", "energy.csv"] {
        let read = |d: &Path| std::fs::read_to_string(d.join(f)).unwrap();
        assert_eq!(read(&whole), read(&parts), "{f} differs");
    }
    assert_eq!(summary(&whole)["winches"], summary(&parts)["winches"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a winch table cannot be is refused with its key: a string the file lacks, a second
/// winch on one string, a payout that is not 0 at `t = 0`, a drum held by a support, and a
/// haul beyond the rope (at run time, by name).
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
    ];
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
    let rows = crate::numeric_rows(&dir.join("bodies.csv"));
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
