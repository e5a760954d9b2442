//! The names and layout of phstring's output files, the lowest floor of the writers: every
//! file name of an output folder (a run's, a sweep's, `phstring paper`'s), the run id that
//! marks a folder as a run's, the temporary files of atomic writes and the atomic write
//! itself, and the header lines of the CSV files. Everything that writes or reads an output
//! folder takes its names from here.

use std::hash::Hasher;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The rigid bodies' states, one row per body at every row of `energy.csv` (header:
/// [`bodies_header`]); written by runs with bodies.
pub const BODIES_FILE: &str = "bodies.csv";

/// The header line of [`BODIES_FILE`]: the time [s], the body's name, its centre of mass
/// `x, y, z` [m], its orientation as the unit quaternion `qw, qx, qy, qz` (body axes to
/// space), the velocity of the centre `vx, vy, vz` [m/s] and the angular velocity in space
/// axes `wx, wy, wz` [rad/s], all at the step's end; with `wrench` (some body has a wrench
/// port) then the port's force `fx, fy, fz` [N] and torque `tx, ty, tz` [N·m] over the step
/// and its mean power `power` [W] (zero at `t = 0` and for a body without a port).
pub fn bodies_header(wrench: bool) -> String {
    let mut h = "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz".to_string();
    if wrench {
        h.push_str(",fx,fy,fz,tx,ty,tz,power");
    }
    h
}

/// The winches, one row per winch at every row of `energy.csv` (header:
/// [`WINCHES_HEADER`]); written by runs with winches.
pub const WINCHES_FILE: &str = "winches.csv";

/// The header line of [`WINCHES_FILE`]: the time [s], the winch's name, the length paid out
/// since `t = 0` `payout` [m] (negative: hauled in), the string's reference length off the
/// drum `length` [m], the mean payout speed over the last step `speed` [m/s], the tension
/// of the element at the drum `tension` [N], the mean power the winch supplied over the last
/// step `power` [W] (negative: taken), the energy it supplied since `t = 0` `energy` [J],
/// the string's mass off the drum `mass` [kg], and for a drum with dynamics the energy its
/// motor supplied `motor_energy` [J] (part of `energy`) and its damping and brake dissipated
/// `drum_dissipated` [J] since `t = 0` (both 0 without).
pub const WINCHES_HEADER: &str =
    "t,winch,payout,length,speed,tension,power,energy,mass,motor_energy,drum_dissipated";

/// The unstretched arc length of every node of each winch's string, at the times of
/// `positions.csv` (header: [`WINCH_ARCLENGTH_HEADER`]); written by runs with winches that
/// write `positions.csv`.
pub const WINCH_ARCLENGTH_FILE: &str = "winch_arclength.csv";

/// The header line of [`WINCH_ARCLENGTH_FILE`]: the time [s], the winch's name, the mesh
/// node (as in `positions.csv`) and its unstretched arc length `s` [m] from the drum point
/// along the string (docs/method.md §23): positive off the drum, the last node's the length
/// off the drum of `winches.csv`; zero or negative for the drum node and the nodes parked on
/// the drum. One row per node of the string, in path order (parked nodes first).
pub const WINCH_ARCLENGTH_HEADER: &str = "t,winch,node,s";

/// Energies, one row per step (header: [`headers`]).
pub const ENERGY_FILE: &str = "energy.csv";
/// Node positions, one row per node and frame (header: [`headers`]).
pub const POSITIONS_FILE: &str = "positions.csv";
/// Port values, one row per port and step (header: [`headers`]).
pub const PORTS_FILE: &str = "ports.csv";
/// What a run (or a statics, modes run) did, as JSON.
pub const SUMMARY_FILE: &str = "summary.json";
/// Name of the checkpoint file in the output folder.
pub const CHECKPOINT: &str = "checkpoint.json";

/// A large network's components, written by a run instead of listing them in
/// `summary.json` (beyond the run driver's `SUMMARY_COMPONENTS`).
pub const COMPONENTS_FILE: &str = "components.json";

/// A long scenario as run, written by a run instead of holding it in `summary.json` (beyond
/// the run driver's `SUMMARY_SCENARIO_BYTES`).
pub const SCENARIO_FILE: &str = "scenario.json";

/// File name of the animation in a run's output folder.
pub const ANIMATION_FILE: &str = "animation.gif";

