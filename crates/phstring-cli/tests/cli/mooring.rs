//! `phstring mooring` and the cable-robot example: the platform's 6 × 6 stiffness against
//! the classic cable-robot stiffness computed independently from the attachment geometry
//! and the cable tensions, the offset curve, the run's pose accuracy and energy balance,
//! and the command's errors.

use crate::{phstring, run_with, summary, temp_dir};

const ROBOT: &str = "examples/cable_robot_3d.toml";
/// The example's frame corners (pulleys) [m], platform points (body axes) [m], cable EA [N]
/// and prestretch.
const PULLEYS: [[f64; 3]; 8] = [
    [-3.0, -2.0, 3.0],
    [3.0, -2.0, 3.0],
    [3.0, 2.0, 3.0],
    [-3.0, 2.0, 3.0],
    [-3.0, -2.0, 0.0],
    [3.0, -2.0, 0.0],
    [3.0, 2.0, 0.0],
    [-3.0, 2.0, 0.0],
];
const POINTS: [[f64; 3]; 8] = [
    [-0.25, -0.25, 0.15],
    [0.25, -0.25, 0.15],
    [0.25, 0.25, 0.15],
    [-0.25, 0.25, 0.15],
    [-0.25, -0.25, -0.15],
    [0.25, -0.25, -0.15],
    [0.25, 0.25, -0.15],
    [-0.25, 0.25, -0.15],
];
const EA: f64 = 2.0e6;
const PRESTRETCH: f64 = 1.002;
/// The platform's centre at the start of the scenario (the cables' lengths follow from it).
const START: [f64; 3] = [0.0, 0.0, 1.5];

type M3 = [[f64; 3]; 3];

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] - b[i])
}

