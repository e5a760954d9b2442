//! Output writers of a run: `energy.csv`, `positions.csv`, `ports.csv`, ParaView frames,
//! plots and `summary.json`, and once at the start the network's layout, `elements.csv`
//! (and `point_masses.csv` if it has point masses), from which `positions.csv` can be drawn.
//! Rows are written as the run goes, so everything up to the last good step is on disk when
//! a run fails: the `t = 0` rows are flushed at once, and the files at least every
//! [`FLUSH_EVERY`] of wall time.
//!
//! No NaN or infinity is ever written: a row with a non-finite value is refused with
//! [`OutputError::NonFinite`]. Memory does not grow with the number of steps: the plots
//! read what they need back from `energy.csv` ([`read_history`]), decimated to at most
//! [`PLOT_POINTS`] points per curve.

use crate::outdir::{PARAVIEW_DIR, PVD_FILE, frame_name};
use std::fs::File;
use std::hash::Hasher;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use phstring::{Law, Material, PortKind, Simulation, StepReport};

use crate::csvfile::{Csv, PendingCsv};
use crate::plot::{self, GroupDrawing, PlotError, Series, Topology};
use crate::vtk::{self, FrameData, PvdWriter, VtkError};

/// Longest wall time between two flushes of the output files during a run.
pub const FLUSH_EVERY: Duration = Duration::from_millis(500);

/// Most points per curve in the plots of a run: longer series are decimated keeping, per
/// bucket of consecutive rows, the rows with the smallest and largest value of each curve
/// (so that spikes survive).
pub const PLOT_POINTS: usize = 20_000;

/// Configuration snapshots taken for the configuration plot (at `t = k T / 5`).
pub const SNAPSHOTS: usize = 6;

/// Names of the temporary files phstring writes next to a file it replaces atomically
/// (left behind only by a kill; removed or replaced by the next write, and not counted as
/// user files when an output folder is checked for being empty).
pub const TEMP_FILES: [&str; 8] = [
    ".checkpoint.json.tmp",
    ".summary.json.tmp",
    ".components.json.tmp",
    ".scenario.json.tmp",
    ".string.pvd.tmp",
    "checkpoint.json.tmp",
    "string.pvd.tmp",
    ".animation.gif.tmp",
];

/// The elements of the mesh, written once at the start of a run (see [`elements_header`]).
pub const ELEMENTS_FILE: &str = "elements.csv";
/// The point masses of the network, `node,mass`, written once at the start of a run that
/// has point masses.
pub const POINT_MASSES_FILE: &str = "point_masses.csv";

/// Whether `name` is one of phstring's own temporary files ([`TEMP_FILES`]).
pub fn is_own_temp_file(name: &str) -> bool {
    TEMP_FILES.contains(&name)
}

/// The temporary sibling `.<name>.tmp` used to replace `path` atomically.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.tmp"))
}

/// Writes `bytes` to `path` atomically: to [`temp_path`] in the same folder, then renamed
/// over `path`, so that readers (and a kill) see either the old or the new file. A stale
/// temporary file is replaced; on failure the temporary file is removed.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let res = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res
}

/// Writes `bytes` over the regular file at `path` in place, padded with spaces (and a final
/// line break) to the file's length, if the file is at least one byte longer than `bytes`
/// (JSON allows trailing white space). On a full disk, where [`atomic_write`] finds no room
/// for its temporary file, the file's own space takes the new text. A write that fails
/// midway removes the file rather than leave it half old, half new.
pub fn overwrite_in_place(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let meta = std::fs::symlink_metadata(path)?;
    let len = usize::try_from(meta.len()).unwrap_or(usize::MAX);
    if !meta.is_file() || len <= bytes.len() {
        return Err(std::io::Error::other(format!(
            "no room in place: the file has {len} bytes, {} are needed",
            bytes.len() + 1
        )));
    }
    let mut padded = Vec::with_capacity(len);
    padded.extend_from_slice(bytes);
    padded.resize(len - 1, b' ');
    padded.push(b'\n');
    let res = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .and_then(|mut f| f.write_all(&padded));
    if res.is_err() {
        let _ = std::fs::remove_file(path);
    }
    res
}

/// Removes phstring's stale temporary files ([`TEMP_FILES`]) from `dir` and
/// `dir/paraview` (regular files only).
pub fn remove_stale_temp_files(dir: &Path) {
    for d in [dir.to_path_buf(), dir.join(PARAVIEW_DIR)] {
        for name in TEMP_FILES {
            let p = d.join(name);
            if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
                let _ = std::fs::remove_file(&p);
            }
        }
    }
}

/// The header lines of `energy.csv`, `positions.csv` and `ports.csv` in dimension `d`.
pub fn headers(d: usize) -> (String, String, String) {
    let comps = ["x", "y", "z"];
    let d = d.clamp(1, 3);
    let energy = "t,kinetic,potential,hamiltonian,supplied_energy,balance_error,newton_iterations,newton_residual,h,dissipated_energy".to_string();
    let positions = format!("t,node,{}", comps[..d].join(","));
    let u: Vec<String> = comps[..d].iter().map(|c| format!("u_{c}")).collect();
    let y: Vec<String> = comps[..d].iter().map(|c| format!("y_{c}")).collect();
    let ports = format!("t_mid,port,node,kind,{},{},power", u.join(","), y.join(","));
    (energy, positions, ports)
}

/// The header line of [`ELEMENTS_FILE`]: one row per element `e = [node_a, node_b]` of the
/// mesh (node indices as in `positions.csv`), its group index (the ParaView cell array
/// `string`), the group's kind (`string` or `spring`), its reference length `l_e` [m]
/// (springs: 1, their rest length is a parameter of their law) and the group's name.
pub fn elements_header() -> &'static str {
    "element,node_a,node_b,group,kind,reference_length,group_name"
}

/// The drawing of the network of `sim`: its elements, groups and point masses.
pub fn topology<const D: usize>(sim: &Simulation<D, Material>) -> Topology {
    system_topology(sim.system())
}

/// The drawing of the network of `sys`: its elements, groups and point masses.
pub fn system_topology<const D: usize>(sys: &phstring::PhSystem<D, Material>) -> Topology {
    Topology {
        elements: sys.mesh().elements().to_vec(),
        groups: sys
            .groups()
            .iter()
            .map(|g| GroupDrawing {
                name: g.name.clone(),
                elements: g.elements.clone(),
                spring: matches!(g.law, Law::Spring(_)),
            })
            .collect(),
        masses: sys.point_masses().to_vec(),
    }
}

