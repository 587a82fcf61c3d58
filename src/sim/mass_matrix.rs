//! Joint-space mass matrix of the position-level model.
//!
//! The inertia term (`crate::energy::inertia`) is
//! `I(θ) = Σ_i tr(D_i M_i D_iᵀ)/(2Δt²)`, `D_i = A_i(θ) − 2A_i^t + A_i^{t−1}`.
//! At zero velocity (`A_i^t = A_i^{t−1} = A_i(θ)`) `D_i = 0`, so the terms
//! with second derivatives of `A_i` drop out of its Hessian:
//! `∂²I/∂θ_k∂θ_l = Σ_i ⟨∂_k A_i M_i, ∂_l A_i⟩/Δt²`. Times `Δt²` this is
//! `H_kl(θ) = Σ_i tr(∂_k A_i M_i ∂_l A_iᵀ)`, the matrix of the kinetic
//! energy `T = ½ Σ_i tr(Ȧ_i M_i Ȧ_iᵀ) = ½ θ̇ᵀ H θ̇` — the joint-space mass
//! matrix (kg m², kg m, kg by coordinate type) that rigid-body codes compute
//! by CRBA. It is computed here by the simulator's own assembler
//! (`assemble`, subtree composites `Σ Ã_i M_i Ã_iᵀ`) fed with the links'
//! second moments `M_i` only, i.e. exactly the inertia term's Hessian at
//! `Δt = 1` and zero velocity.

use super::assemble::assemble_hessian;
use crate::energy::EnergyAccumulator;
use crate::kinematics::{KinOrder, Kinematics};
use crate::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3};

/// `H(θ)` (|θ|×|θ|, symmetric) at coordinates `q` with chart centres
/// `charts` (one per spherical/free joint).
pub fn mass_matrix(model: &Model, q: &DVector<f64>, charts: &[Matrix3<f64>]) -> DMatrix<f64> {
    let mut kin = Kinematics::new(model);
    kin.update(model, q, charts, KinOrder::Second);
    let mut acc = EnergyAccumulator::new(model);
    for (m, w) in acc.link_moment.iter_mut().zip(&model.second_moment) {
        *m = *w;
    }
    acc.link_moment_set = true;
    assemble_hessian(model, &kin, &acc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::path::Path;

    /// A point mass `m` at distance `r` on a hinge: `H = m r²`; two links:
    /// the textbook double-pendulum matrix.
    #[test]
    fn double_pendulum_of_given_point_masses() {
        let text = r#"
dt: 0.01
robots:
  - name: p
    links:
      - name: a
        joint: {type: revolute, axis: [0, 1, 0]}
        mass_model: {type: given, mass: 2.0, com: [0.5, 0, 0], inertia: [0, 0, 0, 0, 0, 0]}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
      - name: b
        parent: a
        joint: {type: revolute, axis: [0, 1, 0], origin: {xyz: [0.5, 0, 0]}}
        mass_model: {type: given, mass: 3.0, com: [0.7, 0, 0], inertia: [0, 0, 0, 0, 0, 0]}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
"#;
        let s = Scene::from_str(text, Path::new("p.yaml")).unwrap();
        for q2 in [0.0, 0.4, -1.3] {
            let q = DVector::from_vec(vec![0.3, q2]);
            let h = mass_matrix(&s.model, &q, &[]);
            let (m1, m2, l1, r1, r2) = (2.0, 3.0, 0.5, 0.5, 0.7);
            let c = f64::cos(q2);
            let h11 = m1 * r1 * r1 + m2 * (l1 * l1 + r2 * r2 + 2.0 * l1 * r2 * c);
            let h12 = m2 * (r2 * r2 + l1 * r2 * c);
            let want = DMatrix::from_row_slice(2, 2, &[h11, h12, h12, m2 * r2 * r2]);
            assert!((&h - &want).norm() < 1e-12, "{q2}: {h} vs {want}");
        }
    }
}
