//! Animated GIF of a run's configuration over time (`animation.gif`), for `d ≥ 2`.
//!
//! Like the plots read `energy.csv` back, the animation reads `positions.csv` back, so that
//! memory does not grow with the number of steps: a first pass indexes the frames (keeping
//! at most [`INDEX_LIMIT`] byte offsets, evenly thinned), then at most [`MAX_FRAMES`] frames,
//! evenly picked from the first to the last, are read twice by their offsets: once for the
//! bounding box of all of them (fixed axes with equal scales), once to draw them. Only one
//! frame's positions are in memory at a time. A 3D run is drawn in the plane of its
//! configuration plot ([`Scene`]); in water, the nodes on the seabed in each frame (the
//! run's contact test, [`crate::scene::ContactTest`]) are marked with triangles.
//!
//! Each frame is drawn with plotters into an RGB buffer of [`ANIMATION_WIDTH`] ×
//! [`ANIMATION_HEIGHT`] px (axes and title drawn once), mapped onto a fixed 256-colour
//! palette (the group colours exactly, greys, a colour cube) and stored as the rectangle of
//! pixels that changed since the previous frame, unchanged pixels transparent; the file is
//! written next to its place and renamed into it when complete, and a file beyond
//! [`MAX_BYTES`] is refused. Strings are drawn in their group's colour (as in the
//! configuration plot), springs thin and grey, point masses as black dots growing with the
//! mass, rigid bodies as the boxes of their inertia with their body axes
//! ([`crate::body_shape`]) at their poses read back from `bodies.csv`. Every failure is an `Err(reason)` for the caller to report as a warning: the
//! animation never fails a run.

use std::borrow::Cow;
use std::fs::File;
use std::io::{BufRead, BufReader, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use plotters::coord::CoordTranslate;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use crate::body_shape::read_poses;
use crate::files::{ANIMATION_FILE, BODIES_FILE, POSITIONS_FILE, temp_path};
use crate::plot::{self, AxisStyle, BODY_AXIS_COLORS, BODY_COLOR, MASS_COLOR, Topology};
use crate::scene::{BodyOutline, Scene};

/// Width of the animation [px].
pub const ANIMATION_WIDTH: u32 = 480;
/// Height of the animation [px].
pub const ANIMATION_HEIGHT: u32 = 360;
/// Most frames in an animation (evenly picked from the frames of `positions.csv`).
pub const MAX_FRAMES: usize = 200;
/// Largest animation file [bytes]; a larger one is not written.
pub const MAX_BYTES: u64 = 16 << 20;
/// Most frame offsets kept while indexing `positions.csv` (thinned by halves beyond it).
pub const INDEX_LIMIT: usize = 4096;
/// Playing time of a whole animation, about [s].
const PLAY_SECONDS: f64 = 8.0;
/// Index of the transparent colour in the palette.
const TRANSPARENT: u8 = 255;
/// First palette index of the exact colours, after the 6 × 6 × 6 colour cube.
const EXACT: usize = 216;
/// Number of exact colours.
const N_EXACT: usize = 8;
/// First palette index of the grey ramp.
const GREYS: usize = EXACT + N_EXACT;
/// Number of grey levels (`GREYS .. GREYS + N_GREYS`, then the transparent index).
const N_GREYS: usize = 31;
/// Height of the title band [px].
const HEADER: u32 = 26;

/// What [`write_animation`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationReport {
    /// The file written (`dir/animation.gif`).
    pub path: PathBuf,
    /// Frames in the animation.
    pub frames: usize,
    /// Complete frames in `positions.csv`.
    pub frames_available: usize,
    /// Size of the file [bytes].
    pub bytes: u64,
}

