//! PETSc and MPI, behind the cargo feature `petsc`: start and end, the rank and size
//! of the world, two collectives (sum, gather) and one KSP solve of a distributed
//! square system.
//!
//! Why our own FFI: the Rust bindings `petsc-rs`/`petsc-sys` target PETSc 3.15-3.16
//! and need bindgen and libclang; they have not been released since 2021, and Debian
//! ships PETSc 3.18. The C side (`shim.c`, compiled by `build.rs` against the
//! `PETSc` pkg-config entry) takes and returns plain C types only, so no MPI or
//! PETSc type, and none of their ABI differences between MPI builds, reaches Rust.
//! All `unsafe` of the backend is in this module.
//!
//! Without the feature the same functions describe a world of one rank, and
//! [`solve`] reports that the backend is absent.

use std::sync::OnceLock;

/// Whether this build has the PETSc backend.
pub const AVAILABLE: bool = cfg!(feature = "petsc");

/// This process's place among the MPI ranks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct World {
    /// Rank of this process, `0..size`.
    pub rank: usize,
    /// Number of ranks.
    pub size: usize,
}

impl World {
    /// One process.
    pub const SERIAL: World = World { rank: 0, size: 1 };
}

/// The world once PETSc is started (or [`World::SERIAL`] if it never was).
static STARTED: OnceLock<Result<World, String>> = OnceLock::new();

/// The number of ranks `mpirun`/`mpiexec` started this process among, from the
/// environment of Open MPI, MPICH or Slurm (1 when none says).
pub fn launched_ranks() -> usize {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"]
        .iter()
        .find_map(|v| std::env::var(v).ok().and_then(|s| s.parse::<usize>().ok()))
        .unwrap_or(1)
}

/// Start PETSc (and MPI) once, with `options` in PETSc's own syntax
/// (`-ksp_type gmres -pc_type gamg`, as given after `--` on the command line; the
/// environment variable `PETSC_OPTIONS` is read by PETSc itself). Later calls return
/// the world of the first.
pub fn start(options: &[String]) -> Result<World, String> {
    STARTED.get_or_init(|| ffi::initialize(options)).clone()
}

/// The world: [`World::SERIAL`] until [`start`] succeeded.
pub fn world() -> World {
    match STARTED.get() {
        Some(Ok(w)) => *w,
        _ => World::SERIAL,
    }
}

/// End PETSc if [`start`] started it (call once, at the end of `main`).
pub fn finish() {
    if let Some(Ok(_)) = STARTED.get() {
        ffi::finalize();
    }
}

/// `data[k] <- sum over ranks of data[k]` (nothing to do on one rank).
pub fn sum_over_ranks(data: &mut [f64]) -> Result<(), String> {
    if world().size == 1 {
        return Ok(());
    }
    ffi::sum(data)
}

/// Every rank's `local` concatenated in rank order; `counts[r]` is the length of
/// rank `r`'s part.
pub fn gather_all(local: &[f64], counts: &[usize]) -> Result<Vec<f64>, String> {
    if world().size == 1 {
        return Ok(local.to_vec());
    }
    ffi::gather(local, counts)
}

/// This rank's rows of a square system `A x = b` distributed by contiguous row blocks:
/// rows `first .. first + rhs.len()` of the global numbering, in compressed sparse
/// rows with global, sorted column indices.
pub struct LocalRows<'a> {
    /// Rows of the whole system.
    pub global_rows: usize,
    /// `rhs.len() + 1` offsets into `cols` and `vals`.
    pub row_ptr: &'a [i64],
    /// Global columns, sorted within each row.
    pub cols: &'a [i64],
    /// Values.
    pub vals: &'a [f64],
    /// Right-hand side of the local rows.
    pub rhs: &'a [f64],
    /// Unknowns per point (the matrix block size).
    pub block_size: usize,
    /// Positions of the local points (one per `block_size` rows), for the rigid-body
    /// near-null space of PETSc's algebraic multigrid (`None`: none given).
    pub coords: Option<&'a [[f64; 2]]>,
}

/// The defaults of a KSP solve; PETSc's options database overrides each of them.
pub struct KspDefaults<'a> {
    /// Krylov method, e.g. `gmres`.
    pub ksp_type: &'a str,
    /// Preconditioner, e.g. `gamg`.
    pub pc_type: &'a str,
    /// Factorisation package of `pc_type = "lu"`, e.g. `mumps` (empty: PETSc's choice).
    pub factor_package: &'a str,
    /// Relative tolerance of the true residual.
    pub rtol: f64,
    /// Iteration limit.
    pub max_it: usize,
    /// GMRES restart.
    pub restart: usize,
}

