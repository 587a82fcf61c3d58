//! Additive continuous collision detection (ACCD; Li et al. 2021, "Codimensional
//! Incremental Potential Contact", Alg. 1) for point–triangle and edge–edge
//! stencils moving **linearly**: `x(t) = x₀ + t Δx`, `t ∈ [0, t_c]`.
//!
//! Conservative advancement: the distance between the two primitives changes
//! at most at rate `l_p = ‖Δp‖ + max ‖Δt_i‖` (point–triangle) or
//! `max ‖Δa_i‖ + max ‖Δb_j‖` (edge–edge), after removing the stencil's mean
//! displacement (a common translation changes no distance). From a gap
//! `g = d − ξ` above the minimum separation `ξ` (m), advancing by
//! `0.9·g / l_p` can close at most 90% of it, so the stencil never gets
//! closer than `ξ` before the returned time of impact. Iteration stops once
//! the gap has shrunk to a fraction `s` of the initial one (a hit, returned
//! as the last safe time) or when `t_c` is passed (no hit).

use crate::distance::vec::V3;
use crate::primitive::{PrimitiveKind, stencil_distance};

/// ACCD settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccdOptions {
    /// Gap fraction `s ∈ (0, 1)` that ends the advancement (a hit keeps at
    /// least `s` of the initial gap above `ξ`). Default 0.1 (ACCD's value).
    pub s: f64,
    /// Iteration cap; reaching it reports a hit at the last safe time
    /// (conservative: the step bound then subdivides or stops there).
    /// Default 5000. A stencil sliding at a constant gap `g` over a
    /// relative displacement `l` needs about `l / (0.9 g)` iterations to
    /// clear the step; with the former cap of 200, chains of 32 links sliding
    /// against each other (gaps ~1e-5 m, tip motions ~0.2 m per Newton step)
    /// were cut to ~1.4 % of every Newton step and the solve stalled
    /// (`notes/ipc-baseline-adjoint-and-cages.md`).
    pub max_iters: usize,
}

impl Default for AccdOptions {
    fn default() -> Self {
        AccdOptions {
            s: 0.1,
            max_iters: 5000,
        }
    }
}

fn distance(kind: PrimitiveKind, x: &[V3<f64>; 4]) -> f64 {
    stencil_distance(kind, x).0.max(0.0).sqrt()
}

/// Time of impact in `[0, t_c]` of the linear motion `x₀ + tΔx` with minimum
/// separation `xi` (m), or `None` when the stencil stays farther than `xi`
/// up to `t_c`. `Some(0)` when it starts within `xi`.
pub fn additive_ccd(
    kind: PrimitiveKind,
    x0: &[V3<f64>; 4],
    dx: &[V3<f64>; 4],
    xi: f64,
    tc: f64,
    opts: &AccdOptions,
) -> Option<f64> {
    let mean: V3<f64> = std::array::from_fn(|k| 0.25 * (dx[0][k] + dx[1][k] + dx[2][k] + dx[3][k]));
    let p: [V3<f64>; 4] = std::array::from_fn(|i| std::array::from_fn(|k| dx[i][k] - mean[k]));
    let n = |v: &V3<f64>| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let lp = match kind {
        PrimitiveKind::PointTriangle => n(&p[0]) + n(&p[1]).max(n(&p[2])).max(n(&p[3])),
        PrimitiveKind::EdgeEdge { .. } => n(&p[0]).max(n(&p[1])) + n(&p[2]).max(n(&p[3])),
    };
    let at = |t: f64| -> [V3<f64>; 4] {
        std::array::from_fn(|i| std::array::from_fn(|k| x0[i][k] + t * p[i][k]))
    };
    let mut d = distance(kind, x0);
    if d <= xi {
        return Some(0.0);
    }
    if lp == 0.0 {
        return None;
    }
    let g = opts.s * (d - xi);
    let mut t = 0.0;
    let mut tl = (1.0 - opts.s) * (d - xi) / lp;
    for _ in 0..opts.max_iters {
        if t + tl > tc {
            return None;
        }
        d = distance(kind, &at(t + tl));
        if t > 0.0 && d - xi < g {
            return Some(t);
        }
        t += tl;
        tl = 0.9 * (d - xi) / lp;
        // (NaN-safe: a non-positive or undefined advance is a hit here.)
        if tl.is_nan() || tl <= 0.0 {
            return Some(t);
        }
    }
    Some(t)
}