/// Writes `dir/animation.gif`: the configuration of the network `topology` over time, read
/// back from `dir/positions.csv` (dimension `dim` ≥ 2, drawn in the plane of `scene` with
/// its water, see [`Scene`]), at most
/// [`MAX_FRAMES`] frames evenly picked from its first to its last, each labelled with its
/// time and `title`. Returns `Err(reason)` and writes nothing (a stale file from an earlier
/// attempt stays) if there is nothing to draw (d = 1, no `positions.csv`, degenerate or
/// extreme coordinates, a topology that does not fit the nodes), if the file would exceed
/// [`MAX_BYTES`], if writing fails, or once `stop` is set.
pub fn write_animation(
    dir: &Path,
    dim: usize,
    title: &str,
    topology: &Topology,
    scene: &Scene,
    stop: Option<&AtomicBool>,
) -> Result<AnimationReport, String> {
    if dim < 2 {
        return Err("an animation needs a configuration in 2D or 3D".into());
    }
    let path = dir.join(ANIMATION_FILE);
    let tmp = temp_path(&path);
    let res = write_to(&tmp, dir, dim, title, (topology, scene), stop).and_then(|mut report| {
        std::fs::rename(&tmp, &path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        report.path = path.clone();
        Ok(report)
    });
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res
}

/// Whether a stop was requested.
fn stopped(stop: Option<&AtomicBool>) -> bool {
    stop.is_some_and(|s| s.load(Ordering::Relaxed))
}

/// The frames of `positions.csv`: byte offsets and times of an evenly thinned subset, and of
/// the last complete frame.
#[derive(Debug, Default)]
struct FrameIndex {
    /// Nodes per frame.
    n_nodes: usize,
    /// `(byte offset, t)` of frames `0, every, 2 every, …`.
    kept: Vec<(u64, f64)>,
    every: usize,
    /// Complete frames.
    count: usize,
    /// The last complete frame.
    last: Option<(u64, f64)>,
}

impl FrameIndex {
    fn add(&mut self, frame: (u64, f64)) {
        if self.count.is_multiple_of(self.every) {
            self.kept.push(frame);
            if self.kept.len() >= INDEX_LIMIT {
                // Keep frames 0, 2 every, 4 every, …
                let mut k = 0;
                self.kept.retain(|_| {
                    k += 1;
                    (k - 1) % 2 == 0
                });
                self.every *= 2;
            }
        }
        self.last = Some(frame);
        self.count += 1;
    }

    /// At most `max` frames, evenly spread from the first to the last.
    fn pick(&self, max: usize) -> Vec<(u64, f64)> {
        let mut all = self.kept.clone();
        if let Some(last) = self.last
            && all.last() != Some(&last)
        {
            all.push(last);
        }
        let m = all.len().min(max);
        if m <= 1 {
            return all.into_iter().take(m).collect();
        }
        (0..m)
            .map(|j| all[(j * (all.len() - 1) + (m - 1) / 2) / (m - 1)])
            .collect()
    }
}

/// The first two comma-separated fields of `line` and the rest.
fn split2(line: &str) -> Option<(&str, &str, &str)> {
    let (t, rest) = line.split_once(',')?;
    match rest.split_once(',') {
        Some((node, rest)) => Some((t, node, rest)),
        None => Some((t, rest, "")),
    }
}

/// Reads the header of `positions.csv` and indexes its frames (see [`FrameIndex`]).
fn index_frames(
    reader: &mut BufReader<File>,
    dim: usize,
    stop: Option<&AtomicBool>,
) -> Result<FrameIndex, String> {
    let comps = ["x", "y", "z"];
    let expected = format!("t,node,{}", comps[..dim.min(3)].join(","));
    let mut line = String::new();
    let mut offset = reader
        .read_line(&mut line)
        .map_err(|e| format!("cannot read positions.csv: {e}"))? as u64;
    if line.trim_end() != expected {
        return Err(format!(
            "positions.csv has the header {:?}, expected {expected:?}",
            crate::text::sanitize_text(line.trim_end(), 60)
        ));
    }
    let mut index = FrameIndex {
        every: 1,
        ..FrameIndex::default()
    };
    // The frame being read: (offset, t, rows so far).
    let mut open: Option<(u64, f64, usize)> = None;
    let mut number = 1usize;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| format!("cannot read positions.csv: {e}"))?;
        if n == 0 {
            break;
        }
        number += 1;
        if number.is_multiple_of(65_536) && stopped(stop) {
            return Err("stop requested".into());
        }
        let bad = |what: &str| format!("positions.csv line {number}: {what}");
        let (t, node, _) = split2(line.trim_end()).ok_or_else(|| bad("too few fields"))?;
        let node: usize = node.parse().map_err(|_| bad("not a node index"))?;
        if node == 0 {
            if let Some((off, t0, rows)) = open {
                if index.n_nodes == 0 {
                    index.n_nodes = rows;
                }
                if rows != index.n_nodes {
                    return Err(bad("a frame has a different number of nodes"));
                }
                index.add((off, t0));
            }
            let t: f64 = t.parse().map_err(|_| bad("not a time"))?;
            open = Some((offset, t, 1));
        } else {
            match &mut open {
                Some((_, _, rows)) if *rows == node => *rows += 1,
                _ => return Err(bad("nodes out of order")),
            }
        }
        offset += n as u64;
    }
    // The last frame counts if it is complete (a killed run may have cut it short).
    if let Some((off, t0, rows)) = open
        && (index.n_nodes == 0 || rows == index.n_nodes)
    {
        index.n_nodes = rows;
        index.add((off, t0));
    }
    if index.count == 0 {
        return Err("positions.csv holds no frame".into());
    }
    Ok(index)
}

