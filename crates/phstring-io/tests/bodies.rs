//! `[bodies.NAME]`: a valid body builds the network the library expects (its points are
//! nodes after the `[[node]]`s, moving with the body; its weight `m g`), and every refusal
//! names the key, its position and the bad value.

use std::path::Path;

use phstring_io::scenario;

/// A 2 t box hanging from a fixed point on two 10 m ropes in 3D, turning about the vertical.
const BOX: &str = r#"
dimension = 3

[[node]]
name = "a"
position = [-1.0, 0.0, 0.0]

[[node]]
name = "b"
position = [1.0, 0.0, 0.0]

[bodies.box]
mass = 2000.0
inertia = [208.3, 708.3, 833.3]
position = [0.0, 0.0, -10.25]
orientation = [0.0, 0.0, 0.0]
velocity = [0.5, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 0.2]
points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0, 0.25] }

[materials.rope]
law = "tension_only_linear"
ea = 2.0e8
rho_a = 2.0

[[string]]
name = "r0"
path = ["a", "box.left"]
elements = 5
material = "rope"

[[string]]
name = "r1"
path = ["b", "box.right"]
elements = 5
material = "rope"

[body_force]
gravity = [0.0, 0.0, -9.81]

[[boundary]]
node = "a"
fixed = true

[[boundary]]
node = "b"
fixed = true

[time]
h = 0.01
end = 0.1
"#;

/// `line:column` of the first `needle` in `text`.
fn pos(text: &str, needle: &str) -> String {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in {text}"));
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
    format!("{line}:{column}")
}

fn validate(text: &str) -> Result<scenario::AnySetup, String> {
    let file = scenario::parse(text, Path::new("box.toml"), &[]).map_err(|e| e.to_string())?;
    file.setup().map_err(|e| e.to_string())
}

/// The error of a scenario that must be refused.
fn refused(text: &str) -> String {
    validate(text).err().expect("refused")
}

/// The box builds: its points are nodes 2 and 3 (after the two `[[node]]`s), at the body's
/// points, moving at `V + ω × R s` (0.5 m/s along x, ∓0.2 m/s along y from the spin about
/// z), its weight is `m g` and the strings' interior nodes start at rest.
#[test]
fn a_body_builds_with_its_points_as_nodes() {
    let setup = validate(BOX).unwrap();
    let phstring::ByDim::D3(s) = setup else {
        panic!("not 3D")
    };
    let sys = &s.problem.system;
    assert_eq!(sys.bodies(), vec![("box", 2000.0)]);
    let st = &s.problem.state;
    assert_eq!(st.r[2].as_slice(), &[-1.0, 0.0, -10.0]);
    assert_eq!(st.r[3].as_slice(), &[1.0, 0.0, -10.0]);
    assert_eq!(st.v[2].as_slice(), &[0.5, -0.2, 0.0]);
    assert_eq!(st.v[3].as_slice(), &[0.5, 0.2, 0.0]);
    assert!(st.v[4..].iter().all(|v| v.norm() == 0.0));
    let b = &st.bodies[0];
    assert_eq!(b.position.as_slice(), &[0.0, 0.0, -10.25]);
    // Ω in body axes (not turned): 0.2 rad/s about z.
    assert_eq!(b.omega.as_slice(), &[0.0, 0.0, 0.2]);
    let c = &s.components.bodies[0];
    assert_eq!(c.weight, vec![0.0, 0.0, -2000.0 * 9.81]);
    assert_eq!(c.points[0].name, "box.left");
    assert_eq!(c.points[0].attached, vec!["string r0".to_string()]);
    assert_eq!(s.components.node_label(3), "node 3 \"box.right\"");
}

