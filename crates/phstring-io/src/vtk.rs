//! ParaView output: polyline meshes as XML PolyData (`.vtp`) and time collections (`.pvd`).
//!
//! Coordinates are in m and velocities in m/s; 1D and 2D callers pad with zeros.
//! Each element (segment) is one VTK line cell, so per-element quantities such as the strain
//! `C` and the stress `S` are cell data with one value per element.

use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataSet, PolyDataPiece, Version, VertexNumbers, Vtk,
};

/// Error while writing or validating VTK output.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VtkError {
    /// The arrays passed in are inconsistent (lengths, indices, names, times).
    #[error("cannot write {path}: {message}")]
    Input {
        /// Output file that was to be written.
        path: PathBuf,
        /// What is wrong with the input.
        message: String,
    },
    /// The vtkio library failed to write the file.
    #[error("cannot write {path}: {message}")]
    Vtk {
        /// Output file that was being written.
        path: PathBuf,
        /// vtkio error message.
        message: String,
    },
    /// Writing the output file failed.
    #[error("cannot write {path}: {cause}")]
    Io {
        /// Output file that was being written.
        path: PathBuf,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: std::io::Error,
    },
}

/// Writes a chain polyline (node `i` joined to node `i + 1`) as an XML PolyData `.vtp` file.
///
/// `points` are node positions in m, `velocity` the nodal velocities in m/s (point data
/// `"velocity"`, same length as `points`), and `cell_data` named per-element arrays with
/// `points.len() - 1` values each (e.g. `("C", strain)`, `("S", stress)`).
pub fn write_vtp(
    path: &Path,
    points: &[[f64; 3]],
    velocity: &[[f64; 3]],
    cell_data: &[(&str, &[f64])],
) -> Result<(), VtkError> {
    let segments: Vec<[usize; 2]> = (1..points.len()).map(|i| [i - 1, i]).collect();
    write_vtp_segments(path, points, &segments, velocity, cell_data)
}

/// Writes a general line mesh as an XML PolyData `.vtp` file: one two-point line cell per
/// entry of `segments` (pairs of node indices into `points`).
///
/// `points` in m; `velocity` in m/s, one per point (point data `"velocity"`); `cell_data`
/// named arrays with one value per segment. Names must be non-empty and distinct.
pub fn write_vtp_segments(
    path: &Path,
    points: &[[f64; 3]],
    segments: &[[usize; 2]],
    velocity: &[[f64; 3]],
    cell_data: &[(&str, &[f64])],
) -> Result<(), VtkError> {
    write_vtp_frame(
        path,
        &FrameData {
            points,
            segments,
            velocity,
            cell_data,
            cell_ints: &[],
            point_data: &[],
        },
    )
}

/// The arrays of one ParaView frame of a line mesh (see [`write_vtp_frame`]).
#[derive(Debug, Clone, Copy)]
pub struct FrameData<'a> {
    /// Node positions [m] (1D and 2D padded with zeros).
    pub points: &'a [[f64; 3]],
    /// Line cells: pairs of indices into `points`.
    pub segments: &'a [[usize; 2]],
    /// Nodal velocities [m/s], one per point (point data `"velocity"`).
    pub velocity: &'a [[f64; 3]],
    /// Named per-segment floating-point arrays (cell data), one value per segment.
    pub cell_data: &'a [(&'a str, &'a [f64])],
    /// Named per-segment integer arrays (cell data, e.g. a group index), one value per
    /// segment.
    pub cell_ints: &'a [(&'a str, &'a [i32])],
    /// Named per-point floating-point arrays (point data besides `"velocity"`), one value
    /// per point.
    pub point_data: &'a [(&'a str, &'a [f64])],
}