/// Reads the frame at `offset` (`n_nodes` rows) into `xy` (each node in the plane of
/// `scene`) and `raw` (as read, `[x, y, z]` with unused components 0).
fn read_frame(
    reader: &mut BufReader<File>,
    (offset, n_nodes): (u64, usize),
    scene: &Scene,
    (xy, raw): (&mut Vec<[f64; 2]>, &mut Vec<[f64; 3]>),
) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot read positions.csv: {e}");
    reader.seek(SeekFrom::Start(offset)).map_err(err)?;
    xy.clear();
    raw.clear();
    let mut line = String::new();
    for i in 0..n_nodes {
        line.clear();
        reader.read_line(&mut line).map_err(err)?;
        let bad = || format!("positions.csv at byte {offset}: row {i} of a frame is malformed");
        let (_, node, rest) = split2(line.trim_end()).ok_or_else(bad)?;
        if node.parse::<usize>().ok() != Some(i) {
            return Err(bad());
        }
        let mut p = [0.0; 3];
        let mut k = 0;
        for c in rest.split(',').take(3) {
            p[k] = c.parse::<f64>().map_err(|_| bad())?;
            k += 1;
        }
        if k < 2 {
            return Err(bad());
        }
        if !p[..k].iter().all(|x| x.is_finite()) {
            return Err(format!(
                "positions.csv at byte {offset}: node {i} has a non-finite position"
            ));
        }
        xy.push(scene.node_point(i, &p[..k]));
        raw.push(p);
    }
    Ok(())
}

/// A writer that counts the bytes written through it.
struct Counting<W> {
    inner: W,
    bytes: u64,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The fixed palette: a 6 × 6 × 6 colour cube, up to [`N_EXACT`] exact colours, a grey
/// ramp, and the transparent index (white).
struct Palette {
    exact: Vec<RGBColor>,
}

impl Palette {
    fn new(exact: &[RGBColor]) -> Self {
        let mut list: Vec<RGBColor> = Vec::new();
        for &c in exact {
            if list.len() < N_EXACT && !list.contains(&c) {
                list.push(c);
            }
        }
        Self { exact: list }
    }

    /// `[r, g, b, …]` of all 256 entries.
    fn rgb(&self) -> Vec<u8> {
        let mut p = Vec::with_capacity(768);
        for r in 0..6u8 {
            for g in 0..6u8 {
                for b in 0..6u8 {
                    p.extend([51 * r, 51 * g, 51 * b]);
                }
            }
        }
        for k in 0..N_EXACT {
            let c = self
                .exact
                .get(k)
                .copied()
                .unwrap_or(RGBColor(255, 255, 255));
            p.extend([c.0, c.1, c.2]);
        }
        for k in 0..N_GREYS {
            let v = (k as f64 * 255.0 / (N_GREYS - 1) as f64).round() as u8;
            p.extend([v, v, v]);
        }
        p.extend([255, 255, 255]);
        p
    }

