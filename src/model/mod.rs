//! The robot model: links made of convex hulls, joints, the kinematic tree.
//!
//! All robots and objects of a scene are flattened into one [`Model`] whose
//! links are in topological order (a parent always precedes its children), and
//! whose generalized coordinates `θ` are the concatenation of the joints'
//! coordinates in link order.

pub mod hull;
pub mod joint;
pub mod mass;

pub use hull::{Hull, HullError};
pub use joint::{JointDerivatives, JointKind, JointLimit, MAX_JOINT_DOF, MimicTie};
pub use mass::{Inertial, MassModel};

use crate::math::Pose;
use nalgebra::{Matrix4, Vector3, Vector4};

/// One rigid link.
#[derive(Clone, Debug)]
pub struct Link {
    /// Link name (unique within its robot).
    pub name: String,
    /// Index of the robot this link belongs to.
    pub robot: usize,
    /// Parent link index in [`Model::links`], `None` for a root (attached to
    /// the world through its robot's base pose).
    pub parent: Option<usize>,
    /// Name of the joint connecting the link to its parent.
    pub joint_name: String,
    /// Joint kind.
    pub joint: JointKind,
    /// Position limits of a revolute/prismatic joint (barrier term).
    pub limit: Option<JointLimit>,
    /// Attachment transform `C_i = [R_i^d | t_i^d]` in the parent frame (for a
    /// root: in the world frame). `t_i^d` is the attachment point, a design
    /// variable.
    pub attach: Pose,
    /// The link's hulls, in the link frame.
    pub hulls: Vec<Hull>,
    /// How the link's mass is distributed (default: at the hull vertices).
    pub mass_model: MassModel,
    /// Per hull, its boundary triangles (indices into `x_local`) for
    /// [`MassModel::Solid`]; empty for the other models. Kept up to date by
    /// [`Model::new`] and [`Model::refresh_moments`].
    pub solid_triangles: Vec<Vec<[usize; 3]>>,
    /// Index of the joint's first coordinate in `θ`.
    pub dof_offset: usize,
    /// Index into the state's chart list for spherical/free joints.
    pub chart: Option<usize>,
    /// Whether the link takes part in contact (objects and robot links do;
    /// massless helper links may not). Reserved for the contact stage.
    pub collides: bool,
    /// Vertices (link frame, m) of a contact surface a factory-provided
    /// contact model uses instead of the hulls, when a design moves it: the
    /// IPC baseline's source mesh under a cage design (`sdrs_ipc::cage`).
    /// Empty by default; no core term reads it. It lives in the model so
    /// design variables can write it ([`crate::optimize::design::Target::SurfaceBlend`])
    /// and the backward pass can return its gradient
    /// ([`crate::diff::Gradients::surface`]).
    pub surface: Vec<Vector3<f64>>,
}

impl Link {
    /// Number of joint coordinates.
    pub fn ndof(&self) -> usize {
        self.joint.ndof()
    }

    /// Second moment `M = ∫ρ x̃ x̃ᵀ` (4×4) and first moment `c = ∫ρ x̃` (its
    /// last column) under the link's [`MassModel`].
    pub fn moments(&self) -> (Matrix4<f64>, Vector4<f64>) {
        let m2 = match &self.mass_model {
            MassModel::Vertices => {
                // Summed per hull, as before the mass models existed.
                return self.hulls.iter().fold(
                    (Matrix4::zeros(), Vector4::zeros()),
                    |(a, b), h| {
                        let (m2, m1) = h.moments();
                        (a + m2, b + m1)
                    },
                );
            }
            MassModel::Solid { density } => self
                .hulls
                .iter()
                .zip(&self.solid_triangles)
                .map(|(h, t)| mass::solid_second_moment(&h.x_local, t, *density))
                .sum(),
            MassModel::Given(g) => g.second_moment(),
        };
        (m2, m2.column(3).into_owned())
    }

    /// Recomputes [`Link::solid_triangles`] from the vertices (solid links
    /// only). A hull whose vertices no longer enclose volume keeps its
    /// previous triangles (the design box keeps vertices near valid ones).
    pub fn refresh_triangles(&mut self) {
        if !matches!(self.mass_model, MassModel::Solid { .. }) {
            self.solid_triangles.clear();
            return;
        }
        self.solid_triangles.resize(self.hulls.len(), Vec::new());
        for (h, t) in self.hulls.iter().zip(self.solid_triangles.iter_mut()) {
            if let Ok(tris) = mass::solid_triangles(&h.x_local) {
                *t = tris;
            }
        }
    }

