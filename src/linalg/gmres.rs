//! Restarted, right-preconditioned GMRES(m) with true-residual verification.
//!
//! Saad & Schultz, "GMRES: a generalized minimal residual algorithm for solving
//! nonsymmetric linear systems", *SIAM J. Sci. Stat. Comput.* 7 (1986) 856–869; right
//! preconditioning as in Saad, *Iterative Methods for Sparse Linear Systems*, 2nd ed.,
//! Alg. 9.5: the Krylov space of `A M⁻¹` is built by modified Gram–Schmidt, the
//! least-squares problem is kept triangular by Givens rotations, whose last entry is
//! the residual norm of the unpreconditioned system, and `x = x₀ + M⁻¹ V y` at each
//! restart. GMRES minimises that residual over the space, so unlike BiCGSTAB it never
//! breaks down on a nonsingular system and its residual never grows; a cycle that
//! leaves more than `stall` of the residual (by default [`STAGNATION`]) is reported as
//! a stall rather than run to the iteration limit.
//!
//! faer 0.24 has no GMRES; the method is short enough to keep here with its checks.

use super::csr::{product, Csr};
use super::orthogonal::{norm, orthogonalise};
use super::watch::Watch;
use super::Preconditioner;
use rayon::prelude::*;

/// How a GMRES run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// True relative residual `≤ tolerance`.
    Converged,
    /// The iteration budget was spent above the tolerance.
    IterationLimit,
    /// A whole restart cycle left more than `stall` of the true residual.
    Stalled,
    /// The iterate became NaN or infinite.
    Breakdown,
}

/// A restart cycle must shrink the true residual at least by this factor, else the
/// run stops as [`Status::Stalled`] (a cycle of GMRES(30) that does not gain 1 % will
/// not reach the tolerance within any sensible budget).
pub const STAGNATION: f64 = 0.99;

/// Result of [`solve_gmres`]: the last iterate and its true residual, whatever the status.
#[derive(Clone, Debug)]
pub struct GmresOutcome {
    /// Last iterate.
    pub x: Vec<f64>,
    /// How the run ended.
    pub status: Status,
    /// Inner iterations (products with `A`), over all restarts.
    pub iterations: usize,
    /// Restart cycles run.
    pub restarts: usize,
    /// True `‖b − A x‖₂ / ‖b‖₂`.
    pub relative_residual: f64,
    /// True relative residual after each restart cycle (the first entry is 1).
    pub history: Vec<f64>,
}

fn true_residual(apply: &impl Fn(&[f64], &mut [f64]), x: &[f64], b: &[f64], r: &mut [f64]) -> f64 {
    apply(x, r);
    r.par_iter_mut().zip(b).with_min_len(4096).for_each(|(r, b)| *r = b - *r);
    norm(r)
}

/// Solve `a x = b` from `x₀ = 0` by GMRES(`restart`) preconditioned on the right by
/// `precondition` (`v ← M⁻¹ v`), until the true relative residual is `≤ tolerance`,
/// `max_iterations` inner steps are spent, or a cycle stalls ([`STAGNATION`]).
pub fn solve_gmres(
    a: &Csr,
    b: &[f64],
    precondition: impl Fn(&[f64], &mut [f64]),
    tolerance: f64,
    max_iterations: usize,
    restart: usize,
) -> GmresOutcome {
    solve_gmres_with(|x, y| product(a, x, y), b, precondition, (tolerance, max_iterations, restart, STAGNATION), &())
}

