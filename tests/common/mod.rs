//! Running the `palpus` binary from chain tests, and finding the captures it generates.
// Each test binary uses some of these, none all of them.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `palpus ARGS` without a vendor library configured in the environment.
pub fn palpus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_palpus"))
        .args(args)
        .env_remove("PALPUS_DHD_LIBRARY")
        .output()
        .expect("the palpus binary runs")
}

/// `o`, which must be a success (else the test fails, showing what it printed).
pub fn success(o: Output) -> Output {
    assert!(o.status.success(), "{}", text(&o));
    o
}

/// Runs `palpus ARGS`, which must succeed.
pub fn succeeds(args: &[&str]) -> Output {
    success(palpus(args))
}

/// Runs `palpus ARGS`, which must succeed, and reads what it printed as JSON.
pub fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&succeeds(args).stdout).expect("json")
}

/// Runs `palpus ARGS`, which must fail; returns what it printed.
pub fn fails(args: &[&str]) -> String {
    let o = palpus(args);
    assert!(!o.status.success(), "{args:?} succeeded");
    text(&o)
}

/// Everything it printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The 21 rubbing captures (7 surfaces × 3 runs) that `palpus gen --only nakano` writes under
/// `dir`, sorted by name.
pub fn nakano_captures(dir: &Path) -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir.join("nakano"))
        .expect("nakano folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    assert_eq!(paths.len(), 21);
    paths
}
