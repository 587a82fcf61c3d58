//! The IPC potential between the surfaces of two links, in pose space.
//!
//! `E_ab = Σ_{(v,t)} b_PT + Σ_{(v,t)} b_PT + Σ_{(e,e')} m·b_EE` over the
//! candidate vertex–triangle pairs both ways and edge–edge pairs (Li et al.
//! 2020, eq. 7 with the constraint set `C` of all point–triangle and
//! edge–edge pairs between the two surfaces; units m⁴, the caller applies
//! `κ`).
//!
//! Chain rule to the link poses: a stencil point on link `L` is
//! `X_k = A_L x̃_k` (`x̃ = [x_local; 1]`), linear in `A_L`, so
//! `∂E/∂A_L = Σ_k g_k x̃_kᵀ` (3×4) and the 24×24 Hessian over
//! `[vec A_a; vec A_b]` (column-major `vec`) has entries
//! `∂²E/∂A_L[r,c]∂A_M[r',c'] = Σ_{k∈L, l∈M} x̃_k[c] x̃_l[c'] H_kl[r,r']`,
//! with `H_kl` the 3×3 blocks of the (PSD-projected) stencil Hessian — a
//! congruence, so PSD blocks stay PSD in pose space.

use crate::broad_phase::Candidates;
use crate::distance::vec::V3;
use crate::mesh::LinkMesh;
use crate::mollifier::eps_x;
use crate::primitive::{Primitive, PrimitiveKind, evaluate_with, stencil_distance};
use nalgebra::{Matrix3x4, SMatrix, Vector3, Vector4};

/// 24×24 Hessian over the two links' poses.
pub type PairHessian = SMatrix<f64, 24, 24>;

/// Result of one link pair.
#[derive(Clone, Debug)]
pub struct PairEval {
    /// `E_ab` (m⁴); `+∞` when a primitive pair touches.
    pub value: f64,
    pub grad_a: Matrix3x4<f64>,
    pub grad_b: Matrix3x4<f64>,
    pub hess: Option<Box<PairHessian>>,
    /// Primitive pairs with non-zero potential.
    pub active: usize,
    /// Smallest squared distance among candidates (m²).
    pub min_d2: f64,
}

impl PairEval {
    fn new(hessian: bool) -> Self {
        PairEval {
            value: 0.0,
            grad_a: Matrix3x4::zeros(),
            grad_b: Matrix3x4::zeros(),
            hess: hessian.then(|| Box::new(PairHessian::zeros())),
            active: 0,
            min_d2: f64::INFINITY,
        }
    }
}

/// The two links' meshes and current world vertices.
pub struct PairGeometry<'a> {
    pub mesh: [&'a LinkMesh; 2],
    pub world: [&'a [Vector3<f64>]; 2],
}

impl PairGeometry<'_> {
    /// The stencil of a candidate: points, their link side (0 = a, 1 = b)
    /// and local homogeneous coordinates.
    pub fn stencil(&self, ids: [(usize, u32); 4]) -> ([V3<f64>; 4], [usize; 4], [Vector4<f64>; 4]) {
        let x = ids.map(|(s, i)| {
            let p = self.world[s][i as usize];
            [p.x, p.y, p.z]
        });
        let loc = ids.map(|(s, i)| self.mesh[s].x_local[i as usize].push(1.0));
        (x, ids.map(|(s, _)| s), loc)
    }

    /// Every candidate's stencil (side, vertex) indices and kind.
    pub fn for_each_stencil(
        &self,
        cand: &Candidates,
        mut f: impl FnMut(PrimitiveKind, [(usize, u32); 4]),
    ) {
        for (sv, st, list) in [(0usize, 1usize, &cand.vt_ab), (1, 0, &cand.vt_ba)] {
            for &(v, t) in list {
                let tri = self.mesh[st].tris[t as usize];
                f(
                    PrimitiveKind::PointTriangle,
                    [(sv, v), (st, tri[0]), (st, tri[1]), (st, tri[2])],
                );
            }
        }
        for &(i, j) in &cand.ee {
            let (ea, eb) = (
                self.mesh[0].edges[i as usize],
                self.mesh[1].edges[j as usize],
            );
            let kind = PrimitiveKind::EdgeEdge {
                eps_x: eps_x(
                    self.mesh[0].edge_len2[i as usize],
                    self.mesh[1].edge_len2[j as usize],
                ),
            };
            f(kind, [(0, ea[0]), (0, ea[1]), (1, eb[0]), (1, eb[1])]);
        }
    }

    /// Smallest classified squared distance over the candidates (m²).
    pub fn min_distance2(&self, cand: &Candidates) -> f64 {
        let mut m = f64::INFINITY;
        self.for_each_stencil(cand, |kind, ids| {
            let (x, _, _) = self.stencil(ids);
            m = m.min(stencil_distance(kind, &x).0);
        });
        m
    }
}

