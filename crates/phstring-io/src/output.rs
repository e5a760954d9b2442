//! Output writers of a run: `energy.csv`, `positions.csv`, `ports.csv`, ParaView frames,
//! plots and `summary.json`. Rows are written as the run goes, so everything up to the last
//! good step is on disk when a run fails.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use phstring::{Material, PortKind, Simulation, StepReport, StoredEnergy};

use crate::plot::{self, PlotError, Series};
use crate::vtk::{self, PvdWriter, VtkError};

/// Errors while writing outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A ParaView file failed.
    #[error(transparent)]
    Vtk(#[from] VtkError),
}

/// Formats `x` with 17 significant digits (round-trip exact).
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x:.16e}")
    }
}

struct Csv {
    path: PathBuf,
    w: BufWriter<File>,
}

impl Csv {
    fn create(path: PathBuf, header: &str) -> Result<Self, OutputError> {
        let f = File::create(&path).map_err(|source| OutputError::Io {
            path: path.clone(),
            source,
        })?;
        let mut c = Self {
            path,
            w: BufWriter::new(f),
        };
        c.line(header)?;
        Ok(c)
    }
    fn line(&mut self, s: &str) -> Result<(), OutputError> {
        writeln!(self.w, "{s}").map_err(|source| OutputError::Io {
            path: self.path.clone(),
            source,
        })
    }
    fn flush(&mut self) -> Result<(), OutputError> {
        self.w.flush().map_err(|source| OutputError::Io {
            path: self.path.clone(),
            source,
        })
    }
    /// Opens an existing file, cut back to `len` bytes, for appending.
    fn reopen(path: PathBuf, len: u64) -> Result<Self, OutputError> {
        use std::io::{Seek, SeekFrom};
        let io = |source| OutputError::Io {
            path: path.clone(),
            source,
        };
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .map_err(io)?;
        if f.metadata().map_err(io)?.len() < len {
            return Err(OutputError::Io {
                path: path.clone(),
                source: std::io::Error::other(format!(
                    "shorter than the {len} bytes the checkpoint recorded"
                )),
            });
        }
        f.set_len(len).map_err(io)?;
        f.seek(SeekFrom::End(0)).map_err(io)?;
        Ok(Self {
            path,
            w: BufWriter::new(f),
        })
    }
    /// Bytes written so far (after a flush).
    fn len(&mut self) -> Result<u64, OutputError> {
        self.flush()?;
        self.w
            .get_ref()
            .metadata()
            .map(|m| m.len())
            .map_err(|source| OutputError::Io {
                path: self.path.clone(),
                source,
            })
    }
}

/// Time series kept in memory for the plots.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct History {
    /// Times [s], one per step including `t = 0`.
    pub t: Vec<f64>,
    /// Kinetic energy [J].
    pub kinetic: Vec<f64>,
    /// Potential energy [J].
    pub potential: Vec<f64>,
    /// Hamiltonian [J].
    pub hamiltonian: Vec<f64>,
    /// Configuration snapshots `(t, node positions x, y)` for the configuration plot.
    pub snapshots: Vec<(f64, Vec<[f64; 2]>)>,
}

impl History {
    /// `|Ĥ_{n+1} − Ĥ_n|` per step, at the step end times.
    pub fn increments(&self) -> (Vec<f64>, Vec<f64>) {
        let t = self.t[1..].to_vec();
        let d = self
            .hamiltonian
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .collect();
        (t, d)
    }
}

/// Writes the standard outputs of one run into a folder.
pub struct Writers {
    dir: PathBuf,
    energy: Csv,
    positions: Option<Csv>,
    ports: Csv,
    pvd: Option<PvdWriter>,
    stride: usize,
    snapshot_times: Vec<f64>,
    /// The recorded series.
    pub history: History,
    dim: usize,
    last_frame: Option<usize>,
    frames: Vec<(f64, String)>,
}