    /// The palette index of a pixel.
    fn index(&self, r: u8, g: u8, b: u8) -> u8 {
        if (r, g, b) == (255, 255, 255) {
            return (EXACT - 1) as u8;
        }
        if let Some(k) = self.exact.iter().position(|c| *c == RGBColor(r, g, b)) {
            return (EXACT + k) as u8;
        }
        if r == g && g == b {
            let level = (f64::from(r) * (N_GREYS - 1) as f64 / 255.0).round() as usize;
            return (GREYS + level) as u8;
        }
        let q = |v: u8| (u16::from(v) + 25) / 51;
        (36 * q(r) + 6 * q(g) + q(b)) as u8
    }
}

/// The padded bounding box `(x0, x1, y0, y1)` [m] of the node positions of all `frames`
/// (offsets into `positions.csv` and times), checked drawable; `xy` and `raw` are the
/// buffers frames are read into.
fn frames_box(
    reader: &mut BufReader<File>,
    (frames, bodies): (&[(u64, f64)], &[Vec<BodyOutline>]),
    (n_nodes, scene): (usize, &Scene),
    stop: Option<&AtomicBool>,
    (xy, raw): (&mut Vec<[f64; 2]>, &mut Vec<[f64; 3]>),
) -> Result<(f64, f64, f64, f64), String> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (k, &(offset, _)) in frames.iter().enumerate() {
        if stopped(stop) {
            return Err("stop requested".into());
        }
        read_frame(reader, (offset, n_nodes), scene, (xy, raw))?;
        let outlines = bodies.get(k).map_or(&[][..], Vec::as_slice);
        let corners = outlines
            .iter()
            .flat_map(|o| o.edges.iter().chain(&o.axes).flatten());
        for p in xy.iter().chain(corners) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let corners = vec![(lo[0], lo[1]), (hi[0], hi[1])];
    let data_box = plot::padded_box(plot::with_water(corners, scene.water.as_ref()).into_iter());
    plot::check_box(data_box)?;
    Ok(data_box)
}

/// The drawings of the rigid bodies of `scene` at each of the `frames` (offsets and times),
/// their poses read back from `dir/bodies.csv` at the frames' times (the nearest rows:
/// the same time unless `output.row_stride` thins them); empty without bodies or in the
/// view of one plane per line.
fn frame_bodies(
    dir: &Path,
    scene: &Scene,
    frames: &[(u64, f64)],
) -> Result<Vec<Vec<BodyOutline>>, String> {
    if scene.bodies.is_empty() || scene.lines.is_some() {
        return Ok(Vec::new());
    }
    let times: Vec<f64> = frames.iter().map(|f| f.1).collect();
    let poses = read_poses(&dir.join(BODIES_FILE), scene.bodies.len(), &times)?;
    let outline = |pose: &Vec<_>| {
        scene
            .bodies
            .iter()
            .zip(pose)
            .filter_map(|(b, p)| scene.body_outline(b, p))
            .filter(|o| {
                o.edges
                    .iter()
                    .chain(&o.axes)
                    .flatten()
                    .flatten()
                    .all(|x| x.is_finite())
            })
            .collect()
    };
    Ok(poses.iter().map(outline).collect())
}

/// The background of every frame, `w × h` RGB pixels: the title, the axes of `data_box`
/// with their grid; and the mapping from positions [m] to its pixels.
fn draw_background(
    (title, scene): (&str, &Scene),
    data_box: (f64, f64, f64, f64),
    (w, h): (u32, u32),
) -> Result<(Vec<u8>, Cartesian2d<RangedCoordf64, RangedCoordf64>), String> {
    let mut background = vec![0u8; (w * h * 3) as usize];
    let coord = {
        let root = BitMapBackend::with_buffer(&mut background, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot::err)?;
        let (header, body) = root.split_vertically(HEADER);
        header
            .draw_text(
                &crate::text::sanitize_text(title, 48),
                &plot::text_style(14.0),
                (8, 6),
            )
            .map_err(plot::err)?;
        let style = AxisStyle {
            tick: 11.0,
            desc: 12.0,
            margin: 8,
            x_label_area: 36,
            labels: 6,
        };
        let (xl, yl) = scene.axis_labels();
        let mut chart = plot::equal_aspect_chart(&body, data_box, &style, (&xl, &yl))?;
        if let Some(water) = &scene.water {
            let spec = chart.as_coord_spec();
            let (xr, yr) = (spec.get_x_range(), spec.get_y_range());
            plot::draw_water(&mut chart, water, (xr.start, xr.end), (yr.start, yr.end))?;
        }
        let coord = chart.as_coord_spec().clone();
        root.present().map_err(plot::err)?;
        coord
    };
    Ok((background, coord))
}

/// How a frame of the animation is drawn over its background.
struct Picture<'a> {
    /// The network.
    topology: &'a Topology,
    /// The color of each group.
    colors: &'a [RGBColor],
    /// Largest point mass [kg] (sets the marker sizes).
    m_max: f64,
    /// Pixel of a position [m].
    to_px: &'a dyn Fn([f64; 2]) -> (i32, i32),
}

