//! The figures of a run drawn from its outputs read back ([`crate::history`]): the energy,
//! configuration and increment plots ([`draw_plots`]) and the animation
//! ([`draw_animation`]), each skipped with a warning rather than failing the run.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::files::ELEMENTS_FILE;
use crate::history::{History, read_topology};
use crate::plot::{self, PlotError, Series};

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

/// Draws the `energy`, `configuration` (2D and 3D) and `increments` plots of a run into
/// `dir`. A plot that cannot be drawn (degenerate or extreme ranges, an I/O error, a
/// failure inside the plotting library) is skipped with a warning and never fails the run;
/// once `stop` is set, the remaining plots are skipped. `history = Err(reason)` (it could
/// not be read, or reading it was stopped) skips all.
pub fn draw_plots(
    dir: &Path,
    dim: usize,
    title: &str,
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
    let topology = if configuration {
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
                Ok(Some(t)) => plot::network_plot(&path, title, t, &h.snapshots),
                Ok(None) => plot::configuration_plot(&path, title, &h.snapshots),
                Err(e) => Err(PlotError::Input {
                    path: path.clone(),
                    message: e.clone(),
                }),
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
/// `dir` ([`read_topology`]), and reports it like [`draw_plots`]: `animation` written, or
/// skipped with a warning (never an error; a stop request skips it). Nothing for `dim = 1`.
pub fn draw_animation(
    dir: &Path,
    dim: usize,
    title: &str,
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
        crate::animation::write_animation(dir, dim, title, &topology, stop)
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
        };
        let stop = AtomicBool::new(true);
        let r = draw_plots(&dir, 2, "t", None, Ok(&h), Some(&stop));
        assert!(r.written.is_empty());
        assert_eq!(r.skipped, ["energy", "configuration", "increments"]);
        assert!(r.warnings.iter().all(|w| w.contains("stop requested")));
        let r = draw_plots(&dir, 2, "t", None, Ok(&h), None);
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
        assert!(draw_animation(&dir, 1, "t", None).written.is_empty());
        let stop = AtomicBool::new(true);
        let r = draw_animation(&dir, 2, "t", Some(&stop));
        assert_eq!(r.skipped, ["animation"]);
        assert!(r.warnings[0].contains("stop requested"), "{:?}", r.warnings);
        let r = draw_animation(&dir, 2, "t", None);
        assert_eq!(r.written, ["animation"], "{:?}", r.warnings);
        assert!(dir.join("animation.gif").exists());
        std::fs::remove_file(dir.join(ELEMENTS_FILE)).unwrap();
        let r = draw_animation(&dir, 2, "t", None);
        assert!(r.warnings[0].contains("elements.csv"), "{:?}", r.warnings);
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
        };
        let r = draw_plots(&dir, 2, "t", None, Ok(&h), None);
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
