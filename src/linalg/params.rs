//! What a solve is asked to do: the solver, its preconditioner and settings, and
//! their names in a scene file.

use crate::scene::choice::choice;

/// Preconditioner `M ≈ A` for BiCGSTAB, applied on the right
/// (`A M⁻¹ y = b`, `x = M⁻¹ y`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Preconditioner {
    /// `M = diag(A)`; see [`precond::Jacobi`].
    Jacobi,
    /// Zero-fill incomplete LU (Saad, *Iterative Methods for Sparse Linear
    /// Systems*, 2nd ed., Alg. 10.4), from `faer-precond`.
    Ilu0,
    /// Saad's dual-threshold ILUT(τ, p) (Saad 1994, *Numer. Linear Algebra
    /// Appl.* 1:387–402; book Alg. 10.6); see [`precond::Ilut`] for the exact
    /// dropping rules. `drop` is τ (relative to the row 2-norm), `fill` is the
    /// number of entries kept per row in each of L and U *beyond* the count of
    /// the corresponding part of the original row.
    Ilut {
        /// Drop tolerance τ, relative to the row 2-norm (`≥ 0`).
        drop: f64,
        /// Extra entries per row kept in each of L and U (`p`).
        fill: usize,
    },
    /// Smoothed-aggregation algebraic multigrid, one V-cycle per application, with
    /// the rigid-body modes as near-null space ([`super::amg`]).
    Amg,
}

impl Preconditioner {
    /// Short machine-friendly label, e.g. `ilut(drop=1e-5,fill=20)`.
    pub fn label(&self) -> String {
        match self {
            Preconditioner::Jacobi => "jacobi".to_string(),
            Preconditioner::Ilu0 => "ilu0".to_string(),
            Preconditioner::Ilut { drop, fill } => format!("ilut(drop={drop:e},fill={fill})"),
            Preconditioner::Amg => "amg".to_string(),
        }
    }

    /// Human-readable name used in error messages, e.g. `ILU(0)`.
    pub fn display_name(&self) -> String {
        match self {
            Preconditioner::Jacobi => "Jacobi".to_string(),
            Preconditioner::Ilu0 => "ILU(0)".to_string(),
            Preconditioner::Ilut { drop, fill } => format!("ILUT(drop={drop:e}, fill={fill})"),
            Preconditioner::Amg => "AMG".to_string(),
        }
    }
}

/// Which solver [`solve`] uses.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum SolverKind {
    /// Sparse direct LU with partial pivoting (`faer::sparse` supernodal/
    /// simplicial LU, COLAMD column ordering).
    Lu,
    /// Right-preconditioned BiCGSTAB (van der Vorst 1992). Converged means the
    /// true relative residual of the original system is `≤ tolerance`; an iteration
    /// is 2 preconditioner applications and 2 products with `A`.
    Bicgstab(Krylov),
    /// Restarted right-preconditioned GMRES(`restart`) (Saad & Schultz 1986;
    /// [`super::gmres`]). Converged means the same true residual as BiCGSTAB's.
    Gmres {
        /// Preconditioner, tolerance and iteration budget (products with `A`, over all
        /// restarts).
        #[serde(flatten)]
        krylov: Krylov,
        /// Krylov vectors kept before a restart.
        restart: usize,
    },
    /// PETSc's KSP over the MPI ranks of the run (feature `petsc`,
    /// [`super::distributed`]): GMRES(`restart`) with the preconditioner's PETSc
    /// counterpart ([`Preconditioner::petsc_name`]) to the same true relative residual;
    /// PETSc's options database overrides each default.
    Petsc {
        /// Preconditioner (mapped to PETSc's), tolerance and iteration budget.
        #[serde(flatten)]
        krylov: Krylov,
        /// Krylov vectors kept before a restart.
        restart: usize,
        /// Preconditioner replaced by a distributed sparse LU (MUMPS): `lu` and `auto`'s
        /// LU choice over MPI ranks.
        direct: bool,
    },
    /// GMRES with these settings when the LU factors would not fit comfortably or
    /// would be slow to make, else LU ([`SolverKind::resolve_system`]).
    Auto(Krylov),
}

/// What every Krylov method is given: its right preconditioner, the true relative
/// residual `‖b − A x‖₂ / ‖b‖₂` of the solved (row-equilibrated, when equilibration is
/// on) system to reach (`> 0`), and its iteration budget. The default is GMRES's and
/// `auto`'s: multigrid, 1e-10, 500 iterations.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Krylov {
    /// Right preconditioner.
    pub preconditioner: Preconditioner,
    /// Target true relative residual of the solved system (`> 0`).
    pub tolerance: f64,
    /// Iteration budget.
    pub max_iterations: usize,
}

