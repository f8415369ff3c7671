//! The house: stage folders in one direction of flow, checked on the source itself.
//!
//! Every `crate::<module>` reference in `src/` must point at the same or a lower layer:
//!
//! ```text
//! 0 error, kinematics (and the re-exported Axis, AxisVec, Plane)
//! 1 input      plain configuration; imports no stage
//! 2 program    NC programs → canonical moves
//! 3 motion     moves → setpoints
//! 4 drive      setpoints → actual axis positions
//! 5 pipeline   the stages connected; the Sink trait
//! 6 measure    sink: the ball bar
//! 7 check      sinks: limits and collisions (uses measure's θ frame)
//! 8 report     files
//! 9 study      runs and studies beside the pipeline
//! 10 cli       the command line
//! ```
//!
//! A reference upwards is a module reaching back up the pipeline, or a cycle in the making.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("kinematics", 0),
    ("Axis", 0),
    ("AxisVec", 0),
    ("Plane", 0),
    ("Error", 0),
    ("Result", 0),
    ("input", 1),
    ("program", 2),
    ("motion", 3),
    ("drive", 4),
    ("pipeline", 5),
    ("measure", 6),
    ("check", 7),
    ("report", 8),
    ("study", 9),
    ("cli", 10),
];

fn layer(name: &str) -> Option<u32> {
    LAYERS.iter().find(|(n, _)| *n == name).map(|(_, l)| *l)
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

/// The top-level module a file of `src/` belongs to (`src/check/scene/monitor.rs` → check).
fn owner(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// Every `crate::name` in `text`, with `crate::{a, b::c}` groups expanded to their heads.
fn crate_references(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            names.extend(
                inner
                    .split(',')
                    .map(|s| s.trim().split("::").next().unwrap_or("").trim().to_string())
                    .filter(|s| !s.is_empty()),
            );
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            names.push(name);
        }
    }
    names
}

#[test]
fn every_module_refers_only_to_its_own_layer_or_below() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut upward = Vec::new();
    let mut edges: BTreeMap<(String, String), usize> = BTreeMap::new();
    for file in &files {
        let module = owner(&src, file);
        if module == "lib" || module == "main" {
            continue;
        }
        let from = layer(&module).unwrap_or_else(|| {
            panic!(
                "{}: module `{module}` has no layer in this test",
                file.display()
            )
        });
        // Code only: a comment that points the reader elsewhere is not a dependency.
        let text: String = std::fs::read_to_string(file)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .map(|l| format!("{l}\n"))
            .collect();
        for name in crate_references(&text) {
            let to = layer(&name).unwrap_or_else(|| {
                panic!("{}: `crate::{name}` is not a known module", file.display())
            });
            *edges.entry((module.clone(), name.clone())).or_default() += 1;
            if to > from {
                upward.push(format!("{} ({module}) -> crate::{name}", file.display()));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "references that reach up:\n{}",
        upward.join("\n")
    );
    // The graph is real: the pipeline's stages do refer to the ones below them.
    for (from, to) in [
        ("motion", "program"),
        ("drive", "input"),
        ("pipeline", "drive"),
        ("measure", "pipeline"),
        ("check", "pipeline"),
        ("report", "measure"),
        ("study", "pipeline"),
        ("cli", "study"),
    ] {
        assert!(
            edges.contains_key(&(from.to_string(), to.to_string())),
            "expected {from} to use {to}"
        );
    }
}

#[test]
fn the_reader_crate_depends_on_nothing_of_mtsim() {
    let manifest = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/Cargo.toml"),
    )
    .unwrap();
    let deps = manifest
        .split("[dependencies]")
        .nth(1)
        .unwrap_or("")
        .split("\n[")
        .next()
        .unwrap_or("");
    let names: Vec<&str> = deps
        .lines()
        .filter_map(|l| l.split('=').next())
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    assert_eq!(names, ["serde"], "ngc's dependencies: {names:?}");
    let mut files = Vec::new();
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/src"),
        &mut files,
    );
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(!text.contains("mtsim::"), "{} names mtsim", file.display());
    }
}
