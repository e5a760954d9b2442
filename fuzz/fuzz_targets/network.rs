//! Fuzz target: network scenarios. The bytes choose a structured network — `[[node]]`s,
//! `[materials.NAME]`, `[[string]]`s whose paths name nodes (by name, index or
//! `"STRING:INDEX"`), `[[spring]]`s (between two nodes or to a fixed point), point masses,
//! supports, prescribed motions, loads, PD control and `[time]` settings — written as TOML.
//! It is parsed and validated; if it is valid, a simulation is set up and takes a few steps.
//! Properties: nothing panics, and every accepted step has a finite energy balance.
#![no_main]

use std::fmt::Write as _;
use std::path::Path;

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use phstring::{Material, Simulation};
use phstring_io::scenario;

/// Most steps taken by an accepted scenario.
const STEP_BUDGET: usize = 6;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(text) = network_toml(&mut u) else {
        return;
    };
    // To see the scenario of an artifact: `PHSTRING_FUZZ_PRINT=1 cargo fuzz run network FILE`.
    if std::env::var_os("PHSTRING_FUZZ_PRINT").is_some() {
        eprintln!("{text}");
    }
    let Ok(file) = scenario::parse(&text, Path::new("network.toml"), &[]) else {
        return;
    };
    match file.dimension() {
        Ok(1) => simulate::<1>(&file),
        Ok(2) => simulate::<2>(&file),
        Ok(3) => simulate::<3>(&file),
        _ => {}
    }
});

/// Validates `file` and, if it is valid, takes up to [`STEP_BUDGET`] steps.
fn simulate<const D: usize>(file: &scenario::ScenarioFile) {
    let Ok(v) = file.validate::<D>() else {
        return;
    };
    let t_end = v.settings.t_end;
    let Ok(mut sim) = Simulation::<D, Material>::new(v.problem, v.settings.step) else {
        return;
    };
    for _ in 0..STEP_BUDGET {
        if sim.time() >= t_end - 1e-9 * sim.step_size() {
            break;
        }
        let Ok(report) = sim.step_until(t_end) else {
            break;
        };
        assert!(
            report.balance_error.is_finite(),
            "step {}: balance error {} (Ĥ {} → {} J, supplied {} J, dissipated {} J)\n{}",
            report.step,
            report.balance_error,
            report.before.hamiltonian(),
            report.after.hamiltonian(),
            report.supplied,
            report.dissipated,
            file.text()
        );
        assert!(report.after.hamiltonian().is_finite(), "{}", file.text());
    }
}

/// One of `values`.
fn pick<'a, T>(u: &mut Unstructured, values: &'a [T]) -> Result<&'a T> {
    u.choose(values)
}

/// A number: mostly from `usual`, sometimes from a list of extreme values.
fn number(u: &mut Unstructured, usual: &[f64]) -> Result<f64> {
    const EXTREME: [f64; 10] = [
        0.0, -1.0, 1e-300, 1e-12, 1e12, 1e154, 1e300, -1e300, 5e-324, 1.7e308,
    ];
    if u.ratio(1, 12)? {
        Ok(*pick(u, &EXTREME)?)
    } else {
        Ok(*pick(u, usual)?)
    }
}

/// A TOML float (`inf` and `nan` as TOML spells them).
fn float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        format!("{x:e}")
    }
}

/// A node reference: a `[[node]]` name, a mesh index, or a node along an earlier string.
fn node_ref(u: &mut Unstructured, nodes: usize, strings: usize) -> Result<String> {
    Ok(match u.int_in_range(0..=5)? {
        0 => format!("{}", u.int_in_range(-3i64..=(nodes as i64 + 2))?),
        1 if strings > 0 => format!(
            "\"s{}:{}\"",
            u.int_in_range(0..=strings - 1)?,
            u.int_in_range(-3i64..=6)?
        ),
        2 => format!("\"n{}\"", u.int_in_range(0..=nodes)?),
        _ => format!("\"n{}\"", u.int_in_range(0..=nodes.saturating_sub(1))?),
    })
}

