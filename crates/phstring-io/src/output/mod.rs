//! Output writers of a run: `energy.csv`, `positions.csv`, `ports.csv`, ParaView frames,
//! plots and `summary.json`, and once at the start the network's layout, `elements.csv`
//! (and `point_masses.csv` if it has point masses), from which `positions.csv` can be drawn.
//! Rows are written as the run goes, so everything up to the last good step is on disk when
//! a run fails: the `t = 0` rows are flushed at once, and the files at least every
//! [`FLUSH_EVERY`] of wall time.
//!
//! No NaN or infinity is ever written: a row with a non-finite value is refused with
//! [`OutputError::NonFinite`]. Memory does not grow with the number of steps: the plots
//! read what they need back from `energy.csv` (the `history` module, a floor above), decimated to at most
//! [`PLOT_POINTS`] points per curve.

mod bodies;
mod channels;
mod csv;
mod ends;
mod winches;

pub use channels::{ChannelString, ChannelTable};
pub use ends::{EndForces, EndWater};

use std::hash::Hasher;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use phstring::{Energies, Law, Material, PortKind, Simulation, StepReport};

use self::csv::{Csv, PendingCsv};
use crate::body_shape::{BodyBox, BodyPose};
use crate::checkpoint::OutputState;
use crate::files::{
    BODIES_FILE, BODIES_PVD_FILE, ELEMENTS_FILE, END_TENSIONS_FILE, ENERGY_FILE, PARAVIEW_DIR,
    POINT_MASSES_FILE, PORTS_FILE, POSITIONS_FILE, PVD_FILE, WINCH_ARCLENGTH_FILE, WINCHES_FILE,
    body_frame_name, elements_header, energy_header, frame_name, headers, num,
    remove_stale_temp_files,
};
use crate::plot::{GroupDrawing, PlotError, Topology};
use crate::text::sanitize_text;
use crate::vtk::{self, FrameData, PvdWriter, VtkError};

/// The file name of `path` (for the checkpoint, which records names, not paths).
fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// Longest wall time between two flushes of the output files during a run.
pub const FLUSH_EVERY: Duration = Duration::from_millis(500);

