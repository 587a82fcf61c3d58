//! Mean value coordinates for closed triangle cages (Ju, Schaefer & Warren,
//! "Mean value coordinates for closed triangular meshes", SIGGRAPH 2005).
//!
//! For a point `x` strictly inside a closed, consistently oriented triangle
//! cage with vertices `c_j`, the coordinates `φ_j(x) ≥ 0`… (positive for a
//! convex cage; they may be negative inside a non-convex one) satisfy
//!
//! ```text
//! Σ_j φ_j(x) = 1,     Σ_j φ_j(x) c_j = x          (linear precision)
//! ```
//!
//! and are smooth in `x` inside the cage. They come from the mean value
//! property of harmonic functions: `w_j = ∫_{S²} ψ_j(u)/‖c(u) − x‖ du` over
//! the unit sphere around `x`, evaluated per spherical triangle in closed
//! form (the paper's robust pseudo-code, Fig. 4):
//!
//! ```text
//! d_i = ‖c_i − x‖, u_i = (c_i − x)/d_i,  l_i = ‖u_{i+1} − u_{i−1}‖,
//! θ_i = 2 arcsin(l_i / 2),  h = (θ₁ + θ₂ + θ₃)/2,
//! c_i = 2 sin h sin(h − θ_i) / (sin θ_{i+1} sin θ_{i−1}) − 1,
//! s_i = sign(det[u₁ u₂ u₃]) √(1 − c_i²),
//! w_i += (θ_i − c_{i+1} θ_{i−1} − c_{i−1} θ_{i+1}) / (d_i sin θ_{i+1} s_{i−1}),
//! ```
//!
//! with the degenerate cases of the paper: `x` at a cage vertex (that
//! vertex's coordinate is 1), `x` on a cage triangle (`π − h < ε`: 2D
//! barycentric coordinates of that triangle), and `x` in a triangle's plane
//! outside it (`|s_i| ≤ ε`: the triangle contributes nothing). Then
//! `φ_j = w_j / Σ_k w_k`.
//!
//! Why MVC (and not harmonic or Green coordinates): the mesh is a *fixed*
//! linear combination of cage vertices (the co-design's chain rule is then a
//! constant sparse-free matrix `Φ`, `∂L/∂c = Φᵀ ∂L/∂x`), they are closed
//! form (no volumetric solve, unlike harmonic coordinates), reproduce
//! affine maps exactly (so a translated or scaled cage moves the mesh
//! rigidly or scales it), and they need only a closed triangle cage (Green
//! coordinates also use face normals, which makes the map non-linear in the
//! cage vertices). Xu et al. (RSS 2021) deform meshes by a cage in the same
//! linear-blend way.

use nalgebra::{Matrix3, Vector3};

/// Tolerance of the degenerate cases (radians or relative lengths).
const EPS: f64 = 1e-12;

/// Mean value coordinates of `x` w.r.t. the cage (`vertices`, `tris`
/// counter-clockwise from outside), written into `out` (length
/// `vertices.len()`). Returns false when they are undefined (zero total
/// weight: `x` outside a degenerate cage).
pub fn mean_value_coordinates(
    x: &Vector3<f64>,
    vertices: &[Vector3<f64>],
    tris: &[[u32; 3]],
    out: &mut [f64],
) -> bool {
    out.iter_mut().for_each(|w| *w = 0.0);
    let scale = vertices.iter().map(|v| (v - x).norm()).fold(0.0, f64::max);
    for (j, v) in vertices.iter().enumerate() {
        if (v - x).norm() <= EPS * scale.max(1e-300) {
            out[j] = 1.0;
            return true;
        }
    }
    for t in tris {
        let p = t.map(|i| vertices[i as usize]);
        let d = p.map(|q| (q - x).norm());
        let u = [0, 1, 2].map(|i| (p[i] - x) / d[i]);
        let l = [0, 1, 2].map(|i| (u[(i + 1) % 3] - u[(i + 2) % 3]).norm());
        let th = l.map(|li| 2.0 * (0.5 * li).min(1.0).asin());
        let h = 0.5 * (th[0] + th[1] + th[2]);
        if std::f64::consts::PI - h < EPS {
            // x on this triangle: 2D barycentric coordinates.
            out.iter_mut().for_each(|w| *w = 0.0);
            for i in 0..3 {
                out[t[i] as usize] = th[i].sin() * d[(i + 2) % 3] * d[(i + 1) % 3];
            }
            normalize(out);
            return true;
        }
        let c = [0, 1, 2].map(|i| {
            2.0 * h.sin() * (h - th[i]).sin() / (th[(i + 1) % 3].sin() * th[(i + 2) % 3].sin())
                - 1.0
        });
        let det = Matrix3::from_columns(&u).determinant();
        let sgn = if det < 0.0 { -1.0 } else { 1.0 };
        let s = c.map(|ci| sgn * (1.0 - ci * ci).max(0.0).sqrt());
        if s.iter().any(|si| si.abs() <= EPS) {
            // x in the triangle's plane, outside it.
            continue;
        }
        for i in 0..3 {
            let (ip, im) = ((i + 1) % 3, (i + 2) % 3);
            out[t[i] as usize] +=
                (th[i] - c[ip] * th[im] - c[im] * th[ip]) / (d[i] * th[ip].sin() * s[im]);
        }
    }
    normalize(out)
}

fn normalize(w: &mut [f64]) -> bool {
    let s: f64 = w.iter().sum();
    if s == 0.0 || !s.is_finite() {
        return false;
    }
    w.iter_mut().for_each(|x| *x /= s);
    true
}
