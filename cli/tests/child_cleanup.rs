//! `SIGTERM` to `sdrs import --decomposer coacd` stops the Python helper and
//! removes its temporary folder (shared/repro README: both used to remain).

use crate::support;

use std::time::{Duration, Instant};
use support::{robots, scratch_dir, sdrs};

/// Children of every thread of `pid` (the import starts helpers from its
/// worker threads, and `/proc/PID/task/TID/children` lists one thread's).
fn children(pid: u32) -> Vec<u32> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    let mut out: Vec<u32> = tasks
        .filter_map(|t| t.ok())
        .flat_map(|t| {
            std::fs::read_to_string(t.path().join("children"))
                .unwrap_or_default()
                .split_whitespace()
                .filter_map(|s| s.parse().ok())
                .collect::<Vec<u32>>()
        })
        .collect();
    out.sort();
    out
}

fn alive(pid: u32) -> bool {
    // A reaped process has no /proc entry; a zombie is dead too.
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map(|s| !s.contains(") Z "))
        .unwrap_or(false)
}

#[test]
fn sigterm_stops_the_coacd_helper_and_removes_its_temporary_folder() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("sigterm");
    let mut run = sdrs()
        .args([
            "import",
            "-q",
            "--decomposer",
            "coacd",
            "--resolution",
            "400",
            "--out",
        ])
        .arg(dir.join("d.yaml"))
        .arg(robots("spider/spider.urdf"))
        .env("SDRS_ROOT", support::root())
        .spawn()
        .unwrap();
    let pid = run.id();
    let t0 = Instant::now();
    let helper = loop {
        if let Some(&c) = children(pid).first() {
            break c;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "no helper started");
        assert!(
            run.try_wait().unwrap().is_none(),
            "import ended before the helper started"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let temp = std::env::temp_dir();
    let prefix = format!("sdrs-coacd-{pid}-");
    let ours = || -> Vec<std::path::PathBuf> {
        std::fs::read_dir(&temp)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .starts_with(&prefix)
            })
            .collect()
    };
    assert!(
        !ours().is_empty(),
        "the helper's folder should exist while it runs"
    );
    std::thread::sleep(Duration::from_millis(300));
    unsafe {
        libc::kill(pid as libc::pid_t, libc::SIGTERM);
    }
    let status = run.wait().unwrap();
    assert!(!status.success());
    let t1 = Instant::now();
    while alive(helper) && t1.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(!alive(helper), "the Python helper {helper} outlived sdrs");
    assert!(ours().is_empty(), "temporary folders left: {:?}", ours());
    let _ = std::fs::remove_dir_all(&dir);
}