impl Picture<'_> {
    /// Draws the time label `t` [s], the elements (springs under strings), the nodes on the
    /// seabed (`grounded`, triangles) and the point masses at the node positions `xy` [m],
    /// and the rigid bodies `bodies`, onto `rgb` (`w × h` RGB pixels, holding the
    /// background).
    fn draw(
        &self,
        rgb: &mut [u8],
        (w, h): (u32, u32),
        t: f64,
        (xy, grounded, bodies): (&[[f64; 2]], Option<&[usize]>, &[BodyOutline]),
    ) -> Result<(), String> {
        let root = BitMapBackend::with_buffer(rgb, (w, h)).into_drawing_area();
        let label = format!("t = {} s", plot::format_plain(t));
        let style = plot::text_style(14.0);
        let (lw, _) = root.estimate_text_size(&label, &style).map_err(plot::err)?;
        root.draw_text(&label, &style, (w as i32 - lw as i32 - 10, 6))
            .map_err(plot::err)?;
        for spring in [true, false] {
            for (g, group) in self.topology.groups.iter().enumerate() {
                if group.spring != spring {
                    continue;
                }
                let line =
                    ShapeStyle::from(&self.colors[g]).stroke_width(if spring { 1 } else { 2 });
                for e in group.elements.clone() {
                    let [a, b] = self.topology.elements[e];
                    root.draw(&PathElement::new(
                        vec![(self.to_px)(xy[a]), (self.to_px)(xy[b])],
                        line,
                    ))
                    .map_err(plot::err)?;
                }
            }
        }
        for p in grounded
            .unwrap_or_default()
            .iter()
            .filter_map(|&i| xy.get(i))
        {
            root.draw(&TriangleMarker::new(
                (self.to_px)(*p),
                plot::GROUNDED_SIZE - 2,
                plot::GROUNDED.filled(),
            ))
            .map_err(plot::err)?;
        }
        for &(node, m) in &self.topology.masses {
            let r = Topology::mass_radius(m, self.m_max, 2.0, 4.0);
            root.draw(&Circle::new((self.to_px)(xy[node]), r, MASS_COLOR.filled()))
                .map_err(plot::err)?;
        }
        let colored = bodies.iter().flat_map(|o| {
            let edges = o.edges.iter().map(|s| (s, BODY_COLOR));
            edges.chain(o.axes.iter().zip(BODY_AXIS_COLORS))
        });
        for ([a, b], color) in colored {
            let line = vec![(self.to_px)(*a), (self.to_px)(*b)];
            root.draw(&PathElement::new(
                line,
                ShapeStyle::from(&color).stroke_width(1),
            ))
            .map_err(plot::err)?;
        }
        root.present().map_err(plot::err)?;
        Ok(())
    }
}

/// Renders and encodes the animation into `tmp`.
fn write_to(
    tmp: &Path,
    dir: &Path,
    dim: usize,
    title: &str,
    (topology, scene): (&Topology, &Scene),
    stop: Option<&AtomicBool>,
) -> Result<AnimationReport, String> {
    let positions = dir.join(POSITIONS_FILE);
    let file = match File::open(&positions) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err("positions.csv was not written (output.positions = false)".into());
        }
        Err(e) => return Err(format!("cannot read {}: {e}", positions.display())),
    };
    let mut reader = BufReader::new(file);
    let index = index_frames(&mut reader, dim, stop)?;
    let n_nodes = index.n_nodes;
    topology
        .check(n_nodes)
        .map_err(|e| format!("the network does not fit positions.csv: {e}"))?;
    let frames = index.pick(MAX_FRAMES);
    let bodies = frame_bodies(dir, scene, &frames)?;

    // Fixed axes: the bounding box of every frame drawn.
    let (mut xy, mut raw) = (Vec::with_capacity(n_nodes), Vec::with_capacity(n_nodes));
    let data_box = frames_box(
        &mut reader,
        (&frames, &bodies),
        (n_nodes, scene),
        stop,
        (&mut xy, &mut raw),
    )?;
    plot::ensure_font().map_err(|e| e.to_string())?;

    let (w, h) = (ANIMATION_WIDTH, ANIMATION_HEIGHT);
    let colors = plot::group_colors(topology);
    let mut exact: Vec<RGBColor> = colors.clone();
    exact.insert(0, MASS_COLOR);
    if scene.water.is_some() {
        exact.extend([plot::SURFACE_BLUE, plot::SEABED_BROWN, plot::SEABED_FILL]);
    }
    if scene.contact.is_some() {
        exact.push(plot::GROUNDED);
    }
    if !bodies.is_empty() {
        exact.push(BODY_COLOR);
        exact.extend(BODY_AXIS_COLORS);
    }
    let palette = Palette::new(&exact);
    let m_max = topology.masses.iter().map(|m| m.1).fold(0.0, f64::max);

    // The background: title, axes, grid.
    let (background, coord) = draw_background((title, scene), data_box, (w, h))?;
    let to_px = |p: [f64; 2]| coord.translate(&(p[0], p[1]));

    let tmp_file = File::create(tmp).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    let out = Counting {
        inner: std::io::BufWriter::new(tmp_file),
        bytes: 0,
    };
    let gif_err = |e: gif::EncodingError| format!("cannot write {}: {e}", tmp.display());
    let mut encoder =
        gif::Encoder::new(out, w as u16, h as u16, &palette.rgb()).map_err(gif_err)?;
    encoder.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;

    let delay = ((PLAY_SECONDS * 100.0 / frames.len() as f64).round() as u16).clamp(4, 50);
    let mut rgb = vec![0u8; background.len()];
    let mut prev: Option<Vec<u8>> = None;
    let mut indices = vec![0u8; (w * h) as usize];
    let picture = Picture {
        topology,
        colors: &colors,
        m_max,
        to_px: &to_px,
    };
    for (k, &(offset, t)) in frames.iter().enumerate() {
        if stopped(stop) {
            return Err("stop requested".into());
        }
        read_frame(&mut reader, (offset, n_nodes), scene, (&mut xy, &mut raw))?;
        rgb.copy_from_slice(&background);
        let grounded = scene.contact.as_ref().map(|c| c.grounded(&raw));
        let outlines = bodies.get(k).map_or(&[][..], Vec::as_slice);
        picture.draw(&mut rgb, (w, h), t, (&xy, grounded.as_deref(), outlines))?;
        for (i, px) in rgb.chunks_exact(3).enumerate() {
            indices[i] = palette.index(px[0], px[1], px[2]);
        }
        let mut frame = gif_frame(&indices, prev.as_deref(), w as usize, h as usize);
        frame.delay = if k + 1 == frames.len() {
            delay.max(150)
        } else {
            delay
        };
        encoder.write_frame(&frame).map_err(gif_err)?;
        if encoder.get_ref().bytes > MAX_BYTES {
            return Err(format!(
                "the animation would be larger than {} MiB",
                MAX_BYTES >> 20
            ));
        }
        match &mut prev {
            Some(p) => p.copy_from_slice(&indices),
            None => prev = Some(indices.clone()),
        }
    }
    let mut out = encoder.into_inner().map_err(gif_err)?;
    out.flush()
        .map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    Ok(AnimationReport {
        path: tmp.to_path_buf(),
        frames: frames.len(),
        frames_available: index.count,
        bytes: out.bytes,
    })
}

