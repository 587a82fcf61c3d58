//! IPC's lagged friction term (Li et al. 2020, §5) behind [`Energy`]:
//! `Σ_c μ λ_c f₀(‖T_cᵀ Σ_k w_ck (X_k − X_k^t)‖)` over the contacts active at
//! the start of the step (`d < d̂²` at `A^t`), with `λ_c`, `w_c` (closest
//! points) and `T_c` (tangent basis) lagged there ([`crate::friction_stencil`]).
//! The lagged normal force is the barrier's: `λ = κ |∂b/∂d| · 2√d` (N).
//! Pose-space chain rule as in [`crate::pair`].

use crate::barrier::barrier_derivative;
use crate::broad_phase::{Candidates, PrimitiveBoxes, candidates};
use crate::distance::closest_weights;
use crate::friction_stencil::{FrictionStencil, tangent_basis};
use crate::mesh::LinkMesh;
use crate::pair::{PairGeometry, PairHessian};
use crate::primitive::stencil_distance;
use nalgebra::{DVector, Matrix3x4, Vector3};
use sdrs::energy::pairs::scatter_pair;
use sdrs::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use sdrs::kinematics::Kinematics;
use sdrs::model::Model;

/// Friction parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct IpcFrictionParams {
    pub dhat: f64,
    /// Barrier stiffness (J/m⁴), for the lagged normal force.
    pub kappa: f64,
    pub mu: f64,
    /// Smoothing speed `ε_v` (m/s); the displacement threshold is `ε_v Δt`.
    pub eps_v: f64,
    pub dt: f64,
}

/// One lagged contact: link pair index, stencil `(side, vertex)` and data.
#[derive(Clone, Debug)]
struct Contact {
    pair: usize,
    ids: StencilIds,
    stencil: FrictionStencil,
}

/// The friction term.
pub struct IpcFriction {
    pub params: IpcFrictionParams,
    meshes: Vec<LinkMesh>,
    link_pairs: Vec<(usize, usize)>,
    world_prev: Vec<Vec<Vector3<f64>>>,
    world: Vec<Vec<Vector3<f64>>>,
    contacts: Vec<Contact>,
    /// Whether `κ` is the scene's `contact.kappa` (then `∂Φ/∂κ` goes to the
    /// physical gradient); false when the baseline chose it.
    pub kappa_given: bool,
}

impl IpcFriction {
    pub fn new(
        model: &Model,
        meshes: Vec<LinkMesh>,
        excluded: &std::collections::BTreeSet<(usize, usize)>,
        params: IpcFrictionParams,
    ) -> Self {
        let c = crate::contact::IpcContact::new(
            model,
            meshes.clone(),
            excluded,
            crate::contact::IpcParams {
                dhat: params.dhat,
                kappa: params.kappa,
                ccd: Default::default(),
            },
        );
        let world: Vec<Vec<Vector3<f64>>> = meshes
            .iter()
            .map(|m| vec![Vector3::zeros(); m.x_local.len()])
            .collect();
        IpcFriction {
            params,
            link_pairs: c.link_pairs.clone(),
            world_prev: world.clone(),
            world,
            meshes,
            contacts: Vec::new(),
            kappa_given: true,
        }
    }

    /// Number of lagged contacts of the current step.
    pub fn contact_count(&self) -> usize {
        self.contacts.len()
    }
}

/// A stencil's `(side, vertex)` ids.
pub type StencilIds = [(usize, u32); 4];

/// IPC's lagged friction contacts of one link pair: every candidate stencil
/// with `0 < d < d̂²` at the step-`t` world vertices `geo.world`, with its
/// closest-point weights, tangent basis and `μ λ` (`λ = κ |∂b/∂d| · 2√d`).
pub fn lag_pair(
    geo: &PairGeometry<'_>,
    cand: &Candidates,
    p: &IpcFrictionParams,
    out: &mut Vec<(StencilIds, FrictionStencil)>,
) {
    let dhat2 = p.dhat * p.dhat;
    geo.for_each_stencil(cand, |kind, ids| {
        let x = ids.map(|(s, i)| {
            let v = geo.world[s][i as usize];
            [v.x, v.y, v.z]
        });
        let (d, ty) = stencil_distance(kind, &x);
        if !(d > 0.0 && d < dhat2) {
            return;
        }
        let w = closest_weights(&x, ty);
        let v: Vector3<f64> = (0..4).map(|j| Vector3::from(x[j]) * w[j]).sum();
        let lambda = p.kappa * barrier_derivative(d, dhat2).abs() * 2.0 * d.sqrt();
        out.push((
            ids,
            FrictionStencil {
                w,
                basis: tangent_basis(&(v / v.norm())),
                mu_lambda: p.mu * lambda,
            },
        ));
    });
}

