//! MoorDyn's output channel names (`FairTen1`, `AnchTen2`, `L1N10T`, `L2NBPZ`, `Point4FX`,
//! `Con3PZ`), read into what they ask for.
//!
//! A name is read, case-insensitively, as letters, digits, letters, digits, letters:
//!
//! - `FairTen<i>` and `AnchTen<i>`: the tension at the fairlead (last node) and the anchor
//!   (node 0) of line `i`.
//! - `L<i>N<j><q>` (also `Line<i>…`): quantity `q` at node `j` of line `i` (0 is the anchor
//!   end `A`, the number of segments the fairlead end `B`); `L<i>NA<q>` and `L<i>NB<q>`
//!   name the end nodes; `L<i><q>` is node 0.
//! - `P<k><q>` (also `Point`, `C`, `Con`, the older `Connect` name): quantity `q` of point
//!   `k`.
//!
//! Quantities: `PX PY PZ` [m], `VX VY VZ` [m/s], `T`/`Ten` [N], `TA`/`TenA` and
//! `TB`/`TenB` [N] (the line's end tensions, whatever the node), `FX FY FZ` [N]. MoorDyn's
//! accelerations, rotations, moments and submerged fraction are recognised and reported as
//! not written ([`Quantity::NotWritten`]).

/// Why a force channel at an interior node of a line is not written.
pub const INTERIOR_FORCE: &str = "the net force on an interior node is its inertia; phstring writes forces at the line's end nodes only";

/// The object a channel reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Object {
    /// Line `i` (1-based), at a node.
    Line(u32, LineNode),
    /// Point `k` (1-based).
    Point(u32),
}

/// A node of a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineNode {
    /// Node `j` (0: the anchor end `A`).
    Index(u32),
    /// The fairlead end `B` (the line's last node, whatever its number).
    EndB,
}

/// What a channel reads at its object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Position component 0, 1, 2 (x, y, z) [m].
    Position(usize),
    /// Velocity component [m/s].
    Velocity(usize),
    /// Tension [N]: at an end node (and of a point) the magnitude of the force of the
    /// line(s) on the node; at an interior node the magnitude of the mean of the two
    /// adjacent segments' tension vectors.
    Tension,
    /// The magnitude of the force of the line on its anchor end `A` [N].
    TensionA,
    /// The magnitude of the force of the line on its fairlead end `B` [N].
    TensionB,
    /// Force component [N] (see [`Quantity::Tension`] for which force).
    Force(usize),
    /// A MoorDyn quantity that phstring does not write, with the reason.
    NotWritten(&'static str),
}

impl Quantity {
    /// The unit as MoorDyn's `.out` header writes it.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::Position(_) => "m",
            Quantity::Velocity(_) => "m/s",
            Quantity::Tension | Quantity::TensionA | Quantity::TensionB | Quantity::Force(_) => "N",
            Quantity::NotWritten(_) => "-",
        }
    }
}

/// One channel read from its name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    /// The name as written (the `.out` column title).
    pub name: String,
    /// What it reads.
    pub object: Object,
    /// Which quantity.
    pub quantity: Quantity,
}

/// The name split into letters, digits, letters, digits, letters (upper case).
fn decompose(name: &str) -> [String; 5] {
    let mut parts: [String; 5] = Default::default();
    let mut k = 0;
    for c in name.chars() {
        let digit = c.is_ascii_digit();
        // Parts 0, 2, 4 hold letters, 1 and 3 digits.
        while k < 5 && (k % 2 == 1) != digit {
            k += 1;
        }
        if k == 5 {
            // More parts than the pattern has: keep the rest in the last part so that the
            // quantity is unknown rather than silently shortened.
            parts[4].push(c.to_ascii_uppercase());
            continue;
        }
        parts[k].push(c.to_ascii_uppercase());
    }
    parts
}

/// The quantity named `q` (upper case).
fn quantity(q: &str) -> Option<Quantity> {
    Some(match q {
        "PX" => Quantity::Position(0),
        "PY" => Quantity::Position(1),
        "PZ" => Quantity::Position(2),
        "VX" => Quantity::Velocity(0),
        "VY" => Quantity::Velocity(1),
        "VZ" => Quantity::Velocity(2),
        "T" | "TEN" => Quantity::Tension,
        "TA" | "TENA" => Quantity::TensionA,
        "TB" | "TENB" => Quantity::TensionB,
        "FX" => Quantity::Force(0),
        "FY" => Quantity::Force(1),
        "FZ" => Quantity::Force(2),
        "AX" | "AY" | "AZ" => {
            Quantity::NotWritten("accelerations are not written (the step stores none)")
        }
        "RX" | "RY" | "RZ" | "RVX" | "RVY" | "RVZ" | "RAX" | "RAY" | "RAZ" | "MX" | "MY" | "MZ" => {
            Quantity::NotWritten("lines and points have no rotations or moments")
        }
        "SUB" => Quantity::NotWritten("the submerged fraction is not written"),
        _ => return None,
    })
}

/// A positive 1-based id from its digits.
fn id(digits: &str, what: &str, name: &str) -> Result<u32, String> {
    match digits.parse::<u32>() {
        Ok(n) if n >= 1 => Ok(n),
        _ if digits.is_empty() => Err(format!("`{name}` names no {what} number")),
        _ => Err(format!(
            "`{name}` names {what} {digits}, which is not 1, 2, …"
        )),
    }
}

