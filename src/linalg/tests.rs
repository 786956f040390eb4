//! Cross-solver tests on a collocation-like system (see [`navier_like`]).

use super::*;
use std::time::Instant;

/// Collocation-like test system: 2D Navier–Cauchy operator with convection,
/// 2 unknowns per node (`u`, `v` interleaved: index `2·(j·m + i) + c`) on an
/// `m × m` grid of the unit square, `h = 1/(m−1)`. Rows are NOT h²-scaled, as
/// in strong-form collocation:
///
/// * interior (`~1/h²`):
///   `(λ+2μ) u_xx + μ u_yy + (λ+μ) v_xy + c·∇u`,
///   `μ v_xx + (λ+2μ) v_yy + (λ+μ) u_xy + c·∇v`
///   (central differences, 9-point stencil through the mixed derivative);
/// * right edge `x = 1` (`~1/h`): traction
///   `t_x = (λ+2μ) u_x + λ v_y`, `t_y = μ (u_y + v_x)`,
///   with second-order one-sided `∂/∂x`;
/// * left, bottom, top edges (`~1`): Dirichlet identity rows.
///
/// Nonsymmetric (convection, one-sided traction rows), indefinite-ish,
/// rows spanning 4–5 orders of magnitude. Returns `(triplets, x_exact, b)`
/// with smooth `x_exact` and `b = A x_exact`.
pub(super) fn navier_like(m: usize, convection: f64) -> (Triplets, Vec<f64>, Vec<f64>) {
    let (lam, mu) = (0.577, 0.385); // E = 1, ν = 0.3
    let h = 1.0 / (m - 1) as f64;
    let (h2, hh) = (h * h, 2.0 * h);
    let (cx, cy) = (convection, 0.5 * convection);
    let idx = |i: usize, j: usize, c: usize| 2 * (j * m + i) + c;
    let n = 2 * m * m;
    let mut t = Triplets::with_capacity(n, 13 * n);
    for j in 0..m {
        for i in 0..m {
            let (ru, rv) = (idx(i, j, 0), idx(i, j, 1));
            if i == 0 || j == 0 || j == m - 1 {
                t.push(ru, ru, 1.0);
                t.push(rv, rv, 1.0);
            } else if i == m - 1 {
                // d/dx one-sided: (3 f_i - 4 f_{i-1} + f_{i-2}) / 2h; d/dy central.
                for (k, w) in [(i, 3.0), (i - 1, -4.0), (i - 2, 1.0)] {
                    t.push(ru, idx(k, j, 0), (lam + 2.0 * mu) * w / hh);
                    t.push(rv, idx(k, j, 1), mu * w / hh);
                }
                t.push(ru, idx(i, j + 1, 1), lam / hh);
                t.push(ru, idx(i, j - 1, 1), -lam / hh);
                t.push(rv, idx(i, j + 1, 0), mu / hh);
                t.push(rv, idx(i, j - 1, 0), -mu / hh);
            } else {
                for (r, c, kx, ky, other) in [(ru, 0, lam + 2.0 * mu, mu, 1), (rv, 1, mu, lam + 2.0 * mu, 0)] {
                    t.push(r, idx(i, j, c), -2.0 * (kx + ky) / h2);
                    t.push(r, idx(i - 1, j, c), kx / h2 - cx / hh);
                    t.push(r, idx(i + 1, j, c), kx / h2 + cx / hh);
                    t.push(r, idx(i, j - 1, c), ky / h2 - cy / hh);
                    t.push(r, idx(i, j + 1, c), ky / h2 + cy / hh);
                    let g = (lam + mu) / (4.0 * h2);
                    t.push(r, idx(i + 1, j + 1, other), g);
                    t.push(r, idx(i - 1, j - 1, other), g);
                    t.push(r, idx(i + 1, j - 1, other), -g);
                    t.push(r, idx(i - 1, j + 1, other), -g);
                }
            }
        }
    }
    let mut x = vec![0.0; n];
    for j in 0..m {
        for i in 0..m {
            let (px, py) = (i as f64 * h, j as f64 * h);
            x[idx(i, j, 0)] = (2.0 * px).sin() * (1.0 + py) + 0.1 * (7.0 * py).cos();
            x[idx(i, j, 1)] = (px * py).exp() - 0.3 * (5.0 * px).sin();
        }
    }
    let b = coo_matvec(&t, &x);
    (t, x, b)
}

