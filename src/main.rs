//! `mlsm`: parse the command line, run, print the error chain, exit with its code
//! (0 success, 1 output or other failure, 2 invalid input, 3 solver failure).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = mlsm::cli::Cli::parse();
    match mlsm::app::run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
