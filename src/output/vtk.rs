//! ParaView output: XML unstructured grids (`.vtu`, via `vtkio`) and collections (`.pvd`).
//!
//! `.vtu` files are written with `vtkio` 0.7.0-rc2 as `version="1.0"`, little endian,
//! `header_type="UInt64"`, uncompressed inline base64 (`format="binary"`). Points and `F64`
//! fields are `Float64` and `I32` fields `Int32`, so everything round-trips bit-exactly.
//! Cells use `UInt64` connectivity/offsets and `UInt8` types (5 = triangle).
//!
//! vtkio quirks worked around here:
//! * Its XML writer (`xml::se::to_writer`) calls `Write::write` instead of `write_all` and lets
//!   its `BufWriter` flush on drop, so short writes and flush errors to a file would be lost
//!   silently. We therefore hand it a writer that turns every `write` into `write_all` and
//!   keeps the first error, which is checked after the serialisation (the file is written
//!   atomically, [`write_atomic_with`]).
//! * It `unwrap`s `u32::try_from` of the point and cell counts, so more than `u32::MAX` points
//!   or triangles would panic; we reject them with an error first.
//! * On reading, it silently drops point-data arrays it cannot decode, and it panics on some
//!   malformed input (e.g. a piece without `<Points>`). [`read_vtu`] counts the arrays in the
//!   raw XML to detect dropped ones and turns panics into [`OutputError::Vtk`].
//! * It writes `RangeMin`/`RangeMax` with Rust float formatting (`NaN`, `inf`), which VTK
//!   cannot parse; such attributes are removed after serialisation. (For multi-component
//!   arrays vtkio's range is the component-wise min/max, whereas VTK's own writer uses the
//!   magnitude range; the attributes are optional hints and left as they are.)
//! * It converts the whole model to base64 strings before writing (about 1.4x the raw array
//!   bytes); the fields' values are moved into it, not copied. A file with a non-finite value
//!   (see below) is built in memory once more, to strip its ranges.
//! * It has no model of the `Collection` (`.pvd`) file type (an unknown `type` is even parsed
//!   as `UnstructuredGrid`), so [`write_pvd`] writes that small XML file by hand.

use std::collections::{BTreeMap, HashSet};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::atomic::write_atomic_with;
use super::{format_f64, write_atomic, OutputError};

/// Values of a point-data field, stored point-major (`[p0c0, p0c1, ..., p1c0, ...]`).
#[derive(Debug, Clone, PartialEq)]
pub enum FieldValues {
    /// Double-precision values, written as `Float64`.
    F64(Vec<f64>),
    /// 32-bit integers (flags, node kinds, ...), written as `Int32`.
    I32(Vec<i32>),
}

impl FieldValues {
    /// Total number of stored values (points x components).
    pub fn len(&self) -> usize {
        match self {
            FieldValues::F64(v) => v.len(),
            FieldValues::I32(v) => v.len(),
        }
    }

    /// True if no values are stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A named point-data array for [`write_vtu`].
///
/// `components` may be any positive number. Two-component fields (2D vectors) are padded to
/// three with a zero z component when written, because ParaView's vector filters (Glyph,
/// Warp By Vector) need 3-vectors; [`read_vtu`] then reports 3 components. One-component
/// fields are tagged as active scalars and three-component ones as active vectors (the first
/// of each kind becomes ParaView's default); other counts are written as generic arrays.
#[derive(Debug, Clone, PartialEq)]
pub struct PointField {
    /// Array name shown in ParaView; must be non-empty and unique within one file.
    pub name: String,
    /// Number of components per point.
    pub components: usize,
    /// `components * number_of_points` values, point-major.
    pub values: FieldValues,
}

impl PointField {
    /// A one-component `f64` field.
    pub fn scalar(name: impl Into<String>, values: Vec<f64>) -> Self {
        PointField { name: name.into(), components: 1, values: FieldValues::F64(values) }
    }

    /// A 2D vector field, stored with 2 components (padded to 3 on writing).
    pub fn vector2(name: impl Into<String>, values: &[[f64; 2]]) -> Self {
        PointField { name: name.into(), components: 2, values: FieldValues::F64(values.iter().flatten().copied().collect()) }
    }

