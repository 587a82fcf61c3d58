//! Adjoint (vector–Jacobian) products of the contact potential of one hull pair, for the
//! backward pass (`crate::diff`).
//!
//! The backward pass needs, per pair, the derivatives of
//!
//! ```text
//! Φ(X, s) = Σ_m ⟨∂U_c/∂X_m, δX_m⟩          (δX fixed: the adjoint direction in vertex space)
//! ```
//!
//! with respect to the world vertices `X` and the barrier width `s`. `∇_X U_c = U*_X(X, p*, s)`
//! by the envelope theorem, and `p*(X, s)` moves with its arguments (implicit function
//! theorem, paper Eq. `planeDerivative`). Both derivatives follow from one scalar,
//!
//! ```text
//! Ψ(X, p, s) = U*_X(X, p, s)·δX − U*_p(X, p, s)·z,      z = (U*_pp)⁻¹ U*_pX δX,
//! ```
//!
//! which equals `Φ` at `p*` (where `U*_p = 0`) and is stationary in `p` there
//! (`∂Ψ/∂p = U*_pX δX − U*_pp z = 0`). Hence `dΦ/dX = ∂Ψ/∂X` and `dΦ/ds = ∂Ψ/∂s` at fixed
//! `p = p*`, `z`:
//!
//! ```text
//! ∂Φ/∂X_m = U*_{X_m X_m} δX_m − U*_{X_m p} z        (= (∂²U_c/∂X²) δX, the IFT Schur complement)
//! ∂Φ/∂s   = Σ_m U*_{X_m s}·δX_m − U*_{ps}·z
//! ```
//!
//! With `y_m = σ_m (n·X_m + o)`, `x̃_m = [X_m; 1]`, `q = 1 − ‖n‖` (see [`super::potential`]):
//!
//! ```text
//! U*_{X_m X_m} = P''(y_m) n nᵀ
//! U*_{X_m p}   = P''(y_m) n x̃_mᵀ + σ_m P'(y_m) [I₃ 0]
//! U*_{X_m s}   = σ_m ∂ₛP'(y_m) n
//! U*_{ps}      = Σ_m σ_m ∂ₛP'(y_m) x̃_m − ∂ₛP'(q) [n̂; 0]
//! ∂ₛP'(x)      = 4 (x − s)² (2x − 5s) / x⁶        (0 < x < s; 0 for x ≥ s)
//! ```
//!
//! Everything is `O(M)`: one pass for `U*_pX δX` (a 4-vector), a 4×4 solve, one pass for the
//! per-vertex products. No (3M)×(3M) matrix is formed.
//!
//! [`PlaneOptimum`] holds `p*` and `(U*_pp)⁻¹` and offers the two primitives (`U*_pX δX` and
//! the pull-back `ζ ↦ (−U*_{Xp} ζ, −U*_{sp}·ζ)` of a plane sensitivity `ζ`); the friction
//! adjoint reuses them to differentiate the lagged plane and normal forces
//! ([`super::adjoint_friction`]).
//!
//! All computations run in a frame shifted by the midpoint `c0` of the two hull centroids (as
//! the forward solve does, for conditioning). The shift is a constant: world quantities do not
//! depend on it, so derivatives w.r.t. world vertices are the same in either frame.

use nalgebra::{Matrix4, Vector3, Vector4};

use super::barrier::barrier_d2;
use super::potential::plane_hessian_inverse;

/// `∂P_s'(x)/∂s = 4 (x − s)² (2x − 5s)/x⁶` on `(0, s)`, `0` for `x ≥ s` (the one-sided limit
/// `−∞` for `x ≤ 0`, never evaluated by the solvers). Continuous at `x = s` (like `(x − s)²`).
#[inline]
pub fn barrier_d1_ds(x: f64, s: f64) -> f64 {
    if x >= s {
        0.0
    } else if x > 0.0 {
        let t = x - s;
        let inv = 1.0 / x;
        let inv2 = inv * inv;
        let inv6 = inv2 * inv2 * inv2;
        4.0 * t * t * (2.0 * x - 5.0 * s) * inv6
    } else {
        f64::NEG_INFINITY
    }
}

/// Barrier data of one vertex at `p*` (shifted frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlaneVertex {
    /// `X − c0`.
    pub x: Vector3<f64>,
    /// `−1` on hull `a`, `+1` on hull `b`.
    pub sigma: f64,
    /// `y = σ (n·x + o)`.
    pub y: f64,
    /// `P_s'(y)`.
    pub d1: f64,
    /// `P_s''(y)`.
    pub d2: f64,
    /// `∂ₛP_s'(y)`.
    pub d1s: f64,
}

