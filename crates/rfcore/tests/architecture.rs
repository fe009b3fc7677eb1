//! The house rules, checked from the sources:
//!
//! - the core's rooms depend on each other one way only ([`core_rooms_depend_one_way`]);
//! - no file of the core or of the bindings imports, directly or through others, a file that
//!   imports it back: no import circle between modules, inside a room or across rooms
//!   ([`no_import_circles_between_files`]), and none between the bindings' top-level modules;
//! - no source file is longer than [`LINE_BUDGET`] lines ([`files_fit_the_line_budget`]).
//!
//! The graph is built per file from `use` statements and inline paths (`crate::`, `super::`,
//! `self::`, or a child module's name), comments and literals excluded. A name imported through a
//! re-export (`pub use` in a `mod.rs`, e.g. `crate::allocation::Certificate`) counts as an
//! import of the file that defines it, and a re-export is not itself an import: a `mod.rs` that
//! only declares and re-exports its children is a facade, not a node of a circle. So a new file
//! that crosses a line fails here first.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Most lines a source file may have (tests included): enough to read in one sitting. The two
/// files issue 26 split were 1,640 and 1,440 lines; the longest left is about 970.
const LINE_BUDGET: usize = 1000;

/// Every `.rs` file below `dir`, as (path relative to `dir` with `/`, text), sorted.
fn sources(dir: &Path) -> Vec<(String, String)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
        for entry in fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(root).unwrap().to_string_lossy();
                out.push((rel.replace('\\', "/"), fs::read_to_string(&path).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// ---- reading the sources --------------------------------------------------------------------

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
}

/// The tokens of Rust source with comments, string and character literals removed (lifetimes
/// kept as identifiers). Enough to follow paths and braces, not a full lexer.
fn tokens(text: &str) -> Vec<Token> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let ident_char = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied().unwrap_or('\0');
        if ch == '/' && next == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && next == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if (ch == 'r' || (ch == 'b' && next == 'r'))
            && (i == 0 || !ident_char(c[i - 1]))
            && {
                let mut j = i + if ch == 'b' { 2 } else { 1 };
                while c.get(j) == Some(&'#') {
                    j += 1;
                }
                c.get(j) == Some(&'"')
            }
        {
            // Raw string: r"...", r#"..."#, br"...".
            let mut j = i + if ch == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while c[j] == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            while j < c.len() {
                if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
        } else if ch == '\'' {
            if next == '\\' {
                // Escaped character literal.
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3; // 'x'
            } else {
                i += 1; // a lifetime: the identifier follows
            }
        } else if ident_char(ch) {
            let start = i;
            while i < c.len() && ident_char(c[i]) {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            if word == "b" && i < c.len() && (c[i] == '"' || c[i] == '\'') {
                continue; // byte literal prefix: the literal is skipped next
            }
            out.push(Token::Ident(word));
        } else if ch == ':' && next == ':' {
            out.push(Token::Path);
            i += 2;
        } else {
            if !ch.is_whitespace() {
                out.push(Token::Punct(ch));
            }
            i += 1;
        }
    }
    out
}

/// One path a `use` tree names: its segments (possibly ending in `*`) and the name it binds.
#[derive(Debug, Clone, PartialEq)]
struct UsePath {
    segments: Vec<String>,
    binds: Option<String>,
}

/// Parses the use tree starting at `t[*i]` (after `use`), appending its leaf paths to `out`.
fn use_tree(t: &[Token], i: &mut usize, prefix: &[String], out: &mut Vec<UsePath>) {
    let mut segments = prefix.to_vec();
    if t.get(*i) == Some(&Token::Path) {
        *i += 1; // a leading `::`: an external crate
    }
    loop {
        match t.get(*i) {
            Some(Token::Punct('{')) => {
                *i += 1;
                while t.get(*i) != Some(&Token::Punct('}')) && *i < t.len() {
                    use_tree(t, i, &segments, out);
                    if t.get(*i) == Some(&Token::Punct(',')) {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            Some(Token::Punct('*')) => {
                *i += 1;
                segments.push("*".into());
                out.push(UsePath {
                    segments,
                    binds: None,
                });
                return;
            }
            Some(Token::Ident(word)) => {
                *i += 1;
                if word == "self" && !segments.is_empty() && segments.len() == prefix.len() {
                    // `a::{self, ...}`: `a` itself.
                } else {
                    segments.push(word.clone());
                }
                if t.get(*i) == Some(&Token::Path) {
                    *i += 1;
                    continue;
                }
                let mut binds = segments.last().cloned();
                if t.get(*i) == Some(&Token::Ident("as".into())) {
                    if let Some(Token::Ident(alias)) = t.get(*i + 1) {
                        binds = Some(alias.clone());
                    }
                    *i += 2;
                }
                out.push(UsePath { segments, binds });
                return;
            }
            _ => return,
        }
    }
}

/// What one file says about modules: where it sits, which paths it uses (with the module each
/// is written in, for `super`/`self`), and which names it re-exports.
#[derive(Debug, Default)]
struct FileInfo {
    /// The file's module path (`allocation/active_set.rs` -> `[allocation, active_set]`).
    module: Vec<String>,
    /// (module the path is written in, path as written).
    uses: Vec<(Vec<String>, Vec<String>)>,
    /// (module written in, re-exported path, name it binds).
    reexports: Vec<(Vec<String>, Vec<String>, Option<String>)>,
}

fn module_of(rel: &str) -> Vec<String> {
    let stem = rel.trim_end_matches(".rs");
    let mut parts: Vec<String> = stem.split('/').map(String::from).collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

fn read_file(rel: &str, text: &str) -> FileInfo {
    let module = module_of(rel);
    let t = tokens(text);
    let mut info = FileInfo {
        module: module.clone(),
        ..Default::default()
    };
    // Inline modules (`mod tests { ... }`): (name, brace depth inside it).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0;
    let current = |inline: &[(String, usize)]| -> Vec<String> {
        let mut m = module.clone();
        m.extend(inline.iter().map(|(n, _)| n.clone()));
        m
    };
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Token::Punct('{') => {
                depth += 1;
                i += 1;
            }
            Token::Punct('}') => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth -= 1;
                i += 1;
            }
            Token::Ident(w) if w == "mod" => {
                if let (Some(Token::Ident(name)), Some(Token::Punct('{'))) =
                    (t.get(i + 1), t.get(i + 2))
                {
                    depth += 1;
                    inline.push((name.clone(), depth));
                    i += 3;
                } else {
                    i += 1;
                }
            }
            Token::Ident(w) if w == "use" => {
                // `pub use` / `pub(crate) use` / `pub(super) use`: a re-export.
                let public = (i >= 1 && t[i - 1] == Token::Ident("pub".into()))
                    || (i >= 4
                        && t[i - 1] == Token::Punct(')')
                        && t[i - 4] == Token::Ident("pub".into()));
                i += 1;
                let mut paths = Vec::new();
                use_tree(&t, &mut i, &[], &mut paths);
                let here = current(&inline);
                for p in paths {
                    if public {
                        info.reexports.push((here.clone(), p.segments, p.binds));
                    } else {
                        info.uses.push((here.clone(), p.segments));
                    }
                }
            }
            Token::Ident(w)
                if t.get(i + 1) == Some(&Token::Path) && (i == 0 || t[i - 1] != Token::Path) =>
            {
                // An inline path `a::b::c` (not inside a longer one).
                let mut segments = vec![w.clone()];
                let mut j = i + 1;
                while t.get(j) == Some(&Token::Path) {
                    match t.get(j + 1) {
                        Some(Token::Ident(s)) => {
                            segments.push(s.clone());
                            j += 2;
                        }
                        _ => break,
                    }
                }
                info.uses.push((current(&inline), segments));
                i = j;
            }
            _ => i += 1,
        }
    }
    info
}

// ---- the module graph -----------------------------------------------------------------------

/// One crate's files as nodes (named by module path, `a/b`; the root is `lib`) and the imports
/// between them.
struct Graph {
    /// module path -> node name
    files: BTreeMap<Vec<String>, String>,
    /// node -> name -> the path it re-exports
    reexports: BTreeMap<String, BTreeMap<String, Vec<String>>>,
    /// node -> nodes it imports (itself excluded)
    edges: BTreeMap<String, BTreeSet<String>>,
}

fn node_name(module: &[String]) -> String {
    if module.is_empty() {
        "lib".into()
    } else {
        module.join("/")
    }
}

impl Graph {
    fn new(sources: &[(String, String)]) -> Self {
        let infos: Vec<FileInfo> = sources.iter().map(|(p, t)| read_file(p, t)).collect();
        let files: BTreeMap<Vec<String>, String> = infos
            .iter()
            .map(|f| (f.module.clone(), node_name(&f.module)))
            .collect();
        let mut graph = Graph {
            files,
            reexports: BTreeMap::new(),
            edges: BTreeMap::new(),
        };
        for info in &infos {
            let node = node_name(&info.module);
            for (here, path, binds) in &info.reexports {
                if let (Some(abs), Some(name)) = (graph.absolute(here, path), binds) {
                    graph
                        .reexports
                        .entry(node.clone())
                        .or_default()
                        .insert(name.clone(), abs);
                }
            }
        }
        for info in &infos {
            let node = node_name(&info.module);
            let mut targets = BTreeSet::new();
            for (here, path) in &info.uses {
                if let Some(target) = graph
                    .absolute(here, path)
                    .and_then(|abs| graph.resolve(&abs, 0))
                {
                    targets.insert(target);
                }
            }
            targets.remove(&node);
            graph.edges.insert(node, targets);
        }
        graph
    }

    /// `path` written in module `here` as a path from the crate root; `None` when it leaves the
    /// crate (an external crate, `std`, a type's associated item).
    fn absolute(&self, here: &[String], path: &[String]) -> Option<Vec<String>> {
        let (first, rest) = path.split_first()?;
        let mut base: Vec<String> = match first.as_str() {
            "crate" => Vec::new(),
            "self" => here.to_vec(),
            "super" => {
                let mut b = here.to_vec();
                b.pop()?;
                let mut rest = rest;
                while rest.first().map(String::as_str) == Some("super") {
                    b.pop()?;
                    rest = &rest[1..];
                }
                b.extend(rest.iter().cloned());
                return Some(b);
            }
            // A child module of the file the path is written in.
            name => {
                let mut child = self.file_module(here);
                child.push(name.to_string());
                if !self.files.contains_key(&child) {
                    return None;
                }
                child
            }
        };
        base.extend(rest.iter().cloned());
        Some(base)
    }

    /// The file module containing module `m` (inline modules belong to their file).
    fn file_module(&self, m: &[String]) -> Vec<String> {
        (0..=m.len())
            .rev()
            .map(|k| m[..k].to_vec())
            .find(|p| self.files.contains_key(p))
            .unwrap_or_default()
    }

    /// The file that defines what the absolute path names, following re-exports.
    fn resolve(&self, abs: &[String], hops: usize) -> Option<String> {
        let mut k = 0;
        while k < abs.len() && self.files.contains_key(&abs[..=k]) {
            k += 1;
        }
        let node = self.files.get(&abs[..k])?.clone();
        if let Some(name) = abs.get(k) {
            if let Some(target) = self.reexports.get(&node).and_then(|r| r.get(name)) {
                if hops < 8 {
                    let mut next = target.clone();
                    next.extend(abs[k + 1..].iter().cloned());
                    return self.resolve(&next, hops + 1).or(Some(node));
                }
            }
        }
        Some(node)
    }

    /// Every import circle (each once, as a path `a -> b -> a`); the crate root (`lib`), which
    /// declares and registers everything, is left out.
    fn circles(&self) -> Vec<String> {
        fn visit(
            node: &str,
            g: &Graph,
            path: &mut Vec<String>,
            done: &mut BTreeSet<String>,
            found: &mut Vec<String>,
        ) {
            if let Some(i) = path.iter().position(|p| p == node) {
                found.push(path[i..].join(" -> ") + " -> " + node);
                return;
            }
            if done.contains(node) || node == "lib" {
                return;
            }
            path.push(node.to_string());
            for next in g.edges.get(node).into_iter().flatten() {
                visit(next, g, path, done, found);
            }
            path.pop();
            done.insert(node.to_string());
        }
        let mut done = BTreeSet::new();
        let mut found = Vec::new();
        for node in self.edges.keys() {
            visit(node, self, &mut Vec::new(), &mut done, &mut found);
        }
        found
    }

    /// The graph between top-level modules (`flight/simulation/step` -> `flight`).
    fn rooms(&self) -> BTreeMap<String, BTreeSet<String>> {
        let room = |n: &str| n.split('/').next().unwrap_or(n).to_string();
        let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (node, targets) in &self.edges {
            let from = room(node);
            let entry = out.entry(from.clone()).or_default();
            entry.extend(targets.iter().map(|t| room(t)).filter(|t| *t != from));
        }
        out
    }
}

fn core() -> Graph {
    Graph::new(&sources(&manifest_dir().join("src")))
}

fn bindings() -> Graph {
    Graph::new(&sources(&manifest_dir().join("../rfcore-py/src")))
}

// ---- the rules ------------------------------------------------------------------------------

#[test]
fn core_rooms_depend_one_way() {
    let g = core().rooms();
    // room -> what it may use; `error`, `cancel` and `airframe` are the shared vocabulary.
    let allowed: BTreeMap<&str, &[&str]> = BTreeMap::from([
        ("error", &[][..]),
        ("cancel", &["error"][..]),
        ("airframe", &["error"][..]),
        ("state", &["error"][..]),
        ("analysis", &["error", "cancel", "airframe"][..]),
        (
            "allocation",
            &["error", "cancel", "airframe", "analysis"][..],
        ),
        (
            "control",
            &["error", "cancel", "airframe", "state", "allocation"][..],
        ),
        (
            "flight",
            &[
                "error",
                "cancel",
                "airframe",
                "state",
                "control",
                "allocation",
                "analysis",
            ][..],
        ),
    ]);
    for (module, uses) in &g {
        if module == "fixtures" || module == "lib" {
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
fn no_import_circles_between_files() {
    for (name, graph) in [("core", core()), ("bindings", bindings())] {
        let circles = graph.circles();
        assert!(
            circles.is_empty(),
            "{name}: import circles between files (a file imports one that imports it back; \
             move what both need into a third file): {circles:#?}"
        );
    }
}

#[test]
fn bindings_have_no_import_circles_between_rooms() {
    let rooms = bindings().rooms();
    let mut g = Graph {
        files: BTreeMap::new(),
        reexports: BTreeMap::new(),
        edges: rooms,
    };
    g.edges.remove("lib");
    let circles = g.circles();
    assert!(circles.is_empty(), "bindings import circle: {circles:?}");
}

#[test]
fn files_fit_the_line_budget() {
    let mut long = Vec::new();
    for (dir, label) in [("src", "rfcore/src"), ("../rfcore-py/src", "rfcore-py/src")] {
        for (path, text) in sources(&manifest_dir().join(dir)) {
            let lines = text.lines().count();
            if lines > LINE_BUDGET {
                long.push(format!("{label}/{path}: {lines} lines"));
            }
        }
    }
    assert!(
        long.is_empty(),
        "files over the budget of {LINE_BUDGET} lines (split them by concept): {long:?}"
    );
}

// ---- the checker checked: each rule fails on a tree that breaks it ----------------------------

fn tree(files: &[(&str, &str)]) -> Graph {
    let owned: Vec<(String, String)> = files
        .iter()
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect();
    Graph::new(&owned)
}

#[test]
fn a_circle_inside_a_room_is_found() {
    let g = tree(&[
        ("lib.rs", "pub mod room;"),
        ("room/mod.rs", "pub mod a;\npub mod b;\npub use a::A;"),
        ("room/a.rs", "use crate::room::b::B;\npub struct A;"),
        // Through a re-export and a multi-line group: still `b -> a`.
        (
            "room/b.rs",
            "use crate::room::{\n    A, // the facade\n};\npub struct B;",
        ),
    ]);
    assert_eq!(g.circles(), ["room/a -> room/b -> room/a"]);
    // The same with `super::` and an inline path in an expression.
    let g = tree(&[
        ("lib.rs", "pub mod room;"),
        ("room/mod.rs", "pub mod a;\npub mod b;"),
        ("room/a.rs", "fn f() { super::b::g(); }"),
        ("room/b.rs", "pub fn g() { let _ = crate::room::a::f; }"),
    ]);
    assert_eq!(g.circles(), ["room/a -> room/b -> room/a"]);
}

#[test]
fn facades_tests_comments_and_literals_make_no_circle() {
    let g = tree(&[
        ("lib.rs", "pub mod room;\npub use room::Shared;"),
        // mod.rs defines a shared item and re-exports its children's.
        (
            "room/mod.rs",
            "pub mod a;\npub mod b;\npub use a::A;\npub use b::B;\npub struct Shared;",
        ),
        (
            "room/a.rs",
            "use crate::room::Shared;\nuse crate::Shared as S;\npub struct A;\n\
             #[cfg(test)]\nmod tests {\n    use super::*;\n    fn t() { let _ = super::A; }\n}",
        ),
        (
            "room/b.rs",
            "use crate::room::A;\n// use crate::room::b::B;\n\
             const X: &str = \"crate::room::b\";\nconst Y: char = '{';\npub struct B;",
        ),
    ]);
    assert!(g.circles().is_empty(), "{:?}", g.circles());
    assert_eq!(g.edges["room/b"], BTreeSet::from(["room/a".to_string()]));
    assert_eq!(g.edges["room/a"], BTreeSet::from(["room".to_string()]));
    // ...but a facade's own code that uses a child which uses the facade is a circle.
    let g = tree(&[
        ("lib.rs", "pub mod room;"),
        (
            "room/mod.rs",
            "pub mod a;\npub trait Shared {}\nfn f() { a::g(); }",
        ),
        ("room/a.rs", "use crate::room::Shared;\npub fn g() {}"),
    ]);
    assert_eq!(g.circles(), ["room -> room/a -> room"]);
}

#[test]
fn nested_rooms_resolve_to_files() {
    let g = tree(&[
        ("lib.rs", "pub mod flight;"),
        ("flight/mod.rs", "pub mod simulation;\npub mod actuator;"),
        ("flight/actuator.rs", "pub struct Lag;"),
        (
            "flight/simulation/mod.rs",
            "pub mod step;\npub mod driver;\npub use driver::simulate;",
        ),
        (
            "flight/simulation/step.rs",
            "use crate::flight::actuator::Lag;",
        ),
        (
            "flight/simulation/driver.rs",
            "use crate::flight::simulation::step::{self, *};\npub fn simulate() {}",
        ),
    ]);
    assert_eq!(
        g.edges["flight/simulation/driver"],
        BTreeSet::from(["flight/simulation/step".to_string()])
    );
    assert_eq!(
        g.rooms()["flight"],
        BTreeSet::new(),
        "inside one room, no room-level edge"
    );
}
