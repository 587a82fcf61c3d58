//! Collision-free step bound for Newton's line search (IPC's CCD filter) on
//! **curved** articulated vertex paths.
//!
//! Along the Newton step `θ(α) = θ + α Δθ`, a vertex of link `L` moves on
//! `X(α) = A_L(θ(α)) x̃`, which is not a straight line when rotational
//! coordinates change. We split `X(α) = X_lin(α) + X_nl(α)`: `X_lin` collects
//! the translations of joints without moving ancestors (exactly linear in
//! `α`), and `X_nl` has speed at most
//!
//! `U_L = Σ_{joints j on the path to L} (‖Δθ_j^rot‖ · R_{j,L} + [j has a
//! moving ancestor] ‖Δθ_j^trans‖)` (m per unit `α`),
//!
//! because each rotational coordinate of `j` turns the subtree at angular
//! speed at most `|Δθ_k|` (hinges: exactly; rotation vectors: the SO(3)
//! Jacobian has norm ≤ 1, so `‖ω‖ ≤ ‖Δφ‖`) about joint `j`'s centre, and
//! `R_{j,L}` bounds the distance from that centre to any vertex of `L` in
//! every configuration: `R_{L,L} = max ‖x̃‖` and `R_{j,L} = ‖t(C_c)‖ +
//! max_α ‖t(J_c)‖ + R_{c,L}` for the child `c` of `j` on the path (rigid
//! attachments; prismatic/free translations bounded at the segment ends,
//! where a linear coordinate is extremal). A path with speed ≤ `U` deviates
//! from its chord on a sub-interval of length `h` by at most `U h / 2`.
//!
//! So on `[α₀, α₁]` the true paths stay within `δ_L = U_L (α₁ − α₀)/2` of
//! the chords between the exactly computed end positions, and additive CCD
//! on the chords ([`crate::ccd`]) with minimum separation `ξ = δ_a + δ_b`
//! proves the true surfaces disjoint up to the returned time. When the
//! deviation bound, not the approach, limits the step (`ξ` not small next to
//! the gap), the interval is halved (up to `max_depth` times). This is a
//! **conservative bound with subdivision**: no trial point it admits has
//! crossing or touching surfaces.

use crate::broad_phase::{Candidates, PrimitiveBoxes, candidates};
use crate::ccd::{AccdOptions, additive_ccd};
use crate::mesh::LinkMesh;
use crate::pair::PairGeometry;
use nalgebra::{DVector, Matrix3, Vector3};
use sdrs::kinematics::{KinOrder, Kinematics};
use sdrs::model::{JointKind, Model};

/// CCD settings of the line search.
#[derive(Clone, Debug, PartialEq)]
pub struct CcdOptions {
    pub accd: AccdOptions,
    /// Smallest piece `2^-max_depth` of the step into which the curvature
    /// bound may split it. Default 48.
    pub max_depth: usize,
    /// Pieces examined per call (bounded work); the step found safe so far
    /// is returned when they run out. Default 64.
    pub max_pieces: usize,
    /// Fraction of each primitive pair's current distance that a step must
    /// keep (on top of the curvature bound). Default 0.1.
    pub keep: f64,
}

impl Default for CcdOptions {
    fn default() -> Self {
        CcdOptions {
            accd: AccdOptions::default(),
            max_depth: 48,
            max_pieces: 64,
            keep: 0.1,
        }
    }
}

/// Buffers of the step bound (apart from state).
#[derive(Default)]
pub struct CcdScratch {
    kin: Option<Kinematics>,
    q: DVector<f64>,
    speed: Vec<(f64, f64)>,
    boxes: Vec<PrimitiveBoxes>,
    cand: Candidates,
}

