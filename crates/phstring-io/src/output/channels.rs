//! The MoorDyn-style channel table (`output.channels`, a deck's OUTPUTS section): one
//! column per channel in MoorDyn's `.out` layout, so that readers of MoorDyn's main output
//! file read it unchanged.
//!
//! Layout, as MoorDyn writes it: a title row (`Time`, then the channel names as written),
//! a units row (`(s)`, then `m`, `m/s` or `N`), then one row per output time; the time
//! right-aligned in 10 characters with 4 decimals, each value right-aligned in 20
//! characters in scientific notation with 7 decimals (`9.0982030e+05`).
//!
//! What a channel reads (see [`crate::channels`] for the names):
//!
//! - the tension at an end node (`FairTen`, `AnchTen`, node 0 or the last node, `TA`,
//!   `TB`) and the end node's `FX FY FZ` are the force of the line on its end node, as
//!   `end_tensions.csv` (the end segment's tension, half a segment's wet weight and the
//!   node's seabed contact; see [`super::EndForces`]) — MoorDyn's `Fnet` of the end node;
//! - the tension at an interior node is the magnitude of the mean of its two segments'
//!   tension vectors, as MoorDyn's;
//! - a point's `T` and `FX FY FZ` are the sum of the forces of the lines attached to it;
//!   for a fixed or coupled point of zero mass that is MoorDyn's `Fnet`;
//! - positions and velocities are the node's.
//!
//! Material damping and drag are left out of the forces, as in `end_tensions.csv`.

use phstring::{Material, Simulation, Vector};

use super::EndForces;
use crate::channels::{Channel, LineNode, Object, Quantity};

/// Width of the time column.
const TIME_WIDTH: usize = 10;
/// Width of each channel column.
const WIDTH: usize = 20;
/// Decimals of the channel values (scientific notation).
const DECIMALS: usize = 7;

/// A string as the channels see it: its path nodes (MoorDyn's nodes 0 … N) and how its
/// elements are laid along them.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelString {
    /// Mesh nodes of its path (MoorDyn's nodes 0, 1, …, N of the line).
    pub path_nodes: Vec<usize>,
    /// First element.
    pub first_element: usize,
    /// Elements between consecutive path nodes.
    pub elements_per_span: usize,
}

/// What one column reads.
#[derive(Debug, Clone, PartialEq)]
enum Column {
    Position(usize, usize),
    Velocity(usize, usize),
    /// Force of string `s` on its end `e` (0: A, 1: B); component or magnitude (`None`).
    End(usize, usize, Option<usize>),
    /// Mean tension vector of two elements of group `g`, magnitude.
    Interior(usize, [usize; 2]),
    /// Sum of the forces of `(string, end)` on a point; component or magnitude.
    Point(Vec<(usize, usize)>, Option<usize>),
}

/// The channel table of a run: its columns and how each is computed.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelTable {
    names: Vec<String>,
    units: Vec<&'static str>,
    columns: Vec<Column>,
    ends: EndForces,
}

impl ChannelTable {
    /// The table of `channels` over the strings `strings` (line `i` is `strings[i − 1]`),
    /// with `point(k)` the mesh node of point `k` (`None`: no such point) and `ends` the
    /// end forces of the same strings in the same order. An error names the channel's
    /// index and what it asks for that does not exist or is not written.
    pub fn new(
        channels: &[Channel],
        strings: &[ChannelString],
        point: impl Fn(u32) -> Option<usize>,
        ends: EndForces,
    ) -> Result<Self, (usize, String)> {
        let end_nodes = ends.end_nodes();
        let groups: Vec<usize> = (0..end_nodes.len()).map(|s| ends.group(s)).collect();
        let columns = channels
            .iter()
            .enumerate()
            .map(|(i, c)| column(c, strings, &groups, &point, &end_nodes).map_err(|e| (i, e)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            names: channels.iter().map(|c| c.name.clone()).collect(),
            units: channels.iter().map(|c| c.quantity.unit()).collect(),
            columns,
            ends,
        })
    }

    /// The two title rows (names, then units), without the final line break.
    pub fn header(&self) -> String {
        header(&self.names, &self.units)
    }

