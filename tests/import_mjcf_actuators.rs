//! MJCF actuators → the scene's PD controller (`src/import/mjcf/actuators.rs`,
//! issue 32 items 1 and 6): a position servo's gains and target follow
//! MuJoCo's force law and the arm settles where MuJoCo's does; motors,
//! tendon and site transmissions and activation dynamics get report lines;
//! the import's PD hold keeps the joints no actuator drives.

use crate::import_support;

use import_support::*;
use sdrs::control::Signal;
use sdrs::import::import;
use sdrs::import::mjcf::actuators::{Drive, drives};
use sdrs::import::ready::{ReadyOptions, make_ready};
use sdrs::scene::Scene;
use sdrs::scene::schema::SignalList;
use std::path::Path;
use std::process::Command;

/// An arm along +x on a hinge about y at the world origin (θ > 0 lowers
/// the tip), a 1 kg point mass at l = 0.5 m, driven by
/// `<position kp="10" kv="1" gear="2" ctrlrange="0.2 1">`: at rest MuJoCo
/// clamps ctrl 0 to u = 0.2.
const ARM: &str = r#"<mujoco model="arm"><compiler angle="radian"/>
  <option gravity="0 0 -9.81" timestep="1e-4" integrator="RK4"/>
  <worldbody>
    <body name="arm">
      <joint name="h" type="hinge" axis="0 1 0"/>
      <inertial pos="0.5 0 0" mass="1" diaginertia="1e-3 1e-3 1e-3"/>
      <geom type="sphere" pos="0.5 0 0" size="0.05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator><position name="servo" joint="h" kp="10" kv="1" gear="2" ctrlrange="0.2 1"/></actuator>
</mujoco>"#;

