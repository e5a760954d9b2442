//! Figures as SVG and PNG: energies, string configurations and generic time series.
//!
//! Every function takes an output *stem* (a path without extension) and writes both
//! `<stem>.svg` (vector, for publication) and `<stem>.png` (raster, [`WIDTH`] × [`HEIGHT`] px).
//! The API is data-only: plain slices in SI units, no dependency on the simulator types.
//! Text uses the bundled DejaVu Sans font, so no system fonts are needed.
//!
//! Data whose axis ranges cannot be drawn faithfully (non-finite bounds or spans, a span
//! below [`MIN_RELATIVE_SPAN`] of the magnitude, magnitudes above [`MAX_MAGNITUDE`]) is
//! refused with [`PlotError::Range`] before anything is drawn: the plotting library's
//! tick computation does not terminate on such ranges. Titles and labels are stripped of
//! control characters and shortened ([`sanitize_text`]).

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{BoldPoints, KeyPointHint, KeyPointWeight, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Width of every figure, in pixels (PNG) or SVG user units.
pub const WIDTH: u32 = 1000;
/// Height of every figure, in pixels (PNG) or SVG user units.
pub const HEIGHT: u32 = 700;

/// Font family name under which the bundled DejaVu Sans is registered.
const FONT: &str = "sans-serif";
const TITLE_SIZE: f64 = 28.0;
const DESC_SIZE: f64 = 22.0;
const TICK_SIZE: f64 = 18.0;
const LEGEND_SIZE: f64 = 18.0;
/// Outer margin of the chart inside its area, in pixels.
const MARGIN: u32 = 18;
/// Height of the x tick-label plus axis-description band, in pixels.
const X_LABEL_AREA: u32 = 70;
/// Snapshots with more nodes than this are drawn without node markers.
const MAX_MARKED_NODES: usize = 200;
/// Largest magnitude of a value on a linear axis (beyond it a plot is refused).
pub const MAX_MAGNITUDE: f64 = 1e15;
/// Smallest span of an axis relative to the magnitude of its values (below it a plot is
/// refused: ticks could not be told apart in `f64`).
pub const MIN_RELATIVE_SPAN: f64 = 1e-12;
/// Longest title or label, in characters (longer ones end in `…`).
pub const MAX_TEXT_CHARS: usize = 200;

use crate::scene::{Scene, WaterLines};
use crate::text::sanitize_text;

/// Checks that the axis range `lo..hi` can be drawn: finite, increasing, a span of at
/// least [`MIN_RELATIVE_SPAN`] of the magnitude, and (linear axes) a magnitude of at most
/// [`MAX_MAGNITUDE`]; log axes need `0 < lo` and finite `hi`.
fn check_axis(name: &str, lo: f64, hi: f64, log: bool) -> Result<(), String> {
    let span = hi - lo;
    let mag = lo.abs().max(hi.abs());
    if !(lo.is_finite() && hi.is_finite() && span.is_finite()) {
        return Err(format!("the {name} range {lo:e} … {hi:e} is not finite"));
    }
    if log {
        if !(f64::MIN_POSITIVE <= lo && hi > lo) {
            return Err(format!(
                "the logarithmic {name} range {lo:e} … {hi:e} is invalid"
            ));
        }
        return Ok(());
    }
    if mag > MAX_MAGNITUDE {
        return Err(format!(
            "the {name} values reach {mag:e}, beyond the {MAX_MAGNITUDE:e} that can be plotted"
        ));
    }
    if span <= 0.0 || span < MIN_RELATIVE_SPAN * mag {
        return Err(format!(
            "the {name} range {lo:e} … {hi:e} is too narrow for its magnitude"
        ));
    }
    Ok(())
}

/// Error while writing a figure.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The bundled font could not be registered with the plotting library.
    #[error("cannot register the bundled DejaVu Sans font for plotting")]
    Font,
    /// The input slices are inconsistent (e.g. different lengths).
    #[error("cannot plot {path}: {message}")]
    Input {
        /// Output file that was to be written.
        path: PathBuf,
        /// What is wrong with the input.
        message: String,
    },
    /// The data's ranges cannot be drawn (non-finite, degenerate or extreme); nothing was
    /// written.
    #[error("cannot plot {path}: {message}")]
    Range {
        /// Output file that was to be written.
        path: PathBuf,
        /// Which range and why.
        message: String,
    },
    /// The plotting backend failed (drawing, encoding or writing the PNG).
    #[error("cannot draw {path}: {message}")]
    Backend {
        /// Output file that was being drawn.
        path: PathBuf,
        /// Backend error message.
        message: String,
    },
    /// Writing the output file failed.
    #[error("cannot write {path}: {cause}")]
    Io {
        /// Output file that was being written.
        path: PathBuf,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: std::io::Error,
    },
}

/// One named curve for [`series_plot`]: `y[i]` plotted against `x[i]` (equal lengths).
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend text.
    pub label: &'a str,
    /// Abscissae, in the unit of the x label.
    pub x: &'a [f64],
    /// Ordinates, in the unit of the y label.
    pub y: &'a [f64],
}

/// Plots kinetic, potential and total energy against time (paper Fig. 3).
///
/// `t` in s; `kinetic`, `potential`, `hamiltonian` in J, each the same length as `t`.
/// Non-finite values are skipped. Writes `<stem>.svg` and `<stem>.png`.
pub fn energy_plot(
    stem: &Path,
    title: &str,
    t: &[f64],
    kinetic: &[f64],
    potential: &[f64],
    hamiltonian: &[f64],
) -> Result<(), PlotError> {
    for (name, v) in [
        ("kinetic", kinetic),
        ("potential", potential),
        ("hamiltonian", hamiltonian),
    ] {
        if v.len() != t.len() {
            return Err(PlotError::Input {
                path: stem.to_path_buf(),
                message: format!("{name} has {} values but t has {}", v.len(), t.len()),
            });
        }
    }
    let curves = vec![
        Curve {
            label: "T̂ (kinetic)".to_string(),
            points: finite_points(t, kinetic, false),
            color: PALETTE[0],
            width: 2,
            dashed: false,
        },
        Curve {
            label: "V̂ (potential)".to_string(),
            points: finite_points(t, potential, false),
            color: PALETTE[1],
            width: 2,
            dashed: false,
        },
        Curve {
            label: "Ĥ (Hamiltonian)".to_string(),
            points: finite_points(t, hamiltonian, false),
            color: RGBColor(0, 0, 0),
            width: 2,
            dashed: false,
        },
    ];
    let title = sanitize_text(title, MAX_TEXT_CHARS);
    let fig = XyFigure {
        title: &title,
        x_label: "t [s]",
        y_label: "energy [J]",
        curves,
        log_y: false,
        vline: None,
    };
    write_both(stem, &fig)
}

