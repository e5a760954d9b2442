//! The table sections (LINE TYPES, POINTS, LINES) and the OUTPUTS list, read row by row.

use super::error::DeckError;
use super::layout::{Block, Row, count, is_number, number};
use super::options::looks_numeric;
use super::{
    Attachment, Body, BodyKind, Line, LineType, LineValue, OutputChannel, Point, PointKind, RodEnd,
    Version,
};

/// A MoorDyn-F v1 count line at the top of a table (`3  NLines  - number of lines`):
/// the count and its name.
pub(super) fn count_line<'a>(row: &Row<'a>) -> Option<(usize, &'a str)> {
    let f = row.fields();
    let n = f.first()?.parse::<usize>().ok()?;
    let key = f.get(1)?;
    let named = key.len() > 1
        && key.starts_with(['N', 'n'])
        && key.chars().all(|c| c.is_ascii_alphabetic());
    named.then_some((n, *key))
}

/// The column names and data rows of a table block: skips a count line, checks that the
/// two header rows (names, units) hold no number, and checks the count if there was one.
/// A block with no rows at all is an empty table.
pub(super) fn table<'b, 'a>(
    file: &str,
    block: &'b Block<'a>,
) -> Result<(Vec<&'a str>, &'b [Row<'a>]), DeckError> {
    let mut rows = &block.rows[..];
    let declared = rows.first().and_then(count_line).map(|c| (rows[0].line, c));
    if declared.is_some() {
        rows = &rows[1..];
    }
    if rows.is_empty() && declared.is_none() {
        return Ok((Vec::new(), rows));
    }
    for k in 0..2 {
        let bad = match rows.get(k) {
            None => Some((block.line, "")),
            Some(r) if r.fields().iter().any(|f| is_number(f)) => Some((r.line, r.text)),
            Some(_) => None,
        };
        if let Some((line, text)) = bad {
            return Err(DeckError::MissingHeader {
                file: file.to_string(),
                line,
                title: block.title.to_string(),
                text: text.to_string(),
            });
        }
    }
    let names = rows[0].fields();
    let data = &rows[2..];
    if let Some((line, (n, key))) = declared
        && n != data.len()
    {
        return Err(DeckError::CountMismatch {
            file: file.to_string(),
            line,
            key: key.to_string(),
            declared: n,
            found: data.len(),
        });
    }
    Ok((names, data))
}

/// A row being read: file and line for messages, and its fields.
struct Fields<'a, 'f> {
    file: &'f str,
    line: usize,
    f: Vec<&'a str>,
}

impl Fields<'_, '_> {
    /// Field `i` as a finite number, or an error naming the column.
    fn num(&self, i: usize, field: &'static str) -> Result<f64, DeckError> {
        number(self.f[i]).ok_or_else(|| DeckError::NotANumber {
            file: self.file.to_string(),
            line: self.line,
            field,
            text: self.f[i].to_string(),
        })
    }
    /// The `ID` field (the first), which must number this row `previous + 1` of `table`
    /// (`previous` rows read before it).
    fn in_sequence(&self, table: &'static str, previous: usize) -> Result<u32, DeckError> {
        let id = self.count(0, "ID")?;
        let expected = previous as u32 + 1;
        if id != expected {
            return Err(DeckError::OutOfSequence {
                file: self.file.to_string(),
                line: self.line,
                table,
                found: id,
                expected,
            });
        }
        Ok(id)
    }
    /// Field `i` as a count (≥ 1).
    fn count(&self, i: usize, field: &'static str) -> Result<u32, DeckError> {
        count(self.f[i]).ok_or_else(|| DeckError::NotACount {
            file: self.file.to_string(),
            line: self.line,
            field,
            text: self.f[i].to_string(),
        })
    }
    /// Field `i` as a number, a curve file name or bar-separated parts.
    fn value(&self, i: usize, field: &'static str) -> Result<LineValue, DeckError> {
        let t = self.f[i];
        if let Some(x) = number(t) {
            Ok(LineValue::Number(x))
        } else if t.contains('|') {
            Ok(LineValue::Parts(t.split('|').map(str::to_string).collect()))
        } else if looks_numeric(t) {
            self.num(i, field).map(LineValue::Number)
        } else {
            Ok(LineValue::CurveFile(t.to_string()))
        }
    }
    /// The field-count error for table `table`.
    fn wrong_count(&self, table: &'static str, expected: &str) -> DeckError {
        DeckError::FieldCount {
            file: self.file.to_string(),
            line: self.line,
            table,
            expected: expected.to_string(),
            found: self.f.len(),
        }
    }
}

/// The known columns of a line type row, in file order, per version.
const V1_TYPE_COLUMNS: usize = 9;
const V2_TYPE_COLUMNS: usize = 10;

/// The columns of the known line type quantities: name, Diam, MassDen, EA, BA, EI (v1
/// decks may lack it), Cd (v1 Cdn), Ca (v1 Can), CdAx (v1 Cdt), CaAx (v1 Cat).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TypeColumns {
    name: usize,
    diam: usize,
    mass: usize,
    ea: usize,
    ba: usize,
    ei: Option<usize>,
    cd: usize,
    ca: usize,
    cd_ax: usize,
    ca_ax: usize,
}

