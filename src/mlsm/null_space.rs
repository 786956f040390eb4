//! The RBF-FD stencil system solved on the null space of its polynomial constraints.
//!
//! The weights `w` of an operator solve `[A P; Pᵀ 0] [w; l] = [b_a; b_p]` (`n` stencil
//! nodes, `m` monomials). Instead of an LU of the whole `(n + m)`-square system, the
//! constraints `Pᵀ w = b_p` are solved for `m` of the weights: with the rows (nodes)
//! and columns (monomials, `b_p` alike) of `P` ordered by an LU with full pivoting,
//! `P = [P1; P2] = [L1; L2] U`,
//!
//! ```text
//! w = [w1; w2],  w1 = P1^-T b_p + Z1 w2,  Z1 = -P1^-T P2^T = -L1^-T L2^T,
//! Z = [Z1; I]  (n x (n - m), a basis of the null space of Pᵀ),
//! (Zᵀ A Z) w2 = Zᵀ (b_a - A [P1^-T b_p; 0])
//! ```
//!
//! (the null-space method for saddle-point systems; Benzi, Golub and Liesen 2005,
//! section 6, with the "fundamental basis" from the pivoted LU of `P`; full pivoting
//! because partial pivoting picked ill-conditioned `P1` on grids: the Lame ring's
//! errors then moved by 1.9e-7 of themselves under a change of the unit of length,
//! 5.4e-8 with the whole system's LU; tests/scale.rs). The Lagrange
//! multipliers are never formed. Flops: `A Z` and `Zᵀ (A Z)` are two matrix products
//! (`2 n m (n - m)` and `2 m (n - m)^2`), the reduced system is `(n - m)`-square, so at
//! `n = 2m` about half of the full LU's `(2/3)(n + m)^3`, and most of it in matrix
//! products, which run near the core's peak where the LU of a small matrix does not.
//! The weights are those of the full system up to round-off.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::full_pivoting::factor as full;
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_unit_upper_triangular_in_place};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, Par};

use super::radial::Radial;

/// The buffers of one thread's null-space solves, kept from stencil to stencil.
#[derive(Default)]
pub struct NullSpaceScratch {
    /// The LU factors of `P` (`n x m`) in pivot order.
    factors: Option<Mat<f64>>,
    /// `b_a - A_1 v1` in pivot order, then the weights in pivot order (`n x k`).
    g: Option<Mat<f64>>,
    /// The stencil's points in pivot order.
    zq: Vec<[f64; 2]>,
    a: Option<Mat<f64>>,
    z1: Option<Mat<f64>>,
    az: Option<Mat<f64>>,
    reduced: Option<Mat<f64>>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    monomial_perm: Vec<usize>,
    monomial_perm_inv: Vec<usize>,
    reduced_perm: Vec<usize>,
    reduced_perm_inv: Vec<usize>,
    buffer: Option<((usize, usize, usize), MemBuffer)>,
}

/// A matrix of `rows x cols` in `slot`, reallocated only when its shape changes.
fn shaped(slot: &mut Option<Mat<f64>>, rows: usize, cols: usize) -> &mut Mat<f64> {
    if slot.as_ref().is_none_or(|a| (a.nrows(), a.ncols()) != (rows, cols)) {
        *slot = Some(Mat::zeros(rows, cols));
    }
    slot.as_mut().expect("set above")
}

/// What [`weights`] returns besides the weights: the largest entries of the full
/// system's matrix and right-hand sides, for the amplification test.
pub struct Norms {
    /// `max |[A P; Pᵀ 0]_ij|`.
    pub system: f64,
    /// `max |[b_a; b_p]_ij|`.
    pub rhs: f64,
}