/// Plots snapshots of the string shape in the plane with equal aspect ratio (paper Fig. 2).
///
/// Each snapshot is `(time in s, node positions [x, y] in m)`, drawn as a polyline with node
/// markers (markers omitted above 200 nodes) and labelled `t = … s`. Non-finite nodes are skipped.
/// Writes `<stem>.svg` and `<stem>.png`.
pub fn configuration_plot(
    stem: &Path,
    title: &str,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> Result<(), PlotError> {
    let title = sanitize_text(title, MAX_TEXT_CHARS);
    write_both(stem, &config_figure(&title, None, snapshots))
}

/// Plots snapshots of a network in the plane with equal aspect ratio: every element of
/// `topology` as a segment between its nodes, point masses as dots (larger for heavier
/// masses).
///
/// Each snapshot is `(time in s, node positions [x, y] in m)`, every node of the network. A
/// single string through nodes `0, 1, …` ([`Topology::is_chain`]) looks exactly like
/// [`configuration_plot`] (one colour per snapshot), plus its point masses. Otherwise each
/// string group has its colour and springs are thin, dashed and grey; the snapshots are told
/// apart by their shade, from faint (the first) to full (the last). Elements with a
/// non-finite node are skipped. A topology that refers to nodes beyond a snapshot is refused
/// with [`PlotError::Input`]. Writes `<stem>.svg` and `<stem>.png`.
pub fn network_plot(
    stem: &Path,
    title: &str,
    topology: &Topology,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> Result<(), PlotError> {
    network_plot_in(stem, title, topology, snapshots, &Scene::default())
}

/// [`network_plot`] in `scene`: the snapshots are in its drawing plane ([`Scene::plane`]),
/// its axes are described by [`Scene::axis_labels`], and a run in water has the surface
/// (height 0, light blue) and the seabed (a brown band below its line) drawn behind it
/// across the plotted range, each with a legend entry; the data box then takes in the
/// surface and the seabed under the nodes. A dry scene draws exactly [`network_plot`].
pub fn network_plot_in(
    stem: &Path,
    title: &str,
    topology: &Topology,
    snapshots: &[(f64, Vec<[f64; 2]>)],
    scene: &Scene,
) -> Result<(), PlotError> {
    for (t, nodes) in snapshots {
        topology
            .check(nodes.len())
            .map_err(|message| PlotError::Input {
                path: stem.to_path_buf(),
                message: format!("snapshot at t = {} s: {message}", format_plain(*t)),
            })?;
    }
    let title = sanitize_text(title, MAX_TEXT_CHARS);
    let mut fig = config_figure(&title, Some(topology), snapshots);
    fig.labels = scene.axis_labels();
    if let Some(w) = &scene.water {
        fig.entries.extend(water_entries(w));
        fig.water = Some(w.clone());
    }
    if !scene.grounded.is_empty() {
        mark_grounded(&mut fig, topology, snapshots, &scene.grounded);
    }
    draw_bodies(&mut fig, scene, snapshots.len());
    write_both(stem, &fig)
}

/// The colour of the rigid bodies' boxes.
pub(crate) const BODY_COLOR: RGBColor = RGBColor(90, 60, 30);
/// The colours of the body axes `x`, `y`, `z`.
pub(crate) const BODY_AXIS_COLORS: [RGBColor; 3] = [
    RGBColor(220, 30, 30),
    RGBColor(20, 150, 40),
    RGBColor(30, 60, 220),
];

/// Adds to `fig` the rigid bodies of `scene` at each of its `n` snapshots (box edges and
/// body axes, faded by age like the strings) and their legend entry; nothing without
/// bodies or their poses, or in the view of one plane per line.
fn draw_bodies(fig: &mut ConfigFigure<'_>, scene: &Scene, n: usize) {
    let curve = |seg: &[[f64; 2]; 2], color: RGBColor| Curve {
        label: String::new(),
        points: seg.iter().map(|p| (p[0], p[1])).collect(),
        color,
        width: 1,
        dashed: false,
    };
    for (k, poses) in scene.body_poses.iter().enumerate().take(n) {
        let f = snapshot_shade(k, n);
        for (b, pose) in scene.bodies.iter().zip(poses) {
            let Some(o) = scene.body_outline(b, pose) else {
                continue;
            };
            let finite = |s: &&[[f64; 2]; 2]| s.iter().all(finite);
            let edges = o.edges.iter().filter(finite);
            fig.outlines
                .extend(edges.map(|s| curve(s, fade(BODY_COLOR, f))));
            for (s, c) in o.axes.iter().zip(BODY_AXIS_COLORS) {
                if finite(&s) {
                    fig.outlines.push(curve(s, fade(c, f)));
                }
            }
        }
    }
    if !fig.outlines.is_empty() {
        fig.entries.push(LegendEntry {
            label: "rigid bodies (axes x, y, z: red, green, blue)".into(),
            color: BODY_COLOR,
            dashed: false,
            marker: false,
            line: true,
            triangle: false,
        });
    }
}

/// The colour of the markers of nodes on the seabed.
pub(crate) const GROUNDED: RGBColor = RGBColor(190, 0, 50);
/// Size of the triangle marking a node on the seabed [px].
pub(crate) const GROUNDED_SIZE: u32 = 6;

/// The drawn positions of the nodes on the seabed in every snapshot: node `i` of
/// `grounded[k].nodes` at its position in snapshot `k` (non-finite positions and nodes
/// beyond a snapshot left out).
pub fn grounded_points(
    snapshots: &[(f64, Vec<[f64; 2]>)],
    grounded: &[crate::scene::Grounded],
) -> Vec<(f64, f64)> {
    snapshots
        .iter()
        .zip(grounded)
        .flat_map(|((_, nodes), g)| {
            g.nodes
                .iter()
                .filter_map(|&i| nodes.get(i).filter(|p| finite(p)).map(|p| (p[0], p[1])))
        })
        .collect()
}

/// Adds to `fig` the triangles of the nodes on the seabed at each snapshot and the legend
/// entry "on the seabed", with the grounded length at the last snapshot (to 0.1 m): of the
/// string of a chain in that entry, of each named string of a network after its name.
fn mark_grounded(
    fig: &mut ConfigFigure<'_>,
    topology: &Topology,
    snapshots: &[(f64, Vec<[f64; 2]>)],
    grounded: &[crate::scene::Grounded],
) {
    fig.grounded = grounded_points(snapshots, grounded);
    let last = snapshots.len().min(grounded.len());
    let Some(g) = last.checked_sub(1).map(|k| &grounded[k]) else {
        return;
    };
    let t = format_plain(snapshots[last - 1].0);
    let length = |group: usize| format!("{:.1}", g.lengths.get(group).copied().unwrap_or(0.0));
    let label = if topology.is_chain() {
        format!("on the seabed ({} m at t = {t} s)", length(0))
    } else {
        let strings = topology
            .groups
            .iter()
            .enumerate()
            .filter(|(_, g)| !g.spring);
        for ((group, _), entry) in strings.zip(fig.entries.iter_mut()) {
            if entry.line && !entry.dashed {
                entry.label = format!("{}: {} m on the seabed", entry.label, length(group));
            }
        }
        format!("on the seabed (lengths at t = {t} s)")
    };
    fig.entries.push(LegendEntry {
        label,
        color: GROUNDED,
        dashed: false,
        marker: true,
        line: false,
        triangle: true,
    });
}

/// The surface's colour in configuration plots and animations.
pub(crate) const SURFACE_BLUE: RGBColor = RGBColor(110, 170, 230);
/// The seabed line's colour.
pub(crate) const SEABED_BROWN: RGBColor = RGBColor(150, 115, 80);
/// The colour of the band below the seabed line.
pub(crate) const SEABED_FILL: RGBColor = RGBColor(228, 214, 192);

/// The legend entries of the water: its surface, and the seabed if there is one.
fn water_entries(w: &WaterLines) -> Vec<LegendEntry> {
    let mut e = vec![LegendEntry {
        label: "water surface".into(),
        color: SURFACE_BLUE,
        dashed: false,
        marker: false,
        line: true,
        triangle: false,
    }];
    if w.seabed.is_some() {
        e.push(LegendEntry {
            label: "seabed".into(),
            color: SEABED_BROWN,
            dashed: false,
            marker: false,
            line: true,
            triangle: false,
        });
    }
    e
}

/// `points` with, for a run in water, the surface and the seabed under their horizontal
/// extent: what the data box of a wet drawing takes in.
pub(crate) fn with_water(points: Vec<(f64, f64)>, water: Option<&WaterLines>) -> Vec<(f64, f64)> {
    let Some(w) = water else {
        return points;
    };
    let Some((x0, x1)) = bounds(points.iter().map(|p| p.0)) else {
        return points;
    };
    let mut all = points;
    all.extend([(x0, 0.0), (x1, 0.0)]);
    all.extend(w.seabed_segments((x0, x1)).into_iter().flatten());
    all
}

/// Draws the water behind a configuration on `chart` (ranges `x`, `y` [m]): the seabed
/// band from its line to the bottom of the chart and the line (piece by piece in the view
/// of one plane per line), then the surface at height 0.
pub(crate) fn draw_water<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    w: &WaterLines,
    (x0, x1): (f64, f64),
    (y0, _): (f64, f64),
) -> Result<(), String> {
    for [(xa, a), (xb, b)] in w.seabed_segments((x0, x1)) {
        let bottom = y0.min(a).min(b);
        chart
            .draw_series(std::iter::once(Polygon::new(
                vec![(xa, a), (xb, b), (xb, bottom), (xa, bottom)],
                SEABED_FILL.filled(),
            )))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(xa, a), (xb, b)],
                SEABED_BROWN.stroke_width(2),
            )))
            .map_err(err)?;
    }
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(x0, 0.0), (x1, 0.0)],
            SURFACE_BLUE.stroke_width(2),
        )))
        .map_err(err)?;
    Ok(())
}

/// One group of elements of a [`Topology`]: a string, or a set of springs.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupDrawing {
    /// Name (legend text).
    pub name: String,
    /// Its elements (indices into [`Topology::elements`]).
    pub elements: Range<usize>,
    /// Springs (drawn thin and grey) rather than a string (a colour per group).
    pub spring: bool,
}

/// What joins the nodes of a configuration: elements as node pairs, in groups (strings and
/// springs), and point masses at nodes. Plain data; `phstring_io::output::topology` builds
/// it from a simulation, `phstring_io::output::read_topology` from an output folder.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Topology {
    /// Elements `[node_a, node_b]`.
    pub elements: Vec<[usize; 2]>,
    /// Element groups, in element order.
    pub groups: Vec<GroupDrawing>,
    /// Point masses `(node, mass [kg])`.
    pub masses: Vec<(usize, f64)>,
}

