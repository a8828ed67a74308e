//! `ariadne`: the command-line entry point.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = ariadne_dlo::cli::Cli::parse();
    match ariadne_dlo::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