impl TypeColumns {
    /// MoorDyn's positional order for `version`.
    fn positional(version: Version) -> Self {
        match version {
            // v1 writes added mass first: Can Cat Cdn Cdt.
            Version::V1 => TypeColumns {
                name: 0,
                diam: 1,
                mass: 2,
                ea: 3,
                ba: 4,
                ei: None,
                ca: 5,
                ca_ax: 6,
                cd: 7,
                cd_ax: 8,
            },
            Version::V2 => TypeColumns {
                name: 0,
                diam: 1,
                mass: 2,
                ea: 3,
                ba: 4,
                ei: Some(5),
                cd: 6,
                ca: 7,
                cd_ax: 8,
                ca_ax: 9,
            },
        }
    }

    /// The columns found by their header names (`LineType`/`TypeName`/`Name`, `Diam`,
    /// `MassDen…`/`Mass/m`, `EA`, `BA…`, `EI`, `Cd`/`Cdn`, `Ca`/`Can`, `CdAx`/`Cdt`,
    /// `CaAx`/`Cat`; compared without case and punctuation), when every quantity but `EI`
    /// is named exactly once; `None` otherwise.
    fn by_names(names: &[&str]) -> Option<Self> {
        let norm: Vec<String> = names
            .iter()
            .map(|n| {
                n.chars()
                    .filter(|c| c.is_ascii_alphanumeric())
                    .collect::<String>()
                    .to_ascii_lowercase()
            })
            .collect();
        let find = |accept: &dyn Fn(&str) -> bool| {
            let mut hits = norm.iter().enumerate().filter(|(_, n)| accept(n));
            let first = hits.next().map(|(i, _)| i);
            if hits.next().is_some() { None } else { first }
        };
        let is = |set: &'static [&'static str]| move |n: &str| set.contains(&n);
        Some(TypeColumns {
            name: find(&is(&["name", "typename", "linetype", "type"]))?,
            diam: find(&is(&["diam", "d", "diameter"]))?,
            mass: find(&|n: &str| n.starts_with("massden") || n == "massm" || n == "mass")?,
            ea: find(&is(&["ea"]))?,
            ba: find(&|n: &str| n.starts_with("ba"))?,
            ei: find(&is(&["ei"])),
            cd: find(&is(&["cd", "cdn"]))?,
            ca: find(&is(&["ca", "can"]))?,
            cd_ax: find(&is(&["cdax", "cdt"]))?,
            ca_ax: find(&is(&["caax", "cat"]))?,
        })
    }

    /// The indices of the known columns.
    fn known(&self) -> Vec<usize> {
        let mut k = vec![
            self.name, self.diam, self.mass, self.ea, self.ba, self.cd, self.ca, self.cd_ax,
            self.ca_ax,
        ];
        k.extend(self.ei);
        k
    }
}

