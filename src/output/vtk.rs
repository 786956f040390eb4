//! ParaView output: XML unstructured grids (`.vtu`, via `vtkio`) and collections (`.pvd`).
//!
//! `.vtu` files are written with `vtkio` 0.7.0-rc2 as `version="1.0"`, little endian,
//! `header_type="UInt64"`, uncompressed inline base64 (`format="binary"`). Points and `F64`
//! fields are `Float64` and `I32` fields `Int32`, so everything round-trips bit-exactly.
//! Cells use `UInt64` connectivity/offsets and `UInt8` types (5 = triangle).
//!
//! Each array is encoded by vtkio (`xml::DataArray::from_io_buffer`: the size header,
//! base64 and the range) and its element serialised by vtkio's serde model through
//! quick-xml, in parallel over the arrays and while the triangulation runs; only the
//! six enclosing tags (`VTKFile`, `UnstructuredGrid`, `Piece`, `PointData`, `Points`,
//! `Cells`) are written here, with the attributes vtkio gives them: the file is byte for
//! byte what `Vtk::write_xml` makes (test `the_file_is_what_vtkio_writes`).
//!
//! vtkio quirks worked around here:
//! * quick-xml's serialiser buffers the content of every element in a string of its own
//!   until the element ends, so `Vtk::write_xml` copied each array once per enclosing
//!   element (five times, with the doublings of each string): at 1e6 nodes (334 MB) the
//!   output stage took 5.5-5.9 s and peaked at 1.30 GB, against 3.1 s and 0.70 GB now
//!   (BENCHMARKS.md). Its writer also called `Write::write` instead of `write_all`; the
//!   payloads now go to the file with `write_all`.
//! * It `unwrap`s `u32::try_from` of the point and cell counts, so more than `u32::MAX` points
//!   or triangles would panic; we reject them with an error first.
//! * On reading, it silently drops point-data arrays it cannot decode, and it panics on some
//!   malformed input (e.g. a piece without `<Points>`). [`read_vtu`] counts the arrays in the
//!   raw XML to detect dropped ones and turns panics into [`OutputError::Vtk`].
//! * It writes `RangeMin`/`RangeMax` with Rust float formatting (`NaN`, `inf`), which VTK
//!   cannot parse; an array whose range is not finite gets none. (For multi-component
//!   arrays vtkio's range is the component-wise min/max, whereas VTK's own writer uses the
//!   magnitude range; the attributes are optional hints and left as they are.)
//! * Encoded arrays are held as base64 strings until written (about 1.4x the raw bytes);
//!   each field's values are moved into its encoding and freed there.
//! * It has no model of the `Collection` (`.pvd`) file type (an unknown `type` is even parsed
//!   as `UnstructuredGrid`), so [`write_pvd`] writes that small XML file by hand.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashSet};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use rayon::prelude::*;
use vtkio::model::{Attribute, ByteOrder, CellType, DataSet, IOBuffer, Vtk};
use vtkio::xml::{self, Compressor, EncodingInfo, ScalarType};

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

/// Checks `fields` against `n` points: names non-empty and unique, components
/// positive, `components * n` values.
fn check_fields(fields: &[PointField], n: usize) -> Result<(), OutputError> {
    let mut seen = HashSet::new();
    for f in fields {
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
    Ok(())
}

/// How ParaView is told to read a point-data array: the first one-component array is
/// its default scalar, the first three-component one its default vector.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Scalar,
    Vector,
    Generic,
}

/// One `<DataArray>` element, encoded by vtkio (header, base64, attributes), held as
/// its opening tag and its payload so that the payload goes to the file once.
struct EncodedArray {
    name: String,
    role: Role,
    open: String,
    payload: String,
}

/// Why a grid with more than `u32::MAX` points or triangles is refused.
const TOO_MANY: &str = "vtkio supports at most u32::MAX points and cells per file";

/// Closing tag of an array, and the stand-in payload whose element vtkio serialises.
const CLOSE: &str = "</DataArray>";
const STAND_IN: &str = "#";

/// `data` as a little-endian, `UInt64`-headed, uncompressed base64 `<DataArray>` named
/// `name` with `components` components, by vtkio; a range that is not finite is left
/// out (VTK cannot parse `NaN` or `inf` there; the attributes are optional hints).
fn encode(name: &str, components: u32, data: IOBuffer) -> Result<EncodedArray, String> {
    let ei = EncodingInfo {
        byte_order: ByteOrder::LittleEndian,
        header_type: ScalarType::UInt64,
        compressor: Compressor::None,
        compression_level: 0,
    };
    let mut array = xml::DataArray::from_io_buffer(data, ei).map_err(|e| e.to_string())?.with_name(name).with_num_comp(components);
    if !(array.range_min.is_some_and(f64::is_finite) && array.range_max.is_some_and(f64::is_finite)) {
        (array.range_min, array.range_max) = (None, None);
    }
    let payload = match array.data.pop() {
        Some(xml::Data::Data(s)) => s,
        _ => String::new(),
    };
    array.data = vec![xml::Data::Data(STAND_IN.into())];
    let element = quick_xml::se::to_string_with_root("DataArray", &array).map_err(|e| e.to_string())?;
    let open = element
        .strip_suffix(CLOSE)
        .and_then(|e| e.strip_suffix(STAND_IN))
        .ok_or_else(|| format!("unexpected serialisation of array `{name}`"))?
        .to_string();
    let role = match components {
        1 => Role::Scalar,
        3 => Role::Vector,
        _ => Role::Generic,
    };
    Ok(EncodedArray { name: name.to_string(), role, open, payload })
}

