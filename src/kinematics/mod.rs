//! Forward kinematics `A_i(d, θ)` and its derivatives.
//!
//! Recursion (paper, `pbad.tex`): `A_i = A_λ(i) · C_i · J_i(q_i)`. We call
//! `P_i = A_λ(i) C_i` the *pre-joint* frame. Every derivative of a link pose is
//! a world-frame matrix applied on the left:
//!
//! - `∂A_i/∂θ_k = S_k Ã_i` for every coordinate `k` of an ancestor-or-self
//!   joint `a`, with `S_k = (P_a ∂J_a/∂q_k) Ã_a⁻¹` (a twist: `[ω]× | v`);
//! - `∂²A_i/∂θ_k∂θ_l = S_k S_l Ã_i` when `k`'s joint is a proper ancestor of
//!   `l`'s joint (order matters), and `= S_kl Ã_i` with
//!   `S_kl = (P_a ∂²J_a/∂q_k∂q_l) Ã_a⁻¹` when both belong to the same joint;
//! - `∂A_i/∂t_c = [0 | R_λ(c) e]` for the attachment point `t_c` of an
//!   ancestor-or-self link `c` (a world translation of the whole subtree);
//! - `∂x_world/∂x_local = R_i` for a hull vertex of link `i`.
//!
//! This lets the assembler reduce every per-link quantity to 3×4 matrices and
//! never build dense per-vertex Jacobians.

pub mod motion_bound;

pub use motion_bound::{SegmentMotion, hull_radii};

use crate::math::{Pose, compose, pose_from, rot, skew, trans, twist_apply};
use crate::model::{JointDerivatives, JointKind, Model};
use nalgebra::{DVector, Matrix3, Matrix3x4, Vector3};

/// How much of the kinematics to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum KinOrder {
    /// Poses only.
    Pose,
    /// Poses and first-derivative twists `S_k`.
    First,
    /// Also the same-joint second-derivative matrices `S_kl`.
    Second,
}

/// Kinematic quantities of one configuration (reused between evaluations:
/// allocate once with [`Kinematics::new`]).
#[derive(Clone, Debug)]
pub struct Kinematics {
    /// World pose `A_i` of every link.
    pub pose: Vec<Pose>,
    /// Pre-joint frame `P_i = A_λ(i) C_i`.
    pub pre: Vec<Pose>,
    /// Local joint transforms and their coordinate derivatives.
    pub local: Vec<JointDerivatives>,
    /// World twist `S_k` of every coordinate.
    pub twist: Vec<Matrix3x4<f64>>,
    /// Same-joint second-derivative matrices `S_kl`, per link, row-major
    /// `ndof × ndof` starting at `twist2_offset[i]`.
    pub twist2: Vec<Matrix3x4<f64>>,
    pub twist2_offset: Vec<usize>,
    pub order: KinOrder,
    /// The coordinates and charts of the last full evaluation
    /// ([`Kinematics::update_cached`]).
    key: EvalKey,
}

/// Coordinates and chart centres, compared bit for bit.
#[derive(Clone, Debug, Default)]
struct EvalKey {
    valid: bool,
    q: Vec<f64>,
    charts: Vec<Matrix3<f64>>,
}

impl EvalKey {
    fn set(&mut self, q: &DVector<f64>, charts: &[Matrix3<f64>]) {
        self.q.clear();
        self.q.extend_from_slice(q.as_slice());
        self.charts.clear();
        self.charts.extend_from_slice(charts);
        self.valid = true;
    }

    fn clear(&mut self) {
        self.valid = false;
    }

    fn matches(&self, q: &DVector<f64>, charts: &[Matrix3<f64>]) -> bool {
        let bits = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        self.valid
            && bits(&self.q, q.as_slice())
            && self.charts.len() == charts.len()
            && self
                .charts
                .iter()
                .zip(charts)
                .all(|(a, b)| bits(a.as_slice(), b.as_slice()))
    }
}

/// `[dR Rᵀ | dt − dR Rᵀ t]`: the world matrix `S` with `D = S Ã` for a
/// pose-derivative `D = [dR | dt]` of the pose `A = [R | t]`.
fn right_divide(d: &Pose, a: &Pose) -> Matrix3x4<f64> {
    let drrt = d.fixed_view::<3, 3>(0, 0) * rot(a).transpose();
    let col = d.column(3) - drrt * trans(a);
    let mut s = Matrix3x4::zeros();
    s.fixed_view_mut::<3, 3>(0, 0).copy_from(&drrt);
    s.set_column(3, &col);
    s
}

/// `P ∘ D` for a pose `P` and a pose-derivative `D` (no translation added).
fn apply_linear(p: &Pose, d: &Pose) -> Pose {
    p.fixed_view::<3, 3>(0, 0) * d
}

