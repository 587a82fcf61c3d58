//! `design.rest_on_ground`: a free-floating designed robot starts at the
//! clearance above the ground that the task's initial design has.
//!
//! Without it the robot's initial pose is the scene's whatever the design: a
//! design that lowers a sole starts with that sole inside the barrier's
//! support (or, lowered further, cannot start at all), and the first step
//! launches the robot off the ground — the biped under the paper's step
//! rule lowered one sole from 20.2 to 2.4–6 mm above the ground and every
//! such start needed 200–556 Newton iterations in its first step
//! (`notes/paper-step-rule.md`).
//!
//! With `n` the ground's unit normal and `o` a point of its surface, the
//! clearance of the robot at design `d` is the height of its lowest hull
//! vertex at `θ^0`,
//!
//! ```text
//! m(d) = min_{l, h, v} nᵀ (R_l x_lhv(d) + t_l − o)        (m)
//! ```
//!
//! (`A_l = [R_l | t_l]` the link poses at `θ^0`, which do not depend on the
//! hull vertices). The robot is moved along `n` by `δ(d) = m(d₀) − m(d)`
//! through its root's world attachment `t_root ← t_root + δ n`, so its lowest
//! vertex keeps the initial design's clearance `m(d₀)`. The loss's gradient
//! gains, on the lowest vertex `x*` of link `l*` (the minimum is piecewise
//! linear in `d`; at a tie the first vertex in link, hull, vertex order is
//! taken),
//!
//! ```text
//! ∂L/∂x* += (∂L/∂t_root · n) ∂δ/∂x* = −(∂L/∂t_root · n) R_l*ᵀ n .
//! ```

use crate::diff::Gradients;
use crate::kinematics::{KinOrder, Kinematics};
use crate::math::Pose;
use crate::model::Model;
use crate::scene::Scene;
use nalgebra::Vector3;

/// The placement of one free-floating robot (see the module docs).
#[derive(Clone, Debug)]
pub struct RestOnGround {
    /// The robot's root link (free joint), whose attachment is moved.
    pub root: usize,
    /// The robot's links and their poses at `θ^0` (world).
    pub poses: Vec<(usize, Pose)>,
    /// Ground normal `n` (unit, world).
    pub normal: Vector3<f64>,
    /// A point `o` of the ground's surface (world, m).
    pub origin: Vector3<f64>,
    /// `m(d₀)`: the initial design's clearance (m).
    pub clearance: f64,
}

/// The lowest hull vertex of a placement: its height `m` above the ground
/// (m) and its link, hull and vertex indices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lowest {
    pub height: f64,
    pub link: usize,
    pub hull: usize,
    pub vertex: usize,
}

impl RestOnGround {
    /// One placement per robot of `robots` (model robot indices) whose root
    /// has a free joint and whose links have hulls, on `scene`'s ground at
    /// `scene`'s initial state, with `model`'s (initial) hulls. `Err` names
    /// what is missing (no ground; a robot without a free root or hulls).
    pub fn build(
        scene: &Scene,
        model: &Model,
        robots: &[usize],
    ) -> Result<Vec<RestOnGround>, String> {
        let ground = model
            .links
            .iter()
            .position(|l| l.name == "ground" && l.parent.is_none() && !l.hulls.is_empty())
            .ok_or("needs a `ground:` in the scene")?;
        let attach = &model.links[ground].attach;
        let normal = attach.fixed_view::<3, 1>(0, 2).into_owned();
        let origin = attach.column(3).into_owned();
        let mut kin = Kinematics::new(model);
        kin.update(model, &scene.q0, &scene.charts, KinOrder::Pose);
        let mut out = Vec::new();
        for &r in robots {
            let links: Vec<usize> = (0..model.links.len())
                .filter(|&l| model.links[l].robot == r)
                .collect();
            let name = &model.robots[r].name;
            let root = links
                .iter()
                .copied()
                .find(|&l| model.links[l].parent.is_none())
                .filter(|&l| model.links[l].joint == crate::model::JointKind::Free)
                .ok_or_else(|| format!("robot {name}: its root has no free joint"))?;
            let mut place = RestOnGround {
                root,
                poses: links.iter().map(|&l| (l, kin.pose[l])).collect(),
                normal,
                origin,
                clearance: 0.0,
            };
            place.clearance = place
                .lowest(model)
                .ok_or_else(|| format!("robot {name}: no hull vertices"))?
                .height;
            out.push(place);
        }
        Ok(out)
    }

    /// The lowest hull vertex of the robot with `model`'s hulls, at the
    /// stored poses (`None` without hull vertices).
    pub fn lowest(&self, model: &Model) -> Option<Lowest> {
        let mut best: Option<Lowest> = None;
        for (l, pose) in &self.poses {
            let r = pose.fixed_view::<3, 3>(0, 0);
            let t = pose.column(3);
            for (h, hull) in model.links[*l].hulls.iter().enumerate() {
                for (v, x) in hull.x_local.iter().enumerate() {
                    let height = self.normal.dot(&(r * x + t - self.origin));
                    if best.is_none_or(|b| height < b.height) {
                        best = Some(Lowest {
                            height,
                            link: *l,
                            hull: h,
                            vertex: v,
                        });
                    }
                }
            }
        }
        best
    }

    /// `δ(d) = m(d₀) − m(d)` for `model`'s hulls (m; 0 without hulls).
    pub fn shift(&self, model: &Model) -> f64 {
        self.lowest(model)
            .map_or(0.0, |b| self.clearance - b.height)
    }

    /// Moves the robot of `model` (its hulls at design `d`) by `δ(d) n`.
    pub fn place(&self, model: &mut Model) {
        let delta = self.shift(model);
        let mut t = model.links[self.root].attach.column(3).into_owned();
        t += self.normal * delta;
        model.links[self.root].attach.set_column(3, &t);
    }

    /// Adds `δ`'s share to the vertex gradient of `grads` (computed on a
    /// model placed by [`RestOnGround::place`], whose hulls are `model`'s):
    /// `−(∂L/∂t_root · n) R_l*ᵀ n` on the lowest vertex.
    pub fn add_gradient(&self, model: &Model, grads: &mut Gradients) {
        let Some(b) = self.lowest(model) else {
            return;
        };
        let dl_dshift = grads.attachments[self.root].dot(&self.normal);
        let pose = &self
            .poses
            .iter()
            .find(|(l, _)| *l == b.link)
            .expect("a link of the robot")
            .1;
        let r = pose.fixed_view::<3, 3>(0, 0);
        grads.vertices[b.link][b.hull][b.vertex] -= dl_dshift * (r.transpose() * self.normal);
    }
}
