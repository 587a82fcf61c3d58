//! The core crate's layering (docs/architecture.md): every top-level module
//! of `src/` may use only modules of a lower layer. Edges are read from the
//! source text as `crate::module` paths (plain and grouped `crate::{a, b}`),
//! with comments and `#[cfg(test)]` unit-test modules left out: a test may
//! reach anywhere, the library may not.
//!
//! Modules of one layer may not use each other either, so an order with no
//! back-edge is also free of cycles.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The declared order, lowest first; modules on one line share a layer.
const LAYERS: &[&[&str]] = &[
    &["math", "files", "progress"],
    &["counters"],
    &["model"],
    &["control"],
    &["geometry"],
    &["kinematics"],
    &["contact"],
    &["energy"],
    &["sim"],
    &["diff"],
    &["scene"],
    &["optimize", "calibrate"],
    &["import"],
    &["output"],
];

/// Back-edges that exist today and are being removed (issue 34). The test
/// fails when one of them disappears without being deleted here, so the
/// list can only shrink.
const KNOWN_BACK_EDGES: &[(&str, &str)] = &[];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// Source text without line comments and without everything from the
/// first `#[cfg(test)]` unit-test module on (they come last by convention).
fn library_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            let next = lines.peek().map(|l| l.trim()).unwrap_or("");
            if next.starts_with("mod ") && next.ends_with(';') {
                lines.next(); // a test module in its own file: see `test_files`
                continue;
            }
            if next.starts_with("mod ") || t.contains(" mod ") {
                break;
            }
        }
        let code = match line.find("//") {
            Some(i) => &line[..i],
            None => line,
        };
        out.push_str(code);
        out.push('\n');
    }
    out
}

fn ident_at(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The top-level modules that `text` names through `crate::`.
fn used_modules(text: &str) -> BTreeSet<String> {
    let mut used = BTreeSet::new();
    let mut rest = text;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let id = ident_at(item.trim_start());
                if !id.is_empty() {
                    used.insert(id.to_string());
                }
            }
        } else {
            used.insert(ident_at(rest).to_string());
        }
    }
    used
}

/// Paths of the files that are `#[cfg(test)] mod name;` declarations
/// (`dir/name.rs` next to the declaring file).
fn test_files(files: &[(String, String)]) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (path, text) in files {
        let dir = match path.rfind('/') {
            Some(i) => &path[..=i],
            None => "",
        };
        let mut lines = text.lines().map(str::trim);
        while let Some(line) = lines.next() {
            if line.starts_with("#[cfg(test)]")
                && let Some(name) = lines
                    .next()
                    .and_then(|l| l.strip_prefix("mod "))
                    .and_then(|l| l.strip_suffix(';'))
            {
                out.insert(format!("{dir}{name}.rs"));
            }
        }
    }
    out
}

/// Edges `module → used module` between top-level modules of the tree
/// given as `(path relative to src/, text)` pairs.
fn edges(files: &[(String, String)]) -> BTreeMap<(String, String), String> {
    let tests = test_files(files);
    let modules: BTreeSet<String> = files
        .iter()
        .map(|(p, _)| top_module(p))
        .filter(|m| m != "lib")
        .collect();
    let mut out = BTreeMap::new();
    for (path, text) in files {
        let from = top_module(path);
        if from == "lib" || tests.contains(path) {
            continue;
        }
        for to in used_modules(&library_text(text)) {
            if to != from && modules.contains(&to) {
                out.entry((from.clone(), to))
                    .or_insert_with(|| path.clone());
            }
        }
    }
    out
}

fn top_module(rel: &str) -> String {
    let first = rel.split('/').next().unwrap_or(rel);
    first.strip_suffix(".rs").unwrap_or(first).to_string()
}

/// Every edge that does not go to a strictly lower layer, with the file
/// that makes it; modules missing from `LAYERS` are reported too.
fn violations(files: &[(String, String)]) -> Vec<String> {
    let mut bad = Vec::new();
    for ((from, to), file) in edges(files) {
        match (layer_of(&from), layer_of(&to)) {
            (Some(a), Some(b)) if b < a => {}
            (Some(_), Some(_)) => bad.push(format!("{from} -> {to} ({file})")),
            _ => bad.push(format!("{from} -> {to}: module not in LAYERS ({file})")),
        }
    }
    bad
}

fn read_tree(dir: &Path, base: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            read_tree(&p, base, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let rel = p
                .strip_prefix(base)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            out.push((rel, std::fs::read_to_string(&p).unwrap()));
        }
    }
}

#[test]
fn core_modules_use_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&src, &src, &mut files);
    let found = violations(&files);
    let known: BTreeSet<String> = KNOWN_BACK_EDGES
        .iter()
        .map(|(a, b)| format!("{a} -> {b}"))
        .collect();
    let new: Vec<&String> = found
        .iter()
        .filter(|v| !known.iter().any(|k| v.starts_with(&format!("{k} ("))))
        .collect();
    assert!(
        new.is_empty(),
        "new back-edges in the core's layering (docs/architecture.md): {new:#?}"
    );
    let gone: Vec<&String> = known
        .iter()
        .filter(|k| !found.iter().any(|v| v.starts_with(&format!("{k} ("))))
        .collect();
    assert!(
        gone.is_empty(),
        "these known back-edges are gone: delete them from KNOWN_BACK_EDGES: {gone:?}"
    );
}

