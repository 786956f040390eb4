//! How `solver.kind = "auto"` chooses by the estimated memory of the LU factors.

use super::*;

/// `auto` takes LU while the estimated factors need at most half the available memory
/// and the iterative settings above it, and says why; with the memory unknown it takes
/// LU; an explicit kind is never changed.
#[test]
fn auto_resolves_by_the_memory_of_the_factors() {
    let auto = SolverKind::Auto(Krylov { preconditioner: Preconditioner::Ilu0, tolerance: 1e-9, max_iterations: 300 });
    let (n, nnz) = (1e5, 2.5e6);
    let factors = lu_factor_bytes(nnz, n);
    assert!(factors > 1e9 && factors < 1e10, "{factors}");
    let (kind, why) = auto.resolve(n, nnz, Some(4.0 * factors));
    assert_eq!(kind, SolverKind::Lu);
    assert!(why.unwrap().contains("within"));
    let (kind, why) = auto.resolve(n, nnz, Some(1.5 * factors));
    assert_eq!(
        kind,
        SolverKind::Gmres {
            krylov: Krylov { preconditioner: Preconditioner::Ilu0, tolerance: 1e-9, max_iterations: 300 },
            restart: GMRES_RESTART
        }
    );
    assert!(why.unwrap().contains("GMRES+ILU(0)"));
    assert_eq!(auto.resolve(n, nnz, None).0, SolverKind::Lu);
    assert_eq!(SolverKind::Lu.resolve(n, nnz, Some(1.0)), (SolverKind::Lu, None));
}

/// In this process `auto` also leaves LU for GMRES when the factors fit but are
/// estimated above [`AUTO_KRYLOV_BYTES`] (for time, with LU as the fallback), except on
/// a saddle point; gone iterative for memory, its fallback is BiCGSTAB+ILU(0). Over MPI
/// ranks ([`SolverKind::resolve`]) only memory counts.
#[test]
fn auto_leaves_lu_for_gmres_above_a_size_when_the_factors_fit() {
    use super::params::AUTO_KRYLOV_BYTES;
    let auto = SolverKind::Auto(Krylov { preconditioner: Preconditioner::Amg, tolerance: 1e-10, max_iterations: 500 });
    let gmres = SolverKind::Gmres {
        krylov: Krylov { preconditioner: Preconditioner::Amg, tolerance: 1e-10, max_iterations: 500 },
        restart: GMRES_RESTART,
    };
    let n = 1e4;
    // The nonzeros whose factors are estimated at `bytes` (the estimate grows with them).
    let nnz = |bytes: f64| {
        let (mut low, mut high): (f64, f64) = (1.0, 1e15);
        for _ in 0..200 {
            let middle = (low * high).sqrt();
            if lu_factor_bytes(middle, n) < bytes {
                low = middle
            } else {
                high = middle
            }
        }
        high
    };
    let roomy = Some(1e12);
    let (kind, why) = auto.resolve_system(n, nnz(0.9 * AUTO_KRYLOV_BYTES), false, roomy);
    assert_eq!(kind, SolverKind::Lu, "{why:?}");
    assert_eq!(auto.auto_fallback(n, nnz(0.9 * AUTO_KRYLOV_BYTES), false, roomy), Some(SolverKind::Lu));
    let (kind, why) = auto.resolve_system(n, nnz(1.1 * AUTO_KRYLOV_BYTES), false, roomy);
    assert_eq!(kind, gmres);
    assert!(why.unwrap().contains("where GMRES+AMG is faster: GMRES+AMG, LU if it fails"));
    assert_eq!(auto.auto_fallback(n, nnz(1.1 * AUTO_KRYLOV_BYTES), false, roomy), Some(SolverKind::Lu));
    assert_eq!(auto.resolve(n, nnz(1.1 * AUTO_KRYLOV_BYTES), roomy).0, SolverKind::Lu, "MPI: memory only");
    assert_eq!(auto.resolve_system(n, nnz(1.1 * AUTO_KRYLOV_BYTES), true, roomy).0, SolverKind::Lu, "saddle point");
    let tight = Some(AUTO_KRYLOV_BYTES);
    assert_eq!(auto.resolve_system(n, nnz(1.1 * AUTO_KRYLOV_BYTES), false, tight).0, gmres);
    assert_eq!(
        auto.auto_fallback(n, nnz(1.1 * AUTO_KRYLOV_BYTES), false, tight),
        Some(SolverKind::Bicgstab(Krylov { preconditioner: Preconditioner::Ilu0, tolerance: 1e-10, max_iterations: 500 }))
    );
    assert_eq!(SolverKind::Lu.auto_fallback(n, 1.0, false, roomy), None);
    // The whole choice as one value: GMRES for time with LU behind it; LU alone below.
    let c = auto.choose(n, nnz(1.1 * AUTO_KRYLOV_BYTES), false, roomy);
    assert_eq!((c.primary, c.fallback), (gmres, Some(SolverKind::Lu)));
    assert!(c.reason.is_some_and(|r| r.contains("LU if it fails")));
    let c = auto.choose(n, nnz(0.9 * AUTO_KRYLOV_BYTES), false, roomy);
    assert_eq!((c.primary, c.fallback), (SolverKind::Lu, None));
    assert_eq!(SolverKind::Lu.choose(n, 1.0, false, roomy), SolverChoice { primary: SolverKind::Lu, fallback: None, reason: None });
}
