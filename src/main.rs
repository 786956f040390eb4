//! `mlsm`: parse the command line, run, print the error chain, exit with its code
//! (0 success, 1 output or other failure, 2 invalid input, 3 solver failure, 4 warnings
//! under `--strict`, 130 interrupted).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Blocks from 128 kB up are always mapped and unmapped when freed: glibc would
    // otherwise raise this threshold and keep freed vectors of a few MB in its heaps
    // at the peak (docs/notebook/round2-target-error.md, "no retained heap").
    // A thread's heap gives its top back only when more than 2 MB of it is free: at
    // 128 kB the buffers of every RBF-FD stencil were returned and faulted in again
    // node after node (docs/notebook/2026-11-27-allocator-trimming.md).
    // M_MMAP_MAX is glibc's default, set again because a library may change both before
    // `main`: SuperLU_DIST (linked in by PETSc) sets M_MMAP_MAX = 0 and M_TRIM_THRESHOLD
    // = -1, and freed memory never went back to the system
    // (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "Freed memory returned").
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
    // Ctrl-C, SIGTERM (a job scheduler's stop) and SIGHUP: a time loop stops between
    // steps and its staged results are removed (exit 130); anywhere else the process
    // removes its staged results and ends at once (exit 130). Either way the message
    // names the signal.
    #[cfg(unix)]
    let _ = mlsm::stages::interrupt::on_signals(|signal| {
        if !mlsm::stages::interrupt::request(signal) {
            mlsm::output::remove_uncommitted();
            let name = mlsm::stages::interrupt::name(signal);
            eprintln!("error: interrupted by {name}; the partial results were removed, earlier results are untouched");
            std::process::exit(130);
        }
    });
    let cli = mlsm::app::cli::Cli::parse_from(mlsm::app::cli::joined_negative_values(std::env::args_os()));
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
    mlsm::parallel::petsc::finish();
    code
}
