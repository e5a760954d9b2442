//! What a run will take, estimated before it is spent: memory (parsing the scenario text,
//! the per-component bookkeeping of a network, the mesh and its outputs), time per step,
//! and the size and number of its output files. `check` prints it and warns; `run`,
//! `sweep`, `statics`, `modes` and `linearize` refuse what does not fit in the memory
//! available, a scenario file too large to parse before it is parsed.

use std::path::Path;

use anyhow::{Result, bail};
use phstring_io::moordyn;
use phstring_io::output::{OutputEstimate, OutputPlan, estimated_output};
use phstring_io::scenario::{self, ScenarioFile};
use phstring_io::text::clip;

/// Most planned steps before `check` warns.
pub const WARN_STEPS: f64 = 1e9;

/// Output size [bytes] above which `check` and `run` warn (5 GB).
pub const WARN_OUTPUT_BYTES: f64 = 5e9;

/// Output files above which `check` and `run` warn (ParaView frames mostly).
pub const WARN_OUTPUT_FILES: f64 = 1e5;

/// Newton iterations per step assumed by the time estimate (3–6 are usual).
pub const ITERATIONS_PER_STEP: f64 = 4.0;

/// Memory of a run beyond [`phstring::estimated_memory_bytes`], per element [bytes], by
/// dimension 1, 2, 3: (validation and the step's other work space, positions and plots,
/// ParaView frames). Measured as the growth of the peak resident memory of `phstring run`
/// (release, one step; `/usr/bin/time -v`) from 3e4 to 3e5 elements, minus the library's
/// estimate, with the outputs off, with positions and plots, and with all:
/// `examples/axial_rod_1d.toml` 175, 171, 756 bytes per element in all (the library's
/// estimate 169), `examples/paper_pendulum.toml` 482, 779, 1062 (378), a 3D hanging rope
/// 705, 852, 1312 (667); rounded up.
const RUN_BYTES_PER_ELEMENT: [(f64, f64, f64); 3] = [
    (16.0, 8.0, 616.0),
    (112.0, 312.0, 304.0),
    (48.0, 160.0, 488.0),
];

/// Memory of the process besides its mesh and scenario [bytes]: the program, the plots'
/// fonts, the allocator's arenas. The peak resident memory of the runs above at 3e4
/// elements minus their per-element share: 7.5 MB with the outputs off, 11–16 MB with all.
const PROCESS_BYTES: f64 = 16e6;

/// Memory of the starting equilibrium (`initial.equilibrium`) on top of a run, per element
/// [bytes]: the static solve's tangent, workspace and paths. The 3D hanging rope at 3e5
/// elements, outputs off: 318 MB with it, 219 MB without; 330 bytes per element, rounded
/// up.
const EQUILIBRIUM_BYTES_PER_ELEMENT: f64 = 352.0;

/// Peak memory of reading a scenario [bytes per byte of its text]: the TOML parser's
/// document with the span of every key and value and its event buffer, then the typed
/// scenario. Calibration: peak resident memory of `phstring check` (release) on generated
/// networks of 25 000, 50 000 and 99 999 one-element strings between as many + 1 named
/// nodes (3.8, 7.7 and 15.5 MB of TOML): 41.7, 40.7 and 40.2 bytes per byte (the parse is
/// the peak of `check` and of `run` alike); the same network without blanks 40.9; with a
/// 200-byte comment per node 19; a single string with `initial.positions` for 200 001
/// nodes (3.3 MB) 27 besides its mesh. Rounded up to 44.
pub const PARSE_BYTES_PER_TEXT_BYTE: f64 = 44.0;

/// Memory per component table of a network (`[[node]]`, `[[string]]`, `[[spring]]`,
/// `[[boundary]]`, `[[point_mass]]`) after parsing [bytes]: its typed table with spans and
/// names, its entry in the validated components and the reference resolution, and its
/// groups and paths in the built network. Calibration: the heap of `phstring run` (valgrind
/// massif) on the 25 000-string network after parsing peaks at 80 MB: 33 MB for the text,
/// the mesh and the outputs' per-element share, 47 MB for its 50 000 tables, 0.94 kB each;
/// rounded up.
pub const COMPONENT_BYTES: f64 = 1024.0;

