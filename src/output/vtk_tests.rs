//! Tests of `vtk.rs` (kept in a separate file to keep `vtk.rs` short).

use super::*;
use crate::domain::cells::triangulate;

/// Asserts that two `f64` slices are identical bit for bit (NaN payloads included).
fn assert_bits_eq(name: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{name}: length");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "{name}[{i}]: {x} vs {y}");
    }
}

/// A 7x5 grid with awkward coordinates and its triangulation.
fn grid() -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let mut pts = Vec::new();
    for j in 0..5 {
        for i in 0..7 {
            pts.push([1e-3 + i as f64 / 3.0, -7.0 + j as f64 * std::f64::consts::PI]);
        }
    }
    let tris = triangulate(&pts, |_| true);
    (pts, tris)
}

#[test]
fn vtu_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.vtu");
    let (pts, tris) = grid();
    let n = pts.len();
    assert_eq!(tris.len(), 2 * 6 * 4);

    let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.1).sin() * 10f64.powi(i as i32 % 40 - 20)).collect();
    let u: Vec<[f64; 2]> = (0..n).map(|i| [1.0 / (i as f64 + 3.0), -1e-310]).collect();
    let v3: Vec<f64> = (0..3 * n).map(|k| (k as f64).sqrt() - 2.5).collect();
    let g4: Vec<f64> = (0..4 * n).map(|k| k as f64 * 0.1).collect();
    let mut kind: Vec<i32> = (0..n as i32).map(|i| i * 7 - 100).collect();
    kind[0] = i32::MIN;
    kind[1] = i32::MAX;
    let mut special = vec![0.0; n];
    special[0] = f64::NAN;
    special[1] = f64::INFINITY;
    special[2] = f64::NEG_INFINITY;
    special[3] = -0.0;

    let fields = vec![
        PointField::scalar("s", s.clone()),
        PointField::vector2("displacement", &u),
        PointField { name: "v3".into(), components: 3, values: FieldValues::F64(v3.clone()) },
        PointField { name: "g4".into(), components: 4, values: FieldValues::F64(g4.clone()) },
        PointField::integer("kind", kind.clone()),
        PointField::scalar("special", special.clone()),
        PointField::scalar("a<b & \"c\"", s.clone()),
    ];
    write_vtu(&path, &pts, &tris, fields.clone()).unwrap();

    let raw = std::fs::read_to_string(&path).unwrap();
    for needle in [
        "type=\"UnstructuredGrid\"",
        "version=\"1.0\"",
        "byte_order=\"LittleEndian\"",
        "header_type=\"UInt64\"",
        "type=\"Float64\" Name=\"Points\"",
        "type=\"Int32\" Name=\"kind\"",
        "format=\"binary\"",
    ] {
        assert!(raw.contains(needle), "missing {needle}");
    }
    // Non-finite ranges (from the "special" array) are removed, finite ones kept.
    assert!(!raw.contains("\"NaN\"") && !raw.contains("\"inf\"") && !raw.contains("\"-inf\""));
    assert!(raw.contains("Name=\"kind\" format=\"binary\" RangeMin=\"-2147483648\" RangeMax=\"2147483647\""));

    let back = read_vtu(&path).unwrap();
    assert_eq!(back.points.len(), n);
    for (p, q) in pts.iter().zip(&back.points) {
        assert_bits_eq("points", &[p[0], p[1], 0.0], q);
    }
    assert_eq!(back.cells, tris.len());
    assert_eq!(back.fields.len(), fields.len());

    let get = |name: &str| back.fields.get(name).unwrap_or_else(|| panic!("{name}"));
    assert_eq!(get("s").0, 1);
    assert_bits_eq("s", &get("s").1, &s);
    let (c, disp) = get("displacement");
    assert_eq!(*c, 3, "2D vectors are padded to 3 components");
    let padded: Vec<f64> = u.iter().flat_map(|d| [d[0], d[1], 0.0]).collect();
    assert_bits_eq("displacement", disp, &padded);
    assert_eq!(get("v3").0, 3);
    assert_bits_eq("v3", &get("v3").1, &v3);
    assert_eq!(get("g4").0, 4);
    assert_bits_eq("g4", &get("g4").1, &g4);
    assert_eq!(get("kind").0, 1);
    let kind_f: Vec<f64> = kind.iter().map(|&k| k as f64).collect();
    assert_bits_eq("kind", &get("kind").1, &kind_f);
    assert_bits_eq("special", &get("special").1, &special);
    assert_bits_eq("escaped name", &get("a<b & \"c\"").1, &s);
}

