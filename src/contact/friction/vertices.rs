//! `U_f` with its derivatives per vertex (`∂/∂X'_m`, `∂²/∂X'²`, `∂²/∂X'∂X`), for the adjoint and
//! for tests against the pose-contracted form.

use nalgebra::{DMatrix, Matrix3, Matrix3x2, SMatrix, Vector2, Vector3};

use super::*;
use crate::contact::error::{FrictionError, Hull};

/// Result of [`friction_vertices`]: value and per-vertex gradient w.r.t. `X^{t+1}`, plus what
/// is needed to form dense second derivatives for tests.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionVertices {
    /// `U_f`.
    pub value: f64,
    /// `u*`.
    pub u: Vector2<f64>,
    /// `ω*`.
    pub omega: f64,
    /// See [`FrictionPair::spin_free`].
    pub spin_free: bool,
    /// Inner iterations.
    pub iterations: usize,
    /// `∂U_f/∂X_a^{t+1,m}` (the friction force on the vertex is its negative).
    pub grad_a: Vec<Vector3<f64>>,
    /// `∂U_f/∂X_b^{t+1,m}`.
    pub grad_b: Vec<Vector3<f64>>,
    terms: Vec<(usize, Active)>,
    hinv: Matrix3<f64>,
    normal: Vector3<f64>,
    basis: Matrix3x2<f64>,
    dt: f64,
    eps: f64,
    nverts: usize,
}

/// [`friction_pair`] for step-`t+1` vertices given directly in world coordinates.
/// Allocates its result: meant for tests and diagnostics.
pub fn friction_vertices(
    frame: &FrictionFrame<'_>,
    xa_next: &[Vector3<f64>],
    xb_next: &[Vector3<f64>],
    params: &FrictionParams,
    scratch: &mut FrictionScratch,
) -> Result<FrictionVertices, FrictionError> {
    for (hull, xs) in [(Hull::A, xa_next), (Hull::B, xb_next)] {
        if let Some(index) = xs.iter().position(|x| !x.iter().all(|v| v.is_finite())) {
            return Err(FrictionError::NonFiniteVertex { hull, index });
        }
    }
    let sides = [xa_next, xb_next];
    let next = |h: usize, m: usize| sides[h][m];
    let spin_free = prepare(
        frame,
        &next,
        [xa_next.len(), xb_next.len()],
        params,
        &mut scratch.act,
    )?;
    let core = solve_inner(&scratch.act, spin_free, params)?;
    let mut grad_a = vec![Vector3::zeros(); xa_next.len()];
    let mut grad_b = vec![Vector3::zeros(); xb_next.len()];
    let mut terms = Vec::with_capacity(scratch.act.len());
    for act in &scratch.act {
        let (_, _, rho, _) = vertex_terms(act, &core.q, params.eps_velocity);
        let g = frame.basis * rho * (act.w / params.dt);
        if act.hull == 0 {
            grad_a[act.index] = g;
        } else {
            grad_b[act.index] = g;
        }
        let global = if act.hull == 0 {
            act.index
        } else {
            xa_next.len() + act.index
        };
        terms.push((global, *act));
    }
    Ok(FrictionVertices {
        value: core.value,
        u: Vector2::new(core.q.x, core.q.y),
        omega: core.q.z,
        spin_free: core.spin_free,
        iterations: core.iterations,
        grad_a,
        grad_b,
        terms,
        hinv: core.hinv,
        normal: frame.normal,
        basis: frame.basis,
        dt: params.dt,
        eps: params.eps_velocity,
        nverts: xa_next.len() + xb_next.len(),
    })
}

/// Per active vertex: global index, `M_m`, `C_m = U*_{X'_m q}`, `U*_{q X_m}`.
type VertexBlocks = (usize, Matrix3<f64>, Matrix3<f64>, Matrix3<f64>);

impl FrictionVertices {
    fn q(&self) -> Vector3<f64> {
        Vector3::new(self.u.x, self.u.y, self.omega)
    }

    /// Per active vertex: (global index, M_m = (w/Δt²)BΦBᵀ, C_m = −(w/Δt)BΦJ, U*_{qX,m}).
    fn blocks(&self) -> Vec<VertexBlocks> {
        let q = self.q();
        let (b, dt) = (self.basis, self.dt);
        let nx = cross_matrix(&self.normal);
        let qm = Matrix3::identity() / dt + nx * q.z;
        self.terms
            .iter()
            .map(|(gi, act)| {
                let (_, _, rho, bp) = vertex_terms(act, &q, self.eps);
                let g = if self.spin_free {
                    Vector2::zeros()
                } else {
                    act.g
                };
                let mut jm = SMatrix::<f64, 2, 3>::zeros();
                jm[(0, 0)] = 1.0;
                jm[(1, 1)] = 1.0;
                jm[(0, 2)] = g.x;
                jm[(1, 2)] = g.y;
                let m = b * bp * b.transpose() * (act.w / (dt * dt));
                let c = -(b * bp * jm) * (act.w / dt);
                let mut qx = jm.transpose() * bp * b.transpose() * qm * act.w;
                if !self.spin_free {
                    let row = (b * rho * act.w).transpose() * nx;
                    for r in 0..3 {
                        qx[(2, r)] -= row[r];
                    }
                }
                (*gi, m, c, qx)
            })
            .collect()
    }

    /// Dense `∂²U_f/∂(X^{t+1})²` over `[X_a; X_b]` (3 rows per vertex). Tests only.
    pub fn dense_hessian(&self) -> DMatrix<f64> {
        let n = 3 * self.nverts;
        let mut h = DMatrix::zeros(n, n);
        let mut c = DMatrix::zeros(n, 3);
        for (gi, m, cm, _) in self.blocks() {
            h.view_mut((3 * gi, 3 * gi), (3, 3)).copy_from(&m);
            c.view_mut((3 * gi, 0), (3, 3)).copy_from(&cm);
        }
        let hinv = DMatrix::from_iterator(3, 3, self.hinv.iter().copied());
        h - &c * hinv * c.transpose()
    }

    /// Dense mixed `∂²U_f/∂X^{t+1}∂X^t` (rows `X^{t+1}`, columns `X^t`, both `[a; b]`) for fixed
    /// lagged normal, basis and forces. Tests only.
    pub fn dense_mixed(&self) -> DMatrix<f64> {
        let n = 3 * self.nverts;
        let q = self.q();
        let nx = cross_matrix(&self.normal);
        let qm = Matrix3::identity() / self.dt + nx * q.z;
        let mut mx = DMatrix::zeros(n, n);
        let mut c = DMatrix::zeros(n, 3);
        let mut qx = DMatrix::zeros(3, n);
        for (gi, m, cm, qxm) in self.blocks() {
            let d = -(m * qm) * self.dt;
            mx.view_mut((3 * gi, 3 * gi), (3, 3)).copy_from(&d);
            c.view_mut((3 * gi, 0), (3, 3)).copy_from(&cm);
            qx.view_mut((0, 3 * gi), (3, 3)).copy_from(&qxm);
        }
        let hinv = DMatrix::from_iterator(3, 3, self.hinv.iter().copied());
        mx - &c * hinv * qx
    }
}
