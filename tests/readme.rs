//! README leads with the two commands that do everything, and CI runs its test command.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::fs;

fn commands_in_readme() -> Vec<String> {
    let readme = fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let mut commands = Vec::new();
    let mut in_block = false;
    for line in readme.lines() {
        if line.starts_with("```") {
            in_block = line == "```sh";
            continue;
        }
        if in_block {
            commands.push(line.trim().to_owned());
        }
    }
    commands
}

#[test]
fn readme_leads_with_the_main_job_and_the_tests() {
    let commands = commands_in_readme();
    assert!(commands.len() >= 2, "{commands:?}");
    // The main job is the default scene.
    assert_eq!(commands[0], "cargo run --release -- run");
    assert!(commands[1].starts_with("cargo test"), "{}", commands[1]);
}

#[test]
fn ci_runs_exactly_the_readme_test_command() {
    let test_command = commands_in_readme().remove(1);
    let ci = fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/.ci/run")).unwrap();
    assert!(
        ci.lines().any(|l| l.trim() == test_command),
        "`{test_command}` not in .ci/run"
    );
    assert!(ci.contains("set -euo pipefail"));
}
