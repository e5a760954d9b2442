//! `phstring check`: validates a scenario file and prints what would run.

use std::path::{Path, PathBuf};

use anyhow::Result;
use phstring_io::moordyn::Mapping;
use phstring_io::scenario::{ScenarioFile, Validated};
use phstring_io::text::{clip, num, nums, printable};

use crate::budget::{self, budget};

// The arguments of `phstring check`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// Override a scenario key by its dotted path.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// For a MoorDyn deck: drop a feature phstring does not model (EI, rods, bodies, …;
    /// docs/moordyn.md).
    #[arg(long = "ignore", value_name = "FEATURE")]
    pub ignore: Vec<String>,
    /// For a MoorDyn deck: the vessel motion, a table `t, x, y, z, roll, pitch, yaw` [s, m,
    /// rad] that moves the deck's Vessel/Coupled points rigidly (docs/moordyn.md); the run
    /// ends at its last time unless --set time.end=… is given.
    #[arg(long, value_name = "FILE")]
    pub motion: Option<PathBuf>,
    /// Print the scenario as run (for a deck, the one generated from it, with the line
    /// numbers its messages refer to) instead of checking it.
    #[arg(long)]
    pub print_scenario: bool,
}

/// `phstring check`: validates the scenario of `args` (a scenario file or a MoorDyn deck)
/// with its `--set` overrides and prints what would run, with the estimate of what it
/// takes and the warnings; for a deck first the table of what each deck entry became.
/// With `--print-scenario`, prints the scenario text (after `--set`) and nothing else.
pub fn check(args: &CheckArgs) -> Result<()> {
    let path = args.scenario.as_path();
    let loaded = budget::load_any(path, &args.sets, &args.ignore, args.motion.as_deref())?;
    let file = &loaded.file;
    if args.print_scenario {
        say!("{}", file.text().trim_end());
        return Ok(());
    }
    if let Some(m) = &loaded.mapping {
        say!("{}", mapping_table(path, m));
    }
    // The system the scenario sets up must be valid too (finite initial energies and
    // forces); set it up only where it fits in memory (otherwise the warning below says so).
    let validated = file.validated()?;
    let text = phstring::by_dim!(&validated, v => describe(file, v));
    let warnings = if budget(file)?.memory_error(1).is_none() {
        phstring::by_dim!(file.build(validated)?, s => s.warnings)
    } else {
        Vec::new()
    };
    let what = match &loaded.mapping {
        Some(_) => format!("the scenario generated from {}", path.display()),
        None => path.display().to_string(),
    };
    say!("{what} is valid:\n{text}");
    let b = budget(file)?;
    say!("  estimate:  {}", b.describe());
    for w in warnings.iter().chain(&b.warnings(1)) {
        tell!("warning: {w}");
    }
    Ok(())
}

/// The table of what each entry of the deck at `path` became, then the conversions with a
/// caveat, the entries not needed and the features dropped.
fn mapping_table(path: &Path, m: &Mapping) -> String {
    use std::fmt::Write;
    // Deck text is clipped; the mapping's own sentences (which quote it clipped) are not.
    let p = |t: &str| printable(&clip(t), false).into_owned();
    let full = |t: &str| printable(t, false).into_owned();
    let mut out = format!(
        "{} is a MoorDyn {} deck; it maps onto a phstring scenario as follows:\n",
        path.display(),
        m.record.version
    );
    let _ = writeln!(out, "  {:>5}  {:<40}  became", "line", "deck entry");
    for r in &m.rows {
        let line = if r.line == 0 {
            "-".to_string()
        } else {
            r.line.to_string()
        };
        let _ = writeln!(out, "  {line:>5}  {:<40}  {}", p(&r.entry), full(&r.became));
    }
    for c in &m.record.converted {
        let _ = writeln!(out, "  converted: {}", full(c));
    }
    for (k, why) in &m.record.not_needed {
        let _ = writeln!(out, "  not needed: {}: {}", p(k), full(why));
    }
    for i in &m.record.ignored {
        let _ = writeln!(out, "  ignored:   {}", full(i));
    }
    let _ = write!(
        out,
        "  (the generated scenario: `phstring check {} --print-scenario`; messages about it name `{}` and its lines)",
        path.display(),
        phstring_io::moordyn::generated_name(path).display()
    );
    out
}

/// Most entries of one kind (strings, springs, fixed nodes, …) that `check` lists.
const LISTED: usize = 20;

/// Lists `items` with `line`, at most [`LISTED`], then how many more there are.
fn list<T>(out: &mut String, items: &[T], what: &str, line: impl Fn(&T) -> String) {
    use std::fmt::Write;
    for item in items.iter().take(LISTED) {
        let _ = writeln!(out, "{}", line(item));
    }
    if items.len() > LISTED {
        let _ = writeln!(out, "  …          and {} more {what}", items.len() - LISTED);
    }
}

