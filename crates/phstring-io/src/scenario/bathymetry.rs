//! The bathymetry file of `seabed.bathymetry` (docs/scenario.md, "Bathymetry grid"): a CSV
//! table of seabed depths [m] (positive down), read into the library's [`Bathymetry`].
//!
//! In 2D, rows `x, depth` (an optional header line such as `x,depth` first); in 3D, a header
//! row `label, x₁, x₂, …` and then rows `y, depth at x₁, depth at x₂, …`. Blank lines and
//! lines starting with `#` are skipped; cells are separated by commas.

use std::path::Path;

use phstring::Bathymetry;

use crate::text::num;

/// Largest bathymetry file read [bytes] (64 MiB: a grid of a few million depths).
pub const MAX_BATHYMETRY_BYTES: u64 = 64 << 20;

/// Reads the bathymetry file at `path` for dimension `dimension` (2 or 3). Errors name the
/// file and, for a bad cell or row, its line.
pub(super) fn read(path: &Path, dimension: usize) -> Result<Bathymetry, String> {
    use std::io::Read as _;
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {name}: {e}"))?;
    let mut text = String::new();
    file.take(MAX_BATHYMETRY_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(|e| format!("cannot read {name}: {e}"))?;
    if text.len() as u64 > MAX_BATHYMETRY_BYTES {
        return Err(format!(
            "{name} is larger than {} MiB",
            MAX_BATHYMETRY_BYTES >> 20
        ));
    }
    parse(&text, &name, dimension)
}

/// The data lines of `text`: `(line number, cells)`, comments and blank lines skipped.
fn rows(text: &str) -> impl Iterator<Item = (usize, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, line)| {
        let t = line.trim();
        (!t.is_empty() && !t.starts_with('#'))
            .then(|| (i + 1, t.split(',').map(str::trim).collect()))
    })
}

/// Cell `k` (0-based) of line `line` as a finite number.
fn number(name: &str, line: usize, k: usize, cell: &str, what: &str) -> Result<f64, String> {
    match cell.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(format!(
            "{name}:{line}: cell {} ({what}) is {}, not a finite number",
            k + 1,
            num(v)
        )),
        Err(_) => Err(format!(
            "{name}:{line}: cell {} ({what}) `{cell}` is not a number",
            k + 1
        )),
    }
}

/// Checks that `v` (at `line`) is above the coordinate before it (at `prev_line`).
fn increasing(
    name: &str,
    axis: &str,
    (line, v): (usize, f64),
    prev: Option<(usize, f64)>,
) -> Result<(), String> {
    match prev {
        Some((pl, p)) if v <= p => Err(format!(
            "{name}:{line}: {axis} = {} is not above the {axis} before it ({} on line {pl}): the coordinates must increase",
            num(v),
            num(p)
        )),
        _ => Ok(()),
    }
}

/// Parses the table `text` (named `name` in messages) for dimension `dimension`.
pub(super) fn parse(text: &str, name: &str, dimension: usize) -> Result<Bathymetry, String> {
    let bathy = if dimension == 2 {
        parse_profile(text, name)?
    } else {
        parse_grid(text, name)?
    };
    // The table's own checks above name the line; the library's are a backstop.
    bathy.map_err(|e| format!("{name}: {e}"))
}

type Parsed = Result<Result<Bathymetry, phstring::SetupError>, String>;

/// 2D: rows `x, depth`, an optional header first.
fn parse_profile(text: &str, name: &str) -> Parsed {
    let (mut x, mut depth) = (Vec::new(), Vec::new());
    let mut prev = None;
    for (k, (line, cells)) in rows(text).enumerate() {
        if k == 0 && cells[0].parse::<f64>().is_err() {
            continue; // the header
        }
        if cells.len() != 2 {
            return Err(format!(
                "{name}:{line}: has {} cells; each row is `x, depth` (2D)",
                cells.len()
            ));
        }
        let xv = number(name, line, 0, cells[0], "x [m]")?;
        increasing(name, "x", (line, xv), prev)?;
        prev = Some((line, xv));
        x.push(xv);
        depth.push(number(name, line, 1, cells[1], "depth [m]")?);
    }
    if x.len() < 2 {
        return Err(format!(
            "{name}: has {} rows of `x, depth`; a profile needs at least 2",
            x.len()
        ));
    }
    Ok(Bathymetry::profile(x, depth))
}