/// The GIF frame of `indices` (`w × h` palette indices): all of it for the first frame;
/// after `prev`, the rectangle of changed pixels, unchanged ones transparent (a single
/// transparent pixel if none changed).
fn gif_frame(indices: &[u8], prev: Option<&[u8]>, w: usize, h: usize) -> gif::Frame<'static> {
    let Some(prev) = prev else {
        return gif::Frame {
            width: w as u16,
            height: h as u16,
            buffer: Cow::Owned(indices.to_vec()),
            ..gif::Frame::default()
        };
    };
    let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
    for y in 0..h {
        let row = y * w..(y + 1) * w;
        let (a, b) = (&indices[row.clone()], &prev[row]);
        if let Some(first) = a.iter().zip(b).position(|(p, q)| p != q) {
            let last = w - 1 - a.iter().zip(b).rev().position(|(p, q)| p != q).unwrap_or(0);
            x0 = x0.min(first);
            x1 = x1.max(last + 1);
            y0 = y0.min(y);
            y1 = y + 1;
        }
    }
    if x0 >= x1 {
        (x0, x1, y0, y1) = (0, 1, 0, 1);
    }
    let mut buffer = Vec::with_capacity((x1 - x0) * (y1 - y0));
    for y in y0..y1 {
        for x in x0..x1 {
            let i = y * w + x;
            buffer.push(if indices[i] == prev[i] {
                TRANSPARENT
            } else {
                indices[i]
            });
        }
    }
    gif::Frame {
        left: x0 as u16,
        top: y0 as u16,
        width: (x1 - x0) as u16,
        height: (y1 - y0) as u16,
        transparent: Some(TRANSPARENT),
        dispose: gif::DisposalMethod::Keep,
        buffer: Cow::Owned(buffer),
        ..gif::Frame::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::GroupDrawing;

    /// Writes `positions.csv` of `frames` frames of a two-string network in dimension `dim`:
    /// nodes 0 (fixed), 1 (the junction) and 2 (fixed) and the interior nodes of string a
    /// (0 → 1) and string b (1 → 2), swinging; a spring from the junction to node 2.
    fn two_strings(dir: &Path, dim: usize, frames: usize, per: usize) -> Topology {
        let n_nodes = 3 + 2 * (per - 1);
        let mut text = format!("t,node,{}\n", ["x", "y", "z"][..dim].join(","));
        for k in 0..frames {
            let t = 0.01 * k as f64;
            let junction = [1.0 + 0.3 * (5.0 * t).sin(), -1.0 + 0.2 * (3.0 * t).cos()];
            let mut r = vec![[0.0, 0.0], junction, [2.0, 0.0]];
            for (from, to) in [(r[0], junction), (junction, r[2])] {
                for i in 1..per {
                    let s = i as f64 / per as f64;
                    let sag = 0.1 * (std::f64::consts::PI * s).sin() * (1.0 + t);
                    r.push([
                        from[0] + s * (to[0] - from[0]),
                        from[1] + s * (to[1] - from[1]) - sag,
                    ]);
                }
            }
            assert_eq!(r.len(), n_nodes);
            for (i, p) in r.iter().enumerate() {
                text += &format!("{t},{i},{},{}", p[0], p[1]);
                if dim == 3 {
                    text += ",0.5";
                }
                text += "\n";
            }
        }
        std::fs::write(dir.join("positions.csv"), text).unwrap();
        let path = |from: usize, to: usize, first: usize| {
            let mut nodes = vec![from];
            nodes.extend(first..first + per - 1);
            nodes.push(to);
            nodes.windows(2).map(|w| [w[0], w[1]]).collect::<Vec<_>>()
        };
        let mut elements = path(0, 1, 3);
        elements.extend(path(1, 2, 3 + per - 1));
        elements.push([1, 2]);
        Topology {
            groups: vec![
                GroupDrawing {
                    name: "a".into(),
                    elements: 0..per,
                    spring: false,
                },
                GroupDrawing {
                    name: "b".into(),
                    elements: per..2 * per,
                    spring: false,
                },
                GroupDrawing {
                    name: "spring".into(),
                    elements: 2 * per..2 * per + 1,
                    spring: true,
                },
            ],
            elements,
            masses: vec![(1, 5.0)],
        }
    }

    /// Decodes a GIF: (width, height, frames, the first frame's delay).
    fn decode(path: &Path) -> (u16, u16, usize, u16) {
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::Indexed);
        let mut d = opts.read_info(File::open(path).unwrap()).unwrap();
        let (w, h) = (d.width(), d.height());
        let mut frames = 0;
        let mut delay = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            if frames == 0 {
                delay = f.delay;
            }
            frames += 1;
        }
        (w, h, frames, delay)
    }

    #[test]
    fn two_string_network_animates() {
        let dir = crate::test_util::temp_dir("animation", "two");
        let topo = two_strings(&dir, 2, 30, 8);
        let r = write_animation(&dir, 2, "two strings", &topo, &Scene::default(), None).unwrap();
        assert_eq!(r.path, dir.join(ANIMATION_FILE));
        assert_eq!((r.frames, r.frames_available), (30, 30));
        let bytes = std::fs::read(&r.path).unwrap();
        assert_eq!(&bytes[..6], b"GIF89a");
        assert_eq!(bytes.len() as u64, r.bytes);
        assert!(r.bytes > 2_000 && r.bytes < 1 << 20, "{} bytes", r.bytes);
        let (w, h, frames, delay) = decode(&r.path);
        assert_eq!(
            (u32::from(w), u32::from(h)),
            (ANIMATION_WIDTH, ANIMATION_HEIGHT)
        );
        assert_eq!(frames, 30);
        assert_eq!(delay, 27, "8 s over 30 frames");
        assert!(!dir.join(".animation.gif.tmp").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Pixels with palette index `index` in the last frame of the GIF at `path` (each
    /// frame is stored as the rectangle that changed; the last one is the largest count
    /// over them when the marked nodes only sink in).
    fn marked_pixels(path: &Path, index: u8) -> usize {
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::Indexed);
        let mut d = opts.read_info(File::open(path).unwrap()).unwrap();
        let mut most = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            most = most.max(f.buffer.iter().filter(|&&i| i == index).count());
        }
        most
    }

    #[test]
    fn frames_mark_the_nodes_on_the_seabed() {
        // The wet line of 20 elements of 5 m laid on a seabed 50 m down: its grounded nodes
        // (the run's contact test on the positions read back) are crimson triangles.
        let dir = crate::test_util::temp_dir("animation", "grounded");
        let mut sim = crate::test_util::wet_line();
        let mut w = crate::output::Writers::start(&dir, &sim, 1, true, false, vec![]).unwrap();
        for _ in 0..3 {
            let r = sim.step().unwrap();
            w.step(&sim, &r).unwrap();
        }
        w.finish(&sim).unwrap();
        let grounded = sim
            .system()
            .seabed_contacts(&sim.state().r)
            .iter()
            .filter(|c| c.grounded)
            .count();
        assert!(grounded >= 5, "{grounded}");
        let topo = Topology::chain(21);
        let mut scene = Scene::default();
        scene.water = Some(crate::scene::WaterLines::new(
            &scene,
            Some((&[0.0, -50.0], &[0.0, 1.0])),
        ));
        let plain = write_animation(&dir, 2, "wet", &topo, &scene, None).unwrap();
        // The palette: mass, the string, the three water colours, then the marker.
        let marker = (EXACT + 5) as u8;
        assert_eq!(marked_pixels(&plain.path, marker), 0);
        scene.contact = crate::scene::ContactTest::of(sim.system());
        let marked = write_animation(&dir, 2, "wet", &topo, &scene, None).unwrap();
        let pixels = marked_pixels(&marked.path, marker);
        eprintln!("{grounded} nodes on the seabed, {pixels} marker pixels in a frame");
        // Each triangle of side ~7 px covers about 20 pixels; neighbours 5 m apart overlap.
        assert!(
            pixels >= 20 * 2,
            "{pixels} marker pixels for {grounded} nodes"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn long_runs_are_thinned_to_at_most_max_frames_in_3d() {
        let dir = crate::test_util::temp_dir("animation", "long");
        // More frames than the index keeps: thinned twice, the last frame kept.
        let topo = two_strings(&dir, 3, 2 * INDEX_LIMIT + 37, 2);
        let r = write_animation(&dir, 3, "", &topo, &Scene::default(), None).unwrap();
        assert_eq!(r.frames, MAX_FRAMES);
        assert_eq!(r.frames_available, 2 * INDEX_LIMIT + 37);
        let (_, _, frames, _) = decode(&r.path);
        assert_eq!(frames, MAX_FRAMES);
        let mut reader = BufReader::new(File::open(dir.join("positions.csv")).unwrap());
        let index = index_frames(&mut reader, 3, None).unwrap();
        let picked = index.pick(MAX_FRAMES);
        assert_eq!(picked[0].1, 0.0);
        assert_eq!(
            picked.last().unwrap().1,
            0.01 * (2 * INDEX_LIMIT + 36) as f64
        );
        assert!(picked.windows(2).all(|w| w[0].1 < w[1].1));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn degenerate_data_is_skipped_with_a_reason() {
        let dir = crate::test_util::temp_dir("animation", "degenerate");
        let topo = Topology::chain(2);
        let skip = |dim: usize, topo: &Topology| {
            let e = write_animation(&dir, dim, "", topo, &Scene::default(), None).unwrap_err();
            assert!(!dir.join(ANIMATION_FILE).exists(), "{e}");
            assert!(!dir.join(".animation.gif.tmp").exists(), "{e}");
            e
        };
        assert!(skip(1, &topo).contains("2D or 3D"));
        assert!(skip(2, &topo).contains("not written"));
        std::fs::write(dir.join("positions.csv"), "t,node,x,y\n").unwrap();
        assert!(skip(2, &topo).contains("no frame"));
        assert!(skip(3, &topo).contains("header"));
        std::fs::write(
            dir.join("positions.csv"),
            "t,node,x,y\n0,0,1e308,0\n0,1,1e308,1\n",
        )
        .unwrap();
        assert!(skip(2, &topo).contains("x values"), "extreme coordinates");
        std::fs::write(dir.join("positions.csv"), "t,node,x,y\n0,0,0,0\n0,2,1,1\n").unwrap();
        assert!(skip(2, &topo).contains("out of order"));
        std::fs::write(dir.join("positions.csv"), "t,node,x,y\n0,0,0,0\n0,1,1,1\n").unwrap();
        assert!(skip(2, &Topology::chain(3)).contains("does not fit"));
        let stop = AtomicBool::new(true);
        let e = write_animation(&dir, 2, "", &topo, &Scene::default(), Some(&stop)).unwrap_err();
        assert!(e.contains("stop requested"), "{e}");
        // A frame cut short at the end (a killed run) is left out.
        std::fs::write(
            dir.join("positions.csv"),
            "t,node,x,y\n0,0,0,0\n0,1,1,1\n0.5,0,0,0\n",
        )
        .unwrap();
        let r = write_animation(&dir, 2, "", &topo, &Scene::default(), None).unwrap();
        assert_eq!((r.frames, r.frames_available), (1, 1));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn palette_keeps_group_colours_exact() {
        let colors = [RGBColor(0, 114, 178), RGBColor(213, 94, 0)];
        let p = Palette::new(&colors);
        let rgb = p.rgb();
        assert_eq!(rgb.len(), 768);
        for c in colors {
            let i = usize::from(p.index(c.0, c.1, c.2));
            assert_eq!(&rgb[3 * i..3 * i + 3], &[c.0, c.1, c.2]);
        }
        let white = usize::from(p.index(255, 255, 255));
        assert_eq!(&rgb[3 * white..3 * white + 3], &[255, 255, 255]);
        assert_ne!(white, usize::from(TRANSPARENT));
        let grey = usize::from(p.index(128, 128, 128));
        assert!((i32::from(rgb[3 * grey]) - 128).abs() <= 5);
        let other = usize::from(p.index(40, 200, 90));
        assert!(other < EXACT);
    }
}