/// What a KSP solve did, with the settings in force after the options database.
#[derive(Debug, Clone)]
pub struct KspOutcome {
    /// This rank's part of the solution.
    pub x: Vec<f64>,
    /// Krylov iterations.
    pub iterations: usize,
    /// PETSc's `KSPConvergedReason` (positive: converged, negative: diverged).
    pub reason: i64,
    /// Its name, e.g. `CONVERGED_RTOL` or `DIVERGED_ITS`.
    pub reason_name: String,
    /// The Krylov method used.
    pub ksp_type: String,
    /// The preconditioner used.
    pub pc_type: String,
    /// The relative tolerance used.
    pub rtol: f64,
    /// The iteration limit used.
    pub max_it: usize,
    /// Matrix, preconditioner and KSP set-up, seconds.
    pub setup_seconds: f64,
    /// `KSPSolve`, seconds.
    pub solve_seconds: f64,
}

/// Solve the distributed system with PETSc's KSP (collective: every rank calls it
/// with its own rows).
/// Starts PETSc without options if nothing started it yet.
pub fn solve(rows: &LocalRows, defaults: &KspDefaults) -> Result<KspOutcome, String> {
    start(&[])?;
    ffi::solve(rows, defaults)
}

/// Whether any rank reports `failed` (collective; on one rank, `failed` itself). MPI
/// aborts the job itself when a collective fails (its default error handler), so a
/// failed sum cannot return here.
pub fn any_rank(failed: bool) -> bool {
    let mut flag = [if failed { 1.0 } else { 0.0 }];
    match sum_over_ranks(&mut flag) {
        Ok(()) => flag[0] > 0.0,
        Err(_) => true,
    }
}

#[cfg(feature = "petsc")]
mod ffi {
    use super::{KspDefaults, KspOutcome, LocalRows, World};
    use std::ffi::{c_char, c_int, CStr, CString};

    #[repr(C)]
    struct System {
        global_rows: i64,
        local_rows: i64,
        row_ptr: *const i64,
        cols: *const i64,
        vals: *const f64,
        rhs: *const f64,
        block_size: i64,
        coords: *const f64,
        rtol: f64,
        max_it: i64,
        restart: i64,
        ksp_type: *const c_char,
        pc_type: *const c_char,
        factor_package: *const c_char,
    }

    #[repr(C)]
    struct Outcome {
        iterations: i64,
        reason: i64,
        rtol: f64,
        max_it: i64,
        setup_seconds: f64,
        solve_seconds: f64,
        reason_name: [c_char; 64],
        ksp_type: [c_char; 32],
        pc_type: [c_char; 32],
    }

    extern "C" {
        fn mlsm_petsc_initialize(argc: c_int, argv: *mut *mut c_char) -> c_int;
        fn mlsm_petsc_finalize() -> c_int;
        fn mlsm_petsc_world(rank: *mut c_int, size: *mut c_int) -> c_int;
        fn mlsm_petsc_sum(data: *mut f64, n: i64) -> c_int;
        fn mlsm_petsc_gather(local: *const f64, counts: *const i64, all: *mut f64) -> c_int;
        fn mlsm_petsc_solve(s: *const System, x: *mut f64, out: *mut Outcome) -> c_int;
    }

    fn text(chars: &[c_char]) -> String {
        // SAFETY: the shim writes NUL-terminated strings (PetscStrncpy) into these arrays.
        unsafe { CStr::from_ptr(chars.as_ptr()) }.to_string_lossy().into_owned()
    }

    pub(super) fn initialize(options: &[String]) -> Result<World, String> {
        let mut args = vec![CString::new("mlsm").expect("no NUL")];
        for o in options {
            args.push(CString::new(o.as_str()).map_err(|_| format!("PETSc option {o:?} holds a NUL byte"))?);
        }
        let argc = args.len() as c_int;
        // PETSc keeps argv for the life of the program: leak it on purpose. MPI reads
        // it up to the null pointer that ends it, as C's argv.
        let mut raw: Vec<*mut c_char> = args.into_iter().map(CString::into_raw).collect();
        raw.push(std::ptr::null_mut());
        let argv: &'static mut [*mut c_char] = Vec::leak(raw);
        // SAFETY: argv holds argc valid NUL-terminated strings, then a null pointer; never freed.
        let code = unsafe { mlsm_petsc_initialize(argc, argv.as_mut_ptr()) };
        if code != 0 {
            return Err(format!("PetscInitialize failed with error code {code}"));
        }
        let (mut rank, mut size) = (0, 0);
        // SAFETY: two out-parameters.
        let code = unsafe { mlsm_petsc_world(&mut rank, &mut size) };
        if code != 0 {
            return Err(format!("MPI_Comm_rank/size failed with error code {code}"));
        }
        Ok(World { rank: rank as usize, size: size as usize })
    }

