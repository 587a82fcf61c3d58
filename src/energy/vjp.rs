//! Adjoint products of the step residual (per energy term).
//!
//! With `g_t = ∇_θ O_t(θ^t; θ^{t−1}, θ^{t−2}, u, d, φ) = 0` and an adjoint
//! vector `λ`, the backward pass needs `(∂g_t/∂x)ᵀ λ = ∂Φ/∂x` for every
//! quantity `x` the residual depends on besides `θ^t`, where
//! `Φ = λᵀ g_t = Σ_i ⟨δA_i, ∂E/∂A_i⟩ + λᵀ ∂E/∂θ|direct` and
//! `δA_i = Σ_k λ_k ∂A_i/∂θ_k` is the pose-space direction of `λ`.
//! Each term adds its part of `∂Φ/∂x` into a [`VjpAccumulator`].

use crate::math::Pose;
use crate::model::Model;
use nalgebra::{DVector, Matrix3x4, Vector3};

/// The direction `λ` and its pose-space image `δA_i` at `θ^t`.
pub struct AdjointDirection<'a> {
    pub lambda: &'a DVector<f64>,
    pub dpose: &'a [Pose],
}

/// Gradients of a physical parameter set (all scene-wide).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhysicalGrad {
    /// `∂/∂ρ` for a scale factor `ρ` multiplying every vertex mass (at `ρ = 1`).
    pub mass_scale: f64,
    /// `∂/∂g` (gravity vector, m/s²).
    pub gravity: [f64; 3],
    /// `∂/∂μ` (friction coefficient).
    pub mu: f64,
    /// `∂/∂s` (barrier support).
    pub s: f64,
    /// `∂/∂κ` (barrier stiffness).
    pub kappa: f64,
}

impl PhysicalGrad {
    pub fn axpy(&mut self, a: f64, o: &PhysicalGrad) {
        self.mass_scale += a * o.mass_scale;
        for e in 0..3 {
            self.gravity[e] += a * o.gravity[e];
        }
        self.mu += a * o.mu;
        self.s += a * o.s;
        self.kappa += a * o.kappa;
    }
}

/// `∂Φ/∂x` buffers for one step.
#[derive(Clone, Debug)]
pub struct VjpAccumulator {
    /// `∂Φ/∂A_i^t` at fixed `δA` (a pose-space Hessian–vector product).
    pub pose: Vec<Matrix3x4<f64>>,
    /// `∂Φ/∂A_i^{t−1}`.
    pub pose_prev: Vec<Matrix3x4<f64>>,
    /// `∂Φ/∂A_i^{t−2}`.
    pub pose_prev2: Vec<Matrix3x4<f64>>,
    /// `∂Φ/∂θ^{t−1}` from terms written in coordinates.
    pub q_prev: DVector<f64>,
    /// `∂Φ/∂θ^{t−2}` from terms written in coordinates (armature).
    pub q_prev2: DVector<f64>,
    /// `∂Φ/∂x_local` per link, hull, vertex (link frame).
    pub vertex: Vec<Vec<Vec<Vector3<f64>>>>,
    /// `∂Φ/∂s` per link and contact-surface vertex
    /// ([`crate::model::Link::surface`]; empty for links without one).
    pub surface: Vec<Vec<Vector3<f64>>>,
    /// Whether vertex gradients are wanted (terms may skip them otherwise).
    pub want_vertices: bool,
    /// `(∂Φ/∂θ*, ∂Φ/∂θ̇*, ∂Φ/∂k_p, ∂Φ/∂k_d)` per controller channel.
    pub channels: Vec<[f64; 4]>,
    pub physical: PhysicalGrad,
    /// `∂Φ/∂p_j` for the parameters of calibration effects installed as
    /// energy terms (`crate::calibrate::effects`), indexed by each effect's
    /// parameter slot; grown on demand by [`VjpAccumulator::effect`].
    pub effects: Vec<f64>,
    /// Quantities some term could not differentiate (a term without a `vjp`
    /// names itself);
    /// gradients that depend on them are not reported.
    pub unavailable: Vec<&'static str>,
}

impl VjpAccumulator {
    pub fn new(model: &Model, nchannels: usize) -> Self {
        let n = model.links.len();
        VjpAccumulator {
            pose: vec![Matrix3x4::zeros(); n],
            pose_prev: vec![Matrix3x4::zeros(); n],
            pose_prev2: vec![Matrix3x4::zeros(); n],
            q_prev: DVector::zeros(model.ndof()),
            q_prev2: DVector::zeros(model.ndof()),
            vertex: model
                .links
                .iter()
                .map(|l| {
                    l.hulls
                        .iter()
                        .map(|h| vec![Vector3::zeros(); h.x_local.len()])
                        .collect()
                })
                .collect(),
            surface: model
                .links
                .iter()
                .map(|l| vec![Vector3::zeros(); l.surface.len()])
                .collect(),
            want_vertices: true,
            channels: vec![[0.0; 4]; nchannels],
            physical: PhysicalGrad::default(),
            effects: Vec::new(),
            unavailable: Vec::new(),
        }
    }

    pub fn reset(&mut self) {
        for v in [&mut self.pose, &mut self.pose_prev, &mut self.pose_prev2] {
            v.iter_mut().for_each(|g| g.fill(0.0));
        }
        self.q_prev.fill(0.0);
        self.q_prev2.fill(0.0);
        self.effects.fill(0.0);
        self.vertex
            .iter_mut()
            .flatten()
            .flatten()
            .for_each(|g| g.fill(0.0));
        self.surface.iter_mut().flatten().for_each(|g| g.fill(0.0));
        self.channels.iter_mut().for_each(|c| *c = [0.0; 4]);
        self.physical = PhysicalGrad::default();
    }
}

impl VjpAccumulator {
    /// The entry `∂Φ/∂p_slot` of the effect-parameter channel (grown with
    /// zeros when `slot` is new).
    pub fn effect(&mut self, slot: usize) -> &mut f64 {
        if self.effects.len() <= slot {
            self.effects.resize(slot + 1, 0.0);
        }
        &mut self.effects[slot]
    }
}