/// A text field for a CSV row: control characters dropped, quoted (`"` doubled) if it holds
/// a comma or a quote or starts or ends with a space.
fn csv_text(text: &str) -> String {
    let t: String = text.chars().filter(|c| !c.is_control()).collect();
    if t.contains([',', '"']) || t.starts_with(' ') || t.ends_with(' ') {
        format!("\"{}\"", t.replace('"', "\"\""))
    } else {
        t
    }
}

/// Inverse of [`csv_text`] for a field that ends its row.
fn csv_untext(field: &str) -> String {
    match field.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
        Some(inner) => inner.replace("\"\"", "\""),
        None => field.to_string(),
    }
}

/// Writes [`ELEMENTS_FILE`] and, if the network has point masses, [`POINT_MASSES_FILE`] into
/// `dir` (replacing earlier ones; a run without point masses removes a stale
/// [`POINT_MASSES_FILE`]).
fn write_topology<const D: usize>(
    dir: &Path,
    sim: &Simulation<D, Material>,
) -> Result<(), OutputError> {
    let sys = sim.system();
    let mut csv = Csv::create(dir.join(ELEMENTS_FILE), elements_header())?;
    check_finite(&csv.path, "reference length", 0.0, sys.mesh().lengths())?;
    for (g, group) in sys.groups().iter().enumerate() {
        let kind = match group.law {
            Law::Spring(_) => "spring",
            Law::String(_) => "string",
        };
        let name = csv_text(&group.name);
        for e in group.elements.clone() {
            let [a, b] = sys.mesh().elements()[e];
            let l = sys.mesh().lengths()[e];
            csv.row(&format!("{e},{a},{b},{g},{kind},{},{name}", num(l)))?;
        }
    }
    csv.flush()?;
    let path = dir.join(POINT_MASSES_FILE);
    if sys.point_masses().is_empty() {
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(&path);
        }
        return Ok(());
    }
    let mut csv = Csv::create(path, "node,mass")?;
    for &(node, m) in sys.point_masses() {
        check_finite(&csv.path, "point mass", 0.0, &[m])?;
        csv.row(&format!("{node},{}", num(m)))?;
    }
    csv.flush()
}

/// Reads the network's drawing back from [`ELEMENTS_FILE`] and [`POINT_MASSES_FILE`] in
/// `dir`; `None` if there is no [`ELEMENTS_FILE`] (a folder written before it existed).
/// Rows must list the elements in order, each group's elements consecutively.
pub fn read_topology(dir: &Path) -> Result<Option<Topology>, OutputError> {
    let path = dir.join(ELEMENTS_FILE);
    let f = match File::open(&path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(cause) => return Err(OutputError::Io { path, cause }),
    };
    let mut t = Topology::default();
    for_each_row(&path, f, |line, row| {
        let fields: Vec<&str> = row.splitn(7, ',').collect();
        let bad = |message: String| OutputError::Read {
            path: path.clone(),
            line,
            message,
        };
        if fields.len() != 7 {
            return Err(bad(format!("{} fields, expected 7", fields.len())));
        }
        let int = |k: usize| {
            fields[k].parse::<usize>().map_err(|_| {
                bad(format!(
                    "not an index: {}",
                    plot::sanitize_text(fields[k], 40)
                ))
            })
        };
        let (e, a, b, g) = (int(0)?, int(1)?, int(2)?, int(3)?);
        if e != t.elements.len() {
            return Err(bad(format!(
                "element {e} where {} was expected",
                t.elements.len()
            )));
        }
        let spring = match fields[4] {
            "spring" => true,
            "string" => false,
            other => {
                return Err(bad(format!(
                    "kind {} is neither string nor spring",
                    plot::sanitize_text(other, 40)
                )));
            }
        };
        t.elements.push([a, b]);
        match t.groups.len() {
            n if g + 1 == n && t.groups[g].elements.end == e => t.groups[g].elements.end = e + 1,
            n if g == n => t.groups.push(GroupDrawing {
                name: csv_untext(fields[6]),
                elements: e..e + 1,
                spring,
            }),
            _ => return Err(bad(format!("group {g} out of order"))),
        }
        Ok(())
    })?;
    let path = dir.join(POINT_MASSES_FILE);
    match File::open(&path) {
        Ok(f) => for_each_row(&path, f, |line, row| {
            let bad = |message: String| OutputError::Read {
                path: path.clone(),
                line,
                message,
            };
            let (node, m) = row
                .split_once(',')
                .ok_or_else(|| bad("2 fields expected".into()))?;
            let node = node.parse().map_err(|_| bad("not a node index".into()))?;
            let m: f64 = m.parse().map_err(|_| bad("not a mass".into()))?;
            t.masses.push((node, m));
            Ok(())
        })?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(cause) => return Err(OutputError::Io { path, cause }),
    }
    Ok(Some(t))
}

/// Calls `row(line number, text)` for every row of the CSV file `f` after its header.
fn for_each_row(
    path: &Path,
    f: File,
    mut row: impl FnMut(usize, &str) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let mut reader = std::io::BufReader::new(f);
    let mut line = String::new();
    let mut number = 0;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|source| OutputError::Io {
                path: path.to_path_buf(),
                cause: source,
            })?;
        if n == 0 {
            return Ok(());
        }
        number += 1;
        if number > 1 {
            row(number, line.trim_end_matches(['\n', '\r']))?;
        }
    }
}

/// FNV-1a hash of a list of ParaView frames, extended by one frame `(t, name)`; start from
/// [`frames_hash_start`].
pub fn frames_hash_add(hash: u64, t: f64, name: &str) -> u64 {
    let mut h = fnv::FnvHasher::with_key(hash);
    h.write(&t.to_bits().to_le_bytes());
    h.write(name.as_bytes());
    h.finish()
}

/// FNV-1a hash of an empty list of frames.
pub fn frames_hash_start() -> u64 {
    fnv::FnvHasher::default().finish()
}