    pub(super) fn finalize() {
        // SAFETY: called once, after every other PETSc call.
        unsafe { mlsm_petsc_finalize() };
    }

    pub(super) fn sum(data: &mut [f64]) -> Result<(), String> {
        // SAFETY: data.len() doubles, summed in place.
        match unsafe { mlsm_petsc_sum(data.as_mut_ptr(), data.len() as i64) } {
            0 => Ok(()),
            c => Err(format!("MPI_Allreduce failed with error code {c}")),
        }
    }

    pub(super) fn gather(local: &[f64], counts: &[usize]) -> Result<Vec<f64>, String> {
        let counts: Vec<i64> = counts.iter().map(|&c| c as i64).collect();
        let mut all = vec![0.0; counts.iter().sum::<i64>() as usize];
        // SAFETY: `all` holds the sum of the counts; `local` this rank's count.
        match unsafe { mlsm_petsc_gather(local.as_ptr(), counts.as_ptr(), all.as_mut_ptr()) } {
            0 => Ok(all),
            c => Err(format!("MPI_Allgatherv failed with error code {c}")),
        }
    }

    pub(super) fn solve(rows: &LocalRows, d: &KspDefaults) -> Result<KspOutcome, String> {
        let n = rows.rhs.len();
        assert_eq!(rows.row_ptr.len(), n + 1, "row offsets of the local rows");
        let ksp_type = CString::new(d.ksp_type).map_err(|e| e.to_string())?;
        let pc_type = CString::new(d.pc_type).map_err(|e| e.to_string())?;
        let factor_package = CString::new(d.factor_package).map_err(|e| e.to_string())?;
        let coords: Option<Vec<f64>> = rows.coords.map(|c| c.iter().flatten().copied().collect());
        let system = System {
            global_rows: rows.global_rows as i64,
            local_rows: n as i64,
            row_ptr: rows.row_ptr.as_ptr(),
            cols: rows.cols.as_ptr(),
            vals: rows.vals.as_ptr(),
            rhs: rows.rhs.as_ptr(),
            block_size: rows.block_size as i64,
            coords: coords.as_ref().map_or(std::ptr::null(), |c| c.as_ptr()),
            rtol: d.rtol,
            max_it: d.max_it as i64,
            restart: d.restart as i64,
            ksp_type: ksp_type.as_ptr(),
            pc_type: pc_type.as_ptr(),
            factor_package: factor_package.as_ptr(),
        };
        let mut x = vec![0.0; n];
        let mut out = Outcome {
            iterations: 0,
            reason: 0,
            rtol: 0.0,
            max_it: 0,
            setup_seconds: 0.0,
            solve_seconds: 0.0,
            reason_name: [0; 64],
            ksp_type: [0; 32],
            pc_type: [0; 32],
        };
        // SAFETY: every pointer of `system` points into a live slice of the stated length.
        let code = unsafe { mlsm_petsc_solve(&system, x.as_mut_ptr(), &mut out) };
        if code != 0 {
            return Err(format!("PETSc error code {code} in the KSP solve (PETSc printed its trace above)"));
        }
        Ok(KspOutcome {
            x,
            iterations: out.iterations as usize,
            reason: out.reason,
            reason_name: text(&out.reason_name),
            ksp_type: text(&out.ksp_type),
            pc_type: text(&out.pc_type),
            rtol: out.rtol,
            max_it: out.max_it as usize,
            setup_seconds: out.setup_seconds,
            solve_seconds: out.solve_seconds,
        })
    }
}

#[cfg(not(feature = "petsc"))]
mod ffi {
    use super::{KspDefaults, KspOutcome, LocalRows, World};

    /// The message of every entry point of a build without the backend.
    const ABSENT: &str = "this mlsm was built without PETSc; build it with `cargo build --release --features petsc` \
                          after `scripts/install-petsc.sh` (docs/guide/petsc-mpi.md)";

    pub(super) fn initialize(_options: &[String]) -> Result<World, String> {
        Err(ABSENT.into())
    }
    pub(super) fn finalize() {}
    pub(super) fn sum(_data: &mut [f64]) -> Result<(), String> {
        Err(ABSENT.into())
    }
    pub(super) fn gather(_local: &[f64], _counts: &[usize]) -> Result<Vec<f64>, String> {
        Err(ABSENT.into())
    }
    pub(super) fn solve(_rows: &LocalRows, _d: &KspDefaults) -> Result<KspOutcome, String> {
        Err(ABSENT.into())
    }
}
