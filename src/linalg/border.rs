//! Constraints imposed with multipliers: the bordered system
//!
//! ```text
//! [ A  G ] [ x      ]   [ b ]
//! [ C  0 ] [ lambda ] = [ d ]
//! ```
//!
//! `A` the `n x n` system, `C` the `k x n` constraint rows, `G` the `n x k` columns that
//! carry the multipliers into `A`'s rows (the sector and ring balances of
//! `navier::sector`, `k` = 3 per balance). Sparse LU factors the bordered matrix as it
//! stands. The Krylov solvers take it with the block upper-triangular preconditioner
//!
//! ```text
//! P = [ M  G ]     T = -C M^-1 G,     P^-1 [v; w] = [ M^-1 (v - G T^-1 w) ; T^-1 w ]
//!     [ 0  T ]
//! ```
//!
//! `M` any preconditioner of `A` (multigrid, ILU, Jacobi) built on the leading block
//! alone, which keeps its diagonal; with `M = A`, `K P^-1 = [I 0; C A^-1 I]`, whose
//! minimal polynomial has degree 2 (Ipsen, "A note on preconditioning nonsymmetric
//! matrices", SIAM J. Sci. Comput. 23 (2001) 1050-1051), so the iteration count is
//! that of `M` on `A`. `T` is `k x k`, formed once by `k` applications of `M`.
//! Eliminating the multipliers on pivot rows instead (the earlier form) put the
//! constraint rows where the unknowns' own rows were: rows without a diagonal entry,
//! on which ILU met a zero pivot.

use super::csr::Csr;
use super::inverse::Inverse;
use super::SolveError;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// The constraints of a bordered system: one multiplier per constraint row.
#[derive(Clone, Debug, Default)]
pub struct Border {
    /// `G` by columns: for each multiplier, the rows of `A` it enters, `(row, value)`.
    pub columns: Vec<Vec<(usize, f64)>>,
    /// `C` by rows: for each multiplier, its constraint `(unknown, coefficient)`.
    pub rows: Vec<Vec<(usize, f64)>>,
    /// `d`: each constraint row's right-hand side.
    pub values: Vec<f64>,
}

impl Border {
    /// Multipliers (constraint rows), `k`.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// No constraints.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// `K = [A G; C 0]` and `[b; d]` (module docs); `A` is consumed (held twice while
    /// its rows are copied).
    pub fn bordered(&self, a: Csr, b: &[f64]) -> (Csr, Vec<f64>) {
        let (n, k) = (a.nrows(), self.len());
        assert_eq!(self.columns.len(), k, "one column of G per constraint row");
        assert_eq!(self.values.len(), k, "one right-hand side per constraint row");
        let mut in_row: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
        for (j, column) in self.columns.iter().enumerate() {
            for &(i, v) in column {
                assert!(i < n, "G enters row {i} of a {n}-row system");
                in_row.entry(i).or_default().push((n + j, v));
            }
        }
        let extra: usize = self.columns.iter().chain(&self.rows).map(Vec::len).sum();
        let (mut offsets, mut cols, mut vals) =
            (Vec::with_capacity(n + k + 1), Vec::with_capacity(a.nnz() + extra), Vec::with_capacity(a.nnz() + extra));
        offsets.push(0);
        let push = |entries: &mut dyn Iterator<Item = (usize, f64)>, cols: &mut Vec<u32>, vals: &mut Vec<f64>| {
            // Sorted by column, duplicates summed.
            let mut sorted: BTreeMap<usize, f64> = BTreeMap::new();
            for (c, v) in entries {
                *sorted.entry(c).or_default() += v;
            }
            for (c, v) in sorted {
                cols.push(u32::try_from(c).expect("columns fit in 32 bits"));
                vals.push(v);
            }
        };
        for i in 0..n {
            let row = a.row(i);
            match in_row.get(&i) {
                // Multiplier columns come after every column of A: the row stays sorted.
                Some(extra) => push(
                    &mut row.col_indices().iter().map(|&c| c as usize).zip(row.values().iter().copied()).chain(extra.iter().copied()),
                    &mut cols,
                    &mut vals,
                ),
                None => {
                    cols.extend_from_slice(row.col_indices());
                    vals.extend_from_slice(row.values());
                }
            }
            offsets.push(cols.len());
        }
        drop(a);
        for r in &self.rows {
            push(
                &mut r.iter().map(|&(c, v)| {
                    assert!(c < n, "a constraint on unknown {c} of {n}");
                    (c, v)
                }),
                &mut cols,
                &mut vals,
            );
            offsets.push(cols.len());
        }
        let mut rhs = Vec::with_capacity(n + k);
        rhs.extend_from_slice(b);
        rhs.extend_from_slice(&self.values);
        (Csr::from_parts(n + k, n + k, offsets, cols, vals), rhs)
    }
}