fn norm(a: &[f64; 3]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn skew(a: &[f64; 3]) -> M3 {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}

fn mat(a: &M3, b: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(a: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

/// The cable-robot stiffness from the geometry alone: each straight, massless cable from
/// platform point `P_k = x + a_k` to its pulley `A_k`, of length `l`, direction `u` (towards
/// the pulley), tension `T` and unstretched length `L`, has the point stiffness
/// `K_c = (EA/L) u uᵀ + (T/l)(I − u uᵀ)`; with `J = [I, −â]` the platform's stiffness is
/// `Σ Jᵀ K_c J` plus, in the turn–turn block, `−F̂ â` of the cable's force `F = T u` on the
/// platform (its arm turns under a fixed force).
fn robot_stiffness(centre: &[f64; 3], tensions: &[f64]) -> [[f64; 6]; 6] {
    let mut k = [[0.0; 6]; 6];
    for ((a_k, s), &t) in PULLEYS.iter().zip(&POINTS).zip(tensions) {
        // The platform does not turn at this equilibrium (checked by the caller).
        let p = [0, 1, 2].map(|i| centre[i] + s[i]);
        let d = sub(a_k, &p);
        let l = norm(&d);
        let u = d.map(|x| x / l);
        let start = [0, 1, 2].map(|i| START[i] + s[i]);
        let rest = norm(&sub(a_k, &start)) / PRESTRETCH;
        let kc: M3 = [0, 1, 2].map(|i| {
            [0, 1, 2].map(|j| {
                let eye = if i == j { 1.0 } else { 0.0 };
                EA / rest * u[i] * u[j] + t / l * (eye - u[i] * u[j])
            })
        });
        let ah = skew(s);
        // J = [I, −â]: the blocks of Jᵀ K_c J.
        let kc_a = mat(&kc, &ah);
        let at_kc = mat(&transpose(&ah), &kc);
        let at_kc_a = mat(&transpose(&ah), &kc_a);
        let geo = mat(&skew(&u.map(|x| x * t)), &ah);
        for i in 0..3 {
            for j in 0..3 {
                k[i][j] += kc[i][j];
                k[i][3 + j] -= kc_a[i][j];
                k[3 + i][j] -= at_kc[i][j];
                k[3 + i][3 + j] += at_kc_a[i][j] - geo[i][j];
            }
        }
    }
    k
}

/// The platform's 6 × 6 stiffness written by `phstring mooring` equals the independent
/// cable-robot stiffness of the attachment geometry, the cable tensions at the equilibrium
/// (`summary.json`) and the cables' `EA/L`, to 4e-5 of its largest entry (measured: 4.0e-6,
/// the cables' own weight, which the independent form leaves out); the offset curve's slope
/// at the equilibrium equals `K_xx` to 1e-5 (measured: 1.0e-6; the curve is ±5 mm in 2
/// steps each side, so its central difference also carries the cables' nonlinearity).
#[test]
fn cable_robot_stiffness_matches_the_independent_form() {
    let out = temp_dir("mooring-robot");
    let o = phstring(&[
        "mooring",
        ROBOT,
        "--max",
        "0.005",
        "--steps",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["body"], "platform");
    let centre: [f64; 3] = [0, 1, 2].map(|i| s["position"][i].as_f64().unwrap());
    let q: Vec<f64> = (0..4)
        .map(|i| s["orientation"][i].as_f64().unwrap())
        .collect();
    assert!(
        (q[0] - 1.0).abs() <= 1e-12,
        "the platform hangs level: {q:?}"
    );
    let curve = s["curve"].as_array().unwrap();
    assert_eq!(curve.len(), 5);
    let at_rest = &curve[2];
    assert_eq!(at_rest["offset"].as_f64().unwrap(), 0.0);
    let tensions: Vec<f64> = at_rest["tensions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let want = robot_stiffness(&centre, &tensions);
    let text = std::fs::read_to_string(out.join("stiffness.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "dof,x,y,z,rx,ry,rz");
    let got: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').skip(1).map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(got.len(), 6);
    let largest = got.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut worst = 0.0f64;
    for i in 0..6 {
        for j in 0..6 {
            worst = worst.max((got[i][j] - want[i][j]).abs() / largest);
        }
    }
    eprintln!("stiffness {got:?}\nindependent {want:?}\nworst {worst:.3e}");
    assert!(worst <= 4e-5, "{worst}");
    // The offset curve: the strings' force against the offset.
    let fx = |i: usize| curve[i]["force"][0].as_f64().unwrap();
    let slope = -(fx(3) - fx(1)) / (2.0 * 0.0025);
    let rel = (slope - got[0][0]).abs() / got[0][0];
    eprintln!("slope {slope} vs K_xx {}: {rel:.3e}", got[0][0]);
    assert!(rel <= 1e-5, "{slope} vs {}", got[0][0]);
    let offsets = std::fs::read_to_string(out.join("offset.csv")).unwrap();
    let header = offsets.lines().next().unwrap();
    assert!(
        header.starts_with(
            "offset_x,force_x,force_y,force_z,moment_x,moment_y,moment_z,tension platform.c0,"
        ),
        "{header}"
    );
    assert!(header.ends_with("reaction pulley7"), "{header}");
    assert_eq!(offsets.lines().count(), 6);
}

/// The cable robot's run: the winches move the platform 0.5 m along x in 3 s; at the end
/// (4 s) its centre is within 1 mm of the commanded 0.5 m (measured: 0.67 mm short, the
/// open-loop error of length control: the tensions keep their sizes as the cables turn) and
/// level within 0.1° (measured: 0.092° of pitch), off the y axis by less than 1e-9 m (the
/// motion is symmetric about the x–z plane), and the energy balance holds to 1e-9 of the
/// stored energy (measured: 3.1e-12 J of 718 J).
#[test]
fn cable_robot_follows_its_winches() {
    let out = temp_dir("robot-run");
    let o = run_with(ROBOT, &out, &[], &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = crate::numeric_rows(&out.join("bodies.csv"));
    let (first, last) = (&rows[0], rows.last().unwrap());
    assert_eq!(last[0], 4.0);
    let dx = last[2] - first[2];
    let tilt = 2.0 * last[7].abs().asin().to_degrees();
    eprintln!(
        "x moved {dx} m (error {:.3e} m), y {:.3e} m, z {:.3e} m, tilt {tilt:.4}°",
        dx - 0.5,
        last[3] - first[3],
        last[4] - first[4]
    );
    assert!((dx - 0.5).abs() <= 1e-3, "{dx}");
    assert!(tilt <= 0.1, "{tilt}");
    assert!((last[3] - first[3]).abs() <= 1e-9);
    let s = summary(&out);
    let err = s["max_balance_error"].as_f64().unwrap();
    let h0 = s["hamiltonian_initial"].as_f64().unwrap();
    assert!(err <= 1e-9 * h0, "{err}");
}

/// The command's errors name the bad value: a scenario without bodies, an unknown body, an
/// unknown degree of freedom, a non-positive offset.
#[test]
fn mooring_refuses_what_does_not_fit() {
    let out = temp_dir("mooring-errors");
    let o_s = out.to_str().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "mooring",
                "examples/mooring_line.toml",
                "--out",
                o_s,
                "--force",
            ],
            "has no rigid body",
        ),
        (
            &["mooring", ROBOT, "--body", "deck", "--out", o_s, "--force"],
            "--body deck: no such rigid body (known: platform)",
        ),
        (
            &["mooring", ROBOT, "--dof", "surge", "--out", o_s, "--force"],
            "--dof surge: a body in 3D has the degrees of freedom x, y, z, rx, ry, rz",
        ),
        (
            &["mooring", ROBOT, "--max=-1", "--out", o_s, "--force"],
            "--max -1: the largest offset must be positive",
        ),
    ];
    for (args, want) in cases {
        let o = phstring(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{args:?}: {err}");
    }
}

/// `phstring modes` with a rigid body: the cable robot's six lowest modes are the
/// platform's (`body`), and each lies within 2 % below the frequency of the platform alone
/// (40 kg, its inertia) on the massless springs of its 6 × 6 stiffness from `phstring
/// mooring` (`det(K − ω² M) = 0`): the cables' own mass (1.1 kg in all) lowers them
/// (measured: 0.5 % to 1.6 %). The next modes are the cables' own.
#[test]
fn cable_robot_modes_are_the_platform_on_its_stiffness() {
    let out = temp_dir("robot-modes");
    let k = robot_stiffness_by_cli(&out.join("m"));
    let mass = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
        40.0, 40.0, 40.0, 1.13, 1.13, 1.67,
    ]));
    // K is symmetric at this equilibrium; M^{-1/2} K M^{-1/2}.
    let ks = (&k + k.transpose()) * 0.5;
    let mh = mass.map(|x: f64| if x > 0.0 { 1.0 / x.sqrt() } else { 0.0 });
    let mut want: Vec<f64> = (&mh * ks * &mh)
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .map(|x| x.sqrt())
        .collect();
    want.sort_by(f64::total_cmp);
    let d = out.join("modes");
    let o = phstring(&["modes", ROBOT, "--count", "8", "--out", d.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let modes = summary(&d)["modes"].as_array().unwrap().clone();
    for (i, w) in want.iter().enumerate() {
        let got = modes[i]["omega_rad_s"].as_f64().unwrap();
        let drop = 1.0 - got / w;
        eprintln!("mode {i}: {got} rad/s, platform on springs {w}: {drop:.4}");
        assert_eq!(modes[i]["character"], "body");
        assert!(drop > 0.0 && drop < 0.02, "mode {i}: {got} against {w}");
        assert_eq!(modes[i]["bodies"].as_array().unwrap().len(), 1);
    }
    assert_ne!(modes[6]["character"], "body");
}

/// A MatrixMarket coordinate file (`linearize`'s `FORM/NAME.mtx`) as a dense matrix.
pub(crate) fn read_mtx(p: &std::path::Path) -> nalgebra::DMatrix<f64> {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let dims: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let mut m = nalgebra::DMatrix::zeros(dims[0], dims[1]);
    for l in lines {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (r, c): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        m[(r - 1, c - 1)] += f[2].parse::<f64>().unwrap();
    }
    m
}

/// `phstring linearize` with a rigid body (the cable robot with a wrench port on its
/// platform): the reduced form only, with the platform's force and torque as inputs and its
/// velocity and angular velocity as outputs; its static gain `K⁻¹ B` from the platform's
/// wrench to its translation and turn is the compliance `K_b⁻¹` of `phstring mooring`'s
/// stiffness to 1e-6 of each column (measured: 1.2e-11; two routes to the same Schur
/// complement, dense here and by bordered solves there).
#[test]
fn cable_robot_linear_model_has_the_mooring_compliance() {
    let out = temp_dir("robot-linear");
    let l = out.join("l");
    let wrench = "bodies.platform.wrench={force=[\"0\",\"0\",\"0\"]}";
    let o = phstring(&[
        "linearize",
        ROBOT,
        "--set",
        wrench,
        "--out",
        l.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(l.join("manifest.json")).unwrap()).unwrap();
    let names: Vec<&str> = m["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "F[platform].x",
            "F[platform].y",
            "F[platform].z",
            "T[platform].x",
            "T[platform].y",
            "T[platform].z"
        ]
    );
    assert_eq!(m["outputs"][5]["name"], "w[platform].z");
    assert_eq!(m["outputs"][5]["body"], "platform");
    assert!(m["forms"]["full"].is_null() && m["stable"] == true);
    let q = read_mtx(&l.join("reduced/Q.mtx"));
    let b = read_mtx(&l.join("reduced/B.mtx"));
    let n = q.nrows() / 2;
    // 8 cables × 3 interior nodes × 3 components, and the platform's 6.
    assert_eq!(n, 78);
    let k = q.view((0, 0), (n, n)).into_owned();
    let bq = b.view((n, 0), (n, 6)).into_owned();
    let x = k.lu().solve(&bq).unwrap();
    let kb = robot_stiffness_by_cli(&out.join("m"));
    let compliance = kb.try_inverse().unwrap();
    // The platform's coordinates are the last six: translation, then ρ w (w = turn here,
    // the platform level): the gyration radius √(tr J / m).
    let rho = ((1.13 + 1.13 + 1.67) / 40.0f64).sqrt();
    let mut worst = 0.0f64;
    for c in 0..6 {
        let scale = compliance.column(c).abs().max();
        for r in 0..6 {
            let got = x[(n - 6 + r, c)] / if r < 3 { 1.0 } else { rho };
            worst = worst.max((got - compliance[(r, c)]).abs() / scale);
        }
    }
    eprintln!("static gain against the compliance: {worst:.2e}");
    assert!(worst <= 1e-6, "{worst}");
}

/// The cable robot's 6 × 6 stiffness by `phstring mooring` (into `dir`).
fn robot_stiffness_by_cli(dir: &std::path::Path) -> nalgebra::DMatrix<f64> {
    let o = phstring(&[
        "mooring",
        ROBOT,
        "--max",
        "0.005",
        "--steps",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(dir);
    nalgebra::DMatrix::from_fn(6, 6, |i, j| s["stiffness"][i][j].as_f64().unwrap())
}

/// The spar example's waterplane moments (`waterplane_moments = [87.62, 87.62]` m⁴, π r⁴/4
/// of its 6.5 m waterline) add exactly their hydrostatic restoring `ρ_w g I` to the roll and
/// pitch stiffness of `phstring mooring` and nothing to heave: against the same spar with
/// the moments set to zero. `check` names them.
#[test]
fn spar_waterplane_moments_add_their_roll_and_pitch_restoring() {
    const SPAR: &str = "examples/spar_buoy_3d.toml";
    let stiffness = |name: &str, sets: &[&str]| {
        let dir = temp_dir(name);
        let mut args = vec![
            "mooring",
            SPAR,
            "--steps",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ];
        for s in sets {
            args.extend(["--set", s]);
        }
        let o = phstring(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = summary(&dir);
        let _ = std::fs::remove_dir_all(&dir);
        nalgebra::DMatrix::from_fn(6, 6, |i, j| s["stiffness"][i][j].as_f64().unwrap())
    };
    let with = stiffness("spar-moments", &[]);
    let without = stiffness(
        "spar-no-moments",
        &["bodies.spar.waterplane_moments=[0, 0]"],
    );
    let restoring = 1025.0 * 9.81 * 87.62; // N·m/rad: ρ_w g I, the example's water and g
    let d = &with - &without;
    for k in [3, 4] {
        assert!(
            (d[(k, k)] - restoring).abs() <= 1e-5 * restoring,
            "{} vs {restoring}",
            d[(k, k)]
        );
    }
    // Heave and the rest: the same equilibrium, so the same to the solves' rounding.
    let mut rest = d.clone();
    rest[(3, 3)] = 0.0;
    rest[(4, 4)] = 0.0;
    assert!(rest.abs().max() <= 1e-6 * with[(2, 2)], "{d}");
    let o = phstring(&["check", SPAR]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("with moments [87.62, 87.62] m⁴"), "{text}");
}
