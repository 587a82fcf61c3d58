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