/// The leading `n x n` block `A` of a bordered matrix with `multipliers` trailing
/// unknowns: its first `n` rows without the multiplier columns (which come last in
/// every row).
pub fn leading_block(system: &Csr, multipliers: usize) -> Csr {
    let n = system.nrows() - multipliers;
    let (mut offsets, mut cols, mut vals) = (Vec::with_capacity(n + 1), Vec::with_capacity(system.nnz()), Vec::with_capacity(system.nnz()));
    offsets.push(0);
    for i in 0..n {
        let row = system.row(i);
        let keep = row.col_indices().partition_point(|&c| (c as usize) < n);
        cols.extend_from_slice(&row.col_indices()[..keep]);
        vals.extend_from_slice(&row.values()[..keep]);
        offsets.push(cols.len());
    }
    Csr::from_parts(n, n, offsets, cols, vals)
}

/// The block upper-triangular preconditioner of a bordered system (module docs).
#[derive(Debug)]
pub struct Bordered {
    /// `M ≈ A`.
    inner: Box<dyn Inverse>,
    /// `G` by columns, in the solved system's scale.
    columns: Vec<Vec<(usize, f64)>>,
    /// `T⁻¹`, `T = −C M⁻¹ G`.
    t_inverse: DMatrix<f64>,
    /// The leading part of the right-hand side as `M` receives it, kept between
    /// applications (one Krylov iteration each) instead of allocated every time.
    workspace: std::sync::Mutex<Vec<f64>>,
}

impl Bordered {
    /// The preconditioner of `system` (`[A G; C 0]` with `multipliers` trailing
    /// unknowns) around `inner ≈ A`. Errors: [`SolveError::Singular`] when `T` is
    /// singular (constraints that `M` cannot tell apart, or that repeat one another).
    pub fn build(system: &Csr, multipliers: usize, inner: Box<dyn Inverse>) -> Result<Self, SolveError> {
        let (n, k) = (system.nrows() - multipliers, multipliers);
        let mut columns = vec![Vec::new(); k];
        for i in 0..n {
            let row = system.row(i);
            for (&c, &v) in row.col_indices().iter().zip(row.values()) {
                if c as usize >= n {
                    columns[c as usize - n].push((i, v));
                }
            }
        }
        let mut t = DMatrix::zeros(k, k);
        let (mut g, mut y) = (vec![0.0; n], vec![0.0; n]);
        for (j, column) in columns.iter().enumerate() {
            g.iter_mut().for_each(|v| *v = 0.0);
            column.iter().for_each(|&(i, v)| g[i] = v);
            inner.solve_into(&g, &mut y);
            for r in 0..k {
                let row = system.row(n + r);
                t[(r, j)] = -row.col_indices().iter().zip(row.values()).map(|(&c, &v)| v * y[c as usize]).sum::<f64>();
            }
        }
        let largest = t.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // Largest entries of T and T⁻¹: their product bounds the condition number
        // within a factor k².
        let t_inverse = t.try_inverse().filter(|inv| {
            let inverse_largest = inv.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            largest > 0.0 && inverse_largest.is_finite() && inverse_largest * largest < 1e14
        });
        // A multigrid whose cycle diverges makes `C M⁻¹ G` meaningless (entries up to
        // 5.8e24 on the bracket at 1 mm): the failure then names that cause.
        let Some(t_inverse) = t_inverse else {
            let singular = SolveError::Singular {
                detail: format!(
                    "the {k} constraint rows of the bordered system are dependent as the preconditioner sees them \
                     (their Schur complement C M^-1 G is singular, largest entry {largest:.3e}); try lu"
                ),
            };
            return Err(singular.with_cycle_growth(inner.multigrid()));
        };
        Ok(Bordered { inner, columns, t_inverse, workspace: std::sync::Mutex::new(Vec::new()) })
    }

    /// `z = P⁻¹ v` (module docs).
    pub fn solve_into(&self, v: &[f64], z: &mut [f64]) {
        let (n, k) = (v.len() - self.columns.len(), self.columns.len());
        let lambda = &self.t_inverse * nalgebra::DVector::from_column_slice(&v[n..]);
        let mut w = self.workspace.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        w.clear();
        w.extend_from_slice(&v[..n]);
        for (column, &l) in self.columns.iter().zip(lambda.iter()) {
            column.iter().for_each(|&(i, g)| w[i] -= g * l);
        }
        self.inner.solve_into(&w, &mut z[..n]);
        z[n..n + k].copy_from_slice(lambda.as_slice());
    }

    /// `M`.
    pub fn inner(&self) -> &dyn Inverse {
        &*self.inner
    }

    /// Unknowns, multipliers included.
    pub fn dim(&self) -> usize {
        self.inner.dim() + self.columns.len()
    }

    /// Stored entries of `M`, `G` and `T⁻¹`.
    pub fn nonzeros(&self) -> usize {
        self.inner.nonzeros() + self.columns.iter().map(Vec::len).sum::<usize>() + self.t_inverse.len()
    }
}

