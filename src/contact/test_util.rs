//! Shared helpers for the contact and friction tests: hull generators, deliberate near-contact
//! configurations, finite differences.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x4, Rotation3, Unit, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn box_vertices(half: Vector3<f64>) -> Vec<Vector3<f64>> {
    let mut v = Vec::with_capacity(8);
    for i in 0..8 {
        let sx = if i & 1 == 0 { -1.0 } else { 1.0 };
        let sy = if i & 2 == 0 { -1.0 } else { 1.0 };
        let sz = if i & 4 == 0 { -1.0 } else { 1.0 };
        v.push(Vector3::new(sx * half.x, sy * half.y, sz * half.z));
    }
    v
}

/// Random points on a sphere of radius `r` (their hull is a convex polytope).
pub use crate::geometry::sampling::sphere_points;

pub fn random_rotation(rng: &mut ChaCha8Rng) -> Rotation3<f64> {
    let axis = loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.norm() > 0.1 {
            break Unit::new_normalize(v);
        }
    };
    Rotation3::from_axis_angle(&axis, rng.random_range(-3.1..3.1))
}

pub fn pose(rot: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix3x4<f64> {
    let mut a = Matrix3x4::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(rot);
    a.set_column(3, t);
    a
}

/// `G ∘ A` for a rigid `G = (rot, t)` applied on the left of a pose.
pub fn compose(rot: &Matrix3<f64>, t: &Vector3<f64>, a: &Matrix3x4<f64>) -> Matrix3x4<f64> {
    let mut out = rot * a;
    let c = out.column(3) + t;
    out.set_column(3, &c);
    out
}

pub fn world(a: &Matrix3x4<f64>, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    x.iter()
        .map(|v| a.fixed_columns::<3>(0) * v + a.column(3))
        .collect()
}

/// `(local_a, pose_a, local_b, pose_b)`.
pub type PosedPair = (
    Vec<Vector3<f64>>,
    Matrix3x4<f64>,
    Vec<Vector3<f64>>,
    Matrix3x4<f64>,
);

/// Kind of closest features in a deliberate near-contact configuration.
#[derive(Clone, Copy, Debug)]
pub enum Features {
    FaceFace,
    EdgeEdge,
    VertexFace,
}

/// A hull pair at gap `d` along +z (in a frame then moved by a random rigid transform):
/// `(local_a, pose_a, local_b, pose_b)`. The closest features are of the requested kind.
pub fn configuration(kind: Features, d: f64, rng: &mut ChaCha8Rng) -> PosedPair {
    let yaw = |a: f64| *Rotation3::from_axis_angle(&Vector3::z_axis(), a).matrix();
    let (la, ra, ta, lb, rb, tb) = match kind {
        Features::FaceFace => {
            let la = box_vertices(Vector3::new(0.5, 0.45, 0.5));
            let lb = box_vertices(Vector3::new(0.3, 0.35, 0.25));
            let off = Vector3::new(
                rng.random_range(-0.2..0.2),
                rng.random_range(-0.2..0.2),
                0.0,
            );
            let rb = yaw(rng.random_range(-1.0..1.0));
            (
                la,
                Matrix3::identity(),
                Vector3::zeros(),
                lb,
                rb,
                off + Vector3::new(0.0, 0.0, 0.75 + d),
            )
        }
        Features::EdgeEdge => {
            let la = box_vertices(Vector3::new(0.5, 0.5, 0.5));
            let lb = box_vertices(Vector3::new(0.4, 0.4, 0.4));
            let q = std::f64::consts::FRAC_PI_4;
            // a: top is an edge along x; b: bottom is an edge along y, then yawed a little.
            let ra = *Rotation3::from_axis_angle(&Vector3::x_axis(), q).matrix();
            let rb = yaw(rng.random_range(-0.5..0.5))
                * Rotation3::from_axis_angle(&Vector3::y_axis(), q).matrix();
            let ha = 0.5 * 2f64.sqrt();
            let hb = 0.4 * 2f64.sqrt();
            let off = Vector3::new(
                rng.random_range(-0.1..0.1),
                rng.random_range(-0.1..0.1),
                0.0,
            );
            (
                la,
                ra,
                Vector3::zeros(),
                lb,
                rb,
                off + Vector3::new(0.0, 0.0, ha + d + hb),
            )
        }
        Features::VertexFace => {
            let la = box_vertices(Vector3::new(0.5, 0.5, 0.4));
            // Tetrahedron with its tip at the local origin pointing down.
            let lb = vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(0.4, 0.0, 0.5),
                Vector3::new(-0.2, 0.35, 0.5),
                Vector3::new(-0.2, -0.35, 0.5),
            ];
            let tilt = Rotation3::from_axis_angle(
                &Unit::new_normalize(Vector3::new(rng.random_range(-1.0..1.0), 1.0, 0.0)),
                rng.random_range(-0.2..0.2),
            );
            let rb = yaw(rng.random_range(-3.0..3.0)) * tilt.matrix();
            let off = Vector3::new(
                rng.random_range(-0.2..0.2),
                rng.random_range(-0.2..0.2),
                0.0,
            );
            (
                la,
                Matrix3::identity(),
                Vector3::zeros(),
                lb,
                rb,
                off + Vector3::new(0.0, 0.0, 0.4 + d),
            )
        }
    };
    // Common random rigid motion so the contact normal is not axis-aligned.
    let g = random_rotation(rng);
    let gt = Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    );
    let pa = compose(g.matrix(), &gt, &pose(&ra, &ta));
    let pb = compose(g.matrix(), &gt, &pose(&rb, &tb));
    (la, pa, lb, pb)
}

