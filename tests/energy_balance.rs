//! The energy balance of the summary (`energy.balance`): where a driven or frictional
//! scene's energy goes. Physics asserted: the controller's work accounts for
//! a driven pendulum's energy change up to the integrator's numerical
//! dissipation, which is non-negative and first order in Δt; friction does
//! negative work on a sliding box, equal to the energy lost up to that same
//! residual; computing the balance leaves the trajectory bitwise unchanged.

use sdrs::output::Summary;
use sdrs::scene::Scene;
use std::path::Path;

fn driven_pendulum(dt: f64) -> String {
    format!(
        r#"
version: 1
dt: {dt}
steps: {steps}
gravity: [0, 0, -9.81]
robots:
  - name: p
    links:
      - name: bob
        joint: {{name: hinge, type: revolute, axis: [0, 1, 0]}}
        mass: 1.0
        hulls: [{{box: {{size: [0.05, 0.05, 0.05], center: [0, 0, -0.5]}}}}]
    controller:
      kp: 20
      kd: 0.5
      targets:
        hinge: {{type: sine, terms: [{{amplitude: 0.6, frequency: 0.8}}]}}
"#,
        steps = (2.0 / dt).round() as usize
    )
}

fn run(text: &str, balance: bool) -> (Summary, Vec<f64>) {
    let scene = Scene::from_str(text, Path::new("inline.yaml")).unwrap();
    let mut sim = scene.simulator();
    sim.energy_balance = balance;
    let traj = sdrs::sim::run::run(&mut sim, scene.steps, |_| {}).unwrap();
    let flat = traj.states.iter().flat_map(|q| q.iter().copied()).collect();
    (
        Summary::new("t", scene.settings.dt, &traj, 0.0, vec![]),
        flat,
    )
}

#[test]
fn controller_work_accounts_for_a_driven_pendulum_up_to_first_order_dissipation() {
    let mut dissipation = Vec::new();
    for dt in [0.004, 0.002, 0.001] {
        let (s, q) = run(&driven_pendulum(dt), true);
        let b = s.energy.as_ref().unwrap().balance.clone().unwrap();
        eprintln!("dt {dt}: {b:?}");
        assert!(
            b.controller_work.abs() > 0.1,
            "the controller did no work: {b:?}"
        );
        assert_eq!(
            (b.friction_work, b.contact_work, b.other_work),
            (0.0, 0.0, 0.0)
        );
        // The balance closes up to the integrator's dissipation, ≥ 0 (its
        // size: implicit Euler damps a mode of frequency ω at a rate of
        // about ω²Δt; here ω ≈ 10 rad/s).
        assert!(b.numerical_dissipation > -1e-9, "{b:?}");
        dissipation.push(b.numerical_dissipation);
        // Bitwise the same trajectory without the balance.
        let (_, q_plain) = run(&driven_pendulum(dt), false);
        assert_eq!(q, q_plain);
    }
    // First order in Δt: halving Δt halves the numerical dissipation.
    for k in 0..2 {
        let r = dissipation[k] / dissipation[k + 1];
        assert!((1.5..2.5).contains(&r), "ratio {r} ({dissipation:?})");
    }
}

#[test]
fn friction_work_is_the_energy_a_sliding_box_loses() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/box_on_slope_mu02.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let (s, q) = run(&text, true);
    let b = s.energy.as_ref().unwrap().balance.clone().unwrap();
    eprintln!("{b:?}");
    assert!(
        b.change < -0.1,
        "a sliding box on a slope loses energy: {b:?}"
    );
    assert!(b.friction_work < -0.1, "{b:?}");
    assert_eq!(b.controller_work, 0.0);
    // Friction takes the bulk of the loss; the rest (barrier and the
    // integrator) is small.
    assert!(
        (b.change - b.friction_work).abs() < 0.1 * b.change.abs(),
        "{b:?}"
    );
    assert!(b.numerical_dissipation > -1e-3 * b.change.abs(), "{b:?}");
    let (_, q_plain) = run(&text, false);
    assert_eq!(q, q_plain);
}