impl Default for Krylov {
    fn default() -> Self {
        Krylov { preconditioner: Preconditioner::Amg, tolerance: 1e-10, max_iterations: 500 }
    }
}

impl Krylov {
    /// BiCGSTAB's default: ILUT(drop = 1e-5, fill = 20), tolerance 1e-10, at most 2000
    /// iterations.
    pub fn bicgstab() -> Self {
        Krylov { preconditioner: Preconditioner::Ilut { drop: 1e-5, fill: 20 }, tolerance: 1e-10, max_iterations: 2000 }
    }
}

/// Estimated bytes of faer's sparse-LU factors of a matrix with `nonzeros` entries `Z`
/// and `unknowns` rows `N`: `5.5 Z^1.2 N^0.164`, a least-squares fit in logarithms
/// over 11 measured factorisations (shipped scenes and their references, 3e3 to 9e4
/// unknowns, 5e4 to 1.6e7 entries: each within 0.72-1.22x of the fit, whose constant
/// 4.65 is raised to 5.5 so that none is underestimated by more than 0.85x; the fill
/// of COLAMD's ordering depends on the geometry as well, so no fit in `Z` and `N`
/// alone does much better; benches/memory_estimate.sh,
/// docs/notebook/2026-11-29-memory-estimate.md).
pub fn lu_factor_bytes(nonzeros: f64, unknowns: f64) -> f64 {
    5.5 * nonzeros.max(1.0).powf(1.2) * unknowns.max(1.0).powf(0.164)
}

/// Krylov vectors GMRES keeps by default (30 vectors of the unknowns: 0.5 GB at
/// 2e6 unknowns).
pub const GMRES_RESTART: usize = 30;

/// Krylov vectors of `auto`'s GMRES on a displacement-pressure system: on the Lame
/// ring at nu = 0.4999 the longer restart took about half the iterations and less time
/// than GMRES(30), for a little more peak memory
/// (docs/notebook/2026-11-26-up-form-iterative-solvers.md).
pub const SADDLE_POINT_RESTART: usize = 100;

/// Least iteration budget of `auto`'s GMRES on a displacement-pressure system.
pub const SADDLE_POINT_ITERATIONS: usize = 2000;

/// Fraction of the available memory that `auto` lets the LU factors take.
pub const AUTO_LU_SHARE: f64 = 0.5;

/// Estimated LU factor bytes ([`lu_factor_bytes`]) above which `auto` solves a
/// displacement system by GMRES + multigrid even though the factors fit, and falls
/// back to LU if the iteration fails: on the shipped scenes the two solve equally fast
/// below it, and GMRES + AMG is faster above it, by far on the largest systems
/// (docs/notebook/2026-11-27-auto-by-time.md).
pub const AUTO_KRYLOV_BYTES: f64 = 4e7;

/// The largest share of its residual a whole restart cycle of the GMRES that `auto`
/// chose for time ([`AUTO_KRYLOV_BYTES`]) may leave before LU takes over: a working
/// multigrid leaves far less per cycle on the shipped scenes, the bracket's (unstable
/// at its re-entrant corner) far more after a first cycle that cost as much as its LU
/// (docs/notebook/2026-11-27-auto-by-time.md).
pub const AUTO_KRYLOV_PACE: f64 = 0.1;

/// What a solve runs, decided once: the solver, the one it falls back to when that
/// fails, and why (`auto`'s reason, for `summary.json`'s `solver.choice`).
#[derive(Clone, Debug, PartialEq)]
pub struct SolverChoice {
    /// The solver run first.
    pub primary: SolverKind,
    /// The solver run when the primary GMRES fails (`auto` only).
    pub fallback: Option<SolverKind>,
    /// Why `auto` chose so (`None` for an explicit kind).
    pub reason: Option<String>,
}

impl SolverKind {
    /// Its name in a scene.
    pub fn method(&self) -> SolverMethod {
        match self {
            SolverKind::Lu => SolverMethod::Lu,
            SolverKind::Bicgstab(..) => SolverMethod::Bicgstab,
            SolverKind::Gmres { .. } => SolverMethod::Gmres,
            SolverKind::Petsc { .. } => SolverMethod::Petsc,
            SolverKind::Auto(..) => SolverMethod::Auto,
        }
    }

