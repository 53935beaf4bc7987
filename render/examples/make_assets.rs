//! Writes the procedurally generated meshes (liver, tissue block, needle, lumbar block, surface
//! tray) as `.glb` files into the directory given as the first argument (default
//! `assets/meshes`).
//!
//! `cargo run -p render --example make_assets -- assets/meshes`

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let dir = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("assets/meshes"), PathBuf::from);
    match render::write_default_assets(&dir) {
        Ok(paths) => {
            for path in paths {
                let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
                eprintln!("wrote {} ({size} bytes)", path.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