/// The equilibrium of `phstring statics`: node positions and reactions.
pub const EQUILIBRIUM_FILE: &str = "equilibrium.csv";
/// The element tensions at the equilibrium of `phstring statics`.
pub const TENSION_FILE: &str = "tension.csv";
/// The equilibrium of `phstring statics` as a ParaView frame.
pub const EQUILIBRIUM_FRAME: &str = "equilibrium.vtp";
/// The natural frequencies of `phstring modes`.
pub const MODES_FILE: &str = "modes.csv";
/// The ParaView collection of the mode shapes of `phstring modes` (frames are
/// [`mode_frame_name`]).
pub const MODES_PVD_FILE: &str = "modes.pvd";
/// The positions a linear model of `phstring linearize` is taken at.
pub const LINEAR_AT_FILE: &str = "at.csv";
/// The manifest of `phstring linearize`: its forms, matrices, ports and equations.
pub const MANIFEST_FILE: &str = "manifest.json";

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

/// The forces of the strings on their end nodes over time (MoorDyn's `FairTen<i>` and
/// `AnchTen<i>`): written by `run` for every scenario with strings.
pub const END_TENSIONS_FILE: &str = "end_tensions.csv";

/// Stem of the plot of the fairlead tensions of `end_tensions.csv` against time (`.svg`
/// and `.png`).
pub const FAIRLEAD_TENSION_STEM: &str = "fairlead_tension";

/// Stem of the plot of each winch's string length off the drum against time (`.svg` and
/// `.png`), from `winches.csv`.
pub const WINCH_LENGTH_STEM: &str = "winch_length";

/// Stem of the plot of each winch's tension at the drum against time (`.svg` and `.png`),
/// from `winches.csv`.
pub const WINCH_TENSION_STEM: &str = "winch_tension";

/// Configuration snapshots taken for the configuration plot (at `t = k T / 5`).
pub const SNAPSHOTS: usize = 6;

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

/// The columns that `energy.csv` of a run in water has after those of [`headers`] (each
/// [J]): the buoyancy and seabed contact potentials (parts of `potential`), then the
/// running totals of the energy dissipated by drag, supplied by the current through the
/// drag (either sign; part of `supplied_energy`), dissipated by the seabed's damping and by
/// seabed friction (parts of `dissipated_energy`), docs/method.md §21.
pub const ENERGY_WATER_COLUMNS: [&str; 6] = [
    "buoyancy",
    "seabed",
    "drag_dissipated",
    "current_supplied",
    "seabed_dissipated",
    "friction_dissipated",
];

/// The header line of `energy.csv` in dimension `d`: that of [`headers`], followed by
/// [`ENERGY_WATER_COLUMNS`] for a run in water (`water`), then per winch `k` (in the
/// scenario's order, `winches` of them) `winch{k}_supplied`, the energy it supplied since
/// `t = 0` [J] (part of `supplied_energy`), and `winch{k}_dissipated`, the energy its drum's
/// damping and brake dissipated [J] (part of `dissipated_energy`; 0 without a drum with
/// dynamics).
pub fn energy_header(d: usize, water: bool, winches: usize) -> String {
    let (mut energy, _, _) = headers(d);
    if water {
        for c in ENERGY_WATER_COLUMNS {
            energy.push(',');
            energy.push_str(c);
        }
    }
    for k in 0..winches {
        energy.push_str(&format!(",winch{k}_supplied,winch{k}_dissipated"));
    }
    energy
}

/// Stem of the plot of where the energy of a run in water went (`.svg` and `.png`): the
/// running totals of every supply and dissipation against time.
pub const ENERGY_SPLIT_STEM: &str = "energy_split";

/// The header line of [`ELEMENTS_FILE`]: one row per element `e = [node_a, node_b]` of the
/// mesh (node indices as in `positions.csv`), its group index (the ParaView cell array
/// `string`), the group's kind (`string` or `spring`), its reference length `l_e` [m]
/// (springs: 1, their rest length is a parameter of their law) and the group's name.
pub fn elements_header() -> &'static str {
    "element,node_a,node_b,group,kind,reference_length,group_name"
}

/// Files of one run, directly in its folder (and the temporary files of
/// [`TEMP_FILES`]).
pub const RUN_FILES: &[&str] = &[
    ENERGY_FILE,
    POSITIONS_FILE,
    PORTS_FILE,
    SUMMARY_FILE,
    CHECKPOINT,
    RUN_ID_FILE,
    "energy.svg",
    "energy.png",
    "configuration.svg",
    "configuration.png",
    "increments.svg",
    "increments.png",
    "energy_split.svg",
    "energy_split.png",
    END_TENSIONS_FILE,
    "fairlead_tension.svg",
    "fairlead_tension.png",
    "winch_length.svg",
    "winch_length.png",
    "winch_tension.svg",
    "winch_tension.png",
    ELEMENTS_FILE,
    POINT_MASSES_FILE,
    ANIMATION_FILE,
    COMPONENTS_FILE,
    SCENARIO_FILE,
    BODIES_FILE,
    WINCHES_FILE,
    WINCH_ARCLENGTH_FILE,
];