/// Writes a line mesh with cell and point data as an XML PolyData `.vtp` file: one two-point
/// line cell per segment, point data `"velocity"` and `data.point_data`, cell data
/// `data.cell_data` then `data.cell_ints`. Array names must be non-empty and distinct (cell
/// names among cell arrays, point names among point arrays and `"velocity"`); non-finite
/// values are refused.
pub fn write_vtp_frame(path: &Path, data: &FrameData<'_>) -> Result<(), VtkError> {
    let FrameData {
        points,
        segments,
        velocity,
        cell_data,
        cell_ints,
        point_data,
    } = *data;
    let input_err = |message: String| VtkError::Input {
        path: path.to_path_buf(),
        message,
    };
    if velocity.len() != points.len() {
        return Err(input_err(format!(
            "{} velocities for {} points",
            velocity.len(),
            points.len()
        )));
    }
    for (what, values) in [
        ("point coordinate", points.as_flattened()),
        ("velocity", velocity.as_flattened()),
    ]
    .into_iter()
    .chain(cell_data.iter().map(|(name, v)| (*name, *v)))
    .chain(point_data.iter().map(|(name, v)| (*name, *v)))
    {
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            return Err(input_err(format!(
                "non-finite {what} value {} (index {i})",
                values[i]
            )));
        }
    }
    if let Some((k, s)) = segments
        .iter()
        .enumerate()
        .find(|(_, s)| s[0] >= points.len() || s[1] >= points.len())
    {
        return Err(input_err(format!(
            "segment {k} = {s:?} refers to a node beyond the {} points",
            points.len()
        )));
    }
    let cell_arrays: Vec<(&str, usize)> = cell_data
        .iter()
        .map(|(n, v)| (*n, v.len()))
        .chain(cell_ints.iter().map(|(n, v)| (*n, v.len())))
        .collect();
    let point_arrays: Vec<(&str, usize)> = point_data.iter().map(|(n, v)| (*n, v.len())).collect();
    for (kind, arrays, count, unit) in [
        ("cell", &cell_arrays, segments.len(), "elements"),
        ("point", &point_arrays, points.len(), "points"),
    ] {
        for (i, (name, len)) in arrays.iter().enumerate() {
            if name.is_empty() || *name == "velocity" {
                return Err(input_err(format!("invalid {kind} data name {name:?}")));
            }
            if arrays[..i].iter().any(|(other, _)| other == name) {
                return Err(input_err(format!("duplicate {kind} data name {name:?}")));
            }
            if *len != count {
                return Err(input_err(format!(
                    "{kind} data {name:?} has {len} values for {count} {unit}"
                )));
            }
        }
    }

    let coords: Vec<f64> = points.iter().flatten().copied().collect();
    let vel: Vec<f64> = velocity.iter().flatten().copied().collect();
    let connectivity: Vec<u64> = segments.iter().flatten().map(|&i| i as u64).collect();
    let offsets: Vec<u64> = (1..=segments.len() as u64).map(|k| 2 * k).collect();
    let cell = cell_data
        .iter()
        .map(|(name, values)| Attribute::scalars(*name, 1).with_data(values.to_vec()))
        .chain(
            cell_ints
                .iter()
                .map(|(name, values)| Attribute::scalars(*name, 1).with_data(values.to_vec())),
        )
        .collect();
    let point = std::iter::once(Attribute::vectors("velocity").with_data(vel))
        .chain(
            point_data
                .iter()
                .map(|(name, values)| Attribute::scalars(*name, 1).with_data(values.to_vec())),
        )
        .collect();

    let piece = PolyDataPiece {
        points: coords.into(),
        lines: Some(VertexNumbers::XML {
            connectivity,
            offsets,
        }),
        data: Attributes { point, cell },
        ..Default::default()
    };
    write_piece(path, piece)
}

