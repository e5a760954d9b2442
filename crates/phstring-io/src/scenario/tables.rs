//! Validation of the table-driven parts of a scenario: `motion_table` and `force_table` of a
//! `[[boundary]]` table, and `[[platform]]` (supports moved rigidly by one table of surge,
//! sway, heave, roll, pitch, yaw). The files are read with [`crate::tables::read_table`],
//! relative to the scenario file's folder.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

use phstring::{Motion, PlatformPath, Sampled, Vector};

use super::components::AXES;
use super::refs::label;
use super::spec::BoundarySpec;
use super::{ScenarioError, ScenarioFile, Skeleton};
use crate::tables::{Table, read_table};
use crate::text::{clip, num};

/// Tolerance of a table's position at `t = 0` against the node's start: `1e-9 max(1, |r₀|)`
/// [m], as for expressions.
pub(super) const START_TOLERANCE: f64 = 1e-9;

/// The components a `motion_table` moves: (component, its signal).
pub(super) type TableMotions = Vec<(usize, Sampled)>;

/// A `force_table`: one signal per component, the components it loads (a column not all
/// zero), a description per component for reports, and the key's span.
pub(super) struct ForceTable {
    pub signals: Vec<Sampled>,
    pub loaded: Vec<bool>,
    pub texts: Vec<String>,
    pub span: Range<usize>,
}

/// One validated `[[platform]]`: its supports (node, body coordinates [m], label, span of
/// the reference) and its path.
pub(super) struct Platform {
    pub nodes: Vec<(usize, Vector<3>, String, Range<usize>)>,
    pub path: Arc<PlatformPath>,
    /// `FILE` for reports.
    pub file: String,
}

impl Platform {
    /// The prescribed motions of the platform's supports, three per node, in node order.
    pub(super) fn motions(&self) -> Vec<Motion> {
        let mut out = Vec::with_capacity(3 * self.nodes.len());
        for &(node, b, _, _) in &self.nodes {
            for c in 0..3 {
                let (p, v) = (self.path.clone(), self.path.clone());
                out.push(Motion::with_rate(
                    node,
                    c,
                    move |t| p.point(t, &b)[c],
                    move |t| v.point_velocity(t, &b)[c],
                ));
            }
        }
        out
    }
}

/// How a report names column `j` (0 = the time) of `file`.
pub(super) fn column_text(file: &str, j: usize, name: &str) -> String {
    format!("table {} column {} ({name})", clip(file), j + 1)
}

impl ScenarioFile {
    /// Every data file the scenario reads, as `(dotted key, the file as the key resolves
    /// it)`: motion and force tables, platform tables, winch payout tables and the bathymetry
    /// grid, in key order.
    pub fn data_files(&self) -> Vec<(String, PathBuf)> {
        let s = &self.scenario;
        let mut out = Vec::new();
        for (k, b) in s.boundary.iter().enumerate() {
            for (name, file) in [
                ("motion_table", &b.motion_table),
                ("force_table", &b.force_table),
            ] {
                if let Some(f) = file {
                    out.push((format!("boundary.{k}.{name}"), self.table_file(f.get_ref())));
                }
            }
        }
        for (k, p) in s.platform.iter().enumerate() {
            let f = &p.motion_table;
            out.push((
                format!("platform.{k}.motion_table"),
                self.table_file(f.get_ref()),
            ));
        }
        for (k, w) in s.winch.iter().enumerate() {
            if let Some(f) = &w.get_ref().payout_table {
                out.push((
                    format!("winch.{k}.payout_table"),
                    self.table_file(f.get_ref()),
                ));
            }
        }
        if let Some(f) = s
            .seabed
            .as_ref()
            .and_then(|b| b.get_ref().bathymetry.as_ref())
        {
            out.push(("seabed.bathymetry".into(), self.table_file(f.get_ref())));
        }
        out
    }

