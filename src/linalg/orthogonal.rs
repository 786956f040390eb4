//! The vector kernels of Arnoldi processes (GMRES's basis, the multigrid's growth
//! estimate): parallel dot products and classical Gram-Schmidt done twice.

use rayon::prelude::*;

/// `a · b`, in parallel (GMRES's and the multigrid's Arnoldi processes).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_iter().zip(b).with_min_len(4096).map(|(x, y)| x * y).sum()
}

/// `‖a‖₂`, in parallel.
pub fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Rows per task of [`orthogonalise`]: a piece of `w` stays in cache while every basis
/// vector is read against it.
const ORTHOGONALISE_ROWS: usize = 4096;

/// `h = Vᵀ w`, `w ← w − V h` in one pass for the dot products and one for the update
/// (classical Gram–Schmidt), repeated once when `w` lost more than `1 − 1/√2` of its
/// norm (Daniel, Gragg, Kaufman & Stewart, *Math. Comp.* 30 (1976) 772–795: "twice is
/// enough"). Returns `h` and `‖w‖` after. Modified Gram–Schmidt reads every basis
/// vector twice and `w` three times per vector; here each pass reads every basis
/// vector once against a piece of `w` held in cache. The partial sums are added in a
/// fixed order: the same `h` on every run.
pub fn orthogonalise(basis: &[Vec<f64>], w: &mut [f64]) -> (Vec<f64>, f64) {
    let project = |w: &mut [f64]| -> Vec<f64> {
        let k = basis.len();
        let parts: Vec<Vec<f64>> = w
            .par_chunks(ORTHOGONALISE_ROWS)
            .enumerate()
            .map(|(c, w)| {
                let first = c * ORTHOGONALISE_ROWS;
                basis.iter().map(|v| v[first..first + w.len()].iter().zip(w).map(|(v, w)| v * w).sum()).collect()
            })
            .collect();
        let mut h = vec![0.0; k];
        for part in &parts {
            h.iter_mut().zip(part).for_each(|(h, p)| *h += p);
        }
        w.par_chunks_mut(ORTHOGONALISE_ROWS).enumerate().for_each(|(c, w)| {
            let rows = c * ORTHOGONALISE_ROWS..c * ORTHOGONALISE_ROWS + w.len();
            for (v, &h) in basis.iter().zip(&h) {
                w.iter_mut().zip(&v[rows.clone()]).for_each(|(w, v)| *w -= h * v);
            }
        });
        h
    };
    let before = norm(w);
    let mut h = project(w);
    let mut after = norm(w);
    if after < before * std::f64::consts::FRAC_1_SQRT_2 {
        project(w).iter().zip(h.iter_mut()).for_each(|(again, h)| *h += again);
        after = norm(w);
    }
    (h, after)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Classical Gram–Schmidt with one reorthogonalisation: `w` ends orthogonal to the
    /// basis to round-off, `h` holds its projections, and `‖w‖` is returned, also when
    /// `w` lies almost in the basis' span (the case that needs the second pass).
    #[test]
    fn orthogonalise_projects_out_the_basis_to_round_off() {
        let n = 10_000;
        let mut basis: Vec<Vec<f64>> = Vec::new();
        for k in 0..6 {
            let mut v: Vec<f64> = (0..n).map(|i| ((i * (k + 3) * 7919) % 1009) as f64 / 1009.0 - 0.5).collect();
            let (_, norm) = orthogonalise(&basis, &mut v);
            v.iter_mut().for_each(|x| *x /= norm);
            basis.push(v);
        }
        for tilt in [1.0, 1e-8] {
            // w = V c + tilt * e, e a vector outside the span.
            let c = [0.3, -1.2, 0.7, 2.0, -0.4, 0.9];
            let mut e: Vec<f64> = (0..n).map(|i| ((i * 104729) % 997) as f64 / 997.0 - 0.5).collect();
            let (_, en) = orthogonalise(&basis, &mut e);
            let mut w: Vec<f64> = (0..n).map(|i| tilt * e[i] / en + basis.iter().zip(c).map(|(v, c)| c * v[i]).sum::<f64>()).collect();
            let (h, wn) = orthogonalise(&basis, &mut w);
            for (hk, ck) in h.iter().zip(c) {
                assert!((hk - ck).abs() < 1e-13, "tilt {tilt}: {hk} against {ck}");
            }
            assert!((wn - tilt).abs() < 1e-6 * tilt, "tilt {tilt}: norm {wn}");
            assert!((wn - norm(&w)).abs() <= 1e-15 * wn.max(1e-300) + 1e-300);
            // Orthogonal relative to what is left of `w`: one pass leaves about
            // `eps ‖w₀‖ / ‖w‖` = 1e-8 at tilt 1e-8, the second pass round-off.
            for v in &basis {
                assert!(dot(v, &w).abs() < 1e-13 * wn, "tilt {tilt}: left {:.1e} of {wn:.1e}", dot(v, &w));
            }
        }
    }
}
