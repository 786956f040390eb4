//! Saad's dual-threshold incomplete LU, ILUT(τ, p), without pivoting, written here
//! because `faer-precond` offers only ILU(0).

use super::{SolveError, SparseMatrix};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Saad's dual-threshold incomplete LU, ILUT(τ, p), without pivoting
/// (Y. Saad, "ILUT: a dual threshold incomplete LU factorization",
/// *Numer. Linear Algebra Appl.* 1 (1994) 387–402; *Iterative Methods for
/// Sparse Linear Systems*, 2nd ed., Alg. 10.6). IKJ (row-by-row) variant:
///
/// ```text
/// for i = 1..n:
///     w = a_i*;  τ_i = τ ‖a_i*‖₂
///     for k < i with w_k ≠ 0, in increasing k:
///         if |w_k| < τ_i: w_k ← 0 (drop)
///         else: w_k ← w_k / u_kk;  w_j ← w_j − w_k u_kj  (j > k)
///     drop every off-diagonal entry whose size (below) is < τ_i
///     L row i ← the  nnz(L-part of a_i*) + p  largest entries, j < i
///     U row i ← w_i and the  nnz(U-part of a_i*) + p  largest entries, j > i
/// ```
///
/// * `fill = p` counts entries allowed **beyond** the original row's count
///   in each triangle (the "p largest" rule offset by the original pattern,
///   so ILUT never stores less than the pattern of `A` when nothing is small).
/// * Size of an L entry is `|l_ik|·|u_kk|` (the working-row entry *before*
///   division by the pivot); of a U entry `|u_ij|`. Saad compares `|l_ik|`
///   itself, which mixes the scales of rows `i` and `k`; our measure makes
///   the dropping invariant under row scaling (`ILUT(DA) = D·ILUT(A)`
///   structurally), and the two coincide for an equilibrated matrix with
///   `|u_kk| ≈ 1`.
/// * With `τ = 0`, `p ≥ n` only exact zeros are dropped and `L U = A`
///   (Gaussian elimination without pivoting).
/// * No pivot modification: a numerically zero (`|u_ii| ≤`
///   [`ILUT_PIVOT_RTOL`]`·‖a_i*‖₂`) or non-finite `u_ii`, or a non-finite
///   `L`/`U` entry, is an error naming the first such row. Testing only for
///   `u_ii == 0` is not enough: a row whose diagonal is a round-off zero
///   (`|a_ii| ~ 1e-17 ‖a_i*‖`, e.g. a traction row whose centre weight
///   cancels) gives a "pivot" of pure round-off, multipliers `~1e17` and then
///   inf/NaN entries, and the factorisation used to fail (or return garbage)
///   thousands of rows later with a meaningless `0`/`NaN` pivot.
#[derive(Clone, Debug)]
pub struct Ilut {
    n: usize,
    // Strictly lower part of L (unit diagonal implied), CSR.
    l_ptr: Vec<usize>,
    l_idx: Vec<usize>,
    l_val: Vec<f64>,
    // Strictly upper part of U, CSR; diagonal stored inverted.
    u_ptr: Vec<usize>,
    u_idx: Vec<usize>,
    u_val: Vec<f64>,
    inv_diag: Vec<f64>,
}

/// Relative size below which an ILUT pivot counts as zero: `u_ii` is
/// rejected when `|u_ii| ≤ ILUT_PIVOT_RTOL · ‖a_i*‖₂`. Such a pivot is
/// dominated by round-off (or makes every later multiplier `≳ 1e12`, which
/// amplifies the dropped entries far beyond the drop tolerance), so the
/// incomplete factor is useless either way.
pub const ILUT_PIVOT_RTOL: f64 = 1e-12;

/// CSR copy `(row_ptr, col_idx, val)` of a CSC matrix (column indices sorted
/// within each row).
fn to_csr(a: &SparseMatrix) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let n = a.nrows();
    let mut ptr = vec![0usize; n + 1];
    for j in 0..a.ncols() {
        for &i in a.symbolic().row_idx_of_col_raw(j) {
            ptr[i + 1] += 1;
        }
    }
    for i in 0..n {
        ptr[i + 1] += ptr[i];
    }
    let nnz = ptr[n];
    let mut next = ptr.clone();
    let (mut idx, mut val) = (vec![0usize; nnz], vec![0.0f64; nnz]);
    for j in 0..a.ncols() {
        for (&i, &v) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            idx[next[i]] = j;
            val[next[i]] = v;
            next[i] += 1;
        }
    }
    (ptr, idx, val)
}