/// Writes the rigid bodies `boxes` at their `poses` (same order) as an XML PolyData `.vtp`
/// file (see [`crate::body_shape`]): per body, its 8 box corners then its centre of mass and
/// the tips of its body axes `x`, `y`, `z` (12 points); its 3 axis lines (line cells) and its
/// 6 box faces (quadrilateral polygon cells). Cell data (lines of every body first, then the
/// faces, as VTK orders cells): `body`, the body's index, and `axis`, 1, 2, 3 for the axis
/// lines `x`, `y`, `z` and 0 for the faces. Non-finite poses are refused.
pub fn write_vtp_bodies(
    path: &Path,
    boxes: &[crate::body_shape::BodyBox],
    poses: &[crate::body_shape::BodyPose],
) -> Result<(), VtkError> {
    use crate::body_shape::BOX_FACES;
    if boxes.len() != poses.len() {
        return Err(VtkError::Input {
            path: path.to_path_buf(),
            message: format!("{} poses for {} bodies", poses.len(), boxes.len()),
        });
    }
    let (mut coords, mut lines, mut polys) = (Vec::<f64>::new(), Vec::<u64>::new(), Vec::new());
    for (bx, pose) in boxes.iter().zip(poses) {
        let mut flat = pose.position.iter().chain(&pose.orientation);
        if let Some(x) = flat.find(|x| !x.is_finite()) {
            return Err(VtkError::Input {
                path: path.to_path_buf(),
                message: format!("body {} has a non-finite pose value {x}", bx.name),
            });
        }
        let first = (coords.len() / 3) as u64;
        coords.extend(bx.corners(pose).iter().chain(&bx.frame(pose)).flatten());
        let centre = first + 8;
        lines.extend((1..=3).flat_map(|k| [centre, centre + k]));
        polys.extend(BOX_FACES.iter().flatten().map(|&i| first + i as u64));
    }
    let n = boxes.len();
    let index = |b: usize| i32::try_from(b).unwrap_or(i32::MAX);
    let body: Vec<i32> = (0..n)
        .flat_map(|b| [index(b); 3])
        .chain((0..n).flat_map(|b| [index(b); 6]))
        .collect();
    let axis: Vec<i32> = (0..n)
        .flat_map(|_| [1, 2, 3])
        .chain(std::iter::repeat_n(0, 6 * n))
        .collect();
    let piece = PolyDataPiece {
        points: coords.into(),
        lines: Some(VertexNumbers::XML {
            connectivity: lines,
            offsets: (1..=3 * n as u64).map(|k| 2 * k).collect(),
        }),
        polys: Some(VertexNumbers::XML {
            connectivity: polys,
            offsets: (1..=6 * n as u64).map(|k| 4 * k).collect(),
        }),
        data: Attributes {
            point: Vec::new(),
            cell: vec![
                Attribute::scalars("body", 1).with_data(body),
                Attribute::scalars("axis", 1).with_data(axis),
            ],
        },
        ..Default::default()
    };
    write_piece(path, piece)
}

/// Writes `piece` as an XML PolyData file at `path`, formatted in memory first: an I/O error
/// (a full disk) is reported as such, not as the formatter's error, and a failed write
/// leaves no partial file.
fn write_piece(path: &Path, piece: PolyDataPiece) -> Result<(), VtkError> {
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        data: DataSet::inline(piece),
        file_path: None,
    };
    let mut bytes = Vec::new();
    vtk.write_xml(&mut bytes).map_err(|e| VtkError::Vtk {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    std::fs::write(path, &bytes).map_err(|cause| {
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(path);
        }
        VtkError::Io {
            path: path.to_path_buf(),
            cause,
        }
    })
}

/// Opening of a collection file, up to its first data set.
const PVD_HEADER: &str = "<?xml version=\"1.0\"?>\n\
<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  \
<Collection>\n";
/// Closing of a collection file, after its last data set.
const PVD_FOOTER: &str = "  </Collection>\n</VTKFile>\n";

/// Writer of a ParaView collection file (`.pvd`) listing one data file per time step.
///
/// Call [`PvdWriter::add`] per frame and [`PvdWriter::write`] as often as wanted: each call
/// appends the data sets added since the last one and rewrites the closing tags, so the
/// collection on disk is valid after every write, and neither memory nor the cost of a write
/// grows with the number of frames.
#[derive(Debug, Clone)]
pub struct PvdWriter {
    path: PathBuf,
    /// Data sets in the file.
    written: usize,
    /// Byte offset of the closing tags in the file (after the last data set written); 0
    /// before the first write.
    body_end: u64,
    /// Data sets added since the last write: `(time in s, file name)`.
    pending: Vec<(f64, String)>,
}

impl PvdWriter {
    /// A writer for the collection file at `pvd_path` (nothing is written yet; the first
    /// write replaces any file there).
    pub fn new(pvd_path: &Path) -> Self {
        Self {
            path: pvd_path.to_path_buf(),
            written: 0,
            body_end: 0,
            pending: Vec::new(),
        }
    }

    /// Path of the collection file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of data sets added so far (written or not).
    pub fn len(&self) -> usize {
        self.written + self.pending.len()
    }

    /// Whether no data set has been added yet.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Records the data file for time `time` (in s), given relative to the `.pvd` file's folder.
    pub fn add(&mut self, time: f64, file_name_relative: &str) {
        self.pending.push((time, file_name_relative.to_string()));
    }

