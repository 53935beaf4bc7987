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

/// One trial of the logs that `palpus gen --only multistream` writes under `dir`: its surface
/// (`mat07`), trial number (from 1) and its four files, in the order force, position,
/// velocity, vibration.
pub struct MultistreamTrial {
    /// Surface as the file names give it: `mat07`.
    pub surface: String,
    /// Trial number as the file names give it, from 1.
    pub trial: u32,
    /// `…_force.csv`, `…_position.csv`, `…_velocity.csv`, `…_vibration.csv`.
    pub files: [PathBuf; 4],
}

/// Every trial of the multistream logs under `dir`, sorted by surface then trial, found as a
/// user's shell loop would find them: by the `matNN_trialTT_force.csv` files.
pub fn multistream_trials(dir: &Path) -> Vec<MultistreamTrial> {
    let folder = dir.join("multistream");
    let mut trials: Vec<MultistreamTrial> = std::fs::read_dir(&folder)
        .expect("multistream folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter_map(|name| {
            let stem = name.strip_suffix("_force.csv")?.to_owned();
            let (surface, trial) = stem.split_once("_trial")?;
            Some(MultistreamTrial {
                surface: surface.to_owned(),
                trial: trial.parse().expect("trial number"),
                files: ["force", "position", "velocity", "vibration"]
                    .map(|stream| folder.join(format!("{stem}_{stream}.csv"))),
            })
        })
        .collect();
    trials.sort_by(|a, b| (&a.surface, a.trial).cmp(&(&b.surface, b.trial)));
    trials
}