/// A point field as an encoded array (two components padded to three).
fn encode_field(f: PointField) -> Result<EncodedArray, String> {
    let (comps, data): (usize, IOBuffer) = match (f.values, f.components) {
        (FieldValues::F64(v), 2) => (3, pad_to_3(&v).into()),
        (FieldValues::I32(v), 2) => (3, pad_to_3(&v).into()),
        (FieldValues::F64(v), c) => (c, v.into()),
        (FieldValues::I32(v), c) => (c, v.into()),
    };
    encode(&f.name, comps as u32, data)
}

/// The points (z = 0) and the triangles' connectivity, offsets and types (5).
fn encode_mesh(points: &[[f64; 2]], triangles: &[[usize; 3]]) -> Result<Vec<EncodedArray>, String> {
    let m = triangles.len() as u64;
    let ((points, connectivity), (offsets, types)) = rayon::join(
        || {
            rayon::join(
                || encode("Points", 3, points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect::<Vec<f64>>().into()),
                || encode("connectivity", 1, triangles.iter().flatten().map(|&i| i as u64).collect::<Vec<u64>>().into()),
            )
        },
        || {
            rayon::join(
                || encode("offsets", 1, (1..=m).map(|k| 3 * k).collect::<Vec<u64>>().into()),
                || encode("types", 1, vec![CellType::Triangle as u8; m as usize].into()),
            )
        },
    );
    Ok(vec![points?, connectivity?, offsets?, types?])
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
    write_vtu_with(path, points, || Cow::Borrowed(triangles), fields)
}

/// [`write_vtu`] with the triangles made by `triangles` while the fields are encoded
/// (a Delaunay triangulation of 1e6 points takes about as long as their encoding).
pub fn write_vtu_with<'t>(
    path: &Path,
    points: &[[f64; 2]],
    triangles: impl FnOnce() -> Cow<'t, [[usize; 3]]> + Send,
    fields: Vec<PointField>,
) -> Result<(), OutputError> {
    let n = points.len();
    if u32::try_from(n).is_err() {
        return Err(OutputError::invalid(path, TOO_MANY));
    }
    if let Some(i) = points.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
        return Err(OutputError::invalid(path, format!("point {i} has a non-finite coordinate {:?}", points[i])));
    }
    check_fields(&fields, n)?;
    let (triangles, arrays) = rayon::join(triangles, || fields.into_par_iter().map(encode_field).collect::<Result<Vec<_>, _>>());
    let arrays = arrays.map_err(|e| OutputError::vtk(path, e))?;
    if u32::try_from(triangles.len()).is_err() {
        return Err(OutputError::invalid(path, TOO_MANY));
    }
    if let Some(k) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(OutputError::invalid(path, format!("triangle {k} {:?} refers to a point >= {n} (number of points)", triangles[k])));
    }
    let mesh = encode_mesh(points, &triangles).map_err(|e| OutputError::vtk(path, e))?;
    let head = format!(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\
         <UnstructuredGrid><Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{}\">",
        triangles.len()
    );
    write_atomic_with(path, |w| write_grid(w, &head, arrays, mesh).map_err(|e| OutputError::io(path, e)))
}

/// The file: `head`, the point data, the points and the cells, each array's payload
/// written straight from its string.
fn write_grid(w: &mut impl Write, head: &str, fields: Vec<EncodedArray>, mesh: Vec<EncodedArray>) -> std::io::Result<()> {
    let write = |w: &mut dyn Write, a: EncodedArray| -> std::io::Result<()> {
        w.write_all(a.open.as_bytes())?;
        w.write_all(a.payload.as_bytes())?;
        w.write_all(CLOSE.as_bytes())
    };
    w.write_all(head.as_bytes())?;
    if !fields.is_empty() {
        let mut tag = String::from("<PointData");
        for (role, attribute) in [(Role::Scalar, "Scalars"), (Role::Vector, "Vectors")] {
            if let Some(a) = fields.iter().find(|a| a.role == role) {
                tag.push_str(&format!(" {attribute}=\"{}\"", xml_escape(&a.name)));
            }
        }
        tag.push('>');
        w.write_all(tag.as_bytes())?;
        for a in fields {
            write(w, a)?;
        }
        w.write_all(b"</PointData>")?;
    }
    let mut mesh = mesh.into_iter();
    w.write_all(b"<Points>")?;
    write(w, mesh.next().expect("points"))?;
    w.write_all(b"</Points><Cells>")?;
    for a in mesh {
        write(w, a)?;
    }
    w.write_all(b"</Cells></Piece></UnstructuredGrid></VTKFile>\n")
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