impl Topology {
    /// One string named `string` through nodes `0, 1, …, n_nodes − 1`, no point masses.
    pub fn chain(n_nodes: usize) -> Self {
        let n_el = n_nodes.saturating_sub(1);
        Self {
            elements: (0..n_el).map(|i| [i, i + 1]).collect(),
            groups: vec![GroupDrawing {
                name: "string".into(),
                elements: 0..n_el,
                spring: false,
            }],
            masses: Vec::new(),
        }
    }

    /// Whether this is a single string through nodes `0, 1, …` in order (point masses
    /// aside): drawn like one string, one colour per snapshot.
    pub fn is_chain(&self) -> bool {
        let one_string = match self.groups.as_slice() {
            [g] => !g.spring && g.elements == (0..self.elements.len()),
            [] => self.elements.is_empty(),
            _ => false,
        };
        one_string
            && self
                .elements
                .iter()
                .enumerate()
                .all(|(i, e)| *e == [i, i + 1])
    }

    /// Checks that the elements and point masses refer to nodes below `n_nodes` and the
    /// groups to existing elements.
    pub fn check(&self, n_nodes: usize) -> Result<(), String> {
        if let Some((k, e)) = self
            .elements
            .iter()
            .enumerate()
            .find(|(_, e)| e[0] >= n_nodes || e[1] >= n_nodes)
        {
            return Err(format!(
                "element {k} = {e:?} refers to a node beyond the {n_nodes} nodes"
            ));
        }
        if let Some(g) = self
            .groups
            .iter()
            .find(|g| g.elements.start > g.elements.end || g.elements.end > self.elements.len())
        {
            return Err(format!(
                "group {:?} has elements {:?} of {}",
                sanitize_text(&g.name, 40),
                g.elements,
                self.elements.len()
            ));
        }
        if let Some((node, _)) = self.masses.iter().find(|(n, _)| *n >= n_nodes) {
            return Err(format!(
                "a point mass is at node {node}, beyond the {n_nodes} nodes"
            ));
        }
        Ok(())
    }

    /// The elements of group `g` as node paths: runs of consecutive elements each starting
    /// where the previous one ended (one path for a string numbered along its length).
    pub fn polylines(&self, g: usize) -> Vec<Vec<usize>> {
        let mut out: Vec<Vec<usize>> = Vec::new();
        let Some(group) = self.groups.get(g) else {
            return out;
        };
        for e in group.elements.clone() {
            let Some(&[a, b]) = self.elements.get(e) else {
                continue;
            };
            match out.last_mut() {
                Some(path) if path.last() == Some(&a) => path.push(b),
                _ => out.push(vec![a, b]),
            }
        }
        out
    }

    /// Radius in pixels of the dot of a point mass `m` when the heaviest is `m_max` (grows
    /// with the cube root of the mass, `base` to `base + extra`).
    pub(crate) fn mass_radius(m: f64, m_max: f64, base: f64, extra: f64) -> u32 {
        let f = if m_max > 0.0 && m.is_finite() {
            (m / m_max).clamp(0.0, 1.0).cbrt()
        } else {
            1.0
        };
        (base + extra * f).round() as u32
    }
}

/// Grey of the springs in configuration plots and animations.
pub(crate) const SPRING_GREY: RGBColor = RGBColor(128, 128, 128);
/// Colour of point masses in network drawings.
pub(crate) const MASS_COLOR: RGBColor = RGBColor(0, 0, 0);
/// Most string groups named in a legend (the rest are summed up in one entry).
const MAX_LEGEND_GROUPS: usize = 10;

/// `c` mixed with white: `f = 1` is `c`, `f = 0` white.
pub(crate) fn fade(c: RGBColor, f: f64) -> RGBColor {
    let mix = |v: u8| (255.0 - (255.0 - f64::from(v)) * f.clamp(0.0, 1.0)).round() as u8;
    RGBColor(mix(c.0), mix(c.1), mix(c.2))
}

/// The colours of the string groups of `topology` (springs get [`SPRING_GREY`]).
pub(crate) fn group_colors(topology: &Topology) -> Vec<RGBColor> {
    let n_strings = topology.groups.iter().filter(|g| !g.spring).count();
    let mut palette = distinct_colors(n_strings).into_iter();
    topology
        .groups
        .iter()
        .map(|g| {
            if g.spring {
                SPRING_GREY
            } else {
                palette.next().unwrap_or(PALETTE[0])
            }
        })
        .collect()
}

/// The configuration figure of `snapshots`: a chain (no topology, or a chain topology) or a
/// network.
fn config_figure<'a>(
    title: &'a str,
    topology: Option<&Topology>,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> ConfigFigure<'a> {
    match topology {
        Some(t) if !t.is_chain() => network_figure(title, t, snapshots),
        _ => chain_figure(title, topology.map_or(&[], |t| &t.masses), snapshots),
    }
}

/// Whether both coordinates of `p` are finite (others are left out of the drawing).
fn finite(p: &[f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// The point masses `(node, kg)` at the positions `nodes`, in `color`, sized relative to the
/// largest mass `m_max` [kg].
fn mass_dots(masses: &[(usize, f64)], m_max: f64, nodes: &[[f64; 2]], color: RGBColor) -> Vec<Dot> {
    masses
        .iter()
        .filter_map(|&(i, m)| nodes.get(i).filter(|p| finite(p)).map(|p| (p, m)))
        .map(|(p, m)| Dot {
            x: p[0],
            y: p[1],
            radius: Topology::mass_radius(m, m_max, 4.0, 5.0),
            color,
        })
        .collect()
}

/// The legend entry of the point masses.
fn mass_entry() -> LegendEntry {
    LegendEntry {
        label: "point masses".into(),
        color: MASS_COLOR,
        dashed: false,
        marker: true,
        line: false,
        triangle: false,
    }
}

/// The legend label of the snapshot at time `t` [s].
fn time_label(t: f64) -> String {
    sanitize_text(&format!("t = {} s", format_plain(t)), MAX_TEXT_CHARS)
}

/// The configuration figure of a chain: one curve per snapshot in its own color, with the
/// point masses `masses` `(node, kg)`.
fn chain_figure<'a>(
    title: &'a str,
    masses: &[(usize, f64)],
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> ConfigFigure<'a> {
    let m_max = masses.iter().map(|m| m.1).fold(0.0, f64::max);
    let colors = distinct_colors(snapshots.len());
    let curves: Vec<Curve> = snapshots
        .iter()
        .zip(&colors)
        .map(|((time, nodes), &color)| Curve {
            label: time_label(*time),
            points: nodes
                .iter()
                .filter(|p| finite(p))
                .map(|p| (p[0], p[1]))
                .collect(),
            color,
            width: 2,
            dashed: false,
        })
        .collect();
    let markers = curves.iter().all(|c| c.points.len() <= MAX_MARKED_NODES);
    let mut entries: Vec<LegendEntry> = curves
        .iter()
        .map(|c| LegendEntry {
            label: c.label.clone(),
            color: c.color,
            dashed: false,
            marker: markers,
            line: true,
            triangle: false,
        })
        .collect();
    let dots: Vec<Dot> = snapshots
        .iter()
        .zip(&colors)
        .flat_map(|((_, nodes), &color)| mass_dots(masses, m_max, nodes, color))
        .collect();
    if !dots.is_empty() {
        entries.push(mass_entry());
    }
    ConfigFigure {
        title,
        curves,
        dots,
        entries,
        markers,
        labels: Scene::default().axis_labels(),
        water: None,
        grounded: Vec::new(),
        outlines: Vec::new(),
    }
}

/// The shade of snapshot `k` of `n`: the earliest faded most, the last in full color.
fn snapshot_shade(k: usize, n: usize) -> f64 {
    if n <= 1 {
        1.0
    } else {
        0.25 + 0.75 * k as f64 / (n - 1) as f64
    }
}

/// The configuration figure of a network: per snapshot, each group in its color (springs
/// dashed, under the strings), faded by age, with the point masses.
fn network_figure<'a>(
    title: &'a str,
    topology: &Topology,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> ConfigFigure<'a> {
    let colors = group_colors(topology);
    let (curves, dots) = network_curves(topology, &colors, snapshots);
    let entries = network_legend(topology, &colors, !dots.is_empty(), snapshots);
    ConfigFigure {
        title,
        curves,
        dots,
        entries,
        markers: false,
        labels: Scene::default().axis_labels(),
        water: None,
        grounded: Vec::new(),
        outlines: Vec::new(),
    }
}