/// MuJoCo's θ(t) of `xml` from `qpos0` at rest, sampled every `every`
/// steps for `steps` steps (the model's own integrator and time step).
fn mujoco_angles(xml: &Path, steps: usize, every: usize) -> Vec<f64> {
    let script = format!(
        "import json, mujoco\n\
         m = mujoco.MjModel.from_xml_path({xml:?})\n\
         d = mujoco.MjData(m)\n\
         out = [float(d.qpos[0])]\n\
         for k in range(1, {steps} + 1):\n\
         \x20   mujoco.mj_step(m, d)\n\
         \x20   if k % {every} == 0:\n\
         \x20       out.append(float(d.qpos[0]))\n\
         print(json.dumps(out))\n",
        xml = xml.to_str().unwrap()
    );
    let out = Command::new(venv_python())
        .args(["-c", &script])
        .output()
        .expect("run the venv's Python");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// A `<position kp kv gear>` servo on a hinge becomes the scene's PD on that
/// joint with MuJoCo's force: `k_p = g² kp/2 = 20`, `k_d = g² kv Δt/2 =
/// 2e-4`, `θ* = u/g = 0.1` (u = ctrl 0 clamped to ctrlrange [0.2, 1]),
/// instead of the import's hold (`ready.gains` does not list the joint).
///
/// Physics against MuJoCo (the same file, RK4 at 1e-4 s) and the analytic
/// equilibrium `g² kp (θ* − θ) + m g_z l cos θ = 0`, i.e.
/// `40 (0.1 − θ) + 4.905 cos θ = 0` (θ ≈ 0.222 rad): the arm is released at
/// θ = 0 and settles (damping `g² kv = 4` N·m·s/rad, ζ ≈ 0.6, decay rate
/// ≈ 8/s: the 0.22 rad offset is below 1e-10 rad after 3 s). Tolerances
/// chosen before the run: final angle of each engine within 1e-4 rad of the
/// analytic root; largest difference between the two trajectories (every
/// 0.01 s over 3 s, SDRS's implicit Euler at Δt = 1e-4, first order:
/// ~ω Δt × 0.22 rad ≈ 3e-4 rad) ≤ 5e-3 rad. A wrong gear power in `k_p`
/// (g instead of g²) moves the equilibrium by > 0.05 rad; in `k_d` it
/// changes ζ from 0.6 to 0.3 (≈ 0.05 rad apart in the first swing).
#[test]
fn a_position_servo_maps_to_the_scene_pd_and_settles_where_mujoco_does() {
    if skip_without_venv() {
        return;
    }
    let dir = temp_dir("mjcf-servo");
    let xml = dir.join("arm.xml");
    std::fs::write(&xml, ARM).unwrap();
    let dt = 1e-4;
    let opts = sdrs::import::ImportOptions {
        dt,
        steps: 30_000,
        ..hull_options()
    };
    let mut imp = import(&xml, &opts).unwrap_or_else(|e| panic!("{e}"));
    let ready = make_ready(
        &mut imp.scene,
        &xml,
        imp.root_static,
        &ReadyOptions {
            contact: false,
            ..ReadyOptions::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(!ready.gains.contains_key("h"), "{:?}", ready.gains);
    let c = &imp.scene.robots[0].controller;
    let (g, kp, kv) = (2.0f64, 10.0f64, 1.0f64);
    let gains = &c.gains["h"];
    assert!(
        (gains.kp.unwrap() - g * g * kp / 2.0).abs() < 1e-12,
        "{gains:?}"
    );
    assert!(
        (gains.kd.unwrap() - g * g * kv * dt / 2.0).abs() < 1e-15,
        "{gains:?}"
    );
    match &c.targets["h"] {
        SignalList::One(Signal::Constant { value }) => {
            assert!((value - 0.2 / g).abs() < 1e-15, "{value}")
        }
        other => panic!("{other:?}"),
    }
    let notes = &imp.report.notes;
    assert!(
        notes.iter().any(|n| n.contains(
            "actuator \"servo\" (position, gear 2, kp 10, kv 1, ctrlrange [0.2, 1]) on joint \"h\" → the scene's PD controller"
        )),
        "{notes:?}"
    );
    assert!(
        notes
            .iter()
            .any(|n| n.contains("ctrlrange [0.2, 1]") && n.contains("does not clamp")),
        "{notes:?}"
    );

    // Analytic equilibrium (Newton).
    let (m, gz, l) = (1.0f64, 9.81f64, 0.5f64);
    let f = |t: f64| g * g * kp * (0.2 / g - t) + m * gz * l * t.cos();
    let df = |t: f64| -g * g * kp - m * gz * l * t.sin();
    let mut eq = 0.0f64;
    for _ in 0..50 {
        eq -= f(eq) / df(eq);
    }
    assert!(f(eq).abs() < 1e-12);

    let scene = Scene::from_spec(imp.scene.clone(), &xml).unwrap();
    let mut sim = scene.simulator();
    let mut ours = vec![sim.state.q[0]];
    for step in 1..=30_000 {
        sim.step().unwrap();
        if step % 100 == 0 {
            ours.push(sim.state.q[0]);
        }
    }
    let theirs = mujoco_angles(&xml, 30_000, 100);
    assert_eq!(ours.len(), theirs.len());
    let worst = ours
        .iter()
        .zip(&theirs)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let (end_ours, end_mj) = (*ours.last().unwrap(), *theirs.last().unwrap());
    eprintln!(
        "servo arm: analytic θ_eq = {eq:.6} rad; final θ sdrs {end_ours:.6} (|Δ| {:.2e}), MuJoCo {end_mj:.6} (|Δ| {:.2e}); largest |θ_sdrs − θ_mujoco| over 3 s = {worst:.3e} rad",
        (end_ours - eq).abs(),
        (end_mj - eq).abs()
    );
    assert!((end_ours - eq).abs() <= 1e-4, "sdrs {end_ours} vs {eq}");
    assert!((end_mj - eq).abs() <= 1e-4, "MuJoCo {end_mj} vs {eq}");
    assert!(worst <= 5e-3, "trajectories differ by {worst} rad");
    let _ = std::fs::remove_dir_all(&dir);
}

/// MuJoCo's own test model (`mujoco/testdata/model.xml` of the venv's
/// `mujoco` package, written by MuJoCo's authors): ten actuators of every
/// kind. Each gets exactly one report line, mapped or left out, naming its
/// element kind, name and joint or transmission target: the two
/// `<position kp="100">` on `hipz_1`, `hipz_2` map to `k_p = 50`, `k_d = 0`,
/// `θ* = 0`; `<velocity kv="1">` on `wheel_2` to `k_p = 0`, `k_d = Δt/2`;
/// the motors on the tendons `fixed` and `spatial` and on `hipy_2`, the
/// `<intvelocity>` (activation integrator), the site-driven and the two
/// other `<general>` with activation dynamics are left out.
#[test]
fn motors_tendons_sites_and_activation_dynamics_are_reported_not_dropped() {
    if skip_without_venv() {
        return;
    }
    let xml = root().join(".venv/lib/python3.11/site-packages/mujoco/testdata/model.xml");
    assert!(xml.is_file(), "{} not found", xml.display());
    let d = sdrs::import::mjcf::dump::dump(&xml).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(d.actuators.len(), 10);
    // Every other element the import leaves out is counted for its report
    // line ("N sensors … left out"), as MuJoCo compiles them for this model.
    let count = |kind: &str| {
        d.unsupported
            .iter()
            .find(|(k, _)| k.starts_with(kind))
            .map(|(_, n)| *n)
            .unwrap_or_else(|| panic!("no count for {kind}: {:?}", d.unsupported))
    };
    for (kind, n) in [
        ("sensors", 11),
        ("sites", 11),
        ("keyframes", 1),
        ("lights", 1),
        ("tendons", 2),
        ("equality constraints", 1),
        ("cameras", 0),
        ("mocap bodies", 0),
        ("skins", 0),
        ("flexes", 0),
    ] {
        assert_eq!(count(kind), n, "{kind}");
    }
    let dt = 1e-3;
    let mut notes = Vec::new();
    let got = drives(&d, dt, &mut notes);
    for n in &notes {
        eprintln!("{n}");
    }
    let servo = Drive {
        kp: 50.0,
        kd: 0.0,
        target: 0.0,
    };
    assert_eq!(got.get("hipz_1"), Some(&servo));
    assert_eq!(got.get("hipz_2"), Some(&servo));
    assert_eq!(
        got.get("wheel_2"),
        Some(&Drive {
            kp: 0.0,
            kd: dt / 2.0,
            target: 0.0
        })
    );
    assert_eq!(got.len(), 3, "{got:?}");
    // One line per actuator (by name; MuJoCo names unnamed ones actuatorN).
    for a in &d.actuators {
        let lines: Vec<_> = notes
            .iter()
            .filter(|n| n.starts_with(&format!("actuator \"{}\" (", a.name)))
            .collect();
        assert_eq!(lines.len(), 1, "{}: {lines:?}", a.name);
    }
    let line = |needle: &str| {
        notes
            .iter()
            .find(|n| n.contains(needle))
            .unwrap_or_else(|| panic!("no line with {needle:?}: {notes:#?}"))
            .clone()
    };
    for t in ["fixed", "spatial"] {
        let l = line(&format!("with tendon transmission \"{t}\" left out"));
        assert!(
            l.contains("motor") && l.contains("only joint transmissions"),
            "{l}"
        );
    }
    let l = line("with site transmission \"wheel_0\" left out");
    assert!(l.contains("general"), "{l}");
    let l = line("on joint \"hipy_2\" left out");
    assert!(
        l.contains("(motor, gear 100, ctrlrange [-1, 1])") && l.contains("torque-input channel"),
        "{l}"
    );
    assert!(l.contains("PD hold"), "{l}");
    for j in ["hipz_0", "wheel_1", "hipy_1"] {
        let l = line(&format!("on joint \"{j}\" left out"));
        assert!(l.contains("activation dynamics (dyntype"), "{l}");
    }
    for j in ["hipz_1", "hipz_2", "wheel_2"] {
        line(&format!("on joint \"{j}\" → the scene's PD controller"));
        line(&format!("joint \"{j}\" is driven by its actuators"));
    }
}

/// Through the whole import: a joint driven by a position servo keeps the
/// servo's gains, a joint with only a motor gets the import's hold, and
/// `ready.gains` lists exactly the held joint; `--no-hold` keeps the servo
/// (it is the model's, MuJoCo simulates it at ctrl 0) and adds nothing.
#[test]
fn the_hold_drives_only_the_joints_no_actuator_maps_to() {
    if skip_without_venv() {
        return;
    }
    let dir = temp_dir("mjcf-servo-hold");
    let xml = dir.join("two.xml");
    std::fs::write(
        &xml,
        r#"<mujoco model="two"><worldbody>
  <body name="a"><joint name="ja" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
    <body name="b" pos="0.3 0 0"><joint name="jb" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.05 0.05 0.05"/></body></body></worldbody>
  <actuator><position name="pa" joint="ja" kp="30" kv="3"/>
    <motor name="mb" joint="jb" gear="5"/></actuator></mujoco>"#,
    )
    .unwrap();
    let imp = import(&xml, &hull_options()).unwrap_or_else(|e| panic!("{e}"));
    let dt = hull_options().dt;
    for hold in [true, false] {
        let mut scene = imp.scene.clone();
        let opts = ReadyOptions {
            hold,
            ..ReadyOptions::default()
        };
        let ready =
            make_ready(&mut scene, &xml, imp.root_static, &opts).unwrap_or_else(|e| panic!("{e}"));
        let c = &scene.robots[0].controller;
        assert_eq!(c.gains["ja"].kp, Some(15.0));
        assert!((c.gains["ja"].kd.unwrap() - 3.0 * dt / 2.0).abs() < 1e-15);
        let held: Vec<&String> = ready.gains.keys().collect();
        if hold {
            assert_eq!(held, ["jb"]);
            assert_eq!(c.gains["jb"].kp, Some(ready.gains["jb"][0]));
            assert!(c.targets.contains_key("jb"));
        } else {
            assert!(held.is_empty());
            assert!(!c.gains.contains_key("jb") && !c.targets.contains_key("jb"));
        }
        Scene::from_spec(scene, &xml).unwrap_or_else(|e| panic!("{e}"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
