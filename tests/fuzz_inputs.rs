//! Property-based fuzzing of every input reader: scene YAML, URDF and meshes
//! (OBJ, STL, COLLADA). Each case mutates a file of the corpus (bundled scenes and
//! robots) — numbers replaced by extremes (NaN, ±∞, ±1e308, 2^63, 0, −1),
//! lines deleted or duplicated, bytes flipped, the file truncated — and
//! feeds it to the reader exactly as the CLI does. The property: the reader
//! returns (a value or an error) without panicking, and within
//! [`CASE_LIMIT`]. A scene that loads is also simulated for two steps when
//! it is small.
//!
//! CI runs [`ci_cases`] cases per reader (about a minute in all); the long
//! run is `SDRS_FUZZ_CASES=100000 cargo test --release --test fuzz_inputs`
//! (`tools/bench/fuzz.sh`). Failing inputs are saved under
//! `target/fuzz-failures/` and proptest shrinks them.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use sdrs::import::{Decomposer, ImportOptions, import};
use sdrs::scene::Scene;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Longest time one input may take (a hang is a failure).
const CASE_LIMIT: Duration = Duration::from_secs(60);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `round` (one proptest run of [`ci_cases`] cases, freshly seeded)
/// once, or — when `SDRS_FUZZ_SECONDS` is set — again and again until that
/// many seconds have passed; prints how many cases ran.
fn rounds(kind: &str, mut round: impl FnMut()) {
    let budget = std::env::var("SDRS_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<u64>().ok());
    let t0 = Instant::now();
    let mut n = 0u64;
    loop {
        round();
        n += 1;
        if budget.is_none_or(|b| t0.elapsed().as_secs() >= b) {
            break;
        }
    }
    eprintln!(
        "fuzz {kind}: {} cases in {:.0} s, no panic, no hang",
        n * ci_cases() as u64,
        t0.elapsed().as_secs_f64()
    );
}

/// Cases per reader: `SDRS_FUZZ_CASES`, default 150.
fn ci_cases() -> u32 {
    std::env::var("SDRS_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(150)
}

const EXTREMES: &[&str] = &[
    "nan",
    "NaN",
    ".nan",
    "inf",
    "-inf",
    ".inf",
    "1e308",
    "-1e308",
    "1e-308",
    "9223372036854775808",
    "18446744073709551616",
    "0",
    "-0",
    "-1",
    "1e6",
    "",
    "x",
];

/// One mutation of a text file.
#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the `k`-th numeric token by `EXTREMES[e]`.
    Number(usize, usize),
    DeleteLine(usize),
    DuplicateLine(usize),
    /// XOR byte `k` with `x`.
    Flip(usize, u8),
    /// Keep the first `k` bytes (mod length).
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..EXTREMES.len()).prop_map(|(k, e)| Mutation::Number(k, e)),
        1 => any::<usize>().prop_map(Mutation::DeleteLine),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        1 => (any::<usize>(), 1u8..=255).prop_map(|(k, x)| Mutation::Flip(k, x)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn is_number_char(c: u8) -> bool {
    c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// Byte ranges of numeric tokens.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if text[i].is_ascii_digit() && (i == 0 || !text[i - 1].is_ascii_alphanumeric()) {
            let mut s = i;
            if s > 0 && text[s - 1] == b'-' {
                s -= 1;
            }
            let mut e = i;
            while e < text.len() && is_number_char(text[e]) {
                e += 1;
            }
            out.push((s, e));
            i = e;
        } else {
            i += 1;
        }
    }
    out
}

fn apply(text: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut t = text.to_vec();
    for m in muts {
        if t.is_empty() {
            break;
        }
        match m {
            Mutation::Number(k, e) => {
                let nums = numbers(&t);
                if let Some(&(s, end)) = nums.get(k % nums.len().max(1)) {
                    t.splice(s..end, EXTREMES[*e].bytes());
                }
            }
            Mutation::DeleteLine(k) | Mutation::DuplicateLine(k) => {
                let lines: Vec<Vec<u8>> = t.split(|&b| b == b'\n').map(|l| l.to_vec()).collect();
                let k = k % lines.len();
                let mut out = Vec::new();
                for (i, l) in lines.iter().enumerate() {
                    let copies = match (m, i == k) {
                        (Mutation::DeleteLine(_), true) => 0,
                        (Mutation::DuplicateLine(_), true) => 2,
                        _ => 1,
                    };
                    for _ in 0..copies {
                        out.extend_from_slice(l);
                        out.push(b'\n');
                    }
                }
                t = out;
            }
            Mutation::Flip(k, x) => {
                let n = t.len();
                t[k % n] ^= x;
            }
            Mutation::Truncate(k) => t.truncate(k % t.len()),
        }
    }
    t
}

