//! The contact potential of one pair along a line: a one-dimensional model for Newton's step
//! length (used by [`crate::sim::line_model`]).
//!
//! Along a direction `δX` of the world vertices (the first-order motion of a Newton step
//! `θ → θ + α Δθ`), with the plane moved by the optimal plane's rate
//! `ṗ = (ṅ, ȯ) = −(U*_pp)⁻¹ U*_pX δX` (implicit function theorem, paper Eq. `derivative2`):
//!
//! ```text
//! W(α)   = U*(X + α δX, p* + α ṗ) = P_s(1 − ‖n + α ṅ‖) + Σ_m P_s(y_m(α)),
//! y_m(α) = σ_m ((n + α ṅ)·(X_m − c₀ + α δX_m) + o + α ȯ) = y⁰_m + α y¹_m + α² y²_m,
//! y¹_m   = σ_m (ṅ·(X_m − c₀) + n·δX_m + ȯ),   y²_m = σ_m ṅ·δX_m
//! ```
//!
//! (shifted frame of [`super::PlaneOptimum`]: `c₀` the mean of the two hulls' centroids, `o`
//! the offset there; `σ = −1` on hull `a`, `+1` on `b`; lengths in m, `W` in the potential's
//! units times the pair's scale, J for the contact term's `κ`).
//!
//! Properties (tested below):
//! - `W(0) = U_c(X)`;
//! - `W'(0) = ∇_X U_c · δX`: the envelope theorem, since `∇_p U* = 0` at `p*`;
//! - `W''(0) = δXᵀ (∂²U_c/∂X²) δX`: the IFT Schur complement, because `ṗ` is the optimal
//!   plane's rate;
//! - `W(α) ≥ U_c(X + α δX)` (`U_c` is the minimum over planes), with a difference `O(α⁴)`.
//!
//! So `W` is exact to second order at `α = 0` and keeps the barrier's own nonlinearity in every
//! vertex, which a quadratic model loses. A vertex deep in the support moving out is the case
//! that matters: there `P_s ≈ s⁴/y⁵`, a Newton step on it alone lengthens `y` by only `y/6`,
//! and the full step undershoots the line's minimum (`notes/performance.md`, twenty-first
//! session, "the Newton tail"). Every vertex of both hulls is kept, not only those in the
//! support at `α = 0`, since a vertex can enter it along the line.

use super::barrier::barrier_d2;
use super::potential::plane_hessian_inverse;
use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

/// One pair's potential along a line (see the module docs), times a scale (the contact
/// term's stiffness `κ`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneLine {
    /// `n*` (shifted frame; `‖n*‖ < 1`).
    n: Vector3<f64>,
    /// `ṅ`.
    dn: Vector3<f64>,
    /// Barrier width `s` (m).
    s: f64,
    /// Factor on `W` (the contact term's `κ`).
    scale: f64,
    /// `(y⁰_m, y¹_m, y²_m)` of the vertices of both hulls (all of them, until
    /// [`PlaneLine::keep_reachable`]).
    y: Vec<[f64; 3]>,
}

/// `W(α)`, `W'(α)`, `W''(α)` of a [`PlaneLine`] (scaled); `value = +∞` where a barrier
/// argument is not positive (the derivatives are then meaningless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinePoint {
    pub value: f64,
    pub d1: f64,
    pub d2: f64,
}

