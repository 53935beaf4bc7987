//! Prints the headless render benchmark table (`palpus bench render` shows the same).
//!
//! `cargo run -p render --example bench_render -- [frames]`

use std::io::Write;
use std::process::ExitCode;

use render::bench::{BenchOptions, run};

fn main() -> ExitCode {
    // SAFETY: first thing in `main`, before any other thread exists.
    let _quiet = unsafe { render::QuietRuntimeDir::install() };
    let mut options = BenchOptions::default();
    if let Some(frames) = std::env::args().nth(1).and_then(|a| a.parse().ok()) {
        options.frames = frames;
    }
    match run(&options) {
        Ok(table) => {
            let _ = write!(std::io::stdout().lock(), "{}", table.to_text());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