    /// The channel values in the state of `sim`, in column order.
    pub fn values<const D: usize>(&self, sim: &Simulation<D, Material>) -> Vec<f64> {
        let forces = self.ends.forces(sim);
        let st = sim.state();
        let pick = |f: Vector<D>, k: Option<usize>| match k {
            Some(k) if k < D => f[k],
            Some(_) => 0.0,
            None => f.norm(),
        };
        self.columns
            .iter()
            .map(|c| match c {
                Column::Position(n, k) => component(&st.r[*n], *k),
                Column::Velocity(n, k) => component(&st.v[*n], *k),
                Column::End(s, e, k) => pick(forces[*s][*e], *k),
                Column::Point(list, k) => {
                    let sum = list
                        .iter()
                        .fold(Vector::<D>::zeros(), |acc, (s, e)| acc + forces[*s][*e]);
                    pick(sum, *k)
                }
                Column::Interior(g, [a, b]) => {
                    (element_tension(sim, *g, *a) + element_tension(sim, *g, *b)).norm() * 0.5
                }
            })
            .collect()
    }

    /// One row of the table at time `t` [s] in the state of `sim`, and its values.
    pub fn row<const D: usize>(&self, t: f64, sim: &Simulation<D, Material>) -> (String, Vec<f64>) {
        let values = self.values(sim);
        (row(t, &values), values)
    }
}

/// The two title rows of a table of channels `names` in `units`, without the final line
/// break.
fn header(names: &[String], units: &[&str]) -> String {
    let mut title = format!("{:>TIME_WIDTH$}", "Time");
    let mut unit_row = format!("{:>TIME_WIDTH$}", "(s)");
    for (n, u) in names.iter().zip(units) {
        cell(&mut title, n);
        cell(&mut unit_row, u);
    }
    format!("{title}\n{unit_row}")
}

/// The row of the values `values` at time `t` [s].
fn row(t: f64, values: &[f64]) -> String {
    let mut row = format!("{t:>TIME_WIDTH$.4}");
    for v in values {
        cell(&mut row, &scientific(*v));
    }
    row
}

/// Appends `text` to `row` right-aligned in a column of [`WIDTH`] characters, after a space
/// when it fills the column, so that every column is separated from the one before it
/// (channel names may be longer than the column).
fn cell(row: &mut String, text: &str) {
    if text.chars().count() >= WIDTH {
        row.push(' ');
    }
    row.push_str(&format!("{text:>WIDTH$}"));
}

/// Component `k` of `x` (0 past the dimension: a 2D run has no `z`).
fn component<const D: usize>(x: &Vector<D>, k: usize) -> f64 {
    if k < D { x[k] } else { 0.0 }
}

/// The tension vector [N] of element `e` of group `g`, from its first node to its second.
fn element_tension<const D: usize>(sim: &Simulation<D, Material>, g: usize, e: usize) -> Vector<D> {
    let [a, b] = sim.system().mesh().elements()[e];
    super::ends::element_pull(sim, g, e, a, b)
}

/// `x` as MoorDyn writes it: 7 decimals and a signed exponent of at least two digits
/// (`-5.3525604e+05`).
fn scientific(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let s = format!("{x:.DECIMALS$e}");
    let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let sign = if exp < 0 { '-' } else { '+' };
    format!("{mantissa}e{sign}{:02}", exp.abs())
}

