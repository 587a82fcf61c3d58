//! World-space vertices of every hull, recomputed from link poses.

use crate::math::{Pose, transform_point};
use crate::model::Model;
use nalgebra::{Matrix3x4, Vector3};

/// A hull placed in the world: `X = pose · [x_local; 1]`.
#[derive(Clone, Copy, Debug)]
pub struct HullPose<'a> {
    /// Link pose `A = [R | t]` (3×4); any affine map is accepted.
    pub pose: &'a Matrix3x4<f64>,
    /// Link-local vertices (V-representation: the body is their convex hull).
    pub x_local: &'a [Vector3<f64>],
}

/// A hull of the model: `(link, hull index within the link)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct HullId {
    pub link: usize,
    pub hull: usize,
}

/// World vertices `X = A_link x_local` of every hull of the colliding links,
/// in one flat buffer (reused between evaluations: no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct WorldHulls {
    /// The hulls, in model order.
    pub ids: Vec<HullId>,
    /// `range[h]` indexes `vertices` for hull `h`.
    pub ranges: Vec<std::ops::Range<usize>>,
    pub vertices: Vec<Vector3<f64>>,
}

impl WorldHulls {
    /// Lists the hulls of links that collide.
    pub fn new(model: &Model) -> Self {
        let mut w = WorldHulls::default();
        let mut n = 0;
        for (link, l) in model.links.iter().enumerate() {
            if !l.collides {
                continue;
            }
            for (hull, h) in l.hulls.iter().enumerate() {
                w.ids.push(HullId { link, hull });
                w.ranges.push(n..n + h.x_local.len());
                n += h.x_local.len();
            }
        }
        w.vertices = vec![Vector3::zeros(); n];
        w
    }

    /// The link-frame box of every hull: `(centre c, half-extents e)` (m).
    pub fn local_boxes(&self, model: &Model) -> Vec<(Vector3<f64>, Vector3<f64>)> {
        self.ids
            .iter()
            .map(|id| {
                let b =
                    crate::geometry::Aabb::of_points(&model.links[id.link].hulls[id.hull].x_local);
                ((b.lo + b.hi) * 0.5, (b.hi - b.lo) * 0.5)
            })
            .collect()
    }

    /// A world box containing hull `h` at its link pose `A = [R | t]`,
    /// from its link-frame box `(c, e)` ([`WorldHulls::local_boxes`]):
    /// centre `R c + t`, half-extents `|R| e` (componentwise absolute
    /// values), grown by a relative 1e-12 and 1e-15 m so that rounding never
    /// leaves a vertex outside. At most √3 × the tight box's size; no vertex
    /// is touched.
    pub fn enclosing_box(
        pose: &Pose,
        local: &(Vector3<f64>, Vector3<f64>),
    ) -> crate::geometry::Aabb {
        let r = pose.fixed_view::<3, 3>(0, 0);
        let centre = r * local.0 + pose.column(3);
        let half = r.abs() * local.1;
        let grow = half * 1e-12 + centre.abs() * 1e-15 + Vector3::repeat(1e-15);
        crate::geometry::Aabb {
            lo: centre - half - grow,
            hi: centre + half + grow,
        }
    }

    /// [`WorldHulls::enclosing_box`] of every hull at the link poses
    /// `poses`, from its link-frame box `local[h]`, into `out`.
    pub fn enclosing_boxes(
        &self,
        local: &[(Vector3<f64>, Vector3<f64>)],
        poses: &[Pose],
        out: &mut Vec<crate::geometry::Aabb>,
    ) {
        out.clear();
        out.extend(
            self.ids
                .iter()
                .zip(local)
                .map(|(id, l)| Self::enclosing_box(&poses[id.link], l)),
        );
    }

    /// Recomputes world vertices for link poses `poses`.
    pub fn update(&mut self, model: &Model, poses: &[Pose]) {
        for h in 0..self.ids.len() {
            self.update_hull(model, poses, h);
        }
    }

    /// Recomputes the world vertices of hull `h` only.
    pub fn update_hull(&mut self, model: &Model, poses: &[Pose], h: usize) {
        let id = self.ids[h];
        let a = &poses[id.link];
        let local = &model.links[id.link].hulls[id.hull].x_local;
        for (x, xl) in self.vertices[self.ranges[h].clone()].iter_mut().zip(local) {
            *x = transform_point(a, xl);
        }
    }

    /// Hull `h` as the contact functions take it: its link's pose in
    /// `poses` and its link-frame vertices.
    pub fn hull_pose<'a>(&self, model: &'a Model, poses: &'a [Pose], h: usize) -> HullPose<'a> {
        let id = self.ids[h];
        HullPose {
            pose: &poses[id.link],
            x_local: &model.links[id.link].hulls[id.hull].x_local,
        }
    }

    /// World vertices of hull `h`.
    pub fn hull(&self, h: usize) -> &[Vector3<f64>] {
        &self.vertices[self.ranges[h].clone()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::math::{pose_from, rpy_to_matrix, transform_point};
    use rand::{RngExt, SeedableRng};

    /// The enclosing box contains every vertex of the posed hull, also for
    /// hulls far from the origin and nearly axis-aligned rotations (where
    /// the tight box is the enclosing one up to rounding), and is at most
    /// √3 (+ its margin) times the tight box along each axis.
    #[test]
    fn enclosing_box_contains_the_posed_hull() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for trial in 0..2000 {
            let far = if trial % 2 == 0 { 1.0 } else { 1e3 };
            let pts: Vec<Vector3<f64>> = (0..12)
                .map(|_| {
                    Vector3::new(
                        rng.random_range(-0.3..0.3),
                        rng.random_range(-0.1..0.1),
                        rng.random_range(-0.2..0.2),
                    ) + Vector3::repeat(far)
                })
                .collect();
            let b = Aabb::of_points(&pts);
            let local = ((b.lo + b.hi) * 0.5, (b.hi - b.lo) * 0.5);
            let scale = if trial % 3 == 0 { 1e-9 } else { 3.0 };
            let r = rpy_to_matrix(&[
                rng.random_range(-scale..scale),
                rng.random_range(-scale..scale),
                rng.random_range(-scale..scale),
            ]);
            let pose = pose_from(&r, &Vector3::new(far, -far, 0.5 * far));
            let enc = WorldHulls::enclosing_box(&pose, &local);
            let world: Vec<Vector3<f64>> = pts.iter().map(|x| transform_point(&pose, x)).collect();
            let tight = Aabb::of_points(&world);
            for e in 0..3 {
                assert!(
                    enc.lo[e] <= tight.lo[e] && tight.hi[e] <= enc.hi[e],
                    "trial {trial}"
                );
                let (we, wt) = (enc.hi[e] - enc.lo[e], tight.hi[e] - tight.lo[e]);
                assert!(
                    we <= 3f64.sqrt() * (b.hi - b.lo).norm() + 1e-9 * far,
                    "trial {trial}"
                );
                assert!(we >= wt);
            }
        }
    }
}