/// The optimal plane `p*` of a separated pair within range, with `(U*_pp)⁻¹`: what the
/// implicit function theorem needs (see the module docs).
#[derive(Clone, Debug)]
pub struct PlaneOptimum<'a> {
    xa: &'a [Vector3<f64>],
    xb: &'a [Vector3<f64>],
    c0: Vector3<f64>,
    /// `n*`.
    n: Vector3<f64>,
    /// Offset in the shifted frame: `n·(X − c0) + o`.
    o: f64,
    s: f64,
    /// `(U*_pp)⁻¹` in the shifted frame.
    hinv: Matrix4<f64>,
}

impl<'a> PlaneOptimum<'a> {
    /// `xa`, `xb`: world vertices of the two hulls; `plane`: the optimal plane `(n*, o*)` in
    /// world coordinates as returned by [`super::contact_pair`] for these vertices; `s`: the
    /// barrier width.
    pub fn new(
        xa: &'a [Vector3<f64>],
        xb: &'a [Vector3<f64>],
        plane: &Vector4<f64>,
        s: f64,
    ) -> Self {
        let centroid =
            |x: &[Vector3<f64>]| x.iter().sum::<Vector3<f64>>() / (x.len().max(1) as f64);
        let c0 = 0.5 * (centroid(xa) + centroid(xb));
        let n = Vector3::new(plane.x, plane.y, plane.z);
        let o = plane.w + n.dot(&c0);
        let mut opt = PlaneOptimum {
            xa,
            xb,
            c0,
            n,
            o,
            s,
            hinv: Matrix4::zeros(),
        };
        // U*_pp = Σ P'' x̃x̃ᵀ + [P''(q) n̂n̂ᵀ − P'(q)/‖n‖ (I − n̂n̂ᵀ), 0; 0, 0].
        let mut h = Matrix4::zeros();
        opt.for_each(|_, _, v| {
            if v.d2 != 0.0 {
                let xt = Vector4::new(v.x.x, v.x.y, v.x.z, 1.0);
                h += xt * xt.transpose() * v.d2;
            }
        });
        let norm = n.norm();
        let (_, d1q, d2q) = barrier_d2(1.0 - norm, s);
        if d1q != 0.0 || d2q != 0.0 {
            let nh = n / norm;
            let nn = nh * nh.transpose();
            let blk = nn * d2q - (nalgebra::Matrix3::identity() - nn) * (d1q / norm);
            let mut top = h.fixed_view_mut::<3, 3>(0, 0);
            top += blk;
        }
        opt.hinv = plane_hessian_inverse(&h);
        opt
    }

    /// `n*` (world; unnormalised, `‖n*‖ < 1`).
    pub fn normal(&self) -> Vector3<f64> {
        self.n
    }

    /// Barrier width `s`.
    pub fn width(&self) -> f64 {
        self.s
    }

    /// `(U*_pp)⁻¹ v` for a plane-space vector `v` (shifted frame).
    pub fn solve(&self, v: &Vector4<f64>) -> Vector4<f64> {
        self.hinv * v
    }

    /// Data of vertex `m` of hull `h` (0 = `a`, 1 = `b`).
    pub(crate) fn vertex(&self, h: usize, m: usize) -> PlaneVertex {
        let (x, sigma) = if h == 0 {
            (self.xa[m], -1.0)
        } else {
            (self.xb[m], 1.0)
        };
        let x = x - self.c0;
        let y = sigma * (self.n.dot(&x) + self.o);
        let (_, d1, d2) = barrier_d2(y, self.s);
        PlaneVertex {
            x,
            sigma,
            y,
            d1,
            d2,
            d1s: barrier_d1_ds(y, self.s),
        }
    }

    /// Calls `f(hull, index, data)` for every vertex within the barrier support (`y < s`);
    /// the others have `P' = P'' = ∂ₛP' = 0` and contribute nothing.
    pub(crate) fn for_each(&self, mut f: impl FnMut(usize, usize, &PlaneVertex)) {
        for (h, len) in [(0, self.xa.len()), (1, self.xb.len())] {
            for m in 0..len {
                let v = self.vertex(h, m);
                if v.y < self.s {
                    f(h, m, &v);
                }
            }
        }
    }

