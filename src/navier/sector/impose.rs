//! Imposing the balances on the assembled system: the multipliers eliminated on
//! three pivot rows of each injection (partial pivoting), so the system stays square
//! (module docs of [`super`]).

use super::SectorBalance;
use crate::linalg::Csr;
use nalgebra::Matrix3;
use std::collections::BTreeMap;

/// `matrix` and `rhs` with every balance imposed (module docs): the injected rows
/// combined with the pivot rows, the pivot rows replaced by the balance. A balance
/// whose injection has no three independent rows is left out.
pub fn impose(matrix: Csr, rhs: &mut [f64], balances: &[SectorBalance]) -> Csr {
    let mut replaced: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
    for b in balances {
        let Some(pivots) = pivot_rows(&b.injected) else { continue };
        let row_of = |k: usize, replaced: &BTreeMap<usize, Vec<(usize, f64)>>| -> Vec<(usize, f64)> {
            replaced.get(&k).cloned().unwrap_or_else(|| {
                let r = matrix.row(k);
                r.col_indices().iter().map(|&c| c as usize).zip(r.values().iter().copied()).collect()
            })
        };
        let gp = Matrix3::from_fn(|a, k| b.injected[pivots[a]].1[k]);
        let Some(gp_inv) = gp.try_inverse() else { continue };
        let pivot_rows: Vec<Vec<(usize, f64)>> = pivots.iter().map(|&a| row_of(b.injected[a].0, &replaced)).collect();
        let pivot_rhs: Vec<f64> = pivots.iter().map(|&a| rhs[b.injected[a].0]).collect();
        for (a, (row, g)) in b.injected.iter().enumerate() {
            if pivots.contains(&a) {
                continue;
            }
            // coef = g G_P^-1 (a row vector over the pivots).
            let coef: Vec<f64> = (0..3).map(|p| (0..3).map(|k| g[k] * gp_inv[(k, p)]).sum()).collect();
            let mut combined: BTreeMap<usize, f64> = row_of(*row, &replaced).into_iter().collect();
            for (p, pr) in pivot_rows.iter().enumerate() {
                for &(col, v) in pr {
                    *combined.entry(col).or_default() -= coef[p] * v;
                }
                rhs[*row] -= coef[p] * pivot_rhs[p];
            }
            replaced.insert(*row, combined.into_iter().collect());
        }
        for (p, &a) in pivots.iter().enumerate() {
            let row = b.injected[a].0;
            replaced.insert(row, b.rows[p].clone());
            rhs[row] = 0.0;
        }
    }
    if replaced.is_empty() {
        return matrix;
    }
    matrix.with_rows_replaced(&replaced)
}

/// Three rows of the injection `g` (one per multiplier) by Gaussian elimination with
/// partial pivoting; `None` when its rank is below three.
pub(super) fn pivot_rows(injected: &[(usize, [f64; 3])]) -> Option<[usize; 3]> {
    let mut g: Vec<[f64; 3]> = injected.iter().map(|(_, g)| *g).collect();
    let largest = g.iter().flat_map(|r| r.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let mut pivots = [usize::MAX; 3];
    for k in 0..3 {
        let (p, v) =
            (0..g.len())
                .filter(|a| !pivots.contains(a))
                .map(|a| (a, g[a][k].abs()))
                .fold((usize::MAX, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        if p == usize::MAX || v <= 1e-8 * largest {
            return None;
        }
        pivots[k] = p;
        let pivot = g[p];
        for (a, row) in g.iter_mut().enumerate() {
            if !pivots.contains(&a) {
                let f = row[k] / pivot[k];
                for j in k..3 {
                    row[j] -= f * pivot[j];
                }
            }
        }
    }
    Some(pivots)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::navier::sector::Around;
    use nalgebra::{DMatrix, DVector};

    /// A deterministic pseudo-random number in [-1, 1).
    fn noise(k: usize) -> f64 {
        let x = ((k as f64 + 1.0) * 12.9898).sin() * 43758.5453;
        2.0 * (x - x.floor()) - 1.0
    }

    /// The eliminated square system has the solution of the bordered one,
    /// `[A G; C 0] [x; lambda] = [b; 0]`, to round-off: the algebra of [`impose`].
    #[test]
    fn imposing_equals_the_bordered_system() {
        let n = 9;
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i, 4.0 + noise(i)));
            for j in [(i + 1) % n, (i + 3) % n] {
                entries.push((i, j, noise(10 * i + j)));
            }
        }
        let a = Csr::from_triplets(n, n, &entries);
        let b: Vec<f64> = (0..n).map(|i| noise(100 + i)).collect();
        let rows: [Vec<(usize, f64)>; 3] =
            std::array::from_fn(|k| (0..n).filter(|j| (j + k) % 2 == 0).map(|j| (j, noise(200 + 10 * k + j))).collect());
        let injected: Vec<(usize, [f64; 3])> =
            [1, 2, 4, 5, 7].iter().map(|&r| (r, [noise(300 + r), noise(310 + r), noise(320 + r)])).collect();
        let balance =
            SectorBalance { around: Around::Corner, centre: [0.0, 0.0], radius: 1.0, rows: rows.clone(), injected: injected.clone() };
        // Bordered system, dense.
        let mut k = DMatrix::zeros(n + 3, n + 3);
        for (i, j, v) in a.entries() {
            k[(i, j)] += v;
        }
        for (r, g) in &injected {
            for m in 0..3 {
                k[(*r, n + m)] = g[m];
            }
        }
        for (m, row) in rows.iter().enumerate() {
            for &(j, v) in row {
                k[(n + m, j)] = v;
            }
        }
        let mut rhs = DVector::zeros(n + 3);
        rhs.rows_mut(0, n).copy_from_slice(&b);
        let bordered = k.lu().solve(&rhs).expect("a regular bordered system");
        // Eliminated.
        let mut b2 = b.clone();
        let imposed = impose(a, &mut b2, &[balance]);
        let mut d = DMatrix::zeros(n, n);
        for (i, j, v) in imposed.entries() {
            d[(i, j)] += v;
        }
        let x = d.lu().solve(&DVector::from_vec(b2)).expect("a regular eliminated system");
        let worst = (0..n).map(|i| (x[i] - bordered[i]).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-12, "eliminated against bordered: {worst:.1e}");
        for (m, row) in rows.iter().enumerate() {
            let c: f64 = row.iter().map(|&(j, v)| v * x[j]).sum();
            assert!(c.abs() < 1e-12, "balance {m} not met: {c:.1e}");
        }
    }

    /// Injections that cannot carry three independent multipliers are refused.
    #[test]
    fn a_rank_deficient_injection_has_no_pivots() {
        assert!(pivot_rows(&[(0, [1.0, 0.0, 0.0]), (1, [2.0, 0.0, 0.0]), (2, [0.0, 1.0, 0.0])]).is_none());
        assert!(pivot_rows(&[(0, [1.0, 0.0, 0.5]), (1, [0.0, 1.0, 0.0]), (2, [0.0, 1.0, 1.0])]).is_some());
    }
}
