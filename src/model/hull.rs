//! Convex hulls in V-representation, in their link's frame.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

/// Why a vertex list is not a usable hull.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HullError {
    #[error("a hull needs at least 4 vertices, got {0}")]
    TooFewVertices(usize),
    #[error("vertex {index} is not finite: {value:?}")]
    NonFinite { index: usize, value: [f64; 3] },
    #[error(
        "the vertices are coplanar or collinear (thickness {thickness:.3e} m vs extent {extent:.3e} m): a hull must enclose volume"
    )]
    Degenerate { thickness: f64, extent: f64 },
    #[error("vertex mass must be finite and non-negative, got {0}")]
    BadMass(f64),
}

/// One convex polyhedron `H = CH(x¹ … x^M)` of a link, with the link's mass
/// lumped at its vertices (paper, `pbad.tex`: `ρ_ij(x) = Σ_m ρ δ(x − x^m)`).
#[derive(Clone, Debug, PartialEq)]
pub struct Hull {
    /// Vertices in the link frame (m).
    pub x_local: Vec<Vector3<f64>>,
    /// Mass lumped at each vertex (kg), same length as `x_local`.
    pub vertex_mass: Vec<f64>,
}

impl Hull {
    /// A hull with the given vertices and a uniform vertex mass.
    pub fn new(x_local: Vec<Vector3<f64>>, vertex_mass: f64) -> Result<Self, HullError> {
        let n = x_local.len();
        let hull = Hull {
            x_local,
            vertex_mass: vec![vertex_mass; n],
        };
        hull.validate()?;
        Ok(hull)
    }

    /// Checks: ≥ 4 finite vertices that enclose volume, non-negative masses
    /// (connectivity vertices added for design ties carry no mass).
    ///
    /// Volume test: the smallest principal extent of the centred vertex cloud
    /// (square root of the smallest eigenvalue of its scatter matrix) must
    /// exceed `1e-9` times the largest.
    pub fn validate(&self) -> Result<(), HullError> {
        let n = self.x_local.len();
        if n < 4 {
            return Err(HullError::TooFewVertices(n));
        }
        for (index, x) in self.x_local.iter().enumerate() {
            if !x.iter().all(|v| v.is_finite()) {
                return Err(HullError::NonFinite {
                    index,
                    value: [x.x, x.y, x.z],
                });
            }
        }
        for &m in &self.vertex_mass {
            if !(m >= 0.0 && m.is_finite()) {
                return Err(HullError::BadMass(m));
            }
        }
        let c = self.x_local.iter().sum::<Vector3<f64>>() / n as f64;
        let mut scatter = Matrix3::zeros();
        for x in &self.x_local {
            let d = x - c;
            scatter += d * d.transpose();
        }
        let eig = scatter.symmetric_eigenvalues();
        let (lo, hi) = (eig.min().max(0.0).sqrt(), eig.max().max(0.0).sqrt());
        if lo.partial_cmp(&(1e-9 * hi)) != Some(std::cmp::Ordering::Greater) || hi == 0.0 {
            return Err(HullError::Degenerate {
                thickness: lo,
                extent: hi,
            });
        }
        Ok(())
    }

    /// Axis-aligned box with the given full `size` centred at `center`
    /// (8 vertices).
    pub fn cuboid(size: Vector3<f64>, center: Vector3<f64>) -> Vec<Vector3<f64>> {
        let h = size / 2.0;
        let mut v = Vec::with_capacity(8);
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    v.push(center + Vector3::new(sx * h.x, sy * h.y, sz * h.z));
                }
            }
        }
        v
    }

    /// Total mass (kg).
    pub fn mass(&self) -> f64 {
        self.vertex_mass.iter().sum()
    }

    /// Second moment `Σ_m ρ_m x̃_m x̃_mᵀ` (4×4, `x̃ = [x; 1]`) and first moment
    /// `Σ_m ρ_m x̃_m`: the inertia term needs nothing else.
    pub fn moments(&self) -> (Matrix4<f64>, Vector4<f64>) {
        let mut m2 = Matrix4::zeros();
        let mut m1 = Vector4::zeros();
        for (x, &rho) in self.x_local.iter().zip(&self.vertex_mass) {
            let xt = Vector4::new(x.x, x.y, x.z, 1.0);
            m2 += rho * xt * xt.transpose();
            m1 += rho * xt;
        }
        (m2, m1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_hulls_are_rejected() {
        let flat = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        assert!(matches!(
            Hull::new(flat, 1.0),
            Err(HullError::Degenerate { .. })
        ));
        let three = vec![Vector3::zeros(), Vector3::x(), Vector3::y()];
        assert_eq!(Hull::new(three, 1.0), Err(HullError::TooFewVertices(3)));
        let tet = vec![Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()];
        assert!(Hull::new(tet, 1.0).is_ok());
    }
}