    /// Forgets the data sets added since the last write (their files could not be listed,
    /// e.g. on a full disk, and were removed).
    pub fn discard_pending(&mut self) {
        self.pending.clear();
    }

    /// Continues the collection file written by [`Self::write`] after its first `frames` data
    /// sets (a resumed run; data sets after them are dropped at the next write), calling
    /// `visit(time, file name)` for each of those. The file is read as a stream and not
    /// changed here. Times must be finite; file names are unescaped.
    pub fn resume(
        pvd_path: &Path,
        frames: usize,
        mut visit: impl FnMut(f64, &str),
    ) -> Result<Self, VtkError> {
        use std::io::BufRead;
        let mut w = Self::new(pvd_path);
        if frames == 0 {
            return Ok(w);
        }
        let io = |source| VtkError::Io {
            path: pvd_path.to_path_buf(),
            cause: source,
        };
        let bad = |line: usize, message: String| VtkError::Input {
            path: pvd_path.to_path_buf(),
            message: format!("line {}: {message}", line + 1),
        };
        let attr = |line: &str, name: &str| -> Option<String> {
            let start = line.find(&format!(" {name}=\""))? + name.len() + 3;
            let len = line[start..].find('"')?;
            Some(line[start..start + len].to_string())
        };
        let mut reader = std::io::BufReader::new(std::fs::File::open(pvd_path).map_err(io)?);
        let (mut line, mut offset, mut i) = (String::new(), 0u64, 0usize);
        while w.written < frames {
            line.clear();
            let n = reader.read_line(&mut line).map_err(io)?;
            if n == 0 {
                return Err(bad(
                    i,
                    format!(
                        "the collection ends after {} data sets, {frames} were expected",
                        w.written
                    ),
                ));
            }
            offset += n as u64;
            if line.trim_start().starts_with("<DataSet ") {
                let time: f64 = attr(&line, "timestep")
                    .and_then(|t| t.parse().ok())
                    .filter(|t: &f64| t.is_finite())
                    .ok_or_else(|| bad(i, "no finite timestep".into()))?;
                let file = attr(&line, "file").ok_or_else(|| bad(i, "no file".into()))?;
                visit(time, &xml_unescape(&file));
                w.written += 1;
            }
            i += 1;
        }
        w.body_end = offset;
        Ok(w)
    }

    /// The XML line of one data set.
    fn entry(time: f64, file: &str) -> String {
        format!(
            "    <DataSet timestep=\"{time:?}\" part=\"0\" file=\"{}\"/>\n",
            xml_escape(file)
        )
    }

    /// Writes the data sets added since the last write, and the closing tags after them (the
    /// first write writes the whole file). Non-finite times are rejected.
    pub fn write(&mut self) -> Result<(), VtkError> {
        use std::io::{Seek, SeekFrom, Write as _};
        if let Some((time, file)) = self.pending.iter().find(|(t, _)| !t.is_finite()) {
            return Err(VtkError::Input {
                path: self.path.clone(),
                message: format!("non-finite time {time} for data set {file:?}"),
            });
        }
        let io = |source| VtkError::Io {
            path: self.path.clone(),
            cause: source,
        };
        let mut body = String::new();
        if self.body_end == 0 {
            body.push_str(PVD_HEADER);
        }
        for (time, file) in &self.pending {
            body.push_str(&Self::entry(*time, file));
        }
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .write(true)
            .truncate(false)
            .open(&self.path)
            .map_err(io)?;
        let end = self.body_end + (body.len() + PVD_FOOTER.len()) as u64;
        let written = f
            .seek(SeekFrom::Start(self.body_end))
            .and_then(|_| f.write_all(body.as_bytes()))
            .and_then(|()| f.write_all(PVD_FOOTER.as_bytes()))
            .and_then(|()| f.set_len(end));
        if let Err(cause) = written {
            // Back to the collection as it was (a full disk): its data sets and closing tags;
            // a first write leaves no file. The pending data sets stay pending.
            if self.body_end == 0 {
                drop(f);
                let _ = std::fs::remove_file(&self.path);
            } else {
                let _ = f
                    .set_len(self.body_end)
                    .and_then(|()| f.seek(SeekFrom::Start(self.body_end)))
                    .and_then(|_| f.write_all(PVD_FOOTER.as_bytes()));
            }
            return Err(io(cause));
        }
        self.body_end += body.len() as u64;
        self.written += self.pending.len();
        self.pending.clear();
        Ok(())
    }
}

