//! RBF-FD weights: a radial function centred at every stencil node, augmented with
//! the monomials of total degree `<= p` (Flyer, Fornberg, Bayona and Barnett; the
//! PHS+poly recipe). For a stencil `z_1..z_n` in local coordinates `z = (x - c) / s`
//! (shifted to the centre `c`, scaled by the stencil radius `s`) the weights `w` of an
//! operator `L` at the centre solve the saddle-point system
//!
//! ```text
//! [ A   P ] [ w ]   [ L phi(|z - z_j|) at 0 ]          A_ij = phi(|z_i - z_j|)
//! [ P^T 0 ] [ l ] = [ L p_k at 0            ],         P_jk = p_k(z_j)
//! ```
//!
//! so that `L` is exact on the radial functions and on every polynomial of degree `p`;
//! physical weights are `w / s^order(L)`. The system is solved by LU with partial
//! pivoting (faer). `P` must have full column rank (checked by QR, like the least-squares
//! bases), and the solve is refused when the weights show that the system lost more
//! than [`AMPLIFICATION_LIMIT`] of the precision (flat Gaussian, MQ or IMQ kernels).
//!
//! Radial functions, `r = |z - z_j|`:
//! * polyharmonic spline `r^beta`, `beta` odd `>= 3` (no shape parameter; all its
//!   derivatives up to second order vanish at `r = 0`);
//! * Gaussian `exp(-(r/c)^2)`, multiquadric `sqrt(r^2 + c^2)`, inverse multiquadric
//!   `1/sqrt(r^2 + c^2)`, with `c` in local units (the scene gives it in units of the
//!   local spacing).

use super::basis::{Basis, LocalBasis};
use super::frame::{monomial_matrix, LocalFrame, RankDeficient};
use super::ops::Op;
use super::radial::Radial;

/// Largest `|w| |M| / |rhs|` accepted (in max norms): a lower bound of the condition
/// number of the local system that is actually reached. Above it the weights carry
/// fewer than four significant digits.
pub const AMPLIFICATION_LIMIT: f64 = 1e12;

/// RBF-FD weights of `ops` at `centre` for the stencil `points` (the centre first),
/// written to `out[k * n .. (k + 1) * n]` for the k-th operator.
pub fn shape_functions(
    radial: &Radial,
    degree: u32,
    centre: [f64; 2],
    points: &[[f64; 2]],
    ops: &[Op],
    out: &mut [f64],
) -> Result<(), RankDeficient> {
    let n = points.len();
    let LocalFrame { radius: s, nearest: h_p, z, .. } = LocalFrame::new(centre, points);
    let c = radial.shape().map_or(0.0, |shape| shape * h_p / s);
    let local = LocalBasis::new(&Basis::Monomials { degree });
    let (exps, m) = (local.exponents(), local.len());
    // The rank of the polynomial part is tested once per support, before the shapes
    // (`shapes::degenerate_supports`, which the discretisation runs on every RBF-FD
    // support): testing it here again was a tenth of a Kirsch run at degree 6 with its
    // degree-8 estimate. A singular saddle system shows as amplification below.
    if n < m {
        return Err(RankDeficient { ratio: 0.0, basis_size: m });
    }
    let p = monomial_matrix(&local, &z);
    let size = n + m;
    SCRATCH.with_borrow_mut(|scratch| {
        let Scratch { sys, rhs, perm, perm_inv, buffer } = scratch.get_or_insert_with(|| Scratch {
            sys: faer::Mat::new(),
            rhs: faer::Mat::new(),
            perm: Vec::new(),
            perm_inv: Vec::new(),
            buffer: None,
        });
        if sys.nrows() != size {
            *sys = faer::Mat::zeros(size, size);
        }
        saddle_matrix(sys, radial, &z, c, &p, m);
        if (rhs.nrows(), rhs.ncols()) != (size, ops.len()) {
            *rhs = faer::Mat::zeros(size, ops.len());
        }
        right_hand_sides(rhs, radial, ops, &z, c, exps);
        let (norm_sys, norm_rhs) = (max_abs(sys), max_abs(rhs));
        solve_in_place(sys, rhs, (perm, perm_inv), buffer);
        crate::linalg::vector_state::clear_upper_halves();
        let w = &*rhs;
        let amplification = if (0..w.ncols()).all(|j| w.col(j).iter().all(|v| v.is_finite())) {
            max_abs(w) * norm_sys / norm_rhs.max(f64::MIN_POSITIVE)
        } else {
            f64::INFINITY
        };
        if amplification > AMPLIFICATION_LIMIT {
            return Err(RankDeficient { ratio: 1.0 / amplification, basis_size: m });
        }
        for (col, &op) in ops.iter().enumerate() {
            let scale = s.powi(-op.order());
            for j in 0..n {
                out[col * n + j] = w[(j, col)] * scale;
            }
        }
        Ok(())
    })
}

