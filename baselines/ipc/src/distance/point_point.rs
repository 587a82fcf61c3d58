//! Point–point squared distance `d = ‖p − q‖²` (m²).

use super::vec::{V3, norm2, sub};
use num_dual::DualNum;

/// `‖p − q‖²`.
pub fn point_point<T: DualNum<Primitive = f64> + Copy>(p: &V3<T>, q: &V3<T>) -> T {
    norm2(&sub(p, q))
}