/// The fixed pieces of a lagged stencil for its adjoint
/// ([`crate::adjoint_stencil::friction_vjp`]): the distance type and
/// tangent axis that [`lag_pair`] chose at the lagged points `xp`. A
/// point–triangle stencil has one point on one side and three on the other;
/// an edge–edge stencil two and two.
pub fn lag_piece(
    ids: &StencilIds,
    xp: &[crate::distance::vec::V3<f64>; 4],
    p: &IpcFrictionParams,
) -> crate::adjoint_stencil::FrictionPiece {
    let kind = if ids[0].0 == ids[1].0 {
        crate::primitive::PrimitiveKind::EdgeEdge { eps_x: 0.0 }
    } else {
        crate::primitive::PrimitiveKind::PointTriangle
    };
    let (_, ty) = stencil_distance(kind, xp);
    let w = closest_weights(xp, ty);
    let v: Vector3<f64> = (0..4).map(|j| Vector3::from(xp[j]) * w[j]).sum();
    crate::adjoint_stencil::FrictionPiece {
        ty,
        axis: crate::friction_stencil::tangent_axis(&(v / v.norm())),
        dhat2: p.dhat * p.dhat,
        kappa: p.kappa,
        mu: p.mu,
        eps: p.eps_v * p.dt,
    }
}

/// `Σ_c D_c` over the lagged contacts of one link pair at the step-`t+1`
/// world vertices `world` (step-`t` ones in `world_prev`), `ε = ε_v Δt`;
/// with `derivs`, adds `∂D/∂A_a`, `∂D/∂A_b` into `grad` and, when given, the
/// 24×24 pose-space Hessian into `hess`. Returns the value (J).
// Arguments kept separate: one pair's stencils, meshes, previous/current vertices and the two outputs, in the friction term's inner loop.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_pair_friction<'c>(
    contacts: impl Iterator<Item = (&'c StencilIds, &'c FrictionStencil)>,
    meshes: [&LinkMesh; 2],
    world_prev: [&Vec<Vector3<f64>>; 2],
    world: [&Vec<Vector3<f64>>; 2],
    eps: f64,
    derivs: bool,
    grad: (&mut Matrix3x4<f64>, &mut Matrix3x4<f64>),
    mut hess: Option<&mut PairHessian>,
) -> f64 {
    let (ga, gb) = grad;
    let mut value = 0.0;
    for (ids, stencil) in contacts {
        let dx = ids.map(|(s, i)| world[s][i as usize] - world_prev[s][i as usize]);
        let (val, g, hs) = stencil.evaluate(&dx, eps, derivs);
        value += val;
        if derivs {
            let loc = ids.map(|(s, i)| meshes[s].x_local[i as usize].push(1.0));
            let side = ids.map(|(s, _)| s);
            crate::pair::chain_to_poses(&g, &hs, &side, &loc, ga, gb, hess.as_deref_mut());
        }
    }
    value
}

fn transform(meshes: &[LinkMesh], pose: &[sdrs::math::Pose], out: &mut [Vec<Vector3<f64>>]) {
    for (i, m) in meshes.iter().enumerate() {
        for (w, x) in out[i].iter_mut().zip(&m.x_local) {
            *w = sdrs::math::transform_point(&pose[i], x);
        }
    }
}

