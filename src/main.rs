use std::process::ExitCode;

use clap::Parser;
use palpus::cli::{Cli, describe, run};
use palpus::exit::exit_code;

fn main() -> ExitCode {
    end_quietly_on_a_closed_pipe();
    // Parsed first: clap ends the process itself on `--help` and on bad arguments, which
    // would leave the directory behind.
    let cli = Cli::parse();
    // SAFETY: no other thread exists yet (clap parses on this one).
    let quiet = unsafe { render::QuietRuntimeDir::install() };
    let code = match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", describe(&error));
            ExitCode::from(exit_code(&error))
        }
    };
    drop(quiet);
    code
}

/// Output piped into a reader that stops early (`palpus gen … | head`) ends the process as it
/// ends other command-line tools, instead of a panic from the standard library's `println!` at
/// the first write to the closed pipe: Rust ignores SIGPIPE at start-up, so the write fails
/// with EPIPE and `println!` panics; the default action ends the process silently. Files are
/// written under temporary names and renamed when complete, so nothing half-written is left;
/// the quiet runtime directory of a process ended this way is removed by the next start.
fn end_quietly_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any other thread exists; restores the
    // default disposition of one signal, which has no handler of ours to race with.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