    /// The solver of an internal reference solve (an error estimate's higher-degree
    /// system on the run's nodes): a scene's explicit GMRES or BiCGSTAB becomes `auto`
    /// with the same tolerance and budget, so that a small reference is solved by LU and
    /// a large one falls back to BiCGSTAB+ILU(0) when the multigrid does not converge
    /// (on degree-6 stencils of 56 nodes GMRES+AMG stalled on a Kirsch plate whose
    /// degree-4 run it solved: docs/notebook/2026-11-25-multigrid-symmetry-edges.md);
    /// LU, PETSc and `auto` stay.
    pub fn for_reference(&self) -> SolverKind {
        match *self {
            SolverKind::Gmres { krylov: Krylov { tolerance, max_iterations, .. }, .. }
            | SolverKind::Bicgstab(Krylov { tolerance, max_iterations, .. }) => {
                SolverKind::Auto(Krylov { preconditioner: Preconditioner::Amg, tolerance, max_iterations })
            }
            other => other,
        }
    }

    /// The same solver with its Krylov tolerance set to `tolerance` (LU unchanged):
    /// a correction needs only a few digits.
    pub fn with_tolerance(&self, tolerance: f64) -> SolverKind {
        let mut kind = *self;
        if let SolverKind::Auto(k) | SolverKind::Bicgstab(k) | SolverKind::Gmres { krylov: k, .. } | SolverKind::Petsc { krylov: k, .. } = &mut kind {
            k.tolerance = tolerance;
        }
        kind
    }

