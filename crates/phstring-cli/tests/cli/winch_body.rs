//! A winch drum on a rigid body through the command line (docs/method.md §23, "A drum on a
//! rigid body"): the offshore crane on a moving vessel that lowers a module with heave
//! compensation, and what a drum on a body refuses and takes.

use std::path::Path;

use crate::{phstring, run_with, summary, temp_dir};

const VESSEL: &str = "examples/crane_vessel_heave_compensation_2d.toml";

/// The smooth lowering of the example [m]: `10 (3x² − 2x³)`, `x = min(t/60, 1)`.
fn lowering(t: f64) -> f64 {
    let x = (t / 60.0).min(1.0);
    10.0 * (3.0 * x * x - 2.0 * x * x * x)
}

/// The height of the example's boom tip [m] at `t` [s]: the vessel's heave plus the tip
/// (20 m forward, 25 m up) turned by the pitch.
fn tip_height(t: f64) -> f64 {
    let ramp = (t / 10.0).min(1.0);
    let heave = 1.5 * (2.0 * std::f64::consts::PI * t / 10.0).sin() * ramp;
    let pitch = (2.0 * (2.0 * std::f64::consts::PI * t / 8.0).sin() * ramp).to_radians();
    heave + 20.0 * pitch.sin() + 25.0 * pitch.cos()
}

/// The module's height with the lowering added back, from `positions.csv` (node 0), from
/// `t` = 20 s on: its range [m] (top to bottom).
fn module_heave(dir: &Path) -> f64 {
    let text = std::fs::read_to_string(dir.join("positions.csv")).unwrap();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        if f[1] == 0.0 && f[0] >= 20.0 {
            let y = f[3] + lowering(f[0]);
            lo = lo.min(y);
            hi = hi.max(y);
        }
    }
    hi - lo
}