/// Each refusal names its key, where the value is and what is wrong with it.
#[test]
fn body_errors_name_the_key_and_position() {
    // (replace, by, the value to locate in the new text, key, message part)
    let cases: &[(&str, &str, &str, &str, &str)] = &[
        (
            r#"path = ["a", "box.left"]"#,
            r#"path = ["a", "bx.left"]"#,
            r#""bx.left""#,
            "string.0.path.1",
            r#"but "bx" is not a [bodies.NAME] table (known: box)"#,
        ),
        (
            r#"path = ["a", "box.left"]"#,
            r#"path = ["a", "box.lft"]"#,
            r#""box.lft""#,
            "string.0.path.1",
            r#"body "box" has no point "lft" (its points: left, right)"#,
        ),
        (
            "mass = 2000.0",
            "mass = -5.0",
            "-5.0",
            "bodies.box.mass",
            "must be positive and finite, got -5",
        ),
        (
            "inertia = [208.3, 708.3, 833.3]",
            "inertia = [208.3, 708.3, 833.3, 900.0, 0.0, 0.0]",
            "[208.3, 708.3, 833.3, 900.0",
            "bodies.box.inertia",
            "is not positive definite",
        ),
        (
            "inertia = [208.3, 708.3, 833.3]",
            "inertia = [208.3, 708.3]",
            "[208.3, 708.3]",
            "bodies.box.inertia",
            "has 2 numbers: give the principal moments [Ixx, Iyy, Izz]",
        ),
        (
            "orientation = [0.0, 0.0, 0.0]",
            "orientation = [0.0, 0.0]",
            "[0.0, 0.0]\nvel",
            "bodies.box.orientation",
            "must have 3 components in 3D, got 2",
        ),
        (
            "[[boundary]]\nnode = \"b\"\nfixed = true",
            "[[boundary]]\nnode = \"b\"\nfixed = true\n\n[[boundary]]\nnode = \"box.right\"\nfixed = [\"z\"]",
            "\"box.right\"\nfixed",
            "boundary.2.node",
            r#"is body point "box.right" (node 3), which its body alone moves: it cannot also be fixed, moved or controlled"#,
        ),
        (
            "points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0, 0.25] }",
            "points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0, 0.25], spare = [0.0, 0.0, -0.25] }",
            "[0.0, 0.0, -0.25]",
            "bodies.box.points.spare",
            "is on no string's path and at no spring's end",
        ),
        (
            "points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0, 0.25] }",
            "points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0] }",
            "[1.0, 0.0] }",
            "bodies.box.points.right",
            "must have 3 components (dimension = 3), got 2",
        ),
        (
            "[bodies.box]",
            "[bodies.\"b.x\"]",
            "[bodies.\"b.x\"]",
            "bodies.b.x",
            "is not a valid name",
        ),
        (
            "[time]",
            "[bodies.box.wrench]\nforce = [\"1/0\", \"0\", \"0\"]\n\n[time]",
            "\"1/0\"",
            "bodies.box.wrench.force.0",
            "division by zero",
        ),
        (
            "[time]",
            "[bodies.box.wrench]\ntorque = [\"0\", \"0\"]\n\n[time]",
            "[\"0\", \"0\"]",
            "bodies.box.wrench.torque",
            "must have 3 expressions, got 2",
        ),
    ];
    for (from, to, at, key, part) in cases {
        assert!(BOX.contains(from), "{from:?}");
        let text = BOX.replacen(from, to, 1);
        let err = validate(&text)
            .err()
            .unwrap_or_else(|| panic!("{key}: accepted"));
        // The position is checked where the value is unique (the name case has none).
        let origin = if *key == "bodies.b.x" {
            "box.toml".to_string()
        } else {
            format!("box.toml:{}", pos(&text, at))
        };
        assert!(
            err.contains(&format!("`{key}`")) && err.contains(part) && err.starts_with(&origin),
            "{key}: {err}\n(expected at {origin}: {part})"
        );
    }
}

