//! The backward (adjoint) pass over a recorded trajectory.

use super::loss::{LevelGrad, Loss};
use super::tape::Tape;
use super::vjp::{AdjointDirection, PhysicalGrad, VjpAccumulator};
use crate::energy::EnergyError;
use crate::kinematics::{KinOrder, Kinematics};
use crate::math::{Pose, rot};
use crate::model::Model;
use crate::sim::Simulator;
use crate::sim::assemble::contract_gradient;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x4, Vector3};
use std::time::Instant;

/// Gradient of one controller channel.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ChannelGrad {
    pub kp: f64,
    pub kd: f64,
    /// W.r.t. the channel's actuation delay `d`:
    /// `Σ_t (∂Φ_t/∂θ* θ̇*(t − d) + ∂Φ_t/∂θ̇* θ̈*(t − d))` (the signal is read
    /// at `t − d`, so `∂θ*/∂d = −θ̇*`, `∂θ̇*/∂d = −θ̈*`).
    pub delay: f64,
    /// W.r.t. the signal's parameters ([`crate::control::Signal::params`]).
    pub signal: Vec<f64>,
}

/// `dL/d·` for everything the trajectory depends on.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Gradients {
    pub loss: f64,
    /// `dL/dθ^0` (charted rotations: body-frame rotation vector at `θ^0`).
    pub q0: DVector<f64>,
    /// `dL/dθ̇^0`.
    pub qdot0: DVector<f64>,
    /// `dL/dt_c` for every link's attachment point (parent frame; world for
    /// roots).
    pub attachments: Vec<Vector3<f64>>,
    /// `dL/dx_local` per link, hull, vertex (link frame).
    pub vertices: Vec<Vec<Vec<Vector3<f64>>>>,
    /// `dL/ds` per link and contact-surface vertex
    /// ([`crate::model::Link::surface`]; empty for links without one).
    pub surface: Vec<Vec<Vector3<f64>>>,
    /// Per controller channel.
    pub channels: Vec<ChannelGrad>,
    pub physical: PhysicalGrad,
    /// `dL/dp_j` for the parameters of calibration effects installed as
    /// energy terms, by parameter slot (see
    /// [`super::vjp::VjpAccumulator::effects`]); empty without such terms.
    pub effects: Vec<f64>,
    /// Quantities some term could not differentiate; gradients that depend
    /// on them are incomplete (see [`super::vjp::VjpAccumulator::unavailable`]).
    pub unavailable: Vec<&'static str>,
    /// Wall time of the backward pass (s).
    pub seconds: f64,
}

/// Why the backward pass failed.
#[derive(Debug, thiserror::Error)]
pub enum BackwardError {
    #[error("backward pass at step {step}: {source}")]
    Energy {
        step: usize,
        #[source]
        source: EnergyError,
    },
    #[error("backward pass at step {step}: the step Hessian is singular")]
    Singular { step: usize },
    #[error("no gradient through {what}: not yet differentiable")]
    Unavailable { what: String },
}

/// Adds `sign · Σ_{i∈subtree(c)} R_λ(c)ᵀ P_i[:, 3]` to every attachment
/// gradient: `∂A_i/∂t_c = [0 | R_λ(c) e] Ã_i` (a world translation).
fn add_attachment(
    model: &Model,
    kin: &Kinematics,
    p: &[Matrix3x4<f64>],
    sign: f64,
    out: &mut [Vector3<f64>],
) {
    let n = model.links.len();
    let mut force: Vec<Vector3<f64>> = p.iter().map(|g| g.column(3).into_owned()).collect();
    for i in (0..n).rev() {
        if let Some(par) = model.links[i].parent {
            let f = force[i];
            force[par] += f;
        }
    }
    for c in 0..n {
        let r = model.links[c]
            .parent
            .map_or_else(Matrix3::identity, |par| rot(&kin.pose[par]));
        out[c] += sign * r.transpose() * force[c];
    }
}

