//! Smoke version of `tools/check/swing_vs_mujoco.py`: the KUKA iiwa imported with
//! default masses (its URDF inertials), swinging freely (hanging, small
//! amplitude) for 0.3 s, against MuJoCo's RK4: the joint-angle error
//! shrinks at first order with Δt (SDRS's implicit scheme). The full table
//! (1 s, Δt = 1e-2 … 1e-4) is in `notes/mass-models.md`.

use crate::support;

use support::{check_script, pybullet_data, root, scratch_dir, sdrs};

/// Runs a convergence script of `tools/check/` (`--sdrs`, `--work`, `--json` added)
/// with `args`, asserts it succeeded and returns its JSON table.
fn table(dir: &std::path::Path, script: &str, args: &[&std::ffi::OsStr]) -> serde_json::Value {
    let json = dir.join("table.json");
    let o = check_script(script)
        .args(args)
        .arg("--work")
        .arg(dir.join("work"))
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    eprintln!("{}", String::from_utf8_lossy(&o.stdout));
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

#[test]
fn imported_iiwa_free_swing_converges_to_mujoco_at_first_order() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("swing-mujoco");
    let urdf = pybullet_data().join("kuka_iiwa/model.urdf");
    let scene = dir.join("iiwa.yaml");
    let o = sdrs()
        .args(["import", "--decomposer", "hull", "--out"])
        .arg(&scene)
        .arg(&urdf)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = table(
        &dir,
        "swing_vs_mujoco.py",
        &[
            scene.as_os_str(),
            "--q".as_ref(),
            "0.05 0.1 -0.05 -0.1 0.05 0.1 0.02".as_ref(),
            "--gravity".as_ref(),
            "0".as_ref(),
            "0".as_ref(),
            "9.81".as_ref(),
            "--duration".as_ref(),
            "0.3".as_ref(),
            "--dts".as_ref(),
            "1e-2,1e-3".as_ref(),
            "--mj-timestep".as_ref(),
            "5e-5".as_ref(),
        ],
    );
    let rows = v["rows"].as_array().unwrap();
    let e: Vec<f64> = rows
        .iter()
        .map(|r| r["max_error_rad"].as_f64().unwrap())
        .collect();
    let order = rows[1]["order"].as_f64().unwrap();
    assert!(e[1] < e[0] && e[1] < 2e-3, "errors {e:?}");
    assert!((0.8..1.3).contains(&order), "order {order} (errors {e:?})");
}

/// Smoke version of `tools/check/pd_vs_mujoco.py`: the spider (free base, eight
/// two-hinge legs) tracking its sine PD targets in the air for 0.5 s, in
/// SDRS and in MuJoCo (the robot from `sdrs export-mjcf`, the same PD law,
/// MuJoCo's implicit integrator at 1e-5 s): joint angles, base position and
/// base orientation converge at first order. Full table (1 s, Δt = 1e-2 …
/// 1e-4, reference at 1e-6 s) in `notes/mjcf-in-and-out.md`.
#[test]
fn spider_pd_tracking_converges_to_mujoco_at_first_order() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("pd-mujoco");
    let spider = root().join("robots/spider/scene.yaml");
    let v = table(
        &dir,
        "pd_vs_mujoco.py",
        &[
            spider.as_os_str(),
            "--duration".as_ref(),
            "0.5".as_ref(),
            "--dts".as_ref(),
            "1e-2,1e-3".as_ref(),
            "--mj-timestep".as_ref(),
            "1e-5".as_ref(),
        ],
    );
    assert_eq!(v["controlled_dofs"], 16, "every leg coordinate is driven");
    let rows = v["rows"].as_array().unwrap();
    let get = |r: usize, k: &str| rows[r][k].as_f64().unwrap();
    for k in [
        "max_joint_error",
        "max_base_position_error",
        "max_base_rotation_error",
    ] {
        let (e0, e1) = (get(0, k), get(1, k));
        let order = (e0 / e1).log10();
        assert!(
            (0.8..1.3).contains(&order),
            "{k}: {e0:.3e} → {e1:.3e}, order {order:.2}"
        );
    }
    assert!(get(1, "max_joint_error") < 5e-3, "{rows:?}");
}