/// Keep the `limit` entries of `set` with largest `size(j)` (order unspecified).
fn keep_largest(set: &mut Vec<usize>, limit: usize, size: impl Fn(usize) -> f64) {
    if set.len() > limit {
        if limit == 0 {
            set.clear();
            return;
        }
        set.select_nth_unstable_by(limit - 1, |&a, &b| size(b).total_cmp(&size(a)));
        set.truncate(limit);
    }
}

impl Ilut {
    /// Factor `a` (see the type docs). Errors: [`SolveError::Singular`] for a
    /// zero/non-finite pivot, [`SolveError::Dimension`] for a negative or
    /// non-finite `drop`.
    pub fn try_new(a: &SparseMatrix, drop: f64, fill: usize) -> Result<Self, SolveError> {
        if !(drop >= 0.0 && drop.is_finite()) {
            return Err(SolveError::Dimension { detail: format!("ILUT drop tolerance must be finite and >= 0, got {drop}") });
        }
        let n = a.nrows();
        let (a_ptr, a_idx, a_val) = to_csr(a);
        let mut f = Ilut {
            n,
            l_ptr: vec![0],
            l_idx: Vec::new(),
            l_val: Vec::new(),
            u_ptr: vec![0],
            u_idx: Vec::new(),
            u_val: Vec::new(),
            inv_diag: vec![0.0; n],
        };
        let mut row = WorkingRow::new(n);
        for i in 0..n {
            let (cols, vals) = (&a_idx[a_ptr[i]..a_ptr[i + 1]], &a_val[a_ptr[i]..a_ptr[i + 1]]);
            let row_norm = vals.iter().map(|v| v * v).sum::<f64>().sqrt();
            let (nl0, nu0) = row.load(i, cols, vals);
            row.eliminate(i, &f, drop * row_norm);
            // τ-rule for U (L was filtered during elimination); the diagonal
            // i is never in `upper` because it was pre-marked.
            let (w, tau) = (&row.w, drop * row_norm);
            row.upper.retain(|&j| w[j] != 0.0 && w[j].abs() >= tau);
            let inv_diag = &f.inv_diag;
            keep_largest(&mut row.lower, nl0 + fill, |j| (w[j] / inv_diag[j]).abs());
            keep_largest(&mut row.upper, nu0 + fill, |j| w[j].abs());
            let piv = row.w[i];
            check_pivot(i, piv, row_norm, cols, vals, drop, fill)?;
            if let Some(&j) = row.lower.iter().chain(&row.upper).find(|&&j| !row.w[j].is_finite()) {
                return Err(SolveError::Singular {
                    detail: format!(
                        "ILUT(drop={drop:e}, fill={fill}) overflowed: entry ({i}, {j}) of the \
                         factors is {}; earlier pivots are too small (element growth without \
                         pivoting); try a smaller drop / larger fill, ilu0, or lu",
                        row.w[j]
                    ),
                });
            }
            f.inv_diag[i] = 1.0 / piv;
            f.l_idx.extend_from_slice(&row.lower);
            f.l_val.extend(row.lower.iter().map(|&j| row.w[j]));
            f.l_ptr.push(f.l_idx.len());
            f.u_idx.extend_from_slice(&row.upper);
            f.u_val.extend(row.upper.iter().map(|&j| row.w[j]));
            f.u_ptr.push(f.u_idx.len());
        }
        Ok(f)
    }

    /// Dimension `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries: strict L + strict U + diagonal.
    pub fn nonzeros(&self) -> usize {
        self.l_idx.len() + self.u_idx.len() + self.n
    }

    /// `x ← (LU)⁻¹ x`: forward substitution with unit-lower `L`, then back
    /// substitution with `U`.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        assert_eq!(x.len(), self.n);
        for i in 0..self.n {
            let mut s = x[i];
            for p in self.l_ptr[i]..self.l_ptr[i + 1] {
                s -= self.l_val[p] * x[self.l_idx[p]];
            }
            x[i] = s;
        }
        for i in (0..self.n).rev() {
            let mut s = x[i];
            for p in self.u_ptr[i]..self.u_ptr[i + 1] {
                s -= self.u_val[p] * x[self.u_idx[p]];
            }
            x[i] = s * self.inv_diag[i];
        }
    }
}

/// The working row `w` of the IKJ elimination with its pattern.
struct WorkingRow {
    w: Vec<f64>,
    /// `mark[j] == i` while row `i` holds an entry at `j`.
    mark: Vec<usize>,
    /// Columns `k < i` still to eliminate, smallest first.
    heap: BinaryHeap<Reverse<usize>>,
    lower: Vec<usize>,
    upper: Vec<usize>,
}