/// Runs `f`, failing on a panic or on exceeding [`CASE_LIMIT`]; saves the
/// input on failure.
fn check(kind: &str, input: &[u8], f: impl FnOnce() -> String) -> Result<(), TestCaseError> {
    let t0 = Instant::now();
    let res = catch_unwind(AssertUnwindSafe(f));
    let took = t0.elapsed();
    let fail = |why: String| {
        let dir = root().join("target/fuzz-failures");
        let _ = std::fs::create_dir_all(&dir);
        let name = format!("{kind}-{:016x}", fxhash(input));
        let _ = std::fs::write(dir.join(&name), input);
        TestCaseError::fail(format!(
            "{kind}: {why} (input saved as target/fuzz-failures/{name})"
        ))
    };
    match res {
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(fail(format!("panicked: {msg}")))
        }
        Ok(_) if took > CASE_LIMIT => Err(fail(format!("took {took:?}"))),
        Ok(_) => Ok(()),
    }
}

fn fxhash(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf29ce484222325u64, |h, &x| {
        (h ^ x as u64).wrapping_mul(0x100000001b3)
    })
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: ci_cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

fn corpus(files: &[&str]) -> Vec<(PathBuf, Vec<u8>)> {
    files
        .iter()
        .map(|f| {
            let p = root().join(f);
            let t = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p, t)
        })
        .collect()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sdrs-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn scene_reader_never_panics_or_hangs() {
    let files = corpus(&[
        "robots/pendulum.yaml",
        "robots/four_chains.yaml",
        "robots/box_on_slope_mu02.yaml",
        "robots/box_stack.yaml",
        "robots/chain_reach/scene.yaml",
    ]);
    let loaded = std::cell::Cell::new(0usize);
    rounds("scene", || {
        runner()
            .run(
                &(0..files.len(), prop::collection::vec(mutation(), 1..4)),
                |(i, muts)| {
                    let input = apply(&files[i].1, &muts);
                    check("scene", &input, || {
                        let text = String::from_utf8_lossy(&input);
                        match Scene::from_str(&text, &files[i].0) {
                            Ok(scene) => {
                                loaded.set(loaded.get() + 1);
                                if scene.model.ndof() <= 64 {
                                    let mut sim = scene.simulator();
                                    for _ in 0..2 {
                                        if let Ok(d) = sim.step() {
                                            assert!(
                                                d.newton.value.is_finite() || d.newton.iters == 0
                                            );
                                        } else {
                                            break;
                                        }
                                    }
                                }
                                String::new()
                            }
                            Err(e) => {
                                let m = e.to_string();
                                assert!(!m.is_empty());
                                m
                            }
                        }
                    })
                },
            )
            .unwrap();
    });
    eprintln!(
        "scene inputs that loaded (and were simulated): {}",
        loaded.get()
    );
}

fn import_quietly(path: &Path) -> String {
    let opts = ImportOptions {
        decomposer: Decomposer::Hull,
        coverage_samples: 50,
        volume_grid: 8,
        ..ImportOptions::default()
    };
    match import(path, &opts) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn urdf_reader_never_panics_or_hangs() {
    let dir = scratch("urdf");
    let src = root().join("robots/spider");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    for e in std::fs::read_dir(src.join("meshes")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, dir.join("meshes").join(p.file_name().unwrap())).unwrap();
    }
    let files = corpus(&[
        "robots/spider/spider.urdf",
        "robots/biped/biped.urdf",
        "tests/data/pybullet_shapes.urdf",
    ]);
    let target = dir.join("robot.urdf");
    rounds("urdf", || {
        runner()
            .run(
                &(0..files.len(), prop::collection::vec(mutation(), 1..4)),
                |(i, muts)| {
                    let input = apply(&files[i].1, &muts);
                    std::fs::write(&target, &input).unwrap();
                    check("urdf", &input, || import_quietly(&target))
                },
            )
            .unwrap();
    });
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mesh_readers_never_panic_or_hang() {
    let dir = scratch("mesh");
    let files = corpus(&[
        "robots/spider/meshes/foot.obj",
        "tests/data/repro/l_finger.stl",
        "tests/data/cube_cm.dae",
        "tests/data/instanced_mm.dae",
    ]);
    rounds("mesh", || {
        runner()
            .run(
                &(0..files.len(), prop::collection::vec(mutation(), 1..4)),
                |(i, muts)| {
                    let input = apply(&files[i].1, &muts);
                    let ext = files[i]
                        .0
                        .extension()
                        .unwrap()
                        .to_string_lossy()
                        .into_owned();
                    let target = dir.join(format!("mesh.{ext}"));
                    std::fs::write(&target, &input).unwrap();
                    check("mesh", &input, || import_quietly(&target))
                },
            )
            .unwrap();
    });
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_mutator_changes_numbers_into_extremes() {
    // The fuzzer must be able to produce the inputs that used to crash.
    let t = b"size: [1, 2.5, -3e2]\n";
    assert_eq!(numbers(t).len(), 3);
    let out = apply(t, &[Mutation::Number(1, 6)]);
    assert_eq!(String::from_utf8(out).unwrap(), "size: [1, 1e308, -3e2]\n");
    let out = apply(t, &[Mutation::Number(2, 0)]);
    assert_eq!(String::from_utf8(out).unwrap(), "size: [1, 2.5, nan]\n");
}