impl PlaneLine {
    /// The line of a separated pair: world vertices `xa`, `xb` with their directions `dxa`,
    /// `dxb` (one per vertex), the optimal world plane `plane = (n*, o*)` found for them
    /// ([`super::contact_pair`]), barrier width `s`, and the factor `scale`. One pass over the
    /// vertices builds `U*_pp` and `U*_pX δX` (as [`super::PlaneOptimum`] does, shifted frame),
    /// the plane's rate `ṗ = −(U*_pp)⁻¹ U*_pX δX`, and a second the vertices' `y¹`, `y²`.
    pub fn new(
        xa: &[Vector3<f64>],
        xb: &[Vector3<f64>],
        dxa: &[Vector3<f64>],
        dxb: &[Vector3<f64>],
        plane: &Vector4<f64>,
        s: f64,
        scale: f64,
    ) -> Self {
        assert_eq!(xa.len(), dxa.len(), "PlaneLine::new: δX_a length");
        assert_eq!(xb.len(), dxb.len(), "PlaneLine::new: δX_b length");
        let centroid =
            |x: &[Vector3<f64>]| x.iter().sum::<Vector3<f64>>() / (x.len().max(1) as f64);
        let c0 = 0.5 * (centroid(xa) + centroid(xb));
        let n = Vector3::new(plane.x, plane.y, plane.z);
        let o = plane.w + n.dot(&c0);
        let hulls = [(xa, dxa, -1.0), (xb, dxb, 1.0)];
        // U*_pp and v = U*_pX δX = Σ_m (P''_m x̃_m (n·δX_m) + σ_m P'_m [δX_m; 0]).
        let (mut h, mut v) = (Matrix4::zeros(), Vector4::zeros());
        let mut y = Vec::with_capacity(xa.len() + xb.len());
        for &(xs, dxs, sigma) in &hulls {
            for (x, dx) in xs.iter().zip(dxs) {
                let x = x - c0;
                let y0 = sigma * (n.dot(&x) + o);
                y.push([y0, 0.0, 0.0]);
                if y0 >= s {
                    continue;
                }
                let (_, d1, d2) = barrier_d2(y0, s);
                let xt = Vector4::new(x.x, x.y, x.z, 1.0);
                h += xt * xt.transpose() * d2;
                v += xt * (d2 * n.dot(dx));
                let f = sigma * d1;
                v.x += f * dx.x;
                v.y += f * dx.y;
                v.z += f * dx.z;
            }
        }
        let norm = n.norm();
        let (_, d1q, d2q) = barrier_d2(1.0 - norm, s);
        if d1q != 0.0 || d2q != 0.0 {
            let nh = n / norm;
            let nn = nh * nh.transpose();
            let blk = nn * d2q - (Matrix3::identity() - nn) * (d1q / norm);
            let mut top = h.fixed_view_mut::<3, 3>(0, 0);
            top += blk;
        }
        let rate = -(plane_hessian_inverse(&h) * v);
        let dn = Vector3::new(rate.x, rate.y, rate.z);
        let mut k = 0;
        for &(xs, dxs, sigma) in &hulls {
            for (x, dx) in xs.iter().zip(dxs) {
                let x = x - c0;
                y[k][1] = sigma * (dn.dot(&x) + n.dot(dx) + rate.w);
                y[k][2] = sigma * dn.dot(dx);
                k += 1;
            }
        }
        PlaneLine { n, dn, s, scale, y }
    }

    /// Drops the vertices that stay outside the support (`y_m(α) ≥ s`) on all of `[0, hi]`:
    /// they contribute nothing there.
    pub fn keep_reachable(&mut self, hi: f64) {
        let s = self.s;
        self.y.retain(|&[y0, y1, y2]| {
            let at = |a: f64| y0 + a * (y1 + a * y2);
            let mut low = y0.min(at(hi));
            if y2 > 0.0 {
                let a = -y1 / (2.0 * y2);
                if a > 0.0 && a < hi {
                    low = low.min(at(a));
                }
            }
            low < s
        });
    }

    /// A line from its parts (tests of the models built on it): normal `n` and its rate `ṅ`,
    /// width `s`, scale, and `(y⁰, y¹, y²)` per vertex.
    #[cfg(test)]
    pub(crate) fn from_parts(
        n: Vector3<f64>,
        dn: Vector3<f64>,
        s: f64,
        scale: f64,
        y: Vec<[f64; 3]>,
    ) -> Self {
        PlaneLine { n, dn, s, scale, y }
    }