/// The axes of a hinge-type joint (revolute, prismatic, ball: fixed axes in
/// the joint frame), whose world twists have a closed form.
#[derive(Clone, Copy, Debug)]
enum HingeAxes<'a> {
    /// One rotation axis `a` (unit, joint frame).
    Revolute(&'a Vector3<f64>),
    /// One translation axis `a` (unit, joint frame).
    Prismatic(&'a Vector3<f64>),
    /// `J = Rot(a₁, q₁) Rot(a₂, q₂)`.
    Ball(&'a [Vector3<f64>; 2]),
}

/// The twist `[[ω]× | −ω × t]` of a rotation about the world axis `ω`
/// through the point `t` (world, m): `∂A/∂q = S Ã` for a link at `t`.
fn rotation_twist(w: &Vector3<f64>, t: &Vector3<f64>) -> Matrix3x4<f64> {
    pose_from(&skew(w), &(-w.cross(t)))
}

/// `[[ω_a]×[ω_b]× | −[ω_a]×[ω_b]× t]`, with `[ω_a]×[ω_b]× = ω_b ω_aᵀ − (ω_a·ω_b) I`.
fn rotation_twist2(wa: &Vector3<f64>, wb: &Vector3<f64>, t: &Vector3<f64>) -> Matrix3x4<f64> {
    let m = wb * wa.transpose() - Matrix3::identity() * wa.dot(wb);
    pose_from(&m, &(-(m * t)))
}

impl<'a> HingeAxes<'a> {
    fn of(joint: &'a JointKind) -> Option<Self> {
        match joint {
            JointKind::Revolute { axis } => Some(HingeAxes::Revolute(axis)),
            JointKind::Prismatic { axis } => Some(HingeAxes::Prismatic(axis)),
            JointKind::Ball { axes } => Some(HingeAxes::Ball(axes)),
            _ => None,
        }
    }

    /// World twists `S_k = (P ∂J/∂q_k) Ã⁻¹` and, for [`KinOrder::Second`],
    /// `S_kl = (P ∂²J/∂q_k∂q_l) Ã⁻¹` of the pre-joint frame `P = [R_P | ·]`
    /// and the link pose `A = [R_A | t]`, in closed form (`∂R/∂q = K R`,
    /// `R K Rᵀ = [R a]×`):
    ///
    /// - revolute: `ω = R_P a`, `S = [[ω]× | −ω × t]`, `S₀₀ = [ω]×²` (with
    ///   the translation `−S₀₀ t`);
    /// - prismatic: `S = [0 | R_P a]`, `S₀₀ = 0`;
    /// - ball: `ω₁ = R_P a₁`, `ω₂ = R_A a₂` (`= R_P R₁ a₂`, as `R₂ a₂ = a₂`),
    ///   `S_k = [[ω_k]× | −ω_k × t]`, `S₁₁ = [ω₁]×²`, `S₁₂ = S₂₁ = [ω₁]×[ω₂]×`,
    ///   `S₂₂ = [ω₂]×²`.
    fn twists(
        self,
        pre: &Pose,
        pose: &Pose,
        order: KinOrder,
        s1: &mut [Matrix3x4<f64>],
        s2: &mut [Matrix3x4<f64>],
    ) {
        let r_pre = pre.fixed_view::<3, 3>(0, 0);
        let t = trans(pose);
        let second = order >= KinOrder::Second;
        match self {
            HingeAxes::Revolute(a) => {
                let w = r_pre * a;
                s1[0] = rotation_twist(&w, &t);
                if second {
                    s2[0] = rotation_twist2(&w, &w, &t);
                }
            }
            HingeAxes::Prismatic(a) => {
                s1[0] = pose_from(&Matrix3::zeros(), &(r_pre * a));
                if second {
                    s2[0] = Matrix3x4::zeros();
                }
            }
            HingeAxes::Ball(axes) => {
                let w1 = r_pre * axes[0];
                let w2 = pose.fixed_view::<3, 3>(0, 0) * axes[1];
                s1[0] = rotation_twist(&w1, &t);
                s1[1] = rotation_twist(&w2, &t);
                if second {
                    s2[0] = rotation_twist2(&w1, &w1, &t);
                    s2[1] = rotation_twist2(&w1, &w2, &t);
                    s2[2] = s2[1];
                    s2[3] = rotation_twist2(&w2, &w2, &t);
                }
            }
        }
    }
}

impl Kinematics {
    /// The world twist of every link along a coordinate direction `λ`:
    /// `S_i(λ) = Σ_{k ∈ anc(i)} λ_k S_k` (world twists `S_k` at the last
    /// evaluation, order [`KinOrder::First`] or higher), accumulated down the
    /// tree into `twists` (one 3×4 `[Ω | v]` per link: a point `X` of link `i`
    /// moves at `Ω X + v` per unit of `λ`).
    pub fn twist_direction(
        &self,
        model: &Model,
        lambda: &DVector<f64>,
        twists: &mut Vec<Matrix3x4<f64>>,
    ) {
        twists.clear();
        twists.resize(model.links.len(), Matrix3x4::zeros());
        for (i, link) in model.links.iter().enumerate() {
            let mut s = link.parent.map_or_else(Matrix3x4::zeros, |p| twists[p]);
            for k in link.dof_offset..link.dof_offset + link.ndof() {
                s += self.twist[k] * lambda[k];
            }
            twists[i] = s;
        }
    }

    /// The pose-space direction of a coordinate direction `λ`:
    /// `δA_i = S_i(λ) Ã_i` ([`Kinematics::twist_direction`]), into `dpose`
    /// (one entry per link). Returns the twists `S_i(λ)`. Used by the adjoint
    /// (`λ` the adjoint vector).
    pub fn pose_direction(
        &self,
        model: &Model,
        lambda: &DVector<f64>,
        dpose: &mut [Pose],
    ) -> Vec<Matrix3x4<f64>> {
        let mut s_acc = Vec::new();
        self.twist_direction(model, lambda, &mut s_acc);
        for (i, s) in s_acc.iter().enumerate() {
            dpose[i] = twist_apply(s, &self.pose[i]);
        }
        s_acc
    }

    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        let mut twist2_offset = Vec::with_capacity(n);
        let mut total = 0;
        for l in &model.links {
            twist2_offset.push(total);
            total += l.ndof() * l.ndof();
        }
        Kinematics {
            pose: vec![Pose::identity(); n],
            pre: vec![Pose::identity(); n],
            local: vec![JointDerivatives::default(); n],
            twist: vec![Matrix3x4::zeros(); model.ndof()],
            twist2: vec![Matrix3x4::zeros(); total],
            twist2_offset,
            order: KinOrder::Pose,
            key: EvalKey::default(),
        }
    }

    /// Evaluates the kinematics at coordinates `q` with chart centres `charts`.
    pub fn update(
        &mut self,
        model: &Model,
        q: &DVector<f64>,
        charts: &[Matrix3<f64>],
        order: KinOrder,
    ) {
        self.order = order;
        for i in 0..model.links.len() {
            self.update_link(model, i, q, charts, order, true);
        }
        self.key.set(q, charts);
    }

    /// As [`Kinematics::update`], but when `q` and `charts` are bit for bit
    /// those of this object's last evaluation the poses are kept and only
    /// the derivative orders it lacks are computed (the same bits as a
    /// fresh evaluation). `model` must be the model of that evaluation: the
    /// caller owns both (the simulator re-evaluates an accepted trial point
    /// with derivatives, and the accepted step's poses).
    pub fn update_cached(
        &mut self,
        model: &Model,
        q: &DVector<f64>,
        charts: &[Matrix3<f64>],
        order: KinOrder,
    ) {
        if !self.key.matches(q, charts) {
            return self.update(model, q, charts, order);
        }
        if order > self.order {
            for i in 0..model.links.len() {
                self.update_link(model, i, q, charts, order, false);
            }
            self.order = order;
        }
    }

    /// As [`Kinematics::update`]`(model, q, charts, KinOrder::Pose)`, but
    /// when `other`'s last full evaluation was at `q` and `charts` bit for
    /// bit, its poses are copied instead (the same bits as a fresh
    /// evaluation; `other` is left as it was, so a cache hit there stays
    /// one). The simulator's step starts at the state its last step
    /// accepted, whose kinematics that step evaluated. `model` must be the
    /// model of `other`'s evaluation.
    pub fn update_or_copy(
        &mut self,
        other: &Kinematics,
        model: &Model,
        q: &DVector<f64>,
        charts: &[Matrix3<f64>],
    ) {
        if !other.key.matches(q, charts) || other.pose.len() != self.pose.len() {
            return self.update(model, q, charts, KinOrder::Pose);
        }
        self.order = KinOrder::Pose;
        self.pose.copy_from_slice(&other.pose);
        self.pre.copy_from_slice(&other.pre);
        for (mine, theirs) in self.local.iter_mut().zip(&other.local) {
            mine.value = theirs.value;
        }
        self.key.set(q, charts);
    }

    /// Link `i`'s pose (when `with_pose`; otherwise the stored `pre`, `pose`
    /// are those of `q`) and its twists up to `order`.
    fn update_link(
        &mut self,
        model: &Model,
        i: usize,
        q: &DVector<f64>,
        charts: &[Matrix3<f64>],
        order: KinOrder,
        with_pose: bool,
    ) {
        let link = &model.links[i];
        let chart = link
            .chart
            .map(|c| charts[c])
            .unwrap_or_else(Matrix3::identity);
        let n = link.ndof();
        let qi = q.rows(link.dof_offset, n);
        let local = &mut self.local[i];
        let hinge = HingeAxes::of(&link.joint);
        if order == KinOrder::Pose || n == 0 || hinge.is_some() {
            if with_pose {
                local.value = link.joint.transform(&chart, qi.as_slice());
            }
        } else {
            link.joint
                .transform_derivatives(&chart, qi.as_slice(), local);
        }
        if with_pose {
            self.pre[i] = match link.parent {
                Some(p) => compose(&self.pose[p], &link.attach),
                None => link.attach,
            };
            self.pose[i] = compose(&self.pre[i], &local.value);
        }
        let (pre, pose) = (&self.pre[i], &self.pose[i]);
        let twists = &mut self.twist[link.dof_offset..link.dof_offset + n];
        let off = self.twist2_offset[i];
        let twists2 = &mut self.twist2[off..off + n * n];
        match hinge {
            Some(axes) if order >= KinOrder::First => {
                axes.twists(pre, pose, order, twists, twists2);
            }
            _ => {
                if order >= KinOrder::First {
                    for (s, d1) in twists.iter_mut().zip(&local.d1) {
                        *s = right_divide(&apply_linear(pre, d1), pose);
                    }
                }
                if order >= KinOrder::Second {
                    for k in 0..n {
                        for l in 0..n {
                            twists2[k * n + l] =
                                right_divide(&apply_linear(pre, &local.d2[k][l]), pose);
                        }
                    }
                }
            }
        }
    }

    /// Poses only (as [`Kinematics::update`] with [`KinOrder::Pose`], the
    /// same operations bit for bit) of the links with `needed[i]`; every
    /// ancestor of a needed link must be needed too. The other links keep
    /// whatever they held.
    pub fn update_poses_where(
        &mut self,
        model: &Model,
        q: &DVector<f64>,
        charts: &[Matrix3<f64>],
        needed: &[bool],
    ) {
        self.order = KinOrder::Pose;
        self.key.clear();
        for (i, link) in model.links.iter().enumerate() {
            if !needed[i] {
                continue;
            }
            let pre = match link.parent {
                Some(p) => compose(&self.pose[p], &link.attach),
                None => link.attach,
            };
            let chart = link
                .chart
                .map(|c| charts[c])
                .unwrap_or_else(Matrix3::identity);
            let qi = q.rows(link.dof_offset, link.ndof());
            let local = &mut self.local[i];
            local.value = link.joint.transform(&chart, qi.as_slice());
            self.pose[i] = compose(&pre, &local.value);
            self.pre[i] = pre;
        }
    }

    /// `∂A_i/∂θ_k` (zero when `k` does not move link `i`).
    pub fn dpose(&self, model: &Model, link: usize, k: usize) -> Pose {
        if model.ancestor_dofs[link].binary_search(&k).is_ok() {
            twist_apply(&self.twist[k], &self.pose[link])
        } else {
            Pose::zeros()
        }
    }

    /// Same-joint second twist `S_kl` for coordinates `k, l` of link `j`'s joint.
    pub fn twist2(&self, model: &Model, j: usize, k: usize, l: usize) -> &Matrix3x4<f64> {
        let n = model.links[j].ndof();
        let o = model.links[j].dof_offset;
        &self.twist2[self.twist2_offset[j] + (k - o) * n + (l - o)]
    }

    /// `∂A_i/∂t_c[e]`: derivative of link `i`'s pose w.r.t. component `e` of
    /// the attachment point of link `c` (zero unless `c` is an ancestor or
    /// `i` itself). The attachment point is expressed in `c`'s parent frame.
    pub fn dpose_attachment(&self, model: &Model, link: usize, c: usize, e: usize) -> Pose {
        if !model.is_ancestor_or_self(c, link) {
            return Pose::zeros();
        }
        let r_parent = match model.links[c].parent {
            Some(p) => rot(&self.pose[p]),
            None => Matrix3::identity(),
        };
        let dir: Vector3<f64> = r_parent.column(e).into_owned();
        pose_from(&Matrix3::zeros(), &dir)
    }
}

/// Poses only, for callers that do not need derivatives.
pub fn link_poses(model: &Model, q: &DVector<f64>, charts: &[Matrix3<f64>]) -> Vec<Pose> {
    let mut k = Kinematics::new(model);
    k.update(model, q, charts, KinOrder::Pose);
    k.pose
}

#[cfg(test)]
mod tests;
