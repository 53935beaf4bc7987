//! The layout's rules, checked on the source tree: crates import only the crates below them
//! (capture and svm at the bottom, the binary on top), and no two files of a crate import each
//! other, directly or around a longer circle.
//!
//! The file graph is read from `crate::…`, `super::…` and `self::…` paths outside test
//! modules; a path resolves to the file of its longest module prefix. A module declaring its
//! children (`mod x;`) or re-exporting them (`pub use x::…`) is not an import of the child, and
//! a path through the crate root (`crate::Name`) goes through the door, so neither makes a
//! circle.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each crate's folder and the palpus crates it may depend on.
const LAYERS: [(&str, &str, &[&str]); 9] = [
    ("capture", "capture", &[]),
    ("fft", "fft", &[]),
    ("svm", "svm", &[]),
    ("identify", "identify", &["capture", "svm"]),
    ("recognize", "recognize", &["capture", "fft", "svm"]),
    ("sim", "sim", &["capture", "fft", "recognize"]),
    (
        "haptics",
        "haptics",
        &["capture", "svm", "identify", "recognize", "sim"],
    ),
    ("render", "render", &["capture"]),
    (
        "palpus",
        ".",
        &[
            "capture",
            "fft",
            "svm",
            "identify",
            "recognize",
            "sim",
            "haptics",
            "render",
        ],
    ),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The palpus crates named in a manifest's `[dependencies]` (not dev- or build-dependencies).
fn palpus_dependencies(manifest: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let names: BTreeSet<&str> = LAYERS.iter().map(|(name, _, _)| *name).collect();
    let mut in_dependencies = false;
    let mut found = BTreeSet::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            in_dependencies = line == "[dependencies]";
            continue;
        }
        if !in_dependencies {
            continue;
        }
        let name = line.split(['.', '=', ' ']).next().unwrap_or_default();
        if names.contains(name) {
            found.insert(name.to_owned());
        }
    }
    found
}

#[test]
fn crates_import_only_the_layers_below_them() {
    for (name, folder, allowed) in LAYERS {
        let deps = palpus_dependencies(&root().join(folder).join("Cargo.toml"));
        let allowed: BTreeSet<String> = allowed.iter().map(|s| (*s).to_owned()).collect();
        let extra: Vec<&String> = deps.difference(&allowed).collect();
        assert!(extra.is_empty(), "{name} depends on {extra:?}, outside its layer");
    }
}