/// The saddle-point matrix `[[A, P], [Pᵀ, 0]]` of the stencil in local coordinates
/// `z` (`A_ij = φ(|z_i − z_j|)` with shape `c`, `P` the `n x m` monomials `p`, stored
/// monomial by monomial) in the top-left `(n + m)`-square of `sys`.
fn saddle_matrix(sys: &mut faer::Mat<f64>, radial: &Radial, z: &[[f64; 2]], c: f64, p: &[f64], m: usize) {
    let n = z.len();
    for i in 0..n {
        // A is symmetric: evaluate each pair once. The local coordinates are within
        // the unit disc, so `sqrt` needs none of `hypot`'s guards against overflow
        // (which made it 11 % of a Kirsch run with its estimate).
        for j in 0..i {
            let (dx, dy) = (z[i][0] - z[j][0], z[i][1] - z[j][1]);
            let v = radial.profile((dx * dx + dy * dy).sqrt(), c).0;
            sys[(i, j)] = v;
            sys[(j, i)] = v;
        }
        sys[(i, i)] = radial.profile(0.0, c).0;
        for k in 0..m {
            sys[(i, n + k)] = p[k * n + i];
            sys[(n + k, i)] = p[k * n + i];
        }
    }
    // The block of the polynomial part is zero (the buffer holds the last factors).
    for j in n..n + m {
        for i in n..n + m {
            sys[(i, j)] = 0.0;
        }
    }
}

/// One right-hand side per operator `L`: `L φ(|· − z_j|)` at the centre for the
/// radial part, and `L` of each monomial `x^a y^b` at the centre (`a! b!` for the
/// operator's own multi-index, 0 for the others).
fn right_hand_sides(rhs: &mut faer::Mat<f64>, radial: &Radial, ops: &[Op], z: &[[f64; 2]], c: f64, exps: &[(u32, u32)]) {
    let n = z.len();
    let fact = |k: u32| (1..=k).product::<u32>() as f64;
    for (col, &op) in ops.iter().enumerate() {
        for j in 0..n {
            rhs[(j, col)] = radial.operator_at_centre(op, z[j], c);
        }
        let target = op.multi_index();
        for (k, &(a, b)) in exps.iter().enumerate() {
            rhs[(n + k, col)] = if (a, b) == target { fact(a) * fact(b) } else { 0.0 };
        }
    }
}

/// The buffers of one thread's stencil solves, kept from node to node: faer's
/// `partial_piv_lu` copied the saddle matrix and split its factors into two more, and
/// at degree 8 (the error estimate's reference of degree-6 runs: 135 unknowns, 146 kB
/// a matrix) each of those blocks was mapped and unmapped again at every node
/// (glibc's mmap threshold of 128 kB, set in `main`;
/// docs/notebook/2026-11-27-stencil-buffers-per-thread.md).
struct Scratch {
    sys: faer::Mat<f64>,
    rhs: faer::Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    buffer: Option<(usize, usize, faer::dyn_stack::MemBuffer)>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Option<Scratch>> = const { std::cell::RefCell::new(None) };
}

/// `rhs <- sys⁻¹ rhs` by faer's LU with partial pivoting factored in place in `sys`
/// (one thread: the nodes are the parallel loop), `buffer` its workspace for this
/// size.
fn solve_in_place(
    sys: &mut faer::Mat<f64>,
    rhs: &mut faer::Mat<f64>,
    (perm, perm_inv): (&mut Vec<usize>, &mut Vec<usize>),
    buffer: &mut Option<(usize, usize, faer::dyn_stack::MemBuffer)>,
) {
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::lu::partial_pivoting::{factor, solve};
    let (size, k, par) = (sys.nrows(), rhs.ncols(), faer::Par::Seq);
    perm.resize(size, 0);
    perm_inv.resize(size, 0);
    if !matches!(buffer, Some((s, c, _)) if (*s, *c) == (size, k)) {
        let req = StackReq::any_of(&[
            factor::lu_in_place_scratch::<usize, f64>(size, size, par, Default::default()),
            solve::solve_in_place_scratch::<usize, f64>(size, k, par),
        ]);
        *buffer = Some((size, k, MemBuffer::new(req)));
    }
    let stack = MemStack::new(&mut buffer.as_mut().expect("made above").2);
    let (_, row_perm) = factor::lu_in_place(sys.as_mut(), perm, perm_inv, par, stack, Default::default());
    // The factors are packed in `sys`: the unit lower triangle is L, the upper U.
    solve::solve_in_place(sys.as_ref(), sys.as_ref(), row_perm, rhs.as_mut(), par, stack);
}

/// Largest `|a_ij|`.
fn max_abs(a: &faer::Mat<f64>) -> f64 {
    let mut largest = 0.0f64;
    for j in 0..a.ncols() {
        for v in a.col(j).iter() {
            largest = largest.max(v.abs());
        }
    }
    largest
}
