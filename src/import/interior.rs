//! The deepest point of an intersection of half-spaces: a Chebyshev-centre
//! problem `max r  s.t.  n_i·x + r ≤ b_i` (unit `n_i`), solved with a
//! log-barrier interior-point method (`r` is free, so any `x` with a small
//! enough `r` is a strictly feasible start; no phase one is needed).
//!
//! For two overlapping hulls the result lies strictly inside both, at depth
//! `margin > 0`; for touching hulls `margin ≈ 0`; for separated hulls
//! `margin < 0` and `point` minimises the largest plane violation.

use nalgebra::{Matrix4, Vector3, Vector4};

/// Result of [`deepest_point`].
#[derive(Clone, Copy, Debug)]
pub struct DeepestPoint {
    /// The point (input units).
    pub point: Vector3<f64>,
    /// `min_i (b_i − n_i·point)`: its depth inside every half-space (< 0:
    /// the largest violation).
    pub margin: f64,
    /// Upper bound on the optimal depth (duality gap added).
    pub upper: f64,
}

/// Solves the Chebyshev-centre problem for `planes` (`n·x ≤ b`, unit `n`),
/// starting near `start`, in units where `scale` is the problem's size.
/// The optimal depth is found to within about `1e-10 · scale`.
pub fn deepest_point(
    planes: &[(Vector3<f64>, f64)],
    start: Vector3<f64>,
    scale: f64,
) -> DeepestPoint {
    let m = planes.len();
    assert!(m > 0 && scale > 0.0);
    // Normalised data: x = start + scale·y, r = scale·ρ.
    let a: Vec<Vector4<f64>> = planes
        .iter()
        .map(|(n, _)| Vector4::new(n.x, n.y, n.z, 1.0))
        .collect();
    let b: Vec<f64> = planes
        .iter()
        .map(|(n, c)| (c - n.dot(&start)) / scale)
        .collect();
    let slacks = |z: &Vector4<f64>| -> Vec<f64> {
        a.iter().zip(&b).map(|(ai, bi)| bi - ai.dot(z)).collect()
    };
    let phi = |z: &Vector4<f64>, t: f64| -> f64 {
        let s = slacks(z);
        if s.iter().any(|&v| v <= 0.0) {
            return f64::INFINITY;
        }
        -t * z.w - s.iter().map(|v| v.ln()).sum::<f64>()
    };
    let min_b = b.iter().copied().fold(f64::INFINITY, f64::min);
    let mut z = Vector4::new(0.0, 0.0, 0.0, min_b - 1.0);
    let mut t = 1.0;
    let tol_gap = 1e-10;
    loop {
        // Centering: damped Newton on φ_t.
        for _ in 0..100 {
            let s = slacks(&z);
            let mut g = Vector4::new(0.0, 0.0, 0.0, -t);
            let mut h = Matrix4::zeros();
            for (ai, si) in a.iter().zip(&s) {
                g += ai / *si;
                h += ai * ai.transpose() / (si * si);
            }
            let ridge = 1e-14 * h.trace();
            let dz = match (h + Matrix4::identity() * ridge).cholesky() {
                Some(c) => -c.solve(&g),
                None => break,
            };
            let dec = -g.dot(&dz);
            if !(dec > 1e-14) {
                break;
            }
            let f0 = phi(&z, t);
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..80 {
                let trial = z + dz * alpha;
                if phi(&trial, t) <= f0 - 0.25 * alpha * dec {
                    z = trial;
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !accepted || dec < 1e-12 {
                break;
            }
        }
        if m as f64 / t < tol_gap {
            break;
        }
        t *= 8.0;
    }
    let y = Vector3::new(z.x, z.y, z.z);
    let point = start + y * scale;
    let margin = planes
        .iter()
        .map(|(n, c)| c - n.dot(&point))
        .fold(f64::INFINITY, f64::min);
    DeepestPoint {
        point,
        margin,
        upper: (z.w + m as f64 / t) * scale,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box_planes(lo: [f64; 3], hi: [f64; 3]) -> Vec<(Vector3<f64>, f64)> {
        let mut p = Vec::new();
        for k in 0..3 {
            let mut e = Vector3::zeros();
            e[k] = 1.0;
            p.push((e, hi[k]));
            p.push((-e, -lo[k]));
        }
        p
    }

    #[test]
    fn overlapping_boxes_give_the_centre_of_the_overlap() {
        let mut p = box_planes([0.0; 3], [2.0, 2.0, 2.0]);
        p.extend(box_planes([1.0, 0.0, 0.0], [3.0, 2.0, 2.0]));
        let d = deepest_point(&p, Vector3::new(5.0, -3.0, 1.0), 3.0);
        assert!((d.margin - 0.5).abs() < 1e-8, "{d:?}");
        assert!((d.point.x - 1.5).abs() < 1e-6);
    }

    #[test]
    fn touching_and_separated_boxes() {
        let mut p = box_planes([0.0; 3], [1.0; 3]);
        p.extend(box_planes([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]));
        let d = deepest_point(&p, Vector3::zeros(), 2.0);
        assert!(d.margin.abs() < 1e-8 && d.upper < 1e-8, "{d:?}");
        let mut p = box_planes([0.0; 3], [1.0; 3]);
        p.extend(box_planes([1.2, 0.0, 0.0], [2.0, 1.0, 1.0]));
        let d = deepest_point(&p, Vector3::zeros(), 2.0);
        assert!((d.margin + 0.1).abs() < 1e-7, "{d:?}");
        assert!((d.point.x - 1.1).abs() < 1e-6);
    }
}
