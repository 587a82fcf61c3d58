//! The IPC contact term `κ Σ_{link pairs} E_ab` ([`crate::pair`]) behind the
//! core's [`Energy`] trait, over every pair of colliding links that the
//! scene does not exclude (the same pairs the SDRS term considers).
//!
//! Stages per evaluation: world vertices `X = A x̃` → per-link primitive
//! boxes inflated by `d̂/2` → candidate primitive pairs per link pair
//! ([`crate::broad_phase`]) → barrier per candidate, link pairs in parallel
//! (rayon), reduced in link-pair order (bitwise deterministic for any thread
//! count) → scatter into pose space. A touching pair (`d ≤ 0`) makes the
//! energy `+∞`; Newton's line search never gets there anyway because
//! [`Energy::max_step`] caps every step by continuous collision detection
//! ([`crate::line_search`]).

use crate::broad_phase::{Candidates, PrimitiveBoxes};
use crate::line_search::{CcdOptions, CcdScratch, max_collision_free_step};
use crate::mesh::LinkMesh;
use crate::pair::{PairEval, PairGeometry, evaluate_pair};
use nalgebra::{DVector, Matrix3, Vector3};
use rayon::prelude::*;
use sdrs::energy::pairs::scatter_pair;
use sdrs::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use sdrs::kinematics::Kinematics;
use sdrs::model::Model;
use sdrs::sim::{Stage, StageTimers, StepDiagnostics};
use std::time::{Duration, Instant};

/// Parameters of the IPC contact term.
#[derive(Clone, Debug, PartialEq)]
pub struct IpcParams {
    /// Activation distance `d̂` (m).
    pub dhat: f64,
    /// Barrier stiffness `κ` (J/m⁴: the barrier acts on squared distances).
    pub kappa: f64,
    /// CCD settings of the line search.
    pub ccd: CcdOptions,
}

/// The IPC contact term.
pub struct IpcContact {
    pub params: IpcParams,
    pub meshes: Vec<LinkMesh>,
    /// Interacting link pairs `(a, b)`, `a < b`.
    pub link_pairs: Vec<(usize, usize)>,
    world: Vec<Vec<Vector3<f64>>>,
    boxes: Vec<PrimitiveBoxes>,
    cands: Vec<Candidates>,
    results: Vec<PairEval>,
    ccd: CcdScratch,
    time_broad: Duration,
    time_ccd: Duration,
    last_active: usize,
    last_min_distance: f64,
    /// Exact per-primitive Hessians instead of PSD-projected ones. False
    /// as constructed; [`crate::IpcFactory`] sets it from the scene's
    /// `contact.ipc.hessian` (exact by default) and always for the
    /// simulator a backward pass linearizes with.
    pub exact_hessian: bool,
    /// Whether `κ` is the scene's `contact.kappa` (then `∂Φ/∂κ` goes to the
    /// physical gradient); false when this baseline chose it.
    pub kappa_given: bool,
}

impl IpcContact {
    /// The term over `meshes` (one per link; empty for links without a
    /// surface) and the non-excluded link pairs.
    pub fn new(
        model: &Model,
        meshes: Vec<LinkMesh>,
        excluded: &std::collections::BTreeSet<(usize, usize)>,
        params: IpcParams,
    ) -> Self {
        let n = model.links.len();
        let mut link_pairs = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                let moves =
                    !model.ancestor_dofs[a].is_empty() || !model.ancestor_dofs[b].is_empty();
                if moves
                    && !meshes[a].is_empty()
                    && !meshes[b].is_empty()
                    && !excluded.contains(&(a, b))
                {
                    link_pairs.push((a, b));
                }
            }
        }
        IpcContact {
            params,
            world: meshes
                .iter()
                .map(|m| vec![Vector3::zeros(); m.x_local.len()])
                .collect(),
            boxes: vec![PrimitiveBoxes::default(); n],
            cands: vec![Candidates::default(); link_pairs.len()],
            results: Vec::new(),
            ccd: CcdScratch::default(),
            meshes,
            link_pairs,
            time_broad: Duration::ZERO,
            time_ccd: Duration::ZERO,
            last_active: 0,
            last_min_distance: f64::INFINITY,
            exact_hessian: false,
            kappa_given: true,
        }
    }

    /// World vertices of every link at the poses `pose`.
    pub fn update_world(&mut self, pose: &[sdrs::math::Pose]) {
        for (i, m) in self.meshes.iter().enumerate() {
            for (w, x) in self.world[i].iter_mut().zip(&m.x_local) {
                *w = sdrs::math::transform_point(&pose[i], x);
            }
        }
    }

    /// Candidate primitive pairs (within `d̂`) of every link pair.
    fn broad_phase(&mut self) {
        let half = 0.5 * self.params.dhat;
        let world = &self.world;
        crate::broad_phase::build_for_pairs(&mut self.boxes, &self.meshes, &self.link_pairs, |i| {
            (&world[i][..], None, half)
        });
        for (k, &(a, b)) in self.link_pairs.iter().enumerate() {
            crate::broad_phase::candidates(&self.boxes[a], &self.boxes[b], &mut self.cands[k]);
        }
    }

    /// Smallest mesh–mesh distance over interacting link pairs at `pose`
    /// (m), with the pair: used to reject an intersecting start.
    pub fn min_distance(&mut self, pose: &[sdrs::math::Pose]) -> (f64, Option<(usize, usize)>) {
        self.update_world(pose);
        let mut best = (f64::INFINITY, None);
        let inf = f64::INFINITY;
        for &(a, b) in &self.link_pairs {
            let mut ba = PrimitiveBoxes::default();
            let mut bb = PrimitiveBoxes::default();
            ba.build(&self.meshes[a], &self.world[a], None, inf);
            bb.build(&self.meshes[b], &self.world[b], None, inf);
            let mut c = Candidates::default();
            crate::broad_phase::candidates(&ba, &bb, &mut c);
            let geo = PairGeometry {
                mesh: [&self.meshes[a], &self.meshes[b]],
                world: [&self.world[a], &self.world[b]],
            };
            let d = geo.min_distance2(&c).sqrt();
            if d < best.0 {
                best = (d, Some((a, b)));
            }
        }
        best
    }
}