/// A body in 1D and a body in a single-string scenario are refused, naming the table; in
/// 2D, orientation and angular velocity are one angle and one rate about z.
#[test]
fn bodies_need_a_network_of_dimension_two_or_three() {
    let one = "dimension = 1\n[[node]]\nname = \"a\"\nposition = [0.0]\n[bodies.box]\nmass = 1.0\ninertia = [1.0, 1.0, 1.0]\nposition = [-1.0]\npoints = { p = [0.0] }\n[materials.m]\nea = 1e6\nrho_a = 1.0\n[[string]]\nname = \"s\"\npath = [\"a\", \"box.p\"]\nelements = 2\nmaterial = \"m\"\n[time]\nh = 0.01\nend = 0.1\n";
    let err = refused(one);
    assert!(
        err.contains("`bodies.box` is a rigid body, but the scenario has dimension 1"),
        "{err}"
    );
    let single = "dimension = 2\n[geometry]\nstart = [0.0, 0.0]\nend = [1.0, 0.0]\n[mesh]\nelements = 2\n[material]\nea = 1e6\nrho_a = 1.0\n[bodies.box]\nmass = 1.0\ninertia = [1.0, 1.0, 1.0]\nposition = [0.0, 0.0]\npoints = { p = [0.0, 0.0] }\n[time]\nh = 0.01\nend = 0.1\n";
    let err = refused(single);
    assert!(
        err.contains("`bodies` belongs to a network, but this scenario has no [[string]] tables"),
        "{err}"
    );
    let planar = one
        .replace("dimension = 1", "dimension = 2")
        .replace("[0.0]", "[0.0, 0.0]")
        .replace("[-1.0]", "[-1.0, 0.0]")
        .replace(
            "points =",
            "orientation = [90.0]\nangular_velocity = [0.5]\npoints =",
        );
    let phstring::ByDim::D2(s) = validate(&planar).unwrap() else {
        panic!("not 2D")
    };
    // Turned 90° about z, the point (0, 0) is the centre, moving with the centre at rest.
    let b = &s.problem.state.bodies[0];
    let q = b.orientation.quaternion();
    assert!(
        (q.w - q.k).abs() < 1e-15 && q.i == 0.0 && q.j == 0.0,
        "{q:?}"
    );
    assert!((b.omega_space().z - 0.5).abs() < 1e-15);
    let err = refused(&planar.replace("angular_velocity = [0.5]", "angular_velocity = [0.0, 0.5]"));
    assert!(
        err.contains("`bodies.box.angular_velocity` must have 1 component in 2D (about z), got 2"),
        "{err}"
    );
}

/// `initial.velocities` must repeat the body's velocity at a body point (node 2 moves at
/// [0.5, -0.2, 0] m/s with the box), naming the entry.
#[test]
fn listed_velocities_must_agree_with_the_body() {
    let mut list = ["[0.0, 0.0, 0.0]"; 12];
    list[2] = "[0.5, 0.0, 0.0]";
    let text = BOX.replace(
        "[time]",
        &format!("[initial]\nvelocities = [{}]\n\n[time]", list.join(", ")),
    );
    let err = refused(&text);
    assert!(
        err.contains("`initial.velocities.2` = [0.5, 0, 0] m/s at node 2, body point \"box.left\", where the body gives [0.5, -0.2, 0] m/s"),
        "{err}"
    );
}

/// A wrench expression that fails during the run stops it at that step as an input failure,
/// and the record names the body's key, the component, the text and the time:
/// `sqrt(0.5 - t)` fails at the mid time 0.505 s of step 51 (h = 0.01 s).
#[test]
fn a_failing_wrench_expression_names_its_key() {
    let text = BOX
        .replace(
            "[time]",
            "[bodies.box.wrench]\nforce = [\"sqrt(0.5 - t)\", \"0\", \"0\"]\n\n[time]",
        )
        .replace("end = 0.1", "end = 1.0");
    let phstring::ByDim::D3(s) = validate(&text).unwrap() else {
        panic!("not 3D")
    };
    let (mut run, _) = s.start(false, None).map_err(|e| e.to_string()).unwrap();
    let err = loop {
        match run.problem.step() {
            Ok(_) => assert!(run.problem.time() < 0.6, "no failure by t = 0.6 s"),
            Err(e) => break e,
        }
    };
    assert!(err.is_input_failure(), "{err}");
    let message = run.load_error.lock().unwrap().clone().unwrap_or_default();
    assert_eq!(
        message,
        "`bodies.box.wrench.force` component x \"sqrt(0.5 - t)\" at t = 0.505 s: operand out of domain (at \"sqrt(0.5 - t)\", characters 0..13)"
    );
}

