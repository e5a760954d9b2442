//! Feedback on a rigid body end to end: the anti-sway example (`examples/
//! hook_block_antisway_3d.toml`, PD on the payload beam's pose), its pose error, the energy
//! balance with the law's work as the port's supply, `check`'s description and the
//! scenario's errors.

use std::path::Path;

use crate::{phstring, run_with, temp_dir};

/// The numeric fields of each row of a CSV file (text as NaN) and its second field.
fn rows(p: &Path) -> Vec<(Vec<f64>, String)> {
    let mut r = csv::Reader::from_path(p).unwrap();
    r.records()
        .map(|x| {
            let x = x.unwrap();
            let nums = x.iter().map(|f| f.parse().unwrap_or(f64::NAN)).collect();
            (nums, x.get(1).unwrap_or("").to_string())
        })
        .collect()
}

/// The beam's pose error in a `bodies.csv` row: the distance [m] of its centre from the
/// reference `(0, 0, −23.90127)` and its turn [rad] from the reference orientation (the
/// identity): `2 acos(|q_w|)`.
fn pose_error(r: &[f64]) -> (f64, f64) {
    let d = [r[2], r[3], r[4] + 23.90127091267474];
    let dist = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    (dist, 2.0 * r[5].abs().min(1.0).acos())
}

/// The anti-sway example, 2000 steps of 10 ms written at every step: the beam starts 1.67 m
/// and 4.0° (with its 0.05 rad/s twist) off its hanging pose; under PD on its pose
/// (4 kN/m, 12 kN·s/m; 20 kN·m/rad, 40 kN·m·s/rad) its pose error falls below 1e-3 of the
/// start by `t = 20 s` (measured: 1.668 m → 3.2e-5 m, 4.0° → 2.2e-4°), while the open-loop
/// example swings on (its beam's error at the end is above 1 m); every step's balance is at
/// round-off with the law's work as supply (`|balance_error| ≤ 1e-12 |Ĥ(0)|`; measured
/// 6.3e-10 J of 1.3e6 J), and the sum of the beam port's mean power times `h` in
/// `bodies.csv` is `supplied_energy` to 1e-10 of the work (−3182 J).
#[test]
fn pd_on_the_beam_damps_the_sway_with_an_exact_balance() {
    let dir = temp_dir("antisway");
    let sets = [
        "output.plots=false",
        "output.animation=false",
        "output.stride=1",
    ];
    let closed = dir.join("closed");
    let o = run_with("examples/hook_block_antisway_3d.toml", &closed, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let energy = rows(&closed.join("energy.csv"));
    let h0 = energy[0].0[3].abs();
    for (r, _) in &energy {
        assert!(
            r[5].abs() <= 1e-12 * h0,
            "balance error {} at t = {}",
            r[5],
            r[0]
        );
    }
    let beam: Vec<Vec<f64>> = rows(&closed.join("bodies.csv"))
        .into_iter()
        .filter(|(_, name)| name == "beam")
        .map(|(r, _)| r)
        .collect();
    assert_eq!(beam.len(), energy.len());
    let (d0, a0) = pose_error(&beam[0]);
    let (d1, a1) = pose_error(beam.last().unwrap());
    let h = 0.01;
    let work: f64 = beam[1..].iter().map(|r| r[21] * h).sum();
    let supplied = energy.last().unwrap().0[4];
    eprintln!(
        "beam pose error: {d0:.4} m, {:.3}° at t = 0; {d1:.3e} m, {:.3e}° at t = 20 s; port work {work} J, supplied {supplied} J",
        a0.to_degrees(),
        a1.to_degrees()
    );
    assert!(d1 < 1e-3 * d0, "position error {d1} m of {d0} m");
    assert!(a1 < 1e-3 * a0, "turn error {a1} rad of {a0} rad");
    assert!(work.abs() > 1.0, "the law did work: {work} J");
    assert!(
        (supplied - work).abs() <= 1e-10 * work.abs(),
        "supplied {supplied} J, port work {work} J"
    );

    let open = dir.join("open");
    let o = run_with("examples/hook_block_3d.toml", &open, &sets[..2], &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let last = rows(&open.join("bodies.csv"))
        .into_iter()
        .rfind(|(_, name)| name == "beam")
        .unwrap()
        .0;
    let (d_open, _) = pose_error(&last);
    eprintln!("open loop: beam {d_open:.4} m off at t = 20 s");
    assert!(d_open > 1.0, "open loop {d_open} m");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `check` describes the law (gains per axis, the reference's expressions); a negative gain,
/// a wrong count of gains and a law with no gain are refused naming the key.
#[test]
fn check_describes_the_feedback_and_bad_gains_are_refused() {
    let o = phstring(&["check", "examples/hook_block_antisway_3d.toml"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("feedback:  beam: PD on the pose, kp [N/m] = [4000, 4000, 4000], kd [N·s/m] = [12000, 12000, 12000], kp_turn [N·m/rad] = [20000, 20000, 20000], kd_turn [N·m·s/rad] = [40000, 40000, 40000], reference position [0, 0, -23.90127091267474] m, orientation [0, 0, 0] deg"),
        "{text}"
    );
    let dir = temp_dir("feedback-errors");
    let base = std::fs::read_to_string(
        crate::workspace_root().join("examples/hook_block_antisway_3d.toml"),
    )
    .unwrap();
    let law = "feedback = { kp = 4.0e3, kd = 1.2e4, kp_turn = 2.0e4, kd_turn = 4.0e4,";
    assert!(base.contains(law));
    for (bad, message) in [
        (
            "feedback = { kp = -4.0e3, kd = 1.2e4, kp_turn = 2.0e4, kd_turn = 4.0e4,",
            "`bodies.beam.feedback.kp` must be at least 0 and finite, got -4000",
        ),
        (
            "feedback = { kp = [1.0, 2.0], kd = 1.2e4, kp_turn = 2.0e4, kd_turn = 4.0e4,",
            "`bodies.beam.feedback.kp` must be one number or 3 (dimension = 3), got 2",
        ),
        (
            "feedback = { kp = 0.0,",
            "`bodies.beam.feedback` has all gains 0 (or none): give kp, kd, kp_turn or kd_turn",
        ),
    ] {
        let file = dir.join("bad.toml");
        std::fs::write(&file, base.replace(law, bad)).unwrap();
        let o = phstring(&["check", file.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(err.contains(message), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