/// What a run will take, roughly: planned steps, memory, time per step, outputs.
pub struct Budget {
    dimension: usize,
    elements: usize,
    /// Component tables of a network (0 for one string).
    components: usize,
    /// Bytes of the scenario text.
    text: usize,
    steps: f64,
    /// Bytes the run needs at its peak, if known (parsing or running, whichever is more).
    memory: Option<f64>,
    /// Bytes of memory available on this machine, if known.
    available: Option<f64>,
    /// Seconds per step (rough, see [`budget`]).
    step_seconds: f64,
    /// The outputs.
    output: OutputEstimate,
}

/// Peak memory of parsing a scenario text of `bytes` bytes (see
/// [`PARSE_BYTES_PER_TEXT_BYTE`]).
fn parse_memory(bytes: usize) -> f64 {
    PARSE_BYTES_PER_TEXT_BYTE * bytes as f64
}

/// Reads the scenario at `path` with `sets` like [`scenario::load`], after refusing a file
/// whose parse alone would not fit in the memory available (estimated from its size, see
/// [`PARSE_BYTES_PER_TEXT_BYTE`]), so that such a file is refused before it is parsed. A
/// MoorDyn deck (told by its content) is mapped onto a scenario first, dropping the
/// features named in `ignore` ([`moordyn::load_scenario`]).
pub fn load(
    path: &Path,
    sets: &[String],
    ignore: &[String],
    motion: Option<&Path>,
) -> Result<ScenarioFile> {
    Ok(load_any(path, sets, ignore, motion)?.file)
}

/// [`load`], with the deck's mapping when `path` is a MoorDyn deck; `motion` moves its
/// coupled points ([`moordyn::load_scenario_driven`]).
pub fn load_any(
    path: &Path,
    sets: &[String],
    ignore: &[String],
    motion: Option<&Path>,
) -> Result<moordyn::Loaded> {
    check_file_size(path)?;
    Ok(moordyn::load_scenario_driven(path, sets, ignore, motion)?)
}

/// Refuses a scenario file whose parse would not fit in the memory available (a file that
/// is not a regular file is left to [`scenario::load`], which reads at most
/// [`scenario::MAX_SCENARIO_BYTES`]).
pub fn check_file_size(path: &Path) -> Result<()> {
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    let len = usize::try_from(meta.len()).unwrap_or(usize::MAX);
    if !meta.is_file() || len as u64 > scenario::MAX_SCENARIO_BYTES {
        return Ok(());
    }
    if let Some(available) = mem_available()?
        && parse_memory(len) > available
    {
        bail!(
            "scenario file {} has {} of text, and reading it needs about {} of memory, but only {} is available on this machine",
            path.display(),
            bytes(len as f64),
            bytes(parse_memory(len)),
            bytes(available)
        );
    }
    Ok(())
}

