//! URDF `<dynamics damping friction>` reach the scene as `joint_damping` /
//! `joint_friction` effects on the joint of the same name, and the damping
//! acts as a viscous torque: a hinge about z (no gravity torque) of inertia
//! I = 0.2 kg m² with damping c = 0.5 N·m·s/rad, spun at 1 rad/s, slows as
//! θ̇(t) = e^{−ct/I}. Tolerance chosen before the run: implicit Euler's
//! first-order error at Δt = 1 ms, ≈ t (c/I)² Δt/2 · e^{−ct/I} = 2.6e-4
//! rad/s at t = 1 s; bound 1e-3 rad/s. A joint merged into a ball joint
//! cannot take a per-axis coefficient: a report line says so.

use crate::import_support;

use import_support::*;
use sdrs::energy::effects::EffectKind;
use sdrs::import::import;
use sdrs::scene::Scene;

const URDF: &str = r#"<robot name="spin">
  <link name="base"/>
  <link name="rotor">
    <inertial><origin xyz="0 0 0"/><mass value="1"/>
      <inertia ixx="0.2" iyy="0.2" izz="0.2" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
  <link name="gimbal"/>
  <link name="tip">
    <inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.02"/></geometry></collision>
  </link>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="rotor"/><axis xyz="0 0 1"/>
    <dynamics damping="0.5" friction="0.02"/>
  </joint>
  <joint name="ga" type="continuous">
    <parent link="rotor"/><child link="gimbal"/><origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>
    <dynamics damping="0.1"/>
  </joint>
  <joint name="gb" type="continuous">
    <parent link="gimbal"/><child link="tip"/><axis xyz="0 1 0"/>
  </joint>
</robot>"#;

#[test]
fn urdf_dynamics_become_effects_and_damp_as_viscous_torque() {
    let dir = temp_dir("urdf-dynamics");
    let urdf = dir.join("spin.urdf");
    std::fs::write(&urdf, URDF).unwrap();
    let imp = import(&urdf, &hull_options()).unwrap_or_else(|e| panic!("{e}"));
    let effects: Vec<_> = imp
        .scene
        .effects
        .iter()
        .map(|e| (e.effect, e.on.as_str(), e.values.clone()))
        .collect();
    assert_eq!(
        effects,
        vec![
            (EffectKind::JointDamping, "spin", vec![0.5]),
            (EffectKind::JointFriction, "spin", vec![0.02]),
        ]
    );
    // `ga` and `gb` (orthogonal, through a bare link) became one ball joint.
    assert!(
        imp.report.notes.iter().any(|n| n.contains(
            "joint \"ga\": <dynamics damping=\"0.1\"> left out (the joint is part of scene joint \"ga+gb\""
        )),
        "{:?}",
        imp.report.notes
    );
    // Damping alone (friction removed), the ball welded, spun at 1 rad/s.
    let mut spec = imp.scene.clone();
    spec.effects
        .retain(|e| e.effect == EffectKind::JointDamping);
    spec.robots[0].links.retain(|l| l.name != "tip");
    spec.robots[0].design = None;
    spec.robots[0].initial.insert(
        "spin".into(),
        sdrs::scene::schema::InitialSpec {
            q: vec![0.0],
            qdot: vec![1.0],
        },
    );
    let scene = Scene::from_spec(spec, &urdf).unwrap();
    let mut sim = scene.simulator();
    let dt = sim.settings.dt;
    assert_eq!(dt, 1e-3);
    let (c, inertia) = (0.5, 0.2);
    let mut worst: f64 = 0.0;
    for step in 1..=1000 {
        sim.step().unwrap();
        let v = (sim.state.q[0] - sim.state.q_prev[0]) / dt;
        let t = step as f64 * dt;
        worst = worst.max((v - (-c * t / inertia).exp()).abs());
    }
    eprintln!("damped spin: worst |θ̇ − e^(−ct/I)| over 1 s = {worst:.3e} rad/s");
    assert!(worst < 1e-3, "{worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// URDF `<limit effort velocity>` and `<transmission>` are not simulated;
/// each gets a report line, never a silent drop. `lift` (revolute, limits
/// [−1, 1] around its initial 0) keeps its scene limit, which carries the
/// URDF's effort 5 N·m and velocity 2 rad/s; `wheel` (continuous, no
/// scene limit) has its effort 3 and velocity 4 listed as left out; each
/// transmission is listed as ignored with its joint, actuator and
/// `mechanicalReduction` (one line each, no generic line).
#[test]
fn urdf_effort_velocity_and_transmissions_are_reported() {
    let dir = temp_dir("urdf-effort");
    let urdf = dir.join("lim.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="lim">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="rim"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.3"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="lift" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <joint name="wheel" type="continuous"><parent link="arm"/><child link="rim"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit effort="3" velocity="4"/></joint>
  <transmission name="t_lift"><type>transmission_interface/SimpleTransmission</type>
    <joint name="lift"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
    <actuator name="m_lift"><mechanicalReduction>50</mechanicalReduction></actuator></transmission>
  <transmission name="t_wheel" type="pr2_mechanism_model/SimpleTransmission">
    <joint name="wheel"/><actuator name="m_wheel"/><mechanicalReduction>7.5</mechanicalReduction></transmission>
</robot>"#,
    )
    .unwrap();
    let imp = import(&urdf, &hull_options()).unwrap_or_else(|e| panic!("{e}"));
    let notes = &imp.report.notes;
    let line = |start: &str| {
        notes
            .iter()
            .find(|n| n.starts_with(start))
            .unwrap_or_else(|| panic!("no line {start:?}: {notes:?}"))
            .clone()
    };
    // Each joint's line: its effort and velocity, and what was done.
    for (joint, effort, velocity, done) in [("lift", 5, 2, "carried"), ("wheel", 3, 4, "left out")]
    {
        let l = line(&format!("joint \"{joint}\": <limit"));
        assert!(
            l.contains(&format!("effort=\"{effort}\""))
                && l.contains(&format!("velocity=\"{velocity}\""))
                && l.contains(done),
            "{l}"
        );
    }
    // One line per transmission: its joint, actuator and reduction (ROS's
    // `<actuator><mechanicalReduction>` and the older direct child).
    for (t, kind, joint, actuator, reduction) in [
        (
            "t_lift",
            "transmission_interface/SimpleTransmission",
            "lift",
            "m_lift",
            "50",
        ),
        (
            "t_wheel",
            "pr2_mechanism_model/SimpleTransmission",
            "wheel",
            "m_wheel",
            "7.5",
        ),
    ] {
        let l = line(&format!("ignored <transmission> \"{t}\" ({kind})"));
        assert!(
            l.contains(&format!("joint(s) [\"{joint}\"]"))
                && l.contains(&format!("actuator(s) [\"{actuator}\"]"))
                && l.contains(&format!("mechanicalReduction [{reduction}]")),
            "{l}"
        );
    }
    assert_eq!(
        notes
            .iter()
            .filter(|n| n.contains("<transmission>"))
            .count(),
        2,
        "{notes:?}"
    );
    let r = &imp.scene.robots[0];
    let lim = |j: &str| {
        r.links
            .iter()
            .find(|l| l.joint.name.as_deref().unwrap_or(&l.name) == j)
            .unwrap_or_else(|| panic!("no joint {j}"))
            .joint
            .limit
            .clone()
    };
    let l = lim("lift").expect("lift keeps its limit");
    assert_eq!((l.effort, l.velocity), (Some(5.0), Some(2.0)));
    assert!(lim("wheel").is_none());
    let _ = std::fs::remove_dir_all(&dir);
}
