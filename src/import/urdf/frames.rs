//! URDF frames and inertials: `<origin>` → scene origins, `<inertial>` →
//! 4×4 second moments (moved between frames when links merge).

use crate::math::rpy_to_matrix;
use crate::scene::schema::Origin;
use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};

pub(super) fn origin_of(p: &urdf_rs::Pose) -> Origin {
    Origin {
        xyz: p.xyz.0,
        rpy: p.rpy.0,
    }
}

/// Rotation and translation of an origin.
pub(super) fn rt(o: &Origin) -> (Matrix3<f64>, Vector3<f64>) {
    (rpy_to_matrix(&o.rpy), Vector3::from(o.xyz))
}

/// `a ∘ b` as an origin (xyz + rpy).
/// The second moment of a URDF `<inertial>` in its link's frame (`None`
/// for a zero mass): the inertia tensor (about the COM, in the axes of the
/// inertial's `origin`) is rotated into link axes, `I = R I_o Rᵀ`, and
/// placed at the origin's `xyz`.
pub(super) fn urdf_moment(i: &urdf_rs::Inertial) -> Option<Matrix4<f64>> {
    if !(i.mass.value > 0.0) {
        return None;
    }
    let t = &i.inertia;
    let io = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    let r = rpy_to_matrix(&[i.origin.rpy[0], i.origin.rpy[1], i.origin.rpy[2]]);
    let g = crate::model::Inertial {
        mass: i.mass.value,
        com: Vector3::new(i.origin.xyz[0], i.origin.xyz[1], i.origin.xyz[2]),
        inertia: r * io * r.transpose(),
    };
    Some(g.second_moment())
}

/// `T M Tᵀ` with `T = [R t; 0 1]`: a second moment given in a child frame,
/// expressed in the parent frame (`x̃_parent = T x̃_child`).
pub(super) fn moved_moment(m: &Matrix4<f64>, r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix4<f64> {
    let mut tt = Matrix4::identity();
    tt.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    tt.fixed_view_mut::<3, 1>(0, 3).copy_from(t);
    tt * m * tt.transpose()
}

pub(super) fn compose_origin(a: &Origin, b: &Origin) -> Origin {
    let (ra, ta) = rt(a);
    let (rb, tb) = rt(b);
    let r = ra * rb;
    let t = ta + ra * tb;
    let (roll, pitch, yaw) = Rotation3::from_matrix_unchecked(r).euler_angles();
    Origin {
        xyz: [t.x, t.y, t.z],
        rpy: [roll, pitch, yaw],
    }
}