    /// Warnings for the tables that end before `t_end` [s] still changing: after its last
    /// row a table holds that row (zero rate), so the motion, load or payout stops at once
    /// there. (Read again here; a table that cannot be read was reported by its key.)
    pub(super) fn table_end_warnings(&self, t_end: f64) -> Vec<String> {
        let mut out = Vec::new();
        let mut seen: Vec<PathBuf> = Vec::new();
        for (key, path) in self.data_files() {
            // Once per file (a deck's coupled points share one table), by its first key.
            if key == "seabed.bathymetry" || seen.contains(&path) {
                continue;
            }
            seen.push(path.clone());
            let Ok(table) = crate::tables::read_table_any(&path) else {
                continue;
            };
            let (Some(&first), Some(&last)) = (table.times.first(), table.times.last()) else {
                continue;
            };
            if t_end <= last + 1e-9 * t_end.abs().max(1.0) {
                continue;
            }
            // The largest end rate relative to its column's range over the table's span.
            let moving = (0..table.values.len())
                .map(|j| {
                    let col = &table.values[j];
                    let range = col.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    let rate = table.signal(j).rate(last);
                    (
                        j,
                        rate,
                        rate.abs() * (last - first) / range.max(f64::MIN_POSITIVE),
                    )
                })
                .filter(|(_, _, rel)| *rel > 1e-6)
                .max_by(|a, b| a.2.total_cmp(&b.2));
            if let Some((j, rate, _)) = moving {
                out.push(format!(
                    "`{key}`: table {} ends at t = {} s with its column {} still changing ({:.3e} per s); from there to time.end = {} s it holds its last row, so it stops at once",
                    // The file's name alone: the same in a resumed run, whose scenario
                    // path is absolute.
                    clip(&path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())),
                    num(last),
                    j + 2,
                    rate,
                    num(t_end)
                ));
            }
        }
        out
    }

    /// The file a table key names: relative to the scenario file's folder.
    fn table_file(&self, rel: &str) -> PathBuf {
        let rel = std::path::Path::new(rel);
        match self.path.parent() {
            Some(dir) if rel.is_relative() => dir.join(rel),
            _ => rel.to_path_buf(),
        }
    }

    /// Reads the table that `key` names, with `columns` columns; errors name the key and the
    /// file's line.
    pub(super) fn scenario_table(
        &self,
        key: &str,
        file: &toml::Spanned<String>,
        columns: usize,
    ) -> Result<Table, ScenarioError> {
        if file.get_ref().trim().is_empty() {
            return Err(self.invalid(key, file.span(), "is empty: give a table file"));
        }
        read_table(&self.table_file(file.get_ref()), columns)
            .map_err(|e| self.invalid(key, file.span(), e.to_string()))
    }

    /// `boundary.{k}.motion_table`: `D + 1` columns, each component at the node's `start`
    /// position (called `label`) at `t = 0`.
    pub(super) fn entry_motion_table<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
        start: Vector<D>,
        label: &str,
    ) -> Result<TableMotions, ScenarioError> {
        let Some(file) = &b.motion_table else {
            if let Some(cols) = &b.motion_columns {
                return Err(self.invalid(
                    &format!("boundary.{k}.motion_columns"),
                    cols.span(),
                    "picks columns of a motion_table, but this table has none",
                ));
            }
            return Ok(Vec::new());
        };
        let key = format!("boundary.{k}.motion_table");
        if b.position.is_some() {
            return Err(self.invalid(
                &key,
                file.span(),
                "and `position` both prescribe the motion: give one of them",
            ));
        }
        let (table, columns) = self.motion_columns::<D>(k, b, file)?;
        let mut out = Vec::with_capacity(D);
        for i in 0..D {
            let signal = table.signal(columns[i]);
            let at_zero = signal.value(0.0);
            let tol = START_TOLERANCE * start[i].abs().max(1.0);
            // NaN (times so far apart that the interpolant overflows) fails too.
            let starts_there = (at_zero - start[i]).abs() <= tol;
            if !starts_there {
                let row = table.row_near(0.0);
                return Err(self.invalid(
                    &key,
                    file.span(),
                    format!(
                        "{}: component {} is at {} m at t = 0 (row at t = {} s), but {label} starts at {} m (tolerance {} m): the table gives the absolute position",
                        table.at_row(row),
                        AXES[i],
                        num(at_zero),
                        num(table.times[row]),
                        num(start[i]),
                        num(tol)
                    ),
                ));
            }
            out.push((i, signal));
        }
        Ok(out)
    }

    /// The table of `boundary.{k}.motion_table` (`file`) and, per component, its value
    /// column (0: the file's second column): `boundary.{k}.motion_columns`, or all `D`
    /// columns of a table of `D + 1`.
    fn motion_columns<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
        file: &toml::Spanned<String>,
    ) -> Result<(Table, [usize; D]), ScenarioError> {
        let Some(cols) = &b.motion_columns else {
            let table = self.scenario_table(&format!("boundary.{k}.motion_table"), file, D + 1)?;
            return Ok((table, std::array::from_fn(|i| i)));
        };
        let key = format!("boundary.{k}.motion_columns");
        if file.get_ref().trim().is_empty() {
            let key = format!("boundary.{k}.motion_table");
            return Err(self.invalid(&key, file.span(), "is empty: give a table file"));
        }
        let table =
            crate::tables::read_table_any(&self.table_file(file.get_ref())).map_err(|e| {
                self.invalid(
                    &format!("boundary.{k}.motion_table"),
                    file.span(),
                    e.to_string(),
                )
            })?;
        let width = table.values.len() + 1;
        let list = cols.get_ref();
        if list.len() != D {
            return Err(self.invalid(
                &key,
                cols.span(),
                format!(
                    "has {} columns, one per component ({D}) is needed",
                    list.len()
                ),
            ));
        }
        let mut out = [0; D];
        for (i, &c) in list.iter().enumerate() {
            if c < 2 || c > width as i64 {
                return Err(self.invalid(
                    &key,
                    cols.span(),
                    format!(
                        "names column {c} for component {}, but {} has columns 2 to {width} after the time (column 1)",
                        AXES[i],
                        clip(file.get_ref())
                    ),
                ));
            }
            out[i] = (c - 2) as usize;
        }
        Ok((table, out))
    }

    /// `boundary.{k}.force_table`: `D + 1` columns of force [N].
    pub(super) fn entry_force_table<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
    ) -> Result<Option<ForceTable>, ScenarioError> {
        let Some(file) = &b.force_table else {
            return Ok(None);
        };
        let key = format!("boundary.{k}.force_table");
        if b.force.is_some() {
            return Err(self.invalid(
                &key,
                file.span(),
                "and `force` both give the load: give one of them",
            ));
        }
        let table = self.scenario_table(&key, file, D + 1)?;
        Ok(Some(ForceTable {
            signals: (0..D).map(|i| table.signal(i)).collect(),
            loaded: table
                .values
                .iter()
                .map(|c| c.iter().any(|&f| f != 0.0))
                .collect(),
            texts: (0..D)
                .map(|i| column_text(file.get_ref(), i + 1, AXES[i]))
                .collect(),
            span: file.span(),
        }))
    }

    /// `[[platform]]`: dimension 3, a table of 7 columns, nodes that exist (each once,
    /// none a spring's fixed point). The body coordinates of each node are its start
    /// position seen from the platform's pose at `t = 0`, `R(0)ᵀ (r₀ − p(0))`, so that the
    /// supports start where the geometry puts them.
    pub(super) fn platforms<const D: usize>(
        &self,
        sk: &Skeleton<D>,
    ) -> Result<Vec<Platform>, ScenarioError> {
        let mut out = Vec::with_capacity(self.scenario.platform.len());
        for (k, p) in self.scenario.platform.iter().enumerate() {
            let key = |f: &str| format!("platform.{k}.{f}");
            if D != 3 {
                return Err(self.invalid(
                    &key("motion_table"),
                    p.motion_table.span(),
                    format!("a platform moves in 3 dimensions, but dimension = {D}"),
                ));
            }
            let table = self.scenario_table(&key("motion_table"), &p.motion_table, 7)?;
            let path = Arc::new(
                table
                    .platform()
                    .unwrap_or_else(|| unreachable!("read with 7 columns")),
            );
            if p.nodes.get_ref().is_empty() {
                return Err(self.invalid(
                    &key("nodes"),
                    p.nodes.span(),
                    "is empty: list the support nodes the platform carries",
                ));
            }
            let mut nodes: Vec<(usize, Vector<3>, String, Range<usize>)> = Vec::new();
            for (i, r) in p.nodes.get_ref().iter().enumerate() {
                let nkey = format!("platform.{k}.nodes.{i}");
                let node = self.resolve(&nkey, r, &sk.nodes)?;
                self.not_an_anchor(&nkey, r.span(), node, sk)?;
                if let Some(j) = nodes.iter().position(|n| n.0 == node) {
                    return Err(self.invalid(
                        &nkey,
                        r.span(),
                        format!(
                            "is node {node} again (platform.{k}.nodes.{j}): list each node once"
                        ),
                    ));
                }
                let r0 = sk.position(node);
                let r0 = Vector::<3>::new(r0[0], r0[1 % D], r0[2 % D]);
                let b = path.body_coordinates(0.0, &r0);
                nodes.push((node, b, label(r.get_ref(), node), r.span()));
            }
            out.push(Platform {
                nodes,
                path,
                file: p.motion_table.get_ref().clone(),
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use phstring::{ByDim, PortKind, Vector};

    use crate::scenario::{ScenarioFile, parse};
    use crate::test_util::temp_dir;

    /// A 113 m steel wire (EA = 1e8 N, 25 kg/m, 20 elements) hanging in air from an anchor at
    /// the origin to a fairlead at (80, 40) m (chord 89 m), from its static equilibrium, the
    /// fairlead moved by `motion` (the keys of its `[[boundary]]` table), `h` = 0.01 s to 3 s.
    fn wire(motion: &str) -> String {
        format!(
            r#"dimension = 2
[[node]]
name = "anchor"
position = [0.0, 0.0]
[[node]]
name = "sag"
position = [45.0, -15.0]
[[node]]
name = "fairlead"
position = [80.0, 40.0]
[materials.wire]
law = "tension_only_linear"
ea = 1.0e8
rho_a = 25.0
[[string]]
name = "line"
path = ["anchor", "sag", "fairlead"]
elements = 10
material = "wire"
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = "anchor"
fixed = true
[[boundary]]
node = "fairlead"
{motion}
[initial]
equilibrium = true
[time]
h = 0.01
end = 3.0
adaptive = false
"#
        )
    }

    /// Surge of the fairlead [m]: ±2 m with a 5 s period, built up over the first second.
    fn surge(t: f64) -> f64 {
        let tau = std::f64::consts::TAU;
        80.0 + 2.0 * (tau * t / 5.0).sin() * (1.0 - (-(t * t)).exp())
    }
    const SURGE: &str = "80 + 2*sin(2*pi*t/5)*(1 - exp(-t^2))";

    /// Writes `surge` sampled every `dt` s from −0.5 s to 3.5 s as `surge.csv` (with a
    /// header and a comment) next to the scenario `wire.toml`, and returns the scenario and
    /// its folder (the table is read when the scenario is validated).
    fn tabled(dt: f64) -> (ScenarioFile, std::path::PathBuf) {
        let dir = temp_dir("tables", "surge");
        let mut csv = String::from("# fairlead surge, heave fixed\nt, x, y\n");
        let n = (4.0 / dt).round() as usize;
        for i in 0..=n {
            let t = -0.5 + 4.0 * i as f64 / n as f64;
            csv.push_str(&format!("{t}, {}, 40\n", surge(t)));
        }
        std::fs::write(dir.join("surge.csv"), csv).unwrap();
        let text = wire("motion_table = \"surge.csv\"");
        (parse(&text, &dir.join("wire.toml"), &[]).unwrap(), dir)
    }

    /// The fairlead's reaction [N] at every step of the run of `file`, and the largest
    /// relative energy-balance error.
    fn reactions(file: &ScenarioFile) -> (Vec<Vector<2>>, f64) {
        let ByDim::D2(setup) = file.setup().unwrap() else {
            panic!("2-D scenario")
        };
        let (running, _) = setup.start(true, None).unwrap();
        let mut sim = running.problem;
        let (mut out, mut worst) = (Vec::new(), 0.0f64);
        while sim.time() < 3.0 - 1e-9 {
            let r = sim.step().unwrap();
            worst = worst.max(r.relative_balance_error());
            let port = sim
                .ports()
                .iter()
                .find(|p| p.node == 2 && p.kind == PortKind::Velocity)
                .copied()
                .unwrap();
            out.push(port.output);
        }
        (out, worst)
    }

    /// A finely sampled table of a surge gives the fairlead reaction of the expression it
    /// samples, converging as the table is refined, with an exact energy balance.
    #[test]
    fn a_motion_table_reproduces_the_expression_it_samples() {
        let expr = parse(
            &wire(&format!("position = [\"{SURGE}\", \"40\"]")),
            Path::new("wire.toml"),
            &[],
        )
        .unwrap();
        let (reference, _) = reactions(&expr);
        let scale = reference.iter().map(|f| f.norm()).fold(0.0, f64::max);
        assert!(scale > 1e4, "fairlead reaction {scale} N");
        let mut errors = Vec::new();
        for dt in [0.1, 0.05, 0.025] {
            let (file, dir) = tabled(dt);
            let (tab, balance) = reactions(&file);
            std::fs::remove_dir_all(&dir).unwrap();
            assert!(balance < 1e-11, "dt = {dt}: balance error {balance:e}");
            let e = tab
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            errors.push(e / scale);
        }
        // Measured: 7.5e-2, 4.7e-3, 6.5e-4 of the largest reaction (23 kN).
        assert!(errors[2] < 1e-3, "{errors:?}");
        assert!(
            errors[0] / errors[1] > 4.0 && errors[1] / errors[2] > 4.0,
            "{errors:?}"
        );
    }

    /// A 100 mm studless chain (200.1 kg/m, EA = 8.56e8 N, volume-equivalent diameter
    /// 0.1801 m, lumped mass) from an anchor on the seabed at (0, −50) m to a fairlead at
    /// (310, −8) m, 200 m of it laid along the seabed, in 2-D, from its static equilibrium;
    /// the fairlead follows `fairlead.csv` (surge ±1.2 m and heave ±0.8 m at an 8 s period,
    /// built up over 10 s, one row a second, as the decks' vessel tables). `wet`: in 50 m
    /// of water on a seabed of 3e6 Pa/m and 3e5 Pa·s/m (MoorDyn's kBot, cBot); dry: in air
    /// with nothing under it.
    fn chain(wet: bool) -> (String, std::path::PathBuf) {
        let dir = temp_dir("tables", if wet { "wet_chain" } else { "dry_chain" });
        let mut csv = String::from("t, x, y\n");
        for k in 0..=12 {
            let t = k as f64;
            let ramp = if t < 10.0 {
                0.5 * (1.0 - (std::f64::consts::PI * t / 10.0).cos())
            } else {
                1.0
            };
            let w = std::f64::consts::TAU * t / 8.0;
            csv.push_str(&format!(
                "{t}, {:.6}, {:.6}\n",
                310.0 + ramp * 1.2 * w.sin(),
                -8.0 + ramp * 0.8 * w.cos() - 0.8 * ramp
            ));
        }
        std::fs::write(dir.join("fairlead.csv"), csv).unwrap();
        let water = if wet {
            "[water]\ndepth = 50.0\n[seabed]\nstiffness = 3.0e6\ndamping = 3.0e5\n"
        } else {
            ""
        };
        let text = format!(
            r#"dimension = 2
[[node]]
name = "anchor"
position = [0.0, -50.0]
[[node]]
name = "touchdown"
position = [200.0, -50.0]
[[node]]
name = "fairlead"
position = [310.0, -8.0]
[materials.chain]
law = "tension_only_linear"
ea = 8.5606e8
rho_a = 200.1
mass = "lumped"
diameter = 0.1801
cd = 1.333
cd_axial = 0.639
ca = 1.0
[[string]]
name = "line"
path = ["anchor", "touchdown", "fairlead"]
elements = 12
material = "chain"
{water}
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = "anchor"
fixed = true
[[boundary]]
node = "fairlead"
motion_table = "fairlead.csv"
[initial]
equilibrium = true
[time]
h = 0.005
end = 12.0
"#
        );
        (text, dir)
    }

    /// A run of `chain` (scenario text, folder) with `scheme` and step `h` [s] to 6 s: the
    /// tension `EA (√C − 1)` [N] of the fairlead's element at every 0.1 s, the attempts
    /// rejected, the Newton iterations and the largest relative balance error.
    fn tension_run(
        chain: &(String, std::path::PathBuf),
        scheme: &str,
        h: f64,
    ) -> (Vec<f64>, usize, usize, f64) {
        let sets = [format!("time.scheme={scheme}"), format!("time.h={h}")];
        let file = parse(&chain.0, &chain.1.join("chain.toml"), &sets).unwrap();
        let ByDim::D2(setup) = file.setup().unwrap() else {
            panic!("2-D scenario")
        };
        let (running, _) = setup.start(true, None).unwrap();
        let mut sim = running.problem;
        let fairlead = sim
            .system()
            .mesh()
            .elements()
            .iter()
            .position(|e| e.contains(&2))
            .unwrap();
        let (mut out, mut rejected, mut newton, mut worst) = (Vec::new(), 0, 0, 0.0f64);
        let every = (0.1 / h).round() as usize;
        for k in 1..=(6.0 / h).round() as usize {
            let r = sim.step().unwrap();
            rejected += r.rejected;
            newton += r.newton_iterations + r.rejected_iterations;
            worst = worst.max(r.relative_balance_error());
            if k % every == 0 {
                out.push(8.5606e8 * (sim.state().c[fairlead].sqrt() - 1.0));
            }
        }
        (out, rejected, newton, worst)
    }

    /// `dg4` with a table-driven fairlead takes every step at h = 5 ms, dry and on a damped
    /// seabed, and its fairlead tension agrees with `dg` at h = 0.625 ms to 1 % of the
    /// largest (measured: 7.1e-4 dry, 2.5e-3 wet; against `dg` at 0.3125 ms 1.1e-3 and
    /// 5.2e-3, where `dg` at 0.625 ms is off by 5e-4 and 1.6e-3: the stiff chain's axial
    /// ringing is not resolved at 5 ms). On the seabed the backward sub-step of a single triple jump at 5 ms sits
    /// next to the contact's singular step (`c s ≈ 2m + k s²`, docs/method.md §19): before
    /// the split into two triple jumps (19.4) it had 201 rejected attempts in these 6 s and
    /// was off by 2.3e-2; the table is not involved (the same line driven by an expression
    /// had 197, dry none).
    #[test]
    fn dg4_follows_a_motion_table_on_a_damped_seabed_without_rejected_steps() {
        for wet in [false, true] {
            let file = chain(wet);
            let (dg4, rejected, newton, balance) = tension_run(&file, "dg4", 0.005);
            let (reference, _, _, _) = tension_run(&file, "dg", 0.000625);
            std::fs::remove_dir_all(&file.1).unwrap();
            assert_eq!(rejected, 0, "wet = {wet}: {rejected} rejected attempts");
            assert!(balance < 1e-11, "wet = {wet}: balance {balance:e}");
            let scale = reference.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            let err = dg4
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f64, f64::max);
            eprintln!(
                "wet = {wet}: max tension {scale} N, |dg4 − dg| {err} N, {newton} Newton iterations"
            );
            assert!(err < 1e-2 * scale, "wet = {wet}: {err} N of {scale} N");
        }
    }

    /// The message of validating `scenario` (written as `s.toml` with the files `files`
    /// beside it).
    fn refusal(scenario: &str, files: &[(&str, &str)]) -> String {
        let dir = temp_dir("tables", "refusal");
        for (name, text) in files {
            std::fs::write(dir.join(name), text).unwrap();
        }
        let file = parse(scenario, &dir.join("s.toml"), &[]).unwrap();
        let e = file.setup().err().expect("refused").to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        e.replace(&format!("{}/", dir.display()), "")
    }

    #[test]
    fn refuses_bad_tables_naming_the_file_line_and_value() {
        let at = |motion: &str| wire(motion);
        let e = refusal(
            &at("motion_table = \"m.csv\""),
            &[("m.csv", "t x y\n0 80 40\n1 80.5 40\n1 81 40\n")],
        );
        assert_eq!(
            e,
            "s.toml:27:16: `boundary.1.motion_table` m.csv:4: time 1 s is not after 1 s (line 3): times must increase strictly"
        );
        let e = refusal(
            &at("motion_table = \"m.csv\""),
            &[("m.csv", "0, 80.001, 40\n1, 81, 40\n")],
        );
        assert_eq!(
            e,
            "s.toml:27:16: `boundary.1.motion_table` m.csv:1: component x is at 80.001 m at t = 0 (row at t = 0 s), but \"fairlead\" (node 2) starts at 80 m (tolerance 8e-8 m): the table gives the absolute position"
        );
        // Times so far apart that the interpolant overflows at t = 0: refused, not NaN.
        let e = refusal(
            &at("motion_table = \"m.csv\""),
            &[("m.csv", "-1e308 80 40\n1e308 80 40\n")],
        );
        assert!(
            e.contains("m.csv:1: component x is at NaN m at t = 0"),
            "{e}"
        );
        let e = refusal(
            &at("motion_table = \"m.csv\""),
            &[("m.csv", "0 80\n1 81\n")],
        );
        assert!(
            e.ends_with("m.csv:1: has 2 columns, the table needs 3 (time, then 2)"),
            "{e}"
        );
        let e = refusal(&at("motion_table = \"m.csv\""), &[("m.csv", "0 80 40\n")]);
        assert!(e.ends_with("table m.csv: has 1 rows of data, at least 2 are needed (time in the first column, then 2 more)"), "{e}");
        let e = refusal(
            &at("force_table = \"f.csv\""),
            &[("f.csv", "0 0 0\n1 nan 0\n")],
        );
        assert!(
            e.ends_with("`boundary.1.force_table` f.csv:2: column 2 is nan, not a finite number"),
            "{e}"
        );
        let e = refusal(&at("motion_table = \"missing.csv\""), &[]);
        assert!(
            e.contains("`boundary.1.motion_table` cannot read table missing.csv: "),
            "{e}"
        );
        let e = refusal(
            &at("motion_table = \"m.csv\"\nposition = [\"80\", \"40\"]"),
            &[("m.csv", "0 80 40\n1 80 40\n")],
        );
        assert!(e.ends_with("`boundary.1.motion_table` and `position` both prescribe the motion: give one of them"), "{e}");
        let e = refusal(
            &at("motion_table = \"m.csv\"\nexternal = true"),
            &[("m.csv", "0 80 40\n1 80 40\n")],
        );
        assert!(
            e.contains("`boundary.1.external` marks an FMU input"),
            "{e}"
        );
        // A load from a table on a component that a table moves.
        let e = refusal(
            &at(
                "motion_table = \"m.csv\"\n[[boundary]]\nnode = \"fairlead\"\nforce_table = \"f.csv\"",
            ),
            &[("m.csv", "0 80 40\n1 80 40\n"), ("f.csv", "0 0 5\n1 0 5\n")],
        );
        assert!(e.ends_with("`boundary.2.force_table` \"fairlead\" (node 2) has a prescribed position (boundary.1.motion_table) in component y and cannot also be loaded in it (give \"0\" there)"), "{e}");
        // A platform needs three dimensions.
        let e = refusal(
            &format!(
                "{}\n[[platform]]\nnodes = [\"sag\"]\nmotion_table = \"p.csv\"\n",
                at("fixed = true")
            ),
            &[("p.csv", "0 0 0 0 0 0 0\n1 0 0 0 0 0 0\n")],
        );
        assert!(
            e.ends_with(
                "`platform.0.motion_table` a platform moves in 3 dimensions, but dimension = 2"
            ),
            "{e}"
        );
    }

    /// A force table loads the node with its interpolant at the mid-step (here a straight
    /// ramp, which the interpolant reproduces exactly) and is held beyond its last row.
    #[test]
    fn a_force_table_is_the_nodal_load() {
        let dir = temp_dir("tables", "force");
        std::fs::write(
            dir.join("f.csv"),
            "t,Fx,Fy\n0,0,-1000\n1,500,-1500\n2,1000,-2000\n",
        )
        .unwrap();
        let text = wire("force_table = \"f.csv\"")
            .replace(
                "[[boundary]]\nnode = \"anchor\"",
                "[[boundary]]\nnode = \"fairlead\"\nfixed = true\n[[boundary]]\nnode = \"anchor\"",
            )
            .replacen(
                "node = \"fairlead\"\nforce_table",
                "node = \"sag\"\nforce_table",
                1,
            );
        let file = parse(&text, &dir.join("s.toml"), &[]).unwrap();
        let ByDim::D2(v) = file.validated().unwrap() else {
            panic!()
        };
        std::fs::remove_dir_all(&dir).unwrap();
        let load = &v.problem.boundary.loads[0];
        assert_eq!(load.node, 1);
        let f = (load.force)(0.25);
        assert!(
            (f - Vector::<2>::new(125.0, -1125.0)).norm() < 1e-12,
            "{f:?}"
        );
        assert_eq!((load.force)(7.0), Vector::<2>::new(1000.0, -2000.0));
        assert_eq!(v.components.loads[0].force[1], "table f.csv column 3 (y)");
    }

    /// Three fairleads carried by a platform whose table yaws, pitches, surges and heaves
    /// it at constant rates (rows at 0, 1, 2 s: the interpolant is exact on straight
    /// columns): each support is at `p(t) + R(t) b` with `R = Rx(roll) Ry(pitch) Rz(yaw)`,
    /// moves at its derivative, and a run keeps the energy balance.
    #[test]
    fn a_platform_table_moves_its_supports_rigidly() {
        let dir = temp_dir("tables", "platform");
        std::fs::write(
            dir.join("p.csv"),
            "# t x y z roll pitch yaw\n0 0 0 0 0 0 0\n1 0.5 0 0.1 0 0.02 0.05\n2 1.0 0 0.2 0 0.04 0.1\n",
        )
        .unwrap();
        let mut text = String::from("dimension = 3\n");
        let fair = [
            [20.0, 0.0, -5.0],
            [-10.0, 17.32, -5.0],
            [-10.0, -17.32, -5.0],
        ];
        for (i, f) in fair.iter().enumerate() {
            let a = [f[0] * 8.0, f[1] * 8.0, -100.0];
            text += &format!(
                "[[node]]\nname = \"a{i}\"\nposition = {a:?}\n[[node]]\nname = \"f{i}\"\nposition = {f:?}\n[[string]]\nname = \"l{i}\"\npath = [\"a{i}\", \"f{i}\"]\nelements = 8\nmaterial = \"chain\"\n[[boundary]]\nnode = \"a{i}\"\nfixed = true\n"
            );
        }
        text += "[materials.chain]\nlaw = \"tension_only_linear\"\nea = 5.0e8\nrho_a = 100.0\n[body_force]\ngravity = [0.0, 0.0, -9.81]\n[[platform]]\nname = \"hull\"\nnodes = [\"f0\", \"f1\", \"f2\"]\nmotion_table = \"p.csv\"\n[time]\nh = 0.01\nend = 0.5\n";
        let file = parse(&text, &dir.join("s.toml"), &[]).unwrap();
        let ByDim::D3(setup) = file.setup().unwrap() else {
            panic!()
        };
        std::fs::remove_dir_all(&dir).unwrap();
        let motions = &setup.problem.system.boundary().motions;
        assert_eq!(motions.len(), 9);
        let t = 1.3;
        let rot = phstring::signal::rotation(0.0, 0.02 * t, 0.05 * t);
        let p = Vector::<3>::new(0.5 * t, 0.0, 0.1 * t);
        for (k, f) in fair.iter().enumerate() {
            let want = p + rot * Vector::<3>::from_column_slice(f);
            for c in 0..3 {
                let m = &motions[3 * k + c];
                assert_eq!((m.node, m.component), (2 * k + 1, c));
                assert!(((m.position)(t) - want[c]).abs() < 1e-12, "f{k} {c}");
                let fd = ((m.position)(t + 1e-6) - (m.position)(t - 1e-6)) / 2e-6;
                assert!((m.velocity(t) - fd).abs() < 1e-8, "f{k} {c}");
            }
        }
        let (running, _) = setup.start(true, None).unwrap();
        let mut sim = running.problem;
        for _ in 0..50 {
            let r = sim.step().unwrap();
            assert!(r.relative_balance_error() < 1e-11, "{r:?}");
        }
    }
}