/// `(U_L, A_L)` for every link: bounds on the speed and the acceleration
/// (per unit `α`) of the non-linear part of its vertex paths (see the module
/// docs). With `s_j` the rotational speed bound of joint `j`, `t_j` its
/// translation speed (when it has a moving ancestor), `R_j = R_{j,L}`,
/// `W_j = Σ_{ancestors i of j} s_i` and `V_j = Σ_{i on the path at or below
/// j} (s_i R_i + t_i)`: `U_L = Σ_j (s_j R_j + t_j)` and
/// `A_L = Σ_j [s_j (W_j + s_j/2) R_j + s_j V_j + t_j W_j]`, from
/// `Ẍ = Σ_j [ω̇_j × (X − c_j) + ω_j × (Ẋ − ċ_j)]` with `‖ω_j‖ ≤ s_j`,
/// `‖ω̇_j‖ ≤ s_j (W_j + s_j/2)` (the axis turns with the ancestors; the
/// rotation-vector Jacobian changes at rate ≤ ½‖Δφ‖) and
/// `‖Ẋ − ċ_j‖ ≤ V_j`.
pub fn nonlinear_speed_bounds(
    model: &Model,
    meshes: &[LinkMesh],
    q: &DVector<f64>,
    dq: &DVector<f64>,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let trans_len = |l: usize, x: &DVector<f64>| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Prismatic { .. } => x[o].abs(),
            JointKind::Free => Vector3::new(x[o], x[o + 1], x[o + 2]).norm(),
            _ => 0.0,
        }
    };
    let rot_speed = |l: usize| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Revolute { .. } => dq[o].abs(),
            JointKind::Ball { .. } => dq[o].abs() + dq[o + 1].abs(),
            JointKind::Spherical => Vector3::new(dq[o], dq[o + 1], dq[o + 2]).norm(),
            JointKind::Free => Vector3::new(dq[o + 3], dq[o + 4], dq[o + 5]).norm(),
            _ => 0.0,
        }
    };
    let trans_speed = |l: usize| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Prismatic { .. } => dq[o].abs(),
            JointKind::Free => Vector3::new(dq[o], dq[o + 1], dq[o + 2]).norm(),
            _ => 0.0,
        }
    };
    let q1 = q + dq;
    for (l, mesh) in meshes.iter().enumerate().take(model.links.len()) {
        // The path L → root: per joint, s (rotational speed), t (translation
        // speed counted as non-linear) and R (centre-to-vertex bound).
        let mut path: Vec<(f64, f64, f64)> = Vec::new();
        let mut reach = mesh.radius;
        let mut j = l;
        loop {
            let link = &model.links[j];
            let has_moving_ancestor = link
                .parent
                .is_some_and(|p| !model.ancestor_dofs[p].is_empty());
            let t = if has_moving_ancestor {
                trans_speed(j)
            } else {
                0.0
            };
            path.push((rot_speed(j), t, reach));
            let Some(p) = link.parent else { break };
            reach += link.attach.column(3).norm() + trans_len(j, q).max(trans_len(j, &q1));
            j = p;
        }
        let (mut u, mut acc, mut below) = (0.0, 0.0, 0.0);
        let total_s: f64 = path.iter().map(|p| p.0).sum();
        let mut anc = total_s;
        for &(sp, tp, rp) in &path {
            anc -= sp;
            u += sp * rp + tp;
            below += sp * rp + tp;
            acc += sp * (anc + 0.5 * sp) * rp + sp * below + tp * anc;
        }
        out.push((u, acc));
    }
}

/// Bound on the distance between a link's true vertex path and its chord
/// over a sub-interval of length `h`: `min(U h/2, A h²/8)` (m).
pub fn chord_deviation((u, a): (f64, f64), h: f64) -> f64 {
    (u * h / 2.0).min(a * h * h / 8.0)
}