    /// `auto`'s choice by memory alone, and why: LU when its estimated factors
    /// ([`lu_factor_bytes`]) take at most [`AUTO_LU_SHARE`] of the `available` memory
    /// (or the available memory is unknown), else GMRES([`GMRES_RESTART`]) with the
    /// `Auto` settings. This is the choice between MUMPS and a Krylov method over MPI
    /// ranks, where no fallback follows a failed iteration; an explicit kind is
    /// returned unchanged.
    pub fn resolve(&self, unknowns: f64, nonzeros: f64, available: Option<f64>) -> (SolverKind, Option<String>) {
        let SolverKind::Auto(Krylov { preconditioner, tolerance, max_iterations }) = *self else { return (*self, None) };
        let factors = lu_factor_bytes(nonzeros, unknowns);
        match available {
            Some(a) if factors > AUTO_LU_SHARE * a => (
                SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart: GMRES_RESTART },
                Some(format!(
                    "auto: LU factors estimated at {:.2} GB, more than {AUTO_LU_SHARE} of the {:.2} GB available: GMRES+{}",
                    factors / 1e9,
                    a / 1e9,
                    preconditioner.display_name()
                )),
            ),
            Some(a) => (
                SolverKind::Lu,
                Some(format!(
                    "auto: LU factors estimated at {:.2} GB, within {AUTO_LU_SHARE} of the {:.2} GB available",
                    factors / 1e9,
                    a / 1e9
                )),
            ),
            None => (SolverKind::Lu, Some("auto: available memory unknown, LU".to_string())),
        }
    }

    /// The solver that runs in this process on a system of `unknowns` rows and
    /// `nonzeros` entries with `available` bytes of memory, and for `Auto` why:
    /// [`SolverKind::resolve`]'s choice by memory, except that a displacement system
    /// whose factors fit but are estimated above [`AUTO_KRYLOV_BYTES`] is solved by
    /// GMRES([`GMRES_RESTART`]) for time (LU is then the fallback,
    /// [`SolverKind::auto_fallback`]). A saddle point (the displacement-pressure form)
    /// keeps LU while it fits; gone iterative by memory, it runs
    /// [`SolverKind::for_saddle_point`]'s longer GMRES and says so in the reason.
    pub fn resolve_system(&self, unknowns: f64, nonzeros: f64, saddle_point: bool, available: Option<f64>) -> (SolverKind, Option<String>) {
        let (kind, mut choice) = self.resolve(unknowns, nonzeros, available);
        let SolverKind::Auto(Krylov { preconditioner, tolerance, max_iterations }) = *self else { return (kind, choice) };
        let factors = lu_factor_bytes(nonzeros, unknowns);
        if kind == SolverKind::Lu && !saddle_point && factors > AUTO_KRYLOV_BYTES {
            let why = format!(
                "{}, but above {:.0} MB, where GMRES+{} is faster: GMRES+{}, LU if it fails",
                choice.unwrap_or_default(),
                AUTO_KRYLOV_BYTES / 1e6,
                preconditioner.display_name(),
                preconditioner.display_name()
            );
            return (SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart: GMRES_RESTART }, Some(why));
        }
        if !saddle_point {
            return (kind, choice);
        }
        let longer = kind.for_saddle_point();
        if let (Some(c), SolverKind::Gmres { krylov: Krylov { max_iterations, .. }, restart, .. }) = (&mut choice, longer) {
            c.push_str(&format!(
                " (the displacement-pressure form: GMRES({restart}), up to {max_iterations} iterations, block-triangular preconditioner)"
            ));
        }
        (longer, choice)
    }

    /// The whole choice for a system of `unknowns` rows and `nonzeros` entries in this
    /// process: [`SolverKind::resolve_system`]'s solver and reason, and when that is a
    /// GMRES, [`SolverKind::auto_fallback`]'s fallback.
    pub fn choose(&self, unknowns: f64, nonzeros: f64, saddle_point: bool, available: Option<f64>) -> SolverChoice {
        let (primary, reason) = self.resolve_system(unknowns, nonzeros, saddle_point, available);
        let fallback = match primary {
            SolverKind::Gmres { .. } => self.auto_fallback(unknowns, nonzeros, saddle_point, available),
            SolverKind::Lu | SolverKind::Bicgstab(_) | SolverKind::Petsc { .. } | SolverKind::Auto(_) => None,
        };
        SolverChoice { primary, fallback, reason }
    }

    /// What `auto` tries when the GMRES it chose for this system fails: LU when the
    /// factors fit ([`SolverKind::resolve`] chose LU: GMRES was chosen for time),
    /// else BiCGSTAB with ILU(0) and the `Auto` tolerance and iteration budget (on the
    /// cantilever grid ILUT diverges where ILU(0) converges;
    /// docs/notebook/round2-direct-against-iterative.md). `None`
    /// for an explicit kind and for a saddle point.
    pub fn auto_fallback(&self, unknowns: f64, nonzeros: f64, saddle_point: bool, available: Option<f64>) -> Option<SolverKind> {
        let SolverKind::Auto(Krylov { tolerance, max_iterations, .. }) = *self else { return None };
        if saddle_point {
            return None;
        }
        Some(match self.resolve(unknowns, nonzeros, available).0 {
            SolverKind::Lu => SolverKind::Lu,
            _ => SolverKind::Bicgstab(Krylov { preconditioner: Preconditioner::Ilu0, tolerance, max_iterations }),
        })
    }

    /// The GMRES that `auto`, gone iterative, runs on a displacement-pressure system:
    /// [`SADDLE_POINT_RESTART`] vectors and at least [`SADDLE_POINT_ITERATIONS`]
    /// iterations (its block preconditioner needs some hundreds, `super::saddle`);
    /// anything else unchanged.
    pub fn for_saddle_point(self) -> SolverKind {
        match self {
            SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, .. } => SolverKind::Gmres {
                krylov: Krylov { preconditioner, tolerance, max_iterations: max_iterations.max(SADDLE_POINT_ITERATIONS) },
                restart: SADDLE_POINT_RESTART,
            },
            other => other,
        }
    }

    /// BiCGSTAB with [`Krylov::bicgstab`]'s settings.
    pub fn default_bicgstab() -> Self {
        SolverKind::Bicgstab(Krylov::bicgstab())
    }

    /// The iterative default: GMRES(30) with [`Krylov::default`]'s settings.
    pub fn default_gmres() -> Self {
        SolverKind::Gmres { krylov: Krylov::default(), restart: GMRES_RESTART }
    }

    /// The Krylov settings of an iterative kind (`None` for LU).
    pub fn krylov(&self) -> Option<Krylov> {
        match *self {
            SolverKind::Lu => None,
            SolverKind::Bicgstab(k) | SolverKind::Auto(k) | SolverKind::Gmres { krylov: k, .. } | SolverKind::Petsc { krylov: k, .. } => {
                Some(k)
            }
        }
    }

    /// Short label for reports, e.g. `lu` or `bicgstab+ilu0`.
    pub fn label(&self) -> String {
        match self {
            SolverKind::Lu => "lu".to_string(),
            SolverKind::Auto(Krylov { preconditioner, .. }) => format!("auto(lu|gmres+{})", preconditioner.label()),
            SolverKind::Gmres { krylov: Krylov { preconditioner, .. }, restart, .. } => {
                format!("gmres({restart})+{}", preconditioner.label())
            }
            SolverKind::Petsc { direct: true, .. } => "petsc:gmres+mumps-lu".to_string(),
            SolverKind::Petsc { krylov: Krylov { preconditioner, .. }, restart, .. } => {
                format!("petsc:gmres({restart})+{}", preconditioner.petsc_name().unwrap_or("?"))
            }
            SolverKind::Bicgstab(Krylov { preconditioner, .. }) => {
                format!("bicgstab+{}", preconditioner.label())
            }
        }
    }
}