/// Reads the LINE TYPES rows. Columns are found by their header names where the header
/// names every quantity (so that a v1 deck with an `EI` column or further columns, such
/// as a viscoelastic one, is read right); otherwise by position: v1 `Name Diam MassDen EA
/// BA/-zeta Can Cat Cdn Cdt`, v2 `Name Diam MassDen EA BA/-zeta EI Cd Ca CdAx CaAx`. Any
/// other column (`Cl dF cF`, `viscoE`, …) is kept raw under the name of its header column.
pub(super) fn line_types(
    file: &str,
    version: Version,
    names: &[&str],
    rows: &[Row],
) -> Result<Vec<LineType>, DeckError> {
    let cols = TypeColumns::by_names(names).unwrap_or_else(|| TypeColumns::positional(version));
    let known = cols.known();
    let needed = known.iter().max().map_or(0, |m| m + 1).max(match version {
        Version::V1 => V1_TYPE_COLUMNS,
        Version::V2 if cols.ei.is_some() => V2_TYPE_COLUMNS,
        Version::V2 => V1_TYPE_COLUMNS,
    });
    let mut out: Vec<LineType> = Vec::with_capacity(rows.len());
    for row in rows {
        let r = Fields {
            file,
            line: row.line,
            f: row.fields(),
        };
        if r.f.len() < needed {
            let expected = match version {
                Version::V1 => "at least 9 (Name Diam MassDen EA BA/-zeta Can Cat Cdn Cdt)",
                Version::V2 => "at least 10 (Name Diam MassDen EA BA/-zeta EI Cd Ca CdAx CaAx)",
            };
            let expected = if cols == TypeColumns::positional(version) {
                expected.to_string()
            } else {
                format!("at least {needed} (up to the last column the header names)")
            };
            return Err(r.wrong_count("LINE TYPES", &expected));
        }
        let name = r.f[cols.name].to_string();
        if let Some(first) = out.iter().find(|t| t.name == name) {
            return Err(DeckError::DuplicateLineType {
                file: file.to_string(),
                line: row.line,
                name,
                first: first.line,
            });
        }
        let (cd, ca, cd_ax, ca_ax) = match version {
            Version::V1 => ("Cdn", "Can", "Cdt", "Cat"),
            Version::V2 => ("Cd", "Ca", "CdAx", "CaAx"),
        };
        let ei = match cols.ei {
            Some(i) => r.value(i, "EI")?,
            None => LineValue::Number(0.0),
        };
        let extra = (0..r.f.len())
            .filter(|i| !known.contains(i))
            .map(|i| {
                let col = names
                    .get(i)
                    .map_or_else(|| format!("column{}", i + 1), |n| n.to_string());
                (col, r.f[i].to_string())
            })
            .collect();
        out.push(LineType {
            name,
            diameter: r.num(cols.diam, "Diam")?,
            mass_per_length: r.num(cols.mass, "MassDen")?,
            ea: r.value(cols.ea, "EA")?,
            ba: r.value(cols.ba, "BA/-zeta")?,
            ei,
            cd: r.num(cols.cd, cd)?,
            ca: r.num(cols.ca, ca)?,
            cd_ax: r.num(cols.cd_ax, cd_ax)?,
            ca_ax: r.num(cols.ca_ax, ca_ax)?,
            extra,
            line: row.line,
        });
    }
    Ok(out)
}

/// A MoorDyn word cut into leading letters (upper-cased), digits and the rest:
/// `Body12` → (`BODY`, `12`, ``), `R1A` → (`R`, `1`, `A`).
fn decompose(word: &str) -> (String, &str, &str) {
    let split = word
        .find(|c: char| !c.is_ascii_alphabetic())
        .unwrap_or(word.len());
    let (letters, tail) = word.split_at(split);
    let digits = tail
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(tail.len());
    (
        letters.to_ascii_uppercase(),
        &tail[..digits],
        &tail[digits..],
    )
}

/// The point type of the `Attachment` (v1 `Type`) column; see [`PointKind`].
fn point_kind(text: &str) -> Option<PointKind> {
    let (letters, digits, rest) = decompose(text);
    if !rest.is_empty() {
        return None;
    }
    let n = digits.parse::<u32>().ok().filter(|n| *n >= 1);
    match letters.as_str() {
        "FIXED" | "FIX" | "ANCHOR" if digits.is_empty() => Some(PointKind::Fixed),
        "VESSEL" | "VES" | "COUPLED" | "CPLD" | "FAIRLEAD" => Some(PointKind::Coupled),
        "FREE" | "CONNECT" | "CON" | "POINT" if digits.is_empty() => Some(PointKind::Free),
        "BODY" => n.map(PointKind::Body),
        "TURBINE" => n.map(PointKind::Turbine),
        _ => None,
    }
}