/// The budget of a parsed scenario: memory the larger of its parse
/// ([`PARSE_BYTES_PER_TEXT_BYTE`]) and the run: [`PROCESS_BYTES`],
/// [`phstring::estimated_memory_bytes`], [`RUN_BYTES_PER_ELEMENT`] for the outputs switched
/// on and [`EQUILIBRIUM_BYTES_PER_ELEMENT`] with `initial.equilibrium`, [`COMPONENT_BYTES`]
/// per component table and the text twice (held, and as the scenario). (The parse's memory
/// is reused by the run: the peak of `run` on the networks of [`PARSE_BYTES_PER_TEXT_BYTE`]
/// is that of `check`.) Time per step from
/// [`phstring::estimated_seconds_per_step`] (a release build) at [`ITERATIONS_PER_STEP`]
/// iterations; outputs from [`estimated_output`].
pub fn budget(file: &ScenarioFile) -> Result<Budget> {
    let s = &file.scenario;
    let dimension = file.dimension()?;
    let elements = file.element_count();
    let steps = (*s.time.end.get_ref() / *s.time.h.get_ref()).round();
    let (base, plots, vtk) = RUN_BYTES_PER_ELEMENT[dimension.clamp(1, 3) - 1];
    let o = &s.output;
    let per_element =
        base + if o.positions || o.plots { plots } else { 0.0 } + if o.vtk { vtk } else { 0.0 };
    let components = if s.string.is_empty() {
        0
    } else {
        s.node.len() + s.string.len() + s.spring.len() + s.boundary.len() + s.point_mass.len()
    };
    let text = file.text().len();
    let equilibrium = s.initial.as_ref().is_some_and(|i| *i.equilibrium.get_ref());
    let per_element = per_element
        + if equilibrium {
            EQUILIBRIUM_BYTES_PER_ELEMENT
        } else {
            0.0
        };
    let run = PROCESS_BYTES
        + phstring::estimated_memory_bytes(dimension, elements) as f64
        + per_element * elements as f64
        + COMPONENT_BYTES * components as f64
        + 2.0 * text as f64;
    let output = estimated_output(&OutputPlan {
        dimension,
        nodes: elements.saturating_add(1),
        elements,
        ports: s.boundary.len(),
        strings: s.string.len().max(usize::from(s.material.is_some())),
        steps,
        stride: usize::try_from(*o.stride.get_ref()).unwrap_or(1).max(1),
        row_stride: o
            .row_stride
            .as_ref()
            .and_then(|r| usize::try_from(*r.get_ref()).ok())
            .unwrap_or(1)
            .max(1),
        positions: o.positions,
        vtk: o.vtk,
        wet: s.water.is_some(),
        channels: o.channels.len(),
    });
    Ok(Budget {
        dimension,
        elements,
        components,
        text,
        steps,
        memory: Some(run.max(parse_memory(text))),
        available: mem_available()?,
        step_seconds: phstring::estimated_seconds_per_step(
            dimension,
            elements,
            ITERATIONS_PER_STEP,
        ),
        output,
    })
}

impl Budget {
    /// The estimate as `check` prints it.
    pub fn describe(&self) -> String {
        let memory = self.memory.map_or_else(
            || "memory unknown".to_string(),
            |m| format!("{} of memory", bytes(m)),
        );
        format!(
            "{memory}, ~{} per step, ~{} for {:.0} steps (rough: release build, {ITERATIONS_PER_STEP} Newton iterations per step)\n  output:    about {} in {} files ({})",
            duration(self.step_seconds),
            duration(self.step_seconds * self.steps),
            self.steps,
            bytes(self.output.bytes),
            count(self.output.files),
            self.output_parts()
        )
    }

    /// The large outputs in words: `positions.csv 1.2 GB, 2.0e6 ParaView frames 19 GB`.
    fn output_parts(&self) -> String {
        let o = &self.output;
        let mut parts = vec![format!(
            "energy.csv, ports.csv and end_tensions.csv {}",
            bytes(o.rows)
        )];
        if o.positions > 0.0 {
            parts.push(format!("positions.csv {}", bytes(o.positions)));
        }
        if o.frames > 0.0 {
            parts.push(format!(
                "{} ParaView frames {}",
                count(o.frames),
                bytes(o.paraview)
            ));
        }
        parts.join(", ")
    }

    /// Problems of `concurrent` such runs at once on this machine.
    pub fn warnings(&self, concurrent: usize) -> Vec<String> {
        let mut w = Vec::new();
        if self.steps > WARN_STEPS {
            w.push(format!(
                "{:.2e} planned steps (about {} in all); a larger time.h or a shorter time.end may be meant",
                self.steps,
                duration(self.step_seconds * self.steps)
            ));
        }
        w.extend(self.output_warning());
        if let Some(e) = self.memory_error(concurrent) {
            w.push(e);
        }
        w
    }

    /// The warning about outputs above [`WARN_OUTPUT_BYTES`] or [`WARN_OUTPUT_FILES`].
    pub fn output_warning(&self) -> Option<String> {
        let o = &self.output;
        (o.bytes > WARN_OUTPUT_BYTES || o.files > WARN_OUTPUT_FILES).then(|| {
            format!(
                "the run would write about {} in {} files ({}); a larger output.stride, output.vtk = false or output.positions = false may be meant",
                bytes(o.bytes),
                count(o.files),
                self.output_parts()
            )
        })
    }