/// `wrench = { external = true }` is a port a front end alone drives: the body has a wrench
/// port (zero force and torque at `t = 0`), and its component says it is external; without
/// the key, a wrench is not.
#[test]
fn an_external_wrench_is_a_port_of_the_front_end() {
    let text = BOX.replace("[time]", "[bodies.box.wrench]\nexternal = true\n\n[time]");
    let phstring::ByDim::D3(s) = validate(&text).unwrap() else {
        panic!("not 3D")
    };
    assert!(s.problem.system.body_has_wrench(0));
    assert!(s.components.bodies[0].wrench_external);
    let text = BOX.replace(
        "[time]",
        "[bodies.box.wrench]\nforce = [\"1e3\", \"0\", \"0\"]\n\n[time]",
    );
    let phstring::ByDim::D3(s) = validate(&text).unwrap() else {
        panic!("not 3D")
    };
    assert!(s.problem.system.body_has_wrench(0));
    assert!(!s.components.bodies[0].wrench_external);
    let bad = BOX.replace("[time]", "[bodies.box.wrench]\nexternal = 1\n\n[time]");
    let err = refused(&bad);
    assert!(err.contains("external"), "{err}");
}

/// The points line of [`BOX`], the last key of its body table.
const POINTS: &str = "points = { left = [-1.0, 0.0, 0.25], right = [1.0, 0.0, 0.25] }";

/// A 6×6 added-mass matrix (kg, kg·m, kg·m²) with a surge–pitch coupling, as TOML rows.
const ADDED_MASS: &str = "[4e3, 0, 0, 0, -500, 0], [0, 4e3, 0, 0, 0, 0], [0, 0, 1e3, 0, 0, 0], \
     [0, 0, 0, 800, 0, 0], [-500, 0, 0, 0, 800, 0], [0, 0, 0, 0, 0, 300]";
/// [`ADDED_MASS`] with its coupling unequal across the diagonal.
const SKEWED_ADDED_MASS: &str = "[4e3, 0, 0, 0, -600, 0], [0, 4e3, 0, 0, 0, 0], \
     [0, 0, 1e3, 0, 0, 0], [0, 0, 0, 800, 0, 0], [-500, 0, 0, 0, 800, 0], [0, 0, 0, 0, 0, 300]";
/// [`ADDED_MASS`] with a coupling too large for its diagonal (`500 × 500 > 4e3 × 20`).
const INDEFINITE_ADDED_MASS: &str = "[4e3, 0, 0, 0, -500, 0], [0, 4e3, 0, 0, 0, 0], \
     [0, 0, 1e3, 0, 0, 0], [0, 0, 0, 800, 0, 0], [-500, 0, 0, 0, 20, 0], [0, 0, 0, 0, 0, 300]";

