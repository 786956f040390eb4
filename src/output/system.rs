//! A linear system `A x = b` on disk, for other solvers: MatrixMarket (written by
//! `nalgebra-sparse`; `A` as a sparse coordinate matrix, `b` and `x` as `n x 1`
//! coordinate matrices, readable by scipy's `mmread`, Matlab/Octave and Julia) and
//! PETSc's binary format (`MatLoad` / `VecLoad`: big-endian 32-bit integers and 64-bit
//! reals; AIJ = row lengths, column indices and values row by row).

use super::{write_atomic, OutputError};
use nalgebra_sparse::{io::save_to_matrix_market_str, CooMatrix, CscMatrix, CsrMatrix};
use std::path::Path;

/// PETSc's class id of a matrix in its binary format (`MAT_FILE_CLASSID`).
pub const PETSC_MAT_CLASSID: i32 = 1211216;
/// PETSc's class id of a vector (`VEC_FILE_CLASSID`).
pub const PETSC_VEC_CLASSID: i32 = 1211214;

/// The banner as the MatrixMarket specification spells it, `%%MatrixMarket`
/// (`nalgebra-sparse` writes it in lower case, which case-sensitive readers such as
/// older scipy versions reject).
fn canonical_banner(text: String) -> String {
    match text.strip_prefix("%%matrixmarket") {
        Some(rest) => format!("%%MatrixMarket{rest}"),
        None => text,
    }
}

/// A square sparse matrix in compressed-column form (as assembled).
pub struct ColumnMatrix<'a> {
    /// Rows = columns.
    pub n: usize,
    /// Start of each column in `rows` / `values` (`n + 1` entries).
    pub column_starts: &'a [usize],
    /// Row of each stored entry.
    pub rows: &'a [usize],
    /// Value of each stored entry.
    pub values: &'a [f64],
}