/// The column of channel `c`.
fn column(
    c: &Channel,
    strings: &[ChannelString],
    groups: &[usize],
    point: &impl Fn(u32) -> Option<usize>,
    end_nodes: &[[usize; 2]],
) -> Result<Column, String> {
    let comp = |q: Quantity| match q {
        Quantity::Force(k) => Some(k),
        _ => None,
    };
    match c.object {
        Object::Line(i, node) => {
            let s = usize::try_from(i).unwrap_or(usize::MAX) - 1;
            let string = strings.get(s).ok_or_else(|| {
                format!(
                    "{} reads line {i}, but there are {} lines",
                    c.name,
                    strings.len()
                )
            })?;
            let last = string.path_nodes.len() - 1;
            let j = match node {
                LineNode::EndB => last,
                LineNode::Index(j) => usize::try_from(j).unwrap_or(usize::MAX),
            };
            if j > last {
                return Err(format!(
                    "{} reads node {j} of line {i}, which has nodes 0 to {last}",
                    c.name
                ));
            }
            let end = if j == 0 {
                Some(0)
            } else if j == last {
                Some(1)
            } else {
                None
            };
            let mesh_node = string.path_nodes[j];
            Ok(match (c.quantity, end) {
                (Quantity::Position(k), _) => Column::Position(mesh_node, k),
                (Quantity::Velocity(k), _) => Column::Velocity(mesh_node, k),
                (Quantity::TensionA, _) => Column::End(s, 0, None),
                (Quantity::TensionB, _) => Column::End(s, 1, None),
                (Quantity::Tension | Quantity::Force(_), Some(e)) => {
                    Column::End(s, e, comp(c.quantity))
                }
                (Quantity::Tension, None) => {
                    let after = string.first_element + j * string.elements_per_span;
                    let g = *groups
                        .get(s)
                        .ok_or_else(|| format!("{}: line {i} has no end forces", c.name))?;
                    Column::Interior(g, [after - 1, after])
                }
                (Quantity::Force(_), None) => {
                    return Err(format!("{}: {}", c.name, crate::channels::INTERIOR_FORCE));
                }
                (Quantity::NotWritten(why), _) => return Err(format!("{}: {why}", c.name)),
            })
        }
        Object::Point(k) => {
            let node = point(k)
                .ok_or_else(|| format!("{} reads point {k}, which is not in the run", c.name))?;
            let attached: Vec<(usize, usize)> = end_nodes
                .iter()
                .enumerate()
                .flat_map(|(s, ends)| {
                    ends.iter()
                        .enumerate()
                        .filter(move |(_, n)| **n == node)
                        .map(move |(e, _)| (s, e))
                })
                .collect();
            Ok(match c.quantity {
                Quantity::Position(k) => Column::Position(node, k),
                Quantity::Velocity(k) => Column::Velocity(node, k),
                Quantity::Tension | Quantity::Force(_) => Column::Point(attached, comp(c.quantity)),
                Quantity::TensionA | Quantity::TensionB => {
                    return Err(format!("{}: TA and TB are line channels", c.name));
                }
                Quantity::NotWritten(why) => return Err(format!("{}: {why}", c.name)),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values are written as MoorDyn writes them.
    #[test]
    fn values_are_written_in_moordyns_notation() {
        assert_eq!(scientific(909_820.3), "9.0982030e+05");
        assert_eq!(scientific(-535_256.04), "-5.3525604e+05");
        assert_eq!(scientific(-70.0), "-7.0000000e+01");
        assert_eq!(scientific(0.0), "0.0000000e+00");
        assert_eq!(scientific(1.5e-120), "1.5000000e-120");
        assert_eq!(format!("{:>TIME_WIDTH$.4}", 1.502), "    1.5020");
    }

    /// Names as long as the column or longer (the deck reader accepts them) stay separated
    /// from their neighbours: the title row, the units row and every value row have as
    /// many whitespace-separated fields, one per channel and the time; names shorter than
    /// the column keep MoorDyn's layout.
    #[test]
    fn long_channel_names_stay_separated_from_their_neighbours() {
        let names: Vec<String> = [
            "FairTen000000000000000001",
            "Point0000000000000002PX",
            "L1N0000000000000010T",
            "AnchTen1",
        ]
        .map(String::from)
        .to_vec();
        let units = ["N", "m", "N", "N"];
        let head = header(&names, &units);
        let rows: Vec<&str> = head.lines().collect();
        let title: Vec<&str> = rows[0].split_whitespace().collect();
        assert_eq!(title[0], "Time");
        assert_eq!(
            title[1..],
            names.iter().map(String::as_str).collect::<Vec<_>>()[..]
        );
        assert_eq!(rows[1].split_whitespace().count(), 5, "{}", rows[1]);
        for t in [0.0, 1.502, 123_456.75] {
            let values = [-5.3525604e5, 1.5e-120, -1.0e300, f64::NAN];
            let r = row(t, &values);
            let fields: Vec<f64> = r.split_whitespace().map(|f| f.parse().unwrap()).collect();
            assert_eq!(fields.len(), title.len(), "{r}");
            assert_eq!(fields[0], t);
            assert_eq!(fields[1], -5.3525604e5);
        }
        // A short name keeps its 20-character column.
        let short = header(&["AnchTen1".to_string()], &["N"]);
        assert_eq!(
            short,
            format!("      Time{:>20}\n       (s){:>20}", "AnchTen1", "N")
        );
    }
}
