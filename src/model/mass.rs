//! Mass models of a link: how its 4×4 second moment `M_i = ∫ ρ x̃ x̃ᵀ dV`
//! (`x̃ = [x; 1]`, link frame, kg m² / kg m / kg) is obtained. Every
//! downstream term (inertia, gravity, calibration effects, losses) sees only
//! `M_i` and its last column `c_i = ∫ ρ x̃ dV`, so the three models share one
//! path; the vertex derivatives of `⟨W, M_i⟩` for a cotangent `W` are
//! [`crate::model::Link::moments_vjp`].
//!
//! - [`MassModel::Vertices`] (default): the paper's lumped vertex masses,
//!   `M = Σ_m ρ_m x̃_m x̃_mᵀ` (`pbad.tex`).
//! - [`MassModel::Solid`]: each hull a solid of uniform density `ρ` (kg/m³).
//!   The boundary triangles `(a, b, c)` (counter-clockwise from outside) of
//!   the hull, relative to a reference point `o`, are coned to `o` into
//!   tetrahedra of signed volume `V = a·(b×c)/6`, whose integrals are exact:
//!   `∫1 = V`, `∫r = V s/4`, `∫r rᵀ = V (aaᵀ + bbᵀ + ccᵀ + ssᵀ)/20`,
//!   `s = a + b + c`; summed over the triangles and shifted by
//!   `x̃ = T r̃`, `T = [I o; 0 1]`: `M = ρ T M_r Tᵀ`. `o` is the vertex mean,
//!   for round-off only (the result does not depend on it, so its
//!   derivative is not needed). The integrals are polynomials in the
//!   vertices of the triangles, hence differentiable for a fixed
//!   triangulation; vertices strictly inside (or on a face within
//!   `1e-12 ×` the hull's size) lie in no triangle and have zero derivative.
//!   A vertex that moves out through a face starts adding a cone of volume
//!   `area·height/3`: `M` is continuous there and its derivative jumps (a
//!   kink; the derivative reported on the face is the inside one).
//!   Likewise at a vertex of a planar face with more than three corners
//!   (a box corner): moving it off the plane flips the face's triangulation,
//!   the one-sided derivatives differ, and the reported derivative is that
//!   of the current triangulation (one of them).
//!   **Overlapping hulls of one link are superposed** (their overlap counts
//!   once per hull), which keeps every hull's contribution a smooth function
//!   of its own vertices; with a link `mass` instead of a density, the
//!   density is `mass / Σ_h vol_h` at load so the link has the given mass.
//! - [`MassModel::Given`]: mass `m`, centre of mass `p` and inertia tensor
//!   `I` about `p` (link axes), as URDF `<inertial>` gives; independent of
//!   the design. With `∫ρ r rᵀ = tr(I)/2 · 1 − I` about the COM:
//!   `M = [tr(I)/2·1 − I + m p pᵀ, m p; m pᵀ, m]`.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

/// How a link's mass is distributed (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum MassModel {
    /// Lumped at the hull vertices (`Hull::vertex_mass`).
    #[default]
    Vertices,
    /// Uniform-density solid hulls (kg/m³); overlapping hulls superposed.
    Solid { density: f64 },
    /// Explicit inertial, fixed under design changes.
    Given(Inertial),
}

/// Rigid-body inertial: mass (kg), centre of mass (m, link frame) and the
/// inertia tensor about the centre of mass (kg m², link axes).
#[derive(Clone, Debug, PartialEq)]
pub struct Inertial {
    pub mass: f64,
    pub com: Vector3<f64>,
    pub inertia: Matrix3<f64>,
}