/// `A`, `b`, `x` written into `dir` as `matrix.mtx`, `rhs.mtx`, `solution.mtx`,
/// `matrix.petsc`, `rhs.petsc` (module docs). `dir` must exist.
pub fn write_system(dir: &Path, a: &ColumnMatrix, b: &[f64], x: &[f64]) -> Result<(), OutputError> {
    let invalid = |what: &str| OutputError::InvalidInput { path: dir.to_path_buf(), detail: what.to_string() };
    let csc = CscMatrix::try_from_csc_data(a.n, a.n, a.column_starts.to_vec(), a.rows.to_vec(), a.values.to_vec())
        .map_err(|e| invalid(&format!("the matrix is not a valid compressed-column matrix: {e}")))?;
    if b.len() != a.n || x.len() != a.n {
        return Err(invalid(&format!("{} unknowns, a right-hand side of {} and a solution of {}", a.n, b.len(), x.len())));
    }
    write_atomic(&dir.join("matrix.mtx"), canonical_banner(save_to_matrix_market_str(&csc)).as_bytes())?;
    let column = |v: &[f64]| {
        let mut c = CooMatrix::new(v.len(), 1);
        for (i, &value) in v.iter().enumerate() {
            c.push(i, 0, value);
        }
        canonical_banner(save_to_matrix_market_str(&c))
    };
    write_atomic(&dir.join("rhs.mtx"), column(b).as_bytes())?;
    write_atomic(&dir.join("solution.mtx"), column(x).as_bytes())?;
    let int = |v: usize| i32::try_from(v).map_err(|_| invalid(&format!("{v} does not fit PETSc's 32-bit indices")));
    let csr = CsrMatrix::from(&csc);
    let mut mat = Vec::with_capacity(16 + 4 * a.n + 12 * csr.nnz());
    for h in [PETSC_MAT_CLASSID, int(a.n)?, int(a.n)?, int(csr.nnz())?] {
        mat.extend_from_slice(&h.to_be_bytes());
    }
    for row in csr.row_iter() {
        mat.extend_from_slice(&int(row.nnz())?.to_be_bytes());
    }
    for &j in csr.col_indices() {
        mat.extend_from_slice(&int(j)?.to_be_bytes());
    }
    for &v in csr.values() {
        mat.extend_from_slice(&v.to_be_bytes());
    }
    write_atomic(&dir.join("matrix.petsc"), &mat)?;
    let mut vec = Vec::with_capacity(8 + 8 * a.n);
    vec.extend_from_slice(&PETSC_VEC_CLASSID.to_be_bytes());
    vec.extend_from_slice(&int(a.n)?.to_be_bytes());
    for &v in b {
        vec.extend_from_slice(&v.to_be_bytes());
    }
    write_atomic(&dir.join("rhs.petsc"), &vec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::io::load_coo_from_matrix_market_str;

    /// `[[4, 1, 0], [2, 5, -1], [0, -3, 6]]`: the MatrixMarket files read back to the
    /// same entries, and the PETSc file has the header, row lengths (2, 3, 2), column
    /// indices row by row and the values, big-endian.
    #[test]
    fn a_small_system_round_trips() {
        let tmp = tempfile::tempdir().unwrap();
        // Columns: 0 -> rows 0, 1; 1 -> rows 0, 1, 2; 2 -> rows 1, 2.
        let a = ColumnMatrix {
            n: 3,
            column_starts: &[0, 2, 5, 7],
            rows: &[0, 1, 0, 1, 2, 1, 2],
            values: &[4.0, 2.0, 1.0, 5.0, -3.0, -1.0, 6.0],
        };
        write_system(tmp.path(), &a, &[1.0, 2.0, 3.0], &[0.5, -0.25, 0.125]).unwrap();
        let text = std::fs::read_to_string(tmp.path().join("matrix.mtx")).unwrap();
        assert!(text.starts_with("%%MatrixMarket matrix coordinate real general\n"), "{text}");
        let m: CooMatrix<f64> = load_coo_from_matrix_market_str(&std::fs::read_to_string(tmp.path().join("matrix.mtx")).unwrap()).unwrap();
        let mut entries: Vec<(usize, usize, f64)> = m.triplet_iter().map(|(i, j, v)| (i, j, *v)).collect();
        entries.sort_by_key(|e| (e.0, e.1));
        assert_eq!(entries, vec![(0, 0, 4.0), (0, 1, 1.0), (1, 0, 2.0), (1, 1, 5.0), (1, 2, -1.0), (2, 1, -3.0), (2, 2, 6.0)]);
        let x: CooMatrix<f64> =
            load_coo_from_matrix_market_str(&std::fs::read_to_string(tmp.path().join("solution.mtx")).unwrap()).unwrap();
        assert_eq!((x.nrows(), x.ncols()), (3, 1));
        assert_eq!(x.values(), &[0.5, -0.25, 0.125]);

        let bytes = std::fs::read(tmp.path().join("matrix.petsc")).unwrap();
        let ints: Vec<i32> = bytes[..4 * (4 + 3 + 7)].chunks(4).map(|c| i32::from_be_bytes(c.try_into().unwrap())).collect();
        assert_eq!(ints, vec![PETSC_MAT_CLASSID, 3, 3, 7, 2, 3, 2, 0, 1, 0, 1, 2, 1, 2]);
        let values: Vec<f64> = bytes[4 * 14..].chunks(8).map(|c| f64::from_be_bytes(c.try_into().unwrap())).collect();
        assert_eq!(values, vec![4.0, 1.0, 2.0, 5.0, -1.0, -3.0, 6.0]);
        let v = std::fs::read(tmp.path().join("rhs.petsc")).unwrap();
        assert_eq!(v.len(), 8 + 24);
        assert_eq!(i32::from_be_bytes(v[..4].try_into().unwrap()), PETSC_VEC_CLASSID);
        assert_eq!(f64::from_be_bytes(v[24..32].try_into().unwrap()), 3.0);
    }
}
