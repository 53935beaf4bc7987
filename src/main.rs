use std::process::ExitCode;

use clap::Parser;
use palpus::cli::{Cli, run};

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // `{:#}` prints the whole chain: what we were doing, then why it failed.
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}