/// The offshore crane lowers its 10 t module from the heaving, pitching vessel: its winch on
/// the boom tip pays out the tip's rise, and from 20 s on the module heaves 2.8 cm (top to
/// bottom, the lowering taken out) where the tip heaves 4.33 m; run again without the
/// compensation (the payout the lowering alone) the module heaves as the tip does, within
/// 2 %: the rope is stiff at these periods. Both runs keep every step's balance to 1e-12 of
/// the energy scale; in the compensated run the winch's energy is its payout's work (the
/// vessel's motion supplies the rest), 70 m of rope is off the drum at the end, weighing
/// `ρA · 70 m`, and the drum tension stays within 2.5 % of the hanging weight (measured
/// 2.0 %: the module's bounce and swing).
#[test]
fn the_crane_vessel_winch_takes_out_the_heave() {
    let dir = temp_dir("winch-body-vessel");
    let fast = [
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    let (on, off) = (dir.join("compensated"), dir.join("plain"));
    let o = run_with(VESSEL, &on, &fast, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut plain = fast.to_vec();
    plain.push("winch.0.payout=10*(3*min(t/60,1)^2 - 2*min(t/60,1)^3)");
    let o = run_with(VESSEL, &off, &plain, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 2000..=6000 {
        let y = tip_height(k as f64 * 0.01);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    let tip = hi - lo;
    let (with, without) = (module_heave(&on), module_heave(&off));
    eprintln!("tip heaves {tip:.4} m; the module {with:.4} m compensated, {without:.4} m not");
    assert!(with < 0.01 * tip, "compensated, the module heaves {with} m");
    assert!(
        (without - tip).abs() < 0.02 * tip,
        "uncompensated, the module heaves {without} m against the tip's {tip} m"
    );
    for dir in [&on, &off] {
        let s = summary(dir);
        let worst = s["max_relative_balance_error"].as_f64().unwrap();
        assert!(worst < 1e-12, "balance {worst:e} of the energy scale");
    }
    let s = summary(&on);
    let w = &s["winches"][0];
    let (length, mass) = (w["length"].as_f64().unwrap(), w["mass"].as_f64().unwrap());
    assert!((length - 70.0).abs() < 1e-9, "{length} m off the drum");
    assert!((mass - 4.1 * 70.0).abs() < 1e-9 * mass, "{mass} kg");
    let weight = 9.81 * (10000.0 + 4.1 * length);
    let text = std::fs::read_to_string(on.join("winches.csv")).unwrap();
    let worst = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(5).unwrap().parse::<f64>().unwrap())
        .map(|t| (t - weight).abs() / weight)
        .fold(0.0, f64::max);
    eprintln!(
        "drum tension within {:.2} % of the hanging weight",
        100.0 * worst
    );
    assert!(
        worst < 0.025,
        "drum tension {:.1} % off the weight",
        100.0 * worst
    );
}

/// A drum on a body moves with the body: `drum_position` on it is refused naming the winch,
/// and so is a point mass on its drum node (with no reserve, the body's point itself); a drum
/// with dynamics (`[winch.drum]`) on it is taken.
#[test]
fn a_drum_on_a_body_refuses_a_motion_of_its_own() {
    let dir = temp_dir("winch-body-refusals");
    let text = std::fs::read_to_string(crate::workspace_root().join(VESSEL)).unwrap();
    let payout = text
        .lines()
        .find(|l| l.starts_with("payout = "))
        .unwrap()
        .to_string();
    let moving = text.replace(
        &payout,
        &format!("{payout}\ndrum_position = [\"0\", \"t\"]"),
    );
    let path = dir.join("moving.toml");
    std::fs::write(&path, moving).unwrap();
    let o = phstring(&["check", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("winch 0 ('crane_winch')")
            && err.contains("its drum is a point of a rigid body and moves with the body"),
        "{err}"
    );
    let loaded = text.replace("reserve = 20.0", "reserve = 0.0")
        + "\n[[point_mass]]\nnode = \"vessel.tip\"\nkg = 100.0\n";
    let path = dir.join("loaded.toml");
    std::fs::write(&path, loaded).unwrap();
    let o = phstring(&["check", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("winch 0 ('crane_winch')") && err.contains("carries something else"),
        "{err}"
    );
    let dynamics = text.replace(&payout, "[winch.drum]\ntension = \"1e5\"\ndamping = 1000.0");
    let path = dir.join("dynamics.toml");
    std::fs::write(&path, dynamics).unwrap();
    let o = phstring(&["check", path.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("a drum on body vessel") && out.contains("a drum with dynamics"),
        "{out}"
    );
}

/// A winch on the hook block of `examples/hook_block_3d.toml` (a free body) paying out its
/// left sling by 0.2 m over 4 s: the run stops at 3 s with a checkpoint (its drum node moved
/// on by a cut), resumes to 5 s writing `winches.csv`, `energy.csv` and `bodies.csv` as the
/// uninterrupted run writes them, byte for byte; and `statics --at` the checkpoint solves the
/// system with the drum on the body, its smallest tension that of the slings off the drum
/// (above 10 kN, not the 0 N of the element on the drum), which `tension.csv` lists under
/// its string, `sling_left`, with N = 0.
#[test]
fn a_drum_on_a_free_body_resumes_and_solves_statics_at_its_checkpoint() {
    let dir = temp_dir("winch-body-hook");
    let text = std::fs::read_to_string(crate::workspace_root().join("examples/hook_block_3d.toml"))
        .unwrap()
        .replace("end = 20.0", "end = 5.0")
        + "\n[[winch]]\nname = \"sling_winch\"\nstring = \"sling_left\"\n\
           payout = \"0.2 * (3*min(t/4,1)^2 - 2*min(t/4,1)^3)\"\nreserve = 1.0\n";
    let scenario = dir.join("hook_winch.toml");
    std::fs::write(&scenario, text).unwrap();
    let path = scenario.to_str().unwrap();
    let fast = [
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    let (stopped, whole) = (dir.join("stopped"), dir.join("whole"));
    let extra = ["--checkpoint-every", "100", "--stop-after-steps", "300"];
    let o = run_with(path, &stopped, &fast, &extra);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let cp = stopped.join("checkpoint.json");
    let statics = crate::winch::statics_at(&scenario, &cp, &dir.join("statics"));
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run_with(path, &whole, &fast, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for file in ["winches.csv", "energy.csv", "bodies.csv"] {
        let (a, b) = (stopped.join(file), whole.join(file));
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{file} of the resumed run"
        );
    }
    let s = summary(&statics);
    let least = s["min_tension"].as_f64().unwrap();
    assert!(least > 1e4, "smallest tension {least} N");
    let text = std::fs::read_to_string(statics.join("tension.csv")).unwrap();
    let on_drum: Vec<&str> = text
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(6) == Some("0"))
        .collect();
    assert!(!on_drum.is_empty(), "no element on the drum");
    assert!(
        on_drum
            .iter()
            .all(|l| l.split(',').nth(1) == Some("sling_left")),
        "{on_drum:?}"
    );
}

/// `modes` and `linearize` refuse a scenario whose rigid body has a prescribed pose (the
/// crane vessel's heave), naming the body, as `mooring` does: the statics hold such a body,
/// and taking its pose as free gave three spurious body modes near 2e-5 Hz.
#[test]
fn modes_and_linearize_refuse_a_prescribed_body() {
    let dir = temp_dir("prescribed-body-modes");
    for cmd in ["modes", "linearize"] {
        let out = dir.join(cmd);
        let o = phstring(&[cmd, VESSEL, "--out", out.to_str().unwrap(), "-q"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{cmd} ran");
        assert!(
            err.contains("rigid body 'vessel' has a prescribed pose (a motion)")
                && err.contains("give it no motion for the analysis"),
            "{cmd}: {err}"
        );
    }
}