/// Errors while writing outputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// A file could not be written.
    #[error("cannot write {}: {cause}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: std::io::Error,
    },
    /// A plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A ParaView file failed.
    #[error(transparent)]
    Vtk(#[from] VtkError),
    /// A value to be written is NaN or infinite: the row is refused (nothing of it written).
    #[error("refusing to write a non-finite {what} ({value}) at t = {} s to {}: the simulation produced NaN or infinity", phstring::Num(*t), path.display())]
    NonFinite {
        /// File.
        path: PathBuf,
        /// The quantity.
        what: String,
        /// Time of the row [s].
        t: f64,
        /// The value.
        value: f64,
    },
    /// An output file does not match the checkpoint a run resumes from.
    #[error("cannot resume into {}: {reason}", path.display())]
    Mismatch {
        /// File.
        path: PathBuf,
        /// What does not match.
        reason: String,
    },
    /// An output file could not be read back (for the plots).
    #[error("cannot read {} line {line}: {message}", path.display())]
    Read {
        /// File.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// Refuses non-finite `values` (named `what`, for the row at time `t`) before they reach
/// `path`.
fn check_finite(path: &Path, what: &str, t: f64, values: &[f64]) -> Result<(), OutputError> {
    match values.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(OutputError::NonFinite {
            path: path.to_path_buf(),
            what: what.to_string(),
            t,
            value,
        }),
        None => Ok(()),
    }
}

/// `path` relative to `dir` (for reports), or as it is if it is not in `dir`.
fn relative(dir: &Path, path: &Path) -> String {
    path.strip_prefix(dir).unwrap_or(path).display().to_string()
}

/// What a run will write, for [`estimated_output`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputPlan {
    /// Spatial dimension (1, 2 or 3).
    pub dimension: usize,
    /// Mesh nodes.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// Ports (rows of `ports.csv` per step).
    pub ports: usize,
    /// Steps.
    pub steps: f64,
    /// `output.stride`.
    pub stride: usize,
    /// `output.positions`.
    pub positions: bool,
    /// `output.vtk`.
    pub vtk: bool,
}

/// The size of a run's outputs, estimated before it runs ([`estimated_output`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputEstimate {
    /// All files [bytes].
    pub bytes: f64,
    /// Number of files.
    pub files: f64,
    /// `energy.csv` and `ports.csv` [bytes].
    pub rows: f64,
    /// `positions.csv` [bytes].
    pub positions: f64,
    /// ParaView frames written.
    pub frames: f64,
    /// `paraview/` [bytes].
    pub paraview: f64,
}

/// Bytes of one number as [`num`] writes it, with its comma (`-3.4565972519949129e0,`).
const NUM_BYTES: f64 = 22.0;
/// Bytes of a row of `energy.csv`: 8 numbers, the iteration count and the dissipated
/// energy (`0` without damping): 182 in the paper's pendulum, 201 at most.
const ENERGY_ROW_BYTES: f64 = 190.0;
/// Bytes of a port value in `ports.csv` on average: a number, or `0` for the velocity and
/// power of a fixed support (a force port's row has 142 bytes in 2D, a fixed support's 85).
const PORT_VALUE_BYTES: f64 = 16.0;
/// Bytes of a ParaView frame besides its arrays (XML header, array tags, the base64
/// headers).
const FRAME_BYTES: f64 = 1500.0;
/// Bytes of a ParaView frame per node: points and velocity (2 × 3 Float64), base64.
const FRAME_BYTES_PER_NODE: f64 = 48.0 * 4.0 / 3.0;
/// Bytes of a ParaView frame per element: connectivity and offsets (3 UInt64), `C`, `S`,
/// `tension` (3 Float64) and `string` (Int32), base64.
const FRAME_BYTES_PER_ELEMENT: f64 = 52.0 * 4.0 / 3.0;
/// Files of a run besides `positions.csv` and the frames: `energy.csv`, `ports.csv`,
/// `elements.csv`, `summary.json`, the run id, `string.pvd`, six plots, `animation.gif`
/// (not the lock file).
const FIXED_FILES: f64 = 13.0;

/// The size and number of files a run writes, from the layout of the writers: a row of
/// `energy.csv` per step ([`ENERGY_ROW_BYTES`]), a row per port and step in `ports.csv`
/// (`t`, `2d` port values, the power, index, node and kind), a row per node
/// and frame in `positions.csv` (`t`, the node, `d` coordinates), a ParaView frame per
/// frame ([`FRAME_BYTES`] plus the base64 arrays) and its line in `string.pvd`, at steps
/// 0, stride, 2·stride, … and the last; plots, `animation.gif`, `elements.csv` and
/// `summary.json` are bounded and not counted in the bytes. Within 10 % of what the examples
/// write (see the test below).
pub fn estimated_output(p: &OutputPlan) -> OutputEstimate {
    let d = p.dimension as f64;
    let steps = p.steps.max(0.0);
    let stride = p.stride.max(1) as f64;
    let on_stride = (steps / stride).floor();
    // Step 0, every stride-th step, and the last if it is not on the stride.
    let frames = on_stride + 1.0 + if on_stride * stride < steps { 1.0 } else { 0.0 };
    let digits = |n: f64| n.max(1.0).log10().floor() + 2.0;
    let nodes = p.nodes as f64;
    let rows = (steps + 1.0) * ENERGY_ROW_BYTES
        + steps * p.ports as f64 * ((2.0 + 2.0 * d) * PORT_VALUE_BYTES + digits(nodes) + 10.0);
    let positions = if p.positions {
        // The first frame's time is written `0`.
        nodes * (frames * ((1.0 + d) * NUM_BYTES + digits(nodes)) - (NUM_BYTES - 2.0))
    } else {
        0.0
    };
    let paraview = if p.vtk {
        frames
            * (FRAME_BYTES
                + 70.0
                + FRAME_BYTES_PER_NODE * nodes
                + FRAME_BYTES_PER_ELEMENT * p.elements as f64)
    } else {
        0.0
    };
    OutputEstimate {
        bytes: rows + positions + paraview,
        files: FIXED_FILES + if p.positions { 1.0 } else { 0.0 } + if p.vtk { frames } else { 0.0 },
        rows,
        positions,
        frames: if p.vtk { frames } else { 0.0 },
        paraview,
    }
}

/// Formats `x` with 17 significant digits (round-trip exact).
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x:.16e}")
    }
}

/// The series the plots draw, read back from `energy.csv` ([`read_history`]): every row of
/// a short run, a min/max decimation of a long one (at most [`PLOT_POINTS`] points per
/// curve), so that its size does not grow with the number of steps.
#[derive(Debug, Clone, Default)]
pub struct History {
    /// Times [s] of the rows kept (including `t = 0`).
    pub t: Vec<f64>,
    /// Kinetic energy [J] at those rows.
    pub kinetic: Vec<f64>,
    /// Potential energy [J] at those rows.
    pub potential: Vec<f64>,
    /// Hamiltonian [J] at those rows.
    pub hamiltonian: Vec<f64>,
    /// Step end times [s] of the increments kept.
    pub increment_t: Vec<f64>,
    /// `|Ĥ_{n+1} − Ĥ_n|` [J] per step, from all rows (decimated after differencing, so the
    /// largest increment is always kept).
    pub increment: Vec<f64>,
    /// Configuration snapshots `(t, node positions x, y)` for the configuration plot.
    pub snapshots: Vec<(f64, Vec<[f64; 2]>)>,
}

impl History {
    /// `|Ĥ_{n+1} − Ĥ_n|` per step, at the step end times (as kept, see [`Self::increment`]).
    pub fn increments(&self) -> (Vec<f64>, Vec<f64>) {
        (self.increment_t.clone(), self.increment.clone())
    }
}