/// The curves of every group and the point masses of every snapshot of a network, the groups
/// in `colors`.
fn network_curves(
    topology: &Topology,
    colors: &[RGBColor],
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> (Vec<Curve>, Vec<Dot>) {
    let m_max = topology.masses.iter().map(|m| m.1).fold(0.0, f64::max);
    let n = snapshots.len();
    let (mut curves, mut dots) = (Vec::new(), Vec::new());
    for (k, (_, nodes)) in snapshots.iter().enumerate() {
        let f = snapshot_shade(k, n);
        // Springs first, under the strings.
        for spring in [true, false] {
            for (g, group) in topology.groups.iter().enumerate() {
                if group.spring != spring {
                    continue;
                }
                for path in topology.polylines(g) {
                    // A path is cut at non-finite nodes.
                    let mut run: Vec<(f64, f64)> = Vec::new();
                    for i in path.into_iter().chain([usize::MAX]) {
                        match nodes.get(i).filter(|p| finite(p)) {
                            Some(p) => run.push((p[0], p[1])),
                            None => {
                                if run.len() > 1 {
                                    curves.push(Curve {
                                        label: String::new(),
                                        points: std::mem::take(&mut run),
                                        color: fade(colors[g], f),
                                        width: if spring { 1 } else { 2 },
                                        dashed: spring,
                                    });
                                }
                                run.clear();
                            }
                        }
                    }
                }
            }
        }
        dots.extend(mass_dots(
            &topology.masses,
            m_max,
            nodes,
            fade(MASS_COLOR, f),
        ));
    }
    (curves, dots)
}

/// The legend of a network's configuration figure: its strings (at most
/// [`MAX_LEGEND_GROUPS`] named), its springs, the point masses if `masses` and the
/// snapshot times.
fn network_legend(
    topology: &Topology,
    colors: &[RGBColor],
    masses: bool,
    snapshots: &[(f64, Vec<[f64; 2]>)],
) -> Vec<LegendEntry> {
    let mut entries = Vec::new();
    let strings: Vec<usize> = (0..topology.groups.len())
        .filter(|&g| !topology.groups[g].spring)
        .collect();
    for (shown, &g) in strings.iter().enumerate() {
        if shown == MAX_LEGEND_GROUPS && strings.len() > MAX_LEGEND_GROUPS + 1 {
            entries.push(LegendEntry {
                label: format!("… {} more strings", strings.len() - shown),
                color: colors[g],
                dashed: false,
                marker: false,
                line: false,
                triangle: false,
            });
            break;
        }
        entries.push(LegendEntry {
            label: sanitize_text(&topology.groups[g].name, 40),
            color: colors[g],
            dashed: false,
            marker: false,
            line: true,
            triangle: false,
        });
    }
    let springs: Vec<&GroupDrawing> = topology.groups.iter().filter(|g| g.spring).collect();
    if !springs.is_empty() {
        entries.push(LegendEntry {
            label: match springs.as_slice() {
                [one] => sanitize_text(&one.name, 40),
                many => format!("springs ({})", many.len()),
            },
            color: SPRING_GREY,
            dashed: true,
            marker: false,
            line: true,
            triangle: false,
        });
    }
    if masses {
        entries.push(mass_entry());
    }
    let n = snapshots.len();
    for (k, (t, _)) in snapshots.iter().enumerate() {
        entries.push(LegendEntry {
            label: time_label(*t),
            color: fade(RGBColor(0, 0, 0), snapshot_shade(k, n)),
            dashed: false,
            marker: false,
            line: true,
            triangle: false,
        });
    }
    entries
}

/// Plots named curves `y(x)` on a shared axis pair (paper Figs. 4 and 5).
///
/// With `log_y`, values ≤ 0 or non-finite are skipped and the y axis is logarithmic with
/// tick labels like `1e-12`; otherwise non-finite values are skipped. `vline = Some((x, label))`
/// adds a dashed vertical marker at `x` with a legend entry. Writes `<stem>.svg` and `<stem>.png`.
pub fn series_plot(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    log_y: bool,
    vline: Option<(f64, &str)>,
) -> Result<(), PlotError> {
    let colors = distinct_colors(series.len());
    let mut curves = Vec::with_capacity(series.len());
    for (s, color) in series.iter().zip(colors) {
        if s.x.len() != s.y.len() {
            return Err(PlotError::Input {
                path: stem.to_path_buf(),
                message: format!(
                    "series '{}' has {} x values but {} y values",
                    s.label,
                    s.x.len(),
                    s.y.len()
                ),
            });
        }
        curves.push(Curve {
            label: sanitize_text(s.label, MAX_TEXT_CHARS),
            points: finite_points(s.x, s.y, log_y),
            color,
            width: 2,
            dashed: false,
        });
    }
    let (title, x_label, y_label) = (
        sanitize_text(title, MAX_TEXT_CHARS),
        sanitize_text(x_label, MAX_TEXT_CHARS),
        sanitize_text(y_label, MAX_TEXT_CHARS),
    );
    let vline_label = vline.map(|(_, l)| sanitize_text(l, MAX_TEXT_CHARS));
    let fig = XyFigure {
        title: &title,
        x_label: &x_label,
        y_label: &y_label,
        curves,
        log_y,
        vline: vline
            .zip(vline_label.as_deref())
            .map(|((x, _), l)| (x, l))
            .filter(|(x, _)| x.is_finite()),
    };
    write_both(stem, &fig)
}

// ---------------------------------------------------------------------------------------------
// Rendering infrastructure
// ---------------------------------------------------------------------------------------------

/// Colour-blind-friendly qualitative palette (Okabe–Ito, without yellow, plus grey).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(128, 128, 128),
];

/// `n` distinct colours: the qualitative palette, or a viridis-like ramp for many curves.
pub(crate) fn distinct_colors(n: usize) -> Vec<RGBColor> {
    if n <= PALETTE.len() {
        return PALETTE[..n].to_vec();
    }
    // Viridis control points (truncated before the light yellow end, which is poor on white).
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (180.0, 200.0, 30.0),
    ];
    (0..n)
        .map(|i| {
            let s = i as f64 / (n - 1) as f64 * (STOPS.len() - 1) as f64;
            let k = (s.floor() as usize).min(STOPS.len() - 2);
            let f = s - k as f64;
            let (a, b) = (STOPS[k], STOPS[k + 1]);
            let mix = |p: f64, q: f64| (p + (q - p) * f).round().clamp(0.0, 255.0) as u8;
            RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
        })
        .collect()
}

/// A polyline with its legend entry.
struct Curve {
    label: String,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    width: u32,
    /// Drawn dashed (springs).
    dashed: bool,
}

/// Something that can be drawn onto any plotters backend.
///
/// `raster` is true for the PNG backend, whose text renderer ignores glyph side bearings, so
/// combining accents (T̂, V̂) are drawn by hand there; SVG viewers render them natively.
trait Figure {
    /// Whether the figure's ranges can be drawn (see [`check_axis`]).
    fn check(&self) -> Result<(), String>;
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
    ) -> Result<(), String>;
}

/// Registers the bundled font once per process.
pub(crate) fn ensure_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// `stem` with `.ext` appended (not replacing any dot already in the file name).
fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Draws `fig` into `<stem>.svg` and `<stem>.png`.
fn write_both(stem: &Path, fig: &impl Figure) -> Result<(), PlotError> {
    fig.check().map_err(|message| PlotError::Range {
        path: stem.to_path_buf(),
        message,
    })?;
    ensure_font()?;
    let size = (WIDTH, HEIGHT);

    let svg_path = with_extension(stem, "svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let backend_err = |message: String| PlotError::Backend {
            path: svg_path.clone(),
            message,
        };
        fig.draw(&root, false).map_err(backend_err)?;
        root.present().map_err(|e| backend_err(e.to_string()))?;
    }
    std::fs::write(&svg_path, svg).map_err(|source| PlotError::Io {
        path: svg_path.clone(),
        cause: source,
    })?;

    let png_path = with_extension(stem, "png");
    let backend_err = |message: String| PlotError::Backend {
        path: png_path.clone(),
        message,
    };
    let root = BitMapBackend::new(&png_path, size).into_drawing_area();
    fig.draw(&root, true).map_err(backend_err)?;
    root.present().map_err(|e| backend_err(e.to_string()))?;
    Ok(())
}

pub(crate) fn text_style(size: f64) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font())
}

pub(crate) fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Pairs `(x[i], y[i])` with both finite (and `y > 0` when `positive`).
fn finite_points(x: &[f64], y: &[f64], positive: bool) -> Vec<(f64, f64)> {
    x.iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && (!positive || **b > 0.0))
        .map(|(a, b)| (*a, *b))
        .collect()
}

