//! Reading a run's outputs back: the energies of `energy.csv` for the plots ([`read_history`],
//! decimated to a bounded [`History`]) and the network's drawing from `elements.csv` and
//! `point_masses.csv` ([`read_topology`]).

use std::fs::File;
use std::io::BufRead;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::files::{ELEMENTS_FILE, POINT_MASSES_FILE};
use crate::output::OutputError;
use crate::plot::{GroupDrawing, Topology};

/// Inverse of [`csv_text`] for a field that ends its row.
fn csv_untext(field: &str) -> String {
    match field.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
        Some(inner) => inner.replace("\"\"", "\""),
        None => field.to_string(),
    }
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
                    crate::text::sanitize_text(fields[k], 40)
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
                    crate::text::sanitize_text(other, 40)
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
    rows_until(path, f, |number, text| {
        row(number, text).map(|()| ControlFlow::Continue(()))
    })
    .map(|_| ())
}

/// Calls `row(line number, text)` for the rows of the CSV file `f` after its header, until
/// it breaks; returns whether it did.
fn rows_until(
    path: &Path,
    f: File,
    mut row: impl FnMut(usize, &str) -> Result<ControlFlow<()>, OutputError>,
) -> Result<ControlFlow<()>, OutputError> {
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
            return Ok(ControlFlow::Continue(()));
        }
        number += 1;
        if number > 1 && row(number, line.trim_end_matches(['\n', '\r']))?.is_break() {
            return Ok(ControlFlow::Break(()));
        }
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
    /// The running totals of a run in water (`energy.csv` with the water columns), `None`
    /// for a dry run.
    pub water: Option<WaterHistory>,
}

/// The running totals of a run in water read back from `energy.csv` for the plot of where
/// the energy went, decimated like [`History`]: all series at the same rows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WaterHistory {
    /// Times [s] of the rows kept.
    pub t: Vec<f64>,
    /// `Ĥ(t) − Ĥ(0)` [J]: the energy stored since the start.
    pub stored: Vec<f64>,
    /// All energy supplied through the ports [J] (`supplied_energy`, with the current's).
    pub supplied: Vec<f64>,
    /// All energy dissipated [J] (`dissipated_energy`, with the water's).
    pub dissipated: Vec<f64>,
    /// Dissipated by drag [J].
    pub drag: Vec<f64>,
    /// Supplied by the current through the drag [J].
    pub current: Vec<f64>,
    /// Dissipated by the seabed's damping [J].
    pub seabed: Vec<f64>,
    /// Dissipated by seabed friction [J].
    pub friction: Vec<f64>,
}

/// Columns of `energy.csv` read for [`WaterHistory`]: `supplied_energy`,
/// `dissipated_energy`, then the four running totals of the water.
const WATER_COLUMNS: [usize; 6] = [4, 9, 12, 13, 14, 15];

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
    let mut energies = Decimator::<4>::new(max_points);
    let mut increments = Decimator::<2>::new(max_points);
    let mut water = Decimator::<8>::new(max_points);
    // A run in water has the water columns after the 10 of a dry run (and a run with
    // winches two per winch after those): told by the header.
    let wet = {
        use std::io::Read;
        let mut header = String::new();
        let file = File::open(path).map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            cause: source,
        })?;
        std::io::BufReader::new(file.take(4096))
            .read_line(&mut header)
            .map_err(|source| OutputError::Io {
                path: path.to_path_buf(),
                cause: source,
            })?;
        header.trim_end().split(',').any(|c| c == "buoyancy")
    };
    let mut h0: Option<f64> = None;
    let mut prev_h: Option<f64> = None;
    let flow = rows_until(path, f, |number, row| {
        if number % 4096 == 0 && stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Ok(ControlFlow::Break(()));
        }
        let bad = |message: String| OutputError::Read {
            path: path.to_path_buf(),
            line: number,
            message,
        };
        let fields: Vec<&str> = row.trim_end().split(',').collect();
        let parse = |k: usize| -> Result<f64, OutputError> {
            let field = fields
                .get(k)
                .ok_or_else(|| bad(format!("{} fields, expected 10", fields.len())))?;
            field.parse().map_err(|_| {
                bad(format!(
                    "not a number: {}",
                    crate::text::sanitize_text(field, 40)
                ))
            })
        };
        let v = [parse(0)?, parse(1)?, parse(2)?, parse(3)?];
        energies.push(v);
        if wet {
            let start = *h0.get_or_insert(v[3]);
            let mut w = [v[0], v[3] - start, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            for (x, k) in w[2..].iter_mut().zip(WATER_COLUMNS) {
                *x = parse(k)?;
            }
            water.push(w);
        }
        if let Some(p) = prev_h {
            increments.push([v[0], (v[3] - p).abs()]);
        }
        prev_h = Some(v[3]);
        Ok(ControlFlow::Continue(()))
    })?;
    if flow.is_break() {
        return Ok(None);
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
    if wet {
        let mut w = WaterHistory::default();
        for [
            t,
            stored,
            supplied,
            dissipated,
            drag,
            current,
            seabed,
            friction,
        ] in water.finish()
        {
            w.t.push(t);
            w.stored.push(stored);
            w.supplied.push(supplied);
            w.dissipated.push(dissipated);
            w.drag.push(drag);
            w.current.push(current);
            w.seabed.push(seabed);
            w.friction.push(friction);
        }
        h.water = Some(w);
    }
    Ok(Some(h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::elements_header;
    use crate::output::{PLOT_POINTS, Writers, topology};
    use crate::test_util::{named_network, sim};

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
    fn water_totals_are_read_back_for_a_wet_run_only() {
        let dir = crate::test_util::temp_dir("output", "wethistory");
        let mut s = crate::test_util::wet_line();
        let h0 = s.energies().hamiltonian();
        let mut w = Writers::start(&dir, &s, 100, false, false, vec![]).unwrap();
        for _ in 0..20 {
            let r = s.step().unwrap();
            w.step(&s, &r).unwrap();
        }
        w.flush().unwrap();
        let h = read_history(w.energy_path(), PLOT_POINTS, vec![], None)
            .unwrap()
            .unwrap();
        let water = h.water.unwrap();
        assert_eq!(water.t.len(), 21);
        assert_eq!(water.t, h.t);
        let ww = s.water_work();
        let last = |v: &[f64]| *v.last().unwrap();
        assert_eq!(last(&water.drag), ww.drag_dissipated);
        assert_eq!(last(&water.current), ww.current_supplied);
        assert_eq!(last(&water.seabed), ww.seabed_dissipated);
        assert_eq!(last(&water.friction), ww.friction_dissipated);
        assert_eq!(last(&water.supplied), s.supplied_energy());
        assert_eq!(last(&water.dissipated), s.dissipated_energy());
        assert_eq!(last(&water.stored), s.energies().hamiltonian() - h0);
        assert_eq!(water.stored[0], 0.0);
        // A dry run has none.
        let dry = crate::test_util::temp_dir("output", "dryhistory");
        let mut s = sim();
        let mut w = Writers::start(&dry, &s, 1, false, false, vec![]).unwrap();
        let r = s.step().unwrap();
        w.step(&s, &r).unwrap();
        w.flush().unwrap();
        let h = read_history(w.energy_path(), PLOT_POINTS, vec![], None)
            .unwrap()
            .unwrap();
        assert!(h.water.is_none());
        let _ = std::fs::remove_dir_all(&dir);
        let _ = std::fs::remove_dir_all(&dry);
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
        assert!(text.ends_with("\n5,0,2,2,spring,1.0,plain\n"), "{text}");
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
}