fn describe<const D: usize>(file: &ScenarioFile, v: &Validated<D>) -> String {
    let p = &v.problem;
    let c = &v.components;
    let s = &v.settings;
    let mut out = String::new();
    use std::fmt::Write;
    let _ = writeln!(
        out,
        "  title:     {}",
        printable(
            &clip(file.scenario.title.as_deref().unwrap_or("(none)")),
            false
        )
    );
    let _ = writeln!(out, "  dimension: {D}");
    let node = |i: usize| c.node_label(i);
    if v.network {
        let _ = writeln!(
            out,
            "  mesh:      {} elements, {} nodes: {} strings, {} springs, {} named nodes",
            p.mesh.n_elements(),
            p.mesh.n_nodes(),
            c.strings.len(),
            c.springs.len(),
            c.nodes.len()
        );
        list(&mut out, &c.nodes, "named nodes", |n| {
            format!("  node:      {} at {} m", node(n.node), nums(&n.position))
        });
        list(&mut out, &c.strings, "strings", |st| {
            let spans = st.path_nodes.len() - 1;
            format!(
                "  string:    {}: {} elements ({spans} span{} of {}), {} to {}, {} ({}), EA = {} N, rhoA = {} kg/m, {} mass, reference length {} m, body force {} N/m",
                st.name,
                st.elements[1] - st.elements[0],
                if spans == 1 { "" } else { "s" },
                st.elements_per_span,
                node(st.path_nodes[0]),
                node(st.path_nodes[spans]),
                st.law,
                st.material,
                num(st.ea),
                num(st.rho_a),
                st.mass,
                num(st.reference_length),
                nums(&st.body_force)
            )
        });
        list(&mut out, &c.springs, "springs", |sp| {
            let to = match &sp.to_point {
                Some(pt) => format!("the fixed point {} m", nums(pt)),
                None => node(sp.nodes[1]),
            };
            format!(
                "  spring:    {}: {} to {to}, k = {} N/m, rest length {} m",
                sp.name,
                node(sp.nodes[0]),
                num(sp.k),
                num(sp.rest)
            )
        });
    } else {
        // One string: its group carries the material.
        let st = &c.strings[0];
        let _ = writeln!(
            out,
            "  mesh:      {} elements, {} nodes, reference length {} m",
            p.mesh.n_elements(),
            p.mesh.n_nodes(),
            num(p.mesh.total_length())
        );
        let _ = writeln!(
            out,
            "  material:  {}, EA = {} N, rhoA = {} kg/m, {} mass",
            st.law,
            num(st.ea),
            num(st.rho_a),
            st.mass
        );
        let _ = writeln!(out, "  body force: {} N/m", nums(&st.body_force));
    }
    describe_water(&mut out, p);
    list(&mut out, &c.supports, "fixed nodes", |f| {
        format!("  fixed:     {} ({})", node(f.node), f.fixed.join(", "))
    });
    list(&mut out, &c.loads, "loads", |l| {
        let exprs: Vec<String> = l.force.iter().map(|e| clip(e).into_owned()).collect();
        format!("  force:     {}: [{}] N", node(l.node), exprs.join(", "))
    });
    list(&mut out, &c.motions, "motions", |m| {
        format!(
            "  motion:    {} {} = {} m (velocity in, reaction out)",
            node(m.node),
            m.component,
            clip(&m.position)
        )
    });
    list(&mut out, &c.point_masses, "point masses", |pm| {
        format!(
            "  mass:      {}: {} kg, weight {} N",
            node(pm.node),
            num(pm.kg),
            nums(&pm.weight)
        )
    });
    describe_bodies(&mut out, &c.bodies);
    describe_winches(&mut out, &c.winches, node);
    let steps = (s.t_end / s.step.h).round() as usize;
    let _ = writeln!(
        out,
        "  time:      {} scheme, h = {} s, T = {} s, {steps} steps",
        s.step.scheme.name(),
        num(s.step.h),
        num(s.t_end)
    );
    let _ = write!(
        out,
        "  newton:    {}, max {} iterations, solver {}",
        newton_test(&s.step.newton),
        s.step.newton.max_iter,
        s.step.solver.name()
    );
    out
}