/// Evaluates `E_ab` and, when `derivatives`, its pose gradient and (when
/// `hessian`) pose Hessian, from per-primitive Hessians that are
/// PSD-projected when `project` (Newton) and exact otherwise (the backward
/// pass).
pub fn evaluate_pair(
    geo: &PairGeometry,
    cand: &Candidates,
    dhat2: f64,
    derivatives: bool,
    hessian: bool,
    project: bool,
) -> PairEval {
    let mut out = PairEval::new(hessian && derivatives && !cand.is_empty());
    geo.for_each_stencil(cand, |kind, ids| {
        if !out.value.is_finite() {
            return;
        }
        let (x, side, loc) = geo.stencil(ids);
        match evaluate_with(kind, &x, dhat2, derivatives, project) {
            Primitive::Inactive { distance2 } => {
                out.min_d2 = out.min_d2.min(distance2);
            }
            Primitive::Touching => {
                out.value = f64::INFINITY;
                out.min_d2 = 0.0;
            }
            Primitive::Active(e) => {
                out.active += 1;
                out.min_d2 = out.min_d2.min(e.distance2);
                out.value += e.value;
                if !derivatives {
                    return;
                }
                crate::pair::chain_to_poses(
                    &e.grad,
                    &e.hess,
                    &side,
                    &loc,
                    &mut out.grad_a,
                    &mut out.grad_b,
                    out.hess.as_deref_mut(),
                );
            }
        }
    });
    out
}

/// Adds a stencil's gradient `g` and Hessian `h` (12, 12×12 over its four
/// points) to the pose gradients of links a/b and the 24×24 pose Hessian
/// (when given), through `X_k = A_{side_k} x̃_k` (see the module docs).
// Arguments kept separate: chain rule of one stencil: its derivatives, sides and local points in, the two pose gradients and Hessian out.
#[allow(clippy::too_many_arguments)]
pub fn chain_to_poses(
    g: &crate::primitive::Vec12,
    h: &crate::primitive::Mat12,
    side: &[usize; 4],
    loc: &[Vector4<f64>; 4],
    grad_a: &mut Matrix3x4<f64>,
    grad_b: &mut Matrix3x4<f64>,
    hess: Option<&mut PairHessian>,
) {
    for k in 0..4 {
        let gk = Vector3::new(g[3 * k], g[3 * k + 1], g[3 * k + 2]) * loc[k].transpose();
        if side[k] == 0 {
            *grad_a += gk;
        } else {
            *grad_b += gk;
        }
    }
    let Some(hp) = hess else { return };
    for k in 0..4 {
        for l in 0..4 {
            let hkl = h.fixed_view::<3, 3>(3 * k, 3 * l);
            let (ro, co) = (12 * side[k], 12 * side[l]);
            for c in 0..4 {
                for cp in 0..4 {
                    let w = loc[k][c] * loc[l][cp];
                    if w != 0.0 {
                        let mut blk = hp.fixed_view_mut::<3, 3>(ro + 3 * c, co + 3 * cp);
                        blk += hkl * w;
                    }
                }
            }
        }
    }
}