#[test]
fn vtu_without_cells_or_fields() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pts.vtu");
    let pts = [[0.5, 0.25], [1.0, -2.0]];
    write_vtu(&path, &pts, &[], vec![]).unwrap();
    let back = read_vtu(&path).unwrap();
    assert_eq!(back.points, vec![[0.5, 0.25, 0.0], [1.0, -2.0, 0.0]]);
    assert_eq!(back.cells, 0);
    assert!(back.fields.is_empty());
}

#[test]
fn invalid_field_length_names_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.vtu");
    let (pts, tris) = grid();
    let n = pts.len();
    let fields = vec![PointField::scalar("ok", vec![0.0; n]), PointField::vector2("sigma_bad", &vec![[0.0; 2]; n - 1])];
    let err = write_vtu(&path, &pts, &tris, fields).unwrap_err();
    match &err {
        OutputError::InvalidField { name, detail } => {
            assert_eq!(name, "sigma_bad");
            assert!(detail.contains(&format!("{}", 2 * (n - 1))), "{detail}");
        }
        other => panic!("unexpected {other:?}"),
    }
    assert!(err.to_string().contains("sigma_bad"));
    assert!(!path.exists(), "nothing may be written on error");

    let zero = PointField { name: "z".into(), components: 0, values: FieldValues::F64(vec![]) };
    let err = write_vtu(&path, &pts, &tris, vec![zero]).unwrap_err();
    assert!(matches!(err, OutputError::InvalidField { ref name, .. } if name == "z"));

    let dup = vec![PointField::integer("k", vec![0; n]), PointField::integer("k", vec![1; n])];
    let err = write_vtu(&path, &pts, &tris, dup).unwrap_err();
    assert!(matches!(err, OutputError::InvalidField { ref name, .. } if name == "k"));
    assert!(!path.exists());
}

#[test]
fn invalid_mesh_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.vtu");
    let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let err = write_vtu(&path, &pts, &[[0, 1, 3]], vec![]).unwrap_err();
    assert!(matches!(err, OutputError::InvalidInput { .. }), "{err:?}");
    assert!(err.to_string().contains("triangle 0"), "{err}");
    let err = write_vtu(&path, &[[0.0, f64::NAN]], &[], vec![]).unwrap_err();
    assert!(err.to_string().contains("point 0"), "{err}");
    assert!(!path.exists());
}

#[test]
fn read_vtu_reports_bad_files_without_panicking() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.vtu");
    assert!(matches!(
        read_vtu(&missing),
        Err(OutputError::Io { ref path, .. }) if path == &missing
    ));

    let garbage = dir.path().join("garbage.vtu");
    std::fs::write(&garbage, b"this is not xml <<<").unwrap();
    assert!(matches!(read_vtu(&garbage), Err(OutputError::Vtk { .. })));

    // A well-formed grid without <Points>: vtkio itself would panic here.
    let no_points = dir.path().join("nopoints.vtu");
    std::fs::write(
        &no_points,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\
         <UnstructuredGrid><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"></Piece>\
         </UnstructuredGrid></VTKFile>",
    )
    .unwrap();
    assert!(matches!(read_vtu(&no_points), Err(OutputError::Vtk { .. })));

    // A point-data array with a wrong length is dropped by vtkio; we must notice.
    let good = dir.path().join("good.vtu");
    write_vtu(&good, &[[0.0, 0.0], [1.0, 0.0]], &[], vec![PointField::scalar("f", vec![1.0, 2.0])]).unwrap();
    assert_eq!(read_vtu(&good).unwrap().fields.len(), 1);
    // Claim two components for a one-component array: vtkio drops it silently on reading.
    let text = std::fs::read_to_string(&good).unwrap();
    let text = text.replacen("Name=\"f\"", "Name=\"f\" NumberOfComponents=\"2\"", 1);
    assert!(text.contains("NumberOfComponents=\"2\""));
    let tampered = dir.path().join("tampered.vtu");
    std::fs::write(&tampered, text).unwrap();
    let err = read_vtu(&tampered).unwrap_err();
    assert!(err.to_string().contains("could be decoded"), "{err}");
}