/// Min and max of an iterator of finite values, `None` if empty.
fn bounds(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// A non-degenerate linear range from data bounds: `pad` is the fraction of the span added on
/// each side; a (near-)constant value `c` becomes `c ± 10 %` (or ±1 around zero). Bounds
/// whose span overflows are returned unchanged (and refused by [`check_axis`]).
fn linear_range(b: Option<(f64, f64)>, pad: f64) -> (f64, f64) {
    let Some((lo, hi)) = b else {
        return (0.0, 1.0);
    };
    let span = hi - lo;
    let mag = lo.abs().max(hi.abs());
    if !span.is_finite() {
        // Not drawable; left as is for `check_axis` to refuse.
        return (lo, hi);
    }
    if span <= 1e-9 * mag {
        let mid = 0.5 * (lo + hi);
        let half = if mid.abs() > 0.0 && mid.is_finite() {
            0.1 * mid.abs()
        } else {
            1.0
        };
        let mid = if mid.is_finite() { mid } else { 0.0 };
        return (mid - half, mid + half);
    }
    (lo - pad * span, hi + pad * span)
}

/// Tick-label formatter for a linear axis over `[lo, hi]`: fixed-point with just enough
/// decimals (trailing zeros trimmed), scientific for very large or very small magnitudes,
/// and exactly `0` for zero (never `-0`).
fn linear_formatter(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let span = (hi - lo).abs().max(f64::MIN_POSITIVE);
    let mag = lo.abs().max(hi.abs());
    // Ticks are at multiples of 1, 2 or 5 × 10^k with at most ~20 per axis.
    let step_exp = (span / 20.0).log10().floor();
    let scientific = !(1e-3..1e6).contains(&mag);
    let decimals = (-step_exp).clamp(0.0, 15.0) as usize;
    let sig = (mag.log10().floor() - step_exp).clamp(0.0, 12.0) as usize;
    move |v: &f64| {
        if v.abs() <= span * 1e-9 {
            return "0".to_string();
        }
        if scientific {
            trim_scientific(&format!("{:.*e}", sig, v))
        } else {
            trim_fixed(&format!("{:.*}", decimals, v))
        }
    }
}

/// Removes trailing zeros (and a trailing dot) from a fixed-point number; `-0` becomes `0`.
fn trim_fixed(s: &str) -> String {
    let t = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    };
    if t == "-0" {
        "0".to_string()
    } else {
        t.to_string()
    }
}

/// Removes trailing zeros from the mantissa of a number formatted with `{:e}`.
fn trim_scientific(s: &str) -> String {
    match s.split_once('e') {
        Some((mantissa, exp)) => format!("{}e{}", trim_fixed(mantissa), exp),
        None => trim_fixed(s),
    }
}

/// Short plain representation of a time for legends (e.g. `0.2`, `1`, `1e-5`).
pub fn format_plain(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    let mag = v.abs();
    if !(1e-3..1e6).contains(&mag) {
        return trim_scientific(&format!("{v:.3e}"));
    }
    trim_fixed(&format!("{v:.6}"))
}

/// Logarithmic y axis: plotters' log mapping with ticks at powers of ten
/// (plus 2× and 5× when the range spans less than two decades).
struct LogAxis {
    inner: LogCoord<f64>,
    lo: f64,
    hi: f64,
}

impl LogAxis {
    fn new(lo: f64, hi: f64) -> Self {
        Self {
            inner: (lo..hi).log_scale().into(),
            lo,
            hi,
        }
    }

    fn decades(&self) -> f64 {
        (self.hi / self.lo).log10()
    }

    /// Values `m × 10^k` inside the range, for each mantissa `m` in `mantissas`.
    fn ticks(&self, mantissas: &[f64], every: i32) -> Vec<f64> {
        let k0 = self.lo.log10().floor() as i32;
        let k1 = self.hi.log10().ceil() as i32;
        let mut out = Vec::new();
        for k in k0..=k1 {
            let p = 10f64.powi(k);
            for &m in mantissas {
                let v = m * p;
                let keep = if m == 1.0 {
                    k.rem_euclid(every) == 0
                } else {
                    true
                };
                if keep && v >= self.lo * (1.0 - 1e-12) && v <= self.hi * (1.0 + 1e-12) {
                    out.push(v);
                }
            }
        }
        out
    }
}

impl Ranged for LogAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        let max = hint.max_num_points().max(1);
        let decades = self.decades();
        match hint.weight() {
            KeyPointWeight::Bold => {
                if decades < 2.0 {
                    self.ticks(&[1.0, 2.0, 5.0], 1)
                } else {
                    let every = ((decades.ceil() as usize).div_ceil(max)).max(1) as i32;
                    self.ticks(&[1.0], every)
                }
            }
            KeyPointWeight::Any => {
                if decades <= 8.0 {
                    self.ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1)
                } else {
                    self.ticks(&[1.0], 1)
                }
            }
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

/// Tick label for the logarithmic axis, e.g. `1e-12`, `5e-3`.
fn log_label(v: &f64) -> String {
    if *v <= 0.0 || !v.is_finite() {
        return String::new();
    }
    format!("{v:.0e}")
}

/// Legend entry: a line sample (optionally dashed, optionally with a circle marker) and text.
struct LegendEntry {
    label: String,
    color: RGBColor,
    dashed: bool,
    marker: bool,
    /// Whether the line sample is drawn (a marker alone stands for point masses).
    line: bool,
    /// A triangle marker (nodes on the seabed) instead of the circle.
    triangle: bool,
}

/// Width in pixels needed by a legend panel holding `entries`.
fn legend_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<u32, String> {
    let style = text_style(LEGEND_SIZE);
    let mut w = 0;
    for e in entries {
        w = w.max(area.estimate_text_size(&e.label, &style).map_err(err)?.0);
    }
    Ok(w + 80)
}

/// Draws a framed legend at the top of `area`, starting `top` pixels down.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top: i32,
    raster: bool,
) -> Result<(), String> {
    if entries.is_empty() {
        return Ok(());
    }
    let (w, _) = area.dim_in_pixel();
    let row = (LEGEND_SIZE * 1.6) as i32;
    let x0 = 8;
    let x1 = w as i32 - 6;
    let y1 = top + row * entries.len() as i32 + 10;
    area.draw(&Rectangle::new(
        [(x0, top), (x1, y1)],
        ShapeStyle::from(&RGBColor(160, 160, 160)).stroke_width(1),
    ))
    .map_err(err)?;
    for (i, e) in entries.iter().enumerate() {
        let y = top + 5 + row * i as i32 + row / 2;
        let (a, b) = (x0 + 10, x0 + 50);
        let style = ShapeStyle::from(&e.color).stroke_width(2);
        if e.line && e.dashed {
            let mut x = a;
            while x < b {
                area.draw(&PathElement::new(vec![(x, y), ((x + 7).min(b), y)], style))
                    .map_err(err)?;
                x += 12;
            }
        } else if e.line {
            area.draw(&PathElement::new(vec![(a, y), (b, y)], style))
                .map_err(err)?;
        }
        if e.triangle {
            area.draw(&TriangleMarker::new(
                ((a + b) / 2, y),
                GROUNDED_SIZE,
                e.color.filled(),
            ))
            .map_err(err)?;
        } else if e.marker {
            area.draw(&Circle::new(((a + b) / 2, y), 4, e.color.filled()))
                .map_err(err)?;
        }
        draw_text_left(area, &e.label, LEGEND_SIZE, (b + 10, y), raster)?;
    }
    Ok(())
}

/// Whether `c` is a Unicode combining diacritical mark (U+0300–U+036F).
fn is_combining(c: char) -> bool {
    ('\u{300}'..='\u{36f}').contains(&c)
}

/// Draws `text` left-aligned and vertically centred at `pos`.
///
/// On raster backends, combining marks are removed from the text and the common ones
/// (circumflex U+0302, macron U+0304) are drawn as strokes over their base letter.
fn draw_text_left<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    size: f64,
    pos: (i32, i32),
    raster: bool,
) -> Result<(), String> {
    let style = text_style(size).pos(Pos::new(HPos::Left, VPos::Center));
    if !raster || !text.chars().any(is_combining) {
        return area.draw_text(text, &style, pos).map_err(err);
    }
    let plain: String = text.chars().filter(|c| !is_combining(*c)).collect();
    area.draw_text(&plain, &style, pos).map_err(err)?;
    // Baseline of the rendered text (plotters' layout: box height size/1.24, glyphs placed
    // size/2 below its top), and cap / x heights of DejaVu Sans relative to that size.
    let baseline = pos.1 - (size / 1.24) as i32 / 2 + (size / 2.0) as i32;
    let mut prefix = String::new();
    let mut base: Option<(i32, i32, char)> = None;
    for c in text.chars() {
        if !is_combining(c) {
            let x0 = area.estimate_text_size(&prefix, &style).map_err(err)?.0 as i32;
            prefix.push(c);
            let x1 = area.estimate_text_size(&prefix, &style).map_err(err)?.0 as i32;
            base = Some((pos.0 + x0, pos.0 + x1, c));
            continue;
        }
        let Some((x0, x1, b)) = base else { continue };
        let height = if b.is_uppercase() || b.is_ascii_digit() {
            0.63
        } else {
            0.48
        };
        let top = baseline as f64 - height * size;
        let xc = 0.5 * f64::from(x0 + x1);
        let hw = (0.22 * size).min(0.45 * f64::from(x1 - x0).max(1.0));
        let stroke = ShapeStyle::from(&BLACK).stroke_width(((size / 16.0).round() as u32).max(1));
        let pts: Vec<(i32, i32)> = match c {
            '\u{302}' => vec![
                ((xc - hw) as i32, (top - 0.09 * size) as i32),
                (xc as i32, (top - 0.3 * size) as i32),
                ((xc + hw) as i32, (top - 0.09 * size) as i32),
            ],
            '\u{304}' => vec![
                ((xc - hw) as i32, (top - 0.2 * size) as i32),
                ((xc + hw) as i32, (top - 0.2 * size) as i32),
            ],
            _ => Vec::new(),
        };
        if !pts.is_empty() {
            area.draw(&PathElement::new(pts, stroke)).map_err(err)?;
        }
    }
    Ok(())
}