/// Runs the adjoint pass for `loss` over `tape`, using `sim`'s model,
/// controller and energy terms (the simulator's state is overwritten).
///
/// Stages: the loss at every level 0 … H; then for t = H … 1 the adjoint
/// solve `λ_t = H_t⁻¹ ā_t` ([`solve_adjoint`]), its pose-space direction
/// ([`pose_direction`]), the terms' vector–Jacobian products and their
/// subtraction from the design and parameter gradients ([`subtract_step`]),
/// and the pending gradients of the two earlier levels; finally levels 0 and
/// −1 onto the initial state ([`initial_state`]).
pub fn backward(sim: &mut Simulator, tape: &Tape, loss: &Loss) -> Result<Gradients, BackwardError> {
    let t0 = Instant::now();
    let model = sim.model.clone();
    let n = model.ndof();
    let nl = model.links.len();
    let h = tape.len();
    let nch = sim.controller.channels.len();
    let mut g = zero_gradients(&model, sim);
    // Pending pose-space and coordinate gradients per time level −1 … H
    // (index k + 1).
    let mut pose_lvl: Vec<Vec<Pose>> = (0..h + 2).map(|_| vec![Matrix3x4::zeros(); nl]).collect();
    let mut q_lvl: Vec<DVector<f64>> = (0..h + 2).map(|_| DVector::zeros(n)).collect();
    let mut kin_k = Kinematics::new(&model);

    // Loss at every recorded level 0 … H.
    for k in 0..=h {
        let (q, charts) = tape.coords(k as isize);
        kin_k.update(&model, q, charts, KinOrder::Pose);
        let mut lg = LevelGrad {
            pose: &mut pose_lvl[k + 1],
            q: &mut q_lvl[k + 1],
            vertex: &mut g.vertices,
        };
        g.loss += loss.eval_level(&model, k, h, &kin_k.pose, q, Some(&mut lg));
    }

    let mut acc = VjpAccumulator::new(&model, nch);
    let mut dpose = vec![Matrix3x4::<f64>::zeros(); nl];
    let mut linear = crate::sim::linear_solve::BlockSolver::default();
    for t in (1..=h).rev() {
        let rec = &tape.steps[t - 1];
        let err = |source| BackwardError::Energy { step: t, source };
        let (_, hess) = sim.linearize(&rec.before, &rec.q_new).map_err(err)?;
        // ā_t and λ_t = H_t⁻¹ ā_t.
        let kin = sim.kinematics().clone();
        let abar = contract_gradient(&model, &kin, &pose_lvl[t + 1]) + &q_lvl[t + 1];
        add_attachment(&model, &kin, &pose_lvl[t + 1], 1.0, &mut g.attachments);
        let lambda = solve_adjoint(&mut linear, &hess, &abar, t)?;
        let s_acc = kin.pose_direction(&model, &lambda, &mut dpose);
        second_order_attachment(
            &model,
            &kin,
            &s_acc,
            sim.pose_gradients(),
            &mut g.attachments,
        );
        acc.reset();
        let dir = AdjointDirection {
            lambda: &lambda,
            dpose: &dpose,
        };
        sim.vjp(&rec.q_new, &dir, &mut acc).map_err(err)?;
        subtract_step(&mut g, &mut acc, &model, &kin, sim, t as f64 * tape.dt);
        // Earlier levels: ā_{t−1}, ā_{t−2} −= (∂g_t/∂θ^{t−1,t−2})ᵀ λ_t.
        for (gl, al) in pose_lvl[t].iter_mut().zip(&acc.pose_prev) {
            *gl -= al;
        }
        for (gl, al) in pose_lvl[t - 1].iter_mut().zip(&acc.pose_prev2) {
            *gl -= al;
        }
        q_lvl[t] -= &acc.q_prev;
        q_lvl[t - 1] -= &acc.q_prev2;
    }
    initial_state(&model, tape, &mut kin_k, &pose_lvl, &q_lvl, &mut g);
    g.seconds = t0.elapsed().as_secs_f64();
    Ok(g)
}

/// Zero gradients shaped like `model`'s design and `sim`'s controller.
fn zero_gradients(model: &Model, sim: &Simulator) -> Gradients {
    let n = model.ndof();
    let nl = model.links.len();
    Gradients {
        q0: DVector::zeros(n),
        qdot0: DVector::zeros(n),
        attachments: vec![Vector3::zeros(); nl],
        vertices: model
            .links
            .iter()
            .map(|l| {
                l.hulls
                    .iter()
                    .map(|hh| vec![Vector3::zeros(); hh.x_local.len()])
                    .collect()
            })
            .collect(),
        surface: model
            .links
            .iter()
            .map(|l| vec![Vector3::zeros(); l.surface.len()])
            .collect(),
        channels: sim
            .controller
            .channels
            .iter()
            .map(|c| ChannelGrad {
                kp: 0.0,
                kd: 0.0,
                signal: vec![0.0; c.signal.nparams()],
                delay: 0.0,
            })
            .collect(),
        ..Default::default()
    }
}

/// `λ_t = H_t⁻¹ ā_t`. The forward pass never factors this matrix (Newton
/// stops at the first iterate whose gradient is below tolerance, before
/// factoring its Hessian), so there is no factorization to reuse:
/// block-wise Cholesky (faer), pivoted LU when a block is not positive
/// definite.
fn solve_adjoint(
    linear: &mut crate::sim::linear_solve::BlockSolver,
    hess: &DMatrix<f64>,
    abar: &DVector<f64>,
    t: usize,
) -> Result<DVector<f64>, BackwardError> {
    let mut lambda = DVector::zeros(abar.len());
    if !linear.spd_solve(hess, abar, &mut lambda) {
        lambda = hess
            .clone()
            .lu()
            .solve(abar)
            .ok_or(BackwardError::Singular { step: t })?;
    }
    Ok(lambda)
}

