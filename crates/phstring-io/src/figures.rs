//! The figures of a run drawn from its outputs read back ([`crate::history`]): the energy,
//! configuration and increment plots ([`draw_plots`]) and the animation
//! ([`draw_animation`]), each skipped with a warning rather than failing the run.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::files::{
    ELEMENTS_FILE, END_TENSIONS_FILE, ENERGY_SPLIT_STEM, FAIRLEAD_TENSION_STEM, WINCH_LENGTH_STEM,
    WINCH_TENSION_STEM, WINCHES_FILE,
};
use crate::history::{History, WaterHistory, read_topology};
use crate::output::PLOT_POINTS;
use crate::plot::{self, PlotError, Series, Topology};
use crate::scene::Scene;

/// What [`draw_plots`] did.
#[derive(Debug, Clone, Default)]
pub struct PlotReport {
    /// Plots written (stems, each as `.svg` and `.png`).
    pub written: Vec<String>,
    /// Plots not written (degenerate or extreme data, a stop request, a failure).
    pub skipped: Vec<String>,
    /// Why each skipped plot was skipped.
    pub warnings: Vec<String>,
}

impl PlotReport {
    /// Records the outcome of drawing `stem` (called `label` in warnings): written, skipped
    /// with the error, or skipped because the plotting library panicked.
    fn record<T, E: std::fmt::Display>(
        &mut self,
        stem: &str,
        label: &str,
        outcome: std::thread::Result<Result<T, E>>,
    ) {
        match outcome {
            Ok(Ok(_)) => self.written.push(stem.to_string()),
            Ok(Err(e)) => {
                self.skipped.push(stem.to_string());
                self.warnings.push(format!("{label} skipped: {e}"));
            }
            Err(_) => {
                self.skipped.push(stem.to_string());
                self.warnings.push(format!(
                    "{label} skipped: the plotting library failed on this data"
                ));
            }
        }
    }
}

/// Draws where the energy of a run in water went ([`ENERGY_SPLIT_STEM`]): the running
/// totals against time of the energy supplied at the boundaries (the ports other than the
/// current) and by the current, dissipated by drag, seabed damping, seabed friction and the
/// rest (material damping), and the energy stored since the start `Ĥ(t) − Ĥ(0)`, which is
/// the supplied minus the dissipated. Mechanisms that never did anything (a share that stays
/// exactly zero) are left out of the legend.
pub fn energy_split_plot(
    stem: &Path,
    title: &str,
    w: &WaterHistory,
    end_of_loading: Option<f64>,
) -> Result<(), PlotError> {
    let ports: Vec<f64> = w
        .supplied
        .iter()
        .zip(&w.current)
        .map(|(s, c)| s - c)
        .collect();
    let water_dissipated = w.drag.iter().zip(&w.seabed).zip(&w.friction);
    let other: Vec<f64> = w
        .dissipated
        .iter()
        .zip(water_dissipated)
        .map(|(d, ((a, b), c))| d - (a + b + c))
        .collect();
    let candidates: [(&str, &[f64]); 7] = [
        ("stored: Ĥ(t) − Ĥ(0)", &w.stored),
        ("supplied at the boundaries", &ports),
        ("supplied by the current", &w.current),
        ("dissipated by drag", &w.drag),
        ("dissipated by seabed damping", &w.seabed),
        ("dissipated by seabed friction", &w.friction),
        ("dissipated by material damping", &other),
    ];
    // The material share is a difference of sums: zero up to their round-off.
    let scale = w.dissipated.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let series: Vec<Series> = candidates
        .iter()
        .enumerate()
        .filter(|(k, (_, y))| {
            let floor = if *k == 6 { 1e-9 * scale } else { 0.0 };
            *k == 0 || y.iter().any(|v| v.abs() > floor)
        })
        .map(|(_, (label, y))| Series { label, x: &w.t, y })
        .collect();
    plot::series_plot(
        stem,
        &format!("{title}: where the energy went"),
        "t [s]",
        "energy since t = 0 [J]",
        &series,
        false,
        end_of_loading.map(|t| (t, "end of loading")),
    )
}