    /// A one-component `i32` field.
    pub fn integer(name: impl Into<String>, values: Vec<i32>) -> Self {
        PointField { name: name.into(), components: 1, values: FieldValues::I32(values) }
    }
}

/// Contents of a `.vtu` file as returned by [`read_vtu`].
#[derive(Debug, Clone, PartialEq)]
pub struct VtuContents {
    /// Point coordinates (z is 0 for files written by [`write_vtu`]).
    pub points: Vec<[f64; 3]>,
    /// Number of cells.
    pub cells: usize,
    /// Every point-data array by name: (number of components, values converted to `f64`,
    /// point-major). Integer arrays convert exactly up to 2^53 in magnitude.
    pub fields: BTreeMap<String, (usize, Vec<f64>)>,
}

/// Pads each group of two values with a zero third component.
fn pad_to_3<T: Copy + Default>(v: &[T]) -> Vec<T> {
    v.chunks_exact(2).flat_map(|c| [c[0], c[1], T::default()]).collect()
}

/// Validates `fields` against `n` points and converts them to `vtkio` attributes, each
/// field's values moved, not copied (two-component ones are padded to three).
fn point_attributes(fields: Vec<PointField>, n: usize) -> Result<Vec<Attribute>, OutputError> {
    let mut seen = HashSet::new();
    for f in &fields {
        let bad = |detail: String| OutputError::InvalidField { name: f.name.clone(), detail };
        if f.name.is_empty() {
            return Err(bad("field name is empty".into()));
        }
        if !seen.insert(f.name.as_str()) {
            return Err(bad("duplicate field name".into()));
        }
        if f.components == 0 {
            return Err(bad("number of components must be positive".into()));
        }
        let expected = f.components.checked_mul(n);
        if expected != Some(f.values.len()) {
            return Err(bad(format!(
                "has {} values but {} components x {} points = {} were expected",
                f.values.len(),
                f.components,
                n,
                f.components as u128 * n as u128
            )));
        }
        if u32::try_from(f.components.max(3)).is_err() {
            return Err(bad("too many components".into()));
        }
    }
    Ok(fields
        .into_iter()
        .map(|f| {
            let comps = if f.components == 2 { 3 } else { f.components };
            let data: IOBuffer = match (f.values, f.components) {
                (FieldValues::F64(v), 2) => pad_to_3(&v).into(),
                (FieldValues::I32(v), 2) => pad_to_3(&v).into(),
                (FieldValues::F64(v), _) => v.into(),
                (FieldValues::I32(v), _) => v.into(),
            };
            let elem = match comps {
                1 => ElementType::Scalars { num_comp: 1, lookup_table: None },
                3 => ElementType::Vectors,
                _ => ElementType::Generic(comps as u32),
            };
            Attribute::DataArray(DataArray { name: f.name, elem, data })
        })
        .collect())
}

/// A writer that passes every `write` on as `write_all` and keeps the first error:
/// vtkio's XML writer calls `write` (a short write would lose bytes) and flushes its
/// own buffer when dropped (a failed flush would pass silently); here the caller reads
/// the error afterwards.
struct Complete<W: Write> {
    inner: W,
    error: Option<std::io::Error>,
}

impl<W: Write> Write for Complete<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.error.is_some() {
            return Err(std::io::Error::other("an earlier write failed"));
        }
        match self.inner.write_all(buf) {
            Ok(()) => Ok(buf.len()),
            Err(e) => {
                let kind = e.kind();
                self.error = Some(e);
                Err(kind.into())
            }
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Unstructured grid: points (z = 0), triangle cells, point data. Atomic.
///
/// Checks before writing anything: all coordinates finite, every triangle index
/// `< points.len()`, at most `u32::MAX` points and triangles ([`OutputError::InvalidInput`]);
/// each field's name non-empty and unique, `components >= 1` and
/// `values.len() == components * points.len()` ([`OutputError::InvalidField`] naming the
/// field). Non-finite field values are allowed and written as they are. The file is
/// written with [`write_atomic`].
pub fn write_vtu(path: &Path, points: &[[f64; 2]], triangles: &[[usize; 3]], fields: Vec<PointField>) -> Result<(), OutputError> {
    let n = points.len();
    if u32::try_from(n).is_err() || u32::try_from(triangles.len()).is_err() {
        return Err(OutputError::invalid(path, "vtkio supports at most u32::MAX points and cells per file"));
    }
    if let Some(i) = points.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
        return Err(OutputError::invalid(path, format!("point {i} has a non-finite coordinate {:?}", points[i])));
    }
    if let Some(k) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(OutputError::invalid(path, format!("triangle {k} {:?} refers to a point >= {n} (number of points)", triangles[k])));
    }
    // Only an array holding NaN or inf gets a range to strip (the scan of the whole file
    // took 0.4 s at 1e6 nodes).
    let nonfinite = fields.iter().any(|f| matches!(&f.values, FieldValues::F64(v) if v.iter().any(|x| !x.is_finite())));
    let point_data = point_attributes(fields, n)?;