/// Second-order kinematic part of the attachment gradient:
/// `−Σ_{k ∈ anc(parent(c))} λ_k R_pᵀ S_k[:, :3]ᵀ Σ_{i∈subtree(c)} G_i[:, 3]`
/// (`G`: the step's pose gradients).
fn second_order_attachment(
    model: &Model,
    kin: &Kinematics,
    s_acc: &[Matrix3x4<f64>],
    pose_grad: &[Matrix3x4<f64>],
    attachments: &mut [Vector3<f64>],
) {
    let nl = model.links.len();
    let mut force: Vec<Vector3<f64>> = pose_grad
        .iter()
        .map(|gg| gg.column(3).into_owned())
        .collect();
    for i in (0..nl).rev() {
        if let Some(par) = model.links[i].parent {
            let f = force[i];
            force[par] += f;
        }
    }
    for (c, (link, f)) in model.links.iter().zip(&force).enumerate() {
        if let Some(par) = link.parent {
            let r = rot(&kin.pose[par]);
            let sl = s_acc[par].fixed_view::<3, 3>(0, 0).into_owned();
            attachments[c] -= r.transpose() * sl.transpose() * f;
        }
    }
}

/// Design and parameters of one step: `dL/dp −= (∂Φ/∂p)ᵀ λ_t` from the
/// terms' products in `acc` (attachments, vertices, surfaces, controller
/// channels at time `time`, physical parameters, effects).
fn subtract_step(
    g: &mut Gradients,
    acc: &mut VjpAccumulator,
    model: &Model,
    kin: &Kinematics,
    sim: &Simulator,
    time: f64,
) {
    for u in acc.unavailable.drain(..) {
        if !g.unavailable.contains(&u) {
            g.unavailable.push(u);
        }
    }
    add_attachment(model, kin, &acc.pose, -1.0, &mut g.attachments);
    let vertices = g.vertices.iter_mut().flatten().flatten();
    for (gl, al) in vertices.zip(acc.vertex.iter().flatten().flatten()) {
        *gl -= al;
    }
    for (gl, al) in g
        .surface
        .iter_mut()
        .flatten()
        .zip(acc.surface.iter().flatten())
    {
        *gl -= al;
    }
    for (ch, (cg, a)) in g.channels.iter_mut().zip(&acc.channels).enumerate() {
        cg.kp -= a[2];
        cg.kd -= a[3];
        let c = &sim.controller.channels[ch];
        let td = time - c.delay;
        cg.delay += a[0] * c.signal.eval(td).1 + a[1] * c.signal.accel(td);
        let (dv, dd) = c.signal.param_grad(td);
        for (k, sg) in cg.signal.iter_mut().enumerate() {
            *sg -= a[0] * dv[k] + a[1] * dd[k];
        }
    }
    g.physical.axpy(-1.0, &acc.physical);
    if g.effects.len() < acc.effects.len() {
        g.effects.resize(acc.effects.len(), 0.0);
    }
    for (gl, al) in g.effects.iter_mut().zip(&acc.effects) {
        *gl -= al;
    }
}

/// Levels 0 and −1 map onto the initial state: `θ^{−1} = θ^0 − Δt θ̇^0`.
fn initial_state(
    model: &Model,
    tape: &Tape,
    kin_k: &mut Kinematics,
    pose_lvl: &[Vec<Pose>],
    q_lvl: &[DVector<f64>],
    g: &mut Gradients,
) {
    for k in [0isize, -1] {
        let (q, charts) = tape.coords(k);
        kin_k.update(model, q, charts, KinOrder::First);
        let lvl = (k + 1) as usize;
        let abar = contract_gradient(model, kin_k, &pose_lvl[lvl]) + &q_lvl[lvl];
        add_attachment(model, kin_k, &pose_lvl[lvl], 1.0, &mut g.attachments);
        g.q0 += &abar;
        if k == -1 {
            g.qdot0 = -tape.dt * abar;
        }
    }
}

/// The loss of a recorded trajectory (forward only).
pub fn loss_of(model: &Model, tape: &Tape, loss: &Loss) -> f64 {
    let mut kin = Kinematics::new(model);
    (0..=tape.len())
        .map(|k| {
            let (q, charts) = tape.coords(k as isize);
            kin.update(model, q, charts, KinOrder::Pose);
            loss.eval_level(model, k, tape.len(), &kin.pose, q, None)
        })
        .sum()
}
