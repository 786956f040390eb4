//! `mlsm`: parse the command line, run, print the error chain, exit with its code
//! (0 success, 1 output or other failure, 2 invalid input, 3 solver failure, 4 warnings
//! under `--strict`, 130 interrupted).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
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