/// The channel table's file name when `output.channels_file` gives none.
pub const CHANNELS_FILE: &str = "channels.out";

/// Whether `name` is a channel table's file name (`output.channels_file`): a plain name
/// ending in `.out`, MoorDyn's extension, with something before it.
pub fn is_channel_table(name: &str) -> bool {
    name.len() > 4
        && name.ends_with(".out")
        && !name.contains(['/', '\\'])
        && !name.starts_with('.')
}

/// The ParaView sub-folder of a run.
pub const PARAVIEW_DIR: &str = "paraview";
/// The ParaView collection in [`PARAVIEW_DIR`] (frames are [`frame_name`]).
pub const PVD_FILE: &str = "string.pvd";
/// The ParaView collection of the rigid bodies in [`PARAVIEW_DIR`] (runs with bodies; frames
/// are [`body_frame_name`], at the steps of [`PVD_FILE`]'s).
pub const BODIES_PVD_FILE: &str = "bodies.pvd";
/// Run sub-folders of `phstring paper`.
pub const PAPER_RUN_DIRS: &[&str] = &["dg", "mp"];
/// Figure sub-folder of `phstring paper`.
pub const FIGURES_DIR: &str = "figures";
/// Figures of `phstring paper` in [`FIGURES_DIR`], without their extension: Fig. 2 to 5 of
/// the paper (configurations, energies, Hamiltonian, increments).
pub const PAPER_FIGURE_STEMS: [&str; 4] = [
    "fig2_configurations",
    "fig3_energies",
    "fig4_hamiltonian",
    "fig5_increments",
];
/// Figures of `phstring paper` in [`FIGURES_DIR`]: [`PAPER_FIGURE_STEMS`] as `.svg` and
/// `.png`.
pub const PAPER_FIGURES: &[&str] = &[
    "fig2_configurations.svg",
    "fig2_configurations.png",
    "fig3_energies.svg",
    "fig3_energies.png",
    "fig4_hamiltonian.svg",
    "fig4_hamiltonian.png",
    "fig5_increments.svg",
    "fig5_increments.png",
];
/// The table of `phstring sweep`.
pub const SWEEP_TABLE: &str = "sweep.csv";
/// The campaign table of a `phstring sweep` over a MoorDyn deck: the extremes of every
/// line of every run (docs/moordyn.md, "Campaigns").
pub const CAMPAIGN_TABLE: &str = "campaign.csv";
/// The lock file of an output folder in use (held by the folder preparation of the command
/// drivers); it is not an output and is never removed.
pub const LOCK_FILE: &str = ".phstring.lock";

/// Name of the ParaView frame of step `step`.
pub fn frame_name(step: usize) -> String {
    format!("frame_{step:06}.vtp")
}

/// Name of the ParaView frame of the rigid bodies at step `step`.
pub fn body_frame_name(step: usize) -> String {
    format!("bodies_{step:06}.vtp")
}

/// Name of the ParaView frame of mode `number` (1-based) of `phstring modes`.
pub fn mode_frame_name(number: usize) -> String {
    format!("mode_{number:03}.vtp")
}

/// Name of the folder of sweep run `index`.
pub fn run_dir_name(index: usize) -> String {
    format!("run_{index:03}")
}

/// Longest label of a sweep run's folder name ([`case_dir_name`]), in characters.
pub const CASE_LABEL_CHARS: usize = 40;

/// Name of the folder of sweep run `index` labelled `label` (e.g. the stem of its motion
/// table): `run_007_surge5`, the label's characters other than ASCII letters, digits, `-`
/// and `.` replaced by `_` and cut to [`CASE_LABEL_CHARS`]; [`run_dir_name`] for an empty
/// label.
pub fn case_dir_name(index: usize, label: &str) -> String {
    let label: String = label
        .chars()
        .take(CASE_LABEL_CHARS)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if label.is_empty() {
        run_dir_name(index)
    } else {
        format!("{}_{label}", run_dir_name(index))
    }
}

/// Name of the file in an output folder that holds the id of the run writing it.
pub const RUN_ID_FILE: &str = ".phstring-run";

/// Whether `id` can be a run id: 1 to 64 ASCII letters and digits.
pub fn is_valid_run_id(id: &str) -> bool {
    !id.is_empty() && id.len() <= 64 && id.chars().all(|c| c.is_ascii_alphanumeric())
}

