//! End-to-end: the tangling four-chain scene through `sdrs simulate
//! --export`, checked pair by pair by an independent checker (python-fcl).

use crate::support;

use support::{robots, scratch_dir};

#[test]
fn four_chains_tangle_for_2000_steps_and_python_fcl_finds_every_pair_separated() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("fcl");
    let summary = support::simulate_export(&dir, &["--steps", "2000"], &robots("four_chains.yaml"));
    let links = summary["final_state"]
        .as_object()
        .unwrap()
        .keys()
        .filter(|k| k.ends_with("j7:0"))
        .count();
    assert_eq!(links, 4, "8 links per chain expected");
    assert!(
        summary["contact"]["steps_in_contact"].as_u64().unwrap() > 100,
        "the chains did not tangle"
    );
    let ours = summary["contact"]["min_distance"].as_f64().unwrap();
    let r = support::python_fcl_check(&dir);
    let fcl_min = r["min_distance"].as_f64().unwrap();
    eprintln!(
        "python-fcl: {} steps × {} hull pairs, min distance {fcl_min:.6e} m at step {} (ours {ours:.6e})",
        r["steps_checked"], r["hull_pairs"], r["min_at_step"]
    );
    assert_eq!(r["steps_checked"], 2001);
    assert!(fcl_min > 0.0);
    assert!(
        (fcl_min - ours).abs() < 1e-6,
        "FCL and GJK disagree: {fcl_min} vs {ours}"
    );
}
