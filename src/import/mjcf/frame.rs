//! Rigid frames and MuJoCo's quaternion convention.

use crate::scene::schema::Origin;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// A rigid transform `x ↦ R x + t`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame {
    pub(super) r: Matrix3<f64>,
    pub(super) t: Vector3<f64>,
}

impl Frame {
    pub(super) fn identity() -> Frame {
        Frame {
            r: Matrix3::identity(),
            t: Vector3::zeros(),
        }
    }
    pub(super) fn translation(t: Vector3<f64>) -> Frame {
        Frame {
            r: Matrix3::identity(),
            t,
        }
    }
    pub(super) fn pos_quat(pos: &[f64; 3], q: &[f64; 4]) -> Frame {
        Frame {
            r: quat_matrix(q),
            t: Vector3::from(*pos),
        }
    }
    pub(super) fn then(&self, o: &Frame) -> Frame {
        Frame {
            r: self.r * o.r,
            t: self.r * o.t + self.t,
        }
    }
    pub(super) fn origin(&self) -> Origin {
        let (roll, pitch, yaw) = Rotation3::from_matrix_unchecked(self.r).euler_angles();
        Origin {
            xyz: self.t.into(),
            rpy: [roll, pitch, yaw],
        }
    }
}

/// MuJoCo quaternion `[w, x, y, z]` → rotation matrix.
pub(super) fn quat_matrix(q: &[f64; 4]) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
        .to_rotation_matrix()
        .into_inner()
}

/// Rotation vector of a rotation matrix.
pub(super) fn rotation_vector(r: &Matrix3<f64>) -> [f64; 3] {
    Rotation3::from_matrix_unchecked(*r).scaled_axis().into()
}
