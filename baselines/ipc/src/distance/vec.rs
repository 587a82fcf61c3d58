//! Minimal 3-vector arithmetic over any [`DualNum`] scalar, so every
//! distance formula is written once and differentiated exactly (value,
//! gradient and Hessian) by forward-mode hyper-dual numbers.

use num_dual::DualNum;

/// A 3-vector of scalars `T` (plain `f64` or a dual number).
pub type V3<T> = [T; 3];

pub fn sub<T: DualNum<Primitive = f64> + Copy>(a: &V3<T>, b: &V3<T>) -> V3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn dot<T: DualNum<Primitive = f64> + Copy>(a: &V3<T>, b: &V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross<T: DualNum<Primitive = f64> + Copy>(a: &V3<T>, b: &V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm2<T: DualNum<Primitive = f64> + Copy>(a: &V3<T>) -> T {
    dot(a, a)
}