/// [`solve_gmres`] with the matrix given by its product `apply(x, y)`: `y ← A x`, and
/// a stall declared when a whole restart cycle leaves more than `stall` (in `(0, 1]`)
/// of the true residual it started from (a cycle cut short by convergence, more than
/// [`STAGNATION`]); `watch` is told the residual estimate after every iteration.
pub fn solve_gmres_with(
    apply: impl Fn(&[f64], &mut [f64]),
    b: &[f64],
    precondition: impl Fn(&[f64], &mut [f64]),
    (tolerance, max_iterations, restart, stall): (f64, usize, usize, f64),
    watch: &dyn Watch,
) -> GmresOutcome {
    let n = b.len();
    // More Krylov vectors than iterations or unknowns would only allocate.
    let m = restart.min(max_iterations).min(n).max(1);
    let mut x = vec![0.0; n];
    let b_norm = norm(b);
    let mut out =
        GmresOutcome { x: Vec::new(), status: Status::Converged, iterations: 0, restarts: 0, relative_residual: 1.0, history: vec![1.0] };
    if b_norm == 0.0 {
        return GmresOutcome { x, relative_residual: 0.0, ..out };
    }
    // `w` holds the residual between cycles (from x₀ = 0 it is b itself: no product
    // needed) and `A M⁻¹ v` within one.
    let (mut w, mut z) = (b.to_vec(), vec![0.0; n]);
    let mut beta = b_norm;
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(m + 1);
    loop {
        let relative = beta / b_norm;
        out.relative_residual = relative;
        if relative <= tolerance {
            out.status = Status::Converged;
            break;
        }
        if out.iterations >= max_iterations {
            out.status = Status::IterationLimit;
            break;
        }
        // One cycle: Arnoldi on A M⁻¹ from r / β.
        basis.clear();
        basis.push(w.iter().map(|v| v / beta).collect());
        let mut hessenberg = Hessenberg::new(m, beta);
        let mut steps = 0;
        for j in 0..m {
            if out.iterations >= max_iterations {
                break;
            }
            precondition(&basis[j], &mut z);
            apply(&z, &mut w);
            let (projections, wn) = orthogonalise(&basis, &mut w);
            let residual = hessenberg.add_column(j, projections, wn);
            out.iterations += 1;
            steps = j + 1;
            let estimate = residual / b_norm;
            watch.residual(estimate, tolerance);
            if wn == 0.0 || estimate <= 0.5 * tolerance {
                break;
            }
            basis.push(w.iter().map(|v| v / wn).collect());
        }
        add_correction(&mut x, &basis, &hessenberg.solve(steps), &precondition, (&mut w, &mut z));
        out.restarts += 1;
        if x.iter().any(|v| !v.is_finite()) {
            out.status = Status::Breakdown;
            out.relative_residual = f64::NAN;
            break;
        }
        let previous = beta;
        beta = true_residual(&apply, &x, b, &mut w);
        out.history.push(beta / b_norm);
        // A cycle cut short by the estimate reaching the tolerance may leave the true
        // residual just above it: only the default stall applies to it.
        let limit = if steps == m { stall } else { stall.max(STAGNATION) };
        if beta / b_norm > tolerance && beta > limit * previous {
            out.status = Status::Stalled;
            out.relative_residual = beta / b_norm;
            break;
        }
    }
    out.x = x;
    out
}

/// `x += M⁻¹ V y` at the end of a cycle (`V` the Krylov basis, `y = H⁻¹ g`), with
/// `V y` formed in `w` and `M⁻¹ V y` in `z` (both free until the next cycle: no vector
/// more at the peak).
fn add_correction(
    x: &mut [f64],
    basis: &[Vec<f64>],
    y: &[f64],
    precondition: &impl Fn(&[f64], &mut [f64]),
    (w, z): (&mut [f64], &mut [f64]),
) {
    w.fill(0.0);
    for (yi, v) in y.iter().zip(basis) {
        w.par_iter_mut().zip(v).with_min_len(4096).for_each(|(u, v)| *u += yi * v);
    }
    precondition(w, z);
    x.par_iter_mut().zip(&*z).with_min_len(4096).for_each(|(x, u)| *x += u);
}

/// The least-squares problem of one GMRES cycle, `min ‖β e₁ − H y‖`, kept upper
/// triangular by Givens rotations as the Arnoldi columns arrive: `h` the rotated
/// Hessenberg matrix (`(m + 1) x m`), `cs`, `sn` the rotations, `g` the rotated `β e₁`.
struct Hessenberg {
    h: Vec<Vec<f64>>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
}

impl Hessenberg {
    /// For `m` Arnoldi steps from a residual of norm `beta`.
    fn new(m: usize, beta: f64) -> Self {
        let mut g = vec![0.0f64; m + 1];
        g[0] = beta;
        Hessenberg { h: vec![vec![0.0f64; m]; m + 1], cs: vec![0.0f64; m], sn: vec![0.0f64; m], g }
    }

    /// Column `j`: the projections `h_ij` on the basis and the norm `h_(j+1)j` of what
    /// is left, rotated by the previous rotations and a new one that zeroes
    /// `h_(j+1)j`. Returns `|g_(j+1)|`, the residual norm of the cycle so far.
    fn add_column(&mut self, j: usize, projections: Vec<f64>, rest: f64) -> f64 {
        let (h, cs, sn, g) = (&mut self.h, &mut self.cs, &mut self.sn, &mut self.g);
        for (i, d) in projections.into_iter().enumerate() {
            h[i][j] = d;
        }
        h[j + 1][j] = rest;
        for i in 0..j {
            let t = cs[i] * h[i][j] + sn[i] * h[i + 1][j];
            h[i + 1][j] = -sn[i] * h[i][j] + cs[i] * h[i + 1][j];
            h[i][j] = t;
        }
        let d = h[j][j].hypot(h[j + 1][j]);
        (cs[j], sn[j]) = if d == 0.0 { (1.0, 0.0) } else { (h[j][j] / d, h[j + 1][j] / d) };
        h[j][j] = d;
        h[j + 1][j] = 0.0;
        g[j + 1] = -sn[j] * g[j];
        g[j] *= cs[j];
        g[j + 1].abs()
    }