/// Position expressions of a moving support at a node that starts at `start`: a motion
/// starting there (or, sometimes, not), `""` for free components.
fn motion(u: &mut Unstructured, start: &[f64]) -> Result<String> {
    let mut parts = Vec::new();
    for &x in start {
        parts.push(match u.int_in_range(0..=4)? {
            0 => "\"\"".to_string(),
            1 => format!(
                "\"{x:e} + {:e}*sin({:e}*t)\"",
                number(u, &[0.01, 0.5, 2.0])?,
                number(u, &[1.0, 6.0, 50.0])?
            ),
            2 => format!("\"{x:e} + {:e}*t\"", number(u, &[0.1, 1.0, 10.0])?),
            3 => format!("\"{:e} + t\"", x + 1.0),
            _ => format!("\"{x:e}\""),
        });
    }
    Ok(format!("[{}]", parts.join(", ")))
}

/// `d` expressions of a force [N].
fn force(u: &mut Unstructured, d: usize) -> Result<String> {
    let mut parts = Vec::new();
    for _ in 0..d {
        parts.push(match u.int_in_range(0..=3)? {
            0 => "\"0\"".to_string(),
            1 => format!("\"{:e}\"", number(u, &[-100.0, 10.0, 1e4])?),
            2 => format!(
                "\"{:e}*sin({:e}*t)\"",
                number(u, &[1.0, 500.0, 1e5])?,
                number(u, &[1.0, 20.0])?
            ),
            _ => "\"1/t\"".to_string(),
        });
    }
    Ok(format!("[{}]", parts.join(", ")))
}