    /// Why `concurrent` such runs do not fit in the available memory, if they do not.
    pub fn memory_error(&self, concurrent: usize) -> Option<String> {
        let need = self.memory? * concurrent as f64;
        let available = self.available?;
        (need > available).then(|| {
            let what = if self.components > 0 || parse_memory(self.text) >= need {
                format!(
                    "the scenario ({} of text, {} component tables) and its {} elements in {}D",
                    bytes(self.text as f64),
                    self.components,
                    self.elements,
                    self.dimension
                )
            } else {
                format!("{} elements in {}D", self.elements, self.dimension)
            };
            format!(
                "{what} need about {} of memory{}, but only {} is available on this machine; use fewer elements{}",
                bytes(need),
                if concurrent > 1 {
                    format!(" ({concurrent} runs at once; fewer --jobs also help)")
                } else {
                    String::new()
                },
                bytes(available),
                if self.components > 0 {
                    " or components"
                } else {
                    ""
                }
            )
        })
    }
}

/// Refuses a run that cannot fit in this machine's available memory.
pub fn check_budget(file: &ScenarioFile) -> Result<()> {
    check_budget_of(file, 1)
}

/// Refuses `concurrent` runs of `file` at once that cannot fit in this machine's available
/// memory.
pub fn check_budget_of(file: &ScenarioFile, concurrent: usize) -> Result<()> {
    if let Some(e) = budget(file)?.memory_error(concurrent) {
        bail!("{e}");
    }
    Ok(())
}

/// Environment variable with the memory [bytes] runs may use, instead of `MemAvailable` (in
/// a container, `/proc/meminfo` may show the host's memory rather than the container's
/// limit).
const MEMORY_ENV: &str = "PHSTRING_MEMORY_AVAILABLE";

/// The memory runs may use [bytes]: [`MEMORY_ENV`] if set, else `MemAvailable` of
/// `/proc/meminfo` if readable.
fn mem_available() -> Result<Option<f64>> {
    if let Some(v) = std::env::var_os(MEMORY_ENV) {
        let text = v.to_string_lossy();
        return match text.trim().parse::<f64>() {
            Ok(b) if b >= 0.0 && b.is_finite() => Ok(Some(b)),
            _ => bail!(
                "{MEMORY_ENV}={}: expected a number of bytes, e.g. 8e9",
                clip(&text)
            ),
        };
    }
    Ok(meminfo_available())
}

/// `MemAvailable` of `/proc/meminfo` [bytes], if readable.
fn meminfo_available() -> Option<f64> {
    use std::io::Read as _;
    let mut text = String::new();
    std::fs::File::open("/proc/meminfo")
        .ok()?
        .take(64 << 10)
        .read_to_string(&mut text)
        .ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line
        .trim_start_matches("MemAvailable:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024.0)
}

/// Bytes for people: `3.2 GB`.
pub fn bytes(b: f64) -> String {
    match b {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.0} MB", b / 1e6),
        b => format!("{:.0} kB", (b / 1e3).max(1.0)),
    }
}

/// A count for people: `20002`, `2.0e6`.
fn count(n: f64) -> String {
    if n < 1e6 {
        format!("{n:.0}")
    } else {
        format!("{n:.1e}")
    }
}

/// Seconds for people: `0.3 ms`, `12 s`, `3.5 h`, `41 days`, `2.1e6 years`.
pub fn duration(s: f64) -> String {
    const DAY: f64 = 86_400.0;
    const YEAR: f64 = 365.25 * DAY;
    match s {
        s if s < 1e-3 => format!("{:.2} ms", s * 1e3),
        s if s < 1.0 => format!("{:.0} ms", s * 1e3),
        s if s < 120.0 => format!("{s:.1} s"),
        s if s < 7200.0 => format!("{:.0} min", s / 60.0),
        s if s < 2.0 * DAY => format!("{:.1} h", s / 3600.0),
        s if s < YEAR => format!("{:.0} days", s / DAY),
        s if s < 1e4 * YEAR => format!("{:.0} years", s / YEAR),
        s => format!("{:.1e} years", s / YEAR),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_counts_and_durations_for_people() {
        assert_eq!(bytes(9.94e8), "994 MB");
        assert_eq!(bytes(2.01e10), "20.1 GB");
        assert_eq!(count(20002.0), "20002");
        assert_eq!(count(2.000002e6), "2.0e6");
        assert_eq!(duration(12.5), "12.5 s");
        assert_eq!(duration(3.0 * 3600.0), "3.0 h");
    }
}
