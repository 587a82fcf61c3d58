//! Every integration-test file runs. The packages' integration tests are one
//! binary each (`tests/integration.rs`, every file a module; `autotests =
//! false` in the manifests, notes/ci-time.md), so a file that is neither a
//! module of it nor a `[[test]]` target of its own would compile into nothing
//! and never fail. This test names such a file, and a module line whose file
//! is gone is a compile error already.

use crate::common::{root, scratch_dir};
use std::path::Path;

/// The top-level `.rs` files of `dir` without their extension, sorted.
fn test_file_stems(dir: &Path) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .filter(|s| s != "integration")
        .collect();
    stems.sort();
    stems
}

/// Files of `package`'s `tests/` that neither `tests/integration.rs` declares
/// as a module (`mod NAME;`) nor the manifest names as a target
/// (`path = "tests/NAME.rs"`).
fn orphans(package: &Path) -> Vec<String> {
    let read =
        |p: &Path| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let integration = read(&package.join("tests/integration.rs"));
    let manifest = read(&package.join("Cargo.toml"));
    assert!(
        manifest.contains("autotests = false"),
        "{}: autotests",
        package.display()
    );
    test_file_stems(&package.join("tests"))
        .into_iter()
        .filter(|s| {
            let module = integration.lines().any(|l| l.trim() == format!("mod {s};"));
            let target = manifest.contains(&format!("path = \"tests/{s}.rs\""));
            !module && !target
        })
        .collect()
}

/// The workspace's packages with Rust integration tests (`.rs` files in
/// `tests/`; the Python package's `tests/` is pytest's): the root and the
/// `members` of its manifest.
fn packages_with_tests() -> Vec<std::path::PathBuf> {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let members = manifest
        .lines()
        .find_map(|l| l.strip_prefix("members = "))
        .expect("Cargo.toml: no `members = [...]` line");
    let names = members.trim_matches(|c| c == '[' || c == ']');
    std::iter::once(root().to_path_buf())
        .chain(
            names
                .split(',')
                .map(|m| root().join(m.trim().trim_matches('"'))),
        )
        .filter(|d| d.join("tests").is_dir() && !test_file_stems(&d.join("tests")).is_empty())
        .collect()
}

#[test]
fn every_test_file_is_a_module_of_the_integration_binary_or_a_target() {
    let packages = packages_with_tests();
    assert!(
        packages.len() > 1,
        "no workspace member with tests: {packages:?}"
    );
    for dir in packages {
        let lost = orphans(&dir);
        assert!(
            lost.is_empty(),
            "{}/tests: files that would never run: {lost:?}",
            dir.display()
        );
    }
}

#[test]
fn a_file_left_out_is_found() {
    let dir = scratch_dir("test-targets");
    std::fs::create_dir_all(dir.join("tests")).unwrap();
    std::fs::write(
        dir.join("Cargo.toml"),
        "autotests = false\n[[test]]\npath = \"tests/alone.rs\"\n",
    )
    .unwrap();
    for f in ["kept", "lost", "alone"] {
        std::fs::write(dir.join(format!("tests/{f}.rs")), "").unwrap();
    }
    std::fs::write(
        dir.join("tests/integration.rs"),
        "mod kept;\n// mod lost;\n",
    )
    .unwrap();
    let lost = orphans(&dir);
    assert_eq!(lost, vec!["lost".to_string()]);
}