/// The scenario text.
fn network_toml(u: &mut Unstructured) -> Result<String> {
    let d = *pick(u, &[2usize, 3, 3, 2, 1])?;
    let mut t = format!("dimension = {d}\n\n");
    if u.ratio(3, 4)? {
        let mut g = vec![0.0; d];
        g[d - 1] = number(u, &[-9.81, -1.62, 0.0])?;
        let g: Vec<String> = g.into_iter().map(float).collect();
        let _ = writeln!(t, "[body_force]\ngravity = [{}]\n", g.join(", "));
    }
    // Materials.
    let materials = u.int_in_range(1..=2)?;
    for m in 0..materials {
        let law = pick(
            u,
            &[
                "tension_only_linear",
                "linear_elastic",
                "hyperelastic",
                "st_venant_kirchhoff",
                "tension_only_hyperelastic",
            ],
        )?;
        let _ = writeln!(
            t,
            "[materials.m{m}]\nlaw = \"{law}\"\nea = {}\nrho_a = {}\nmass = \"{}\"",
            float(number(u, &[1e5, 1e7, 1e8, 1e9])?),
            float(number(u, &[0.5, 1.0, 20.0])?),
            pick(u, &["lumped", "consistent"])?
        );
        if u.ratio(1, 4)? {
            let _ = writeln!(t, "drag = {}", float(number(u, &[0.0, 1.0, 100.0])?));
        }
        if u.ratio(1, 4)? {
            let _ = writeln!(t, "kelvin_voigt = {}", float(number(u, &[0.0, 1e3, 1e5])?));
        }
        t.push('\n');
    }
    // Named nodes on a coarse grid (so that some coincide), sometimes scaled far out.
    let nodes = u.int_in_range(2..=6)?;
    let scale = number(u, &[1.0, 10.0, 100.0])?;
    let mut positions = Vec::new();
    for n in 0..nodes {
        let p: Vec<f64> = (0..d)
            .map(|_| Ok(scale * f64::from(u.int_in_range(-3i8..=3)?)))
            .collect::<Result<_>>()?;
        let text: Vec<String> = p.iter().copied().map(float).collect();
        let _ = writeln!(
            t,
            "[[node]]\nname = \"n{n}\"\nposition = [{}]\n",
            text.join(", ")
        );
        positions.push(p);
    }
    // Strings.
    let strings = u.int_in_range(1..=3)?;
    for s in 0..strings {
        let len = u.int_in_range(2..=4)?;
        let path: Vec<String> = (0..len)
            .map(|_| node_ref(u, nodes, s))
            .collect::<Result<_>>()?;
        let _ = writeln!(
            t,
            "[[string]]\nname = \"s{s}\"\npath = [{}]\nelements = {}\nmaterial = \"m{}\"",
            path.join(", "),
            u.int_in_range(0i64..=6)?,
            u.int_in_range(0..=materials)?
        );
        if u.ratio(1, 3)? {
            let _ = writeln!(
                t,
                "prestretch = {}",
                float(number(u, &[1.0, 1.001, 0.99, 1.1])?)
            );
        }
        t.push('\n');
    }
    // Springs.
    for k in 0..u.int_in_range(0..=2)? {
        let a = node_ref(u, nodes, strings)?;
        let _ = write!(t, "[[spring]]\nname = \"k{k}\"\n");
        if u.ratio(1, 2)? {
            let p: Vec<String> = (0..d).map(|i| float(i as f64 + 0.5)).collect();
            let _ = writeln!(t, "between = [{a}]\nto_point = [{}]", p.join(", "));
        } else {
            let _ = writeln!(t, "between = [{a}, {}]", node_ref(u, nodes, strings)?);
        }
        let _ = writeln!(
            t,
            "k = {}\nrest = {}",
            float(number(u, &[100.0, 1e4, 1e6])?),
            float(number(u, &[0.0, 0.5, 1.0])?)
        );
        if u.ratio(1, 4)? {
            let _ = writeln!(t, "damping = {}", float(number(u, &[10.0, 1e3])?));
        }
        t.push('\n');
    }
    // Point masses.
    for _ in 0..u.int_in_range(0..=2)? {
        let _ = writeln!(
            t,
            "[[point_mass]]\nnode = {}\nkg = {}\n",
            node_ref(u, nodes, strings)?,
            float(number(u, &[1.0, 200.0, 2000.0])?)
        );
    }
    // Boundary conditions: supports, motions, loads and control, mostly at named nodes (whose
    // start is known, so that motions can start there).
    for _ in 0..u.int_in_range(1..=4)? {
        let n = u.int_in_range(0..=nodes - 1)?;
        let node = if u.ratio(5, 6)? {
            format!("\"n{n}\"")
        } else {
            node_ref(u, nodes, strings)?
        };
        let _ = writeln!(t, "[[boundary]]\nnode = {node}");
        match u.int_in_range(0..=5)? {
            0 | 1 => t.push_str("fixed = true\n"),
            2 => {
                let axis = ["x", "y", "z"][u.int_in_range(0..=d - 1)?];
                let _ = writeln!(t, "fixed = [\"{axis}\"]");
            }
            3 => {
                let _ = writeln!(t, "position = {}", motion(u, &positions[n])?);
            }
            4 => {
                let _ = writeln!(t, "force = {}", force(u, d)?);
            }
            _ => {
                let kd = float(number(u, &[10.0, 1e3, 1e5])?);
                if u.ratio(1, 2)? {
                    let _ = writeln!(t, "control = {{ kd = {kd} }}");
                } else {
                    let reference: Vec<String> = positions[n]
                        .iter()
                        .map(|x| format!("\"{x:e} + 0.1*sin(t)\""))
                        .collect();
                    let _ = writeln!(
                        t,
                        "control = {{ kp = {}, kd = {kd}, reference = [{}] }}",
                        float(number(u, &[100.0, 1e4, 1e6])?),
                        reference.join(", ")
                    );
                }
            }
        }
        t.push('\n');
    }
    // Time: a few steps.
    let h = number(u, &[1e-3, 0.01, 0.05])?;
    let steps = f64::from(u.int_in_range(1u8..=5)?);
    let _ = writeln!(
        t,
        "[time]\nh = {}\nend = {}\nscheme = \"{}\"\nadaptive = {}\nmax_halvings = {}",
        float(h),
        float(h * steps),
        pick(u, &["dg", "mp", "dg4"])?,
        u.ratio(3, 4)?,
        u.int_in_range(0..=8)?
    );
    if u.ratio(1, 4)? {
        let tol = float(number(u, &[1e-3, 1e-6, 1e-9])?);
        let _ = writeln!(t, "rtol = {tol}\natol = {tol}");
    }
    // Error per step: with the tolerances above, or without them (refused, never a panic).
    if u.ratio(1, 4)? {
        let _ = writeln!(t, "error_per_step = {}", u.ratio(1, 2)?);
    }
    Ok(t)
}