/// The rows of `end_tensions.csv` in `dir` (`t` and the tensions [N]), evenly thinned to
/// at most [`PLOT_POINTS`] rows (every `k`-th, `k` doubling as the file grows, and the last
/// row); `None` if there is no such file.
fn read_end_tensions(dir: &Path) -> Result<Option<Vec<Vec<f64>>>, String> {
    let path = dir.join(END_TENSIONS_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
    };
    let (mut rows, mut every, mut last) = (Vec::new(), 1usize, None);
    for (k, line) in text.lines().skip(1).enumerate() {
        let row: Vec<f64> = line
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| format!("{END_TENSIONS_FILE} line {}: not numbers", k + 2))?;
        if k % every == 0 {
            rows.push(row);
            if rows.len() >= PLOT_POINTS {
                let mut j = 0;
                rows.retain(|_| {
                    j += 1;
                    (j - 1) % 2 == 0
                });
                every *= 2;
            }
            last = None;
        } else {
            last = Some(row);
        }
    }
    rows.extend(last);
    Ok(Some(rows))
}

/// Draws the fairlead tension of every string against time ([`FAIRLEAD_TENSION_STEM`])
/// from `end_tensions.csv` in `dir` (columns `FairTen<i>`), each string named as in
/// `topology` (its string groups in order).
pub fn fairlead_tension_plot(
    dir: &Path,
    title: &str,
    topology: Option<&Topology>,
) -> Result<(), PlotError> {
    let stem = dir.join(FAIRLEAD_TENSION_STEM);
    let input = |message: String| PlotError::Input {
        path: stem.clone(),
        message,
    };
    let rows = read_end_tensions(dir)
        .map_err(input)?
        .ok_or_else(|| input(format!("{END_TENSIONS_FILE} was not written")))?;
    let n = rows.first().map_or(0, |r| r.len().saturating_sub(1) / 2);
    let t: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let columns: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            rows.iter()
                .map(|r| r.get(1 + 2 * i).copied().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let names: Vec<String> = topology
        .map(|t| {
            t.groups
                .iter()
                .filter(|g| !g.spring)
                .map(|g| g.name.clone())
                .collect()
        })
        .unwrap_or_default();
    let labels: Vec<String> = (0..n)
        .map(|i| match names.get(i) {
            Some(name) => format!("{name} (FairTen{})", i + 1),
            None => format!("FairTen{}", i + 1),
        })
        .collect();
    let series: Vec<Series> = labels
        .iter()
        .zip(&columns)
        .map(|(label, y)| Series { label, x: &t, y })
        .collect();
    plot::series_plot(
        &stem,
        &format!("{title}: fairlead tension"),
        "t [s]",
        "fairlead tension [N]",
        &series,
        false,
        None,
    )
}

/// Per winch of `winches.csv` in `dir` (in the order they first appear), its name and its
/// rows `(t, length off the drum, drum tension)`, at most about [`PLOT_POINTS`] each (every
/// `k`-th row, and the last); `None` without the file.
#[allow(clippy::type_complexity)]
fn read_winches(dir: &Path) -> Result<Option<Vec<(String, Vec<[f64; 3]>)>>, String> {
    let path = dir.join(WINCHES_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
    };
    let mut winches: Vec<(String, Vec<[f64; 3]>)> = Vec::new();
    for (k, line) in text.lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let num = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok());
        let (Some(t), Some(length), Some(tension)) = (num(0), num(3), num(5)) else {
            return Err(format!("{WINCHES_FILE} line {}: not a winch row", k + 2));
        };
        let name = f.get(1).copied().unwrap_or_default();
        match winches.iter_mut().find(|(n, _)| n == name) {
            Some((_, rows)) => rows.push([t, length, tension]),
            None => winches.push((name.to_string(), vec![[t, length, tension]])),
        }
    }
    for (_, rows) in &mut winches {
        let every = rows.len().div_ceil(PLOT_POINTS).max(1);
        let last = rows.last().copied();
        let mut j = 0;
        rows.retain(|_| {
            j += 1;
            (j - 1) % every == 0
        });
        if let Some(l) = last
            && rows.last() != Some(&l)
        {
            rows.push(l);
        }
    }
    Ok(Some(winches))
}

