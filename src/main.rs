//! `mlsm`: parse the command line, run, print the error chain, exit with its code
//! (0 success, 1 output or other failure, 2 invalid input, 3 solver failure).

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
    let cli = mlsm::cli::Cli::parse();
    match mlsm::app::run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