/// Reads the POINTS rows: `ID Attachment X Y Z Mass Volume CdA Ca` (9 fields) or, as in v1
/// decks, with `FX FY FZ` between `Volume` and `CdA` (12 fields). Ids run 1, 2, 3, ….
pub(super) fn points(file: &str, rows: &[Row]) -> Result<Vec<Point>, DeckError> {
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        let r = Fields {
            file,
            line: row.line,
            f: row.fields(),
        };
        if r.f.len() != 9 && r.f.len() != 12 {
            return Err(r.wrong_count(
                "POINTS",
                "9 (ID Attachment X Y Z Mass Volume CdA Ca) or 12 (with FX FY FZ after Volume)",
            ));
        }
        let id = r.in_sequence("POINTS", out.len())?;
        let kind = point_kind(r.f[1]).ok_or_else(|| DeckError::UnknownPointKind {
            file: file.to_string(),
            line: row.line,
            text: r.f[1].to_string(),
        })?;
        let with_force = r.f.len() == 12;
        let force = if with_force {
            Some([r.num(7, "FX")?, r.num(8, "FY")?, r.num(9, "FZ")?])
        } else {
            None
        };
        let tail = if with_force { 10 } else { 7 };
        out.push(Point {
            id,
            kind,
            kind_text: r.f[1].to_string(),
            position: [r.num(2, "X")?, r.num(3, "Y")?, r.num(4, "Z")?],
            mass: r.num(5, "Mass")?,
            volume: r.num(6, "Volume")?,
            force,
            cda: r.num(tail, "CdA")?,
            ca: r.num(tail + 1, "Ca")?,
            line: row.line,
        });
    }
    Ok(out)
}

/// The body type of the BODIES `Attachment` column; see [`BodyKind`].
fn body_kind(text: &str) -> Option<BodyKind> {
    let (letters, _, rest) = decompose(text);
    let pinned = |w: &str| {
        w.strip_suffix("PINNED")
            .is_some_and(|head| ["", "COUPLED", "VESSEL", "CPLD", "VES"].contains(&head))
    };
    match (letters.as_str(), rest.to_ascii_uppercase().as_str()) {
        ("FIXED" | "FIX" | "ANCHOR", "") => Some(BodyKind::Fixed),
        ("VESSEL" | "VES" | "COUPLED" | "CPLD", "") => Some(BodyKind::Coupled),
        ("FREE", "") => Some(BodyKind::Free),
        (w, "") if pinned(w) => Some(BodyKind::Pinned),
        _ => None,
    }
}

/// A starred BODIES column (`CG`, `I`, `CdA`, `Ca`): numbers separated by `|`, as many as
/// one of `counts` allows.
fn bar_values(
    r: &Fields,
    i: usize,
    field: &'static str,
    counts: &[usize],
) -> Result<Vec<f64>, DeckError> {
    let text = r.f[i];
    let values: Option<Vec<f64>> = text.split('|').map(number).collect();
    match values {
        Some(v) if counts.contains(&v.len()) => Ok(v),
        _ => Err(DeckError::NotANumber {
            file: r.file.to_string(),
            line: r.line,
            field,
            text: text.to_string(),
        }),
    }
}

/// Reads the BODIES rows (v2): `ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG* I* Volume CdA*
/// Ca*` (14 fields); ids run 1, 2, 3, ….
pub(super) fn bodies(file: &str, rows: &[Row]) -> Result<Vec<Body>, DeckError> {
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        let r = Fields {
            file,
            line: row.line,
            f: row.fields(),
        };
        if r.f.len() != 14 {
            return Err(r.wrong_count(
                "BODIES",
                "14 (ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I Volume CdA Ca)",
            ));
        }
        let id = r.in_sequence("BODIES", out.len())?;
        let kind = body_kind(r.f[1]).ok_or_else(|| DeckError::UnknownBodyKind {
            file: file.to_string(),
            line: row.line,
            text: r.f[1].to_string(),
        })?;
        let names = ["X0", "Y0", "Z0", "r0", "p0", "y0"];
        let mut pose = [0.0; 6];
        for (k, name) in names.iter().enumerate() {
            pose[k] = r.num(2 + k, name)?;
        }
        out.push(Body {
            id,
            kind,
            kind_text: r.f[1].to_string(),
            pose,
            mass: r.num(8, "Mass")?,
            cg: bar_values(&r, 9, "CG", &[1, 3])?,
            inertia: bar_values(&r, 10, "I", &[1, 3])?,
            volume: r.num(11, "Volume")?,
            cda: bar_values(&r, 12, "CdA", &[1, 2, 3, 6])?,
            ca: bar_values(&r, 13, "Ca", &[1, 3, 6])?,
            line: row.line,
        });
    }
    Ok(out)
}

