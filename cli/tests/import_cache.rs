//! Imports that reuse work write what a plain import writes:
//! - the decomposition cache (`sdrs import --cache DIR`): an import that
//!   finds its decompositions in the cache writes the same bytes (scene, hull
//!   OBJs, report) as one that computes them, and a damaged entry is
//!   recomputed, never used;
//! - links in parallel: one thread and two write the same bytes (the spider's
//!   four identical legs share decompositions across threads).

use crate::support;

use std::path::{Path, PathBuf};
use support::{files_under, root, run_ok, scratch_dir, sdrs};

/// Imports the spider (four legs of mesh links) into `out_dir`, through
/// `cache` when given; the files written, by name.
fn import(out_dir: &Path, cache: Option<&Path>) -> Vec<(String, Vec<u8>)> {
    import_on(out_dir, cache, None)
}

/// [`import`] with `RAYON_NUM_THREADS` set to `threads` when given.
fn import_on(
    out_dir: &Path,
    cache: Option<&Path>,
    threads: Option<&str>,
) -> Vec<(String, Vec<u8>)> {
    std::fs::create_dir_all(out_dir).unwrap();
    let mut cmd = sdrs();
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t);
    }
    cmd.args(["import", "-q", "--ground", "--out"])
        .arg(out_dir.join("spider.yaml"))
        .arg("--report")
        .arg(out_dir.join("report.json"));
    if let Some(c) = cache {
        cmd.arg("--cache").arg(c);
    }
    run_ok(cmd.arg(root().join("robots/spider/spider.urdf")));
    files(out_dir)
}

/// Every file under `dir` (relative name, bytes), sorted; the report's
/// wall times (keys ending in `seconds`) are left out.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    files_under(dir, |_| true)
        .into_iter()
        .map(|p| {
            let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(&p).unwrap();
            if name == "report.json" {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                strip_seconds(&mut v);
                bytes = serde_json::to_vec(&v).unwrap();
            }
            (name, bytes)
        })
        .collect()
}

fn strip_seconds(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !k.ends_with("seconds"));
            m.values_mut().for_each(strip_seconds);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_seconds),
        _ => {}
    }
}

fn entries(cache: &Path) -> Vec<PathBuf> {
    let mut e: Vec<PathBuf> = std::fs::read_dir(cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    e.sort();
    e
}

#[test]
fn a_cached_import_writes_the_same_files_as_a_new_one() {
    let dir = scratch_dir("import-cache");
    let cache = dir.join("cache");
    let plain = import(&dir.join("plain"), None);
    let first = import(&dir.join("first"), Some(&cache));
    let stored = entries(&cache);
    assert!(!stored.is_empty(), "no cache entry was written");
    assert!(
        stored
            .iter()
            .all(|p| p.extension().is_some_and(|x| x == "hulls")),
        "{stored:?}"
    );
    let second = import(&dir.join("second"), Some(&cache));
    assert_eq!(entries(&cache), stored, "a hit must not add entries");
    assert!(
        plain.len() >= 3,
        "{:?}",
        plain.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for (name, run) in [
        ("first (cache misses)", &first),
        ("second (cache hits)", &second),
    ] {
        assert_eq!(
            run.iter().map(|f| &f.0).collect::<Vec<_>>(),
            plain.iter().map(|f| &f.0).collect::<Vec<_>>(),
            "{name}: other files"
        );
        for ((n, a), (_, b)) in run.iter().zip(&plain) {
            assert!(
                a == b,
                "{name}: {n} differs from the import without a cache"
            );
        }
    }
    // A damaged entry is a miss: recomputed, rewritten, same output.
    let victim = &stored[0];
    let good = std::fs::read(victim).unwrap();
    std::fs::write(victim, &good[..good.len() / 2]).unwrap();
    let third = import(&dir.join("third"), Some(&cache));
    assert!(third == plain, "an import over a damaged entry differs");
    assert_eq!(
        std::fs::read(victim).unwrap(),
        good,
        "the damaged entry was not rewritten"
    );
}

#[test]
fn a_cache_path_that_is_a_file_is_a_clear_error() {
    let dir = scratch_dir("import-cache-file");
    let not_dir = dir.join("cache");
    std::fs::write(&not_dir, b"user data").unwrap();
    let out = sdrs()
        .args(["import", "-q", "--out"])
        .arg(dir.join("x.yaml"))
        .arg("--cache")
        .arg(&not_dir)
        .arg(root().join("robots/spider/spider.urdf"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(&*not_dir.to_string_lossy()) && err.contains("cache directory"),
        "{err}"
    );
    assert_eq!(std::fs::read(&not_dir).unwrap(), b"user data");
}

#[test]
fn an_import_on_one_thread_writes_the_same_files_as_on_two() {
    let dir = scratch_dir("import-threads");
    let one = import_on(&dir.join("one"), None, Some("1"));
    let two = import_on(&dir.join("two"), None, Some("2"));
    assert!(one.len() >= 3);
    assert_eq!(
        one.iter().map(|f| &f.0).collect::<Vec<_>>(),
        two.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((n, a), (_, b)) in one.iter().zip(&two) {
        assert!(a == b, "{n} differs between 1 and 2 threads");
    }
}