    let vtk = unstructured_grid(points, triangles, point_data);
    if nonfinite {
        // In memory, to strip the ranges vtkio writes as `NaN` or `inf`.
        let mut bytes = Vec::new();
        vtk.write_xml(&mut bytes).map_err(|e| OutputError::vtk(path, e))?;
        bytes.push(b'\n');
        return write_atomic(path, &strip_nonfinite_ranges(&bytes));
    }
    // Straight to the file (module docs): the cantilever at 1e6 nodes writes 334 MB,
    // which in memory first cost up to twice that on top of vtkio's own copy.
    write_atomic_with(path, |w| write_streamed(vtk, w, path))
}

/// The `vtkio` model of `points` (z = 0), triangle cells and `point_data`.
fn unstructured_grid(points: &[[f64; 2]], triangles: &[[usize; 3]], point_data: Vec<Attribute>) -> Vtk {
    let piece = UnstructuredGridPiece {
        points: points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect::<Vec<f64>>().into(),
        cells: Cells {
            cell_verts: VertexNumbers::XML {
                connectivity: triangles.iter().flatten().map(|&i| i as u64).collect(),
                offsets: (1..=triangles.len() as u64).map(|k| 3 * k).collect(),
            },
            types: vec![CellType::Triangle; triangles.len()],
        },
        data: Attributes { point: point_data, cell: Vec::new() },
    };
    Vtk {
        version: Version::new_xml(1, 0),
        byte_order: ByteOrder::LittleEndian,
        title: String::new(),
        file_path: None,
        data: DataSet::inline(piece),
    }
}

/// Serialise `vtk` into `w` and a final newline through [`Complete`]: the first write
/// error is the result, whatever vtkio made of it (`path` names the file in errors).
fn write_streamed(vtk: Vtk, w: impl Write, path: &Path) -> Result<(), OutputError> {
    let mut out = Complete { inner: w, error: None };
    let written = vtk.write_xml(&mut out);
    if let Some(e) = out.error {
        return Err(OutputError::io(path, e));
    }
    written.map_err(|e| OutputError::vtk(path, e))?;
    out.inner.write_all(b"\n").map_err(|e| OutputError::io(path, e))?;
    out.inner.flush().map_err(|e| OutputError::io(path, e))
}

/// Removes `RangeMin`/`RangeMax` attributes whose value is not a finite number.
///
/// vtkio writes the range of each array with Rust's float formatting, so an array holding
/// NaN or ±inf gets `RangeMin="NaN"` or `RangeMax="inf"`, which VTK's attribute parser does
/// not understand. The attributes are optional hints, so dropping them is always valid. (Base64
/// payloads contain neither spaces nor quotes, and quotes in names are escaped, so the
/// pattern can only match real attributes.)
fn strip_nonfinite_ranges(xml: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(xml.len());
    let mut at = 0;
    while let Some(p) = find(xml, b" Range", at) {
        out.extend_from_slice(&xml[at..p]);
        at = p;
        for key in [&b" RangeMin=\""[..], &b" RangeMax=\""[..]] {
            if !xml[p..].starts_with(key) {
                continue;
            }
            let v0 = p + key.len();
            if let Some(v1) = find(xml, b"\"", v0) {
                let value = std::str::from_utf8(&xml[v0..v1]).ok();
                let finite = value.and_then(|v| v.parse::<f64>().ok()).is_some_and(f64::is_finite);
                if !finite {
                    at = v1 + 1; // skip the whole attribute
                }
            }
        }
        if at == p {
            out.extend_from_slice(b" Range");
            at = p + b" Range".len();
        }
    }
    out.extend_from_slice(&xml[at..]);
    out
}

/// Position of `needle` in `hay` at or after `from`.
fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    hay.get(from..)?.windows(needle.len()).position(|w| w == needle).map(|p| p + from)
}