/// 3D: a header `label, x₁, …` and rows `y, depth…`.
fn parse_grid(text: &str, name: &str) -> Parsed {
    let mut lines = rows(text);
    let Some((hl, header)) = lines.next() else {
        return Err(format!(
            "{name}: is empty; a grid has a header row `label, x1, x2, …` and rows `y, depths…`"
        ));
    };
    let mut x = Vec::with_capacity(header.len().saturating_sub(1));
    for (k, cell) in header.iter().enumerate().skip(1) {
        let v = number(name, hl, k, cell, "x [m] of the header")?;
        increasing(name, "x", (hl, v), x.last().map(|&p| (hl, p)))?;
        x.push(v);
    }
    if x.len() < 2 {
        return Err(format!(
            "{name}:{hl}: the header has {} x coordinates; a grid needs at least 2 (`label, x1, x2, …`)",
            x.len()
        ));
    }
    let (mut y, mut depth) = (Vec::new(), Vec::new());
    let mut prev = None;
    for (line, cells) in lines {
        if cells.len() != x.len() + 1 {
            return Err(format!(
                "{name}:{line}: has {} cells; the header has {} x coordinates, so each row is `y` and {} depths",
                cells.len(),
                x.len(),
                x.len()
            ));
        }
        let yv = number(name, line, 0, cells[0], "y [m]")?;
        increasing(name, "y", (line, yv), prev)?;
        prev = Some((line, yv));
        y.push(yv);
        for (k, cell) in cells.iter().enumerate().skip(1) {
            depth.push(number(name, line, k, cell, "depth [m]")?);
        }
    }
    if y.len() < 2 {
        return Err(format!(
            "{name}: has {} rows of depths; a grid needs at least 2 (one per y)",
            y.len()
        ));
    }
    Ok(Bathymetry::grid(x, y, depth))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid and a profile are read as written; comments, blanks and spaces are skipped.
    #[test]
    fn reads_grids_and_profiles() {
        let g = parse(
            "# depths [m]\ny\\x, 0, 50, 100\n-20, 150, 140.5, 130\n\n20, 151, 141, 131\n",
            "b.csv",
            3,
        )
        .unwrap();
        assert_eq!(g.x(), &[0.0, 50.0, 100.0]);
        assert_eq!(g.y(), &[-20.0, 20.0]);
        assert_eq!(g.depths(), &[150.0, 140.5, 130.0, 151.0, 141.0, 131.0]);
        assert!((g.depth_at(50.0, 20.0) - 141.0).abs() < 1e-12);
        let p = parse("x,depth\n0,120\n100,110\n", "p.csv", 2).unwrap();
        assert!(p.is_profile() && p.x() == [0.0, 100.0]);
        // Without a header too.
        assert_eq!(parse("0,120\n100,110\n", "p.csv", 2).unwrap(), p);
    }

    /// Each bad table is refused with the file, the line and the cell.
    #[test]
    fn refuses_bad_tables_naming_the_line() {
        let err = |t: &str, d: usize| parse(t, "b.csv", d).unwrap_err();
        assert_eq!(
            err("x,depth\n0,120\n10,abc\n", 2),
            "b.csv:3: cell 2 (depth [m]) `abc` is not a number"
        );
        assert_eq!(
            err("0,120\n10,NaN\n", 2),
            "b.csv:2: cell 2 (depth [m]) is NaN, not a finite number"
        );
        assert!(
            err("0,120\n10,100\n10,90\n", 2)
                .starts_with("b.csv:3: x = 10 is not above the x before it (10 on line 2)")
        );
        assert_eq!(
            err("x,depth\n0,120\n", 2),
            "b.csv: has 1 rows of `x, depth`; a profile needs at least 2"
        );
        assert!(err("0,120,3\n", 2).starts_with("b.csv:1: has 3 cells"));
        assert!(err("y,0,50\n0,1,2\n5,1\n", 3).starts_with("b.csv:3: has 2 cells"));
        assert!(
            err("y,0,50\n0,1,2\n-5,1,2\n", 3)
                .starts_with("b.csv:3: y = -5 is not above the y before it (0 on line 2)")
        );
        assert!(err("y,0,0\n0,1,2\n5,1,2\n", 3).starts_with("b.csv:1: x = 0 is not above"));
        assert!(err("y,0\n", 3).contains("the header has 1 x coordinates"));
        assert!(err("y,0,1\n0,1,2\n", 3).contains("has 1 rows of depths"));
        assert_eq!(
            err("y,0,1\n0,1,2\n1,1,inf\n", 3),
            "b.csv:3: cell 3 (depth [m]) is inf, not a finite number"
        );
        assert!(err("# nothing\n", 3).contains("is empty"));
    }

    /// `seabed.bathymetry` in a scenario: the file is read next to the scenario and becomes
    /// the seabed (depth 150 m at x = 50, the given value); a bad cell is reported with the
    /// key, the scenario's place and the table's file:line; a plane's keys with it, a missing
    /// file and a grid of the wrong dimension are refused.
    #[test]
    fn the_scenario_key_reads_the_file_next_to_the_scenario() {
        let dir = crate::test_util::temp_dir("bathy", "key");
        let scenario = |seabed: &str, dim: usize| {
            let (gravity, end) = if dim == 2 {
                ("[0.0, -9.81]", "[100.0, -140.0]")
            } else {
                ("[0.0, 0.0, -9.81]", "[100.0, 0.0, -140.0]")
            };
            let start = if dim == 2 {
                "[0.0, -140.0]"
            } else {
                "[0.0, 0.0, -140.0]"
            };
            let text = format!(
                "dimension = {dim}\n[geometry]\nstart = {start}\nend = {end}\n[mesh]\nelements = 10\n\
                 [material]\nlaw = \"linear_elastic\"\nea = 6.0e8\nrho_a = 113.0\ndiameter = 0.1368\n\
                 [body_force]\ngravity = {gravity}\n[water]\n[seabed]\nstiffness = 3.0e6\n{seabed}\n\
                 [[boundary]]\nnode = 0\nfixed = true\n[time]\nh = 0.01\nend = 0.1\n"
            );
            let path = dir.join("s.toml");
            std::fs::write(&path, text).unwrap();
            crate::scenario::load(&path, &[]).unwrap()
        };
        std::fs::write(dir.join("p.csv"), "x,depth\n0,160\n50,150\n100,140\n").unwrap();
        std::fs::write(dir.join("bad.csv"), "x,depth\n0,160\n50,1 50\n").unwrap();
        let v = scenario("bathymetry = \"p.csv\"", 2)
            .validate::<2>()
            .unwrap();
        let water = v.problem.water.as_ref().unwrap();
        let Some(phstring::SeabedSurface::Grid(g)) = water.seabed.as_ref().map(|s| &s.surface)
        else {
            panic!("not a grid: {water:?}");
        };
        assert_eq!(g.depth_at(50.0, 0.0), 150.0);
        let e = scenario("bathymetry = \"bad.csv\"", 2)
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.toml:")
                && e.contains("`seabed.bathymetry`")
                && e.contains("bad.csv:3: cell 2 (depth [m]) `1 50` is not a number"),
            "{e}"
        );
        let e = scenario("bathymetry = \"p.csv\"\nnormal = [0.0, 1.0]", 2)
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`seabed.normal` is given with seabed.bathymetry"),
            "{e}"
        );
        let e = scenario("bathymetry = \"none.csv\"", 2)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read") && e.contains("none.csv"), "{e}");
        // A profile in 3D is read as a grid: its header's second cell is no x.
        let e = scenario("bathymetry = \"p.csv\"", 3)
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("p.csv:1: cell 2 (x [m] of the header) `depth` is not a number"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