/// The winches' lines of `check`: each winch's string, drum, payout and reserve.
fn describe_winches(
    out: &mut String,
    winches: &[phstring_io::scenario::WinchComponent],
    node: impl Fn(usize) -> String,
) {
    list(out, winches, "winches", |w| {
        let drum = if let Some((body, point)) = &w.on_body {
            format!("a drum on body {body}, at {point:?} m in its axes")
        } else if w.drum_position.is_empty() {
            "a fixed drum".to_string()
        } else {
            let exprs: Vec<String> = w
                .drum_position
                .iter()
                .map(|e| clip(e).into_owned())
                .collect();
            format!("the drum at [{}] m", exprs.join(", "))
        };
        let drive = match &w.drum {
            Some(d) => format!("a drum with dynamics: {d}"),
            None if w.external => format!(
                "payout speed an input (external: the FMU's winch.{}.speed; `run` holds the payout at 0)",
                w.name
            ),
            None => match &w.payout_table {
                Some(file) => format!("payout [m] from the table {}", clip(file)),
                None => format!("payout = {} m", clip(&w.payout)),
            },
        };
        format!(
            "  winch:     {}: pays out string {} from {} ({drum}), {drive}, {} elements of {} m on the drum (can pay out {} m)",
            w.name,
            w.string,
            node(w.drum_node),
            w.reserve_elements,
            num(w.element_length),
            num(w.capacity)
        )
    });
}

/// The rigid bodies: mass, weight, inertia, initial pose, each point with what attaches
/// there, the feedback law and the wrench port.
fn describe_bodies(out: &mut String, bodies: &[phstring_io::scenario::BodyComponent]) {
    use std::fmt::Write;
    for b in bodies {
        let j = &b.inertia;
        let _ = writeln!(
            out,
            "  body:      {}: {} kg, weight {} N, inertia [{}, {}, {}] kg·m² (body axes), centre at {} m, orientation {} deg",
            b.name,
            num(b.mass),
            nums(&b.weight),
            nums(&j[0]),
            nums(&j[1]),
            nums(&j[2]),
            nums(&b.position),
            nums(&b.orientation)
        );
        for p in &b.points {
            let _ = writeln!(
                out,
                "  point:     {} (node {}) at {} m in body axes, {} m in space; holds {}",
                p.name,
                p.node,
                nums(&p.point),
                nums(&p.position),
                p.attached.join(", ")
            );
        }
        if !b.motion.is_empty() {
            let list: Vec<String> = b.motion.iter().map(|e| clip(e).into_owned()).collect();
            let _ = writeln!(
                out,
                "  motion:    {}: prescribed [{}] (position m, then angles deg; or a table of x, y, z m, roll, pitch, yaw rad), reaction force and torque out",
                b.name,
                list.join(", ")
            );
        }
        if !b.feedback.is_empty() {
            let list: Vec<String> = b.feedback.iter().map(|e| clip(e).into_owned()).collect();
            let _ = writeln!(
                out,
                "  feedback:  {}: PD on the pose, {} (gains per space axis; reference position m, then angles deg; force and torque at the mid-step, velocity and angular velocity out)",
                b.name,
                list.join(", ")
            );
        }
        if !b.wrench_force.is_empty() || !b.wrench_torque.is_empty() || b.wrench_external {
            let list = |l: &[String]| {
                let v: Vec<String> = l.iter().map(|e| clip(e).into_owned()).collect();
                if v.is_empty() {
                    "0".to_string()
                } else {
                    format!("[{}]", v.join(", "))
                }
            };
            let _ = writeln!(
                out,
                "  wrench:    {}: force {} N, torque {} N·m (space axes; velocity and angular velocity out){}",
                b.name,
                list(&b.wrench_force),
                list(&b.wrench_torque),
                if b.wrench_external {
                    "; external: an input of a front end, starting at these values"
                } else {
                    ""
                }
            );
        }
    }
}

/// The Newton convergence test in words: `‖R‖ ≤ max(tol, rtol·F)` or `‖R‖ ≤ tol`.
fn newton_test(n: &phstring::NewtonParams) -> String {
    if n.rtol > 0.0 {
        format!("‖R‖ ≤ max({} N, {} × force scale)", num(n.tol), num(n.rtol))
    } else {
        format!("‖R‖ ≤ {} N (absolute)", num(n.tol))
    }
}

/// `[water]`, `[seabed]` and what feels them: each wet string's diameter and coefficients and
/// its weight in water per unit length `(ρA − ρ_w π d²/4) g` [N/m], each point's volume and
/// weight in water `(m − ρ_w V) g` [N].
/// A bathymetry grid in one phrase: its points, extent and depth range.
fn bathymetry_text(g: &phstring::Bathymetry) -> String {
    let (lo, hi) = g
        .depths()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    let span = |t: &[f64]| format!("{} … {} m", num(t[0]), num(t[t.len() - 1]));
    if g.is_profile() {
        format!(
            "a bathymetry profile of {} points over x = {}, {} to {} m deep",
            g.x().len(),
            span(g.x()),
            num(lo),
            num(hi)
        )
    } else {
        format!(
            "a bathymetry grid of {} × {} points over x = {}, y = {}, {} to {} m deep",
            g.x().len(),
            g.y().len(),
            span(g.x()),
            span(g.y()),
            num(lo),
            num(hi)
        )
    }
}

