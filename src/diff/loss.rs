//! Trajectory losses: weighted squared errors of joint states, link points,
//! centres of mass and relative positions, at the final time or averaged
//! over every step.

use crate::math::{Pose, rot, transform_point};
use crate::model::Model;
use nalgebra::{DVector, Matrix3x4, Matrix4, Vector3, Vector4};

/// When a term applies.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum When {
    /// At `θ^H` only.
    Final,
    /// Mean over `θ^1 … θ^H`.
    Running,
    /// A stage (YAML `when: {window: {from: a, to: b}}`): mean over
    /// `θ^{a+1} … θ^b` (`0 ≤ a < b ≤ H`, checked when a task is loaded);
    /// `{from: b−1, to: b}` is the value at `θ^b` alone.
    Window {
        /// First step `a` (exclusive).
        from: usize,
        /// Last step `b` (inclusive).
        to: usize,
    },
}

impl When {
    /// Weight of time level `k` (of `H`) in the term: `1` at `H` for
    /// `final`, `1/H` for `k ≥ 1` when `running`, `1/(b − a)` for
    /// `a < k ≤ b` in a window, else `0`.
    pub fn scale(&self, k: usize, horizon: usize) -> f64 {
        match *self {
            When::Final if k == horizon => 1.0,
            When::Running if k >= 1 => 1.0 / horizon as f64,
            When::Window { from, to } if from < k && k <= to => 1.0 / (to - from) as f64,
            _ => 0.0,
        }
    }
}

/// One loss term; each is `weight · ‖e‖²`.
#[derive(Clone, Debug, PartialEq)]
pub enum LossTerm {
    /// `e = θ_k − target`.
    Joint {
        dof: usize,
        target: f64,
        weight: f64,
        when: When,
    },
    /// `e = A_link [p; 1] − target` (world).
    LinkPoint {
        link: usize,
        point: Vector3<f64>,
        target: Vector3<f64>,
        weight: f64,
        when: When,
    },
    /// `e = (Σ_i A_i c_i)/(Σ m_i) − target`, masses from the hulls; `axes`
    /// masks components (e.g. `[1, 1, 0]` for horizontal only).
    CenterOfMass {
        links: Vec<usize>,
        target: Vector3<f64>,
        axes: Vector3<f64>,
        weight: f64,
        when: When,
    },
    /// A linear functional `coef · θ_dof^level` at one time level (no
    /// square): with `coef = ∂L/∂θ_dof^level` of an outer loss, its gradient
    /// w.r.t. any parameter is that loss's gradient through the trajectory
    /// (used by calibration to get `Jᵀr` of interpolated residuals).
    JointLinear { dof: usize, level: usize, coef: f64 },
    /// `e = X_a − X_b − offset` for points on two links (object relative
    /// to a gripper).
    Relative {
        link_a: usize,
        point_a: Vector3<f64>,
        link_b: usize,
        point_b: Vector3<f64>,
        offset: Vector3<f64>,
        weight: f64,
        when: When,
    },
}

/// A sum of terms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Loss {
    pub terms: Vec<LossTerm>,
}

/// Gradients of the loss at one time level.
pub struct LevelGrad<'a> {
    /// `∂L/∂A_i` (pose space).
    pub pose: &'a mut [Matrix3x4<f64>],
    /// `∂L/∂θ` (direct).
    pub q: &'a mut DVector<f64>,
    /// `∂L/∂x_local` per link, hull, vertex.
    pub vertex: &'a mut [Vec<Vec<Vector3<f64>>>],
}

impl Loss {
    /// Value at time level `k` of `H` (`k = 0 … H`) with poses `poses` and
    /// coordinates `q`; adds the gradients into `out` when given.
    pub fn eval_level(
        &self,
        model: &Model,
        k: usize,
        horizon: usize,
        poses: &[Pose],
        q: &DVector<f64>,
        mut out: Option<&mut LevelGrad>,
    ) -> f64 {
        let mut value = 0.0;
        for term in &self.terms {
            if let LossTerm::JointLinear { dof, level, coef } = term {
                if k == *level {
                    value += coef * q[*dof];
                    if let Some(o) = out.as_deref_mut() {
                        o.q[*dof] += coef;
                    }
                }
                continue;
            }
            let when = match term {
                LossTerm::Joint { when, .. }
                | LossTerm::LinkPoint { when, .. }
                | LossTerm::CenterOfMass { when, .. }
                | LossTerm::Relative { when, .. } => *when,
                LossTerm::JointLinear { .. } => continue,
            };
            let scale = when.scale(k, horizon);
            if scale == 0.0 {
                continue;
            }
            match term {
                LossTerm::JointLinear { .. } => {}
                LossTerm::Joint {
                    dof,
                    target,
                    weight,
                    ..
                } => {
                    let e = q[*dof] - target;
                    value += scale * weight * e * e;
                    if let Some(o) = out.as_deref_mut() {
                        o.q[*dof] += 2.0 * scale * weight * e;
                    }
                }
                LossTerm::LinkPoint {
                    link,
                    point,
                    target,
                    weight,
                    ..
                } => {
                    let e = transform_point(&poses[*link], point) - target;
                    value += scale * weight * e.norm_squared();
                    if let Some(o) = out.as_deref_mut() {
                        let g = 2.0 * scale * weight * e;
                        o.pose[*link] +=
                            g * Vector4::new(point.x, point.y, point.z, 1.0).transpose();
                    }
                }
                LossTerm::Relative {
                    link_a,
                    point_a,
                    link_b,
                    point_b,
                    offset,
                    weight,
                    ..
                } => {
                    let e = transform_point(&poses[*link_a], point_a)
                        - transform_point(&poses[*link_b], point_b)
                        - offset;
                    value += scale * weight * e.norm_squared();
                    if let Some(o) = out.as_deref_mut() {
                        let g = 2.0 * scale * weight * e;
                        o.pose[*link_a] +=
                            g * Vector4::new(point_a.x, point_a.y, point_a.z, 1.0).transpose();
                        o.pose[*link_b] -=
                            g * Vector4::new(point_b.x, point_b.y, point_b.z, 1.0).transpose();
                    }
                }
                LossTerm::CenterOfMass {
                    links,
                    target,
                    axes,
                    weight,
                    ..
                } => {
                    let mass: f64 = links.iter().map(|&i| model.first_moment[i][3]).sum();
                    let com: Vector3<f64> = links
                        .iter()
                        .map(|&i| poses[i] * model.first_moment[i])
                        .sum::<Vector3<f64>>()
                        / mass;
                    let e = (com - target).component_mul(axes);
                    value += scale * weight * e.norm_squared();
                    if let Some(o) = out.as_deref_mut() {
                        // ∂L/∂com = 2 w e∘axes; com = Σ A_i c_i / Σ c_i₄, so
                        // with gc = ∂L/∂com / mass: ∂L/∂A_i = gc c_iᵀ and
                        // ∂L/∂c_i = A_iᵀgc − (gc·com) e₄ (the mass term
                        // matters only where the mass depends on the design).
                        let gc = 2.0 * scale * weight * e.component_mul(axes) / mass;
                        let shift = gc.dot(&com);
                        for &i in links {
                            o.pose[i] += gc * model.first_moment[i].transpose();
                            let r = rot(&poses[i]);
                            let rg = r.transpose() * gc;
                            let t = poses[i].column(3);
                            let w1 = Vector4::new(rg.x, rg.y, rg.z, t.dot(&gc) - shift);
                            model.links[i].moments_vjp(&Matrix4::zeros(), &w1, &mut o.vertex[i]);
                        }
                    }
                }
            }
        }
        value
    }
}