/// Fills white, draws the title, and splits off a right-hand legend panel.
/// Returns `(chart area, legend area)`.
#[allow(clippy::type_complexity)]
fn layout<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    entries: &[LegendEntry],
) -> Result<(DrawingArea<DB, Shift>, DrawingArea<DB, Shift>), String> {
    root.fill(&WHITE).map_err(err)?;
    let body = if title.trim().is_empty() {
        root.clone()
    } else {
        root.margin(8, 0, 0, 0)
            .titled(title, text_style(TITLE_SIZE))
            .map_err(err)?
    };
    let (w, _) = body.dim_in_pixel();
    let lw = if entries.is_empty() {
        0
    } else {
        legend_width(&body, entries)?.min(w / 2)
    };
    Ok(body.split_horizontally(w - lw))
}

/// Width of the y label area needed for the given tick labels, in pixels.
fn y_label_area<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    labels: impl Iterator<Item = String>,
) -> Result<u32, String> {
    y_label_area_sized(area, labels, TICK_SIZE, DESC_SIZE)
}

/// Width of the y label area for tick labels of font size `tick` and an axis description of
/// size `desc`, in pixels.
fn y_label_area_sized<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    labels: impl Iterator<Item = String>,
    tick: f64,
    desc: f64,
) -> Result<u32, String> {
    let style = text_style(tick);
    let mut w = 0;
    for l in labels {
        w = w.max(area.estimate_text_size(&l, &style).map_err(err)?.0);
    }
    // tick marks + gap + rotated axis description
    Ok(w + (tick * 11.0 / 9.0) as u32 + (desc * 1.6) as u32)
}

/// Draws the polylines (and markers) of `curves` into a built chart.
///
/// On raster backends wide polylines are drawn segment by segment: plotters joins wide bitmap
/// paths with unlimited miters, which turns sharp zig-zags (noisy data) into long false spikes.
fn draw_curves<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    curves: &[Curve],
    markers: bool,
    raster: bool,
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for c in curves {
        let style = ShapeStyle::from(&c.color).stroke_width(c.width);
        if c.dashed && c.points.len() > 1 {
            chart
                .draw_series(DashedLineSeries::new(c.points.iter().copied(), 6, 4, style))
                .map_err(err)?;
        } else if c.points.len() > 1 && raster && c.width > 1 {
            chart
                .draw_series(
                    c.points
                        .windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], style)),
                )
                .map_err(err)?;
        } else if c.points.len() > 1 {
            chart
                .draw_series(LineSeries::new(c.points.iter().copied(), style))
                .map_err(err)?;
        }
        if markers || c.points.len() == 1 {
            chart
                .draw_series(
                    c.points
                        .iter()
                        .map(|&p| Circle::new(p, 3, c.color.filled())),
                )
                .map_err(err)?;
        }
    }
    Ok(())
}

/// Line plot of several curves against a common x axis (linear or log y).
struct XyFigure<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    curves: Vec<Curve>,
    log_y: bool,
    vline: Option<(f64, &'a str)>,
}

impl XyFigure<'_> {
    /// The x axis range: all curves and the vertical marker.
    fn x_range(&self) -> (f64, f64) {
        let xs = self
            .curves
            .iter()
            .flat_map(|c| c.points.iter().map(|p| p.0));
        let xs = xs.chain(self.vline.map(|v| v.0));
        linear_range(bounds(xs), 0.0)
    }

    /// The y axis range (a decade and a half of margin on a log axis).
    fn y_range(&self) -> (f64, f64) {
        let ys = self
            .curves
            .iter()
            .flat_map(|c| c.points.iter().map(|p| p.1));
        if self.log_y {
            match bounds(ys) {
                Some((lo, hi)) => (lo / 3.0, hi * 3.0),
                None => (0.1, 10.0),
            }
        } else {
            linear_range(bounds(ys), 0.05)
        }
    }

    fn legend(&self) -> Vec<LegendEntry> {
        let mut entries: Vec<LegendEntry> = self
            .curves
            .iter()
            .map(|c| LegendEntry {
                label: c.label.clone(),
                color: c.color,
                dashed: false,
                marker: false,
                line: true,
                triangle: false,
            })
            .collect();
        if let Some((_, label)) = self.vline {
            entries.push(LegendEntry {
                label: label.to_string(),
                color: RGBColor(90, 90, 90),
                dashed: true,
                marker: false,
                line: true,
                triangle: false,
            });
        }
        entries
    }
}

impl Figure for XyFigure<'_> {
    fn check(&self) -> Result<(), String> {
        let (x0, x1) = self.x_range();
        check_axis("x", x0, x1, false)?;
        let (y0, y1) = self.y_range();
        check_axis("y", y0, y1, self.log_y)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
    ) -> Result<(), String> {
        let entries = self.legend();
        let (plot_area, legend_area) = layout(root, self.title, &entries)?;

        let (x0, x1) = self.x_range();
        let x_fmt = linear_formatter(x0, x1);

        let tick = text_style(TICK_SIZE);
        let desc = text_style(DESC_SIZE);
        let vline_style = ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(2);

        if self.log_y {
            let (y0, y1) = self.y_range();
            let axis = LogAxis::new(y0, y1);
            let labels = axis.key_points(BoldPoints(12));
            let yl = y_label_area(&plot_area, labels.iter().map(log_label))?;
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(MARGIN)
                .x_label_area_size(X_LABEL_AREA)
                .y_label_area_size(yl)
                .build_cartesian_2d(x0..x1, axis)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(self.x_label)
                .y_desc(self.y_label)
                .x_labels(10)
                .y_labels(12)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&log_label)
                .label_style(tick.clone())
                .axis_desc_style(desc.clone())
                .light_line_style(RGBColor(235, 235, 235))
                .bold_line_style(RGBColor(205, 205, 205))
                .draw()
                .map_err(err)?;
            draw_curves(&mut chart, &self.curves, false, raster)?;
            if let Some((x, _)) = self.vline {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(x, y0), (x, y1)],
                        10,
                        7,
                        vline_style,
                    ))
                    .map_err(err)?;
            }
        } else {
            let (y0, y1) = self.y_range();
            let y_fmt = linear_formatter(y0, y1);
            let axis = RangedCoordf64::from(y0..y1);
            let labels = axis.key_points(10usize);
            let yl = y_label_area(&plot_area, labels.iter().map(&y_fmt))?;
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(MARGIN)
                .x_label_area_size(X_LABEL_AREA)
                .y_label_area_size(yl)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(self.x_label)
                .y_desc(self.y_label)
                .x_labels(10)
                .y_labels(10)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&y_fmt)
                .label_style(tick.clone())
                .axis_desc_style(desc.clone())
                .light_line_style(RGBColor(238, 238, 238))
                .max_light_lines(4)
                .bold_line_style(RGBColor(210, 210, 210))
                .draw()
                .map_err(err)?;
            draw_curves(&mut chart, &self.curves, false, raster)?;
            if let Some((x, _)) = self.vline {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(x, y0), (x, y1)],
                        10,
                        7,
                        vline_style,
                    ))
                    .map_err(err)?;
            }
        }
        draw_legend(&legend_area, &entries, MARGIN as i32, raster)
    }
}

/// Sizes of the axes of an x-y chart, in pixels.
pub(crate) struct AxisStyle {
    /// Tick label font size.
    pub tick: f64,
    /// Axis description font size.
    pub desc: f64,
    /// Outer margin of the chart.
    pub margin: u32,
    /// Height of the x tick-label plus axis-description band.
    pub x_label_area: u32,
    /// Number of tick labels per axis (at most).
    pub labels: usize,
}

impl AxisStyle {
    /// The axes of the figures ([`WIDTH`] × [`HEIGHT`]).
    pub const FIGURE: Self = Self {
        tick: TICK_SIZE,
        desc: DESC_SIZE,
        margin: MARGIN,
        x_label_area: X_LABEL_AREA,
        labels: 10,
    };
}