/// A source file's module path: `lib.rs` is the root, `a/mod.rs` and `a.rs` are `a`.
fn module_path(relative: &Path) -> Vec<String> {
    let mut parts: Vec<String> = relative
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(parts.last().map(String::as_str), Some("lib" | "main" | "mod")) {
        parts.pop();
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Splits `a, b::{c, d}, e` at its top-level commas.
fn top_level_items(inner: &str) -> Vec<&str> {
    let mut items = Vec::new();
    let (mut depth, mut start) = (0usize, 0usize);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => {
                items.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items.push(&inner[start..]);
    items
}

/// The module paths named by a use tree or path starting at `text` (after `crate::`).
fn paths_in(text: &str) -> Vec<Vec<String>> {
    let text = text.trim_start();
    if let Some(rest) = text.strip_prefix('{') {
        let mut depth = 1usize;
        let end = rest
            .char_indices()
            .find(|&(_, c)| {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    _ => {}
                }
                depth == 0
            })
            .map_or(rest.len(), |(i, _)| i);
        return top_level_items(&rest[..end])
            .into_iter()
            .flat_map(paths_in)
            .collect();
    }
    let mut segments = Vec::new();
    let mut rest = text;
    loop {
        let len = rest.find(|c: char| !is_ident(c)).unwrap_or(rest.len());
        if len == 0 {
            break;
        }
        segments.push(rest[..len].to_owned());
        rest = &rest[len..];
        match rest.strip_prefix("::") {
            Some(next) if next.starts_with('{') => {
                return paths_in(next)
                    .into_iter()
                    .map(|tail| segments.iter().cloned().chain(tail).collect())
                    .collect();
            }
            Some(next) => rest = next,
            None => break,
        }
    }
    vec![segments]
}

/// The files of one crate and the files each imports from.
fn file_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<Vec<String>, String> = files
        .iter()
        .map(|f| {
            let relative = f.strip_prefix(src).unwrap();
            (module_path(relative), relative.to_string_lossy().into_owned())
        })
        .collect();
    let mut graph = BTreeMap::new();
    for (here, name) in &modules {
        if name.ends_with("tests.rs") || name.contains("tests/") {
            continue;
        }
        let text = std::fs::read_to_string(src.join(name)).unwrap();
        let text = text.split("#[cfg(test)]").next().unwrap_or_default();
        let code: String = text
            .lines()
            .map(|line| line.split("//").next().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n");
        let mut targets = BTreeSet::new();
        for (at, _) in code.match_indices("::") {
            let before = &code[..at];
            let word_start = before.rfind(|c: char| !is_ident(c)).map_or(0, |i| i + 1);
            if before[..word_start].ends_with("::") {
                continue; // not the head of a path
            }
            let mut tail = &code[at + 2..];
            let base = match &before[word_start..] {
                "crate" => Vec::new(),
                "self" => here.clone(),
                "super" => {
                    let mut up = 1;
                    while let Some(rest) = tail.strip_prefix("super::") {
                        tail = rest;
                        up += 1;
                    }
                    here[..here.len().saturating_sub(up)].to_vec()
                }
                _ => continue,
            };
            for path in paths_in(tail) {
                let full: Vec<String> = base.iter().cloned().chain(path).collect();
                let target = (0..=full.len())
                    .rev()
                    .find_map(|k| modules.get(&full[..k]).map(|file| (k, file)));
                if let Some((k, file)) = target
                    && k > 0
                    && file != name
                {
                    targets.insert(file.clone());
                }
            }
        }
        graph.insert(name.clone(), targets);
    }
    graph
}

/// Strongly connected components of more than one file (Tarjan).
fn circles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        found: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        let graph = s.graph;
        for w in graph.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let low = s.low[v].min(s.low[w]);
                s.low.insert(v, low);
            } else if s.stack.contains(&w) {
                let low = s.low[v].min(s.index[w]);
                s.low.insert(v, low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                component.push(w.to_owned());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                s.found.push(component);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.found
}

/// Whether a `src/cli` module is a command (its subcommand's arguments and run), not an
/// argument module the commands share.
fn is_command(module: &str) -> bool {
    module.ends_with("_cmd") || module.starts_with("bench_")
}

#[test]
fn commands_are_thin_and_import_no_other_command() {
    let dir = root().join("src/cli");
    let mut found = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let Some(module) = path.file_stem().and_then(|s| s.to_str()).map(str::to_owned) else {
            continue;
        };
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let lines = text.lines().count();
        assert!(
            lines <= 300,
            "src/cli/{module}.rs has {lines} lines: its tables or loops belong outside the command"
        );
        if module == "mod" {
            continue;
        }
        for (at, _) in text.match_indices("super::") {
            let other: String = text[at + "super::".len()..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            assert!(
                !(is_command(&other) && other != module),
                "src/cli/{module}.rs imports the command `{other}`: share an argument module instead"
            );
        }
        found += usize::from(is_command(&module));
    }
    assert!(
        found >= 10,
        "only {found} command modules found in {}",
        dir.display()
    );
}

#[test]
fn no_two_files_import_each_other() {
    let mut all = Vec::new();
    for (name, folder, _) in LAYERS {
        for circle in circles(&file_graph(&root().join(folder).join("src"))) {
            all.push(format!("{name}: {}", circle.join(" <-> ")));
        }
    }
    assert!(all.is_empty(), "import circles:\n{}", all.join("\n"));
}

#[test]
fn the_circle_finder_sees_a_circle_and_a_grouped_import() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a; mod b;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "mod c;\nuse crate::{b::Thing, x};\n").unwrap();
    std::fs::write(src.join("a/c.rs"), "use super::super::b::Other;\n").unwrap();
    std::fs::write(
        src.join("b.rs"),
        "use crate::a::Item;\n#[cfg(test)]\nuse crate::a::c::T;\n",
    )
    .unwrap();
    let graph = file_graph(src);
    assert_eq!(graph["a/c.rs"], BTreeSet::from(["b.rs".to_owned()]));
    assert_eq!(graph["b.rs"], BTreeSet::from(["a/mod.rs".to_owned()]));
    let found = circles(&graph);
    assert_eq!(found.len(), 1, "{found:?}");
    let mut circle = found[0].clone();
    circle.sort();
    assert_eq!(circle, ["a/mod.rs", "b.rs"]);
}

/// The 1 kHz core (`haptics::rt`) is the bottom of the haptic side: it drives a device through
/// the safety filter and knows nothing of what runs on it (laws, controllers, the simulated
/// world, recording, acquisition protocols), which wire themselves to it from above.
#[test]
fn the_haptic_loop_imports_nothing_above_it() {
    let graph = file_graph(&root().join("haptics/src"));
    let above = ["control", "law", "sim", "recorder", "acquire", "bench"];
    let mut upward = Vec::new();
    for (file, targets) in graph.iter().filter(|(file, _)| file.starts_with("rt/")) {
        for target in targets {
            if above
                .iter()
                .any(|a| target.starts_with(&format!("{a}/")) || *target == format!("{a}.rs"))
            {
                upward.push(format!("{file} -> {target}"));
            }
        }
    }
    assert!(upward.is_empty(), "rt/ imports upward: {upward:?}");
}

