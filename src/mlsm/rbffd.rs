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
//! physical weights are `w / s^order(L)`. The system is solved on the null space of
//! `Pᵀ` ([`super::null_space`]: two matrix products and an LU of `n - m` unknowns, 0.6-0.7x
//! the time of the LU of all `n + m` at degrees 4-8; BENCHMARKS.md "Shape functions per
//! node"), and by the LU of the whole system with partial pivoting (faer) where that
//! loses precision. `P` must have full column rank (checked by QR once per support,
//! like the least-squares bases), and the solve is refused when the weights show that
//! the system lost more than [`AMPLIFICATION_LIMIT`] of the precision (flat Gaussian,
//! MQ or IMQ kernels).
//!
//! Radial functions, `r = |z - z_j|`:
//! * polyharmonic spline `r^beta`, `beta` odd `>= 3` (no shape parameter; all its
//!   derivatives up to second order vanish at `r = 0`);
//! * Gaussian `exp(-(r/c)^2)`, multiquadric `sqrt(r^2 + c^2)`, inverse multiquadric
//!   `1/sqrt(r^2 + c^2)`, with `c` in local units (the scene gives it in units of the
//!   local spacing).

use super::basis::{Basis, LocalBasis};
use super::frame::{monomial_matrix_into, LocalFrame, RankDeficient};
use super::null_space::Norms;
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
    SCRATCH.with_borrow_mut(|scratch| {
        let Scratch { sys, rhs, perm, perm_inv, buffer, z, p, basis, w, null_space } = scratch.get_or_insert_with(|| Scratch {
            sys: faer::Mat::new(),
            rhs: faer::Mat::new(),
            perm: Vec::new(),
            perm_inv: Vec::new(),
            buffer: None,
            z: Vec::new(),
            p: Vec::new(),
            basis: None,
            w: faer::Mat::new(),
            null_space: Default::default(),
        });
        let (s, h_p) = local_coordinates(centre, points, z);
        let c = radial.shape().map_or(0.0, |shape| shape * h_p / s);
        if basis.as_ref().is_none_or(|(d, _)| *d != degree) {
            *basis = Some((degree, LocalBasis::new(&Basis::Monomials { degree })));
        }
        let local = &basis.as_ref().expect("set above").1;
        let m = local.len();
        // The rank of the polynomial part is tested once per support, before the shapes
        // (`shapes::degenerate_supports`, which the discretisation runs on every RBF-FD
        // support): testing it here again was a tenth of a Kirsch run at degree 6 with its
        // degree-8 estimate. A singular saddle system shows as amplification below.
        if n < m {
            return Err(RankDeficient { ratio: 0.0, basis_size: m });
        }
        monomial_matrix_into(local, z, p);
        let size = n + m;
        if (rhs.nrows(), rhs.ncols()) != (size, ops.len()) {
            *rhs = faer::Mat::zeros(size, ops.len());
        }
        right_hand_sides(rhs, radial, ops, z, c, local.exponents());
        let norms = super::null_space::weights(radial, c, (z, p), rhs.as_ref(), w, null_space);
        let mut amplification = amplification_of(w, &norms);
        if !(amplification <= AMPLIFICATION_LIMIT) {
            // The null-space basis from the pivoted LU of `P` can lose digits that the
            // LU of the whole system keeps (an ill-conditioned `P1`): before refusing
            // the stencil, its weights are taken from the whole system.
            if sys.nrows() != size {
                *sys = faer::Mat::zeros(size, size);
            }
            let norms = Norms { system: saddle_matrix(sys, radial, z, c, p, m), rhs: max_abs(rhs) };
            solve_in_place(sys, rhs, (perm, perm_inv), buffer);
            w.copy_from(rhs.as_ref().split_at_row(n).0);
            amplification = amplification_of(w, &norms);
        }
        crate::linalg::vector_state::clear_upper_halves();
        if !(amplification <= AMPLIFICATION_LIMIT) {
            return Err(RankDeficient { ratio: 1.0 / amplification, basis_size: m });
        }
        for (col, &op) in ops.iter().enumerate() {
            let scale = s.powi(-op.order());
            for (o, &v) in out[col * n..(col + 1) * n].iter_mut().zip(column(w, col)) {
                *o = v * scale;
            }
        }
        Ok(())
    })
}