#[test]
fn a_planted_back_edge_is_reported() {
    let tree = |extra: &str| {
        vec![
            ("math/mod.rs".to_string(), "pub fn f() {}".to_string()),
            (
                "model/mod.rs".to_string(),
                format!("use crate::math::f;\n{extra}"),
            ),
            (
                "sim.rs".to_string(),
                "use crate::{math::f, model};\n// crate::output in a comment\n".to_string(),
            ),
        ]
    };
    assert!(violations(&tree("")).is_empty());
    // A use of a higher layer, plain or grouped, is reported with its file.
    let v = violations(&tree("use crate::sim::step;"));
    assert_eq!(v, vec!["model -> sim (model/mod.rs)".to_string()]);
    let v = violations(&tree("use crate::{sim::step, math};"));
    assert_eq!(v, vec!["model -> sim (model/mod.rs)".to_string()]);
    // A unit-test module may reach anywhere, inline or in its own file.
    assert!(violations(&tree("#[cfg(test)]\nmod tests { use crate::sim; }")).is_empty());
    let mut t = tree("#[cfg(test)]\nmod model_tests;\npub fn g() {}");
    t.push(("model/model_tests.rs".into(), "use crate::sim;".into()));
    assert!(violations(&t).is_empty());
    t[1].1.push_str("\nuse crate::sim;");
    assert_eq!(
        violations(&t),
        vec!["model -> sim (model/mod.rs)".to_string()]
    );
}

/// Every file under `tools/`, as paths relative to it (`check/check_glb.py`),
/// less `README.md`, Python's caches and hidden files.
fn tool_files(dir: &Path, rel: &str, out: &mut Vec<String>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || name == "__pycache__" || name.ends_with(".pyc") {
            continue;
        }
        let path = format!("{rel}{name}");
        if e.file_type().unwrap().is_dir() {
            tool_files(&e.path(), &format!("{path}/"), out);
        } else if path != "README.md" {
            out.push(path);
        }
    }
}

/// The scripts `tools/README.md` lists, by folder: a section `## `…`/` …`
/// lists that folder's scripts (`` `name`` opening a table row or a line);
/// the text before the first section lists those of `tools/` itself.
fn listed_tools(index: &str) -> BTreeSet<String> {
    let mut listed = BTreeSet::new();
    let mut folder = String::new();
    for line in index.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            folder = heading
                .split('`')
                .nth(1)
                .filter(|f| f.ends_with('/'))
                .unwrap_or("?/")
                .to_string();
            continue;
        }
        // A table row's first cell, or a line (or list item) of text.
        let first = line.strip_prefix('|').unwrap_or(line).trim_start();
        let first = first.strip_prefix("- ").unwrap_or(first);
        if let Some(name) = first
            .strip_prefix('`')
            .and_then(|c| c.split(['`', ' ']).next())
        {
            listed.insert(format!("{folder}{name}"));
        }
    }
    listed
}

/// The files under `tools/` that `tools/README.md` does not list in their
/// folder's section.
fn unlisted_tools(tools: &Path) -> Vec<String> {
    let index = std::fs::read_to_string(tools.join("README.md")).unwrap();
    let listed = listed_tools(&index);
    let mut files = Vec::new();
    tool_files(tools, "", &mut files);
    files.sort();
    files.retain(|f| !listed.contains(f));
    files
}

/// Issue 34, item 7: every script under `tools/` (sorted into folders by
/// kind) has its line in its folder's section of `tools/README.md` (a script
/// added without one, or put in another folder than its line says, fails
/// here), and the README stays a user's page (≤ 12 KB; results live in
/// `docs/`).
#[test]
fn every_tool_is_listed_and_the_readme_is_short() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let missing = unlisted_tools(&root.join("tools"));
    assert!(
        missing.is_empty(),
        "tools/README.md has no line for {missing:?} in their folders' sections"
    );
    let readme = std::fs::metadata(root.join("README.md")).unwrap().len();
    assert!(readme <= 12 * 1024, "README.md is {readme} bytes");
}

/// The listing check itself: in a copy of `tools/README.md` beside planted
/// files, a script in a folder's section is found only in that folder.
#[test]
fn the_tool_listing_check_sees_unlisted_and_misplaced_scripts() {
    let dir = std::env::temp_dir().join(format!("sdrs-layers-tools-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("check")).unwrap();
    std::fs::create_dir_all(dir.join("bench/__pycache__")).unwrap();
    std::fs::write(
        dir.join("README.md"),
        "# tools/\n\n`test.sh` runs it all.\n\n## Checks (`check/`)\n\n| script | what |\n|---|---|\n| `a.py X` | a |\n\n## Benchmarks (`bench/`)\n\n| `b.sh` | b |\n",
    )
    .unwrap();
    for f in [
        "test.sh",
        "check/a.py",
        "bench/b.sh",
        "bench/__pycache__/x.pyc",
    ] {
        std::fs::write(dir.join(f), "").unwrap();
    }
    assert!(unlisted_tools(&dir).is_empty());
    for f in ["check/new.py", "check/b.sh", "loose.sh"] {
        std::fs::write(dir.join(f), "").unwrap();
    }
    assert_eq!(
        unlisted_tools(&dir),
        ["check/b.sh", "check/new.py", "loose.sh"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