/// `A x` straight from the COO triplets — an independent code path from the
/// CSC sweep in [`relative_residual`].
pub(super) fn coo_matvec(t: &Triplets, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; t.dim()];
    for (row, col, val) in t.entries() {
        y[row] += val * x[col];
    }
    y
}

/// Independent true relative residual from the COO triplets.
pub(super) fn coo_relres(t: &Triplets, x: &[f64], b: &[f64]) -> f64 {
    let ax = coo_matvec(t, x);
    let r: Vec<f64> = b.iter().zip(&ax).map(|(bi, ai)| bi - ai).collect();
    norm2(&r) / norm2(b)
}

pub(super) fn max_rel_diff(x: &[f64], y: &[f64]) -> f64 {
    let d = x.iter().zip(y).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    d / y.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Rounding floor of a computed relative residual: `ε ‖ |A| |x| ‖₂ / ‖b‖₂`.
/// Two correct evaluations of `‖b − A x‖/‖b‖` in different summation orders
/// can differ by about this much.
fn residual_floor(t: &Triplets, x: &[f64], b: &[f64]) -> f64 {
    let mut y = vec![0.0; t.dim()];
    for (row, col, val) in t.entries() {
        y[row] += (val * x[col]).abs();
    }
    f64::EPSILON * norm2(&y) / norm2(b)
}

fn bicgstab_params(preconditioner: Preconditioner, equilibrate: bool) -> SolverParams {
    SolverParams { kind: SolverKind::Bicgstab(Krylov { preconditioner, tolerance: 1e-10, max_iterations: 2000 }), equilibrate }
}

#[test]
fn lu_and_bicgstab_agree_on_collocation_like_system() {
    let (t, x_exact, b) = navier_like(100, 20.0);
    let a = assemble(&t).unwrap();
    assert_eq!(a.nrows(), 20_000);

    let t0 = Instant::now();
    let (x_lu, rep) = solve(&a, &b, &SolverParams::lu()).unwrap();
    let floor = residual_floor(&t, &x_lu, &b);
    println!(
        "n = {}, nnz = {}, LU: residual {:.2e} (floor {floor:.1e}), setup {:.3}s, solve {:.3}s, \
         total {:.3}s, |x - x_exact|/|x| = {:.1e}",
        a.nrows(),
        a.compute_nnz(),
        rep.relative_residual,
        rep.setup_seconds,
        rep.solve_seconds,
        t0.elapsed().as_secs_f64(),
        max_rel_diff(&x_lu, &x_exact)
    );
    // Backward-stable LU: residual at the rounding floor (~2e-13 measured);
    // 1e-11 would catch a badly pivoted or wrong factorisation.
    assert!(rep.relative_residual < 1e-11);
    assert!((rep.relative_residual - coo_relres(&t, &x_lu, &b)).abs() <= 10.0 * floor);
    // b = A x_exact exactly, so LU must recover x_exact up to κ ε; κ of the
    // equilibrated system is ≲ 1e6 here, so 1e-9 is safe (measured 3e-14).
    assert!(max_rel_diff(&x_lu, &x_exact) < 1e-9);

    let mut iterations = Vec::new();
    for pc in [Preconditioner::Jacobi, Preconditioner::Ilu0, Preconditioner::Ilut { drop: 1e-5, fill: 20 }] {
        let (x, rep) = solve(&a, &b, &bicgstab_params(pc, true)).unwrap();
        let independent = coo_relres(&t, &x, &b);
        let floor = residual_floor(&t, &x, &b);
        let (ts, bs) = row_scaled(&t, &b);
        let independent_scaled = coo_relres(&ts, &x, &bs);
        let floor_scaled = residual_floor(&ts, &x, &bs);
        let diff = max_rel_diff(&x, &x_lu);
        println!(
            "{}: {} iterations ({} restarts), residual {:.2e} (independent {independent:.2e}), \
             setup {:.3}s, solve {:.3}s, precond nnz {:?}, max|x - x_lu|/max|x_lu| = {diff:.1e}",
            rep.method,
            rep.iterations,
            rep.restarts,
            rep.relative_residual,
            rep.setup_seconds,
            rep.solve_seconds,
            rep.preconditioner_nonzeros
        );
        // Converged means the TRUE residual of the equilibrated system ≤ tolerance
        // (not faer's recursive one); both reported residuals are true ones: equal
        // to evaluations from the COO triplets (row-scaled, and original) up to the
        // rounding floor of forming b − A x (~1e-13).
        assert!(rep.relative_residual <= 1e-10);
        assert!(
            (rep.relative_residual - independent_scaled).abs() <= 10.0 * floor_scaled,
            "reported {} vs independent {independent_scaled} (floor {floor_scaled:.1e})",
            rep.relative_residual
        );
        assert!(
            (rep.original_relative_residual - independent).abs() <= 10.0 * floor,
            "reported {} vs independent {independent} (floor {floor:.1e})",
            rep.original_relative_residual
        );
        // Residual 1e-10 of the equilibrated system, amplified by its condition
        // (κ₁ ≲ 1e6 here; effective amplification measured up to 430, Jacobi:
        // 4.3e-8): 1e-7 still catches a wrong solution by orders of magnitude.
        assert!(diff < 1e-7, "{pc:?}: relative max-norm difference to LU {diff:.2e}");
        iterations.push(rep.iterations);
    }
    // Stronger preconditioners must need fewer iterations (measured 844 /
    // 206 / 15); a broken ILU would fail this even if BiCGSTAB still converges.
    assert!(iterations[2] < iterations[1] && iterations[1] < iterations[0], "{iterations:?}");
}

/// Rows of `navier_like(30, 20)` multiplied by `10^u`, `u` spread
/// quasi-uniformly over [-12, 12] (golden-ratio sequence).
fn badly_scaled() -> (Triplets, Vec<f64>, Vec<f64>) {
    let (t, x_exact, b) = navier_like(30, 20.0);
    let scale = |i: usize| 10f64.powf(24.0 * (i as f64 * 0.618_033_988_749_895).fract() - 12.0);
    let mut ts = Triplets::with_capacity(t.dim(), t.len());
    for (row, col, val) in t.entries() {
        ts.push(row, col, val * scale(row));
    }
    let bs = b.iter().enumerate().map(|(i, v)| v * scale(i)).collect();
    (ts, x_exact, bs)
}

#[test]
fn equilibration_handles_rows_scaled_from_1e_minus_12_to_1e12() {
    let (t, x_exact, b) = badly_scaled();
    let a = assemble(&t).unwrap();
    for kind in [
        SolverKind::Lu,
        SolverKind::default_bicgstab(),
        SolverKind::Bicgstab(Krylov { preconditioner: Preconditioner::Ilu0, tolerance: 1e-10, max_iterations: 2000 }),
    ] {
        let params = SolverParams { kind, equilibrate: true };
        let (x, rep) = solve(&a, &b, &params).unwrap();
        let err = max_rel_diff(&x, &x_exact);
        let independent = coo_relres(&t, &x, &b);
        println!(
            "scaled rows, {}: {} iterations, residual (original system) {:.2e}, \
             independent {independent:.2e}, max|x - x_exact|/max|x| = {err:.1e}",
            rep.method, rep.iterations, rep.relative_residual
        );
        assert!(rep.equilibrated);
        // b = A x_exact, equilibrated κ ≲ 1e5 (n = 1800): LU recovers x_exact to
        // ~1e-14 and BiCGSTAB at residual 1e-10 to ~1e-10 (measured 1.5e-14 /
        // 4.7e-12 / 9.2e-11); 1e-8 is the brief's agreement level.
        assert!(err < 1e-8, "{}: error {err:.2e}", rep.method);
        // `original_relative_residual` is that of the ORIGINAL (row-scaled by up
        // to 1e±12) system: equal to the COO recomputation up to the rounding
        // floor; convergence is measured on the equilibrated one.
        let floor = residual_floor(&t, &x, &b);
        assert!((rep.original_relative_residual - independent).abs() <= 10.0 * floor);
        assert!(rep.relative_residual <= 1e-10);
    }
    // Without equilibration LU pivots on the huge rows: faer's "solution" is
    // off by ~7e-4 and κ₁ ≈ 1e29, so it must be refused, not returned.
    let params = SolverParams { kind: SolverKind::Lu, equilibrate: false };
    match solve(&a, &b, &params) {
        Err(SolveError::Singular { detail }) => assert!(detail.contains("turn it on"), "{detail}"),
        other => panic!("expected Singular without equilibration, got {other:?}"),
    }
}

/// Pure-Neumann 5-point Laplacian on an `m × m` grid (second-order one-sided
/// normal derivatives on the boundary): constants span its null space, the
/// scalar analogue of the rigid-body modes of a pure-traction problem.
fn pure_neumann(m: usize) -> Triplets {
    let h = 1.0 / (m - 1) as f64;
    let id = |i: usize, j: usize| j * m + i;
    let one_sided = [(0, -3.0), (1, 4.0), (2, -1.0)];
    let mut t = Triplets::new(m * m);
    for j in 0..m {
        for i in 0..m {
            let r = id(i, j);
            if i == 0 || i == m - 1 {
                for (k, w) in one_sided {
                    let k = if i == 0 { k } else { m - 1 - k };
                    t.push(r, id(k, j), w / (2.0 * h));
                }
            } else if j == 0 || j == m - 1 {
                for (k, w) in one_sided {
                    let k = if j == 0 { k } else { m - 1 - k };
                    t.push(r, id(i, k), w / (2.0 * h));
                }
            } else {
                t.push(r, r, -4.0 / (h * h));
                for k in [id(i - 1, j), id(i + 1, j), id(i, j - 1), id(i, j + 1)] {
                    t.push(r, k, 1.0 / (h * h));
                }
            }
        }
    }
    t
}

fn expect_singular(r: Result<(Vec<f64>, SolveReport), SolveError>, what: &str) -> String {
    match r {
        Err(e @ SolveError::Singular { .. }) => e.to_string(),
        Err(e) => panic!("{what}: expected Singular, got error {e}"),
        Ok((_, rep)) => panic!("{what}: expected Singular, got a solution: {rep:?}"),
    }
}

#[test]
fn singular_systems_are_errors_not_garbage() {
    let lu = |equilibrate| SolverParams { kind: SolverKind::Lu, equilibrate };
    for eq in [true, false] {
        // All-zero row 1 (its column still has an entry).
        let mut t = Triplets::new(3);
        for (i, j, v) in [(0, 0, 2.0), (0, 1, 1.0), (2, 1, 1.0), (2, 2, 3.0)] {
            t.push(i, j, v);
        }
        let a = assemble(&t).unwrap();
        let msg = expect_singular(solve(&a, &[1.0, 1.0, 1.0], &lu(eq)), "zero row");
        assert!(msg.contains("row 1"), "{msg}");
        let msg = expect_singular(solve(&a, &[1.0, 1.0, 1.0], &bicgstab_params(Preconditioner::Ilu0, eq)), "zero row, bicgstab");
        assert!(msg.contains("row 1"), "{msg}");

        // Two identical rows, consistent and inconsistent right-hand sides.
        let mut t = Triplets::new(3);
        for (i, j, v) in [(0, 0, 1.0), (0, 1, 2.0), (0, 2, 3.0), (1, 0, 1.0)] {
            t.push(i, j, v);
        }
        for (i, j, v) in [(1, 1, 2.0), (1, 2, 3.0), (2, 1, 1.0), (2, 2, 4.0)] {
            t.push(i, j, v);
        }
        let a = assemble(&t).unwrap();
        for b in [[6.0, 6.0, 5.0], [6.0, 7.0, 5.0]] {
            let msg = expect_singular(solve(&a, &b, &lu(eq)), "identical rows");
            assert!(msg.contains("boundary conditions"), "{msg}");
        }

        // Pure Neumann: inconsistent data -> LU residual ~1e-4 (refused);
        // consistent data -> tiny residual but arbitrary constant, refused by
        // the κ₁ estimate (~6e17 measured vs limit 1e14).
        let t = pure_neumann(20);
        let a = assemble(&t).unwrap();
        let x0: Vec<f64> = (0..t.dim()).map(|k| (k as f64 * 0.1).sin()).collect();
        let b = coo_matvec(&t, &x0);
        let msg = expect_singular(solve(&a, &b, &lu(eq)), "consistent Neumann");
        assert!(msg.contains("rigid-body"), "{msg}");
        let mut b_bad = b.clone();
        b_bad[5] += 1.0;
        let msg = expect_singular(solve(&a, &b_bad, &lu(eq)), "inconsistent Neumann");
        assert!(msg.contains("residual"), "{msg}");
    }
}

#[test]
fn non_finite_matrix_entry_is_named() {
    // `Triplets::push` debug-asserts finiteness, so build the faer matrix
    // directly, as a caller bypassing `assemble` could.
    use faer::sparse::Triplet;
    let entries = [Triplet::new(0, 0, 1.0), Triplet::new(1, 1, 1.0), Triplet::new(1, 0, f64::INFINITY)];
    let a = SparseMatrix::try_new_from_triplets(2, 2, &entries).unwrap();
    for params in [SolverParams::lu(), bicgstab_params(Preconditioner::Jacobi, false)] {
        match solve(&a, &[1.0, 1.0], &params) {
            Err(e @ SolveError::NotFinite { row: 1, col: 0, .. }) => {
                assert!(e.to_string().contains("(1, 0)"))
            }
            other => panic!("expected NotFinite at (1, 0), got {other:?}"),
        }
    }
}

/// The triplets and right-hand side with every row divided by its largest |entry|
/// (the equilibration of `scaling`, recomputed independently).
fn row_scaled(t: &Triplets, b: &[f64]) -> (Triplets, Vec<f64>) {
    let mut row_max = vec![0.0f64; b.len()];
    for (row, _, val) in t.entries() {
        row_max[row] = row_max[row].max(val.abs());
    }
    let mut ts = Triplets::new(b.len());
    for (row, col, val) in t.entries() {
        ts.push(row, col, val / row_max[row]);
    }
    (ts, b.iter().zip(&row_max).map(|(v, m)| v / m).collect())
}

#[test]
fn no_convergence_reports_the_true_residual() {
    let (t, _, b) = navier_like(40, 20.0);
    let a = assemble(&t).unwrap();
    let (pc, tol, max_it) = (Preconditioner::Jacobi, 1e-10, 2);
    let params = SolverParams {
        kind: SolverKind::Bicgstab(Krylov { preconditioner: pc, tolerance: tol, max_iterations: max_it }),
        equilibrate: true,
    };
    let err = solve(&a, &b, &params).unwrap_err();
    let msg = err.to_string();
    let SolveError::NoConvergence { iterations, relative_residual, ref method, .. } = err else {
        panic!("expected NoConvergence, got {err}");
    };
    println!("{msg}");
    assert_eq!(iterations, 2);
    assert_eq!(method, "BiCGSTAB+Jacobi");
    assert!(msg.contains("did not converge in 2 iterations"), "{msg}");
    assert!(msg.contains("stopped by the iteration limit (solver.max_iterations = 2)"), "{msg}");
    assert!(relative_residual > tol);
    // faer alone would report the INITIAL residual (exactly 1 for x₀ = 0);
    // re-run the same deterministic iteration to get the final iterate and
    // recompute its residual independently from the COO triplets.
    let (s, d) = scaling::equilibrate_rows(&csr::to_csr(&a)).unwrap();
    let s = csr::columns_of(s);
    let bs = scaling::scale_rhs(&b, &d);
    let p = precond::BuiltPreconditioner::build(&s, pc, None).unwrap();
    let out = bicgstab::solve_bicgstab(&s, &bs, &p, tol, max_it, |x| super::relative_residual(&s, x, &bs));
    let (ts, b_scaled) = row_scaled(&t, &b);
    let independent = coo_relres(&ts, &out.x, &b_scaled);
    assert!((relative_residual - independent).abs() <= 10.0 * residual_floor(&ts, &out.x, &b_scaled));
    assert!((relative_residual - 1.0).abs() > 1e-3, "looks like the initial residual");
}

/// `auto` gone iterative retries with BiCGSTAB+ILU(0) when its GMRES stops: with a
/// 300-iteration budget Jacobi does not converge on the collocation-like system of the
/// test above (it needs 548 iterations there), ILU(0) does (135), and the choice says
/// what happened; with the memory to spare it is LU without a retry.
#[test]
fn auto_retries_with_ilu0_when_the_iteration_stops() {
    let (t, _, b) = navier_like(100, 20.0);
    let a = assemble(&t).unwrap();
    let kind = |preconditioner| SolverKind::Bicgstab(Krylov { preconditioner, tolerance: 1e-10, max_iterations: 300 });
    assert!(solve(&a, &b, &SolverParams { kind: kind(Preconditioner::Jacobi), equilibrate: true }).is_err(), "Jacobi alone must stop");
    let auto = SolverParams {
        kind: SolverKind::Auto(Krylov { preconditioner: Preconditioner::Jacobi, tolerance: 1e-10, max_iterations: 300 }),
        equilibrate: true,
    };
    let (x, rep) = solve_with_memory(std::borrow::Cow::Owned(csr::to_csr(&a)), &b, &auto, None, None, (Some(1.0), &(), None)).unwrap();
    assert_eq!(rep.method, "bicgstab+ilu0");
    let why = rep.choice.unwrap();
    assert!(why.contains("did not converge") && why.contains("retried with BiCGSTAB+ILU(0)"), "{why}");
    let (x_lu, _) = solve(&a, &b, &SolverParams::lu()).unwrap();
    assert!(max_rel_diff(&x, &x_lu) < 1e-7);
    let (_, rep) = solve_with_memory(std::borrow::Cow::Owned(csr::to_csr(&a)), &b, &auto, None, None, (Some(1e12), &(), None)).unwrap();
    assert_eq!(rep.method, "lu");
}

/// A low-order operator that cannot be made leaves the multigrid on the system and
/// says why in the report's `choice` (never only in the method's label): the solution
/// is the system's, as without a builder.
#[test]
fn a_failed_low_order_operator_is_reported() {
    let (t, _, b) = navier_like(100, 20.0);
    let a = assemble(&t).unwrap();
    let params = SolverParams { kind: SolverKind::default_gmres(), equilibrate: true };
    let failing: Auxiliary = Some(Box::new(|| Err("a stencil without enough nodes".to_string())));
    let (x, rep) = solve_with_memory(std::borrow::Cow::Owned(csr::to_csr(&a)), &b, &params, None, failing, (None, &(), None)).unwrap();
    assert!(!rep.method.contains("low-order"), "{}", rep.method);
    let why = rep.choice.unwrap_or_default();
    assert!(why.contains("could not be made (a stencil without enough nodes): built on the system"), "{why}");
    let (plain, rep) = solve_with_memory(std::borrow::Cow::Owned(csr::to_csr(&a)), &b, &params, None, None, (None, &(), None)).unwrap();
    assert_eq!(rep.choice, None);
    // The same method on the same operator (rayon's reductions may order sums
    // differently between runs: round-off only).
    assert!(max_rel_diff(&x, &plain) < 1e-9);
}