/// Largest `α ∈ [0, 1]` such that the surfaces of every link pair stay
/// disjoint along `θ + α' Δθ` for all `α' ≤ α` (see the module docs).
// Arguments kept separate: the trial's state (q, Δq, kinematics, charts) plus the mesh set, options and reusable scratch, as the core's `ccd::certify`.
#[allow(clippy::too_many_arguments)]
pub fn max_collision_free_step(
    model: &Model,
    meshes: &[LinkMesh],
    link_pairs: &[(usize, usize)],
    q: &DVector<f64>,
    dq: &DVector<f64>,
    kin: &Kinematics,
    charts: &[Matrix3<f64>],
    opts: &CcdOptions,
    s: &mut CcdScratch,
) -> f64 {
    if link_pairs.is_empty() || dq.iter().all(|&v| v == 0.0) {
        return 1.0;
    }
    nonlinear_speed_bounds(model, meshes, q, dq, &mut s.speed);
    let world = |pose: &[sdrs::math::Pose]| -> Vec<Vec<Vector3<f64>>> {
        meshes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                m.x_local
                    .iter()
                    .map(|x| sdrs::math::transform_point(&pose[i], x))
                    .collect()
            })
            .collect()
    };
    let mut x0 = world(&kin.pose);
    let (mut a0, mut h): (f64, f64) = (0.0, 1.0);
    for _ in 0..opts.max_pieces {
        let a1 = (a0 + h).min(1.0);
        let kin1 = s.kin.get_or_insert_with(|| Kinematics::new(model));
        s.q = q + dq * a1;
        kin1.update(model, &s.q, charts, KinOrder::Pose);
        let x1 = world(&kin1.pose);
        let (t, limited) = piece(meshes, link_pairs, &x0, &x1, a1 - a0, opts, s);
        if t >= 1.0 {
            if a1 >= 1.0 {
                return 1.0;
            }
            (a0, x0, h) = (a1, x1, 2.0 * (a1 - a0));
            continue;
        }
        if limited && a1 - a0 > 0.5f64.powi(opts.max_depth as i32) {
            h = 0.5 * (a1 - a0);
            continue;
        }
        return a0 + t * (a1 - a0);
    }
    a0
}

/// CCD of one sub-interval of length `h` between the vertex positions `x0`
/// and `x1`: the smallest time of impact in `[0, 1]` (1: none) and whether
/// the deviation bound rather than the approach limited it.
fn piece(
    meshes: &[LinkMesh],
    link_pairs: &[(usize, usize)],
    x0: &[Vec<Vector3<f64>>],
    x1: &[Vec<Vector3<f64>>],
    h: f64,
    opts: &CcdOptions,
    s: &mut CcdScratch,
) -> (f64, bool) {
    s.boxes.resize(meshes.len(), PrimitiveBoxes::default());
    // Each link's boxes are inflated by its own deviation bound δ_L: two
    // primitives are then paired when their chords' boxes are within
    // δ_a + δ_b = ξ on every axis, i.e. whenever the chords may come within ξ.
    for (i, m) in meshes.iter().enumerate() {
        if !m.is_empty() {
            s.boxes[i].build(
                m,
                &x0[i],
                Some(&x1[i]),
                chord_deviation(s.speed[i], h) + 1e-12,
            );
        }
    }
    let mut t_min: f64 = 1.0;
    let mut limited = false;
    for &(a, b) in link_pairs {
        candidates(&s.boxes[a], &s.boxes[b], &mut s.cand);
        if s.cand.is_empty() {
            continue;
        }
        let xi = chord_deviation(s.speed[a], h) + chord_deviation(s.speed[b], h);
        let g0 = PairGeometry {
            mesh: [&meshes[a], &meshes[b]],
            world: [&x0[a], &x0[b]],
        };
        let g1 = PairGeometry {
            mesh: [&meshes[a], &meshes[b]],
            world: [&x1[a], &x1[b]],
        };
        g0.for_each_stencil(&s.cand, |kind, ids| {
            let p0 = ids.map(|(sd, i)| {
                let v = g0.world[sd][i as usize];
                [v.x, v.y, v.z]
            });
            let dx: [[f64; 3]; 4] = std::array::from_fn(|k| {
                let (sd, i) = ids[k];
                let v = g1.world[sd][i as usize];
                [v.x - p0[k][0], v.y - p0[k][1], v.z - p0[k][2]]
            });
            // Minimum chord separation: the deviation bound ξ plus a fraction
            // of the current distance, so the true distance stays above
            // `keep·d₀` (as ACCD keeps `s·d₀` for straight paths) instead of
            // only above `s(d₀ − ξ)`, which vanishes when ξ → d₀.
            let d0 = crate::primitive::stencil_distance(kind, &p0)
                .0
                .max(0.0)
                .sqrt();
            let sep = xi + opts.keep * d0;
            if let Some(t) = additive_ccd(kind, &p0, &dx, sep, 1.0, &opts.accd)
                && t < t_min
            {
                t_min = t;
                limited = xi > 0.1 * (d0 - sep).max(0.0);
            }
        });
    }
    (t_min, limited)
}