impl WorkingRow {
    fn new(n: usize) -> Self {
        // No row is numbered n: every column starts unmarked.
        WorkingRow { w: vec![0.0; n], mark: vec![n; n], heap: BinaryHeap::new(), lower: Vec::new(), upper: Vec::new() }
    }

    /// Scatter row `i` of `A`; returns its entry counts left and right of the diagonal.
    fn load(&mut self, i: usize, cols: &[usize], vals: &[f64]) -> (usize, usize) {
        self.lower.clear();
        self.upper.clear();
        self.mark[i] = i;
        self.w[i] = 0.0;
        let (mut nl0, mut nu0) = (0, 0);
        for (&j, &v) in cols.iter().zip(vals) {
            self.mark[j] = i;
            self.w[j] = v;
            if j < i {
                nl0 += 1;
                self.heap.push(Reverse(j));
            } else if j > i {
                nu0 += 1;
                self.upper.push(j);
            }
        }
        (nl0, nu0)
    }

    /// Eliminate with the finished rows of `f`, in increasing `k`, dropping
    /// multipliers below `tau`; fill-in from row `k` lands at `j > k`, so the heap
    /// never needs an index smaller than the one popped.
    fn eliminate(&mut self, i: usize, f: &Ilut, tau: f64) {
        let w = &mut self.w;
        while let Some(Reverse(k)) = self.heap.pop() {
            if w[k] == 0.0 || w[k].abs() < tau {
                w[k] = 0.0;
                continue;
            }
            let wk = w[k] * f.inv_diag[k];
            w[k] = wk;
            self.lower.push(k);
            for p in f.u_ptr[k]..f.u_ptr[k + 1] {
                let j = f.u_idx[p];
                if self.mark[j] != i {
                    self.mark[j] = i;
                    w[j] = 0.0;
                    if j < i {
                        self.heap.push(Reverse(j));
                    } else {
                        self.upper.push(j); // j > i: the diagonal i was pre-marked
                    }
                }
                w[j] -= wk * f.u_val[p];
            }
        }
    }
}