    /// `U*_pX δX = Σ_m (P''_m x̃_m (n·δX_m) + σ_m P'_m [δX_m; 0])` (shifted frame).
    pub fn plane_of_direction(&self, dxa: &[Vector3<f64>], dxb: &[Vector3<f64>]) -> Vector4<f64> {
        let mut v = Vector4::zeros();
        self.for_each(|h, m, t| {
            let dx = if h == 0 { dxa[m] } else { dxb[m] };
            let xt = Vector4::new(t.x.x, t.x.y, t.x.z, 1.0);
            v += xt * (t.d2 * self.n.dot(&dx));
            let f = t.sigma * t.d1;
            v.x += f * dx.x;
            v.y += f * dx.y;
            v.z += f * dx.z;
        });
        v
    }

    /// Pull-back of a plane sensitivity `ζ` (shifted frame): adds `−U*_{X_m p} ζ` to
    /// `out_a[m]` / `out_b[m]` and returns `−U*_{sp}·ζ`. With `ζ = (U*_pp)⁻¹ G` this is the
    /// contribution of `G·p*` to the derivatives w.r.t. `X` and `s`
    /// (`∂p*/∂X = −(U*_pp)⁻¹ U*_pX`, `∂p*/∂s = −(U*_pp)⁻¹ U*_ps`).
    pub fn pull_back(
        &self,
        zeta: &Vector4<f64>,
        out_a: &mut [Vector3<f64>],
        out_b: &mut [Vector3<f64>],
    ) -> f64 {
        let zn = Vector3::new(zeta.x, zeta.y, zeta.z);
        let mut ds = 0.0;
        self.for_each(|h, m, t| {
            let xz = t.x.dot(&zn) + zeta.w;
            let g = -(self.n * (t.d2 * xz) + zn * (t.sigma * t.d1));
            if h == 0 {
                out_a[m] += g;
            } else {
                out_b[m] += g;
            }
            ds -= t.sigma * t.d1s * xz;
        });
        let norm = self.n.norm();
        let d1qs = barrier_d1_ds(1.0 - norm, self.s);
        if d1qs != 0.0 {
            ds += d1qs * self.n.dot(&zn) / norm;
        }
        ds
    }
}

/// Adjoint products of one pair (unscaled by the stiffness κ). See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactVjp {
    /// `Φ = Σ_m ⟨∂U_c/∂X_m, δX_m⟩`.
    pub phi: f64,
    /// `∂U_c/∂X_m` per vertex of `a` (world).
    pub grad_a: Vec<Vector3<f64>>,
    /// `∂U_c/∂X_m` per vertex of `b` (world).
    pub grad_b: Vec<Vector3<f64>>,
    /// `∂Φ/∂X_m = ((∂²U_c/∂X²) δX)_m` per vertex of `a`.
    pub hvp_a: Vec<Vector3<f64>>,
    /// `∂Φ/∂X_m` per vertex of `b`.
    pub hvp_b: Vec<Vector3<f64>>,
    /// `∂Φ/∂s`.
    pub ds: f64,
}

