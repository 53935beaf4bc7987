//! README leads with the two commands that do everything, and CI runs its test command; README
//! stays a short page, and its links and those of the pages under docs/ lead somewhere.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::fs;
use std::path::PathBuf;

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

#[test]
fn readme_is_a_page_of_at_most_300_lines() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(
        lines <= 300,
        "README.md has {lines} lines; move the detail into docs/"
    );
}

#[test]
fn every_relative_link_resolves_and_readme_links_every_docs_page() {
    let readme_path = root().join("README.md");
    let mut pages = vec![readme_path.clone()];
    let mut docs: Vec<PathBuf> = fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "md"))
        .collect();
    docs.sort();
    assert!(!docs.is_empty(), "no docs/*.md");
    pages.extend(docs.iter().cloned());

    let mut broken = Vec::new();
    let mut linked_from_readme = Vec::new();
    for page in &pages {
        let text = fs::read_to_string(page).unwrap();
        let dir = page.parent().unwrap();
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let path = target.split('#').next().unwrap();
            if path.is_empty() {
                continue; // An anchor in the same page.
            }
            let resolved = dir.join(path);
            if !resolved.exists() {
                broken.push(format!("{}: ({target})", page.display()));
            } else if page == &readme_path {
                linked_from_readme.push(resolved.canonicalize().unwrap());
            }
        }
    }
    assert!(broken.is_empty(), "links to nothing: {broken:#?}");

    let unlinked: Vec<_> = docs
        .iter()
        .filter(|doc| !linked_from_readme.contains(&doc.canonicalize().unwrap()))
        .collect();
    assert!(
        unlinked.is_empty(),
        "docs pages README.md does not link: {unlinked:?}"
    );
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The targets of the Markdown links `[text](target)` in `text`, outside code blocks and code
/// spans (where `[i](x)` is code, not a link). A code span may run over a line break, so spans
/// are found per paragraph.
fn link_targets(text: &str) -> Vec<String> {
    let mut prose = String::new();
    let mut in_block = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            prose.push('\n');
            continue;
        }
        if !in_block {
            prose.push_str(line);
        }
        prose.push('\n');
    }
    let mut targets = Vec::new();
    for paragraph in prose.split("\n\n") {
        // Every odd piece between backticks is code.
        for piece in paragraph.split('`').step_by(2) {
            let mut rest = piece;
            while let Some(at) = rest.find("](") {
                let after = &rest[at + 2..];
                let Some(end) = after.find(')') else { break };
                // `[text](target "title")`: the target is the first word.
                if let Some(target) = after[..end].split_whitespace().next() {
                    targets.push(target.to_owned());
                }
                rest = &after[end + 1..];
            }
        }
    }
    targets
}