/// The weights of the stencil `z` (local coordinates; `p` its `n x m` monomials,
/// column-major) for the right-hand sides `rhs = [b_a; b_p]` (`(n + m) x k`: `b_a` is
/// `L phi(|. - z_j|)` at the centre in stencil order, `b_p` `L` of the monomials),
/// written to `w` (`n x k`, stencil order).
pub fn weights(radial: &Radial, c: f64, (z, p): (&[[f64; 2]], &[f64]), rhs: faer::MatRef<'_, f64>, w: &mut Mat<f64>, s: &mut NullSpaceScratch) -> Norms {
    let (n, k) = (z.len(), rhs.ncols());
    let (b_a, b_p) = rhs.split_at_row(n);
    if (w.nrows(), w.ncols()) != (n, k) {
        *w = Mat::zeros(n, k);
    }
    let m = p.len() / n;
    let r = n - m;
    let par = Par::Seq;
    let p_largest = p.iter().fold(0.0f64, |l, v| l.max(v.abs()));
    // The LU of P (n x m) with full pivoting: its first m rows in pivot order make P1,
    // its columns are the monomials in pivot order.
    let f = shaped(&mut s.factors, n, m);
    for j in 0..m {
        f.col_mut(j).try_as_col_major_mut().expect("contiguous").as_slice_mut().copy_from_slice(&p[j * n..(j + 1) * n]);
    }
    s.perm.resize(n, 0);
    s.perm_inv.resize(n, 0);
    s.monomial_perm.resize(m, 0);
    s.monomial_perm_inv.resize(m, 0);
    s.reduced_perm.resize(r, 0);
    s.reduced_perm_inv.resize(r, 0);
    if !matches!(&s.buffer, Some((shape, _)) if *shape == (n, m, k)) {
        let req = StackReq::any_of(&[
            full::lu_in_place_scratch::<usize, f64>(n, m, par, Default::default()),
            factor::lu_in_place_scratch::<usize, f64>(r, r, par, Default::default()),
            solve::solve_in_place_scratch::<usize, f64>(r, k, par),
        ]);
        s.buffer = Some(((n, m, k), MemBuffer::new(req)));
    }
    let stack = MemStack::new(&mut s.buffer.as_mut().expect("made above").1);
    full::lu_in_place(f.as_mut(), &mut s.perm, &mut s.perm_inv, &mut s.monomial_perm, &mut s.monomial_perm_inv, par, stack, Default::default());
    let (l1u, l2) = f.as_ref().split_at_row(m);
    // Z1 = -L1^-T L2^T (m x r).
    let z1 = shaped(&mut s.z1, m, r);
    for i in 0..m {
        for j in 0..r {
            z1[(i, j)] = -l2[(j, i)];
        }
    }
    solve_unit_upper_triangular_in_place(l1u.transpose(), z1.as_mut(), par);
    // A in pivot order.
    s.zq.clear();
    s.zq.extend(s.perm.iter().map(|&i| z[i]));
    let a = shaped(&mut s.a, n, n);
    let mut a_largest = 0.0f64;
    for j in 0..n {
        let col = a.col_mut(j).try_as_col_major_mut().expect("contiguous").as_slice_mut();
        radial.column(&s.zq, s.zq[j], c, col);
        a_largest = col.iter().fold(a_largest, |l, v| l.max(v.abs()));
    }
    let (a_1, a_2) = a.as_ref().split_at_col(m);
    // A Z = A_2 + A_1 Z1 (n x r); the reduced matrix Zᵀ A Z = (A Z)_2 + Z1ᵀ (A Z)_1.
    let az = shaped(&mut s.az, n, r);
    az.copy_from(a_2);
    matmul(az.as_mut(), Accum::Add, a_1, z1.as_ref(), 1.0, par);
    let (az_1, az_2) = az.as_ref().split_at_row(m);
    let reduced = shaped(&mut s.reduced, r, r);
    reduced.copy_from(az_2);
    matmul(reduced.as_mut(), Accum::Add, z1.as_ref().transpose(), az_1, 1.0, par);
    // v1 = P1^-T b_p = L1^-T U^-T b_p (b_p in the monomials' pivot order): the
    // particular solution's first block.
    let (mut w_1, mut w_2) = w.as_mut().split_at_row_mut(m);
    for (q, &i) in s.monomial_perm.iter().enumerate() {
        for col in 0..k {
            w_1[(q, col)] = b_p[(i, col)];
        }
    }
    solve_lower_triangular_in_place(l1u.transpose(), w_1.rb_mut(), par);
    solve_unit_upper_triangular_in_place(l1u.transpose(), w_1.rb_mut(), par);
    // g = b_a - A_1 v1 in pivot order; the reduced right-hand side g_2 + Z1ᵀ g_1 into w_2.
    let g = shaped(&mut s.g, n, k);
    for (row, &i) in s.perm.iter().enumerate() {
        for col in 0..k {
            g[(row, col)] = b_a[(i, col)];
        }
    }
    matmul(g.as_mut(), Accum::Add, a_1, w_1.rb(), -1.0, par);
    let (g_1, g_2) = g.as_ref().split_at_row(m);
    w_2.copy_from(g_2);
    matmul(w_2.rb_mut(), Accum::Add, z1.as_ref().transpose(), g_1, 1.0, par);
    let (_, reduced_perm) = factor::lu_in_place(reduced.as_mut(), &mut s.reduced_perm, &mut s.reduced_perm_inv, par, stack, Default::default());
    solve::solve_in_place(reduced.as_ref(), reduced.as_ref(), reduced_perm, w_2.rb_mut(), par, stack);
    // w1 = v1 + Z1 w2.
    matmul(w_1.rb_mut(), Accum::Add, z1.as_ref(), w_2.rb(), 1.0, par);
    // Back to stencil order.
    g.copy_from(w.as_ref());
    for (row, &i) in s.perm.iter().enumerate() {
        for col in 0..k {
            w[(i, col)] = g[(row, col)];
        }
    }
    let rhs_largest = (0..k).flat_map(|j| rhs.col(j).iter().copied()).fold(0.0f64, |l, v| l.max(v.abs()));
    Norms { system: a_largest.max(p_largest), rhs: rhs_largest }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mlsm::basis::{Basis, LocalBasis};
    use crate::mlsm::frame::monomial_matrix;

    /// `n` points of a unit lattice jittered by up to 0.3, the nearest to the origin
    /// (centre first), scaled into the unit disc.
    fn stencil(n: usize, seed: u64) -> Vec<[f64; 2]> {
        let mut z = crate::mlsm::stencil::jittered_lattice(n, 0.6, seed);
        let radius = z.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        z.iter_mut().for_each(|p| *p = [p[0] / radius, p[1] / radius]);
        z
    }

    /// The whole saddle system `[A P; Pᵀ 0]` and right-hand sides of `Dx` and `Dyy`,
    /// solved by nalgebra's LU (an implementation of its own): the right-hand sides,
    /// the weights (`n x 2`) and the system's 2-norm condition number.
    fn whole_system(radial: &Radial, c: f64, z: &[[f64; 2]], local: &LocalBasis) -> (Mat<f64>, nalgebra::DMatrix<f64>, f64) {
        let (n, m) = (z.len(), local.len());
        let p = monomial_matrix(local, z);
        let ops = [crate::mlsm::ops::Op::Dx, crate::mlsm::ops::Op::Dyy];
        let mut k = nalgebra::DMatrix::<f64>::zeros(n + m, n + m);
        let mut rhs = Mat::<f64>::zeros(n + m, ops.len());
        let mut column = vec![0.0; n];
        for j in 0..n {
            radial.column(z, z[j], c, &mut column);
            for i in 0..n {
                k[(i, j)] = column[i];
            }
            for q in 0..m {
                k[(j, n + q)] = p[q * n + j];
                k[(n + q, j)] = p[q * n + j];
            }
            let at = radial.at_centre(z[j], c);
            for (col, &op) in ops.iter().enumerate() {
                rhs[(j, col)] = at.apply(op);
            }
        }
        for (q, &(a, b)) in local.exponents().iter().enumerate() {
            rhs[(n + q, 0)] = if (a, b) == (1, 0) { 1.0 } else { 0.0 };
            rhs[(n + q, 1)] = if (a, b) == (0, 2) { 2.0 } else { 0.0 };
        }
        let b = nalgebra::DMatrix::from_fn(n + m, ops.len(), |i, j| rhs[(i, j)]);
        let singular = k.clone().singular_values();
        let condition = singular.max() / singular.min();
        let w = k.lu().solve(&b).expect("the whole system is regular").rows(0, n).into_owned();
        (rhs, w, condition)
    }

    /// The null-space weights are the whole system's up to round-off: on jittered
    /// stencils of the default size `2 m` (and the smallest, `n = m + 1`) for PHS of
    /// degrees 2-8 and the shape-parameter kernels, the largest difference is below
    /// `10 kappa eps` of the largest weight, `kappa` the whole system's condition
    /// number. Two backward-stable solves of one system differ by about `kappa eps`;
    /// the null-space basis would add the condition of `P1`, which full pivoting keeps
    /// small (measured: at most 8e-3 of the bound, over 60 stencils).
    #[test]
    fn weights_are_the_whole_systems_up_to_round_off() {
        let kernels = [
            (Radial::Phs { order: 3 }, 0.0),
            (Radial::Phs { order: 5 }, 0.0),
            (Radial::Gaussian { shape: 1.0 }, 0.6),
            (Radial::Mq { shape: 1.0 }, 0.3),
            (Radial::Imq { shape: 1.0 }, 0.3),
        ];
        for (radial, c) in kernels {
            for degree in [2u32, 4, 6, 8] {
                let local = LocalBasis::new(&Basis::Monomials { degree });
                let m = local.len();
                for (n, seed) in [(2 * m, 1u64), (2 * m, 2), (m + 1, 3)] {
                    let z = stencil(n, seed);
                    let (rhs, expected, condition) = whole_system(&radial, c, &z, &local);
                    let p = monomial_matrix(&local, &z);
                    let mut w = Mat::zeros(0, 0);
                    weights(&radial, c, (&z, &p), rhs.as_ref(), &mut w, &mut NullSpaceScratch::default());
                    let largest = expected.iter().fold(0.0f64, |l, v| l.max(v.abs()));
                    let difference = (0..n).flat_map(|i| (0..2).map(move |j| (i, j))).map(|(i, j)| (w[(i, j)] - expected[(i, j)]).abs()).fold(0.0, f64::max);
                    let bound = 10.0 * condition * f64::EPSILON;
                    eprintln!("{radial:?} degree {degree} n {n}: difference {:.1e} of the largest weight, condition {condition:.1e}, bound {bound:.1e}", difference / largest);
                    assert!(difference <= bound * largest, "{radial:?} degree {degree} n {n}: difference {difference:e} of {largest:e}, condition {condition:e}");
                }
            }
        }
    }
}
