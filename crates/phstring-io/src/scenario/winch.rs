//! `[[winch]]`: winches of a network, each paying out one `[[string]]` from a drum at its
//! first path node (docs/method.md §23, docs/scenario.md).

use std::sync::Arc;

use phstring::{Material, Network, Winch, WinchDrum};
use toml::Spanned;

use super::components::WinchComponent;
use super::expr::Expr;
use super::spec::{DrumSpec, WinchSpec};
use super::{ScenarioError, ScenarioFile};

/// A winch's string as built: the winch's index in the file, its string's group and the
/// elements parked on its drum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WinchString {
    pub winch: usize,
    pub group: usize,
    pub reserve: usize,
}

impl ScenarioFile {
    /// The winch of string `name`, if one pays it out: its index and table.
    pub(super) fn winch_of(&self, name: &str) -> Option<(usize, &WinchSpec)> {
        self.scenario
            .winch
            .iter()
            .enumerate()
            .find(|(_, w)| w.get_ref().string.get_ref() == name)
            .map(|(k, w)| (k, w.get_ref()))
    }

    /// Checks the `[[winch]]` tables before the strings are built: a network's, each
    /// naming a `[[string]]` of the file that no other winch names, with a name of its own
    /// and exactly one of `payout` and `external = true`.
    pub(super) fn check_winch_tables(&self, network: bool) -> Result<(), ScenarioError> {
        let s = &self.scenario;
        for (k, w) in s.winch.iter().enumerate() {
            let spec = w.get_ref();
            let key = |f: &str| format!("winch.{k}.{f}");
            if !network {
                return Err(self.invalid(
                    &key("string"),
                    w.span(),
                    "belongs to a network: a winch pays out a [[string]] from a drum at its first path node (a single-string scenario has none)",
                ));
            }
            let name = spec.string.get_ref();
            if !s
                .string
                .iter()
                .any(|st| st.get_ref().name.get_ref() == name)
            {
                let known: Vec<&str> = s
                    .string
                    .iter()
                    .map(|st| st.get_ref().name.get_ref().as_str())
                    .collect();
                return Err(self.invalid(
                    &key("string"),
                    spec.string.span(),
                    format!(
                        "= \"{}\" is not a [[string]] of this scenario (strings: {})",
                        crate::text::clip(name),
                        known.join(", ")
                    ),
                ));
            }
            // Outputs (winches.csv's rows) and FMU variables are named after it.
            self.checked_name(&key("name"), spec.name.get_ref(), spec.name.span())?;
            if let Some(j) =
                (0..k).find(|&j| s.winch[j].get_ref().name.get_ref() == spec.name.get_ref())
            {
                return Err(self.invalid(
                    &key("name"),
                    spec.name.span(),
                    format!(
                        "= \"{}\" is already the name of winch.{j}: names must differ (outputs and FMU variables are named after them)",
                        crate::text::clip(spec.name.get_ref())
                    ),
                ));
            }
            self.check_winch_payout(k, w)?;
            if let Some(j) = (0..k).find(|&j| s.winch[j].get_ref().string.get_ref() == name) {
                return Err(self.invalid(
                    &key("string"),
                    spec.string.span(),
                    format!(
                        "= \"{}\" is already paid out by winch.{j}: a string has one winch",
                        crate::text::clip(name)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks that winch `k` (table `w`) has exactly one drive: `payout`, `payout_table`,
    /// `external = true` or `[winch.drum]`.
    fn check_winch_payout(&self, k: usize, w: &Spanned<WinchSpec>) -> Result<(), ScenarioError> {
        let spec = w.get_ref();
        let key = format!("winch.{k}.payout");
        if let Some(table) = &spec.payout_table {
            let clash = if spec.payout.is_some() {
                Some("`payout`")
            } else if external(spec) {
                Some("`external = true`")
            } else if spec.drum.is_some() {
                Some("[winch.drum]")
            } else {
                None
            };
            if let Some(other) = clash {
                return Err(self.invalid(
                    &format!("winch.{k}.payout_table"),
                    table.span(),
                    format!("and {other} both drive the payout: give one of them"),
                ));
            }
            return Ok(());
        }
        match (&spec.payout, external(spec), &spec.drum) {
            (Some(p), true, _) => Err(self.invalid(
                &key,
                p.span(),
                format!(
                    "cannot be given with `external = true`, which makes the payout speed an input of the FMU (winch.{}.speed): remove one of them",
                    crate::text::clip(spec.name.get_ref())
                ),
            )),
            (_, true, Some(d)) => Err(self.invalid(
                &format!("winch.{k}.drum"),
                d.span(),
                "cannot be given with `external = true`: a drum with dynamics moves its payout itself (hold its motor pull from Python with set_winch_force instead)",
            )),
            (Some(p), false, Some(_)) => Err(self.invalid(
                &key,
                p.span(),
                "and [winch.drum] exclude each other: a drum with dynamics moves the payout itself",
            )),
            (None, false, None) => Err(self.invalid(
                &key,
                w.span(),
                "is missing: give the length paid out since t = 0 [m] as an expression of t (or a `payout_table`), `external = true` to set the payout speed from the FMU, or a [winch.drum]",
            )),
            _ => Ok(()),
        }
    }

    /// The elements winch `k` parks on its drum: its `reserve` [m] over the string's element
    /// length `l` [m], rounded up.
    pub(super) fn reserve_elements(
        &self,
        k: usize,
        spec: &WinchSpec,
        l: f64,
    ) -> Result<usize, ScenarioError> {
        let Some(r) = &spec.reserve else {
            return Ok(0);
        };
        let m = *r.get_ref();
        if !(m >= 0.0 && m.is_finite()) || m / l > 1e6 {
            return Err(self.invalid(
                &format!("winch.{k}.reserve"),
                r.span(),
                format!(
                    "= {} m must be at least 0 and finite, and at most a million elements of {} m",
                    crate::text::num(m),
                    crate::text::num(l)
                ),
            ));
        }
        Ok((m / l - 1e-9).ceil().max(0.0) as usize)
    }

    /// The winches on `network` (their strings built as `strings`), with their payout and
    /// drum expressions; their report entries into `report`.
    pub(super) fn attach_winches<const D: usize>(
        &self,
        mut network: Network<D, Material>,
        strings: &[WinchString],
        report: &mut Vec<WinchComponent>,
    ) -> Result<Network<D, Material>, ScenarioError> {
        let t_check = self.first_mid_time();
        // In file order (the strings are in theirs): the winches' outputs, `energy.csv`'s
        // winch columns and Python's indices follow the `[[winch]]` tables.
        let mut in_file_order: Vec<&WinchString> = strings.iter().collect();
        in_file_order.sort_by_key(|ws| ws.winch);
        for ws in in_file_order {
            let spec = self.scenario.winch[ws.winch].get_ref();
            let key = |f: &str| format!("winch.{}.{f}", ws.winch);
            let (payout, dynamics) = self.winch_drive(ws.winch, spec)?;
            let mut drum = Vec::new();
            if let Some(d) = &spec.drum_position {
                if d.get_ref().len() != D {
                    return Err(self.invalid(
                        &key("drum_position"),
                        d.span(),
                        format!(
                            "must have {D} expressions (dimension = {D}), got {}",
                            d.get_ref().len()
                        ),
                    ));
                }
                for txt in d.get_ref() {
                    drum.push(
                        Expr::new(txt, t_check)
                            .map_err(|m| self.invalid(&key("drum_position"), d.span(), m))?,
                    );
                }
            }
            let grp = &network.groups[ws.group];
            let first = grp.elements.start;
            let l = network.mesh.lengths()[first];
            let drum_node = network.mesh.elements()[first + ws.reserve][0];
            report.push(WinchComponent {
                name: spec.name.get_ref().clone(),
                string: spec.string.get_ref().clone(),
                drum_node,
                reserve_elements: ws.reserve,
                element_length: l,
                capacity: ws.reserve as f64 * l,
                payout: match (&payout, &spec.payout_table) {
                    (Some((_, text)), None) => text.clone(),
                    _ => String::new(),
                },
                payout_table: spec.payout_table.as_ref().map(|f| f.get_ref().clone()),
                external: external(spec),
                drum_position: drum.iter().map(|e| e.text().to_string()).collect(),
                on_body: None,
                drum: dynamics.as_ref().map(|(_, text)| text.clone()),
            });
            let drum_motion: Option<phstring::DrumFn> = (!drum.is_empty()).then(|| {
                let f: phstring::DrumFn = Arc::new(move |t| {
                    let mut x = [0.0; 3];
                    for (k, e) in drum.iter().enumerate() {
                        x[k] = e.eval(t).unwrap_or(f64::NAN);
                    }
                    x
                });
                f
            });
            network = network.with_winch(Winch {
                name: spec.name.get_ref().clone(),
                group: ws.group,
                reserve: ws.reserve,
                payout: match payout {
                    Some((p, _)) => p,
                    None => Arc::new(|_| 0.0),
                },
                drum_motion,
                drum: dynamics.map(|(d, _)| d),
            });
        }
        Ok(network)
    }

    /// Fills in `report` (in the winches' file order) which winches have their drum on a
    /// rigid body of `network`: the string's first path node is a body's point.
    pub(super) fn report_body_drums<const D: usize>(
        network: &Network<D, Material>,
        strings: &[WinchString],
        report: &mut [WinchComponent],
    ) {
        for ws in strings {
            let first = network.groups[ws.group].elements.start;
            let path_start = network.mesh.elements()[first][0];
            let Some(entry) = report.get_mut(ws.winch) else {
                continue;
            };
            entry.on_body = network.bodies.iter().find_map(|b| {
                let a = b.attachments.iter().find(|a| a.node == path_start)?;
                Some((b.name.clone(), a.point.iter().copied().collect()))
            });
        }
    }

    /// Winch `k`'s drive: its payout expression (checked 0 at `t = 0`), its drum with
    /// dynamics and a description of it, or neither (`external = true`). A payout comes
    /// with its text for the reports: the expression, or `table FILE`.
    #[allow(clippy::type_complexity)]
    fn winch_drive(
        &self,
        k: usize,
        spec: &WinchSpec,
    ) -> Result<
        (
            Option<(phstring::PayoutFn, String)>,
            Option<(WinchDrum, String)>,
        ),
        ScenarioError,
    > {
        let key = |f: &str| format!("winch.{k}.{f}");
        let t_check = self.first_mid_time();
        // The combinations are checked with the tables ([`Self::check_winch_payout`]).
        if let Some(d) = &spec.drum {
            return Ok((None, Some(self.drum_dynamics(k, d.get_ref())?)));
        }
        if let Some(file) = &spec.payout_table {
            return Ok((Some(self.payout_table(k, file)?), None));
        }
        // An external winch's payout follows the speed its front end sets, 0 until then.
        let Some(p) = &spec.payout else {
            return Ok((None, None));
        };
        let payout = Expr::new(p.get_ref(), t_check)
            .map_err(|m| self.invalid(&key("payout"), p.span(), m))?;
        let at_zero = payout.eval(0.0).unwrap_or(f64::NAN);
        if at_zero != 0.0 {
            return Err(self.invalid(
                &key("payout"),
                p.span(),
                format!(
                    "is {at_zero} m at t = 0: it is the length paid out since t = 0, so 0 then"
                ),
            ));
        }
        let text = payout.text().to_string();
        let f: phstring::PayoutFn = Arc::new(move |t| payout.eval(t).unwrap_or(f64::NAN));
        Ok((Some((f, text)), None))
    }

    /// Winch `k`'s payout from its `payout_table` (`file`): columns `t, payout [m]`, the C¹
    /// interpolant of motion tables, 0 at `t = 0` (to 1e-9 of the table's largest payout,
    /// at least 1e-9 m; what is left there is taken out); with its text `table FILE`.
    fn payout_table(
        &self,
        k: usize,
        file: &Spanned<String>,
    ) -> Result<(phstring::PayoutFn, String), ScenarioError> {
        let key = format!("winch.{k}.payout_table");
        let table = self.scenario_table(&key, file, 2)?;
        let signal = table.signal(0);
        let largest = table.values[0].iter().fold(1.0f64, |m, p| m.max(p.abs()));
        let at_zero = signal.value(0.0);
        // NaN (times so far apart that the interpolant overflows) fails too.
        let at_rest = at_zero.abs() <= super::tables::START_TOLERANCE * largest;
        if !at_rest {
            let row = table.row_near(0.0);
            return Err(self.invalid(
                &key,
                file.span(),
                format!(
                    "{}: the payout is {at_zero} m at t = 0 (row at t = {} s): it is the length paid out since t = 0, so 0 then",
                    table.at_row(row),
                    table.times[row]
                ),
            ));
        }
        let text = format!("table {}", crate::text::clip(file.get_ref()));
        // Within the tolerance, the table's value at t = 0 is its rounding: taken out, so
        // that the payout is 0 at t = 0 exactly, as a winch needs.
        let f: phstring::PayoutFn = Arc::new(move |t| signal.value(t) - at_zero);
        Ok((f, text))
    }

    /// The drum of `[winch.drum]` of winch `k` and its description: `J/R²`, the motor's pull
    /// (`tension`, or `torque/R`), damping, derivative time and brake, each checked.
    fn drum_dynamics(&self, k: usize, d: &DrumSpec) -> Result<(WinchDrum, String), ScenarioError> {
        let key = |f: &str| format!("winch.{k}.drum.{f}");
        let t_check = self.first_mid_time();
        let value = |f: &str, v: &Option<Spanned<f64>>, positive: bool| {
            let Some(v) = v else {
                return Ok(None);
            };
            let x = *v.get_ref();
            if !(x.is_finite() && (x > 0.0 || (!positive && x == 0.0))) {
                let bound = if positive { "> 0" } else { "≥ 0" };
                return Err(self.invalid(
                    &key(f),
                    v.span(),
                    format!("= {x} must be finite and {bound}"),
                ));
            }
            Ok(Some(x))
        };
        let radius = value("radius", &d.radius, true)?;
        let needs_radius = |f: &str, span: std::ops::Range<usize>| {
            radius.ok_or_else(|| {
                self.invalid(
                    &key(f),
                    span,
                    "needs the drum's radius (winch.drum.radius [m]) to act at the rope",
                )
            })
        };
        let inertia = match value("inertia", &d.inertia, false)? {
            Some(j) => {
                j / needs_radius("inertia", d.inertia.as_ref().map_or(0..0, |v| v.span()))?.powi(2)
            }
            None => 0.0,
        };
        let damping = value("damping", &d.damping, false)?.unwrap_or(0.0);
        let derivative_time = value("derivative_time", &d.derivative_time, false)?.unwrap_or(0.0);
        let dg4 = self.scenario.time.scheme.get_ref() == "dg4";
        if let Some(tau) = d
            .derivative_time
            .as_ref()
            .filter(|_| derivative_time > 0.0 && dg4)
        {
            return Err(self.invalid(
                &key("derivative_time"),
                tau.span(),
                format!(
                    "= {derivative_time} s is not supported with time.scheme = \"dg4\" (its backward sub-step makes the derivative of the rope's pull change sign): use dg or mp"
                ),
            ));
        }
        let brake = match value("brake", &d.brake, false)? {
            Some(hold) => Some((
                hold,
                value("brake_slip", &d.brake_slip, true)?.unwrap_or(1e-3),
            )),
            None => None,
        };
        let mut text = vec![format!("inertia {inertia} kg at the rope")];
        let force: phstring::DrumForceFn = match (&d.tension, &d.torque) {
            (Some(_), Some(q)) => {
                return Err(self.invalid(
                    &key("torque"),
                    q.span(),
                    "and winch.drum.tension exclude each other (a tension controller's motor pulls with the target tension)",
                ));
            }
            (Some(tn), None) => {
                let e = Expr::new(tn.get_ref(), t_check)
                    .map_err(|m| self.invalid(&key("tension"), tn.span(), m))?;
                text.push(format!("motor pull (target tension) {} N", e.text()));
                Arc::new(move |t| e.eval(t).unwrap_or(f64::NAN))
            }
            (None, Some(q)) => {
                let r = needs_radius("torque", q.span())?;
                let e = Expr::new(q.get_ref(), t_check)
                    .map_err(|m| self.invalid(&key("torque"), q.span(), m))?;
                text.push(format!("motor torque {} N·m over {r} m", e.text()));
                Arc::new(move |t| e.eval(t).unwrap_or(f64::NAN) / r)
            }
            (None, None) => Arc::new(|_| 0.0),
        };
        if damping > 0.0 {
            text.push(format!("damping {damping} N·s/m"));
        }
        if derivative_time > 0.0 {
            text.push(format!("derivative time {derivative_time} s"));
        }
        if let Some((hold, slip)) = brake {
            text.push(format!("brake {hold} N (slip {slip} m/s)"));
        }
        let drum = WinchDrum {
            derivative_time,
            inertia,
            force,
            damping,
            brake,
        };
        Ok((drum, text.join(", ")))
    }
}

/// Whether `spec` marks its payout speed as a front end's input (`external = true`).
fn external(spec: &WinchSpec) -> bool {
    spec.external.as_ref().is_some_and(|x| *x.get_ref())
}