/// Builds a chart with axes `x_desc`, `y_desc` (`x [m]`, `y [m]`) on `area` with equal scales (1 m in x as long as 1 m in
/// y) that shows at least the data box `(x0, x1, y0, y1)`, centred, and draws its axes and
/// grid. The box must pass [`check_box`].
pub(crate) fn equal_aspect_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    data_box: (f64, f64, f64, f64),
    style: &AxisStyle,
    (x_desc, y_desc): (&str, &str),
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, String> {
    let (bx0, bx1, by0, by1) = data_box;
    // Label area sized for labels of the padded box (final ranges are similar or wider).
    let y_fmt_guess = linear_formatter(by0, by1);
    let guess = RangedCoordf64::from(by0..by1).key_points(style.labels);
    let yl = y_label_area_sized(area, guess.iter().map(&y_fmt_guess), style.tick, style.desc)?
        + (style.tick * 2.0 / 3.0) as u32;

    // Measure the plotting area to make 1 m in x as long as 1 m in y.
    let (pw, ph) = {
        let probe = ChartBuilder::on(area)
            .margin(style.margin)
            .x_label_area_size(style.x_label_area)
            .y_label_area_size(yl)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(err)?;
        let (w, h) = probe.plotting_area().dim_in_pixel();
        (f64::from(w.max(1)), f64::from(h.max(1)))
    };
    let m_per_px = ((bx1 - bx0) / pw).max((by1 - by0) / ph);
    let (cx, cy) = (0.5 * (bx0 + bx1), 0.5 * (by0 + by1));
    let (x0, x1) = (cx - 0.5 * m_per_px * pw, cx + 0.5 * m_per_px * pw);
    let (y0, y1) = (cy - 0.5 * m_per_px * ph, cy + 0.5 * m_per_px * ph);
    let x_fmt = linear_formatter(x0, x1);
    let y_fmt = linear_formatter(y0, y1);

    let mut chart = ChartBuilder::on(area)
        .margin(style.margin)
        .x_label_area_size(style.x_label_area)
        .y_label_area_size(yl)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(style.labels)
        .y_labels(style.labels)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(text_style(style.tick))
        .axis_desc_style(text_style(style.desc))
        .light_line_style(RGBColor(238, 238, 238))
        .max_light_lines(4)
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// A filled circle of `radius` px at `(x, y)` in m (a point mass).
struct Dot {
    x: f64,
    y: f64,
    radius: u32,
    color: RGBColor,
}

/// Snapshots of the string or network in the plane, equal aspect ratio.
struct ConfigFigure<'a> {
    title: &'a str,
    curves: Vec<Curve>,
    dots: Vec<Dot>,
    entries: Vec<LegendEntry>,
    /// Node markers on the curves.
    markers: bool,
    /// Axis descriptions (horizontal, vertical).
    labels: (String, String),
    /// The water drawn behind the configuration (none: dry).
    water: Option<WaterLines>,
    /// Nodes on the seabed `(x, y)` [m], drawn as triangles over the curves.
    grounded: Vec<(f64, f64)>,
    /// The rigid bodies' edges and axes, drawn over the curves without node markers.
    outlines: Vec<Curve>,
}

/// The data box `(x0, x1, y0, y1)` of `points` in m, padded by 6 % of its larger span (a
/// point or no points: a box around it).
pub(crate) fn padded_box(points: impl Iterator<Item = (f64, f64)> + Clone) -> (f64, f64, f64, f64) {
    let bx = bounds(points.clone().map(|p| p.0));
    let by = bounds(points.map(|p| p.1));
    let ((bx0, bx1), (by0, by1)) = match (bx, by) {
        (Some(x), Some(y)) => (x, y),
        _ => ((0.0, 1.0), (0.0, 1.0)),
    };
    let span = (bx1 - bx0).max(by1 - by0);
    let pad = if span > 0.0 {
        0.06 * span
    } else {
        0.1 * bx0.abs().max(by0.abs()).max(1.0)
    };
    (bx0 - pad, bx1 + pad, by0 - pad, by1 + pad)
}

/// Checks that the data box `(x0, x1, y0, y1)` can be drawn (see [`check_axis`]).
pub(crate) fn check_box(b: (f64, f64, f64, f64)) -> Result<(), String> {
    check_axis("x", b.0, b.1, false)?;
    check_axis("y", b.2, b.3, false)
}

impl ConfigFigure<'_> {
    /// The padded data box `(x0, x1, y0, y1)` in m.
    fn data_box(&self) -> (f64, f64, f64, f64) {
        let pts = self
            .curves
            .iter()
            .chain(&self.outlines)
            .flat_map(|c| c.points.iter().copied())
            .chain(self.dots.iter().map(|d| (d.x, d.y)));
        if self.water.is_none() {
            return padded_box(pts);
        }
        padded_box(with_water(pts.collect(), self.water.as_ref()).into_iter())
    }
}

