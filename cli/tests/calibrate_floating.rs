//! Calibration on a contact-rich robot nobody here wrote (issue 33,
//! acceptance: a quadruped on the ground), CI size: gymnasium's `ant.xml`
//! imported with `sdrs import`, data from MuJoCo (RK4, 0.1 ms, elliptic
//! cone) on the original MJCF under the scene's PD push-ups, 1e-3 noise at
//! 100 Hz, 3 s (`tools/check/calib_floating.py`, the cases as registered in
//! session 5 of `notes/calibration.md`). Clean data must give `none`; the
//! ground friction changed 1.0 → 0.3 must be named alone and fitted within
//! 15 % — at the scene's Δt = 2 ms the best fit is 0.235 (our step's
//! first-order error), so this needs the Δt → 0 extrapolation decided per
//! channel (the torso height gets worse at Δt/2 and hid the joints'
//! evidence on the summed error: fitted 0.232 before).
//!
//! CI size: the candidates are `contact_mu` and `link_mass_scale` only
//! (the full set, ~1000–2400 simulations per case, is the script without
//! `--effects`). A 2 s recording was tried first for CI time: its clean
//! case named `contact_mu/all + link_mass_scale/all` (μ 0.80, an
//! integrator bias the floor did not count); recorded in
//! `notes/calibration.md` (session 12) as open, and the registered 3 s kept.

use crate::support;

#[test]
fn ant_clean_is_none_and_ground_friction_is_named_alone() {
    if support::skip_without_venv() {
        return;
    }
    let dir = support::scratch_dir("calibrate-floating");
    // One rayon thread for `sdrs calibrate`: the ant's calibration spends
    // much of its serial phases (baseline, error floors, the Δt/2 refit) in
    // a second worker spinning for per-step parallel work, 113 CPU-s for
    // the two cases against 78.5 with one thread (same calibration.json but
    // its `seconds`, bit for bit). Under nextest two tests share the two
    // cores, so CPU time is the test's cost; calibrate's parallel paths are
    // run by the in-process calibration tests (`tests/calibrate_*.rs`).
    let mut cmd = support::check_script("calib_floating.py");
    cmd.args([
        "--cases",
        "clean,mu",
        "--effects",
        "contact_mu,link_mass_scale",
    ])
    .env("RAYON_NUM_THREADS", "1");
    let (ok, cases) = support::calibration_check_with(&mut cmd, &dir);
    assert_eq!(cases.len(), 2);
    let clean = &cases[0];
    assert_eq!(clean["verdict"], "none", "{}", clean["reason"]);
    let mu = &cases[1];
    assert_eq!(mu["candidate"], "contact_mu/all", "{}", mu["reason"]);
    let v = mu["parameters"]["contact_mu/all"].as_f64().unwrap();
    assert!((v / 0.3 - 1.0).abs() <= 0.15, "μ {v} (true 0.3)");
    assert!(ok);
}