#[test]
fn pvd_lists_every_file_and_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("series.pvd");
    let entries: Vec<(f64, String)> =
        vec![(0.0, "run_0000.vtu".into()), (0.1 + 0.2, "run_0001.vtu".into()), (1e-9, "sub/run&2.vtu".into())];
    write_pvd(&path, &entries).unwrap();
    let xml = std::fs::read_to_string(&path).unwrap();
    assert!(xml.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\""));
    assert_eq!(xml.matches("<Collection>").count(), 1);
    assert!(xml.trim_end().ends_with("</Collection>\n</VTKFile>"));

    // Minimal parse of the DataSet elements: timestep and file attributes, in order.
    let attr = |line: &str, key: &str| -> String {
        let start = line.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
        let len = line[start..].find('"').unwrap();
        line[start..start + len].to_string()
    };
    let datasets: Vec<&str> = xml.lines().filter(|l| l.contains("<DataSet ")).collect();
    assert_eq!(datasets.len(), entries.len());
    for (line, (t, file)) in datasets.iter().zip(&entries) {
        assert!(line.trim_end().ends_with("/>"));
        let t_back: f64 = attr(line, "timestep").parse().unwrap();
        assert_eq!(t_back.to_bits(), t.to_bits());
        assert_eq!(attr(line, "file").replace("&amp;", "&"), *file);
    }
    assert!(xml.contains("file=\"sub/run&amp;2.vtu\""));

    let err = write_pvd(&path, &[(f64::NAN, "x.vtu".into())]).unwrap_err();
    assert!(matches!(err, OutputError::InvalidInput { .. }));
    // The earlier file is still intact after the failed call.
    assert_eq!(std::fs::read_to_string(&path).unwrap(), xml);
}

/// A writer that takes at most `chunk` bytes per call and fails once `limit` bytes
/// have been taken.
struct Stingy {
    taken: Vec<u8>,
    chunk: usize,
    limit: usize,
}

impl std::io::Write for Stingy {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.taken.len() >= self.limit {
            return Err(std::io::Error::other("device full"));
        }
        let n = buf.len().min(self.chunk).min(self.limit - self.taken.len());
        self.taken.extend_from_slice(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// vtkio's own model of `points`, `triangles` and one scalar field `s`: what its
/// `write_xml` makes of it is the reference for [`write_vtu`].
fn vtkio_model(points: &[[f64; 2]], triangles: &[[usize; 3]], s: &[f64], v: &[f64]) -> Vtk {
    use vtkio::model::{Attributes, Cells, DataArray, ElementType, UnstructuredGridPiece, Version, VertexNumbers};
    let point_data = vec![
        Attribute::DataArray(DataArray {
            name: "s".into(),
            elem: ElementType::Scalars { num_comp: 1, lookup_table: None },
            data: s.to_vec().into(),
        }),
        Attribute::DataArray(DataArray { name: "v".into(), elem: ElementType::Vectors, data: v.to_vec().into() }),
    ];
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

/// The file is byte for byte what vtkio's own writer makes of the same grid (plus a
/// final newline): only the nesting is written here, so that the arrays are not copied
/// once per enclosing element as quick-xml's serialiser does.
#[test]
fn the_file_is_what_vtkio_writes() {
    let (pts, tris) = grid();
    let s: Vec<f64> = (0..pts.len()).map(|i| (i as f64 * 0.37).sin()).collect();
    let v: Vec<f64> = (0..3 * pts.len()).map(|k| k as f64 / 7.0 - 3.0).collect();
    let mut reference = Vec::new();
    vtkio_model(&pts, &tris, &s, &v).write_xml(&mut reference).unwrap();
    reference.push(b'\n');
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.vtu");
    let fields = vec![PointField::scalar("s", s), PointField { name: "v".into(), components: 3, values: FieldValues::F64(v) }];
    write_vtu(&path, &pts, &tris, fields).unwrap();
    let ours = std::fs::read(&path).unwrap();
    assert_eq!(String::from_utf8(ours).unwrap(), String::from_utf8(reference).unwrap());
}

/// A write error (a device that fills up at 10 bytes, half the file or one byte short)
/// is the result, whatever the writer takes per call; through a writer that takes 7
/// bytes per call the file is complete.
#[test]
fn a_write_error_is_the_result() {
    let (pts, tris) = grid();
    let arrays = || {
        let fields = vec![PointField::scalar("s", (0..pts.len()).map(|k| k as f64 / 3.0).collect())];
        (fields.into_iter().map(|f| encode_field(f).unwrap()).collect::<Vec<_>>(), encode_mesh(&pts, &tris).unwrap())
    };
    let head = "<VTKFile>";
    let mut whole = Stingy { taken: Vec::new(), chunk: 7, limit: usize::MAX };
    let (f, m) = arrays();
    write_grid(&mut whole, head, f, m).unwrap();
    let size = whole.taken.len();
    assert!(whole.taken.ends_with(b"</VTKFile>\n"));
    for limit in [10, size / 2, size - 1] {
        let mut full = Stingy { taken: Vec::new(), chunk: 4096, limit };
        let (f, m) = arrays();
        let err = write_grid(&mut full, head, f, m).unwrap_err();
        assert!(err.to_string().contains("device full"), "limit {limit}: {err}");
    }
}
