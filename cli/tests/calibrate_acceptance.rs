//! Calibration acceptance on a robot nobody here wrote (issue 33, item 3),
//! CI size: gymnasium's `reacher.xml` imported with `sdrs import`, data from
//! MuJoCo (RK4, 0.1 ms) on the original MJCF with 1e-3 noise at 100 Hz
//! (`tools/check/calib_acceptance.py --cases quick`): clean data must give `none`
//! with the error floor explaining the gap, and a hidden joint damping on
//! every joint must be named alone and fitted within 10 %. The full set
//! (two robots, clean, one and two effects) is the script without
//! `--cases quick`; see `notes/calibration.md`.

use crate::support;

#[test]
fn reacher_clean_is_none_and_damping_is_named_alone() {
    if support::skip_without_venv() {
        return;
    }
    let dir = support::scratch_dir("calibrate-acceptance");
    let (ok, cases) = support::calibration_check(
        "calib_acceptance.py",
        &["--cases", "quick", "--duration", "2.0"],
        &dir,
    );
    assert_eq!(cases.len(), 2);
    let clean = &cases[0];
    assert_eq!(clean["verdict"], "none", "{}", clean["reason"]);
    let fl = &clean["error_floor"];
    assert!(fl["gap"].as_f64().unwrap() <= fl["floor"].as_f64().unwrap());
    let damp = &cases[1];
    assert_eq!(damp["candidate"], "joint_damping/all", "{}", damp["reason"]);
    let c = damp["parameters"]["joint_damping/all"].as_f64().unwrap();
    assert!((c / 0.5 - 1.0).abs() <= 0.1, "damping {c} (true 0.5)");
    assert!(ok);
}
