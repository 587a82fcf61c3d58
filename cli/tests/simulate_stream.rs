//! `sdrs simulate` streams its trajectory (reproducers
//! `shared/repro/sim_long_run_memory`, `shared/repro/sim_dt_1e308`):
//! memory does not grow with `--steps`, an interrupted or killed run
//! leaves a valid CSV prefix, and meaningless `dt`/`steps` are refused
//! with the file and the key.
//!
//! Settings chosen before the runs: the pendulum scene (1 DOF, `dt` =
//! 1 ms); "bounded" means the peak resident memory (`ru_maxrss` of the
//! child) of a 200 000-step run exceeds that of a 20 000-step run by less
//! than 8 MB. Keeping the run in memory costs ≥ 250 bytes per step
//! (diagnostics, coordinates, CSV text), i.e. ≥ 45 MB for the extra
//! 180 000 steps, so the check separates the two behaviours.

use crate::support;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use support::{robots, scratch_dir, sdrs};

/// Runs `cmd` to completion and returns (exit code, peak RSS in kB).
/// The child is reaped by `wait4` (which also gives its `rusage`).
#[allow(clippy::zombie_processes)]
fn run_with_peak_rss(mut cmd: Command) -> (i32, i64) {
    let child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: plain syscall on our own child; `ru` is a valid out-pointer.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut ru) };
    assert_eq!(r, pid);
    (libc::WEXITSTATUS(status), ru.ru_maxrss)
}

#[test]
fn long_run_memory_does_not_grow_with_steps() {
    let dir = scratch_dir("stream-rss");
    let mut peaks = Vec::new();
    for steps in ["20000", "200000"] {
        let mut cmd = sdrs();
        cmd.args(["simulate", "-q", "--steps", steps, "--out"])
            .arg(dir.join(format!("t{steps}.csv")))
            .arg("--json")
            .arg(dir.join(format!("s{steps}.json")))
            .arg(robots("pendulum.yaml"));
        let (code, rss) = run_with_peak_rss(cmd);
        assert_eq!(code, 0, "{steps} steps");
        let text = std::fs::read_to_string(dir.join(format!("t{steps}.csv"))).unwrap();
        assert_eq!(text.lines().count(), steps.parse::<usize>().unwrap() + 2);
        peaks.push(rss);
    }
    eprintln!(
        "peak RSS (kB): 20 000 steps {}, 200 000 steps {}",
        peaks[0], peaks[1]
    );
    assert!(
        peaks[1] - peaks[0] < 8 * 1024,
        "peak RSS grew from {} kB to {} kB",
        peaks[0],
        peaks[1]
    );
}

/// Every line after the header has the header's field count and numbers
/// only; `t` goes up by `dt` from 0. Returns the number of rows.
fn check_prefix(csv: &Path, dt: f64) -> usize {
    let text = std::fs::read_to_string(csv).unwrap();
    assert!(text.ends_with('\n'), "the file ends inside a row");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,hinge"));
    let mut n = 0;
    for (k, l) in lines.enumerate() {
        let f: Vec<f64> = l
            .split(',')
            .map(|x| x.parse().unwrap_or_else(|_| panic!("row {k}: {l:?}")))
            .collect();
        assert_eq!(f.len(), 2, "row {k}: {l:?}");
        assert!(
            (f[0] - k as f64 * dt).abs() <= 1e-9 * (1.0 + k as f64 * dt),
            "row {k}: t = {}",
            f[0]
        );
        assert!(f[1].is_finite());
        n += 1;
    }
    n
}

/// Starts an endless run, waits until rows reach the file, sends `signal`.
fn interrupted_run(dir: &Path, signal: libc::c_int) -> (Option<i32>, usize) {
    let csv = dir.join(format!("sig{signal}.csv"));
    let mut child = sdrs()
        .args(["simulate", "-q", "--steps", "1000000000", "--out"])
        .arg(&csv)
        .arg(robots("pendulum.yaml"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while std::fs::metadata(&csv).map_or(0, |m| m.len()) < 4096 {
        assert!(t0.elapsed() < Duration::from_secs(60), "no rows after 60 s");
        std::thread::sleep(Duration::from_millis(50));
    }
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    let status = child.wait().unwrap();
    (status.code(), check_prefix(&csv, 0.001))
}

#[test]
fn interrupted_or_killed_run_leaves_a_valid_csv_prefix() {
    let dir = scratch_dir("stream-interrupt");
    let (code, rows) = interrupted_run(&dir, libc::SIGINT);
    assert_eq!(code, Some(130), "Ctrl-C exits with 130");
    assert!(rows > 10, "{rows} rows");
    // SIGKILL cannot be handled: the file still holds whole rows only.
    let (code, rows) = interrupted_run(&dir, libc::SIGKILL);
    assert_eq!(code, None);
    assert!(rows > 10, "{rows} rows");
}

fn refused(scene_text: &str, extra: &[&str], expect: &[&str]) {
    let dir = scratch_dir("stream-dt");
    let scene = dir.join("meaningless.yaml");
    std::fs::write(&scene, scene_text).unwrap();
    let out = sdrs()
        .args(["simulate", "-q"])
        .args(extra)
        .arg("--out")
        .arg(dir.join("t.csv"))
        .arg(&scene)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect.iter().chain(&["meaningless.yaml"]) {
        assert!(err.contains(e), "missing {e:?} in: {err}");
    }
}

#[test]
fn meaningless_dt_and_steps_are_refused_naming_file_and_key() {
    let pendulum = std::fs::read_to_string(robots("pendulum.yaml")).unwrap();
    let with_dt = |dt: &str| pendulum.replace("dt: 0.001", &format!("dt: {dt}"));
    refused(&with_dt("1.0e+308"), &[], &["dt", "meaningless"]);
    refused(&with_dt(".inf"), &[], &["dt", "finite"]);
    refused(&with_dt(".nan"), &[], &["dt", "finite"]);
    // t = steps·dt stops advancing by dt (1.8e16 s: its spacing is 4 s).
    refused(
        &pendulum.replace("steps: 5000", "steps: 18446744073709551615"),
        &[],
        &["steps", "no longer advances"],
    );
    refused(
        &pendulum,
        &["--steps", "18446744073709551615"],
        &["--steps", "no longer advances"],
    );
}
