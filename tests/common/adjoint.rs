//! Harness for whole-trajectory gradient checks: a perturbable copy of
//! everything a trajectory depends on, central finite differences of the
//! loss (re-simulating), and a relative-error check.

use nalgebra::Vector3;
use nalgebra::{DVector, Matrix3};
use sdrs::control::Controller;
use sdrs::diff::{Gradients, Loss, LossTerm, When, backward, loss_of, record};
use sdrs::model::Model;
use sdrs::scene::{Scene, SharedContactFactory};
use sdrs::sim::{SimSettings, SimState, Simulator};
use std::path::Path;

/// Everything a trajectory depends on, so a test can perturb any of it
/// (contact parameters live in `scene.contact`).
#[derive(Clone)]
pub struct Setup {
    pub scene: Scene,
    pub model: Model,
    pub settings: SimSettings,
    pub controller: Controller,
    pub q0: DVector<f64>,
    pub qdot0: DVector<f64>,
    pub charts: Vec<Matrix3<f64>>,
    pub steps: usize,
    /// The contact model's factory when it is not the core's (the IPC
    /// baseline's tests set it): the trajectory is recorded with
    /// `Scene::simulator_with` and linearized with
    /// `Scene::adjoint_simulator_with`. `None`: the core's simulator for both.
    pub factory: Option<SharedContactFactory>,
}

impl Setup {
    pub fn new(text: &str, steps: usize) -> Self {
        let scene = Scene::from_str(text, Path::new("adjoint.yaml")).unwrap();
        Setup {
            model: scene.model.clone(),
            settings: scene.settings.clone(),
            controller: scene.controller.clone(),
            q0: scene.q0.clone(),
            qdot0: scene.qdot0.clone(),
            charts: scene.charts.clone(),
            steps,
            scene,
            factory: None,
        }
    }

    pub fn simulator(&self) -> Simulator {
        self.simulator_for(false)
    }

    /// The simulator of this setup's state; `adjoint`: the one the backward
    /// pass linearizes (differs from the forward one only with a factory).
    fn simulator_for(&self, adjoint: bool) -> Simulator {
        let mut sc = self.scene.clone();
        sc.model = self.model.clone();
        sc.settings = self.settings.clone();
        sc.controller = self.controller.clone();
        if self.factory.is_some() {
            // The IPC baseline checks the start for intersections.
            sc.q0 = self.q0.clone();
        }
        let mut sim = match &self.factory {
            None => sc.simulator(),
            Some(f) if adjoint => sc.adjoint_simulator_with(f.as_ref()).unwrap(),
            Some(f) => sc.simulator_with(f.as_ref()).unwrap(),
        };
        sim.state = SimState::new(
            &self.model,
            self.q0.clone(),
            &self.qdot0,
            self.charts.clone(),
            self.settings.dt,
        );
        sim
    }

    pub fn loss(&self, loss: &Loss) -> f64 {
        let mut sim = self.simulator();
        let tape = record(&mut sim, self.steps).unwrap();
        loss_of(&self.model, &tape, loss)
    }

    pub fn gradients(&self, loss: &Loss) -> Gradients {
        let mut sim = self.simulator();
        let tape = record(&mut sim, self.steps).unwrap();
        if self.factory.is_some() {
            let mut adj = self.simulator_for(true);
            return backward(&mut adj, &tape, loss).unwrap();
        }
        backward(&mut sim, &tape, loss).unwrap()
    }

    /// Index of the link named `name`.
    pub fn link(&self, name: &str) -> usize {
        self.model
            .links
            .iter()
            .position(|l| l.name == name)
            .unwrap_or_else(|| panic!("no link {name}"))
    }
}

/// Central difference of the loss under a perturbation `f(setup, ±h)`; the
/// two simulations run on two threads.
pub fn fd(setup: &Setup, loss: &Loss, h: f64, f: impl Fn(&mut Setup, f64)) -> f64 {
    let mut p = setup.clone();
    f(&mut p, h);
    let mut m = setup.clone();
    f(&mut m, -h);
    let (lp, lm) = std::thread::scope(|sc| {
        let jp = sc.spawn(|| p.loss(loss));
        let lm = m.loss(loss);
        (jp.join().unwrap(), lm)
    });
    (lp - lm) / (2.0 * h)
}

/// Relative error `|a − f| / max(|a|, |f|, 1e-8)`, printed; asserts it is at
/// most `tol` and records the worst one.
pub fn check(name: &str, adjoint: f64, finite: f64, tol: f64, worst: &mut f64) {
    let rel = (adjoint - finite).abs() / adjoint.abs().max(finite.abs()).max(1e-8);
    eprintln!("{name:<28} adjoint {adjoint:+.9e}  fd {finite:+.9e}  rel {rel:.1e}");
    *worst = worst.max(rel);
    assert!(
        rel <= tol,
        "{name}: adjoint {adjoint} vs finite difference {finite} (relative error {rel:.2e})"
    );
}

/// The loss of the pushing tests (a prismatic finger `pusher` pushes a box
/// `box`; SDRS contact in `tests/adjoint_contact_gradients.rs`, IPC in
/// `baselines/ipc/tests/adjoint_trajectory.rs`): one term of each kind —
/// a final link point, a running centre of mass, a final relative
/// position and a running joint target — so every loss path is exercised.
pub fn push_loss(setup: &Setup) -> Loss {
    let bx = setup.link("box");
    let finger = setup.link("pusher");
    Loss {
        terms: vec![
            LossTerm::LinkPoint {
                link: bx,
                point: Vector3::new(0.1, 0.1, 0.1),
                target: Vector3::new(0.2, 0.1, 0.3),
                weight: 1.0,
                when: When::Final,
            },
            LossTerm::CenterOfMass {
                links: vec![bx],
                target: Vector3::new(0.03, 0.01, 0.0),
                axes: Vector3::new(1.0, 1.0, 0.0),
                weight: 2.0,
                when: When::Running,
            },
            LossTerm::Relative {
                link_a: bx,
                point_a: Vector3::new(-0.1, 0.05, 0.15),
                link_b: finger,
                point_b: Vector3::new(0.0, 0.0, 0.0),
                offset: Vector3::new(0.01, 0.02, 0.0),
                weight: 3.0,
                when: When::Final,
            },
            LossTerm::Joint {
                dof: setup.model.links[finger].dof_offset,
                target: 0.05,
                weight: 0.5,
                when: When::Running,
            },
        ],
    }
}