fn describe_water<const D: usize>(out: &mut String, p: &phstring::Network<D, phstring::Material>) {
    use std::fmt::Write;
    let Some(w) = &p.water else { return };
    let _ = writeln!(
        out,
        "  water:     density {} kg/m³, surface at 0, g = {} m/s², current {}",
        num(w.density),
        num(w.gravity),
        match &w.current {
            phstring::Current::Uniform(u) => format!("{} m/s", nums(u.as_slice())),
            _ => "a depth profile".to_string(),
        }
    );
    if let Some(sb) = &w.seabed {
        let _ = writeln!(
            out,
            "  seabed:    {}, stiffness {} Pa/m, damping {} Pa·s/m, {}",
            match &sb.surface {
                phstring::SeabedSurface::Flat { depth } => format!("flat at −{} m", num(*depth)),
                phstring::SeabedSurface::Grid(g) => bathymetry_text(g),
                _ => "an inclined plane".to_string(),
            },
            num(sb.stiffness),
            num(sb.damping),
            match sb.friction {
                Some(f) => format!("friction μ = {}", num(f.coefficient)),
                None => "no friction".to_string(),
            }
        );
    }
    let area = |d: f64| std::f64::consts::PI * d * d / 4.0;
    for (g, h) in &p.hydro.lines {
        let grp = &p.groups[*g];
        let wet = (grp.rho_a - w.density * area(h.diameter)) * w.gravity;
        let _ = writeln!(
            out,
            "  in water:  {}: d = {} m, Cd = {}, CdAx = {}, Ca = {}, CaAx = {}, weight in water {} N/m{}",
            grp.name,
            num(h.diameter),
            num(h.cd),
            num(h.cd_axial),
            num(h.ca),
            num(h.ca_axial),
            num(wet),
            if wet < 0.0 { " (it floats)" } else { "" }
        );
    }
    for ph in &p.hydro.points {
        let mass: f64 = p
            .point_masses
            .iter()
            .filter(|m| m.node == ph.node)
            .map(|m| m.mass)
            .sum();
        let _ = writeln!(
            out,
            "  in water:  point at node {}: volume {} m³, CdA = {} m², Ca = {}, weight in water {} N",
            ph.node,
            num(ph.volume),
            num(ph.cda),
            num(ph.ca),
            num((mass - w.density * ph.volume) * w.gravity)
        );
    }
    for b in &p.bodies {
        let Some(h) = &b.hydro else { continue };
        let wet = (b.mass - w.density * h.volume) * w.gravity;
        // The added-mass matrix's diagonal and its largest off-diagonal entry (the plane's
        // x, y, θ in 2D).
        let matrix = h.added_mass.map_or(String::new(), |a| {
            let idx: Vec<usize> = if D == 2 {
                vec![0, 1, 5]
            } else {
                (0..6).collect()
            };
            let diag: Vec<f64> = idx.iter().map(|&k| a[(k, k)]).collect();
            let off = idx
                .iter()
                .flat_map(|&r| idx.iter().map(move |&c| (r, c)))
                .filter(|(r, c)| r != c)
                .map(|(r, c)| a[(r, c)].abs())
                .fold(0.0, f64::max);
            format!(
                ", added-mass matrix diagonal {} (kg, kg·m²), largest coupling {}",
                nums(&diag),
                num(off)
            )
        });
        let moments = match h.waterplane_moments {
            [0.0, 0.0] => String::new(),
            m => format!(" with moments {} m⁴", nums(&m[..D.min(3) - 1])),
        };
        let _ = writeln!(
            out,
            "  in water:  body {}: volume {} m³ at {} m (body axes), CdA = {} m², linear drag {} N·s/m, Ca = {}, added inertia {} kg·m²{matrix}, waterplane {} m² at {} m{moments}, weight in water {} N{}",
            b.name,
            num(h.volume),
            nums(&h.centre_of_buoyancy.as_slice()[..D.min(3)]),
            num(h.cda),
            num(h.linear_drag),
            num(h.ca),
            nums(h.added_inertia.as_slice()),
            num(h.waterplane_area),
            nums(&h.waterline.as_slice()[..D.min(3)]),
            num(wet),
            if wet < 0.0 { " (it floats)" } else { "" }
        );
    }
}