/// The modules of each crate that other crates may name (`capture::kind::DEPTH_M`): a
/// namespace of its own (a paper's settings, a sample's channel layout, the loop's API), listed
/// here and in `docs/architecture.md`. Everything else is reached through the crate's root
/// (`capture::import_csv`, not `capture::import::import_csv`).
const NAMESPACES: [(&str, &str, &[&str]); 8] = [
    ("capture", "capture", &["json_file", "kind", "rng"]),
    ("fft", "fft", &[]),
    ("svm", "svm", &[]),
    ("identify", "identify", &[]),
    ("recognize", "recognize", &["nakano", "protocol", "spectral"]),
    ("sim", "sim", &["li_bi", "multistream", "nakano", "sinapov"]),
    (
        "haptics",
        "haptics",
        &[
            "acquire",
            "admittance_channel",
            "flag",
            "insertion_channel",
            "recognizer_channel",
            "rt",
            "rubbing_channel",
        ],
    ),
    (
        "render",
        "render",
        &["assets_gen", "bench", "golden", "shapes", "window"],
    ),
];

/// Every module name declared in the files under `src`.
fn module_names(src: &Path) -> BTreeSet<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut names = BTreeSet::new();
    for file in files {
        for line in std::fs::read_to_string(&file).unwrap().lines() {
            let line = line.trim_start();
            let line = line.strip_prefix("pub ").unwrap_or(line);
            if let Some(rest) = line.strip_prefix("mod ") {
                let name: String = rest.chars().take_while(|&c| is_ident(c)).collect();
                names.insert(name);
            }
        }
    }
    names
}

/// The paths, after the crate's name, by which `code` names the crate `krate`.
fn paths_into(code: &str, krate: &str) -> Vec<Vec<String>> {
    let head = format!("{krate}::");
    let mut paths = Vec::new();
    for (at, _) in code.match_indices(&head) {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| is_ident(c) || c == ':') {
            continue; // inside a longer name or path
        }
        paths.extend(paths_in(&code[at + head.len()..]));
    }
    paths
}

/// Where a path from outside goes past a crate's door: through a module that is not one of
/// its namespaces, or below a namespace into one of its modules. A segment is taken for a
/// module only where the path goes on after it: a function of the same name (`svm::fit`, with
/// a module `fit` inside) is an item at the door.
fn past_the_door(path: &[String], modules: &BTreeSet<String>, namespaces: &[&str]) -> bool {
    let Some((_, inner)) = path.split_last() else {
        return false;
    };
    match inner.split_first() {
        Some((first, below)) if namespaces.contains(&first.as_str()) => {
            below.iter().any(|s| modules.contains(s))
        }
        Some((first, _)) => modules.contains(first),
        None => false,
    }
}

/// Source files outside `exclude` (a crate's own `src`), skipping build output.
fn files_outside(exclude: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let root = root();
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if path.is_dir() && !name.starts_with('.') && name != "target" {
            rust_files(&path, &mut files);
        }
    }
    // This file's own examples of paths past a door are not uses.
    let this = root.join(file!());
    files.retain(|f| {
        !f.starts_with(exclude) && *f != this && !f.components().any(|c| c.as_os_str() == "target")
    });
    files
}

#[test]
fn other_crates_use_each_crate_through_its_door() {
    let mut past = Vec::new();
    for (name, folder, namespaces) in NAMESPACES {
        let src = root().join(folder).join("src");
        let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
        for line in lib.lines() {
            if let Some(rest) = line.strip_prefix("pub mod ") {
                let module = rest.trim_end_matches(';');
                assert!(
                    namespaces.contains(&module),
                    "{name}/src/lib.rs: `pub mod {module}` is not one of the crate's namespaces \
                     ({namespaces:?}): make it private and re-export what other crates use"
                );
            }
        }
        let modules = module_names(&src);
        for file in files_outside(&src) {
            let text = std::fs::read_to_string(&file).unwrap();
            let code: String = text
                .lines()
                .map(|line| line.split("//").next().unwrap_or_default())
                .collect::<Vec<_>>()
                .join("\n");
            for path in paths_into(&code, name) {
                if past_the_door(&path, &modules, namespaces) {
                    let relative = file.strip_prefix(root()).unwrap_or(&file);
                    past.push(format!("{}: {name}::{}", relative.display(), path.join("::")));
                }
            }
        }
    }
    past.sort();
    past.dedup();
    assert!(past.is_empty(), "paths past a crate's door:\n{}", past.join("\n"));
}

#[test]
fn the_door_check_sees_a_deep_path_a_grouped_one_and_a_namespace() {
    let modules: BTreeSet<String> = ["device", "sim_omega7", "rt", "pacer", "flag"]
        .map(str::to_owned)
        .into();
    let namespaces = ["rt", "flag"];
    let code = "use haptics::{HapticDevice, device::sim_omega7::SimWorld};\n\
                let x = haptics::rt::pacer::Pacer::new();\n\
                use haptics::rt::{self, spawn};\n\
                let f = haptics::flag::STALL;\n\
                use haptics::device;\n\
                let g = my_haptics::device::X;";
    let flagged: Vec<String> = paths_into(code, "haptics")
        .into_iter()
        .filter(|p| past_the_door(p, &modules, &namespaces))
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(flagged, ["device::sim_omega7::SimWorld", "rt::pacer::Pacer::new"]);
}