/// A line end: a point (`3`, `P3`, `Point3`, `C3`, `Con3`) or a rod end (`R1A`, `Rod2B`).
fn attachment(text: &str) -> Option<Attachment> {
    let (letters, digits, rest) = decompose(text);
    let n = digits.parse::<u32>().ok().filter(|n| *n >= 1)?;
    match (letters.as_str(), rest.to_ascii_uppercase().as_str()) {
        ("" | "P" | "POINT" | "C" | "CON", "") => Some(Attachment::Point(n)),
        ("R" | "ROD", "A") => Some(Attachment::Rod(n, RodEnd::A)),
        ("R" | "ROD", "B") => Some(Attachment::Rod(n, RodEnd::B)),
        _ => None,
    }
}

/// Reads the LINES rows. v2: `ID LineType AttachA AttachB UnstrLen NumSegs Outputs`; v1:
/// `Line LineType UnstrLen NumSegs NodeAnch NodeFair Flags`. Line types must be defined
/// and points must exist; ids run 1, 2, 3, ….
pub(super) fn lines(
    file: &str,
    version: Version,
    rows: &[Row],
    types: &[LineType],
    points: &[Point],
) -> Result<Vec<Line>, DeckError> {
    let (a, b, len, segs, names) = match version {
        Version::V1 => (4, 5, 2, 3, ["NodeAnch", "NodeFair"]),
        Version::V2 => (2, 3, 4, 5, ["AttachA", "AttachB"]),
    };
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        let r = Fields {
            file,
            line: row.line,
            f: row.fields(),
        };
        if r.f.len() != 7 {
            return Err(r.wrong_count(
                "LINES",
                match version {
                    Version::V1 => "7 (Line LineType UnstrLen NumSegs NodeAnch NodeFair Flags)",
                    Version::V2 => "7 (ID LineType AttachA AttachB UnstrLen NumSegs Outputs)",
                },
            ));
        }
        let id = r.in_sequence("LINES", out.len())?;
        if !types.iter().any(|t| t.name == r.f[1]) {
            return Err(DeckError::UnknownLineType {
                file: file.to_string(),
                line: row.line,
                name: r.f[1].to_string(),
            });
        }
        let mut ends = [Attachment::Point(0); 2];
        for (k, (i, field)) in [(a, names[0]), (b, names[1])].into_iter().enumerate() {
            let end = attachment(r.f[i]).ok_or_else(|| DeckError::BadAttachment {
                file: file.to_string(),
                line: row.line,
                field,
                text: r.f[i].to_string(),
            })?;
            if let Attachment::Point(id) = end
                && id as usize > points.len()
            {
                return Err(DeckError::UnknownPoint {
                    file: file.to_string(),
                    line: row.line,
                    field,
                    id,
                    count: points.len(),
                });
            }
            ends[k] = end;
        }
        out.push(Line {
            id,
            line_type: r.f[1].to_string(),
            attach_a: ends[0],
            attach_b: ends[1],
            unstretched_length: r.num(len, "UnstrLen")?,
            segments: r.count(segs, "NumSegs")?,
            outputs: r.f[6].to_string(),
            line: row.line,
        });
    }
    Ok(out)
}

/// Reads the OUTPUTS rows: every word is a channel, words separated by spaces, tabs or
/// commas and each may stand in double quotes (OpenFAST's `"FairTen1", "AnchTen1"`); a row
/// `END` ends the list, and anything after it is refused.
pub(super) fn outputs(file: &str, rows: &[Row]) -> Result<Vec<OutputChannel>, DeckError> {
    let mut out = Vec::new();
    let mut ended = false;
    for row in rows {
        if ended {
            return Err(DeckError::AfterEnd {
                file: file.to_string(),
                line: row.line,
                text: row.text.to_string(),
            });
        }
        let words = row
            .text
            .split(|c: char| c.is_whitespace() || c == ',')
            .map(|w| w.trim_matches('"'))
            .filter(|w| !w.is_empty());
        for word in words {
            if word.eq_ignore_ascii_case("END") {
                ended = true;
            } else if ended {
                return Err(DeckError::AfterEnd {
                    file: file.to_string(),
                    line: row.line,
                    text: word.to_string(),
                });
            } else {
                out.push(OutputChannel {
                    name: word.to_string(),
                    line: row.line,
                });
            }
        }
    }
    Ok(out)
}
