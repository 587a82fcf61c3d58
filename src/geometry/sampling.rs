//! Seeded random shapes and poses for benchmarks and tests: points on a
//! sphere (their convex hull is a random convex polytope with every point a
//! vertex) and uniformly drawn rotation axes.

use nalgebra::{Matrix3, Matrix3x4, Rotation3, Unit, Vector3};
use rand::{Rng, RngExt};

/// `m` points on the sphere of radius `r` (m) about the origin, by rejection
/// sampling in the unit cube (uniform on the sphere).
pub fn sphere_points<R: Rng>(rng: &mut R, m: usize, r: f64) -> Vec<Vector3<f64>> {
    (0..m)
        .map(|_| {
            loop {
                let v = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let n = v.norm();
                if n > 1e-3 && n <= 1.0 {
                    break v * (r / n);
                }
            }
        })
        .collect()
}

/// A rotation about a random axis by an angle uniform in (−3.1, 3.1) rad.
pub fn random_rotation<R: Rng>(rng: &mut R) -> Matrix3<f64> {
    let axis = Unit::new_normalize(Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ));
    *Rotation3::from_axis_angle(&axis, rng.random_range(-3.1..3.1)).matrix()
}

/// The pose `[R | t]` (world from body).
pub fn pose(r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix3x4<f64> {
    let mut a = Matrix3x4::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    a.set_column(3, t);
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn points_lie_on_the_sphere_and_rotations_are_orthonormal() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for p in sphere_points(&mut rng, 200, 0.3) {
            assert!((p.norm() - 0.3).abs() < 1e-12);
        }
        for _ in 0..20 {
            let r = random_rotation(&mut rng);
            assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
            assert!((r.determinant() - 1.0).abs() < 1e-12);
        }
    }
}