impl Writers {
    /// Creates the folder's files and writes the `t = 0` rows.
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
            move |source| OutputError::Io { path: p, source }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let energy = Csv::create(
            dir.join("energy.csv"),
            "t,kinetic,potential,hamiltonian,supplied_energy,balance_error,newton_iterations,newton_residual,h",
        )?;
        let comps = ["x", "y", "z"];
        let positions = if positions {
            let header = format!("t,node,{}", comps[..D].join(","));
            Some(Csv::create(dir.join("positions.csv"), &header)?)
        } else {
            None
        };
        let u: Vec<String> = comps[..D].iter().map(|c| format!("u_{c}")).collect();
        let y: Vec<String> = comps[..D].iter().map(|c| format!("y_{c}")).collect();
        let ports = Csv::create(
            dir.join("ports.csv"),
            &format!("t_mid,port,node,kind,{},{},power", u.join(","), y.join(",")),
        )?;
        let pvd = if vtk_frames {
            let pdir = dir.join("paraview");
            std::fs::create_dir_all(&pdir).map_err(io(&pdir))?;
            Some(PvdWriter::new(&pdir.join("string.pvd")))
        } else {
            None
        };
        let mut w = Self {
            dir: dir.to_path_buf(),
            energy,
            positions,
            ports,
            pvd,
            stride,
            snapshot_times,
            history: History::default(),
            dim: D,
            last_frame: None,
            frames: Vec::new(),
        };
        let e = sim.energies();
        w.energy.line(&format!(
            "{},{},{},{},0,0,0,0,0",
            num(0.0),
            num(e.kinetic),
            num(e.potential()),
            num(e.hamiltonian())
        ))?;
        w.record(sim)?;
        w.frame(sim)?;
        Ok(w)
    }

    fn record<const D: usize>(&mut self, sim: &Simulation<D, Material>) -> Result<(), OutputError> {
        let e = sim.energies();
        let t = sim.time();
        self.history.t.push(t);
        self.history.kinetic.push(e.kinetic);
        self.history.potential.push(e.potential());
        self.history.hamiltonian.push(e.hamiltonian());
        // Each snapshot time once, at the first step that reaches it.
        let next = self.history.snapshots.len();
        if D >= 2
            && self
                .snapshot_times
                .get(next)
                .is_some_and(|&s| t >= s - 1e-9 * sim.params().h)
        {
            let pts = sim.state().r.iter().map(|r| [r[0], r[1]]).collect();
            self.history.snapshots.push((t, pts));
        }
        Ok(())
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
        self.last_frame = Some(sim.steps());
        let t = sim.time();
        let st = sim.state();
        if let Some(p) = &mut self.positions {
            for (i, r) in st.r.iter().enumerate() {
                let comps: Vec<String> = r.iter().map(|x| num(*x)).collect();
                p.line(&format!("{},{i},{}", num(t), comps.join(",")))?;
            }
        }
        if let Some(pvd) = &mut self.pvd {
            let pad = |v: &phstring::Vector<D>| {
                let mut a = [0.0; 3];
                a[..D].copy_from_slice(v.as_slice());
                a
            };
            let points: Vec<[f64; 3]> = st.r.iter().map(pad).collect();
            let vel: Vec<[f64; 3]> = st.v.iter().map(pad).collect();
            let mat = sim.system().material();
            let s: Vec<f64> = st.c.iter().map(|&c| 2.0 * mat.dw(c)).collect();
            let name = format!("frame_{:06}.vtp", sim.steps());
            vtk::write_vtp_segments(
                &self.dir.join("paraview").join(&name),
                &points,
                sim.system().mesh().elements(),
                &vel,
                &[("C", &st.c), ("S", &s)],
            )?;
            pvd.add(t, &name);
            pvd.write()?;
            self.frames.push((t, name));
        }
        Ok(())
    }

    /// Records one step: energy row, port rows, and (every `stride` steps) positions and a
    /// ParaView frame.
    pub fn step<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
        r: &StepReport,
    ) -> Result<(), OutputError> {
        self.energy.line(&format!(
            "{},{},{},{},{},{},{},{},{}",
            num(r.t),
            num(r.after.kinetic),
            num(r.after.potential()),
            num(r.after.hamiltonian()),
            num(sim.supplied_energy()),
            num(r.balance_error),
            r.newton_iterations,
            num(r.residual),
            num(r.h)
        ))?;
        let t_mid = r.t - 0.5 * r.h;
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
        self.record(sim)?;
        self.frame(sim)
    }

    /// Reopens the outputs of an interrupted run in `dir` at the state a checkpoint recorded
    /// (files longer than recorded are cut back), to continue appending.
    pub fn resume(
        dir: &Path,
        dim: usize,
        stride: usize,
        vtk_frames: bool,
        snapshot_times: Vec<f64>,
        state: crate::checkpoint::OutputState,
    ) -> Result<Self, OutputError> {
        let positions = match state.positions_bytes {
            Some(n) => Some(Csv::reopen(dir.join("positions.csv"), n)?),
            None => None,
        };
        let pvd = if vtk_frames {
            let mut p = PvdWriter::new(&dir.join("paraview").join("string.pvd"));
            for (t, name) in &state.frames {
                p.add(*t, name);
            }
            Some(p)
        } else {
            None
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: Csv::reopen(dir.join("energy.csv"), state.energy_bytes)?,
            positions,
            ports: Csv::reopen(dir.join("ports.csv"), state.ports_bytes)?,
            pvd,
            stride,
            snapshot_times,
            history: state.history,
            dim,
            last_frame: state.last_frame,
            frames: state.frames,
        })
    }

    /// The output state for a checkpoint (flushes all files).
    pub fn state(&mut self) -> Result<crate::checkpoint::OutputState, OutputError> {
        Ok(crate::checkpoint::OutputState {
            energy_bytes: self.energy.len()?,
            positions_bytes: match &mut self.positions {
                Some(p) => Some(p.len()?),
                None => None,
            },
            ports_bytes: self.ports.len()?,
            frames: self.frames.clone(),
            last_frame: self.last_frame,
            history: self.history.clone(),
        })
    }

    /// Writes the final state (positions and ParaView frame) if the last step was not on
    /// the output stride, then flushes all CSV files.
    pub fn finish<const D: usize>(
        &mut self,
        sim: &Simulation<D, Material>,
    ) -> Result<(), OutputError> {
        self.frame_if(sim, true)?;
        self.flush()
    }

    /// Flushes all CSV files.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        self.energy.flush()?;
        self.ports.flush()?;
        if let Some(p) = &mut self.positions {
            p.flush()?;
        }
        Ok(())
    }

    /// Draws `energy`, `configuration` and `increments` plots (SVG and PNG). Returns the
    /// files written.
    pub fn plots(
        &self,
        title: &str,
        end_of_loading: Option<f64>,
    ) -> Result<Vec<String>, OutputError> {
        let h = &self.history;
        let mut written = Vec::new();
        plot::energy_plot(
            &self.dir.join("energy"),
            title,
            &h.t,
            &h.kinetic,
            &h.potential,
            &h.hamiltonian,
        )?;
        written.push("energy".to_string());
        if self.dim >= 2 && !h.snapshots.is_empty() {
            plot::configuration_plot(&self.dir.join("configuration"), title, &h.snapshots)?;
            written.push("configuration".to_string());
        }
        let (ti, inc) = h.increments();
        plot::series_plot(
            &self.dir.join("increments"),
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
        )?;
        written.push("increments".to_string());
        Ok(written)
    }
}