impl Energy for IpcFriction {
    fn name(&self) -> &'static str {
        "ipc_friction"
    }

    fn kind(&self) -> sdrs::energy::TermKind {
        sdrs::energy::TermKind::Friction
    }

    fn begin_step(&mut self, ctx: &StepContext, _kin_prev: &Kinematics) -> Result<(), EnergyError> {
        transform(&self.meshes, ctx.poses_prev, &mut self.world_prev);
        let p = &self.params;
        let mut boxes = vec![PrimitiveBoxes::default(); self.meshes.len()];
        let world = &self.world_prev;
        crate::broad_phase::build_for_pairs(&mut boxes, &self.meshes, &self.link_pairs, |i| {
            (&world[i][..], None, 0.5 * p.dhat)
        });
        self.contacts.clear();
        let mut cand = Candidates::default();
        let mut lagged = Vec::new();
        for (k, &(a, b)) in self.link_pairs.iter().enumerate() {
            candidates(&boxes[a], &boxes[b], &mut cand);
            let geo = PairGeometry {
                mesh: [&self.meshes[a], &self.meshes[b]],
                world: [&self.world_prev[a], &self.world_prev[b]],
            };
            lagged.clear();
            lag_pair(&geo, &cand, p, &mut lagged);
            self.contacts
                .extend(lagged.drain(..).map(|(ids, stencil)| Contact {
                    pair: k,
                    ids,
                    stencil,
                }));
        }
        Ok(())
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        if self.contacts.is_empty() {
            return Ok(());
        }
        transform(&self.meshes, &kin.pose, &mut self.world);
        let eps = self.params.eps_v * self.params.dt;
        let derivs = need >= Need::Gradient;
        let mut k = 0;
        while k < self.contacts.len() {
            let pair = self.contacts[k].pair;
            let (la, lb) = self.link_pairs[pair];
            let (mut ga, mut gb) = (Matrix3x4::zeros(), Matrix3x4::zeros());
            let mut h = (need >= Need::Hessian).then(|| Box::new(PairHessian::zeros()));
            let start = k;
            while k < self.contacts.len() && self.contacts[k].pair == pair {
                k += 1;
            }
            let geo_prev = [&self.world_prev[la], &self.world_prev[lb]];
            let geo = [&self.world[la], &self.world[lb]];
            acc.value += evaluate_pair_friction(
                self.contacts[start..k].iter().map(|c| (&c.ids, &c.stencil)),
                [&self.meshes[la], &self.meshes[lb]],
                geo_prev,
                geo,
                eps,
                derivs,
                (&mut ga, &mut gb),
                h.as_deref_mut(),
            );
            if derivs {
                scatter_pair(
                    ctx.model,
                    acc,
                    need,
                    (la, lb),
                    1.0,
                    (&ga, &gb),
                    h.as_deref(),
                );
            }
        }
        Ok(())
    }

    /// Adjoint product (see [`crate::adjoint_stencil::friction_vjp`]): per
    /// lagged contact, `∂Φ/∂X` (step `t+1`) and `∂Φ/∂Xᵗ` (step `t`, through
    /// the displacement and the lagged `λ`, `w`, `T`) into pose, lagged-pose
    /// and hull-vertex space; `∂Φ/∂μ = Φ/μ`, and `∂Φ/∂κ = Φ/κ` when `κ` is
    /// the scene's. `begin_step` has run for this step (the lagged set).
    fn vjp(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        dir: &sdrs::diff::AdjointDirection,
        out: &mut sdrs::diff::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let p = &self.params;
        let poses = crate::adjoint::PoseSet {
            pose: &kin.pose,
            dpose: dir.dpose,
            prev: ctx.poses_prev,
        };
        for c in &self.contacts {
            let (la, lb) = self.link_pairs[c.pair];
            let st = crate::adjoint::StencilRef {
                ids: c.ids,
                links: [la, lb],
                meshes: [&self.meshes[la], &self.meshes[lb]],
            };
            let x = st.points(&kin.pose);
            let xp = st.points(ctx.poses_prev);
            let dx = crate::adjoint::directions(&st, dir.dpose);
            let piece = lag_piece(&c.ids, &xp, p);
            let v = crate::adjoint_stencil::friction_vjp(&x, &xp, &dx, &piece);
            out.physical.mu += v.phi / p.mu;
            if self.kappa_given {
                out.physical.kappa += v.phi / p.kappa;
            }
            crate::adjoint::scatter(&st, &poses, &v, 1.0, out);
        }
        Ok(())
    }
}
