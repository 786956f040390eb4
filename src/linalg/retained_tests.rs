//! Tests of the kept solver ([`super`]).

use super::super::tests::{max_rel_diff, navier_like};
use super::super::{assemble, csr, solve_nodal_retained, Krylov, NodeLayout, Preconditioner, SolverKind, SolverParams};

/// A kept solver solves the system with some of its rows replaced: GMRES on the
/// perturbed rows, preconditioned by the kept LU factors or multigrid, recovers a
/// known solution (the `defect` estimate's rows at singular corners). 60 rows of
/// 3 200, each with its off-diagonal coefficients scaled by 1.5: a perturbation of
/// rank 60, which the LU-preconditioned GMRES resolves in at most about 61 iterations.
#[test]
fn a_kept_solver_solves_with_rows_replaced() {
    let m = 40;
    let (t, _, b) = navier_like(m, 0.0);
    let a = csr::to_csr(&assemble(&t).unwrap());
    let positions: Vec<[f64; 2]> = (0..m * m).map(|k| [(k % m) as f64, (k / m) as f64]).collect();
    let gmres_amg = SolverParams {
        kind: SolverKind::Gmres { krylov: Krylov { preconditioner: Preconditioner::Amg, tolerance: 1e-10, max_iterations: 500 }, restart: 30 },
        equilibrate: true,
    };
    for params in [SolverParams::lu(), gmres_amg] {
        let layout = Some(NodeLayout { per_node: 2, positions: &positions, multipliers: 0 });
        let (_, _, kept) = solve_nodal_retained(std::borrow::Cow::Borrowed(&a), &b, &params, layout, None, &()).unwrap();
        let kept = kept.expect("a kept solver");
        let rows = kept.rows().clone();
        // Rows of the nodes of a central block, off-diagonals scaled by 1.5.
        let replaced: Vec<(usize, Vec<(u32, f64)>)> = (0..m * m)
            .filter(|k| (18..23).contains(&(k % m)) && (17..23).contains(&(k / m)))
            .flat_map(|k| [2 * k, 2 * k + 1])
            .map(|r| {
                let row = rows.row(r);
                let entries = row.col_indices().iter().zip(row.values()).map(|(&c, &v)| (c, if c as usize == r { v } else { 1.5 * v })).collect();
                (r, entries)
            })
            .collect();
        assert_eq!(replaced.len(), 60);
        let y_true: Vec<f64> = (0..a.nrows()).map(|i| ((i as f64) * 0.37).sin() + 0.1).collect();
        let mut c = vec![0.0; a.nrows()];
        csr::product(&rows, &y_true, &mut c);
        for (r, entries) in &replaced {
            c[*r] = entries.iter().map(|&(col, v)| v * y_true[col as usize]).sum();
        }
        let (y, note) = kept.solve_replaced(&c, &replaced, 1e-10, &()).unwrap();
        assert!(note.contains("60 rows replaced"), "{note}");
        let err = max_rel_diff(&y, &y_true);
        assert!(err < 1e-6, "{}: {err:.1e} ({note})", params.kind.label());
        // Without the replaced rows the same right-hand side gives another answer.
        let (y_plain, _) = kept.solve_replaced(&c, &[], 1e-10, &()).unwrap();
        assert!(max_rel_diff(&y_plain, &y_true) > 1e-3);
    }
}