/// Most points per curve in the plots of a run: longer series are decimated keeping, per
/// bucket of consecutive rows, the rows with the smallest and largest value of each curve
/// (so that spikes survive).
pub const PLOT_POINTS: usize = 20_000;

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
    let t = sanitize_text(text, usize::MAX);
    if t.contains([',', '"']) || t.starts_with(' ') || t.ends_with(' ') {
        format!("\"{}\"", t.replace('"', "\"\""))
    } else {
        t
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
        for e in sys.group_span(g) {
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

/// Refuses ([`OutputError::Mismatch`]) a CSV file at `path` whose first line is not
/// `header`.
fn check_header(path: &Path, header: &str) -> Result<(), OutputError> {
    use std::io::{BufRead, Read};
    let f = std::fs::File::open(path).map_err(|cause| OutputError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    let mut first = String::new();
    std::io::BufReader::new(f.take(header.len() as u64 + 2))
        .read_line(&mut first)
        .map_err(|cause| OutputError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
    if first.trim_end_matches(['\n', '\r']) == header {
        Ok(())
    } else {
        Err(OutputError::Mismatch {
            path: path.to_path_buf(),
            reason: format!("its header is not that of this run ({header})"),
        })
    }
}

/// `path` relative to `dir` (for reports), or as it is if it is not in `dir`.
fn relative(dir: &Path, path: &Path) -> String {
    path.strip_prefix(dir).unwrap_or(path).display().to_string()
}

/// The side view of `sim` ([`crate::scene::Scene::side`]): for a 3D run whose body force
/// points straight down the z axis, the principal horizontal direction of its nodes now;
/// `None` otherwise.
fn side_view<const D: usize>(sim: &Simulation<D, Material>) -> Option<[f64; 2]> {
    if D != 3 {
        return None;
    }
    let f = sim
        .system()
        .body_force_vector()
        .iter()
        .fold(phstring::Vector::<D>::zeros(), |a, b| a + b);
    let down = f[2] < 0.0 && f[0].hypot(f[1]) <= 1e-12 * f.norm();
    down.then(|| {
        crate::scene::principal_horizontal(sim.state().r.iter().map(|r| [r[0], r[1], r[2]]))
    })
}

/// The view of one plane per line of `sim` ([`crate::scene::LinePlanes`]) for a run in
/// water drawn in a side view (`side`), chosen from its strings' node paths and its nodes
/// now; `None` when one plane is right (and for every dry run).
fn line_planes<const D: usize>(
    sim: &Simulation<D, Material>,
    side: Option<[f64; 2]>,
) -> Option<crate::scene::LinePlanes> {
    side?;
    let sys = sim.system();
    if !sys.has_water() {
        return None;
    }
    let mut springs = false;
    let mut strings = Vec::new();
    for (g, group) in sys.groups().iter().enumerate() {
        if matches!(group.law, Law::Spring(_)) {
            springs = true;
            continue;
        }
        let mut path: Vec<usize> = Vec::new();
        for e in sys.group_span(g) {
            let [a, b] = sys.mesh().elements()[e];
            if path.last() != Some(&a) {
                path.push(a);
            }
            path.push(b);
        }
        strings.push(path);
    }
    let r: Vec<[f64; 3]> = sim.state().r.iter().map(|p| [p[0], p[1], p[2]]).collect();
    crate::scene::LinePlanes::layout(&strings, springs, &r)
}

/// The nodes on the seabed now and every group's grounded length (the core's seabed
/// contact); `None` without a seabed.
fn grounded_now<const D: usize>(sim: &Simulation<D, Material>) -> Option<crate::scene::Grounded> {
    let sys = sim.system();
    let r = &sim.state().r;
    let contacts = sys.seabed_contacts(r);
    if contacts.is_empty() {
        return None;
    }
    Some(crate::scene::Grounded {
        nodes: contacts
            .iter()
            .filter(|c| c.grounded)
            .map(|c| c.node)
            .collect(),
        lengths: sys.grounded_lengths(&contacts),
    })
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
    /// Strings (two columns each in `end_tensions.csv`, written every step).
    pub strings: usize,
    /// Steps.
    pub steps: f64,
    /// `output.stride`.
    pub stride: usize,
    /// `output.row_stride`: rows of `energy.csv`, `ports.csv`, `end_tensions.csv` every
    /// so many steps.
    pub row_stride: usize,
    /// `output.positions`.
    pub positions: bool,
    /// `output.vtk`.
    pub vtk: bool,
    /// A run in water: six more columns in `energy.csv`, two more arrays per ParaView
    /// frame, the energy-split plot (PNG and SVG).
    pub wet: bool,
    /// Columns of the channel table (`output.channels`; 0: not written), a row per frame.
    pub channels: usize,
}

/// The size of a run's outputs, estimated before it runs ([`estimated_output`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputEstimate {
    /// All files [bytes].
    pub bytes: f64,
    /// Number of files.
    pub files: f64,
    /// `energy.csv`, `ports.csv`, `end_tensions.csv` and the channel table [bytes].
    pub rows: f64,
    /// `positions.csv` [bytes].
    pub positions: f64,
    /// ParaView frames written.
    pub frames: f64,
    /// `paraview/` [bytes].
    pub paraview: f64,
}

/// Bytes of one number as [`num`] writes it, with its comma, on average (`-3.456597251994913,`;
/// 14.5 to 16.7 bytes a number without the comma in the spar deck's and the mooring line's
/// outputs).
const NUM_BYTES: f64 = 17.0;
/// Bytes of a time with its comma on average: a multiple of the step is mostly short (`0.25,`),
/// sometimes 17 digits (`0.30000000000000004,`).
const TIME_BYTES: f64 = 8.0;
/// Bytes of a row of `energy.csv`: 8 numbers, the iteration count and the dissipated
/// energy (`0` without damping): 133 on average in the 2D test network below.
const ENERGY_ROW_BYTES: f64 = 135.0;
/// Bytes of a port value in `ports.csv` on average: a number, or `0` for the velocity and
/// power of a fixed support (10.9 in the 2D test network below, 9.2 in the paper's pendulum,
/// 13.9 in the spar deck).
const PORT_VALUE_BYTES: f64 = 11.0;
/// Bytes of a ParaView frame besides its arrays (XML header, array tags, the base64
/// headers).
const FRAME_BYTES: f64 = 1500.0;
/// Bytes of a ParaView frame per node: points and velocity (2 × 3 Float64), base64.
const FRAME_BYTES_PER_NODE: f64 = 48.0 * 4.0 / 3.0;
/// Bytes of a ParaView frame per element: connectivity and offsets (3 UInt64), `C`, `S`,
/// `tension` (3 Float64) and `string` (Int32), base64.
const FRAME_BYTES_PER_ELEMENT: f64 = 52.0 * 4.0 / 3.0;
/// Files of a run besides `positions.csv` and the frames: `energy.csv`, `ports.csv`,
/// `end_tensions.csv`, `elements.csv`, `summary.json`, the run id, `string.pvd`, eight
/// plots, `animation.gif` (not the lock file).
const FIXED_FILES: f64 = 16.0;
/// Bytes of a ParaView frame per node in water: the `grounded` flag and the
/// `contact_force` (2 Float64), base64.
const FRAME_BYTES_PER_WET_NODE: f64 = 16.0 * 4.0 / 3.0;
/// Bytes of a ParaView frame's two water arrays besides their values (tags, base64
/// headers).
const FRAME_BYTES_WET: f64 = 300.0;

/// The size and number of files a run writes, from the layout of the writers: a row of
/// `energy.csv` per step ([`ENERGY_ROW_BYTES`]), a row per port and step in `ports.csv`
/// (`t`, `2d` port values, the power, index, node and kind), a row of `end_tensions.csv`
/// per step (`t` and two numbers per string), a row per node
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
    let wet = if p.wet { 1.0 } else { 0.0 };
    // Rows at step 0, every row_stride-th step and the last.
    let row_stride = p.row_stride.max(1) as f64;
    let on_rows = (steps / row_stride).floor();
    let row_steps = on_rows
        + if on_rows * row_stride < steps {
            1.0
        } else {
            0.0
        };
    let rows = (row_steps + 1.0) * (ENERGY_ROW_BYTES + wet * 6.0 * NUM_BYTES)
        + row_steps * p.ports as f64 * ((2.0 + 2.0 * d) * PORT_VALUE_BYTES + digits(nodes) + 10.0)
        + if p.strings > 0 {
            (row_steps + 1.0) * (1.0 + 2.0 * p.strings as f64) * NUM_BYTES
        } else {
            0.0
        };
    // The channel table: two title rows and a row per frame, 10 + 20 bytes a channel.
    let channels = if p.channels > 0 {
        (frames + 2.0) * (11.0 + 20.0 * p.channels as f64)
    } else {
        0.0
    };
    let rows = rows + channels;
    let positions = if p.positions {
        // The first frame's time is written `0`.
        nodes * (frames * (TIME_BYTES + d * NUM_BYTES + digits(nodes)) - (TIME_BYTES - 2.0))
    } else {
        0.0
    };
    let paraview = if p.vtk {
        frames
            * (FRAME_BYTES
                + 70.0
                + wet * FRAME_BYTES_WET
                + (FRAME_BYTES_PER_NODE + wet * FRAME_BYTES_PER_WET_NODE) * nodes
                + FRAME_BYTES_PER_ELEMENT * p.elements as f64)
    } else {
        0.0
    };
    OutputEstimate {
        bytes: rows + positions + paraview,
        files: FIXED_FILES
            + 2.0 * wet
            + if p.channels > 0 { 1.0 } else { 0.0 }
            + if p.positions { 1.0 } else { 0.0 }
            + if p.vtk { frames } else { 0.0 },
        rows,
        positions,
        frames: if p.vtk { frames } else { 0.0 },
        paraview,
    }
}

/// The values of the water columns of an `energy.csv` row ([`crate::files::ENERGY_WATER_COLUMNS`])
/// for energies `e` of `sim`'s state [J]: the buoyancy and seabed potentials, then the water's
/// running totals of `sim`.
fn water_values<const D: usize>(sim: &Simulation<D, Material>, e: &Energies) -> [f64; 6] {
    let w = sim.water_work();
    [
        e.buoyancy,
        e.seabed,
        w.drag_dissipated,
        w.current_supplied,
        w.seabed_dissipated,
        w.friction_dissipated,
    ]
}

/// `values` as the fields of a CSV row, each after a comma.
fn more_fields(values: &[f64]) -> String {
    values.iter().map(|x| format!(",{}", num(*x))).collect()
}

/// The seabed contact of every node at `r` as the ParaView point arrays `grounded` (1 on the
/// seabed, 0 off it or out of reach of it) and `contact_force` [N]; `None` without a seabed
/// (the frames then carry neither array).
fn contact_arrays<const D: usize>(
    sys: &phstring::PhSystem<D, Material>,
    r: &[phstring::Vector<D>],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let contacts = sys.seabed_contacts(r);
    if contacts.is_empty() {
        return None;
    }
    let mut grounded = vec![0.0; r.len()];
    let mut force = vec![0.0; r.len()];
    for c in contacts {
        grounded[c.node] = if c.grounded { 1.0 } else { 0.0 };
        force[c.node] = c.force;
    }
    Some((grounded, force))
}

/// Writes the standard outputs of one run into a folder. Memory does not grow with the
/// number of steps (the configuration snapshots are bounded; the ParaView collection lists
/// one entry per frame file written).
pub struct Writers {
    dir: PathBuf,
    /// The run is in water: `energy.csv` has the water columns.
    water: bool,
    /// The run's winches: `energy.csv` has two columns for each.
    n_winches: usize,
    energy: Csv,
    positions: Option<Csv>,
    ports: Csv,
    /// `end_tensions.csv` and how its rows are computed (see [`Writers::end_tensions`]).
    ends: Option<Csv>,
    end_model: Option<EndForces>,
    /// `bodies.csv` (runs with rigid bodies).
    bodies: Option<Csv>,
    /// `winches.csv` (runs with winches).
    winches: Option<Csv>,
    /// `winch_arclength.csv` (runs with winches that write `positions.csv`).
    arclength: Option<Csv>,
    /// The channel table (`output.channels`) and how its rows are computed.
    channels: Option<Csv>,
    channel_model: Option<ChannelTable>,
    pvd: Option<PvdWriter>,
    /// The rigid bodies' collection (`paraview/bodies.pvd`; runs with bodies), a frame at
    /// every frame of `pvd`.
    body_pvd: Option<PvdWriter>,
    /// The collection file must be written again before it is whole (a resume continues
    /// it after the checkpoint's frames); frames are listed as they are written.
    pvd_dirty: bool,
    stride: usize,
    snapshot_times: Vec<f64>,
    snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    /// The side view of a 3D run the snapshots are drawn in ([`crate::scene::Scene::side`]).
    side: Option<[f64; 2]>,
    /// The view of one plane per line the snapshots are drawn in, if chosen.
    lines: Option<crate::scene::LinePlanes>,
    /// The nodes on the seabed at each snapshot (runs with a seabed).
    grounded: Vec<crate::scene::Grounded>,
    last_frame: Option<usize>,
    frames: usize,
    frames_hash: u64,
    last_flush: Instant,
    flush_every: Duration,
    /// A ParaView frame or the collection could not be written (the collection lists the
    /// frames written before).
    paraview_failed: bool,
    /// Rows of `energy.csv`, `ports.csv` and `end_tensions.csv` every `row_stride` steps.
    row_stride: usize,
    /// The last step's report when its rows were not written (off the row stride).
    pending_rows: Option<StepReport>,
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
        let water = sim.system().has_water();
        let n_winches = sim.system().winches().len();
        let (_, positions_header, ports_header) = headers(D);
        let energy = Csv::create(dir.join(ENERGY_FILE), &energy_header(D, water, n_winches))?;
        let positions = if positions {
            Some(Csv::create(dir.join(POSITIONS_FILE), &positions_header)?)
        } else {
            None
        };
        let ports = Csv::create(dir.join(PORTS_FILE), &ports_header)?;
        let bodies = bodies::create(dir, sim)?;
        let winches = winches::create(dir, sim)?;
        let arclength = match positions.is_some() {
            true => winches::create_arclength(dir, sim)?,
            false => None,
        };
        write_topology(dir, sim)?;
        let pvd = if vtk_frames {
            let pdir = dir.join(PARAVIEW_DIR);
            std::fs::create_dir_all(&pdir).map_err(io(&pdir))?;
            Some(PvdWriter::new(&pdir.join(PVD_FILE)))
        } else {
            None
        };
        let body_pvd = (vtk_frames && !sim.system().bodies().is_empty())
            .then(|| PvdWriter::new(&dir.join(PARAVIEW_DIR).join(BODIES_PVD_FILE)));
        let mut w = Self {
            dir: dir.to_path_buf(),
            water,
            n_winches,
            energy,
            positions,
            ports,
            ends: None,
            end_model: None,
            bodies,
            winches,
            arclength,
            channels: None,
            channel_model: None,
            pvd,
            body_pvd,
            pvd_dirty: false,
            stride,
            snapshot_times,
            snapshots: Vec::new(),
            side: side_view(sim),
            lines: line_planes(sim, side_view(sim)),
            grounded: Vec::new(),
            last_frame: None,
            frames: 0,
            frames_hash: frames_hash_start(),
            last_flush: Instant::now(),
            flush_every: FLUSH_EVERY,
            paraview_failed: false,
            row_stride: 1,
            pending_rows: None,
        };
        let e = sim.energies();
        let values = [e.kinetic, e.potential(), e.hamiltonian()];
        check_finite(&w.energy.path, "initial energy", 0.0, &values)?;
        // In water: the two potentials, and the running totals (zero before the first step).
        let wet = if water {
            let v = water_values(sim, &e);
            check_finite(&w.energy.path, "initial energy", 0.0, &v)?;
            more_fields(&v)
        } else {
            String::new()
        };
        // The winches' running totals (zero at the start).
        let wet = wet + &",0,0".repeat(n_winches);
        w.energy.row(&format!(
            "{},{},{},{},0,0,0,0,0,0{wet}",
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

    /// Writes the rows of `energy.csv`, `ports.csv` and `end_tensions.csv` every `n` steps
    /// (`output.row_stride`; and always the last step) instead of every step.
    pub fn set_row_stride(&mut self, n: usize) {
        self.row_stride = n.max(1);
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
            let scene = crate::scene::Scene {
                side: self.side,
                lines: self.lines.clone(),
                ..crate::scene::Scene::default()
            };
            let pts = sim
                .state()
                .r
                .iter()
                .enumerate()
                .map(|(i, r)| scene.node_point(i, r.as_slice()))
                .collect();
            self.snapshots.push((t, pts));
            if let Some(g) = grounded_now(sim) {
                // Aligned with the snapshots (a checkpoint may predate the record).
                let before = self.snapshots.len() - 1;
                self.grounded
                    .resize(before, crate::scene::Grounded::default());
                self.grounded.push(g);
            }
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
        self.channel_row(sim, t)?;
        if let Some(p) = &mut self.positions {
            for (i, r) in st.r.iter().enumerate() {
                p.num(t).field(i).nums(r.as_slice()).end_line()?;
            }
            p.end_record()?;
        }
        if let Some(a) = &mut self.arclength {
            winches::arc_rows(a, sim)?;
        }
        self.body_frame(sim)?;
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
            let contact = contact_arrays(sys, &st.r);
            let point_data: Vec<(&str, &[f64])> = mass
                .iter()
                .map(|m| ("mass", m.as_slice()))
                .chain(contact.iter().flat_map(|(g, f)| {
                    [("grounded", g.as_slice()), ("contact_force", f.as_slice())]
                }))
                .collect();
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

    /// Writes the rigid bodies' ParaView frame of the step of `sim` ([`vtk::write_vtp_bodies`])
    /// and lists it in `paraview/bodies.pvd` (runs with bodies and ParaView frames; a frame
    /// the collection cannot list is removed, as the strings' are).
    fn body_frame<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        let Some(pvd) = &mut self.body_pvd else {
            return Ok(());
        };
        let boxes = BodyBox::of(sim);
        let poses: Vec<BodyPose> = sim
            .state()
            .bodies
            .iter()
            .map(|st| {
                let q = st.orientation.quaternion();
                BodyPose {
                    position: st.position.into(),
                    orientation: [q.w, q.i, q.j, q.k],
                }
            })
            .collect();
        let name = body_frame_name(sim.steps());
        let path = self.dir.join(PARAVIEW_DIR).join(&name);
        vtk::write_vtp_bodies(&path, &boxes, &poses)
            .inspect_err(|_| self.paraview_failed = true)?;
        pvd.add(sim.time(), &name);
        if let Err(e) = pvd.write() {
            pvd.discard_pending();
            self.paraview_failed = true;
            let _ = std::fs::remove_file(&path);
            return Err(e.into());
        }
        Ok(())
    }

    /// Records one step: energy row, port rows and end tensions (every `row_stride` steps),
    /// and (every `stride` steps) positions and a ParaView frame. Refuses
    /// ([`OutputError::NonFinite`]) a row with NaN or infinity.
    pub fn step<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        r: &StepReport,
    ) -> Result<(), OutputError> {
        self.step_with(sim, r, None)
    }

    /// [`Self::step`] with the row of `end_tensions.csv` for the state of `sim` already
    /// computed (`end_tensions`, as [`EndForces::tensions`] gives it), so that a caller who
    /// needs it too computes it once.
    pub fn step_with<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        r: &StepReport,
        end_tensions: Option<&[f64]>,
    ) -> Result<(), OutputError> {
        if self.row_stride <= 1 || sim.steps().is_multiple_of(self.row_stride) {
            self.pending_rows = None;
            self.rows(sim, r, end_tensions)?;
        } else {
            self.pending_rows = Some(*r);
        }
        self.record(sim);
        self.frame(sim)?;
        if self.last_flush.elapsed() >= self.flush_every {
            self.flush()?;
        }
        Ok(())
    }

    /// The energy row, port rows and end tensions of the step `r` that led to `sim`'s state.
    fn rows<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        r: &StepReport,
        end_tensions: Option<&[f64]>,
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
        let wet = if self.water {
            let v = water_values(sim, &r.after);
            check_finite(&self.energy.path, "energy row value", r.t, &v)?;
            Some(v)
        } else {
            None
        };
        let t_mid = r.t - 0.5 * r.h;
        for p in sim.ports() {
            check_finite(&self.ports.path, "port input", t_mid, p.input.as_slice())?;
            check_finite(&self.ports.path, "port output", t_mid, p.output.as_slice())?;
            check_finite(&self.ports.path, "port power", t_mid, &[p.power()])?;
        }
        let e = &mut self.energy;
        e.num(values[0]).nums(&values[1..6]);
        e.field(r.newton_iterations).nums(&values[6..9]);
        e.nums(wet.as_ref().map_or(&[], |v| v.as_slice()));
        if self.n_winches > 0 {
            for w in sim.winch_samples() {
                let v = [w.energy, w.dissipated];
                check_finite(&e.path, "energy row value", r.t, &v)?;
                e.nums(&v);
            }
        }
        e.end_line()?;
        e.end_record()?;
        for (k, p) in sim.ports().iter().enumerate() {
            let kind = match p.kind {
                PortKind::Force => "force",
                PortKind::Velocity => "velocity",
            };
            let ports = &mut self.ports;
            ports.num(t_mid).field(k).field(p.node).field(kind);
            ports.nums(p.input.as_slice()).nums(p.output.as_slice());
            ports.nums(&[p.power()]).end_line()?;
        }
        // The winches' ports (docs/method.md §23) after the nodes', their power with the
        // held velocity and the cuts.
        let first = sim.ports().len();
        for (w, ws) in sim.winch_samples().iter().enumerate() {
            let (node, u, y) = ws.port;
            check_finite(
                &self.ports.path,
                "winch port",
                t_mid,
                &[u[..D].to_vec(), y[..D].to_vec(), vec![ws.power]].concat(),
            )?;
            let ports = &mut self.ports;
            ports.num(t_mid).field(first + w).field(node).field("winch");
            ports
                .nums(&u[..D])
                .nums(&y[..D])
                .nums(&[ws.power])
                .end_line()?;
        }
        self.ports.end_record()?;
        self.end_row(sim, r.t, end_tensions)?;
        if let Some(b) = &mut self.bodies {
            bodies::rows(b, sim, true)?;
        }
        if let Some(w) = &mut self.winches {
            winches::rows(w, sim)?;
        }
        Ok(())
    }

    /// Reopens the outputs of an interrupted run in `dir` at the state a checkpoint recorded
    /// (files longer than recorded are cut back), to continue appending. The ParaView
    /// collection is read back from `paraview/string.pvd` and must list the checkpoint's
    /// frames; `energy.csv` must have the header of a run of dimension `D` in water
    /// (`water`) or not, with `winches` winches, so that the rows appended have its columns.
    pub fn resume<const D: usize>(
        dir: &Path,
        stride: usize,
        vtk_frames: bool,
        snapshot_times: Vec<f64>,
        state: OutputState,
        (water, n_winches): (bool, usize),
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
        let body_pvd = if vtk_frames && state.bodies_bytes.is_some() {
            let path = dir.join(PARAVIEW_DIR).join(BODIES_PVD_FILE);
            let p = PvdWriter::resume(&path, state.frames, |_, _| {}).map_err(|e| {
                OutputError::Mismatch {
                    path: path.clone(),
                    reason: format!(
                        "it does not list the checkpoint's {} frames ({e})",
                        state.frames
                    ),
                }
            })?;
            Some(p)
        } else {
            None
        };
        // Check every file before any is cut back.
        check_header(&dir.join(ENERGY_FILE), &energy_header(D, water, n_winches))?;
        let energy = PendingCsv::open(dir.join(ENERGY_FILE), state.energy_bytes)?;
        let ports = PendingCsv::open(dir.join(PORTS_FILE), state.ports_bytes)?;
        let positions = match state.positions_bytes {
            Some(n) => Some(PendingCsv::open(dir.join(POSITIONS_FILE), n)?),
            None => None,
        };
        let ends = match state.end_tensions_bytes {
            Some(n) => Some(PendingCsv::open(dir.join(END_TENSIONS_FILE), n)?),
            None => None,
        };
        let bodies = match state.bodies_bytes {
            Some(n) => Some(PendingCsv::open(dir.join(BODIES_FILE), n)?),
            None => None,
        };
        let winches = match state.winches_bytes {
            Some(n) => Some(PendingCsv::open(dir.join(WINCHES_FILE), n)?),
            None => None,
        };
        let arclength = match state.winch_arclength_bytes {
            Some(n) => Some(PendingCsv::open(dir.join(WINCH_ARCLENGTH_FILE), n)?),
            None => None,
        };
        let channels = match &state.channels {
            Some((name, n)) => Some(PendingCsv::open(dir.join(name), *n)?),
            None => None,
        };
        let positions = positions.map(PendingCsv::commit).transpose()?;
        let ends = ends.map(PendingCsv::commit).transpose()?;
        let bodies = bodies.map(PendingCsv::commit).transpose()?;
        let winches = winches.map(PendingCsv::commit).transpose()?;
        let arclength = arclength.map(PendingCsv::commit).transpose()?;
        let channels = channels.map(PendingCsv::commit).transpose()?;
        Ok(Self {
            dir: dir.to_path_buf(),
            water,
            n_winches,
            energy: energy.commit()?,
            positions,
            ports: ports.commit()?,
            ends,
            end_model: None,
            bodies,
            winches,
            arclength,
            channels,
            channel_model: None,
            pvd,
            body_pvd,
            pvd_dirty: true,
            stride,
            snapshot_times,
            snapshots: state.snapshots,
            side: state.side,
            lines: state.lines,
            grounded: state.grounded,
            last_frame: state.last_frame,
            frames: state.frames,
            frames_hash: state.frames_hash,
            last_flush: Instant::now(),
            flush_every: FLUSH_EVERY,
            paraview_failed: false,
            row_stride: 1,
            pending_rows: None,
        })
    }

    /// The output state for a checkpoint (flushes all files).
    pub fn state(&mut self) -> Result<OutputState, OutputError> {
        self.flush()?;
        Ok(OutputState {
            energy_bytes: self.energy.len()?,
            positions_bytes: match &mut self.positions {
                Some(p) => Some(p.len()?),
                None => None,
            },
            ports_bytes: self.ports.len()?,
            end_tensions_bytes: match &mut self.ends {
                Some(e) => Some(e.len()?),
                None => None,
            },
            bodies_bytes: match &mut self.bodies {
                Some(b) => Some(b.len()?),
                None => None,
            },
            winches_bytes: match &mut self.winches {
                Some(w) => Some(w.len()?),
                None => None,
            },
            winch_arclength_bytes: match &mut self.arclength {
                Some(a) => Some(a.len()?),
                None => None,
            },
            channels: match &mut self.channels {
                Some(c) => Some((file_name(&c.path), c.len()?)),
                None => None,
            },
            frames: self.frames,
            frames_hash: self.frames_hash,
            last_frame: self.last_frame,
            snapshots: self.snapshots.clone(),
            side: self.side,
            lines: self.lines.clone(),
            grounded: self.grounded.clone(),
        })
    }

    /// The side view of a 3D run that the configuration is drawn in (`None`: 2D, or the
    /// plan of a 3D run), see [`crate::scene`].
    pub fn side(&self) -> Option<[f64; 2]> {
        self.side
    }

    /// The view of one plane per line the configuration is drawn in, if chosen (see
    /// [`crate::scene::LinePlanes`]).
    pub fn lines(&self) -> Option<&crate::scene::LinePlanes> {
        self.lines.as_ref()
    }

    /// The nodes on the seabed at each snapshot taken so far (empty without a seabed).
    pub fn grounded(&self) -> &[crate::scene::Grounded] {
        &self.grounded
    }

    /// Writes `end_tensions.csv` from now on, its rows computed by `model` (see
    /// [`EndForces`]): a fresh run creates it with the row of the state of `sim` (`t = 0`);
    /// a resumed run whose checkpoint recorded the file continues it (the file was reopened
    /// by [`Self::resume`]).
    pub fn end_tensions<const D: usize>(
        &mut self,
        model: EndForces,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        let fresh = self.ends.is_none();
        if fresh {
            self.ends = Some(Csv::create(
                self.dir.join(END_TENSIONS_FILE),
                &model.header(),
            )?);
        }
        self.end_model = Some(model);
        if fresh {
            self.end_row(sim, sim.time(), None)?;
            if let Some(e) = &mut self.ends {
                e.flush()?;
            }
        }
        Ok(())
    }

    /// Writes the channel table `name` (in the run's folder) from now on, its rows computed
    /// by `model`, at the times of `positions.csv`: a fresh run creates it with the row of
    /// the state of `sim`; a resumed run whose checkpoint recorded it continues it.
    pub fn channels<const D: usize>(
        &mut self,
        model: ChannelTable,
        name: &str,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        let fresh = self.channels.is_none();
        if fresh {
            self.channels = Some(Csv::create(self.dir.join(name), &model.header())?);
        }
        self.channel_model = Some(model);
        if fresh {
            self.channel_row(sim, sim.time())?;
            if let Some(c) = &mut self.channels {
                c.flush()?;
            }
        }
        Ok(())
    }

    /// Writes the channel table's row at time `t` [s] (if it is written).
    fn channel_row<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        t: f64,
    ) -> Result<(), OutputError> {
        let (Some(file), Some(model)) = (&mut self.channels, &self.channel_model) else {
            return Ok(());
        };
        let (row, values) = model.row(t, sim);
        check_finite(&file.path, "channel value", t, &values)?;
        file.row(&row)
    }

    /// Writes the row of `end_tensions.csv` at time `t` [s] (if it is written).
    fn end_row<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        t: f64,
        given: Option<&[f64]>,
    ) -> Result<(), OutputError> {
        let (Some(csv), Some(model)) = (&mut self.ends, &self.end_model) else {
            return Ok(());
        };
        let computed;
        let values = match given {
            Some(v) => v,
            None => {
                computed = model.tensions(sim);
                &computed
            }
        };
        check_finite(&csv.path, "end tension", t, values)?;
        csv.num(t).nums(values).end_line()?;
        csv.end_record()
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
    /// the output stride, and its rows if it was not on the row stride, then flushes all
    /// files.
    pub fn finish<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        if let Some(r) = self.pending_rows.take() {
            self.rows(sim, &r, None)?;
        }
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
        if let Some(e) = &mut self.ends {
            e.flush()?;
        }
        if let Some(b) = &mut self.bodies {
            b.flush()?;
        }
        if let Some(w) = &mut self.winches {
            w.flush()?;
        }
        if let Some(a) = &mut self.arclength {
            a.flush()?;
        }
        if let Some(c) = &mut self.channels {
            c.flush()?;
        }
        if self.pvd_dirty {
            for pvd in [&mut self.pvd, &mut self.body_pvd].into_iter().flatten() {
                pvd.write().inspect_err(|_| self.paraview_failed = true)?;
            }
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
            self.ends.as_ref(),
            self.bodies.as_ref(),
            self.winches.as_ref(),
            self.arclength.as_ref(),
            self.channels.as_ref(),
        ]
        .into_iter()
        .flatten()
        .filter(|c| c.is_incomplete())
        .map(|c| relative(&self.dir, &c.path))
        .collect();
        if self.paraview_failed {
            files.push(format!("{PARAVIEW_DIR}/{PVD_FILE}"));
            if self.body_pvd.is_some() {
                files.push(format!("{PARAVIEW_DIR}/{BODIES_PVD_FILE}"));
            }
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
        if let Some(e) = &mut self.ends {
            let _ = e.flush();
        }
        if let Some(b) = &mut self.bodies {
            let _ = b.flush();
        }
        if let Some(w) = &mut self.winches {
            let _ = w.flush();
        }
        if let Some(a) = &mut self.arclength {
            let _ = a.flush();
        }
        if let Some(c) = &mut self.channels {
            let _ = c.flush();
        }
        if self.pvd_dirty {
            for pvd in [&mut self.pvd, &mut self.body_pvd].into_iter().flatten() {
                if pvd.write().is_err() {
                    self.paraview_failed = true;
                }
            }
        }
        self.incomplete_files()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::atomic_write;
    use crate::test_util::sim;

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
        assert_eq!(lines(&dir.join(ENERGY_FILE)), 2);
        assert_eq!(lines(&dir.join(POSITIONS_FILE)), 1 + 11);
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
        assert_eq!(lines(&dir.join(ENERGY_FILE)), 2);
        // Interval zero: every step is on disk when `step` returns.
        w.set_flush_interval(Duration::ZERO);
        for k in 0..3 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
            assert_eq!(lines(&dir.join(ENERGY_FILE)), 4 + k);
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
        assert_eq!(lines(&dir.join(ENERGY_FILE)), 3);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The rows of the CSV file at `p` after its header, as numbers.
    fn number_rows(p: &Path) -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect()
    }

    #[test]
    fn wet_run_writes_the_water_columns_and_contact_arrays() {
        use crate::test_util::{frame_point_array, wet_line};
        let dir = crate::test_util::temp_dir("output", "wet");
        let mut s = wet_line();
        let mut w = Writers::start(&dir, &s, 10, false, true, vec![]).unwrap();
        for _ in 0..30 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
        }
        w.finish(&s).unwrap();
        let energy = dir.join(ENERGY_FILE);
        let text = std::fs::read_to_string(&energy).unwrap();
        assert_eq!(
            text.lines().next().unwrap(),
            format!(
                "{},buoyancy,seabed,drag_dissipated,current_supplied,seabed_dissipated,friction_dissipated",
                headers(2).0
            )
        );
        let rows = number_rows(&energy);
        assert_eq!(rows.len(), 31);
        assert!(rows.iter().all(|r| r.len() == 16));
        // Before the first step: the potentials, no work yet.
        let e0 = &rows[0];
        assert!(e0[10] != 0.0 && e0[11] >= 0.0, "{e0:?}");
        assert_eq!(e0[12..], [0.0; 4]);
        // The last row: this state's potentials and the running totals, to the last digit.
        let (e, ww) = (s.energies(), s.water_work());
        let expected = [
            e.buoyancy,
            e.seabed,
            ww.drag_dissipated,
            ww.current_supplied,
            ww.seabed_dissipated,
            ww.friction_dissipated,
        ];
        let last = rows.last().unwrap();
        assert_eq!(last[10..], expected);
        assert!(ww.drag_dissipated > 0.0 && ww.seabed_dissipated > 0.0);
        assert!(ww.friction_dissipated > 0.0 && e.seabed > 0.0);
        // No material damping: the water's shares are all of the dissipated energy.
        for r in &rows {
            let water = r[12] + r[14] + r[15];
            assert!((water - r[9]).abs() <= 1e-12 * r[9].abs(), "{r:?}");
        }
        // The frames: one grounded flag and contact force per node, those of the contacts.
        let frame = dir.join(PARAVIEW_DIR).join(frame_name(30));
        let grounded = frame_point_array(&frame, "grounded").unwrap();
        let force = frame_point_array(&frame, "contact_force").unwrap();
        assert_eq!(grounded.len(), 21);
        let contacts = s.system().seabed_contacts(&s.state().r);
        assert_eq!(contacts.len(), 21);
        for c in &contacts {
            assert_eq!(grounded[c.node], f64::from(u8::from(c.grounded)));
            assert_eq!(force[c.node], c.force);
        }
        let on_bed = grounded.iter().sum::<f64>();
        assert!((5.0..21.0).contains(&on_bed), "{on_bed} nodes grounded");
        // A resume checks the header: a dry one is refused, a wet one appends wet rows.
        let state = w.state().unwrap();
        drop(w);
        let refused = Writers::resume::<2>(&dir, 10, true, vec![], state.clone(), (false, 0));
        let e = refused.err().unwrap();
        assert!(matches!(e, OutputError::Mismatch { .. }), "{e}");
        assert!(e.to_string().contains("header"), "{e}");
        let mut w = Writers::resume::<2>(&dir, 10, true, vec![], state, (true, 0)).unwrap();
        let r = s.step().unwrap();
        w.step(&s, &r).unwrap();
        w.finish(&s).unwrap();
        let rows = number_rows(&energy);
        assert_eq!((rows.len(), rows[31].len()), (32, 16));
        // A dry run: the header it always had, frames without the contact arrays.
        let dry = crate::test_util::temp_dir("output", "dry");
        let _w = Writers::start(&dry, &sim(), 1, false, true, vec![]).unwrap();
        let header = std::fs::read_to_string(dry.join(ENERGY_FILE)).unwrap();
        assert_eq!(header.lines().next().unwrap(), headers(2).0);
        let frame = dry.join(PARAVIEW_DIR).join(frame_name(0));
        assert!(frame_point_array(&frame, "grounded").is_none());
        assert!(frame_point_array(&frame, "contact_force").is_none());
        let _ = std::fs::remove_dir_all(&dir);
        let _ = std::fs::remove_dir_all(&dry);
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
        let cases = [
            (1, 40, false),
            (7, 40, false),
            (40, 40, false),
            (1, 40, true),
            (7, 40, true),
        ];
        for (stride, steps, wet) in cases {
            let dir = crate::test_util::temp_dir("output", "estimate");
            let mut s = if wet {
                crate::test_util::wet_line()
            } else {
                sim()
            };
            let mesh = s.system().mesh();
            let (nodes, elements) = (mesh.n_nodes(), mesh.n_elements());
            let mut w = Writers::start(&dir, &s, stride, true, true, vec![]).unwrap();
            let ends = EndForces::new(s.system(), &[], None).unwrap();
            w.end_tensions(ends.clone(), &s).unwrap();
            let names = ["FairTen1", "AnchTen1", "L1N1PX", "L1N1PY"];
            let channels: Vec<_> = names
                .iter()
                .map(|n| crate::channels::parse(n).unwrap())
                .collect();
            let string = ChannelString {
                path_nodes: vec![0, nodes - 1],
                first_element: 0,
                elements_per_span: elements,
            };
            let table = ChannelTable::new(&channels, &[string], |_| None, ends).unwrap();
            w.channels(table, "run.out", &s).unwrap();
            for _ in 0..steps {
                let r = s.step().unwrap();
                w.step(&s, &r).unwrap();
            }
            w.finish(&s).unwrap();
            let plan = OutputPlan {
                dimension: 2,
                nodes,
                elements,
                ports: s.ports().len(),
                strings: 1,
                steps: steps as f64,
                stride,
                row_stride: 1,
                positions: true,
                vtk: true,
                wet,
                channels: names.len(),
            };
            let e = estimated_output(&plan);
            let pv = dir.join(PARAVIEW_DIR);
            let frames = std::fs::read_dir(&pv).unwrap().count() as f64 - 1.0;
            assert_eq!(e.frames, frames, "stride {stride}");
            let rows = bytes_of(&dir, &|n| {
                n == "energy.csv" || n == "ports.csv" || n == END_TENSIONS_FILE || n == "run.out"
            });
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
                    "stride {stride}, wet {wet}, {what}: estimate {estimate}, written {actual}"
                );
            }
            // The channel table's share alone: the estimate less the one without it.
            let without = estimated_output(&OutputPlan {
                channels: 0,
                ..plan
            });
            let table = bytes_of(&dir, &|n| n == "run.out");
            assert!(
                ((e.rows - without.rows) / table - 1.0).abs() < 0.02,
                "stride {stride}: channel table estimate {}, written {table}",
                e.rows - without.rows
            );
            assert_eq!(e.files - without.files, 1.0);
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
}