impl Inertial {
    /// `M = [tr(I)/2·1 − I + m p pᵀ, m p; m pᵀ, m]`.
    pub fn second_moment(&self) -> Matrix4<f64> {
        let (m, p) = (self.mass, self.com);
        let s = Matrix3::identity() * (self.inertia.trace() / 2.0) - self.inertia
            + p * p.transpose() * m;
        let mut out = Matrix4::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&s);
        out.fixed_view_mut::<3, 1>(0, 3).copy_from(&(p * m));
        out.fixed_view_mut::<1, 3>(3, 0)
            .copy_from(&(p * m).transpose());
        out[(3, 3)] = m;
        out
    }

    /// The inverse of [`Inertial::second_moment`] (for a positive mass):
    /// `p = c/m`, `Σ = M₃ₓ₃ − m p pᵀ`, `I = tr(Σ)·1 − Σ`.
    pub fn from_second_moment(mm: &Matrix4<f64>) -> Inertial {
        let m = mm[(3, 3)];
        let p = mm.fixed_view::<3, 1>(0, 3) / m;
        let s = mm.fixed_view::<3, 3>(0, 0) - p * p.transpose() * m;
        Inertial {
            mass: m,
            com: p,
            inertia: Matrix3::identity() * s.trace() - s,
        }
    }

    /// Why this is not a physical inertial, if it is not: the mass must be
    /// positive and finite, the COM finite, the tensor symmetric (to 1e-9
    /// relative) with non-negative principal moments obeying the triangle
    /// inequality `I₁ ≤ I₂ + I₃` (to 1e-9 relative). A massless frame (mass
    /// and tensor exactly zero) is accepted: a link that only carries a
    /// joint (e.g. between two joints of one MJCF body).
    pub fn check(&self) -> Result<(), String> {
        if self.mass == 0.0 && self.inertia.iter().all(|v| *v == 0.0) {
            return if self.com.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(format!("centre of mass is not finite: {:?}", self.com))
            };
        }
        if !(self.mass > 0.0 && self.mass.is_finite()) {
            return Err(format!(
                "mass must be positive and finite (or zero with a zero inertia tensor: a massless frame), got {}",
                self.mass
            ));
        }
        if !self.com.iter().all(|v| v.is_finite()) {
            return Err(format!("centre of mass is not finite: {:?}", self.com));
        }
        if !self.inertia.iter().all(|v| v.is_finite()) {
            return Err("inertia tensor is not finite".into());
        }
        let scale = self.inertia.abs().max().max(f64::MIN_POSITIVE);
        if (self.inertia - self.inertia.transpose()).abs().max() > 1e-9 * scale {
            return Err("inertia tensor is not symmetric".into());
        }
        let e = self.inertia.symmetric_eigenvalues();
        let tol = 1e-9 * scale;
        if e.min() < -tol {
            return Err(format!(
                "inertia tensor has a negative principal moment {:.3e}",
                e.min()
            ));
        }
        let (lo, hi) = (e.min(), e.max());
        let mid = e.sum() - lo - hi;
        if hi > lo + mid + tol {
            return Err(format!(
                "principal moments {lo:.3e}, {mid:.3e}, {hi:.3e} violate the triangle inequality"
            ));
        }
        Ok(())
    }
}

/// Boundary triangles of a hull as indices into its vertex list
/// (counter-clockwise seen from outside); see [`MassModel::Solid`].
pub fn solid_triangles(x: &[Vector3<f64>]) -> Result<Vec<[usize; 3]>, String> {
    crate::math::polytope::hull_triangles(x)
}

/// Reference point `o` (vertex mean) of the polyhedral integrals.
fn reference(x: &[Vector3<f64>]) -> Vector3<f64> {
    x.iter().sum::<Vector3<f64>>() / x.len().max(1) as f64
}

/// `T = [I o; 0 1]`.
fn shift(o: &Vector3<f64>) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    t.fixed_view_mut::<3, 1>(0, 3).copy_from(o);
    t
}

/// `M = ρ ∫_hull x̃ x̃ᵀ dV` of a uniform solid hull with boundary `tris`.
pub fn solid_second_moment(x: &[Vector3<f64>], tris: &[[usize; 3]], density: f64) -> Matrix4<f64> {
    let o = reference(x);
    let mut r = Matrix4::zeros();
    for t in tris {
        let (a, b, c) = (x[t[0]] - o, x[t[1]] - o, x[t[2]] - o);
        let v = a.dot(&b.cross(&c)) / 6.0;
        let s = a + b + c;
        let ss = (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose())
            * (v / 20.0);
        let mut k = r.fixed_view_mut::<3, 3>(0, 0);
        k += ss;
        let first = s * (v / 4.0);
        for e in 0..3 {
            r[(e, 3)] += first[e];
            r[(3, e)] += first[e];
        }
        r[(3, 3)] += v;
    }
    let t = shift(&o);
    t * r * t.transpose() * density
}

