//! `mlsm`: parse the command line, run, print the error chain, exit with its code
//! (0 success, 1 output or other failure, 2 invalid input, 3 solver failure, 4 warnings
//! under `--strict`, 130 interrupted).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Blocks from 128 kB up are always mapped, and unmapped when freed. glibc raises
    // this threshold to the size of the first mapped block that is freed (up to 32 MB),
    // after which freed vectors of a few MB stay in its heaps: 0.07 GB of the peak at
    // 1e6 nodes (BENCHMARKS.md); the multigrid keeps its cycle's vectors, so the solve
    // does not map and fault in fresh pages at every iteration.
    // A thread's heap gives its top back to the system only when more than 2 MB of it
    // is free: at glibc's 128 kB the small buffers of every RBF-FD stencil (tens of kB
    // at degree 8) were returned and faulted in again node after node (page faults,
    // zeroing and TLB shootdowns were 10-15 % of a Kirsch run); the balanced preset on
    // Kirsch took 2.42 s instead of 3.75-3.79, the 1e6-node cantilever's peak stayed at
    // 1.93 GB (1.89-1.93 before; BENCHMARKS.md, "Allocator trimming").
    // M_MMAP_MAX is glibc's default, set again because a library may have changed it
    // (and the trim threshold) before `main`: with the `petsc` feature, SuperLU_DIST's load-time constructor
    // (linked in by PETSc) sets M_MMAP_MAX = 0 and M_TRIM_THRESHOLD = -1, so that freed
    // memory never went back to the system: the cantilever at 1e6 nodes in one process
    // peaked at 2.31-2.40 GB with the feature against 1.96 GB without, and rank 0 of a
    // two-rank run still held 2.36 GB when it started writing its output.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: sets malloc parameters before any thread starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
        libc::mallopt(libc::M_MMAP_MAX, 65536);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 2 * 1024 * 1024);
    }
    // Piping into `head` closes stdout early: end quietly like other command-line
    // tools instead of panicking in println! (Rust ignores SIGPIPE by default).
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Ctrl-C: a time loop stops between steps and its staged results are removed
    // (exit 130); anywhere else the process removes its staged results and ends at once.
    let _ = ctrlc::set_handler(|| {
        if !mlsm::pipeline::interrupt::request() {
            mlsm::output::remove_uncommitted();
            std::process::exit(130);
        }
    });
    let cli = mlsm::cli::Cli::parse_from(mlsm::cli::joined_negative_values(std::env::args_os()));
    let code = match mlsm::app::run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    };
    // Every rank of an MPI run ends PETSc (and MPI) before it exits, after printing:
    // MPI_Finalize waits for all ranks, so no rank's non-zero exit makes mpirun kill
    // rank 0 before its message is out.
    mlsm::petsc::finish();
    code
}
