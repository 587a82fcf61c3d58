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

use super::adjoint_contact::PlaneOptimum;
use super::barrier::barrier_d2;
use nalgebra::Vector3;

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
    /// `(y⁰_m, y¹_m, y²_m)` of every vertex of both hulls.
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

impl PlaneOptimum<'_> {
    /// The pair's potential along the vertex direction `(dxa, dxb)` (one vector per vertex of
    /// each hull, world frame), scaled by `scale` (see the module docs).
    pub fn line(&self, dxa: &[Vector3<f64>], dxb: &[Vector3<f64>], scale: f64) -> PlaneLine {
        assert_eq!(self.xa.len(), dxa.len(), "PlaneOptimum::line: δX_a length");
        assert_eq!(self.xb.len(), dxb.len(), "PlaneOptimum::line: δX_b length");
        let rate = -self.solve(&self.plane_of_direction(dxa, dxb));
        let dn = Vector3::new(rate.x, rate.y, rate.z);
        let dof = rate.w;
        let mut y = Vec::with_capacity(dxa.len() + dxb.len());
        for (xs, dxs, sigma) in [(self.xa, dxa, -1.0), (self.xb, dxb, 1.0)] {
            for (x, dx) in xs.iter().zip(dxs) {
                let x = x - self.c0;
                y.push([
                    sigma * (self.n.dot(&x) + self.o),
                    sigma * (dn.dot(&x) + self.n.dot(dx) + dof),
                    sigma * dn.dot(dx),
                ]);
            }
        }
        PlaneLine {
            n: self.n,
            dn,
            s: self.s,
            scale,
            y,
        }
    }
}

impl PlaneLine {
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
    use rand::RngExt;

    const S: f64 = 0.05;

    fn uc(xa: &[Vector3<f64>], xb: &[Vector3<f64>]) -> f64 {
        let mut sc = ContactScratch::new();
        match contact_vertices(xa, xb, &ContactParams::with_width(S), None, &mut sc).unwrap() {
            VertexOutcome::Separated(c) => c.value,
            VertexOutcome::OutOfRange { .. } => 0.0,
            VertexOutcome::Intersecting => f64::INFINITY,
        }
    }

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
        PlaneOptimum::new(xa, xb, &c.plane, S).line(&d[..na], &d[na..], 1.0)
    }

    /// `W(0) = U_c`, `W'(0)` and `W''(0)` against central differences of `U_c(X + α δX)`
    /// (the plane re-solved at every point), from near the support's edge to deep inside it,
    /// opening and closing.
    #[test]
    fn line_model_matches_the_potential_to_second_order() {
        let mut worst = (0.0f64, 0.0f64);
        for (k, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
            .into_iter()
            .enumerate()
        {
            for &frac in &[0.02, 0.1, 0.4, 0.8, 0.97] {
                for &closing in &[1.0, -1.0, 0.0] {
                    let (xa, xb, d) = case(kind, frac, closing, 7 + k as u64);
                    let w = line_of(&xa, &xb, &d);
                    let f = |a: f64| uc(&moved(&xa, &d[..xa.len()], a), &moved(&xb, &d[xa.len()..], a));
                    let u0 = f(0.0);
                    let p = w.at(0.0);
                    assert!((p.value - u0).abs() <= 1e-9 * u0.abs().max(1e-300), "{kind:?} {frac}: W(0)");
                    // Steps small next to the gap (the barrier's scale): frac · 1e-3 of it.
                    let h = 1e-3 * frac;
                    let (up, um) = (f(h), f(-h));
                    let (up2, um2) = (f(2.0 * h), f(-2.0 * h));
                    // Fourth-order central differences.
                    let d1 = (8.0 * (up - um) - (up2 - um2)) / (12.0 * h);
                    let d2 = (16.0 * (up + um) - (up2 + um2) - 30.0 * u0) / (12.0 * h * h);
                    let e1 = (p.d1 - d1).abs() / p.d1.abs().max(p.d2.abs() * h);
                    let e2 = (p.d2 - d2).abs() / p.d2.abs().max(1e-300);
                    report(&format!("line {kind:?} frac {frac} closing {closing}: W'"), e1);
                    report(&format!("line {kind:?} frac {frac} closing {closing}: W''"), e2);
                    assert!(e1 <= 1e-5, "{kind:?} {frac} {closing}: W'(0) {} vs {d1}", p.d1);
                    assert!(e2 <= 1e-4, "{kind:?} {frac} {closing}: W''(0) {} vs {d2}", p.d2);
                    worst = (worst.0.max(e1), worst.1.max(e2));
                }
            }
        }
        report("line model worst W'", worst.0);
        report("line model worst W''", worst.1);
    }

    /// `W(α) ≥ U_c(X + α δX)` along the line (the model keeps a first-order plane, the potential
    /// the optimal one), and the gap shrinks like `α⁴`.
    #[test]
    fn line_model_bounds_the_potential_from_above_with_a_fourth_order_gap() {
        for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
            for &frac in &[0.1, 0.5] {
                let (xa, xb, d) = case(kind, frac, -1.0, 11);
                let w = line_of(&xa, &xb, &d);
                let f = |a: f64| uc(&moved(&xa, &d[..xa.len()], a), &moved(&xb, &d[xa.len()..], a));
                let mut gaps = vec![];
                for &a in &[0.2, 0.1, 0.05] {
                    let (wv, u) = (w.at(a).value, f(a));
                    assert!(wv >= u * (1.0 - 1e-10), "{kind:?} {frac} α {a}: W {wv} < U_c {u}");
                    gaps.push(wv - u);
                }
                // Halving α divides an O(α⁴) gap by about 16 (at least 6 here).
                for g in gaps.windows(2) {
                    if g[0] > 1e-12 * f(0.0) {
                        assert!(g[1] <= g[0] / 6.0, "{kind:?} {frac}: gaps {gaps:?}");
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
                    assert!((p.d1 - d1).abs() <= 1e-5 * p.d1.abs().max(p.value), "{kind:?} α {a}: W'");
                    assert!((p.d2 - d2).abs() <= 1e-5 * p.d2.abs().max(p.d1.abs()), "{kind:?} α {a}: W''");
                }
                a += 0.05;
            }
        }
    }
}