/// A row of a decimated series: its index and values (column 0 is the abscissa).
type Row<const N: usize> = (usize, [f64; N]);

/// Rows of one bucket with the smallest and largest value of each column `1..N`.
#[derive(Clone, Copy)]
struct Bucket<const N: usize> {
    rows: usize,
    lo: [Row<N>; N],
    hi: [Row<N>; N],
}

impl<const N: usize> Bucket<N> {
    fn new(r: Row<N>) -> Self {
        Self {
            rows: 1,
            lo: [r; N],
            hi: [r; N],
        }
    }
    fn add(&mut self, r: Row<N>) {
        self.rows += 1;
        for j in 1..N {
            if r.1[j] < self.lo[j].1[j] {
                self.lo[j] = r;
            }
            if r.1[j] > self.hi[j].1[j] {
                self.hi[j] = r;
            }
        }
    }
    fn merge(mut self, o: &Self) -> Self {
        self.rows += o.rows;
        for j in 1..N {
            if o.lo[j].1[j] < self.lo[j].1[j] {
                self.lo[j] = o.lo[j];
            }
            if o.hi[j].1[j] > self.hi[j].1[j] {
                self.hi[j] = o.hi[j];
            }
        }
        self
    }
}

/// Streaming min/max decimation of rows `[x, y_1, …, y_{N−1}]` of unknown count: consecutive
/// rows are grouped in buckets (one row each at first, twice as many whenever the bucket
/// count reaches its limit), and per bucket the rows with the smallest and largest `y_j`
/// are kept, plus the first and last row. At most `max_points` rows (+ 2) come out, in
/// order; fewer than about `max_points / (2 (N − 1))` rows come out unchanged.
struct Decimator<const N: usize> {
    max_buckets: usize,
    width: usize,
    buckets: Vec<Bucket<N>>,
    first: Option<Row<N>>,
    last: Option<Row<N>>,
    count: usize,
}

impl<const N: usize> Decimator<N> {
    fn new(max_points: usize) -> Self {
        let per_bucket = 4 * N.saturating_sub(1).max(1);
        Self {
            max_buckets: (max_points / per_bucket).max(1),
            width: 1,
            buckets: Vec::new(),
            first: None,
            last: None,
            count: 0,
        }
    }

    fn push(&mut self, row: [f64; N]) {
        let r = (self.count, row);
        self.count += 1;
        if self.first.is_none() {
            self.first = Some(r);
        }
        self.last = Some(r);
        match self.buckets.last_mut() {
            Some(b) if b.rows < self.width => b.add(r),
            _ => {
                if self.buckets.len() >= 2 * self.max_buckets {
                    // All buckets are full: merge pairs.
                    self.buckets = self
                        .buckets
                        .chunks(2)
                        .map(|p| {
                            if p.len() == 2 {
                                p[0].merge(&p[1])
                            } else {
                                p[0]
                            }
                        })
                        .collect();
                    self.width *= 2;
                }
                self.buckets.push(Bucket::new(r));
            }
        }
    }

    fn finish(self) -> Vec<[f64; N]> {
        let mut rows: Vec<Row<N>> = self.first.into_iter().chain(self.last).collect();
        for b in &self.buckets {
            for j in 1..N {
                rows.push(b.lo[j]);
                rows.push(b.hi[j]);
            }
        }
        rows.sort_by_key(|r| r.0);
        rows.dedup_by_key(|r| r.0);
        rows.into_iter().map(|r| r.1).collect()
    }
}

/// Reads the energies of a run back from its `energy.csv` for the plots, streaming, with at
/// most `max_points` points per curve (min/max decimation, see [`History`]); `snapshots` are
/// passed through. Returns `None` if `stop` is set meanwhile.
pub fn read_history(
    path: &Path,
    max_points: usize,
    snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    stop: Option<&AtomicBool>,
) -> Result<Option<History>, OutputError> {
    let f = File::open(path).map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        cause: source,
    })?;
    let mut reader = std::io::BufReader::new(f);
    let mut energies = Decimator::<4>::new(max_points);
    let mut increments = Decimator::<2>::new(max_points);
    let mut line = String::new();
    let mut prev_h: Option<f64> = None;
    let mut number = 0;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|source| OutputError::Io {
                path: path.to_path_buf(),
                cause: source,
            })?;
        if n == 0 {
            break;
        }
        number += 1;
        if number == 1 {
            continue; // header
        }
        if number % 4096 == 0 && stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Ok(None);
        }
        let bad = |message: String| OutputError::Read {
            path: path.to_path_buf(),
            line: number,
            message,
        };
        let mut v = [0.0; 4];
        let mut fields = line.trim_end().split(',');
        for (k, x) in v.iter_mut().enumerate() {
            let field = fields
                .next()
                .ok_or_else(|| bad(format!("{} fields, expected 10", k)))?;
            *x = field
                .parse()
                .map_err(|_| bad(format!("not a number: {}", plot::sanitize_text(field, 40))))?;
        }
        energies.push(v);
        if let Some(p) = prev_h {
            increments.push([v[0], (v[3] - p).abs()]);
        }
        prev_h = Some(v[3]);
    }
    let mut h = History {
        snapshots,
        ..History::default()
    };
    for [t, k, p, e] in energies.finish() {
        h.t.push(t);
        h.kinetic.push(k);
        h.potential.push(p);
        h.hamiltonian.push(e);
    }
    for [t, d] in increments.finish() {
        h.increment_t.push(t);
        h.increment.push(d);
    }
    Ok(Some(h))
}

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

/// Writes the standard outputs of one run into a folder. Memory does not grow with the
/// number of steps (the configuration snapshots are bounded; the ParaView collection lists
/// one entry per frame file written).
pub struct Writers {
    dir: PathBuf,
    energy: Csv,
    positions: Option<Csv>,
    ports: Csv,
    pvd: Option<PvdWriter>,
    /// The collection file must be written again before it is whole (a resume continues
    /// it after the checkpoint's frames); frames are listed as they are written.
    pvd_dirty: bool,
    stride: usize,
    snapshot_times: Vec<f64>,
    snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    last_frame: Option<usize>,
    frames: usize,
    frames_hash: u64,
    last_flush: Instant,
    flush_every: Duration,
    /// A ParaView frame or the collection could not be written (the collection lists the
    /// frames written before).
    paraview_failed: bool,
}