/// Draws each winch's string length off the drum ([`WINCH_LENGTH_STEM`]) or its tension at
/// the drum ([`WINCH_TENSION_STEM`], `stem`) against time from `winches.csv` in `dir`.
pub fn winch_plot(dir: &Path, stem: &str) -> Result<(), PlotError> {
    let path = dir.join(stem);
    let input = |message: String| PlotError::Input {
        path: path.clone(),
        message,
    };
    let winches = read_winches(dir)
        .map_err(input)?
        .ok_or_else(|| input(format!("{WINCHES_FILE} was not written")))?;
    let (column, what, unit) = if stem == WINCH_LENGTH_STEM {
        (1, "length off the drum", "length off the drum [m]")
    } else {
        (2, "tension at the drum", "tension at the drum [N]")
    };
    let columns: Vec<(Vec<f64>, Vec<f64>)> = winches
        .iter()
        .map(|(_, rows)| {
            (
                rows.iter().map(|r| r[0]).collect(),
                rows.iter().map(|r| r[column]).collect(),
            )
        })
        .collect();
    let series: Vec<Series> = winches
        .iter()
        .zip(&columns)
        .map(|((name, _), (t, y))| Series {
            label: name,
            x: t,
            y,
        })
        .collect();
    plot::series_plot(
        &path,
        &format!("winches: {what}"),
        "t [s]",
        unit,
        &series,
        false,
        None,
    )
}

/// Draws the `energy`, `configuration` (2D and 3D) and `increments` plots of a run into
/// `dir`, and for a run in water the plot of where the energy went
/// ([`energy_split_plot`]). A plot that cannot be drawn (degenerate or extreme ranges, an I/O error, a
/// failure inside the plotting library) is skipped with a warning and never fails the run;
/// once `stop` is set, the remaining plots are skipped. `history = Err(reason)` (it could
/// not be read, or reading it was stopped) skips all. The configuration is drawn in
/// `scene` (its snapshots are in its plane, see [`Scene`]). With `end_tensions.csv` in
/// `dir`, the fairlead tensions are drawn too ([`fairlead_tension_plot`]); with
/// `winches.csv`, the winches' lengths off the drum and drum tensions ([`winch_plot`]).
pub fn draw_plots(
    dir: &Path,
    dim: usize,
    (title, scene): (&str, &Scene),
    end_of_loading: Option<f64>,
    history: Result<&History, &str>,
    stop: Option<&AtomicBool>,
) -> PlotReport {
    let mut report = PlotReport::default();
    let mut stems = vec!["energy"];
    let configuration = history.is_ok_and(|h| dim >= 2 && !h.snapshots.is_empty());
    if configuration || (history.is_err() && dim >= 2) {
        stems.push("configuration");
    }
    stems.push("increments");
    if history.is_ok_and(|h| h.water.is_some()) {
        stems.push(ENERGY_SPLIT_STEM);
    }
    if dir.join(END_TENSIONS_FILE).is_file() {
        stems.push(FAIRLEAD_TENSION_STEM);
    }
    if dir.join(WINCHES_FILE).is_file() {
        stems.extend([WINCH_LENGTH_STEM, WINCH_TENSION_STEM]);
    }
    let h = match history {
        Ok(h) => h,
        Err(why) => {
            for s in stems {
                report.skipped.push(s.to_string());
                report.warnings.push(format!("{s} plot skipped: {why}"));
            }
            return report;
        }
    };
    let (ti, inc) = h.increments();
    // The network drawn by the configuration plot (a chain in a folder without it).
    let topology = if configuration || stems.contains(&FAIRLEAD_TENSION_STEM) {
        read_topology(dir).map_err(|e| e.to_string())
    } else {
        Ok(None)
    };
    for stem in stems {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            report.skipped.push(stem.to_string());
            report
                .warnings
                .push(format!("{stem} plot skipped: stop requested"));
            continue;
        }
        let path = dir.join(stem);
        let draw = || match stem {
            "energy" => {
                plot::energy_plot(&path, title, &h.t, &h.kinetic, &h.potential, &h.hamiltonian)
            }
            "configuration" => match &topology {
                Ok(Some(t)) => plot::network_plot_in(&path, title, t, &h.snapshots, scene),
                Ok(None) => plot::configuration_plot(&path, title, &h.snapshots),
                Err(e) => Err(PlotError::Input {
                    path: path.clone(),
                    message: e.clone(),
                }),
            },
            FAIRLEAD_TENSION_STEM => {
                fairlead_tension_plot(dir, title, topology.as_ref().ok().and_then(Option::as_ref))
            }
            WINCH_LENGTH_STEM | WINCH_TENSION_STEM => winch_plot(dir, stem),
            ENERGY_SPLIT_STEM => match &h.water {
                Some(w) => energy_split_plot(&path, title, w, end_of_loading),
                None => Ok(()),
            },
            _ => plot::series_plot(
                &path,
                title,
                "t [s]",
                "|Ĥ(n+1) − Ĥ(n)| [J]",
                &[Series {
                    label: "|ΔĤ| per step",
                    x: &ti,
                    y: &inc,
                }],
                true,
                end_of_loading.map(|t| (t, "end of loading")),
            ),
        };
        // A panic inside the plotting library must not take the run's summary with it.
        report.record(
            stem,
            &format!("{stem} plot"),
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(draw)),
        );
    }
    report
}