    /// `W`, `W'`, `W''` at `α` (see the module docs).
    pub fn at(&self, alpha: f64) -> LinePoint {
        let infeasible = LinePoint {
            value: f64::INFINITY,
            d1: 0.0,
            d2: 0.0,
        };
        // P_s(1 − ‖n + α ṅ‖): with r = ‖v‖, v = n + α ṅ,
        // r' = v·ṅ / r, r'' = (‖ṅ‖² − r'²) / r.
        let v = self.n + self.dn * alpha;
        let r = v.norm();
        let (p, p1, p2) = barrier_d2(1.0 - r, self.s);
        if !p.is_finite() || r == 0.0 {
            return infeasible;
        }
        let r1 = v.dot(&self.dn) / r;
        let r2 = (self.dn.norm_squared() - r1 * r1) / r;
        let (mut w, mut w1, mut w2) = (p, -p1 * r1, p2 * r1 * r1 - p1 * r2);
        for &[y0, y1, y2] in &self.y {
            let y = y0 + alpha * (y1 + alpha * y2);
            if y >= self.s {
                continue;
            }
            let (p, p1, p2) = barrier_d2(y, self.s);
            if !p.is_finite() {
                return infeasible;
            }
            let dy = y1 + 2.0 * alpha * y2;
            w += p;
            w1 += p1 * dy;
            w2 += p2 * dy * dy + 2.0 * p1 * y2;
        }
        LinePoint {
            value: self.scale * w,
            d1: self.scale * w1,
            d2: self.scale * w2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::super::*;
    use nalgebra::Vector3;
    use rand::RngExt;

    const S: f64 = 0.05;

    fn moved(x: &[Vector3<f64>], d: &[Vector3<f64>], a: f64) -> Vec<Vector3<f64>> {
        x.iter().zip(d).map(|(x, d)| x + d * a).collect()
    }

    /// A pair at a fraction of the support distance and a vertex direction that closes the
    /// gap (`closing > 0`) or opens it, plus a random part.
    fn case(
        kind: Features,
        frac: f64,
        closing: f64,
        seed: u64,
    ) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let thr = ContactParams::with_width(S).support_distance();
        let mut r = rng(seed);
        let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut r);
        let (xa, xb) = (world(&pa, &la), world(&pb, &lb));
        // The gap's direction: from a's centroid to b's.
        let ca = xa.iter().sum::<Vector3<f64>>() / xa.len() as f64;
        let cb = xb.iter().sum::<Vector3<f64>>() / xb.len() as f64;
        let e = (cb - ca).normalize();
        let mut rnd = || {
            Vector3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            ) * 0.3
        };
        let spin = rnd();
        let d: Vec<Vector3<f64>> = xa
            .iter()
            .map(|x| e * (0.5 * closing) + spin.cross(&(x - ca)) * 0.1)
            .chain(xb.iter().map(|_| -e * (0.5 * closing) + rnd() * 0.05))
            .collect();
        let scale = thr;
        (xa, xb, d.iter().map(|v| v * scale).collect())
    }

    fn line_of(xa: &[Vector3<f64>], xb: &[Vector3<f64>], d: &[Vector3<f64>]) -> PlaneLine {
        let mut sc = ContactScratch::new();
        let VertexOutcome::Separated(c) =
            contact_vertices(xa, xb, &ContactParams::with_width(S), None, &mut sc).unwrap()
        else {
            panic!("not separated within range")
        };
        let na = xa.len();
        PlaneLine::new(xa, xb, &d[..na], &d[na..], &c.plane, S, 1.0)
    }

    /// `Φ(α) = ∇U_c·δX` at `X + α δX` (the plane re-solved), as the adjoint tests do.
    fn phi(xa: &[Vector3<f64>], xb: &[Vector3<f64>], d: &[Vector3<f64>], a: f64) -> f64 {
        let na = xa.len();
        let (ma, mb) = (moved(xa, &d[..na], a), moved(xb, &d[na..], a));
        directional_gradient(&ma, &mb, S, d)
    }

    /// `W(0) = U_c`, `W'(0) = ∇U_c·δX` and `W''(0) = δXᵀ(∂²U_c/∂X²)δX` against the forward
    /// module (value, gradient, dense Hessian), and `W''(0)` against central differences of
    /// `∇U_c·δX` along the line (the plane re-solved at every point); from near the support's
    /// edge to deep inside it, opening, closing and sideways.
    #[test]
    fn line_model_matches_the_potential_to_second_order() {
        let mut worst = 0.0f64;
        for (k, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
            .into_iter()
            .enumerate()
        {
            for &frac in &[0.02, 0.1, 0.4, 0.8, 0.97] {
                for &closing in &[1.0, -1.0, 0.0] {
                    let (xa, xb, d) = case(kind, frac, closing, 7 + k as u64);
                    let na = xa.len();
                    let mut sc = ContactScratch::new();
                    let params = ContactParams::with_width(S);
                    let VertexOutcome::Separated(c) =
                        contact_vertices(&xa, &xb, &params, None, &mut sc).unwrap()
                    else {
                        panic!("{kind:?} {frac}: not separated within range")
                    };
                    let w = PlaneLine::new(&xa, &xb, &d[..na], &d[na..], &c.plane, S, 1.0);
                    let p = w.at(0.0);
                    let tag = format!("{kind:?} frac {frac} closing {closing}");
                    assert!((p.value - c.value).abs() <= 1e-12 * c.value, "{tag}: W(0)");
                    let g: f64 = c
                        .grad_a
                        .iter()
                        .chain(&c.grad_b)
                        .zip(&d)
                        .map(|(g, v)| g.dot(v))
                        .sum();
                    let gs = c
                        .grad_a
                        .iter()
                        .chain(&c.grad_b)
                        .zip(&d)
                        .map(|(g, v)| g.norm() * v.norm())
                        .sum::<f64>();
                    assert!(
                        (p.d1 - g).abs() <= 1e-10 * gs,
                        "{tag}: W'(0) {} vs {g}",
                        p.d1
                    );
                    let flat = flatten(&d);
                    let dense = flat.dot(&(c.dense_hessian(&xa, &xb) * &flat));
                    let ed = (p.d2 - dense).abs() / dense.abs();
                    assert!(ed <= 1e-9, "{tag}: W''(0) {} vs dense {dense}", p.d2);
                    // Each vertex moves at most 10⁻⁵ of the gap across the difference.
                    let gap = frac * params.support_distance();
                    let h = 1e-5 * gap / d.iter().map(|v| v.norm()).fold(0.0, f64::max);
                    let fd = (phi(&xa, &xb, &d, h) - phi(&xa, &xb, &d, -h)) / (2.0 * h);
                    let ef = (p.d2 - fd).abs() / p.d2.abs();
                    report(&format!("line {tag}: W'' vs differences"), ef);
                    assert!(ef <= 1e-5, "{tag}: W''(0) {} vs differences {fd}", p.d2);
                    worst = worst.max(ef);
                }
            }
        }
        report("line model worst W'' vs differences", worst);
    }

    /// `W(α) ≥ U_c(X + α δX)` along the line (the model keeps a first-order plane, the
    /// potential the optimal one), and the gap shrinks like `α⁴`: halving `α` divides it by
    /// about 16 (at least 8 asserted).
    #[test]
    fn line_model_bounds_the_potential_from_above_with_a_fourth_order_gap() {
        let params = ContactParams {
            inner_tol: 1e-13,
            ..ContactParams::with_width(S)
        };
        let uc = |xa: &[Vector3<f64>], xb: &[Vector3<f64>]| {
            let mut sc = ContactScratch::new();
            match contact_vertices(xa, xb, &params, None, &mut sc).unwrap() {
                VertexOutcome::Separated(c) => c.value,
                _ => panic!("left the support"),
            }
        };
        for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
            for &frac in &[0.1, 0.5] {
                for &closing in &[1.0, -1.0] {
                    let (xa, xb, d) = case(kind, frac, closing, 11);
                    let w = line_of(&xa, &xb, &d);
                    let na = xa.len();
                    let f = |a: f64| uc(&moved(&xa, &d[..na], a), &moved(&xb, &d[na..], a));
                    let mut gaps = vec![];
                    for &a in &[0.2 * frac, 0.1 * frac, 0.05 * frac] {
                        let (wv, u) = (w.at(a).value, f(a));
                        assert!(
                            wv >= u * (1.0 - 1e-12),
                            "{kind:?} {frac} α {a}: W {wv} < U_c {u}"
                        );
                        gaps.push((wv - u) / u);
                    }
                    for g in gaps.windows(2) {
                        if g[0] > 1e-9 {
                            assert!(
                                g[1] <= g[0] / 8.0,
                                "{kind:?} {frac} {closing}: gaps {gaps:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The model's own derivatives against central differences of its value, along a line that
    /// brings outside vertices into the support and toward the barrier's pole.
    #[test]
    fn line_point_derivatives_match_differences_of_its_value() {
        for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
            let (xa, xb, d) = case(kind, 0.6, 1.0, 3);
            let w = line_of(&xa, &xb, &d);
            let mut a = 0.0;
            while w.at(a).value.is_finite() && a < 10.0 {
                let h = 1e-6;
                let (p, pp, pm) = (w.at(a), w.at(a + h), w.at(a - h));
                if pp.value.is_finite() && pm.value.is_finite() && p.value > 0.0 {
                    let d1 = (pp.value - pm.value) / (2.0 * h);
                    let d2 = (pp.d1 - pm.d1) / (2.0 * h);
                    assert!(
                        (p.d1 - d1).abs() <= 1e-5 * p.d1.abs().max(p.value),
                        "{kind:?} α {a}: W'"
                    );
                    assert!(
                        (p.d2 - d2).abs() <= 1e-5 * p.d2.abs().max(p.d1.abs()),
                        "{kind:?} α {a}: W''"
                    );
                }
                a += 0.05;
            }
        }
    }

    /// Pruning the vertices that stay outside the support on `[0, hi]` changes no bit of `W`
    /// there, and does drop some.
    #[test]
    fn keeping_reachable_vertices_changes_no_bit_on_the_interval() {
        let mut dropped = 0;
        for (k, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
            .into_iter()
            .enumerate()
        {
            for &closing in &[1.0, -1.0, 0.0] {
                let (xa, xb, d) = case(kind, 0.5, closing, 21 + k as u64);
                let full = line_of(&xa, &xb, &d);
                for &hi in &[0.05, 0.5, 4.0] {
                    let mut kept = full.clone();
                    kept.keep_reachable(hi);
                    dropped += full.y.len() - kept.y.len();
                    for i in 0..=40 {
                        let a = hi * i as f64 / 40.0;
                        let (p, q) = (full.at(a), kept.at(a));
                        let bits = |p: super::LinePoint| {
                            [p.value.to_bits(), p.d1.to_bits(), p.d2.to_bits()]
                        };
                        if p.value.is_finite() {
                            assert_eq!(bits(p), bits(q), "{kind:?} {closing} hi {hi} α {a}");
                        } else {
                            assert!(!q.value.is_finite());
                        }
                    }
                }
            }
        }
        assert!(dropped > 0);
    }
}