/// The stencil in local coordinates, written to `z`: `z_j = (x_j - centre) / s`, `s`
/// the largest distance from the centre; returns `(s, h_p)`, `h_p` the smallest
/// non-zero distance (the local spacing that scales shape parameters). The same frame
/// as [`super::frame::LocalFrame`], without its per-point distances: the squared
/// distances are taken after dividing by the largest coordinate difference, so that
/// no square overflows whatever the unit of length, and two square roots remain.
fn local_coordinates(centre: [f64; 2], points: &[[f64; 2]], z: &mut Vec<[f64; 2]>) -> (f64, f64) {
    z.clear();
    z.extend(points.iter().map(|x| [x[0] - centre[0], x[1] - centre[1]]));
    let box_size = z.iter().fold(0.0f64, |a, d| a.max(d[0].abs()).max(d[1].abs()));
    if box_size == 0.0 || !box_size.is_finite() {
        // A degenerate stencil: the frame's own treatment (the solve then fails on
        // amplification, as before).
        let frame = LocalFrame::new(centre, points);
        z.clear();
        z.extend_from_slice(&frame.z);
        return (frame.radius, frame.nearest);
    }
    let (mut far, mut near) = (0.0f64, f64::INFINITY);
    for d in z.iter() {
        let (a, b) = (d[0] / box_size, d[1] / box_size);
        let r2 = a * a + b * b;
        far = far.max(r2);
        if r2 > 0.0 {
            near = near.min(r2);
        }
    }
    let radius = box_size * far.sqrt();
    z.iter_mut().for_each(|d| *d = [d[0] / radius, d[1] / radius]);
    (radius, box_size * near.sqrt())
}

/// Column `j` of a faer matrix as a slice (faer's owned matrices store columns
/// contiguously).
fn column(a: &faer::Mat<f64>, j: usize) -> &[f64] {
    a.col(j).try_as_col_major().expect("faer::Mat columns are contiguous").as_slice()
}

/// The saddle-point matrix `[[A, P], [Pᵀ, 0]]` of the stencil in local coordinates
/// `z` (`A_ij = φ(|z_i − z_j|)` with shape `c`, `P` the `n x m` monomials `p`, stored
/// monomial by monomial) in the top-left `(n + m)`-square of `sys`, column by column
/// (contiguous in faer's column-major storage: `A`'s columns are evaluated whole,
/// straight-line code that vectorises, rather than each symmetric pair once through
/// strided writes). Returns `max |sys_ij|`.
fn saddle_matrix(sys: &mut faer::Mat<f64>, radial: &Radial, z: &[[f64; 2]], c: f64, p: &[f64], m: usize) -> f64 {
    let n = z.len();
    let size = n + m;
    let mut largest = 0.0f64;
    for j in 0..size {
        let col = sys.col_mut(j).try_as_col_major_mut().expect("faer::Mat columns are contiguous").as_slice_mut();
        let (a, poly) = col[..size].split_at_mut(n);
        if j < n {
            radial.column(z, z[j], c, a);
            for (k, v) in poly.iter_mut().enumerate() {
                *v = p[k * n + j];
            }
        } else {
            a.copy_from_slice(&p[(j - n) * n..(j - n + 1) * n]);
            poly.fill(0.0);
        }
        largest = a.iter().fold(largest, |l, v| l.max(v.abs()));
    }
    largest
}

/// One right-hand side per operator `L`: `L φ(|· − z_j|)` at the centre for the
/// radial part (the radial profile evaluated once per point for all operators), and
/// `L` of each monomial `x^a y^b` at the centre (`a! b!` for the operator's own
/// multi-index, 0 for the others).
fn right_hand_sides(rhs: &mut faer::Mat<f64>, radial: &Radial, ops: &[Op], z: &[[f64; 2]], c: f64, exps: &[(u32, u32)]) {
    let n = z.len();
    let fact = |k: u32| (1..=k).product::<u32>() as f64;
    for (j, &zj) in z.iter().enumerate() {
        let at = radial.at_centre(zj, c);
        for (col, &op) in ops.iter().enumerate() {
            rhs[(j, col)] = at.apply(op);
        }
    }
    for (col, &op) in ops.iter().enumerate() {
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
    /// The stencil in local coordinates.
    z: Vec<[f64; 2]>,
    /// Its monomials, column-major `n x m`.
    p: Vec<f64>,
    /// The monomials of the last degree asked for.
    basis: Option<(u32, LocalBasis)>,
    w: faer::Mat<f64>,
    null_space: super::null_space::NullSpaceScratch,
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

/// `max |w_ij| max |K_ij| / max |rhs_ij|` for the weights `w` of the system `K`: a
/// lower bound of the condition number actually reached (NaN if a weight is not
/// finite, which fails every comparison).
fn amplification_of(w: &faer::Mat<f64>, norms: &Norms) -> f64 {
    max_abs(w) * norms.system / norms.rhs.max(f64::MIN_POSITIVE)
}

/// Largest `|a_ij|` (NaN if any entry is NaN, so that the amplification test fails).
fn max_abs(a: &faer::Mat<f64>) -> f64 {
    let mut largest = 0.0f64;
    for j in 0..a.ncols() {
        for &v in column(a, j) {
            if !(v.abs() <= largest) {
                largest = if v.is_nan() { return f64::NAN } else { v.abs() };
            }
        }
    }
    largest
}