/// Adds `∂⟨W, M⟩/∂x_m` of [`solid_second_moment`] (fixed triangulation) to
/// `out[m]`. With `Wₛ = Tᵀ (W + Wᵀ)/2 T = [S w; wᵀ ω]`, each triangle gives
/// `f = ρV q`, `q = (aᵀSa + bᵀSb + cᵀSc + sᵀSs)/20 + w·s/2 + ω`, so
/// `∂f/∂a = ρ[q (b×c)/6 + V((Sa + Ss)/10 + w/2)]` and cyclically for `b`, `c`.
pub fn solid_second_moment_vjp(
    x: &[Vector3<f64>],
    tris: &[[usize; 3]],
    density: f64,
    w: &Matrix4<f64>,
    out: &mut [Vector3<f64>],
) {
    let o = reference(x);
    let t = shift(&o);
    let ws = t.transpose() * (w + w.transpose()) * t * 0.5;
    let sm = ws.fixed_view::<3, 3>(0, 0).into_owned();
    let wv = ws.fixed_view::<3, 1>(0, 3).into_owned();
    let omega = ws[(3, 3)];
    for tri in tris {
        let p = [x[tri[0]] - o, x[tri[1]] - o, x[tri[2]] - o];
        let v = p[0].dot(&p[1].cross(&p[2])) / 6.0;
        let s = p[0] + p[1] + p[2];
        let ssv = sm * s;
        let q = (p.iter().map(|a| a.dot(&(sm * a))).sum::<f64>() + s.dot(&ssv)) / 20.0
            + wv.dot(&s) / 2.0
            + omega;
        for k in 0..3 {
            let (a, b, c) = (&p[k], &p[(k + 1) % 3], &p[(k + 2) % 3]);
            let dv = b.cross(c) / 6.0;
            let g = dv * q + ((sm * a + ssv) / 10.0 + wv / 2.0) * v;
            out[tri[k]] += g * density;
        }
    }
}

/// Volume (m³) of a solid hull: `M₄₄` at unit density.
pub fn solid_volume(x: &[Vector3<f64>], tris: &[[usize; 3]]) -> f64 {
    solid_second_moment(x, tris, 1.0)[(3, 3)]
}

/// `M` of point masses `ρ_m` at `x_m`: `Σ_m ρ_m x̃_m x̃_mᵀ`.
pub fn vertex_second_moment(x: &[Vector3<f64>], rho: &[f64]) -> Matrix4<f64> {
    let mut m2 = Matrix4::zeros();
    for (x, &r) in x.iter().zip(rho) {
        let xt = Vector4::new(x.x, x.y, x.z, 1.0);
        m2 += r * xt * xt.transpose();
    }
    m2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn given_inertial_round_trips_through_the_second_moment() {
        let g = Inertial {
            mass: 2.5,
            com: Vector3::new(0.1, -0.2, 0.3),
            inertia: Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.25, 0.03, -0.02, 0.03, 0.2),
        };
        g.check().unwrap();
        let back = Inertial::from_second_moment(&g.second_moment());
        assert!((back.mass - g.mass).abs() < 1e-14);
        assert!((back.com - g.com).norm() < 1e-14);
        assert!((back.inertia - g.inertia).norm() < 1e-14);
        let bad = Inertial {
            inertia: Matrix3::from_diagonal(&Vector3::new(1.0, 0.1, 0.1)),
            ..g
        };
        assert!(bad.check().unwrap_err().contains("triangle"));
    }

    #[test]
    fn unit_cube_has_the_textbook_moments() {
        let x =
            crate::model::Hull::cuboid(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.5, 0.0, -1.0));
        let tris = solid_triangles(&x).unwrap();
        let m = solid_second_moment(&x, &tris, 10.0);
        let i = Inertial::from_second_moment(&m);
        assert!((i.mass - 60.0).abs() < 1e-12);
        assert!((i.com - Vector3::new(0.5, 0.0, -1.0)).norm() < 1e-14);
        // I_xx = m (b² + c²)/12.
        let want = Vector3::new(60.0 * 13.0 / 12.0, 60.0 * 10.0 / 12.0, 60.0 * 5.0 / 12.0);
        assert!((i.inertia.diagonal() - want).norm() < 1e-12);
        assert!(i.inertia.map(f64::abs).sum() - want.sum() < 1e-12);
    }
}