/// Escapes text for an XML attribute value: the five special characters as entities, tab,
/// newline and carriage return as character references (attribute values normalize them
/// otherwise), and the characters XML 1.0 forbids (other control characters, NUL, U+FFFE,
/// U+FFFF) dropped, so the file is always well-formed.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\u{FFFE}' | '\u{FFFF}' => {}
            c if c.is_control() && (c as u32) < 0x20 => {}
            c if c == '\u{7f}' || ('\u{80}'..='\u{9f}').contains(&c) => {}
            _ => out.push(c),
        }
    }
    out
}

/// Inverse of [`xml_escape`] for the entities and character references it writes.
fn xml_unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find('&') {
        out.push_str(&rest[..i]);
        rest = &rest[i..];
        let Some(end) = rest.find(';') else { break };
        let entity = &rest[1..end];
        let c = match entity {
            "amp" => Some('&'),
            "lt" => Some('<'),
            "gt" => Some('>'),
            "quot" => Some('"'),
            "apos" => Some('\''),
            _ => entity
                .strip_prefix('#')
                .and_then(|n| n.parse::<u32>().ok())
                .and_then(char::from_u32),
        };
        match c {
            Some(c) => {
                out.push(c);
                rest = &rest[end + 1..];
            }
            None => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty directory under the system temp dir.
    fn temp_dir(name: &str) -> PathBuf {
        crate::test_util::temp_dir("vtk", name)
    }

    fn poly_piece(vtk: Vtk) -> PolyDataPiece {
        match vtk.data {
            DataSet::PolyData { mut pieces, .. } => {
                assert_eq!(pieces.len(), 1);
                match pieces.remove(0) {
                    vtkio::model::Piece::Inline(p) => *p,
                    other => panic!("unexpected piece {other:?}"),
                }
            }
            other => panic!("not PolyData: {other:?}"),
        }
    }

    fn array(attrs: &[Attribute], name: &str) -> Vec<f64> {
        let a = attrs
            .iter()
            .find(|a| a.name() == name)
            .unwrap_or_else(|| panic!("no array {name}"));
        match a {
            Attribute::DataArray(d) => d.data.cast_into::<f64>().unwrap(),
            Attribute::Field { .. } => panic!("field attribute"),
        }
    }

    #[test]
    fn vtp_chain_round_trip() {
        let dir = temp_dir("chain");
        let path = dir.join("frame_0000.vtp");
        let n = 5;
        let points: Vec<[f64; 3]> = (0..n)
            .map(|i| [0.25 * i as f64, -0.1 * i as f64, 0.0])
            .collect();
        let velocity: Vec<[f64; 3]> = (0..n).map(|i| [0.0, i as f64, 0.5]).collect();
        let c = [1.0, 1.01, 1.02, 1.03];
        let s = [10.0, 20.0, 30.0, 40.0];
        write_vtp(&path, &points, &velocity, &[("C", &c), ("S", &s)]).unwrap();

        let piece = poly_piece(Vtk::import(&path).unwrap());
        assert_eq!(piece.num_points(), n);
        assert_eq!(piece.num_lines(), n - 1);
        assert_eq!(piece.num_cells(), n - 1);
        let pts = piece.points.cast_into::<f64>().unwrap();
        assert_eq!(pts[3..6], [0.25, -0.1, 0.0]);
        let (conn, offs) = match piece.lines.clone().unwrap() {
            VertexNumbers::XML {
                connectivity,
                offsets,
            } => (connectivity, offsets),
            VertexNumbers::Legacy { .. } => panic!("legacy topology"),
        };
        assert_eq!(conn, vec![0, 1, 1, 2, 2, 3, 3, 4]);
        assert_eq!(offs, vec![2, 4, 6, 8]);
        let v = array(&piece.data.point, "velocity");
        assert_eq!(v.len(), 3 * n);
        assert_eq!(v[3 * 2 + 1], 2.0);
        let names: Vec<&str> = piece.data.cell.iter().map(|a| a.name()).collect();
        assert_eq!(names, ["C", "S"]);
        assert_eq!(array(&piece.data.cell, "S"), s);
        assert_eq!(array(&piece.data.cell, "C")[2], 1.02);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Two bodies: the hook block (600 kg, 40, 50, 26 kg·m², a 0.6 × 0.4 × 0.8 m box) at
    /// (1, 2, 3) m unturned and a 1 t cube; the file has 12 points, 3 lines and 6
    /// quadrilaterals per body, the hook's first corner at (0.7, 1.8, 2.6) m and its
    /// axis tips 0.6 m out, and faces whose corners span the box.
    #[test]
    fn vtp_bodies_round_trip() {
        use crate::body_shape::{BodyBox, BodyPose};
        let dir = temp_dir("bodies");
        let path = dir.join("bodies_000000.vtp");
        let diag = |a: f64, b: f64, c: f64| [[a, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]];
        let boxes = [
            BodyBox::new("hook", 600.0, diag(40.0, 50.0, 26.0), 3),
            BodyBox::new("cube", 1000.0, diag(150.0, 150.0, 150.0), 3),
        ];
        let rest = |p: [f64; 3]| BodyPose {
            position: p,
            orientation: [1.0, 0.0, 0.0, 0.0],
        };
        write_vtp_bodies(&path, &boxes, &[rest([1.0, 2.0, 3.0]), rest([0.0; 3])]).unwrap();
        let piece = poly_piece(Vtk::import(&path).unwrap());
        assert_eq!(piece.num_points(), 24);
        assert_eq!(piece.num_lines(), 6);
        assert_eq!(piece.num_polys(), 12);
        assert_eq!(piece.num_cells(), 18);
        let pts = piece.points.cast_into::<f64>().unwrap();
        let point = |i: usize| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
        // Corner 0 of the hook is the centre minus every half side, whatever the axes' order.
        for (k, want) in [0.7, 1.8, 2.6].into_iter().enumerate() {
            assert!((point(0)[k] - want).abs() < 1e-14, "{:?}", point(0));
        }
        assert_eq!(point(8), [1.0, 2.0, 3.0]);
        for (k, tip) in [[1.6, 2.0, 3.0], [1.0, 2.6, 3.0], [1.0, 2.0, 3.6]]
            .iter()
            .enumerate()
        {
            let p = point(9 + k);
            assert!((0..3).all(|i| (p[i] - tip[i]).abs() < 1e-14), "{p:?}");
        }
        // The cube of 150 kg·m² at 1 t: side sqrt(6 · 150 / 1000) m, corner 12 at −side/2.
        let half = 0.5 * 0.9f64.sqrt();
        assert!(
            point(12).iter().all(|x| (x + half).abs() < 1e-14),
            "{:?}",
            point(12)
        );
        let (conn, offs) = match piece.polys.clone().unwrap() {
            VertexNumbers::XML {
                connectivity,
                offsets,
            } => (connectivity, offsets),
            VertexNumbers::Legacy { .. } => panic!("legacy topology"),
        };
        assert_eq!(offs.last(), Some(&48));
        // The first face of the second body uses its own corners 12..20.
        assert!(conn[24..28].iter().all(|&i| (12..20).contains(&i)));
        let body = array(&piece.data.cell, "body");
        let axis = array(&piece.data.cell, "axis");
        assert_eq!(body[..6], [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        assert_eq!(body[6..12], [0.0; 6]);
        assert_eq!(axis[..6], [1.0, 2.0, 3.0, 1.0, 2.0, 3.0]);
        assert!(axis[6..].iter().all(|&a| a == 0.0));
        let mut bad = rest([f64::NAN, 0.0, 0.0]);
        let e = write_vtp_bodies(&path, &boxes[..1], &[bad]).unwrap_err();
        assert!(
            e.to_string()
                .contains("body hook has a non-finite pose value NaN"),
            "{e}"
        );
        bad.position[0] = 0.0;
        let e = write_vtp_bodies(&path, &boxes, &[bad]).unwrap_err();
        assert!(e.to_string().contains("1 poses for 2 bodies"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn vtp_segments_and_validation() {
        let dir = temp_dir("segments");
        let path = dir.join("mesh.vtp");
        let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let vel = [[0.0; 3]; 3];
        let segs = [[0, 1], [0, 2]];
        write_vtp_segments(&path, &points, &segs, &vel, &[("S", &[1.0, 2.0])]).unwrap();
        let piece = poly_piece(Vtk::import(&path).unwrap());
        assert_eq!(piece.num_points(), 3);
        assert_eq!(piece.num_cells(), 2);

        let bad = |r: Result<(), VtkError>| assert!(matches!(r, Err(VtkError::Input { .. })));
        bad(write_vtp_segments(&path, &points, &[[0, 3]], &vel, &[]));
        bad(write_vtp(&path, &points, &vel[..2], &[]));
        bad(write_vtp(&path, &points, &vel, &[("C", &[1.0])]));
        bad(write_vtp(
            &path,
            &points,
            &vel,
            &[("C", &[1.0, 2.0]), ("C", &[1.0, 2.0])],
        ));

        // A single node (no elements) and an empty mesh are still valid files.
        write_vtp(&dir.join("one.vtp"), &points[..1], &vel[..1], &[("C", &[])]).unwrap();
        write_vtp(&dir.join("none.vtp"), &[], &[], &[]).unwrap();
        let err = write_vtp(&dir.join("missing").join("x.vtp"), &points, &vel, &[]);
        assert!(err.unwrap_err().to_string().contains("x.vtp"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn vtp_frame_with_integer_cell_data_and_point_data() {
        let dir = temp_dir("frame");
        let path = dir.join("net.vtp");
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let vel = [[0.5, 0.0, 0.0]; 4];
        let segs = [[0, 1], [1, 2], [1, 3]];
        let data = FrameData {
            points: &points,
            segments: &segs,
            velocity: &vel,
            cell_data: &[("tension", &[10.0, 20.0, 30.0])],
            cell_ints: &[("string", &[0, 0, 1])],
            point_data: &[("mass", &[0.0, 2.5, 0.0, 0.0])],
        };
        write_vtp_frame(&path, &data).unwrap();
        let piece = poly_piece(Vtk::import(&path).unwrap());
        assert_eq!(piece.num_cells(), 3);
        let names: Vec<&str> = piece.data.cell.iter().map(|a| a.name()).collect();
        assert_eq!(names, ["tension", "string"]);
        assert_eq!(array(&piece.data.cell, "string"), [0.0, 0.0, 1.0]);
        assert_eq!(array(&piece.data.point, "mass"), [0.0, 2.5, 0.0, 0.0]);
        assert_eq!(array(&piece.data.point, "velocity").len(), 12);
        let xml = std::fs::read_to_string(&path).unwrap();
        assert!(xml.contains("Int32"), "integer array type: {xml}");

        let bad = |d: FrameData<'_>| {
            let e = write_vtp_frame(&path, &d).unwrap_err();
            assert!(matches!(e, VtkError::Input { .. }), "{e}");
        };
        bad(FrameData {
            cell_ints: &[("string", &[0, 1])],
            ..data
        });
        bad(FrameData {
            cell_ints: &[("tension", &[0, 1, 2])],
            ..data
        });
        bad(FrameData {
            point_data: &[("velocity", &[0.0; 4])],
            ..data
        });
        bad(FrameData {
            point_data: &[("mass", &[0.0, f64::NAN, 0.0, 0.0])],
            ..data
        });
        bad(FrameData {
            point_data: &[("mass", &[0.0; 3])],
            ..data
        });
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Control characters are dropped (tab, line feed and carriage return escaped), so that a
    /// title cannot make the XML invalid; escaping and unescaping round-trip.
    #[test]
    fn xml_escape_strips_control_characters() {
        assert_eq!(xml_escape("a\0b\x1bc\u{7f}d\u{FFFF}"), "abcd");
        assert_eq!(xml_escape("t\tn\nr\r"), "t&#9;n&#10;r&#13;");
        assert_eq!(xml_escape("<&>\"'"), "&lt;&amp;&gt;&quot;&apos;");
        for s in ["plain", "a&b<c>\"d'", "t\tn\nr\r", "ü &amp; &#9;"] {
            assert_eq!(xml_unescape(&xml_escape(s)), s);
        }
        let dir = temp_dir("escape");
        let mut pvd = PvdWriter::new(&dir.join("s.pvd"));
        pvd.add(0.5, "frame\0_\x1b1.vtp");
        pvd.write().unwrap();
        let xml = std::fs::read_to_string(dir.join("s.pvd")).unwrap();
        assert!(xml.contains("file=\"frame_1.vtp\""), "{xml}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn pvd_reads_back_what_it_wrote() {
        let dir = temp_dir("pvdread");
        let path = dir.join("string.pvd");
        let mut pvd = PvdWriter::new(&path);
        for (t, f) in [
            (0.0, "frame_000000.vtp"),
            (0.1 + 0.2, "a&b.vtp"),
            (1e-300, "x\ty.vtp"),
        ] {
            pvd.add(t, f);
        }
        pvd.write().unwrap();
        let mut back = Vec::new();
        let resumed = PvdWriter::resume(&path, 3, |t, f| back.push((t, f.to_string()))).unwrap();
        assert_eq!(resumed.len(), 3);
        let expected = [
            (0.0, "frame_000000.vtp"),
            (0.1 + 0.2, "a&b.vtp"),
            (1e-300, "x\ty.vtp"),
        ];
        assert_eq!(back.len(), 3);
        for ((t, f), (te, fe)) in back.iter().zip(expected) {
            assert_eq!((*t, f.as_str()), (te, fe));
        }
        // Resuming after the first two drops the third at the next write.
        let before = std::fs::read_to_string(&path).unwrap();
        let mut two = PvdWriter::resume(&path, 2, |_, _| {}).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            before,
            "resume changed the file"
        );
        two.add(0.5, "next.vtp");
        two.write().unwrap();
        let xml = std::fs::read_to_string(&path).unwrap();
        assert_eq!(xml.matches("<DataSet ").count(), 3, "{xml}");
        assert!(
            xml.contains("next.vtp") && !xml.contains("x&#9;y.vtp"),
            "{xml}"
        );
        assert!(xml.ends_with("</VTKFile>\n"), "{xml}");
        // Fewer data sets than asked for, and a non-finite time, are errors.
        assert!(PvdWriter::resume(&path, 4, |_, _| {}).is_err());
        std::fs::write(&path, "<DataSet timestep=\"nan\" part=\"0\" file=\"f\"/>\n").unwrap();
        assert!(PvdWriter::resume(&path, 1, |_, _| {}).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A NaN or infinite position, velocity or element field is refused and no `.vtp` file is
    /// written.
    #[test]
    fn non_finite_values_are_refused_in_vtp() {
        let dir = temp_dir("vtpnan");
        let path = dir.join("f.vtp");
        let p = [[0.0; 3], [1.0, f64::NAN, 0.0]];
        let v = [[0.0; 3]; 2];
        let e = write_vtp(&path, &p, &v, &[]).unwrap_err();
        assert!(matches!(e, VtkError::Input { .. }), "{e}");
        let ok = [[0.0; 3], [1.0, 0.0, 0.0]];
        let bad_v = [[0.0; 3], [f64::INFINITY, 0.0, 0.0]];
        assert!(write_vtp(&path, &ok, &bad_v, &[]).is_err());
        assert!(write_vtp(&path, &ok, &v, &[("S", &[f64::NAN])]).is_err());
        assert!(!path.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn pvd_lists_all_frames() {
        let dir = temp_dir("pvd");
        let path = dir.join("run.pvd");
        let mut pvd = PvdWriter::new(&path);
        assert!(pvd.is_empty());
        pvd.add(0.0, "frames/frame_0000.vtp");
        pvd.write().unwrap();
        pvd.add(0.1, "frames/frame_0001.vtp");
        pvd.add(0.1 + 0.2, "frames/a&b.vtp");
        pvd.write().unwrap();
        assert_eq!(pvd.len(), 3);

        let xml = std::fs::read_to_string(&path).unwrap();
        assert!(xml.contains("<VTKFile type=\"Collection\" version=\"0.1\""));
        assert!(xml.contains("<Collection>") && xml.contains("</Collection>"));
        assert!(
            xml.contains("<DataSet timestep=\"0.0\" part=\"0\" file=\"frames/frame_0000.vtp\"/>")
        );
        assert!(xml.contains("timestep=\"0.1\" part=\"0\" file=\"frames/frame_0001.vtp\""));
        // Round-trip precision: 0.1 + 0.2 is not 0.3 in binary.
        assert!(xml.contains("timestep=\"0.30000000000000004\""));
        assert!(xml.contains("file=\"frames/a&amp;b.vtp\""));
        assert_eq!(xml.matches("<DataSet ").count(), 3);
        assert!(xml.trim_end().ends_with("</VTKFile>"));

        pvd.add(f64::NAN, "bad.vtp");
        assert!(matches!(pvd.write(), Err(VtkError::Input { .. })));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