    /// Adds the vertex derivatives of `⟨W₂, M⟩ + w₁·c` (`M`, `c` as in
    /// [`Link::moments`]) to `out[h][m]`. With `c = M e₄` this is
    /// `⟨W, M⟩`, `W = W₂ + w₁e₄ᵀ`; for vertex masses
    /// `∂/∂x_m = ρ_m[(W₂ + W₂ᵀ)x̃_m + w₁]_{xyz}`, for solids see
    /// [`mass::solid_second_moment_vjp`], for a given inertial zero.
    pub fn moments_vjp(&self, w2: &Matrix4<f64>, w1: &Vector4<f64>, out: &mut [Vec<Vector3<f64>>]) {
        match &self.mass_model {
            MassModel::Vertices => {
                let ws = w2 + w2.transpose();
                for (h, hull) in self.hulls.iter().enumerate() {
                    for (k, (x, rho)) in hull.x_local.iter().zip(&hull.vertex_mass).enumerate() {
                        let g = (ws * Vector4::new(x.x, x.y, x.z, 1.0) + w1) * *rho;
                        out[h][k] += g.fixed_rows::<3>(0);
                    }
                }
            }
            MassModel::Solid { density } => {
                let mut w = *w2;
                for e in 0..4 {
                    w[(e, 3)] += w1[e];
                }
                for (h, (hull, t)) in self.hulls.iter().zip(&self.solid_triangles).enumerate() {
                    mass::solid_second_moment_vjp(&hull.x_local, t, *density, &w, &mut out[h]);
                }
            }
            MassModel::Given(_) => {}
        }
    }

    /// Total mass (kg).
    pub fn mass(&self) -> f64 {
        match &self.mass_model {
            MassModel::Vertices => self.hulls.iter().map(Hull::mass).sum(),
            _ => self.moments().1[3],
        }
    }
}

/// A robot (or free object) as a contiguous range of links.
#[derive(Clone, Debug)]
pub struct RobotInfo {
    pub name: String,
    /// Links `first..end` of [`Model::links`].
    pub links: std::ops::Range<usize>,
}

/// What each generalized coordinate is.
#[derive(Clone, Debug)]
pub struct DofInfo {
    /// Link whose joint owns the coordinate.
    pub link: usize,
    /// Index within the joint's coordinates.
    pub local: usize,
    /// Column name used in trajectory files.
    pub name: String,
}

/// Flattened articulated model of a whole scene.
#[derive(Clone, Debug)]
pub struct Model {
    pub links: Vec<Link>,
    pub robots: Vec<RobotInfo>,
    pub dofs: Vec<DofInfo>,
    /// Coordinates that affect each link's pose (its ancestors' and its own
    /// joint's), ascending.
    pub ancestor_dofs: Vec<Vec<usize>>,
    /// Number of spherical/free joints (charts in the state).
    pub nchart: usize,
    /// Per link: `∫ρ x̃ x̃ᵀ` (kg m², 4×4) under its [`MassModel`], cached.
    pub second_moment: Vec<Matrix4<f64>>,
    /// Per link: `∫ρ x̃` (kg m, kg), cached.
    pub first_moment: Vec<Vector4<f64>>,
    /// Mimic ties between coordinates (set by the scene builder).
    pub mimics: Vec<MimicTie>,
}

impl Model {
    /// Builds the derived tables from links that are already in topological
    /// order with `robot` and `parent` set. Assigns `dof_offset` and `chart`.
    pub fn new(mut links: Vec<Link>, robots: Vec<RobotInfo>) -> Model {
        links.iter_mut().for_each(Link::refresh_triangles);
        let mut dofs = Vec::new();
        let mut nchart = 0;
        let multi_robot = robots.len() > 1;
        for (i, link) in links.iter_mut().enumerate() {
            link.dof_offset = dofs.len();
            link.chart = if link.joint.has_chart() {
                nchart += 1;
                Some(nchart - 1)
            } else {
                None
            };
            let prefix = if multi_robot {
                format!("{}/{}", robots[link.robot].name, link.joint_name)
            } else {
                link.joint_name.clone()
            };
            for (local, label) in link.joint.dof_labels().iter().enumerate() {
                let name = if label.is_empty() {
                    prefix.clone()
                } else {
                    format!("{prefix}:{label}")
                };
                dofs.push(DofInfo {
                    link: i,
                    local,
                    name,
                });
            }
        }
        let mut ancestor_dofs: Vec<Vec<usize>> = Vec::with_capacity(links.len());
        for (i, link) in links.iter().enumerate() {
            let mut a = match link.parent {
                Some(p) => {
                    assert!(p < i, "links must be in topological order");
                    ancestor_dofs[p].clone()
                }
                None => Vec::new(),
            };
            a.extend(link.dof_offset..link.dof_offset + link.ndof());
            ancestor_dofs.push(a);
        }
        let (second_moment, first_moment) = links.iter().map(Link::moments).unzip();
        Model {
            links,
            robots,
            dofs,
            ancestor_dofs,
            nchart,
            second_moment,
            first_moment,
            mimics: Vec::new(),
        }
    }

    /// Number of generalized coordinates `|θ|`.
    pub fn ndof(&self) -> usize {
        self.dofs.len()
    }

    /// Recomputes the cached mass moments after hull vertices changed.
    pub fn refresh_moments(&mut self) {
        for (i, l) in self.links.iter_mut().enumerate() {
            l.refresh_triangles();
            let (m2, m1) = l.moments();
            self.second_moment[i] = m2;
            self.first_moment[i] = m1;
        }
    }

    /// Whether link `a` is an ancestor of (or equal to) link `b`.
    pub fn is_ancestor_or_self(&self, a: usize, mut b: usize) -> bool {
        loop {
            if a == b {
                return true;
            }
            match self.links[b].parent {
                Some(p) if p >= a => b = p,
                _ => return false,
            }
        }
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(Link::mass).sum()
    }
}