/// A usable pivot, or the error that names row `i` and the likely cause.
fn check_pivot(i: usize, piv: f64, row_norm: f64, cols: &[usize], vals: &[f64], drop: f64, fill: usize) -> Result<(), SolveError> {
    // A NaN threshold or pivot fails this test too.
    let threshold = ILUT_PIVOT_RTOL * row_norm;
    if piv.is_finite() && threshold.is_finite() && piv.abs() > threshold {
        return Ok(());
    }
    let a_ii = cols.binary_search(&i).map_or(0.0, |p| vals[p]);
    let cause = if a_ii.abs() <= ILUT_PIVOT_RTOL * row_norm {
        format!(
            "the row's own diagonal a_ii = {a_ii:.1e} is (numerically) zero, so \
             its pivot can only come from fill the drop/fill limits removed; \
             order the equations so that every row has a substantial diagonal, \
             or use lu"
        )
    } else {
        format!("a_ii = {a_ii:.1e}; try a smaller drop / larger fill, ilu0, or lu")
    };
    Err(SolveError::Singular {
        detail: format!(
            "ILUT(drop={drop:e}, fill={fill}) hit a zero or non-finite pivot \
             u_ii = {piv:.1e} in row {i} (‖a_i‖₂ = {row_norm:.1e}); {cause}"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{assemble, relative_residual, Triplets};
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Random n×n matrix, ~`density` off-diagonal fill, strictly diagonally
    /// dominant by rows (so Gaussian elimination without pivoting is stable).
    fn random_dd(n: usize, density: f64, seed: u64) -> SparseMatrix {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut t = Triplets::new(n);
        for i in 0..n {
            let mut row_sum = 0.0;
            for j in 0..n {
                if j != i && rng.random::<f64>() < density {
                    let v: f64 = rng.random_range(-1.0..1.0);
                    row_sum += v.abs();
                    t.push(i, j, v);
                }
            }
            t.push(i, i, (row_sum + 1.0) * if rng.random::<bool>() { 1.0 } else { -1.0 });
        }
        assemble(&t).unwrap()
    }

    #[test]
    fn ilut_without_dropping_is_exact_lu() {
        let n = 60;
        let a = random_dd(n, 0.3, 7);
        let p = Ilut::try_new(&a, 0.0, n).unwrap();
        // Full fill: L + U must have (almost) n² entries for a 30%-dense random matrix.
        assert!(p.nonzeros() > n * n * 9 / 10, "nnz {}", p.nonzeros());
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.5).collect();
        let mut x = b.clone();
        p.solve_in_place(&mut x);
        let r = relative_residual(&a, &x, &b);
        // Exact LU of a diagonally dominant (κ ≈ 10) 60×60 matrix: residual is
        // O(n ε) ≈ 1e-14; 1e-12 leaves margin but would catch any dropped entry
        // (a single dropped fill entry gives ≳ 1e-4).
        assert!(r < 1e-12, "one ILUT(0, n) application left residual {r:.2e}");
    }

    #[test]
    fn ilut_dropping_reduces_fill_and_respects_row_limits() {
        let n = 200;
        let a = random_dd(n, 0.1, 3);
        let full = Ilut::try_new(&a, 0.0, n).unwrap();
        let fill = 2;
        let p = Ilut::try_new(&a, 1e-2, fill).unwrap();
        assert!(p.nonzeros() < full.nonzeros() / 2);
        // Per-row limit: original L (U) count + fill.
        let (ap, ai, _) = to_csr(&a);
        for i in 0..n {
            let nl0 = ai[ap[i]..ap[i + 1]].iter().filter(|&&j| j < i).count();
            let nu0 = ai[ap[i]..ap[i + 1]].iter().filter(|&&j| j > i).count();
            assert!(p.l_ptr[i + 1] - p.l_ptr[i] <= nl0 + fill);
            assert!(p.u_ptr[i + 1] - p.u_ptr[i] <= nu0 + fill);
            assert!(p.l_idx[p.l_ptr[i]..p.l_ptr[i + 1]].iter().all(|&j| j < i));
            assert!(p.u_idx[p.u_ptr[i]..p.u_ptr[i + 1]].iter().all(|&j| j > i));
        }
        // Still a useful approximation: one application reduces the residual
        // well below 1 (measured ~0.1–0.3 for this matrix; 0.7 is lenient).
        let b = vec![1.0; n];
        let mut x = b.clone();
        p.solve_in_place(&mut x);
        let r = relative_residual(&a, &x, &b);
        assert!(r < 0.7, "residual after one ILUT application {r}");
    }

    /// Regression (steel plate with the traction equations in the boundary
    /// nodes' own rows): a row whose diagonal is a round-off zero gets its
    /// pivot only from fill, and the fill limit can drop exactly that fill.
    /// ILUT used to accept the round-off "pivot" (here 1e-17), divide by it
    /// and fail thousands of rows later with a meaningless `0`/`NaN` pivot
    /// (or return inf entries). It must stop at the offending row instead.
    #[test]
    fn round_off_zero_pivot_is_reported_at_its_own_row() {
        // Row 1 eliminates row 0 and gets fill -1 at columns 3, 4, 5, which
        // outranks its own a_12 = 0.5 under the p-rule (fill = 1 keeps
        // 1 + 1 U entries), so u_12 is dropped and row 2 (a_21 = 1,
        // a_22 = 1e-17) receives nothing on its diagonal. Exact LU has
        // u_22 = 1e-17 - 0.5 ≈ -0.5.
        let t = Triplets::from_entries(
            6,
            &[
                (0, 0, 1.0),
                (0, 3, 1.0),
                (0, 4, 1.0),
                (0, 5, 1.0),
                (1, 0, 1.0),
                (1, 1, 1.0),
                (1, 2, 0.5),
                (2, 1, 1.0),
                (2, 2, 1e-17),
                (3, 3, 1.0),
                (4, 4, 1.0),
                (5, 5, 1.0),
            ],
        );
        let a = assemble(&t).unwrap();
        match Ilut::try_new(&a, 0.0, 1) {
            Err(SolveError::Singular { detail }) => {
                assert!(detail.contains("in row 2"), "{detail}");
                assert!(detail.contains("diagonal"), "{detail}");
            }
            other => panic!("expected a Singular error at row 2, got {other:?}"),
        }
        // With room for u_12 the factorisation is the exact LU.
        let p = Ilut::try_new(&a, 0.0, 3).unwrap();
        assert!((1.0 / p.inv_diag[2] + 0.5).abs() < 1e-15);
        let b = vec![1.0; 6];
        let mut x = b.clone();
        p.solve_in_place(&mut x);
        assert!(relative_residual(&a, &x, &b) < 1e-14);
    }
}