impl Energy for IpcContact {
    fn name(&self) -> &'static str {
        "ipc_contact"
    }

    fn kind(&self) -> sdrs::energy::TermKind {
        sdrs::energy::TermKind::Contact
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let t0 = Instant::now();
        self.update_world(&kin.pose);
        self.broad_phase();
        self.time_broad += t0.elapsed();
        let dhat2 = self.params.dhat * self.params.dhat;
        let (meshes, world, cands) = (&self.meshes, &self.world, &self.cands);
        let derivs = need >= Need::Gradient;
        let hess = need >= Need::Hessian;
        let project = !self.exact_hessian;
        self.link_pairs
            .par_iter()
            .zip(cands.par_iter())
            .map(|(&(a, b), c)| {
                let geo = PairGeometry {
                    mesh: [&meshes[a], &meshes[b]],
                    world: [&world[a], &world[b]],
                };
                evaluate_pair(&geo, c, dhat2, derivs, hess, project)
            })
            .collect_into_vec(&mut self.results);
        let kappa = self.params.kappa;
        let (mut active, mut min_d2) = (0, f64::INFINITY);
        for (k, r) in self.results.iter().enumerate() {
            min_d2 = min_d2.min(r.min_d2);
            if !r.value.is_finite() {
                acc.value = f64::INFINITY;
                return Ok(());
            }
            if r.active == 0 {
                continue;
            }
            active += r.active;
            acc.value += kappa * r.value;
            scatter_pair(
                ctx.model,
                acc,
                need,
                self.link_pairs[k],
                kappa,
                (&r.grad_a, &r.grad_b),
                r.hess.as_deref(),
            );
        }
        self.last_active = active;
        self.last_min_distance = min_d2.sqrt();
        Ok(())
    }

    /// Adjoint product (see [`crate::adjoint_stencil`], [`crate::adjoint`]):
    /// for every active stencil at `θ^t = q`, `κ (∂²P/∂X²) δX` (exact
    /// Hessian) into pose and hull-vertex space, the mollifier threshold's
    /// dependence on link-frame edge lengths, and `∂Φ/∂κ = Φ/κ` when `κ` is
    /// the scene's. `d̂` is not differentiated (the physical `s` gradient
    /// belongs to the SDRS barrier and stays untouched).
    fn vjp(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        kin: &Kinematics,
        dir: &sdrs::diff::AdjointDirection,
        out: &mut sdrs::diff::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let mut tmp = EnergyAccumulator::new(ctx.model);
        // World vertices and candidates at θ^t.
        self.accumulate(ctx, q, kin, Need::Value, &mut tmp)?;
        if !tmp.value.is_finite() {
            return Err(EnergyError::Failed {
                term: "ipc_contact",
                msg: "intersecting state in the backward pass".into(),
            });
        }
        let dhat2 = self.params.dhat * self.params.dhat;
        let kappa = self.params.kappa;
        let poses = crate::adjoint::PoseSet {
            pose: &kin.pose,
            dpose: dir.dpose,
            prev: ctx.poses_prev,
        };
        for (k, &(a, b)) in self.link_pairs.iter().enumerate() {
            let geo = PairGeometry {
                mesh: [&self.meshes[a], &self.meshes[b]],
                world: [&self.world[a], &self.world[b]],
            };
            geo.for_each_stencil(&self.cands[k], |kind, ids| {
                let (x, _, _) = geo.stencil(ids);
                let (d, ty) = crate::primitive::stencil_distance(kind, &x);
                if !(d > 0.0 && d < dhat2) {
                    return;
                }
                let st = crate::adjoint::StencilRef {
                    ids,
                    links: [a, b],
                    meshes: geo.mesh,
                };
                let piece = crate::adjoint_stencil::ContactPiece {
                    ty,
                    mollifier: crate::primitive::mollified(kind, &x),
                    dhat2,
                };
                let dx = crate::adjoint::directions(&st, dir.dpose);
                let v = crate::adjoint_stencil::contact_vjp(&x, &dx, &piece);
                if self.kappa_given {
                    out.physical.kappa += v.phi;
                }
                crate::adjoint::scatter(&st, &poses, &v, kappa, out);
            });
        }
        Ok(())
    }

    fn max_step(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        dq: &DVector<f64>,
        kin: &Kinematics,
        charts: &[Matrix3<f64>],
    ) -> Result<f64, EnergyError> {
        let t0 = Instant::now();
        let a = max_collision_free_step(
            ctx.model,
            &self.meshes,
            &self.link_pairs,
            q,
            dq,
            kin,
            charts,
            &self.params.ccd,
            &mut self.ccd,
        );
        self.time_ccd += t0.elapsed();
        Ok(a)
    }

    fn report(&mut self, d: &mut StepDiagnostics, timers: &mut StageTimers) {
        d.contact_pairs += self.last_active;
        d.min_distance = d.min_distance.min(self.last_min_distance);
        timers.carve(Stage::BroadPhase, std::mem::take(&mut self.time_broad));
        timers.add(Stage::Ccd, std::mem::take(&mut self.time_ccd));
    }
}
