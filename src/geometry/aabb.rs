//! The axis-aligned bounding box: one type for the core's hull broad phase
//! ([`super::BroadPhase`]), its continuous collision detection
//! (`crate::contact::ccd`) and the IPC baseline's primitive broad phase.
//!
//! A box is the closed set `{x : lo ≤ x ≤ hi}` (componentwise, world frame,
//! m). Boxes are compared with closed intervals, so touching boxes
//! intersect; a box with a NaN bound intersects nothing.

use nalgebra::Vector3;

/// An axis-aligned box `[lo, hi]` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Componentwise lower corner.
    pub lo: Vector3<f64>,
    /// Componentwise upper corner.
    pub hi: Vector3<f64>,
}

impl Aabb {
    /// The empty box (`lo = +∞`, `hi = −∞`): the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        lo: Vector3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        hi: Vector3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    };

    /// The box of one point.
    pub fn point(p: &Vector3<f64>) -> Aabb {
        Aabb { lo: *p, hi: *p }
    }

    /// The tight box of `pts`: componentwise `f64::min` / `f64::max`
    /// (NaN coordinates are skipped); [`Aabb::EMPTY`] for no points.
    pub fn of_points<'a>(pts: impl IntoIterator<Item = &'a Vector3<f64>>) -> Aabb {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for v in pts {
            for e in 0..3 {
                lo[e] = lo[e].min(v[e]);
                hi[e] = hi[e].max(v[e]);
            }
        }
        Aabb {
            lo: Vector3::from(lo),
            hi: Vector3::from(hi),
        }
    }

    /// The box grown by `m` on every side: `[lo − m, hi + m]`.
    pub fn padded(&self, m: f64) -> Aabb {
        let d = Vector3::repeat(m);
        Aabb {
            lo: self.lo - d,
            hi: self.hi + d,
        }
    }

    /// The smallest box containing both (componentwise infimum of the lower
    /// corners, supremum of the upper ones).
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            lo: self.lo.inf(&o.lo),
            hi: self.hi.sup(&o.hi),
        }
    }

    /// Whether the closed intervals of the two boxes overlap along axis `e`
    /// (`false` when a bound is NaN).
    #[inline]
    pub fn overlaps_on(&self, o: &Aabb, e: usize) -> bool {
        o.lo[e] <= self.hi[e] && self.lo[e] <= o.hi[e]
    }

    /// Whether the boxes intersect (overlap on all three axes).
    pub fn intersects(&self, o: &Aabb) -> bool {
        (0..3).all(|e| self.lo[e] <= o.hi[e] && o.lo[e] <= self.hi[e])
    }

    /// The intersection (empty on some axis, `lo > hi`, when the boxes do
    /// not intersect).
    pub fn intersection(&self, o: &Aabb) -> Aabb {
        Aabb {
            lo: self.lo.sup(&o.lo),
            hi: self.hi.inf(&o.hi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_of_points_pad_union_and_intersect_as_sets() {
        let a = Aabb::of_points(&[Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 2.0, 3.0)]);
        assert_eq!(a.lo, Vector3::zeros());
        assert_eq!(a.hi, Vector3::new(1.0, 2.0, 3.0));
        // Touching boxes intersect (closed intervals); a gap of 1e-9 does not.
        let b = Aabb::point(&Vector3::new(1.0, 0.5, 0.5));
        assert!(a.intersects(&b) && b.intersects(&a));
        let c = Aabb::point(&Vector3::new(1.0 + 1e-9, 0.5, 0.5));
        assert!(!a.intersects(&c) && !a.overlaps_on(&c, 0) && a.overlaps_on(&c, 1));
        // Padding by the gap makes them meet.
        assert!(a.padded(1e-9).intersects(&c));
        assert_eq!(a.union(&c).hi.x, 1.0 + 1e-9);
        assert_eq!(Aabb::EMPTY.union(&a), a);
        let i = a.intersection(&a.padded(-0.25));
        assert_eq!(i, a.padded(-0.25));
        // A NaN bound intersects nothing.
        let n = Aabb::point(&Vector3::new(f64::NAN, 0.5, 0.5));
        assert!(!a.intersects(&n) && !n.intersects(&a));
    }
}