/// Writes the animation of the run in `dir` (`animation.gif`, see
/// [`crate::animation::write_animation`]) for `dim ≥ 2`, drawing the network read back from
/// `dir` ([`read_topology`]) in `scene`, and reports it like [`draw_plots`]: `animation` written, or
/// skipped with a warning (never an error; a stop request skips it). Nothing for `dim = 1`.
pub fn draw_animation(
    dir: &Path,
    dim: usize,
    (title, scene): (&str, &Scene),
    stop: Option<&AtomicBool>,
) -> PlotReport {
    let mut report = PlotReport::default();
    if dim < 2 {
        return report;
    }
    let stem = "animation";
    let draw = || {
        let topology = read_topology(dir)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| format!("{ELEMENTS_FILE} was not written"))?;
        crate::animation::write_animation(dir, dim, title, &topology, scene, stop)
    };
    report.record(
        stem,
        stem,
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(draw)),
    );
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::Writers;
    use crate::test_util::named_network;

    #[test]
    fn stop_during_plots_skips_them() {
        let dir = crate::test_util::temp_dir("output", "plotstop");
        let h = History {
            t: vec![0.0, 1.0],
            kinetic: vec![0.0, 1.0],
            potential: vec![1.0, 0.0],
            hamiltonian: vec![1.0, 1.0],
            increment_t: vec![1.0],
            increment: vec![1e-15],
            snapshots: vec![(0.0, vec![[0.0, 0.0], [1.0, 0.0]])],
            water: None,
        };
        let stop = AtomicBool::new(true);
        let r = draw_plots(&dir, 2, ("t", &Scene::default()), None, Ok(&h), Some(&stop));
        assert!(r.written.is_empty());
        assert_eq!(r.skipped, ["energy", "configuration", "increments"]);
        assert!(r.warnings.iter().all(|w| w.contains("stop requested")));
        let r = draw_plots(&dir, 2, ("t", &Scene::default()), None, Ok(&h), None);
        assert_eq!(r.written, ["energy", "configuration", "increments"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn animation_is_reported_like_a_plot() {
        let dir = crate::test_util::temp_dir("output", "animation");
        let mut s = named_network();
        let mut w = Writers::start(&dir, &s, 1, true, false, vec![]).unwrap();
        for _ in 0..3 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
        }
        w.finish(&s).unwrap();
        assert!(
            draw_animation(&dir, 1, ("t", &Scene::default()), None)
                .written
                .is_empty()
        );
        let stop = AtomicBool::new(true);
        let r = draw_animation(&dir, 2, ("t", &Scene::default()), Some(&stop));
        assert_eq!(r.skipped, ["animation"]);
        assert!(r.warnings[0].contains("stop requested"), "{:?}", r.warnings);
        let r = draw_animation(&dir, 2, ("t", &Scene::default()), None);
        assert_eq!(r.written, ["animation"], "{:?}", r.warnings);
        assert!(dir.join("animation.gif").exists());
        std::fs::remove_file(dir.join(ELEMENTS_FILE)).unwrap();
        let r = draw_animation(&dir, 2, ("t", &Scene::default()), None);
        assert!(r.warnings[0].contains("elements.csv"), "{:?}", r.warnings);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_wet_history_adds_the_plot_of_where_the_energy_went() {
        use crate::history::WaterHistory;
        let dir = crate::test_util::temp_dir("output", "split");
        let t = vec![0.0, 1.0, 2.0];
        let water = WaterHistory {
            t: t.clone(),
            stored: vec![0.0, 5.0, 8.0],
            supplied: vec![0.0, 7.0, 12.0],
            dissipated: vec![0.0, 2.0, 4.0],
            drag: vec![0.0, 1.5, 3.0],
            current: vec![0.0, 1.0, 2.0],
            seabed: vec![0.0, 0.5, 1.0],
            friction: vec![0.0; 3],
        };
        let h = History {
            t: t.clone(),
            kinetic: vec![0.0, 1.0, 2.0],
            potential: vec![1.0, 5.0, 7.0],
            hamiltonian: vec![1.0, 6.0, 9.0],
            increment_t: vec![1.0, 2.0],
            increment: vec![5.0, 3.0],
            snapshots: vec![],
            water: Some(water),
        };
        let r = draw_plots(&dir, 2, ("wet", &Scene::default()), None, Ok(&h), None);
        assert_eq!(r.written, ["energy", "increments", "energy_split"], "{r:?}");
        let svg = std::fs::read_to_string(dir.join("energy_split.svg")).unwrap();
        for label in [
            "where the energy went",
            "supplied at the boundaries",
            "supplied by the current",
            "dissipated by drag",
            "dissipated by seabed damping",
            "stored",
            "energy since t = 0 [J]",
            "t [s]",
        ] {
            assert!(svg.contains(label), "{label}");
        }
        // Friction did nothing, and all the dissipation is the water's: neither is drawn.
        assert!(!svg.contains("friction") && !svg.contains("material"));
        assert!(dir.join("energy_split.png").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn plot_problems_are_warnings_not_errors() {
        let dir = crate::test_util::temp_dir("output", "plotwarn");
        let far = vec![[1e308, 0.0], [1e308, -1.0]];
        let h = History {
            t: vec![0.0, 1.0],
            kinetic: vec![0.0, 1e300],
            potential: vec![1.0, 0.0],
            hamiltonian: vec![1.0, 1e300],
            increment_t: vec![1.0],
            increment: vec![1e300],
            snapshots: vec![(0.0, far)],
            water: None,
        };
        let r = draw_plots(&dir, 2, ("t", &Scene::default()), None, Ok(&h), None);
        assert_eq!(r.written, ["increments"]);
        assert_eq!(r.skipped, ["energy", "configuration"]);
        assert_eq!(r.warnings.len(), 2);
        assert!(
            r.warnings[1].contains("configuration plot skipped"),
            "{:?}",
            r.warnings
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
