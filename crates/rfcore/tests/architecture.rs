//! The house rules, checked: the core's rooms depend on each other one way only, and no bindings
//! file imports a sibling that imports it back. Reads `use crate::...` paths (and inline
//! `crate::room::` paths) from the sources, so a new file that crosses a line fails here first.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Every `.rs` file below `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(sources(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// The top-level module a source file belongs to (`src/flight/vehicle.rs` -> `flight`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// The top-level modules a file refers to through `crate::name` (comments excluded).
fn references(file: &Path) -> BTreeSet<String> {
    let text = fs::read_to_string(file).unwrap();
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// module -> the other top-level modules its files use.
fn graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in sources(src) {
        let module = module_of(src, &file);
        if module == "lib" {
            continue;
        }
        let refs = references(&file);
        let entry = g.entry(module.clone()).or_default();
        entry.extend(refs.into_iter().filter(|r| *r != module));
    }
    g
}

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn core_rooms_depend_one_way() {
    let g = graph(&manifest_dir().join("src"));
    // room -> what it may use; `error` and `airframe` are the shared vocabulary.
    let allowed: BTreeMap<&str, &[&str]> = BTreeMap::from([
        ("error", &[][..]),
        ("airframe", &["error"][..]),
        ("state", &["error"][..]),
        ("analysis", &["error", "airframe"][..]),
        ("allocation", &["error", "airframe", "analysis"][..]),
        ("control", &["error", "airframe", "state", "allocation"][..]),
        (
            "flight",
            &[
                "error",
                "airframe",
                "state",
                "control",
                "allocation",
                "analysis",
            ][..],
        ),
    ]);
    for (module, uses) in &g {
        if module == "fixtures" {
            continue;
        }
        let Some(ok) = allowed.get(module.as_str()) else {
            panic!("src/{module}: a new top-level module; give it a room and a rule here");
        };
        // Test and bench support is usable from every room's tests.
        for used in uses.iter().filter(|u| *u != "fixtures") {
            assert!(
                ok.contains(&used.as_str()),
                "src/{module} uses crate::{used}, which its room may not (allowed: {ok:?})"
            );
        }
    }
}

#[test]
fn bindings_have_no_import_circles() {
    let src = manifest_dir().join("../rfcore-py/src");
    let g = graph(&src);
    // Depth-first search for a cycle among the bindings' top-level modules.
    fn visit(
        node: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) {
        if let Some(i) = path.iter().position(|p| p == node) {
            panic!(
                "bindings import circle: {}",
                path[i..].join(" -> ") + " -> " + node
            );
        }
        if done.contains(node) {
            return;
        }
        path.push(node.to_string());
        for next in g.get(node).into_iter().flatten() {
            visit(next, g, path, done);
        }
        path.pop();
        done.insert(node.to_string());
    }
    let mut done = BTreeSet::new();
    for node in g.keys() {
        visit(node, &g, &mut Vec::new(), &mut done);
    }
}
