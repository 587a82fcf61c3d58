//! Scatters a stencil's adjoint product ([`crate::adjoint_stencil`]) into
//! the backward pass's buffers ([`sdrs::diff::VjpAccumulator`]).
//!
//! A stencil point `k` on link `L` is `X_k = A_L x̃_k` with direction
//! `δX_k = δA_L x̃_k` (`x̃ = [x_local; 1]`), and its lagged copy
//! `Xᵗ_k = A_Lᵗ x̃_k`. With `Φ` as in [`crate::adjoint_stencil`]:
//!
//! ```text
//! ∂Φ/∂A_L   += Σ_k (∂Φ/∂X_k) x̃_kᵀ             (at fixed δA: `out.pose`)
//! ∂Φ/∂A_Lᵗ  += Σ_k (∂Φ/∂Xᵗ_k) x̃_kᵀ            (`out.pose_prev`)
//! ∂Φ/∂x_k   += Rᵀ ∂Φ/∂X_k + δRᵀ ∂E/∂X_k + Rᵗᵀ ∂Φ/∂Xᵗ_k     (`out.vertex`)
//! ```
//!
//! (`R`, `δR`, `Rᵗ` the rotation blocks of `A`, `δA`, `Aᵗ`), the same
//! contraction as the core's `sdrs::energy::pairs::scatter_vertex_products`.
//! Mesh vertex `k` is the model's hull vertex [`LinkMesh::source`], so the
//! vertex gradient lands where the SDRS terms put theirs; a source-mesh
//! vertex is `Link::surface[k]` ([`crate::mesh::MeshOrigin::Source`]).

use crate::adjoint_stencil::StencilVjp;
use crate::distance::vec::V3;
use crate::mesh::{LinkMesh, MeshOrigin};
use nalgebra::{Matrix3, Vector3};
use sdrs::diff::VjpAccumulator;
use sdrs::math::Pose;

/// Poses the scatter needs: current `A`, direction `δA`, lagged `Aᵗ`.
pub struct PoseSet<'a> {
    pub pose: &'a [Pose],
    pub dpose: &'a [Pose],
    pub prev: &'a [Pose],
}

/// One stencil's points: `(side, mesh vertex)`, the two sides' links and
/// meshes.
pub struct StencilRef<'a> {
    pub ids: [(usize, u32); 4],
    pub links: [usize; 2],
    pub meshes: [&'a LinkMesh; 2],
}

impl StencilRef<'_> {
    /// World points `A x̃` of the stencil under `poses`.
    pub fn points(&self, poses: &[Pose]) -> [V3<f64>; 4] {
        self.ids.map(|(s, i)| {
            let p = sdrs::math::transform_point(
                &poses[self.links[s]],
                &self.meshes[s].x_local[i as usize],
            );
            [p.x, p.y, p.z]
        })
    }

    fn local(&self, k: usize) -> Vector3<f64> {
        let (s, i) = self.ids[k];
        self.meshes[s].x_local[i as usize]
    }
}

fn rot(p: &Pose) -> Matrix3<f64> {
    p.fixed_view::<3, 3>(0, 0).into_owned()
}

/// Adds `scale ×` the stencil's products (see the module docs) to `out`.
/// `∂Φ/∂ε_x` is chained to the link-frame edge lengths of an edge–edge
/// stencil (`ε_x = 10⁻³ ‖ā₁ − ā₀‖² ‖b̄₁ − b̄₀‖²`, [`crate::mollifier::eps_x`]).
pub fn scatter(
    st: &StencilRef,
    poses: &PoseSet,
    v: &StencilVjp,
    scale: f64,
    out: &mut VjpAccumulator,
) {
    let want = out.want_vertices;
    for k in 0..4 {
        let (s, i) = st.ids[k];
        let l = st.links[s];
        let xt = st.local(k).push(1.0);
        let dx = v.d_x[k] * scale;
        let dp = v.d_prev[k] * scale;
        out.pose[l] += dx * xt.transpose();
        if dp != Vector3::zeros() {
            out.pose_prev[l] += dp * xt.transpose();
        }
        if want {
            let mut g = rot(&poses.pose[l]).transpose() * dx
                + rot(&poses.dpose[l]).transpose() * v.grad[k] * scale;
            if dp != Vector3::zeros() {
                g += rot(&poses.prev[l]).transpose() * dp;
            }
            add_vertex(out, l, st.meshes[s], i, g);
        }
    }
    if want && v.d_eps != 0.0 {
        // Edge–edge stencil [a₀, a₁, b₀, b₁].
        let de = v.d_eps * scale;
        let ea = st.local(1) - st.local(0);
        let eb = st.local(3) - st.local(2);
        let ga = ea * (2e-3 * eb.norm_squared() * de);
        let gb = eb * (2e-3 * ea.norm_squared() * de);
        for (k, g) in [(0, -ga), (1, ga), (2, -gb), (3, gb)] {
            let (s, i) = st.ids[k];
            add_vertex(out, st.links[s], st.meshes[s], i, g);
        }
    }
}

/// Mesh vertex `i`'s gradient to the model quantity it copies: a hull
/// vertex, or for a source mesh `Link::surface[i]` when a design carries
/// the surface (otherwise the source mesh is fixed geometry: nothing to add).
fn add_vertex(out: &mut VjpAccumulator, link: usize, mesh: &LinkMesh, i: u32, g: Vector3<f64>) {
    match mesh.origin {
        MeshOrigin::Hulls => {
            let (h, v) = mesh.source[i as usize];
            out.vertex[link][h as usize][v as usize] += g;
        }
        MeshOrigin::Source { .. } => {
            if let Some(s) = out.surface[link].get_mut(i as usize) {
                *s += g;
            }
        }
    }
}

/// The stencil's direction `δX_k = δA x̃_k`.
pub fn directions(st: &StencilRef, dpose: &[Pose]) -> [V3<f64>; 4] {
    st.points(dpose)
}
