//! pybullet's geometry extensions that are not URDF shapes, and how they are
//! imported.
//!
//! - `<plane normal="n"/>` (an infinite static plane, e.g.
//!   `plane_implicit.urdf`): a slab [`PLANE_EXTENT`] × [`PLANE_EXTENT`] ×
//!   [`PLANE_THICKNESS`] m whose top face is the plane through the geometry
//!   origin with normal `n` (pybullet_data's own `plane_implicit.urdf` names
//!   a 100 × 100 × 10 m box as its alternative). A convex hull cannot be
//!   infinite; the import report says so.
//! - `<cdf filename="…"/>` (a signed-distance-field file, e.g.
//!   `toys/concave_box.urdf`): the link's visual geometry is used for
//!   collision instead, decomposed like any mesh. The report says so.
//!
//! The tolerant pass ([`super::tolerant`]) replaces each such element by a
//! placeholder shape so that `urdf-rs` can parse the file, and records it
//! here by link and geometry index; [`super::urdf`] substitutes the real
//! geometry.

use nalgebra::{Matrix3, Rotation3, Vector3};
use std::collections::HashMap;

/// Edge of the slab standing in for an infinite plane (m).
pub const PLANE_EXTENT: f64 = 100.0;
/// Thickness of that slab (m), below the plane.
pub const PLANE_THICKNESS: f64 = 1.0;

/// `<collision>` or `<visual>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Slot {
    Collision,
    Visual,
}

/// A pybullet-only shape met in the file.
#[derive(Clone, Debug, PartialEq)]
pub enum Special {
    /// `<plane normal>`; the normal as written (validated when used).
    Plane { normal: String },
    /// `<cdf filename>`.
    Cdf { filename: String },
}

/// The pybullet shapes of a file by (link name, slot, index within the
/// link's elements of that slot).
pub type SpecialShapes = HashMap<(String, Slot, usize), Special>;

/// A box placed in a geometry frame.
#[derive(Clone, Debug)]
pub struct Slab {
    /// Rotation of the box frame (its +z is the plane normal).
    pub rotation: Matrix3<f64>,
    /// Box centre (m).
    pub centre: Vector3<f64>,
    /// Full edge lengths (m).
    pub size: [f64; 3],
}

/// The slab for a plane with unit normal `n` through the geometry origin, in
/// the geometry frame: the rotation taking +z to `n` and the box centre at
/// `−(T/2) n`. Errors name what is wrong with the normal text.
pub fn plane_slab(normal: &str) -> Result<Slab, String> {
    let v: Vec<f64> = normal
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| format!("<plane normal=\"{normal}\">: not three numbers"))?;
    let n = match v.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|c| c.is_finite()) => Vector3::new(*x, *y, *z),
        _ => {
            return Err(format!(
                "<plane normal=\"{normal}\">: needs three finite numbers"
            ));
        }
    };
    let len = n.norm();
    if !(len > 1e-12) {
        return Err(format!("<plane normal=\"{normal}\">: the normal is zero"));
    }
    let n = n / len;
    let r = Rotation3::rotation_between(&Vector3::z(), &n)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    Ok(Slab {
        rotation: *r.matrix(),
        centre: -0.5 * PLANE_THICKNESS * n,
        size: [PLANE_EXTENT, PLANE_EXTENT, PLANE_THICKNESS],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slab_top_face_is_the_plane() {
        for normal in ["0 0 1", "0 0 -1", "1 0 0", "0.3 -0.4 0.5", "0 0 2"] {
            let Slab {
                rotation: r,
                centre: c,
                size,
            } = plane_slab(normal).unwrap();
            let n: Vector3<f64> = {
                let v: Vec<f64> = normal.split(' ').map(|t| t.parse().unwrap()).collect();
                Vector3::new(v[0], v[1], v[2]).normalize()
            };
            // The box's +z face centre is c + R (0, 0, T/2): on the plane.
            let top = c + r * Vector3::new(0.0, 0.0, size[2] / 2.0);
            assert!(top.norm() < 1e-12, "{normal}: top face centre {top:?}");
            assert!((r * Vector3::z() - n).norm() < 1e-12, "{normal}");
            assert!((r.determinant() - 1.0).abs() < 1e-12);
        }
        assert!(plane_slab("0 0 0").is_err());
        assert!(plane_slab("0 nan 1").is_err());
        assert!(plane_slab("0 1").is_err());
    }
}
