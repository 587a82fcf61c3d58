//! Collision-free step bound for Newton's line search (IPC's CCD filter) on
//! **curved** articulated vertex paths.
//!
//! Along the Newton step `θ(α) = θ + α Δθ`, a vertex of link `L` moves on
//! `X(α) = A_L(θ(α)) x̃`, which is not a straight line when rotational
//! coordinates change. The bound is the core's articulated motion bound
//! ([`sdrs::kinematics::SegmentMotion`], the one the core's own CCD uses):
//! a point of link `L` moves at a constant drift (translations of joints
//! whose frame does not turn, exactly linear in `α`) plus at most `E_L`, and
//! accelerates at most at `A_L`, so on a sub-interval of length `h` it
//! deviates from its chord by at most
//! `δ_L = min(E_L h/2, A_L h²/8)` ([`sdrs::kinematics::SegmentMotion::chord_deviation`]).
//!
//! So on `[α₀, α₁]` the true paths stay within `δ_L` of the chords between
//! the exactly computed end positions, and additive CCD on the chords
//! ([`crate::ccd`]) with minimum separation `ξ = δ_a + δ_b` proves the true
//! surfaces disjoint up to the returned time. When the
//! deviation bound, not the approach, limits the step (`ξ` not small next to
//! the gap), the interval is halved (up to `max_depth` times). This is a
//! **conservative bound with subdivision**: no trial point it admits has
//! crossing or touching surfaces.

use crate::broad_phase::{Candidates, PrimitiveBoxes, candidates};
use crate::ccd::{AccdOptions, additive_ccd};
use crate::mesh::LinkMesh;
use crate::pair::PairGeometry;
use nalgebra::{DVector, Matrix3, Vector3};
use sdrs::kinematics::{KinOrder, Kinematics, SegmentMotion};
use sdrs::model::Model;

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
    motion: SegmentMotion,
    radius: Vec<f64>,
    boxes: Vec<PrimitiveBoxes>,
    cand: Candidates,
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
    s.radius.clear();
    s.radius.extend(meshes.iter().map(|m| m.radius));
    s.motion
        .update(model, &kin.pre, &kin.pose, charts, &s.radius, q, dq);
    s.motion.update_chord(model, dq);
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
    let motion = &s.motion;
    crate::broad_phase::build_for_pairs(&mut s.boxes, meshes, link_pairs, |i| {
        (
            &x0[i][..],
            Some(&x1[i][..]),
            motion.chord_deviation(i, h) + 1e-12,
        )
    });
    let mut t_min: f64 = 1.0;
    let mut limited = false;
    for &(a, b) in link_pairs {
        candidates(&s.boxes[a], &s.boxes[b], &mut s.cand);
        if s.cand.is_empty() {
            continue;
        }
        let xi = s.motion.chord_deviation(a, h) + s.motion.chord_deviation(b, h);
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