/// Central-difference gradient of `f` at `x`.
pub fn fd_gradient(
    f: &mut dyn FnMut(&DVector<f64>) -> f64,
    x: &DVector<f64>,
    h: f64,
) -> DVector<f64> {
    let mut g = DVector::zeros(x.len());
    let mut xp = x.clone();
    for i in 0..x.len() {
        xp[i] = x[i] + h;
        let fp = f(&xp);
        xp[i] = x[i] - h;
        let fm = f(&xp);
        xp[i] = x[i];
        g[i] = (fp - fm) / (2.0 * h);
    }
    g
}

/// Central-difference Jacobian of a vector function (columns = inputs).
pub fn fd_jacobian(
    f: &mut dyn FnMut(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    h: f64,
) -> DMatrix<f64> {
    let mut cols = vec![];
    let mut xp = x.clone();
    for i in 0..x.len() {
        xp[i] = x[i] + h;
        let fp = f(&xp);
        xp[i] = x[i] - h;
        let fm = f(&xp);
        xp[i] = x[i];
        cols.push((fp - fm) / (2.0 * h));
    }
    DMatrix::from_columns(&cols)
}

/// `‖a − b‖ / max(‖a‖, ‖b‖, floor)` (Frobenius).
pub fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>, floor: f64) -> f64 {
    (a - b).norm() / a.norm().max(b.norm()).max(floor)
}

pub fn flatten(v: &[Vector3<f64>]) -> DVector<f64> {
    DVector::from_iterator(3 * v.len(), v.iter().flat_map(|x| [x.x, x.y, x.z]))
}

pub fn unflatten(v: &DVector<f64>) -> Vec<Vector3<f64>> {
    (0..v.len() / 3)
        .map(|i| Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
        .collect()
}

/// `[vec(A_a); vec(A_b)]` (column-major, 24 entries).
pub fn pose_params(a: &Matrix3x4<f64>, b: &Matrix3x4<f64>) -> DVector<f64> {
    DVector::from_iterator(24, a.as_slice().iter().chain(b.as_slice()).copied())
}

pub fn poses_from_params(p: &DVector<f64>) -> (Matrix3x4<f64>, Matrix3x4<f64>) {
    (
        Matrix3x4::from_column_slice(&p.as_slice()[..12]),
        Matrix3x4::from_column_slice(&p.as_slice()[12..]),
    )
}

/// Records the worst value of a named error measure (printed with `--nocapture`).
pub fn report(name: &str, value: f64) {
    eprintln!("[fd-report] {name}: {value:.3e}");
}

/// `Φ = Σ_m ∂U_c/∂X_m · δX_m` by the forward solver (cold start, barrier width `s`): the
/// directional derivative the adjoint and line-model tests difference.
pub fn directional_gradient(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    s: f64,
    d: &[Vector3<f64>],
) -> f64 {
    use super::{ContactParams, ContactScratch, VertexOutcome, contact_vertices};
    let mut sc = ContactScratch::new();
    match contact_vertices(xa, xb, &ContactParams::with_width(s), None, &mut sc).unwrap() {
        VertexOutcome::Separated(c) => c
            .grad_a
            .iter()
            .chain(&c.grad_b)
            .zip(d)
            .map(|(g, v)| g.dot(v))
            .sum(),
        VertexOutcome::OutOfRange { .. } => 0.0,
        VertexOutcome::Intersecting => panic!("intersecting"),
    }
}