#[cfg(test)]
mod tests {
    use super::super::precond::BuiltPreconditioner;
    use super::super::{csr, gmres, Preconditioner};
    use super::*;
    use nalgebra::DVector;

    /// A deterministic pseudo-random number in [-1, 1).
    fn noise(k: usize) -> f64 {
        let x = ((k as f64 + 1.0) * 12.9898).sin() * 43758.5453;
        2.0 * (x - x.floor()) - 1.0
    }

    /// A diagonally dominant `n x n` system with couplings, and three constraints on
    /// the unknowns of its first third with nonzero right-hand sides, whose rows 1..7
    /// carry the multipliers.
    fn example(n: usize) -> (Csr, Vec<f64>, Border) {
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i, 4.0 + noise(i)));
            for j in [(i + 1) % n, (i + 3) % n, (i + n - 1) % n] {
                entries.push((i, j, noise(10 * i + j)));
            }
        }
        let a = Csr::from_triplets(n, n, &entries);
        let b: Vec<f64> = (0..n).map(|i| noise(100 + i)).collect();
        let rows = (0..3).map(|k| (0..n / 3).filter(|j| (j + k) % 2 == 0).map(|j| (j, noise(200 + 10 * k + j))).collect()).collect();
        let columns = (0..3).map(|k| [1, 2, 4, 5, 7].iter().map(|&r| (r, noise(300 + 10 * k + r))).collect()).collect();
        let values = (0..3).map(|k| noise(400 + k)).collect();
        (a, b, Border { columns, rows, values })
    }

    /// The bordered matrix holds `A`, `G` and `C` where the module docs put them.
    #[test]
    fn the_bordered_matrix_is_a_g_c_zero() {
        let (a, b, border) = example(12);
        let (k, rhs) = border.bordered(a.clone(), &b);
        assert_eq!((k.nrows(), k.ncols(), rhs.len()), (15, 15, 15));
        let dense = |m: &Csr| {
            let mut d = DMatrix::<f64>::zeros(m.nrows(), m.ncols());
            m.entries().for_each(|(i, j, v)| d[(i, j)] += v);
            d
        };
        let (kd, ad) = (dense(&k), dense(&a));
        assert_eq!(kd.view((0, 0), (12, 12)), ad);
        assert_eq!(dense(&leading_block(&k, 3)), ad);
        for (j, column) in border.columns.iter().enumerate() {
            column.iter().for_each(|&(i, v)| assert_eq!(kd[(i, 12 + j)], v));
        }
        for (r, row) in border.rows.iter().enumerate() {
            row.iter().for_each(|&(c, v)| assert_eq!(kd[(12 + r, c)], v));
        }
        assert_eq!(kd.view((12, 12), (3, 3)), DMatrix::zeros(3, 3));
        assert_eq!(&rhs[..12], &b[..]);
        assert_eq!(&rhs[12..], &border.values[..]);
    }

    /// GMRES on the bordered system with the block preconditioner around ILU(0) of
    /// `A` meets the constraints and gives the dense solution; with `M = A` exactly
    /// (here ILUT without dropping, a complete LU of the leading block) it needs at
    /// most two iterations (module docs).
    #[test]
    fn gmres_with_the_block_preconditioner_solves_the_bordered_system() {
        let (a, b, border) = example(60);
        let (k, rhs) = border.bordered(a, &b);
        let mut dense = DMatrix::<f64>::zeros(63, 63);
        k.entries().for_each(|(i, j, v)| dense[(i, j)] += v);
        let exact = dense.lu().solve(&DVector::from_column_slice(&rhs)).expect("a regular bordered system");
        let lead = csr::columns_of(leading_block(&k, 3));
        for (kind, most) in [(Preconditioner::Ilu0, 60), (Preconditioner::Ilut { drop: 0.0, fill: 60 }, 2)] {
            let inner = BuiltPreconditioner::build(&lead, kind, None).expect("a regular leading block");
            let pc = Bordered::build(&k, 3, Box::new(inner)).expect("independent constraints");
            let out = gmres::solve_gmres(&k, &rhs, |v, z| pc.solve_into(v, z), 1e-12, 200, 30);
            assert_eq!(out.status, gmres::Status::Converged, "{kind:?}");
            assert!(out.iterations <= most, "{kind:?}: {} iterations", out.iterations);
            let worst = (0..63).map(|i| (out.x[i] - exact[i]).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-9, "{kind:?}: against the dense solution {worst:.1e}");
        }
    }

    /// Constraints that repeat one another are refused, not iterated on.
    #[test]
    fn dependent_constraints_are_singular() {
        let (a, b, mut border) = example(30);
        border.rows[2] = border.rows[1].clone();
        let (k, _) = border.bordered(a, &b);
        let inner = BuiltPreconditioner::build(&csr::columns_of(leading_block(&k, 3)), Preconditioner::Ilu0, None).unwrap();
        assert!(matches!(Bordered::build(&k, 3, Box::new(inner)), Err(SolveError::Singular { .. })));
    }
}