/// A new run id: a hash of the time, the process id, a counter and the output folder.
pub fn new_run_id(out: &Path) -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let mut h = fnv::FnvHasher::default();
    h.write(&nanos.to_le_bytes());
    h.write(&std::process::id().to_le_bytes());
    h.write(&COUNTER.fetch_add(1, Ordering::Relaxed).to_le_bytes());
    h.write(out.as_os_str().as_encoded_bytes());
    format!("{:016x}", h.finish())
}

/// The run id recorded in output folder `dir` ([`RUN_ID_FILE`]), if any.
pub fn read_run_id(dir: &Path) -> Option<String> {
    let mut text = String::new();
    std::fs::File::open(dir.join(RUN_ID_FILE))
        .ok()?
        .take(256)
        .read_to_string(&mut text)
        .ok()?;
    let id = text.trim();
    Some(if is_valid_run_id(id) {
        id.to_string()
    } else {
        "(unreadable)".to_string()
    })
}

/// A number as the output files write it (CSV rows, JSON summaries, matrices): the shortest
/// decimal form that reads back to the same `f64` (round-trip exact), in plain notation for
/// magnitudes from 1e-5 to 1e16 and scientific notation (`e`, no `+`) beyond:
/// `0.1`, `-909926.4183654375`, `1.2e-7`, `1e300`; zero is written `0`, and the non-finite
/// values `NaN`, `inf`, `-inf`.
pub fn num(x: f64) -> String {
    let mut out = Vec::with_capacity(24);
    push_num(&mut out, x);
    // Only ASCII is ever pushed.
    String::from_utf8(out).unwrap_or_default()
}

/// Appends [`num`]`(x)` to `out`.
pub fn push_num(out: &mut Vec<u8>, x: f64) {
    if x == 0.0 {
        out.push(b'0');
    } else if x.is_finite() {
        out.extend_from_slice(ryu::Buffer::new().format_finite(x).as_bytes());
    } else if x.is_nan() {
        out.extend_from_slice(b"NaN");
    } else if x > 0.0 {
        out.extend_from_slice(b"inf");
    } else {
        out.extend_from_slice(b"-inf");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn numbers_are_written_as_documented() {
        let cases = [
            (0.1, "0.1"),
            (-909926.4183654375, "-909926.4183654375"),
            (1.2e-7, "1.2e-7"),
            (1e300, "1e300"),
            (-2.5e17, "-2.5e17"),
            (0.0, "0"),
            (-0.0, "0"),
            (f64::NAN, "NaN"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
        ];
        for (x, text) in cases {
            assert_eq!(num(x), text, "{x:e}");
        }
    }

    proptest! {
        /// Every finite number reads back to itself, with no `+` in its exponent, in plain
        /// notation at ordinary magnitudes and in scientific notation far from them.
        #[test]
        fn numbers_read_back_exactly(bits in any::<u64>(), ordinary in -1e15f64..1e15, small in -1e-3f64..1e-3) {
            for x in [f64::from_bits(bits), ordinary, small] {
                number_reads_back(x)?;
            }
        }
    }

    /// The checks of `numbers_read_back_exactly` on one number `x`.
    fn number_reads_back(x: f64) -> Result<(), TestCaseError> {
        if x.is_finite() && x != 0.0 {
            let text = num(x);
            prop_assert_eq!(text.parse::<f64>().unwrap(), x);
            prop_assert!(!text.contains('+'), "{}", text);
            let a = x.abs();
            if (1e-4..1e15).contains(&a) {
                prop_assert!(!text.contains('e'), "{}", text);
            }
            if !(1e-6..1e17).contains(&a) {
                prop_assert!(text.contains('e'), "{}", text);
            }
        }
        Ok(())
    }

    #[test]
    fn paper_figures_are_their_stems_as_svg_and_png() {
        let named: Vec<String> = PAPER_FIGURE_STEMS
            .iter()
            .flat_map(|s| [format!("{s}.svg"), format!("{s}.png")])
            .collect();
        assert_eq!(named, PAPER_FIGURES);
    }

    #[test]
    fn a_dry_energy_header_is_the_old_one_and_water_appends_its_columns() {
        for d in 1..=3 {
            let dry = headers(d).0;
            assert_eq!(energy_header(d, false, 0), dry);
            assert_eq!(
                energy_header(d, true, 0),
                format!("{dry},{}", ENERGY_WATER_COLUMNS.join(","))
            );
        }
        assert!(RUN_FILES.contains(&format!("{ENERGY_SPLIT_STEM}.png").as_str()));
        assert!(RUN_FILES.contains(&format!("{ENERGY_SPLIT_STEM}.svg").as_str()));
        for stem in [WINCH_LENGTH_STEM, WINCH_TENSION_STEM] {
            for ext in ["svg", "png"] {
                assert!(RUN_FILES.contains(&format!("{stem}.{ext}").as_str()));
            }
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
}