impl Writers {
    /// Creates the folder's files and writes (and flushes) the `t = 0` rows. Stale temporary
    /// files of an earlier, killed run are removed.
    pub fn start<const D: usize>(
        dir: &Path,
        sim: &Simulation<D, Material>,
        stride: usize,
        positions: bool,
        vtk_frames: bool,
        snapshot_times: Vec<f64>,
    ) -> Result<Self, OutputError> {
        let io = |path: &Path| {
            let p = path.to_path_buf();
            move |source| OutputError::Io {
                path: p,
                cause: source,
            }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        remove_stale_temp_files(dir);
        let (energy_header, positions_header, ports_header) = headers(D);
        let energy = Csv::create(dir.join("energy.csv"), &energy_header)?;
        let positions = if positions {
            Some(Csv::create(dir.join("positions.csv"), &positions_header)?)
        } else {
            None
        };
        let ports = Csv::create(dir.join("ports.csv"), &ports_header)?;
        write_topology(dir, sim)?;
        let pvd = if vtk_frames {
            let pdir = dir.join(PARAVIEW_DIR);
            std::fs::create_dir_all(&pdir).map_err(io(&pdir))?;
            Some(PvdWriter::new(&pdir.join(PVD_FILE)))
        } else {
            None
        };
        let mut w = Self {
            dir: dir.to_path_buf(),
            energy,
            positions,
            ports,
            pvd,
            pvd_dirty: false,
            stride,
            snapshot_times,
            snapshots: Vec::new(),
            last_frame: None,
            frames: 0,
            frames_hash: frames_hash_start(),
            last_flush: Instant::now(),
            flush_every: FLUSH_EVERY,
            paraview_failed: false,
        };
        let e = sim.energies();
        let values = [e.kinetic, e.potential(), e.hamiltonian()];
        check_finite(&w.energy.path, "initial energy", 0.0, &values)?;
        w.energy.row(&format!(
            "{},{},{},{},0,0,0,0,0,0",
            num(0.0),
            num(values[0]),
            num(values[1]),
            num(values[2])
        ))?;
        w.record(sim);
        w.frame(sim)?;
        // The t = 0 rows are on disk at once, whatever happens next.
        w.flush()?;
        Ok(w)
    }

    /// Flushes at most every `every` of wall time during a run (default [`FLUSH_EVERY`];
    /// `Duration::ZERO` flushes after every step).
    pub fn set_flush_interval(&mut self, every: Duration) {
        self.flush_every = every;
    }

    fn record<const D: usize>(&mut self, sim: &Simulation<D, Material>) {
        let t = sim.time();
        // Each snapshot time once, at the first step that reaches it.
        let next = self.snapshots.len();
        if D >= 2
            && self
                .snapshot_times
                .get(next)
                .is_some_and(|&s| t >= s - 1e-9 * sim.params().h)
        {
            let pts = sim.state().r.iter().map(|r| [r[0], r[1]]).collect();
            self.snapshots.push((t, pts));
        }
    }

    /// Writes positions and a ParaView frame every `stride` steps.
    fn frame<const D: usize>(&mut self, sim: &Simulation<D, Material>) -> Result<(), OutputError> {
        self.frame_if(sim, false)
    }

    /// Writes positions and a ParaView frame on the stride, or for the last step (`last`),
    /// once per step.
    fn frame_if<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        last: bool,
    ) -> Result<(), OutputError> {
        let wanted = last || sim.steps().is_multiple_of(self.stride);
        if !wanted || self.last_frame == Some(sim.steps()) {
            return Ok(());
        }
        let t = sim.time();
        let st = sim.state();
        if let Some(p) = &self.positions {
            for r in &st.r {
                check_finite(&p.path, "position", t, r.as_slice())?;
            }
        }
        self.last_frame = Some(sim.steps());
        if let Some(p) = &mut self.positions {
            for (i, r) in st.r.iter().enumerate() {
                let comps: Vec<String> = r.iter().map(|x| num(*x)).collect();
                p.line(&format!("{},{i},{}", num(t), comps.join(",")))?;
            }
            p.end_record()?;
        }
        if let Some(pvd) = &mut self.pvd {
            let pad = |v: &phstring::Vector<D>| {
                let mut a = [0.0; 3];
                a[..D].copy_from_slice(v.as_slice());
                a
            };
            let sys = sim.system();
            let points: Vec<[f64; 3]> = st.r.iter().map(pad).collect();
            let vel: Vec<[f64; 3]> = st.v.iter().map(pad).collect();
            let mut s = vec![0.0; st.c.len()];
            sys.stresses(&st.c, &mut s);
            // Axial force S √C [N]: strings and springs alike (C ≥ 0 up to round-off).
            let tension: Vec<f64> = s
                .iter()
                .zip(&st.c)
                .map(|(s, c)| s * c.max(0.0).sqrt())
                .collect();
            let mut group = vec![0i32; st.c.len()];
            for (g, grp) in sys.groups().iter().enumerate() {
                let g = i32::try_from(g).unwrap_or(i32::MAX);
                group[grp.elements.clone()].fill(g);
            }
            let mass = (!sys.point_masses().is_empty()).then(|| {
                let mut m = vec![0.0; points.len()];
                for &(node, kg) in sys.point_masses() {
                    m[node] += kg;
                }
                m
            });
            let point_data: Vec<(&str, &[f64])> =
                mass.iter().map(|m| ("mass", m.as_slice())).collect();
            let name = frame_name(sim.steps());
            let path = self.dir.join(PARAVIEW_DIR).join(&name);
            vtk::write_vtp_frame(
                &path,
                &FrameData {
                    points: &points,
                    segments: sys.mesh().elements(),
                    velocity: &vel,
                    cell_data: &[("C", &st.c), ("S", &s), ("tension", &tension)],
                    cell_ints: &[("string", &group)],
                    point_data: &point_data,
                },
            )
            .inspect_err(|_| self.paraview_failed = true)?;
            pvd.add(t, &name);
            // The collection lists the frame at once. A frame it cannot list (a full disk)
            // is removed: the collection always lists exactly the frames on disk.
            if let Err(e) = pvd.write() {
                pvd.discard_pending();
                self.paraview_failed = true;
                let _ = std::fs::remove_file(&path);
                return Err(e.into());
            }
            self.pvd_dirty = false;
            self.frames += 1;
            self.frames_hash = frames_hash_add(self.frames_hash, t, &name);
        }
        Ok(())
    }