/// Reads the channel `name` (see the module documentation). An unknown object type or
/// quantity, or a missing number, is an error that says which.
pub fn parse(name: &str) -> Result<Channel, String> {
    let [let1, num1, let2, num2, let3] = decompose(name.trim());
    let channel = |object, quantity| Channel {
        name: name.trim().to_string(),
        object,
        quantity,
    };
    let rest_empty = let2.is_empty() && num2.is_empty() && let3.is_empty();
    match let1.as_str() {
        "FAIRTEN" | "ANCHTEN" => {
            let line = id(&num1, "line", name)?;
            if !rest_empty {
                return Err(format!("`{name}`: nothing may follow the line number"));
            }
            let node = if let1 == "FAIRTEN" {
                LineNode::EndB
            } else {
                LineNode::Index(0)
            };
            Ok(channel(Object::Line(line, node), Quantity::Tension))
        }
        "L" | "LINE" => {
            let line = id(&num1, "line", name)?;
            let (node, q) = if !num2.is_empty() {
                if let2 != "N" {
                    return Err(format!(
                        "`{name}`: a node number follows `N` (as in L1N10T), not `{let2}`"
                    ));
                }
                let j = num2
                    .parse::<u32>()
                    .map_err(|_| format!("`{name}`: node number {num2} is too large"))?;
                (LineNode::Index(j), let3.clone())
            } else if let Some(q) = let2.strip_prefix("NA") {
                (LineNode::Index(0), q.to_string())
            } else if let Some(q) = let2.strip_prefix("NB") {
                (LineNode::EndB, q.to_string())
            } else {
                (LineNode::Index(0), let2.clone())
            };
            let q = quantity(&q).ok_or_else(|| unknown_quantity(name, &q))?;
            Ok(channel(Object::Line(line, node), q))
        }
        "P" | "POINT" | "C" | "CON" | "CONNECT" => {
            let point = id(&num1, "point", name)?;
            if !num2.is_empty() || !let3.is_empty() {
                return Err(format!(
                    "`{name}`: a point channel is P<k><quantity>, e.g. Point4FZ"
                ));
            }
            let q = quantity(&let2).ok_or_else(|| unknown_quantity(name, &let2))?;
            Ok(channel(Object::Point(point), q))
        }
        "R" | "ROD" => Err(format!(
            "`{name}` reads a rod; phstring does not model rods (the deck mapping refuses them)"
        )),
        "B" | "BODY" => Err(format!(
            "`{name}` reads a body; phstring does not write body channels yet"
        )),
        _ => Err(format!(
            "`{name}`: the object must be FairTen<i>, AnchTen<i>, L<i>…, Line<i>…, P<k>…, Point<k>… or Con<k>…"
        )),
    }
}

fn unknown_quantity(name: &str, q: &str) -> String {
    if q.is_empty() {
        format!("`{name}` names no quantity (PX … VZ, T, TA, TB, FX … FZ)")
    } else {
        format!("`{name}`: unknown quantity `{q}` (PX … VZ, T, TA, TB, FX … FZ)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(name: &str) -> (Object, Quantity) {
        let c = parse(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(c.name, name.trim());
        (c.object, c.quantity)
    }

    /// Every form of MoorDyn's channel names reads as MoorDyn reads it.
    #[test]
    fn channel_names_read_as_moordyn_reads_them() {
        use LineNode::*;
        use Object::*;
        assert_eq!(ok("FairTen1"), (Line(1, EndB), Quantity::Tension));
        assert_eq!(ok("ANCHTEN12"), (Line(12, Index(0)), Quantity::Tension));
        assert_eq!(ok("L1N10T"), (Line(1, Index(10)), Quantity::Tension));
        assert_eq!(ok("l2n0pz"), (Line(2, Index(0)), Quantity::Position(2)));
        assert_eq!(ok("Line3N5VX"), (Line(3, Index(5)), Quantity::Velocity(0)));
        assert_eq!(ok("L1NBT"), (Line(1, EndB), Quantity::Tension));
        assert_eq!(ok("L1NAFZ"), (Line(1, Index(0)), Quantity::Force(2)));
        assert_eq!(ok("L1TenA"), (Line(1, Index(0)), Quantity::TensionA));
        assert_eq!(ok("L4TB"), (Line(4, Index(0)), Quantity::TensionB));
        assert_eq!(ok("Point4FX"), (Point(4), Quantity::Force(0)));
        assert_eq!(ok("P2T"), (Point(2), Quantity::Tension));
        assert_eq!(ok("Con4pX"), (Point(4), Quantity::Position(0)));
        assert_eq!(ok(" C7VZ "), (Point(7), Quantity::Velocity(2)));
        assert!(matches!(ok("L1N3AX").1, Quantity::NotWritten(_)));
        assert!(matches!(ok("Point1Sub").1, Quantity::NotWritten(_)));
        assert_eq!(Quantity::Position(1).unit(), "m");
        assert_eq!(Quantity::Velocity(1).unit(), "m/s");
        assert_eq!(Quantity::TensionB.unit(), "N");
    }

    /// A malformed name is an error that quotes it and says what is wrong.
    #[test]
    fn malformed_channel_names_are_refused_with_the_reason() {
        for (name, says) in [
            ("FairTen", "names no line number"),
            ("FairTen0", "which is not 1, 2"),
            ("FairTen1X", "nothing may follow"),
            ("L1N10", "names no quantity"),
            ("L1N10Q", "unknown quantity `Q`"),
            ("L1X10T", "follows `N`"),
            ("Point4", "names no quantity"),
            ("Point4N2PZ", "point channel"),
            ("Rod1PX", "rod"),
            ("Body1PX", "body"),
            ("Buoy1PZ", "the object must be"),
            ("", "the object must be"),
        ] {
            let e = parse(name).expect_err(name);
            assert!(e.contains(says), "{name}: {e}");
        }
    }
}