/// Each refusal of a body's water keys and prescribed motion names its key, where the value
/// is and what is wrong with it (`dry`: without `[water]`; the others in sea water).
#[test]
fn water_and_motion_errors_name_the_key_and_position() {
    let wet = |keys: &str| format!("{POINTS}\n{keys}\n\n[water]\ndensity = 1025.0");
    let dry = |keys: &str| format!("{POINTS}\n{keys}");
    // (replacement of the points line, the value to locate, key, message part)
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (
            dry("volume = 2.5"),
            "2.5",
            "bodies.box.volume",
            "is a water term of a rigid body, but the scenario has no [water] table",
        ),
        (
            wet("cda = -1.5"),
            "-1.5",
            "bodies.box.cda",
            "must be at least 0 and finite, got -1.5",
        ),
        (
            wet("volume = 2.5\ncentre_of_buoyancy = [0.0, 0.1]"),
            "[0.0, 0.1]",
            "bodies.box.centre_of_buoyancy",
            "must have 3 components (dimension = 3), got 2",
        ),
        (
            wet("waterline = [0.0, 0.0, 1.5]"),
            "[0.0, 0.0, 1.5]",
            "bodies.box.waterline",
            "needs a positive `waterplane_area` of the same body (it is 0)",
        ),
        (
            wet("added_inertia = [1.0, -2.0, 3.0]"),
            "[1.0, -2.0, 3.0]",
            "bodies.box.added_inertia",
            "has the moment -2 kg·m²: each must be at least 0 and finite",
        ),
        (
            wet("added_mass = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]"),
            "[[1.0, 0.0, 0.0]",
            "bodies.box.added_mass",
            "must be 6 rows of 6 in dimension 3",
        ),
        (
            wet(&format!("added_mass = [{}]", SKEWED_ADDED_MASS)),
            "[[4e3",
            "bodies.box.added_mass",
            "added mass is not symmetric: entry (row 1, column 5) = -600 but (row 5, column 1) = -500",
        ),
        (
            wet(&format!("added_mass = [{}]", INDEFINITE_ADDED_MASS)),
            "[[4e3",
            "bodies.box.added_mass",
            "added mass is not positive semi-definite: eigenvalue",
        ),
        (
            wet(&format!("ca = 0.0\nadded_mass = [{}]", ADDED_MASS)),
            "[[4e3",
            "bodies.box.added_mass",
            "is given beside `ca` of the same body",
        ),
        (
            wet("ca = 0.5"),
            "0.5\n",
            "bodies.box.ca",
            "= 0.5 is a coefficient on the displaced mass ρ_w V, but the body's `volume` is 0",
        ),
        (
            dry("motion = { position = [\"0\", \"0\"] }"),
            "[\"0\", \"0\"]",
            "bodies.box.motion.position",
            "must have 3 expressions, got 2",
        ),
        (
            dry("motion = { position = [\"0\", \"0\", \"-10.25 + 1/(t - t)\"] }"),
            "\"-10.25 + 1/(t - t)\"",
            "bodies.box.motion.position.2",
            "division by zero",
        ),
        (
            dry("motion = { position = [\"0\", \"0\", \"-10.25\"] }"),
            "[0.5, 0.0, 0.0]",
            "bodies.box.velocity",
            "is given, but the body has a prescribed motion, which takes no a velocity (the motion gives it): remove `velocity`",
        ),
        (
            dry(
                "motion = { position = [\"0\", \"0\", \"-10.25\"] }\nmotion_table = \"vessel.csv\"",
            ),
            "\"vessel.csv\"",
            "bodies.box.motion_table",
            "and `motion` both prescribe the body's motion: give one of them",
        ),
    ];
    for (to, at, key, part) in &cases {
        let text = BOX.replacen(POINTS, to, 1);
        let err = validate(&text)
            .err()
            .unwrap_or_else(|| panic!("{key}: accepted"));
        let origin = format!("box.toml:{}", pos(&text, at));
        assert!(
            err.contains(&format!("`{key}`")) && err.contains(part) && err.starts_with(&origin),
            "{key}: {err}\n(expected at {origin}: {part})"
        );
    }
}

/// [`BOX`] at rest, in sea water, with every water term, heaving `0.5 sin t` m and turning
/// `10 t` deg about z by a prescribed motion.
fn prescribed_box() -> String {
    BOX.replace("velocity = [0.5, 0.0, 0.0]\n", "")
        .replace("angular_velocity = [0.0, 0.0, 0.2]\n", "")
        .replace(
            POINTS,
            &format!(
                "{POINTS}\nvolume = 1.2\ncentre_of_buoyancy = [0.0, 0.0, 0.1]\ncda = 2.0\nlinear_drag = 50.0\nca = 0.8\nadded_inertia = [10.0, 20.0, 30.0]\nwaterplane_area = 1.5\nwaterline = [0.0, 0.0, 0.5]\nmotion = {{ position = [\"0\", \"0\", \"-10.25 + 0.5*sin(t)\"], orientation = [\"0\", \"0\", \"10*t\"] }}\n\n[water]\ndensity = 1025.0"
            ),
        )
}