    /// Records one step: energy row, port rows, and (every `stride` steps) positions and a
    /// ParaView frame. Refuses ([`OutputError::NonFinite`]) a row with NaN or infinity.
    pub fn step<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        r: &StepReport,
    ) -> Result<(), OutputError> {
        let values = [
            r.t,
            r.after.kinetic,
            r.after.potential(),
            r.after.hamiltonian(),
            sim.supplied_energy(),
            r.balance_error,
            r.residual,
            r.h,
            sim.dissipated_energy(),
        ];
        check_finite(&self.energy.path, "energy row value", r.t, &values)?;
        let t_mid = r.t - 0.5 * r.h;
        for p in sim.ports() {
            check_finite(&self.ports.path, "port input", t_mid, p.input.as_slice())?;
            check_finite(&self.ports.path, "port output", t_mid, p.output.as_slice())?;
            check_finite(&self.ports.path, "port power", t_mid, &[p.power()])?;
        }
        self.energy.row(&format!(
            "{},{},{},{},{},{},{},{},{},{}",
            num(values[0]),
            num(values[1]),
            num(values[2]),
            num(values[3]),
            num(values[4]),
            num(values[5]),
            r.newton_iterations,
            num(values[6]),
            num(values[7]),
            num(values[8])
        ))?;
        for (k, p) in sim.ports().iter().enumerate() {
            let kind = match p.kind {
                PortKind::Force => "force",
                PortKind::Velocity => "velocity",
            };
            let u: Vec<String> = p.input.iter().map(|x| num(*x)).collect();
            let y: Vec<String> = p.output.iter().map(|x| num(*x)).collect();
            self.ports.line(&format!(
                "{},{k},{},{kind},{},{},{}",
                num(t_mid),
                p.node,
                u.join(","),
                y.join(","),
                num(p.power())
            ))?;
        }
        self.ports.end_record()?;
        self.record(sim);
        self.frame(sim)?;
        if self.last_flush.elapsed() >= self.flush_every {
            self.flush()?;
        }
        Ok(())
    }

    /// Reopens the outputs of an interrupted run in `dir` at the state a checkpoint recorded
    /// (files longer than recorded are cut back), to continue appending. The ParaView
    /// collection is read back from `paraview/string.pvd` and must list the checkpoint's
    /// frames.
    pub fn resume(
        dir: &Path,
        stride: usize,
        vtk_frames: bool,
        snapshot_times: Vec<f64>,
        state: crate::checkpoint::OutputState,
    ) -> Result<Self, OutputError> {
        remove_stale_temp_files(dir);
        let pvd = if vtk_frames {
            let path = dir.join(PARAVIEW_DIR).join(PVD_FILE);
            let mut hash = frames_hash_start();
            let p = PvdWriter::resume(&path, state.frames, |t, name| {
                hash = frames_hash_add(hash, t, name);
            })
            .map_err(|e| OutputError::Mismatch {
                path: path.clone(),
                reason: format!(
                    "it does not list the checkpoint's {} frames ({e})",
                    state.frames
                ),
            })?;
            if hash != state.frames_hash {
                return Err(OutputError::Mismatch {
                    path,
                    reason: "its frames differ from those the checkpoint recorded".into(),
                });
            }
            Some(p)
        } else {
            None
        };
        // Check every file before any is cut back.
        let energy = PendingCsv::open(dir.join("energy.csv"), state.energy_bytes)?;
        let ports = PendingCsv::open(dir.join("ports.csv"), state.ports_bytes)?;
        let positions = match state.positions_bytes {
            Some(n) => Some(PendingCsv::open(dir.join("positions.csv"), n)?),
            None => None,
        };
        let positions = positions.map(PendingCsv::commit).transpose()?;
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: energy.commit()?,
            positions,
            ports: ports.commit()?,
            pvd,
            pvd_dirty: true,
            stride,
            snapshot_times,
            snapshots: state.snapshots,
            last_frame: state.last_frame,
            frames: state.frames,
            frames_hash: state.frames_hash,
            last_flush: Instant::now(),
            flush_every: FLUSH_EVERY,
            paraview_failed: false,
        })
    }

    /// The output state for a checkpoint (flushes all files).
    pub fn state(&mut self) -> Result<crate::checkpoint::OutputState, OutputError> {
        self.flush()?;
        Ok(crate::checkpoint::OutputState {
            energy_bytes: self.energy.len()?,
            positions_bytes: match &mut self.positions {
                Some(p) => Some(p.len()?),
                None => None,
            },
            ports_bytes: self.ports.len()?,
            frames: self.frames,
            frames_hash: self.frames_hash,
            last_frame: self.last_frame,
            snapshots: self.snapshots.clone(),
        })
    }

    /// The configuration snapshots taken so far.
    pub fn snapshots(&self) -> &[(f64, Vec<[f64; 2]>)] {
        &self.snapshots
    }

    /// Path of `energy.csv`.
    pub fn energy_path(&self) -> &Path {
        &self.energy.path
    }

    /// Writes the final state (positions and ParaView frame) if the last step was not on
    /// the output stride, then flushes all files.
    pub fn finish<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        self.frame_if(sim, true)?;
        self.flush()
    }

    /// Flushes all CSV files and writes the ParaView collection if a resume left it to be
    /// written.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        self.energy.flush()?;
        self.ports.flush()?;
        if let Some(p) = &mut self.positions {
            p.flush()?;
        }
        if let Some(pvd) = &mut self.pvd
            && self.pvd_dirty
        {
            pvd.write().inspect_err(|_| self.paraview_failed = true)?;
            self.pvd_dirty = false;
        }
        self.last_flush = Instant::now();
        Ok(())
    }

    /// The outputs (relative to the run folder) that a failed write left short of the steps
    /// the run took: CSV files cut back to their last whole record, and
    /// `paraview/string.pvd` if a frame or the collection could not be written (it lists the
    /// frames written before; a frame that failed is removed).
    pub fn incomplete_files(&self) -> Vec<String> {
        let mut files: Vec<String> = [
            Some(&self.energy),
            self.positions.as_ref(),
            Some(&self.ports),
        ]
        .into_iter()
        .flatten()
        .filter(|c| c.is_incomplete())
        .map(|c| relative(&self.dir, &c.path))
        .collect();
        if self.paraview_failed {
            files.push(format!("{PARAVIEW_DIR}/{PVD_FILE}"));
        }
        files
    }

    /// After a failed write: writes out what every file still holds, so that all rows
    /// written before the failure reach the disk (a file whose write fails too is cut back
    /// to its last whole record), and returns [`Self::incomplete_files`].
    pub fn salvage(&mut self) -> Vec<String> {
        let _ = self.energy.flush();
        let _ = self.ports.flush();
        if let Some(p) = &mut self.positions {
            let _ = p.flush();
        }
        if let Some(pvd) = &mut self.pvd
            && self.pvd_dirty
            && pvd.write().is_err()
        {
            self.paraview_failed = true;
        }
        self.incomplete_files()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phstring::benchmarks::paper_pendulum;
    use phstring::{Scheme, StepParams};

    fn sim() -> Simulation<2, Material> {
        let params = StepParams {
            h: 0.01,
            scheme: Scheme::DiscreteGradient,
            ..Default::default()
        };
        Simulation::new(paper_pendulum(10), params).unwrap()
    }

    fn lines(p: &Path) -> usize {
        std::fs::read_to_string(p).unwrap().lines().count()
    }

    #[test]
    fn t0_rows_are_flushed_at_start() {
        let dir = crate::test_util::temp_dir("output", "t0");
        let s = sim();
        let _w = Writers::start(&dir, &s, 1, true, true, vec![0.0]).unwrap();
        // The writers are alive (nothing dropped or flushed by the caller): the header and
        // the t = 0 row are already on disk.
        assert_eq!(lines(&dir.join("energy.csv")), 2);
        assert_eq!(lines(&dir.join("positions.csv")), 1 + 11);
        assert!(
            std::fs::read_to_string(dir.join("paraview/string.pvd"))
                .unwrap()
                .contains("frame_000000.vtp")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn flush_interval_bounds_what_a_kill_loses() {
        let dir = crate::test_util::temp_dir("output", "flush");
        let mut s = sim();
        let mut w = Writers::start(&dir, &s, 1, false, false, vec![]).unwrap();
        // A huge interval: rows stay buffered (a few hundred bytes, below the buffer size).
        w.set_flush_interval(Duration::from_secs(3600));
        let r = s.step().unwrap();
        w.step(&s, &r).unwrap();
        assert_eq!(lines(&dir.join("energy.csv")), 2);
        // Interval zero: every step is on disk when `step` returns.
        w.set_flush_interval(Duration::ZERO);
        for k in 0..3 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
            assert_eq!(lines(&dir.join("energy.csv")), 4 + k);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn non_finite_values_are_refused_not_written() {
        let dir = crate::test_util::temp_dir("output", "nonfinite");
        let mut s = sim();
        let mut w = Writers::start(&dir, &s, 1, true, true, vec![]).unwrap();
        let good = s.step().unwrap();
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut r = good;
            r.balance_error = bad;
            let e = w.step(&s, &r).unwrap_err();
            assert!(matches!(e, OutputError::NonFinite { .. }), "{e}");
            assert!(e.to_string().contains("non-finite"), "{e}");
            let mut r = good;
            r.after.kinetic = bad;
            assert!(matches!(w.step(&s, &r), Err(OutputError::NonFinite { .. })));
        }
        w.step(&s, &good).unwrap();
        w.flush().unwrap();
        for f in [
            "energy.csv",
            "ports.csv",
            "positions.csv",
            "paraview/string.pvd",
        ] {
            let text = std::fs::read_to_string(dir.join(f)).unwrap().to_lowercase();
            assert!(
                !text.contains("nan") && !text.contains("inf"),
                "{f}: {text}"
            );
        }
        // One good row after the t = 0 row: the refused rows left nothing behind.
        assert_eq!(lines(&dir.join("energy.csv")), 3);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn full_disk_is_an_error() {
        // /dev/full accepts the open and fails every write with ENOSPC.
        if !Path::new("/dev/full").exists() {
            return;
        }
        let mut c = Csv::create(PathBuf::from("/dev/full"), "header").unwrap();
        let e = c.flush().unwrap_err();
        assert!(matches!(e, OutputError::Io { .. }), "{e}");
        assert!(atomic_write(Path::new("/dev/full/x"), b"x").is_err());
    }

    /// Bytes of the files under `dir` whose names pass `keep`.
    fn bytes_of(dir: &Path, keep: &dyn Fn(&str) -> bool) -> f64 {
        std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .filter(|e| keep(&e.file_name().to_string_lossy()))
            .map(|e| e.metadata().unwrap().len() as f64)
            .sum()
    }

    #[test]
    fn output_estimate_matches_what_the_writers_write() {
        for (stride, steps) in [(1, 40), (7, 40), (40, 40)] {
            let dir = crate::test_util::temp_dir("output", "estimate");
            let mut s = sim();
            let mut w = Writers::start(&dir, &s, stride, true, true, vec![]).unwrap();
            for _ in 0..steps {
                let r = s.step().unwrap();
                w.step(&s, &r).unwrap();
            }
            w.finish(&s).unwrap();
            let e = estimated_output(&OutputPlan {
                dimension: 2,
                nodes: 11,
                elements: 10,
                ports: s.ports().len(),
                steps: steps as f64,
                stride,
                positions: true,
                vtk: true,
            });
            let pv = dir.join(PARAVIEW_DIR);
            let frames = std::fs::read_dir(&pv).unwrap().count() as f64 - 1.0;
            assert_eq!(e.frames, frames, "stride {stride}");
            let rows = bytes_of(&dir, &|n| n == "energy.csv" || n == "ports.csv");
            let positions = bytes_of(&dir, &|n| n == "positions.csv");
            let paraview = bytes_of(&pv, &|_| true);
            for (what, estimate, actual) in [
                ("rows", e.rows, rows),
                ("positions", e.positions, positions),
                ("paraview", e.paraview, paraview),
            ] {
                let ratio = estimate / actual;
                assert!(
                    (0.9..=1.1).contains(&ratio),
                    "stride {stride}, {what}: estimate {estimate}, written {actual}"
                );
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    #[test]
    fn overwrite_in_place_fits_the_new_text_in_the_old_file() {
        let dir = crate::test_util::temp_dir("output", "inplace");
        let path = dir.join("summary.json");
        std::fs::write(
            &path,
            format!("{{\"status\": \"running\"}}\n{}\n", " ".repeat(100)),
        )
        .unwrap();
        let len = std::fs::metadata(&path).unwrap().len();
        overwrite_in_place(
            &path,
            b"{\"status\": \"failed\", \"error\": \"disk full\"}\n",
        )
        .unwrap();
        // Same length, the new text, then white space: valid JSON.
        assert_eq!(std::fs::metadata(&path).unwrap().len(), len);
        let text = std::fs::read_to_string(&path).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["error"], "disk full");
        // Text longer than the file: refused, the file as it was.
        let long = vec![b'x'; len as usize];
        let e = overwrite_in_place(&path, &long).unwrap_err();
        assert!(e.to_string().contains("no room in place"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
        assert!(overwrite_in_place(&dir.join("missing.json"), b"{}").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn atomic_write_replaces_a_stale_temp_file() {
        let dir = crate::test_util::temp_dir("output", "atomic");
        let path = dir.join("summary.json");
        std::fs::write(dir.join(".summary.json.tmp"), "stale").unwrap();
        std::fs::write(&path, "old").unwrap();
        atomic_write(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert!(!dir.join(".summary.json.tmp").exists());
        // A write that fails (a folder where the file should be) leaves no temp file.
        std::fs::create_dir(dir.join("d.json")).unwrap();
        assert!(atomic_write(&dir.join("d.json"), b"x").is_err());
        assert!(!dir.join(".d.json.tmp").exists());
        for name in TEMP_FILES {
            assert!(is_own_temp_file(name));
        }
        assert!(!is_own_temp_file("notes.tmp") && !is_own_temp_file("energy.csv"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn decimation_bounds_points_and_keeps_spikes() {
        let n = 1_000_003;
        let mut d = Decimator::<2>::new(PLOT_POINTS);
        for i in 0..n {
            let y = if i == 777_777 {
                1e3
            } else if i == 123_457 {
                -1e3
            } else {
                (i as f64 * 0.37).sin()
            };
            d.push([i as f64, y]);
        }
        let rows = d.finish();
        assert!(rows.len() <= PLOT_POINTS + 2, "{}", rows.len());
        assert!(rows.len() > PLOT_POINTS / 4, "{}", rows.len());
        assert_eq!(rows[0][0], 0.0);
        assert_eq!(rows.last().unwrap()[0], (n - 1) as f64);
        assert!(rows.iter().any(|r| r == &[777_777.0, 1e3]));
        assert!(rows.iter().any(|r| r == &[123_457.0, -1e3]));
        assert!(rows.windows(2).all(|w| w[0][0] < w[1][0]), "in order");
        // Short series pass unchanged.
        let mut d = Decimator::<4>::new(PLOT_POINTS);
        let short: Vec<[f64; 4]> = (0..1000)
            .map(|i| [i as f64, (i % 7) as f64, -(i as f64), 1.0])
            .collect();
        for r in &short {
            d.push(*r);
        }
        assert_eq!(d.finish(), short);
    }

    #[test]
    fn history_is_read_back_from_energy_csv() {
        let dir = crate::test_util::temp_dir("output", "history");
        let mut s = sim();
        let mut w = Writers::start(&dir, &s, 1, false, false, vec![0.0, 0.05]).unwrap();
        let mut hs = vec![s.energies().hamiltonian()];
        for _ in 0..10 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
            hs.push(r.after.hamiltonian());
        }
        w.flush().unwrap();
        let h = read_history(w.energy_path(), PLOT_POINTS, w.snapshots().to_vec(), None)
            .unwrap()
            .unwrap();
        assert_eq!(h.hamiltonian, hs, "17 digits round-trip exactly");
        assert_eq!(h.t.len(), 11);
        let (ti, inc) = h.increments();
        assert_eq!(ti.len(), 10);
        assert_eq!(inc[3], (hs[4] - hs[3]).abs());
        assert_eq!(h.snapshots.len(), 2);
        // A stop request while reading gives no history (only checked every 4096 rows, so
        // this short file is read in full).
        let stop = AtomicBool::new(true);
        assert!(
            read_history(w.energy_path(), PLOT_POINTS, vec![], Some(&stop))
                .unwrap()
                .is_some()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

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

    /// A network of two strings with awkward names and a spring, with a point mass.
    fn named_network() -> Simulation<2, Material> {
        use phstring::{Boundary, MassMatrix, NetworkBuilder, PointMass, StringSpec, Vector};
        let mut b = NetworkBuilder::<2, Material>::new();
        let n: Vec<usize> = [(0.0, 0.0), (1.0, -1.0), (2.0, 0.0)]
            .iter()
            .map(|&(x, y)| b.node(Vector::<2>::new(x, y)))
            .collect();
        let spec = |name: &str| StringSpec {
            name: name.into(),
            material: Material::linear_elastic(1e3),
            rho_a: 0.1,
            mass: MassMatrix::Lumped,
            body_force: Vector::zeros(),
            prestretch: 1.0,
        };
        b.string(spec("a,b \"c\""), &[n[0], n[1]], 3).unwrap();
        b.string(spec(" line\nbreak"), &[n[1], n[2]], 2).unwrap();
        b.spring("plain", n[0], n[2], 10.0, 2.0).unwrap();
        let net = b
            .build(
                Boundary::default(),
                vec![PointMass {
                    node: n[1],
                    mass: 0.5,
                    weight: Vector::zeros(),
                }],
            )
            .unwrap();
        let params = StepParams {
            h: 0.01,
            ..Default::default()
        };
        Simulation::new(net, params).unwrap()
    }

    #[test]
    fn elements_csv_round_trips_and_malformed_files_are_refused() {
        let dir = crate::test_util::temp_dir("output", "elements");
        let s = named_network();
        let _w = Writers::start(&dir, &s, 1, false, false, vec![]).unwrap();
        let text = std::fs::read_to_string(dir.join(ELEMENTS_FILE)).unwrap();
        assert!(text.contains(",string,"), "{text}");
        assert!(text.contains("\"a,b \"\"c\"\"\"\n"), "{text}");
        assert!(text.contains("\" linebreak\"\n"), "{text}");
        assert!(
            text.ends_with("\n5,0,2,2,spring,1.0000000000000000e0,plain\n"),
            "{text}"
        );
        let t = read_topology(&dir).unwrap().unwrap();
        let mut expected = topology(&s);
        expected.groups[1].name = " linebreak".into();
        assert_eq!(t, expected);
        assert_eq!(t.masses, [(1, 0.5)]);
        assert_eq!(t.elements.len(), 6);

        let header = elements_header();
        for (rows, why, line) in [
            ("0,0,1,0,rope,1,x\n", "neither string nor spring", 2),
            ("1,0,1,0,string,1,x\n", "element 1 where 0", 2),
            ("0,0,1,1,string,1,x\n", "group 1 out of order", 2),
            (
                "0,0,1,0,string,1,x\n1,1,2,1,string,1,y\n2,2,3,0,string,1,x\n",
                "group 0 out of order",
                4,
            ),
            ("0,0,1,0,string\n", "fields, expected 7", 2),
            ("0,-1,1,0,string,1,x\n", "not an index", 2),
        ] {
            std::fs::write(dir.join(ELEMENTS_FILE), format!("{header}\n{rows}")).unwrap();
            let e = read_topology(&dir).unwrap_err().to_string();
            assert!(
                e.contains(why) && e.contains(&format!("line {line}:")),
                "{rows}: {e}"
            );
        }
        std::fs::write(dir.join(ELEMENTS_FILE), format!("{header}\n")).unwrap();
        std::fs::write(dir.join(POINT_MASSES_FILE), "node,mass\n1,heavy\n").unwrap();
        let e = read_topology(&dir).unwrap_err().to_string();
        assert!(e.contains("not a mass"), "{e}");
        std::fs::remove_file(dir.join(ELEMENTS_FILE)).unwrap();
        assert_eq!(read_topology(&dir).unwrap(), None);
        // A later single-string run into the folder removes the stale point masses.
        let _w = Writers::start(&dir, &sim(), 1, false, false, vec![]).unwrap();
        assert!(!dir.join(POINT_MASSES_FILE).exists());
        assert!(read_topology(&dir).unwrap().unwrap().is_chain());
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