/// Adjoint products of the contact potential of a separated pair within range: `xa`, `xb`
/// are the world vertices, `plane` the optimal world plane `p*` found for them (by
/// [`super::contact_pair`] or [`super::contact_vertices`]), `s` the barrier width, and
/// `dxa`, `dxb` the direction `δX` (one vector per vertex). Cost `O(M)`.
pub fn contact_vjp(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    plane: &Vector4<f64>,
    s: f64,
    dxa: &[Vector3<f64>],
    dxb: &[Vector3<f64>],
) -> ContactVjp {
    assert_eq!(xa.len(), dxa.len(), "contact_vjp: δX_a length");
    assert_eq!(xb.len(), dxb.len(), "contact_vjp: δX_b length");
    let opt = PlaneOptimum::new(xa, xb, plane, s);
    let z = opt.solve(&opt.plane_of_direction(dxa, dxb));
    let mut out = ContactVjp {
        phi: 0.0,
        grad_a: vec![Vector3::zeros(); xa.len()],
        grad_b: vec![Vector3::zeros(); xb.len()],
        hvp_a: vec![Vector3::zeros(); xa.len()],
        hvp_b: vec![Vector3::zeros(); xb.len()],
        ds: 0.0,
    };
    out.ds = opt.pull_back(&z, &mut out.hvp_a, &mut out.hvp_b);
    let n = opt.n;
    opt.for_each(|h, m, t| {
        let (dx, g, hv) = if h == 0 {
            (dxa[m], &mut out.grad_a[m], &mut out.hvp_a[m])
        } else {
            (dxb[m], &mut out.grad_b[m], &mut out.hvp_b[m])
        };
        let ndx = n.dot(&dx);
        *g = n * (t.sigma * t.d1);
        *hv += n * (t.d2 * ndx);
        out.ds += t.sigma * t.d1s * ndx;
        out.phi += t.sigma * t.d1 * ndx;
    });
    out
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::super::*;
    use super::*;
    use nalgebra::DVector;
    use rand::RngExt;

    const S: f64 = 0.05;

    #[test]
    fn barrier_d1_ds_matches_dual_numbers_and_vanishes_at_support_edge() {
        use num_dual::{Dual64, DualNum, first_derivative};
        for &s in &[0.3, 0.05, 1e-3] {
            for k in 1..40 {
                let x = s * k as f64 / 40.0;
                // d/ds of P_s'(x) = (x − s)³ (5s − x)/x⁶ with dual numbers in s.
                let (_, want) = first_derivative(
                    |sd: Dual64| (-sd + x).powi(3) * (sd * 5.0 - x) / x.powi(6),
                    s,
                );
                let got = barrier_d1_ds(x, s);
                let scale = want.abs().max(1e-12 * s.powi(-4));
                assert!((got - want).abs() <= 1e-10 * scale, "x={x} s={s}");
            }
            assert_eq!(barrier_d1_ds(s, s), 0.0);
            assert_eq!(barrier_d1_ds(2.0 * s, s), 0.0);
            let inside = barrier_d1_ds(s * (1.0 - 1e-6), s);
            assert!(inside.abs() < 1e-9 * s.powi(-4));
        }
    }

    /// `Φ(X, s) = Σ ∂U_c/∂X·δX` by the forward solver (cold start).
    fn phi(xa: &[Vector3<f64>], xb: &[Vector3<f64>], s: f64, d: &[Vector3<f64>]) -> f64 {
        directional_gradient(xa, xb, s, d)
    }

    fn random_direction(n: usize, r: &mut rand_chacha::ChaCha8Rng) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|_| {
                Vector3::new(
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                )
            })
            .collect()
    }

    /// Worst relative errors of `∂Φ/∂X` and `∂Φ/∂s` against central differences of `Φ`
    /// recomputed by the forward solver.
    fn fd_check(kind: Features, seed: u64) -> (f64, f64) {
        let params = ContactParams::with_width(S);
        let thr = params.support_distance();
        let mut r = rng(seed);
        let (mut worst_x, mut worst_s) = (0.0f64, 0.0f64);
        for &frac in &[0.05, 0.3, 0.7, 0.97] {
            let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut r);
            let xa = world(&pa, &la);
            let xb = world(&pb, &lb);
            let na = xa.len();
            let d = random_direction(xa.len() + xb.len(), &mut r);
            let mut sc = ContactScratch::new();
            let VertexOutcome::Separated(c) =
                contact_vertices(&xa, &xb, &params, None, &mut sc).unwrap()
            else {
                panic!("{kind:?} at {frac}: not separated within range")
            };
            let v = contact_vjp(&xa, &xb, &c.plane, S, &d[..na], &d[na..]);
            // Φ and the gradient agree with the forward solver.
            let g_fwd: Vec<Vector3<f64>> = c.grad_a.iter().chain(&c.grad_b).copied().collect();
            let g_adj: Vec<Vector3<f64>> = v.grad_a.iter().chain(&v.grad_b).copied().collect();
            let gscale = g_fwd.iter().map(|g| g.norm()).fold(0.0, f64::max);
            for (a, b) in g_fwd.iter().zip(&g_adj) {
                assert!((a - b).norm() <= 1e-12 * gscale);
            }
            let phi0 = phi(&xa, &xb, S, &d);
            assert!((v.phi - phi0).abs() <= 1e-12 * phi0.abs().max(gscale));
            // ∂Φ/∂X against FD.
            let x0 = flatten(&[xa.clone(), xb.clone()].concat());
            let h = 1e-7 * frac.max(0.1);
            let gfd = fd_gradient(
                &mut |x| {
                    let all = unflatten(x);
                    phi(&all[..na], &all[na..], S, &d)
                },
                &x0,
                h,
            );
            let hvp = flatten(&[v.hvp_a.clone(), v.hvp_b.clone()].concat());
            let ex = (&hvp - &gfd).norm() / hvp.norm().max(gfd.norm());
            // Same product from the dense Hessian of the forward module.
            let dense = c.dense_hessian(&xa, &xb) * flatten(&d);
            let ed = (&hvp - &dense).norm() / hvp.norm();
            assert!(ed <= 1e-10, "{kind:?} {frac}: dense Hessian product {ed:e}");
            // ∂Φ/∂s against FD (the plane is re-solved at s ± h).
            let hs = 1e-7 * S;
            let sfd = (phi(&xa, &xb, S + hs, &d) - phi(&xa, &xb, S - hs, &d)) / (2.0 * hs);
            let es = (v.ds - sfd).abs() / v.ds.abs().max(sfd.abs());
            report(&format!("contact vjp {kind:?} frac {frac}: X"), ex);
            report(&format!("contact vjp {kind:?} frac {frac}: s"), es);
            assert!(ex <= 1e-5, "{kind:?} {frac}: ∂Φ/∂X rel err {ex:e}");
            assert!(
                es <= 1e-5,
                "{kind:?} {frac}: ∂Φ/∂s rel err {es:e} ({} vs {sfd})",
                v.ds
            );
            worst_x = worst_x.max(ex);
            worst_s = worst_s.max(es);
        }
        (worst_x, worst_s)
    }

    #[test]
    fn contact_vjp_matches_fd_face_face() {
        for seed in 0..3 {
            fd_check(Features::FaceFace, 100 + seed);
        }
    }

    #[test]
    fn contact_vjp_matches_fd_edge_edge() {
        for seed in 0..3 {
            fd_check(Features::EdgeEdge, 200 + seed);
        }
    }

    #[test]
    fn contact_vjp_matches_fd_vertex_face() {
        for seed in 0..3 {
            fd_check(Features::VertexFace, 300 + seed);
        }
    }

    #[test]
    fn contact_vjp_pull_back_is_the_plane_sensitivity() {
        // −U*_{Xp}(U*_pp)⁻¹G is the gradient of G·p*(X): check against FD of the solved plane
        // (shifted frame: G·p* with p* = (n*, o* + n*·c0) for a fixed c0).
        let params = ContactParams::with_width(S);
        let mut r = rng(7);
        let (la, pa, lb, pb) =
            configuration(Features::FaceFace, 0.4 * params.support_distance(), &mut r);
        let xa = world(&pa, &la);
        let xb = world(&pb, &lb);
        let na = xa.len();
        let solve = |a: &[Vector3<f64>], b: &[Vector3<f64>], s: f64| -> Vector4<f64> {
            let mut sc = ContactScratch::new();
            match contact_vertices(a, b, &ContactParams::with_width(s), None, &mut sc).unwrap() {
                VertexOutcome::Separated(c) => c.plane,
                _ => panic!(),
            }
        };
        let plane = solve(&xa, &xb, S);
        let opt = PlaneOptimum::new(&xa, &xb, &plane, S);
        let c0 = opt.c0;
        let g = Vector4::new(0.3, -0.7, 0.2, 1.1);
        let shifted = |p: Vector4<f64>| {
            let n = Vector3::new(p.x, p.y, p.z);
            Vector4::new(p.x, p.y, p.z, p.w + n.dot(&c0))
        };
        let mut ga = vec![Vector3::zeros(); xa.len()];
        let mut gb = vec![Vector3::zeros(); xb.len()];
        let ds = opt.pull_back(&opt.solve(&g), &mut ga, &mut gb);
        let x0 = flatten(&[xa.clone(), xb.clone()].concat());
        let gfd = fd_gradient(
            &mut |x| {
                let all = unflatten(x);
                g.dot(&shifted(solve(&all[..na], &all[na..], S)))
            },
            &x0,
            1e-7,
        );
        let got = flatten(&[ga, gb].concat());
        let e = (&got - &gfd).norm() / got.norm().max(gfd.norm());
        let hs = 1e-7 * S;
        let sfd = (g.dot(&shifted(solve(&xa, &xb, S + hs)))
            - g.dot(&shifted(solve(&xa, &xb, S - hs))))
            / (2.0 * hs);
        let es = (ds - sfd).abs() / ds.abs().max(sfd.abs());
        report("plane sensitivity X", e);
        report("plane sensitivity s", es);
        assert!(e <= 1e-5, "{e:e}");
        assert!(es <= 1e-5, "{es:e}");
        let _ = DVector::<f64>::zeros(0);
    }
}
