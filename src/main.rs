//! The `meshtrace` binary: parses the command line, runs the command, and prints any error
//! once, on one line, with a non-zero exit.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    let result = match &args.command {
        cli::Command::Render(r) => cli::render(r),
        cli::Command::Info { scene } => cli::info(scene),
        cli::Command::Adapters => cli::adapters(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