    /// `y = H⁻¹ g` over the first `steps` columns (back substitution; a zero pivot
    /// gives a zero component).
    fn solve(&self, steps: usize) -> Vec<f64> {
        let (h, g) = (&self.h, &self.g);
        let mut y = vec![0.0f64; steps];
        for i in (0..steps).rev() {
            let s: f64 = (i + 1..steps).map(|k| h[i][k] * y[k]).sum();
            y[i] = if h[i][i] != 0.0 { (g[i] - s) / h[i][i] } else { 0.0 };
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A nonsymmetric, diagonally dominant tridiagonal matrix (convection–diffusion).
    fn convection(n: usize) -> Csr {
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i, 4.0));
            if i > 0 {
                entries.push((i, i - 1, -2.5));
            }
            if i + 1 < n {
                entries.push((i, i + 1, -0.5));
            }
        }
        Csr::from_triplets(n, n, &entries)
    }

    /// The watch hears of every iteration, with the tolerance, and its last residual
    /// is the estimate that ended the solve (at most half the tolerance, the stopping
    /// rule of a cycle); the estimates never grow within a cycle (GMRES minimises it).
    #[test]
    fn the_watch_hears_every_iteration() {
        struct Heard(std::cell::RefCell<Vec<(f64, f64)>>);
        impl Watch for Heard {
            fn residual(&self, reached: f64, target: f64) {
                self.0.borrow_mut().push((reached, target));
            }
        }
        let a = convection(200);
        let b: Vec<f64> = (0..200).map(|i| (i as f64 * 0.1).sin()).collect();
        let heard = Heard(Default::default());
        let out = solve_gmres_with(|x, y| product(&a, x, y), &b, |v, z| z.copy_from_slice(v), (1e-10, 1000, 500, STAGNATION), &heard);
        let heard = heard.0.into_inner();
        assert_eq!(out.status, Status::Converged);
        assert_eq!(heard.len(), out.iterations, "one report per iteration");
        assert!(heard.iter().all(|h| h.1 == 1e-10));
        assert!(heard.last().unwrap().0 <= 0.5e-10, "{:?}", heard.last());
        assert!(heard.windows(2).all(|w| w[1].0 <= w[0].0 * (1.0 + 1e-12)), "one cycle: the estimates never grow");
    }

    #[test]
    fn converges_on_a_nonsymmetric_system_and_reports_the_true_residual() {
        let a = convection(200);
        let b: Vec<f64> = (0..200).map(|i| (i as f64 * 0.1).sin()).collect();
        let out = solve_gmres(&a, &b, |v, z| z.copy_from_slice(v), 1e-12, 1000, 20);
        assert_eq!(out.status, Status::Converged);
        let mut r = vec![0.0; 200];
        let res = true_residual(&|x: &[f64], y: &mut [f64]| product(&a, x, y), &out.x, &b, &mut r) / norm(&b);
        assert!(res <= 1e-12, "{res}");
        assert!((res - out.relative_residual).abs() < 1e-15);
        assert!(out.history.windows(2).all(|w| w[1] <= w[0]), "GMRES residuals never grow: {:?}", out.history);
    }

    #[test]
    fn an_exact_preconditioner_converges_in_one_step() {
        let a = convection(50);
        let b = vec![1.0; 50];
        // M = A: solve by running GMRES itself to round-off.
        let exact = |v: &[f64], z: &mut [f64]| {
            let inner = solve_gmres(&a, v, |v, z| z.copy_from_slice(v), 1e-15, 500, 50);
            z.copy_from_slice(&inner.x);
        };
        let out = solve_gmres(&a, &b, exact, 1e-10, 100, 10);
        assert_eq!(out.status, Status::Converged);
        assert!(out.iterations <= 2, "{} iterations", out.iterations);
    }

    #[test]
    fn a_stall_is_reported_with_its_residual() {
        // The 2x2 rotation [[0, 1], [-1, 0]]: GMRES(1) makes no progress on it.
        let a = Csr::from_triplets(2, 2, &[(0, 1, 1.0), (1, 0, -1.0)]);
        let out = solve_gmres(&a, &[1.0, 0.0], |v, z| z.copy_from_slice(v), 1e-10, 100, 1);
        assert_eq!(out.status, Status::Stalled);
        assert!((out.relative_residual - 1.0).abs() < 1e-12);
        assert!(out.iterations < 100);
    }
}

/// The settings of a GMRES solve.
#[derive(Clone, Copy)]
pub struct GmresSettings {
    pub preconditioner: Preconditioner,
    pub tolerance: f64,
    pub max_iterations: usize,
    pub restart: usize,
    /// The largest share of its residual a restart cycle may leave
    /// ([`gmres::solve_gmres_with`]).
    pub stall: f64,
}