/// The prescribed box builds: the library's body has the water terms as given (`ca`,
/// `added_inertia`, the points in body axes) and a motion; it starts at the motion's pose and
/// rates at `t = 0` (0.5 m/s up, 10°/s = 0.17453 rad/s about z, to the backward difference's
/// 1e-8), its points moving with it (`V + ω × R s`: point left at (−1, 0, 0.25) m moves at
/// (0, −0.17453, 0.5) m/s); `summary.json`'s components list the water terms and the
/// motion's expressions. A motion that does not start at `position` is refused, naming both.
#[test]
fn a_prescribed_wet_body_starts_with_its_motion() {
    let text = prescribed_box();
    let phstring::ByDim::D3(s) = validate(&text).unwrap() else {
        panic!("not 3D")
    };
    let sys = &s.problem.system;
    assert!(sys.body_has_motion(0) && !sys.body_has_wrench(0));
    let st = &s.problem.state;
    let b = &st.bodies[0];
    let rate = 10.0_f64.to_radians();
    assert!(
        (b.velocity - phstring::body::Vec3::new(0.0, 0.0, 0.5)).norm() < 1e-8,
        "{:?}",
        b.velocity
    );
    assert!((b.omega_space() - phstring::body::Vec3::new(0.0, 0.0, rate)).norm() < 1e-8);
    let v = st.v[2];
    assert!(
        (v - phstring::Vector::<3>::new(0.0, -rate, 0.5)).norm() < 1e-8,
        "{v:?}"
    );
    let c = &s.components.bodies[0];
    let w = c.water.as_ref().unwrap();
    assert_eq!(
        (w.volume, w.cda, w.linear_drag, w.ca, w.waterplane_area),
        (1.2, 2.0, 50.0, 0.8, 1.5)
    );
    assert_eq!(w.centre_of_buoyancy, vec![0.0, 0.0, 0.1]);
    assert_eq!(w.added_inertia, vec![10.0, 20.0, 30.0]);
    assert_eq!(
        c.motion,
        vec!["0", "0", "-10.25 + 0.5*sin(t)", "0", "0", "10*t"]
    );
    let off = text.replace("-10.25 + 0.5*sin(t)", "-10.0 + 0.5*sin(t)");
    let err = refused(&off);
    assert!(
        err.contains("`bodies.box.position` = [0, 0, -10.25] m, but the body's prescribed motion (`bodies.box.motion`) starts at [0, 0, -10] m"),
        "{err}"
    );
}

/// An accepted `added_mass` reaches the body's report as given (3D: the 6×6; the kinetic
/// energy of the started state is then the Kirchhoff form's `½ ξ·(M_RB + A) ξ`, which with
/// the box's surge of 0.5 m/s and yaw of 0.2 rad/s adds `½ A₁₁ u² + ½ A₆₆ Ω²` = 500 + 6 J
/// beside the box's own kinetic energy).
#[test]
fn an_added_mass_matrix_is_taken_as_given() {
    let dry = BOX.replacen(
        POINTS,
        &format!("{POINTS}\nvolume = 1.0\n\n[water]\ndensity = 1025.0"),
        1,
    );
    let wet = BOX.replacen(
        POINTS,
        &format!(
            "{POINTS}\nvolume = 1.0\nadded_mass = [{ADDED_MASS}]\n\n[water]\ndensity = 1025.0"
        ),
        1,
    );
    let energy = |text: &str| {
        let phstring::ByDim::D3(s) = validate(text).unwrap() else {
            panic!("not 3D")
        };
        let sys = &s.problem.system;
        let rows = s.components.bodies[0]
            .water
            .as_ref()
            .and_then(|w| w.added_mass.clone());
        (sys.energies(&s.problem.state).kinetic, rows)
    };
    let (e_dry, none) = energy(&dry);
    let (e_wet, rows) = energy(&wet);
    assert!(none.is_none());
    let rows = rows.unwrap();
    assert_eq!(rows.len(), 6);
    assert_eq!(
        (rows[0][4], rows[4][0], rows[5][5]),
        (-500.0, -500.0, 300.0)
    );
    let extra = 0.5 * 4e3 * 0.25 + 0.5 * 300.0 * 0.04;
    assert!(
        ((e_wet - e_dry) / extra - 1.0).abs() < 1e-12,
        "{e_wet} − {e_dry} against {extra}"
    );
}