impl Figure for ConfigFigure<'_> {
    fn check(&self) -> Result<(), String> {
        check_box(self.data_box())
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
    ) -> Result<(), String> {
        let entries = &self.entries;
        let (plot_area, legend_area) = layout(root, self.title, entries)?;

        let (xl, yl) = (&self.labels.0, &self.labels.1);
        let mut chart =
            equal_aspect_chart(&plot_area, self.data_box(), &AxisStyle::FIGURE, (xl, yl))?;
        if let Some(w) = &self.water {
            let spec = chart.as_coord_spec();
            let (xr, yr) = (spec.get_x_range(), spec.get_y_range());
            draw_water(&mut chart, w, (xr.start, xr.end), (yr.start, yr.end))?;
        }
        draw_curves(&mut chart, &self.curves, self.markers, raster)?;
        draw_curves(&mut chart, &self.outlines, false, raster)?;
        if !self.grounded.is_empty() {
            chart
                .draw_series(
                    self.grounded
                        .iter()
                        .map(|p| TriangleMarker::new(*p, GROUNDED_SIZE, GROUNDED.filled())),
                )
                .map_err(err)?;
        }
        chart
            .draw_series(
                self.dots
                    .iter()
                    .map(|d| Circle::new((d.x, d.y), d.radius, d.color.filled())),
            )
            .map_err(err)?;
        draw_legend(&legend_area, entries, MARGIN as i32, raster)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A fresh, empty directory under the system temp dir.
    fn temp_dir(name: &str) -> PathBuf {
        crate::test_util::temp_dir("plot", name)
    }

    /// Removes a test directory unless `PHSTRING_KEEP_TEST_PLOTS` is set (to inspect the figures).
    fn cleanup(dir: &Path) {
        if std::env::var_os("PHSTRING_KEEP_TEST_PLOTS").is_none() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }

    /// Asserts both files exist, the SVG holds `texts`, the PNG has the right signature and size.
    fn check_outputs(stem: &Path, texts: &[&str]) {
        let svg = std::fs::read_to_string(with_extension(stem, "svg")).unwrap();
        assert!(svg.contains("<svg"), "not an SVG");
        for t in texts {
            assert!(svg.contains(t), "SVG lacks {t:?}");
        }
        let png = std::fs::read(with_extension(stem, "png")).unwrap();
        assert!(png.len() > 24);
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&png[12..16], b"IHDR");
        let w = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
        let h = u32::from_be_bytes([png[20], png[21], png[22], png[23]]);
        assert_eq!((w, h), (WIDTH, HEIGHT));
    }

    /// Pendulum-like snapshots: 31 nodes of a 1 m string hanging from the origin.
    fn pendulum_snapshots() -> Vec<(f64, Vec<[f64; 2]>)> {
        (0..6)
            .map(|k| {
                let t = 0.2 * k as f64;
                let phi0 = -PI / 4.0 + 1.3 * t; // swing from 45° right towards left
                let nodes = (0..31)
                    .map(|i| {
                        let s = i as f64 / 30.0;
                        let phi = phi0 + 0.6 * t * s * s; // whip-like bending
                        [
                            s * (phi + PI / 2.0).cos() * 1.0,
                            -s * (phi + PI / 2.0).sin(),
                        ]
                    })
                    .collect();
                (t, nodes)
            })
            .collect()
    }

    #[test]
    fn formatter_zero_and_trimming() {
        let f = linear_formatter(-1.0, 1.0);
        assert_eq!(f(&-0.0), "0");
        assert_eq!(f(&1e-17), "0");
        assert_eq!(f(&0.5), "0.5");
        assert_eq!(f(&0.30000000000000004), "0.3");
        assert_eq!(f(&-0.2), "-0.2");
        let g = linear_formatter(0.0, 1e-5);
        assert_eq!(g(&5e-6), "5e-6");
        assert_eq!(log_label(&1e-12), "1e-12");
        let almost = 1e-12 * (1.0 - 1e-15);
        assert!(almost < 1e-12);
        assert_eq!(log_label(&almost), "1e-12");
        assert_eq!(format_plain(0.2), "0.2");
        assert_eq!(format_plain(1.0), "1");
    }

    #[test]
    fn log_axis_ticks_cover_tiny_values() {
        let axis = LogAxis::new(1.8e-17, 3e-4);
        let ticks = axis.key_points(BoldPoints(12));
        assert!(ticks.iter().any(|v| (v / 1e-16 - 1.0).abs() < 1e-9));
        assert!(ticks.len() <= 12);
        let narrow = LogAxis::new(3e-6, 3e-5);
        assert!(narrow.key_points(BoldPoints(12)).len() >= 3);
    }

    #[test]
    fn energy_plot_writes_svg_and_png() {
        let dir = temp_dir("energy");
        let stem = dir.join("energy");
        let t: Vec<f64> = (0..=500).map(|i| i as f64 * 0.002).collect();
        let kin: Vec<f64> = t
            .iter()
            .map(|t| 0.5 * (PI * t / 2.0).sin().powi(2))
            .collect();
        let pot: Vec<f64> = kin.iter().map(|k| 0.5 - k).collect();
        let ham: Vec<f64> = kin.iter().zip(&pot).map(|(a, b)| a + b).collect();
        energy_plot(&stem, "String pendulum: energy", &t, &kin, &pot, &ham).unwrap();
        check_outputs(&stem, &["t [s]", "energy [J]", "kinetic", "Hamiltonian"]);
        cleanup(&dir);
    }

    #[test]
    fn configuration_plot_writes_svg_and_png() {
        let dir = temp_dir("config");
        let stem = dir.join("configuration");
        configuration_plot(&stem, "String pendulum", &pendulum_snapshots()).unwrap();
        check_outputs(&stem, &["x [m]", "y [m]", "t = 0.2 s", "t = 1 s"]);
        cleanup(&dir);
    }

    #[test]
    fn series_plot_linear_and_log() {
        let dir = temp_dir("series");
        let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 1e-3).collect();
        let dg: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, _)| {
                if i % 7 == 0 {
                    0.0
                } else {
                    1e-14 * (1.0 + (i as f64).sin())
                }
            })
            .collect();
        let mp: Vec<f64> = t
            .iter()
            .map(|t| 1e-5 * (1.0 + 0.8 * (20.0 * t).sin()))
            .collect();
        let stem = dir.join("increments");
        series_plot(
            &stem,
            "Energy increments",
            "t [s]",
            "|Ĥ(n+1) − Ĥ(n)| [J]",
            &[
                Series {
                    label: "DG",
                    x: &t,
                    y: &dg,
                },
                Series {
                    label: "MP",
                    x: &t,
                    y: &mp,
                },
            ],
            true,
            Some((0.2, "end of loading")),
        )
        .unwrap();
        check_outputs(&stem, &["t [s]", "DG", "MP", "end of loading", "1e-14"]);

        let h_dg: Vec<f64> = t.iter().map(|_| 0.5).collect();
        let h_mp: Vec<f64> = t.iter().map(|t| 0.5 - 2e-4 * t).collect();
        let stem = dir.join("hamiltonian");
        series_plot(
            &stem,
            "Hamiltonian",
            "t [s]",
            "Ĥ [J]",
            &[
                Series {
                    label: "DG",
                    x: &t,
                    y: &h_dg,
                },
                Series {
                    label: "MP",
                    x: &t,
                    y: &h_mp,
                },
            ],
            false,
            Some((0.2, "end of loading")),
        )
        .unwrap();
        check_outputs(&stem, &["Ĥ [J]", "DG", "MP", "end of loading", "0.4999"]);
        cleanup(&dir);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let dir = temp_dir("degenerate");
        let empty: [f64; 0] = [];
        energy_plot(&dir.join("e0"), "", &empty, &empty, &empty, &empty).unwrap();
        check_outputs(&dir.join("e0"), &["energy [J]"]);
        let t = [0.0, 1.0, 2.0];
        let c = [1.0, 1.0, 1.0];
        let nan = [f64::NAN, f64::INFINITY, f64::NAN];
        energy_plot(&dir.join("e1"), "flat", &t, &c, &nan, &c).unwrap();
        configuration_plot(&dir.join("c0"), "none", &[]).unwrap();
        configuration_plot(&dir.join("c1"), "point", &[(0.0, vec![[0.0, 0.0]])]).unwrap();
        let zeros = [0.0, -1.0, f64::NAN];
        series_plot(
            &dir.join("s0"),
            "all skipped",
            "t [s]",
            "y",
            &[Series {
                label: "z",
                x: &t,
                y: &zeros,
            }],
            true,
            Some((f64::NAN, "bad")),
        )
        .unwrap();
        series_plot(&dir.join("s1"), "", "x", "y", &[], false, None).unwrap();
        let bad = series_plot(
            &dir.join("s2"),
            "",
            "x",
            "y",
            &[Series {
                label: "m",
                x: &t,
                y: &c[..2],
            }],
            false,
            None,
        );
        assert!(matches!(bad, Err(PlotError::Input { .. })));
        cleanup(&dir);
    }

    /// Plotters' tick computation loops forever on ranges that are not finite or too narrow
    /// for their magnitude; such data is refused before drawing, so a plot never hangs.
    #[test]
    fn plot_hang_degenerate_and_extreme_ranges_are_refused() {
        let dir = temp_dir("extreme");
        let range_err = |r: Result<(), PlotError>| {
            let e = r.unwrap_err();
            assert!(matches!(e, PlotError::Range { .. }), "{e}");
        };
        // Every node at x = 1e308.
        let far = vec![(0.0, vec![[1e308, 0.0], [1e308, -1.0]])];
        range_err(configuration_plot(&dir.join("c1"), "far", &far));
        // A span of 1e-10 m at 1e10 m (relative 1e-20) and a huge magnitude.
        let narrow = vec![(0.0, vec![[1e10, 0.0], [1e10 + 1e-6, 0.0]])];
        range_err(configuration_plot(&dir.join("c2"), "narrow", &narrow));
        let huge = vec![(0.0, vec![[0.0, 0.0], [1e16, -1.0]])];
        range_err(configuration_plot(&dir.join("c3"), "huge", &huge));
        let t = [0.0, 1.0, 2.0];
        let big = [1e300, -1e300, 1.7e308];
        range_err(energy_plot(&dir.join("e1"), "big", &t, &big, &big, &big));
        let ext = [f64::MAX, -f64::MAX, 0.0];
        let s = |y: &'static [f64]| Series {
            label: "y",
            x: &[0.0, 1.0, 2.0],
            y,
        };
        range_err(series_plot(
            &dir.join("s1"),
            "",
            "x",
            "y",
            &[s(&[1e300, 1.7e308, 1e200])],
            true,
            None,
        ));
        range_err(series_plot(
            &dir.join("s2"),
            "",
            "x",
            "y",
            &[Series {
                label: "e",
                x: &ext,
                y: &t,
            }],
            false,
            None,
        ));
        // Constant values are widened, not refused; moderate extremes still draw.
        let c = [1e12, 1e12, 1e12];
        energy_plot(&dir.join("e2"), "constant", &t, &c, &c, &c).unwrap();
        let tiny = vec![(0.0, vec![[1e-300, 0.0], [2e-300, 1e-300]])];
        configuration_plot(&dir.join("c4"), "tiny", &tiny).unwrap();
        series_plot(
            &dir.join("s3"),
            "",
            "x",
            "y",
            &[s(&[1e-300, 1e300, 5.0])],
            true,
            None,
        )
        .unwrap();
        for name in ["c1", "c2", "c3", "e1", "s1", "s2"] {
            assert!(!with_extension(&dir.join(name), "svg").exists(), "{name}");
        }
        cleanup(&dir);
    }

    /// Control characters are stripped from titles (they would reach a terminal, and NUL would
    /// make the SVG invalid), and long titles are clipped.
    #[test]
    fn control_characters_in_titles_are_stripped() {
        assert_eq!(sanitize_text("a\0b\x1b[31mc\r\n\u{85}d", 100), "ab[31mcd");
        assert_eq!(sanitize_text("abcdef", 3), "abc…");
        assert_eq!(sanitize_text("Ĥ (Hamiltonian)", 100), "Ĥ (Hamiltonian)");
        let dir = temp_dir("control");
        let stem = dir.join("energy");
        let t = [0.0, 1.0];
        let title = format!("bad\0title\x1b[2J{}", "x".repeat(10_000));
        energy_plot(&stem, &title, &t, &t, &t, &t).unwrap();
        let svg = std::fs::read_to_string(with_extension(&stem, "svg")).unwrap();
        assert!(
            !svg.chars()
                .any(|c| c.is_control() && c != '\n' && c != '\t' && c != '\r')
        );
        assert!(svg.contains("badtitle[2J"));
        assert!(!svg.contains(&"x".repeat(MAX_TEXT_CHARS + 1)));
        cleanup(&dir);
    }

    #[test]
    fn missing_directory_is_an_error() {
        let stem = std::env::temp_dir()
            .join("phstring-plot-does-not-exist-dir")
            .join("sub")
            .join("fig");
        let r = series_plot(&stem, "", "x", "y", &[], false, None);
        assert!(r.is_err());
    }
}