/// Number of `<DataArray` elements inside the first `<PointData>` element of the raw XML.
fn count_point_arrays(xml: &[u8]) -> usize {
    let Some(start) = find(xml, b"<PointData", 0) else {
        return 0;
    };
    let Some(tag_end) = find(xml, b">", start) else {
        return 0;
    };
    if xml[tag_end - 1] == b'/' {
        return 0; // <PointData/>
    }
    let end = find(xml, b"</PointData", tag_end).unwrap_or(xml.len());
    let mut count = 0;
    let mut at = tag_end;
    while let Some(p) = find(&xml[..end], b"<DataArray", at) {
        count += 1;
        at = p + 1;
    }
    count
}

/// Read back (for tests and the compare tool): points, number of cells, and every point-data
/// array by name as f64.
///
/// Accepts serial XML unstructured grids (`.vtu`) with exactly one inline piece and
/// uncompressed data (this build of vtkio has no decompressors; ParaView saves compressed by
/// default), ASCII, base64 or appended. Any scalar
/// type is converted to `f64`. Errors: [`OutputError::Io`] if the file cannot be read,
/// [`OutputError::Vtk`] if it cannot be parsed, is not of that form, has duplicate array
/// names, or has point-data arrays that vtkio could not decode.
/// A panic inside vtkio is caught and reported as [`OutputError::Vtk`] (the default panic
/// hook still prints its message to stderr).
pub fn read_vtu(path: &Path) -> Result<VtuContents, OutputError> {
    let vtk_err = |detail: String| OutputError::vtk(path, detail);
    let bytes = std::fs::read(path).map_err(|e| OutputError::io(path, e))?;
    let expected_arrays = count_point_arrays(&bytes);
    // vtkio panics on some malformed files; report those as errors instead.
    let vtk = std::panic::catch_unwind(|| Vtk::parse_xml(&bytes[..]))
        .map_err(|_| vtk_err("vtkio panicked while parsing (malformed file)".into()))?
        .map_err(|e| vtk_err(e.to_string()))?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(vtk_err("not an UnstructuredGrid".into()));
    };
    if pieces.len() != 1 {
        return Err(vtk_err(format!("expected 1 piece, found {}", pieces.len())));
    }
    let piece = pieces.into_iter().next().expect("one piece").into_loaded_piece_data(None).map_err(|e| vtk_err(e.to_string()))?;

    let coords = piece.points.cast_into::<f64>().ok_or_else(|| vtk_err("points are not numeric".into()))?;
    if coords.len() % 3 != 0 {
        return Err(vtk_err(format!("{} point coordinates", coords.len())));
    }
    let points = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let cells = piece.cells.num_cells();
    if piece.cells.cell_verts.num_cells() != cells {
        return Err(vtk_err("cell offsets and types differ in length".into()));
    }

    let mut fields = BTreeMap::new();
    for attr in piece.data.point {
        let Attribute::DataArray(a) = attr else {
            continue; // field data: legacy format only, never in .vtu
        };
        let values = a.data.cast_into::<f64>().ok_or_else(|| vtk_err(format!("array `{}` is not numeric", a.name)))?;
        let comps = a.elem.num_comp() as usize;
        if fields.insert(a.name.clone(), (comps, values)).is_some() {
            return Err(vtk_err(format!("duplicate point-data array `{}`", a.name)));
        }
    }
    if fields.len() != expected_arrays {
        return Err(vtk_err(format!("file has {expected_arrays} point-data arrays but only {} could be decoded", fields.len())));
    }
    Ok(VtuContents { points, cells, fields })
}

/// Escapes the five XML special characters for use in an attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// ParaView collection (`.pvd`) listing `(time, file)` entries, for time series. Atomic.
///
/// `file` is written as given and should be relative to the directory of the `.pvd` (it is
/// XML-escaped). Times must be finite and are written with round-trip precision; entries
/// keep the given order (ParaView sorts by time itself). Hand-written because vtkio has no
/// model of the `Collection` file type.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> Result<(), OutputError> {
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (i, (t, file)) in entries.iter().enumerate() {
        if !t.is_finite() {
            return Err(OutputError::invalid(path, format!("entry {i} has non-finite time {t}")));
        }
        if file.is_empty() {
            return Err(OutputError::invalid(path, format!("entry {i} has no file")));
        }
        // Writing to a String cannot fail.
        let _ = writeln!(xml, "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>", format_f64(*t), xml_escape(file));
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, xml.as_bytes())
}

#[cfg(test)]
#[path = "vtk_tests.rs"]
mod tests;