choice! {
    /// The name of a solver in a scene (`solver.kind`); its settings are their own fields.
    pub enum SolverMethod("solver.kind", default Some(SolverMethod::Auto), note "\"auto\"; in [peridynamics.solver] \"gmres\" with \"amg\"") {
        Auto = "auto" => "LU while its estimated factors are at most 40 MB; above, GMRES with the preconditioner, tolerance and max_iterations given, LU if a restart cycle leaves more than 0.1 of the residual; GMRES alone (then BiCGSTAB+ILU(0)) once the factors would take more than half the available memory (the displacement-pressure form: LU while it fits, else GMRES(100), at least 2000 iterations); reason in summary.json, `solver.choice`",
        Lu = "lu" => "sparse direct LU (faer, COLAMD ordering): robust, memory grows fastest with the node count",
        Bicgstab = "bicgstab" => "right-preconditioned BiCGSTAB to a true relative residual `tolerance`",
        Gmres = "gmres" => "right-preconditioned restarted GMRES(`restart`, default 30) to a true relative residual `tolerance`; stops when a restart cycle gains less than 1 %",
        Petsc = "petsc" => "PETSc's KSP over the MPI ranks of `mpirun -n P` (build with `--features petsc`): GMRES(`restart`) with GAMG (amg, rigid-body modes), block-Jacobi ILU(0) (ilu0) or Jacobi to a true relative residual `tolerance`; PETSc options after `--` on the command line or in PETSC_OPTIONS override each",
    }
}

choice! {
    /// The name of a preconditioner in a scene (`solver.preconditioner`).
    pub enum PreconditionerKind("solver.preconditioner", default Some(PreconditionerKind::Amg), note "\"amg\" with gmres and auto, \"ilut\" with bicgstab") {
        Ilut = "ilut" => "Saad's dual-threshold ILUT(drop, fill), defaults drop = 1e-5, fill = 20",
        Ilu0 = "ilu0" => "zero-fill incomplete LU",
        Jacobi = "jacobi" => "the diagonal",
        Amg = "amg" => "smoothed-aggregation algebraic multigrid with the rigid-body modes (one V-cycle, block Gauss-Seidel smoothing); the default of gmres and auto",
    }
}

impl Preconditioner {
    /// PETSc's counterpart (`-pc_type`): `gamg`, `bjacobi` (ILU(0) in each block),
    /// `jacobi`; ILUT has none.
    pub fn petsc_name(&self) -> Option<&'static str> {
        match self {
            Preconditioner::Amg => Some("gamg"),
            Preconditioner::Ilu0 => Some("bjacobi"),
            Preconditioner::Jacobi => Some("jacobi"),
            Preconditioner::Ilut { .. } => None,
        }
    }

    /// Its name in a scene.
    pub fn kind(&self) -> PreconditionerKind {
        match self {
            Preconditioner::Ilut { .. } => PreconditionerKind::Ilut,
            Preconditioner::Ilu0 => PreconditionerKind::Ilu0,
            Preconditioner::Jacobi => PreconditionerKind::Jacobi,
            Preconditioner::Amg => PreconditionerKind::Amg,
        }
    }
}

/// Parameters of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverParams {
    /// Solver and its settings.
    pub kind: SolverKind,
    /// Divide each row of `A` and `b` by `max_j |a_ij|` before solving
    /// (see [`scaling`]).
    pub equilibrate: bool,
}

impl Default for SolverParams {
    /// What a scene gets without `[solver]`: `auto` with [`Krylov::default`], on the
    /// row-equilibrated system.
    fn default() -> Self {
        SolverParams { kind: SolverKind::Auto(Krylov::default()), equilibrate: true }
    }
}

impl SolverParams {
    /// Direct LU on the row-equilibrated system.
    pub fn lu() -> Self {
        SolverParams { kind: SolverKind::Lu, equilibrate: true }
    }
}
