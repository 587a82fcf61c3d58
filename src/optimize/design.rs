//! The design space `D` (paper, `shape.tex`): a vector `d` of scalar design
//! variables, each written to one or more *targets* (attachment-point
//! components and hull-vertex components) so that tied quantities are one
//! variable and stay identical by construction; box bounds make `D` convex
//! and the projection a clamp.
//!
//! Attachment points: the attachment `t_c` of link `c` (in its parent's
//! frame) is tied to a vertex of a parent hull at the same point — an
//! existing vertex if one is there, else a massless vertex added to the
//! parent hull nearest to the point — and a massless vertex at the child's
//! origin is added to the child's first hull, so both links' hulls always
//! contain the joint. Massless vertices leave masses unchanged; a vertex on
//! or inside a hull leaves its shape unchanged.

use super::names::{self, NameError};
use crate::diff::Gradients;
use crate::model::Model;
use nalgebra::{DVector, Vector3};

/// Vertices `(link, hull, vertex)` that are one point.
pub type TieGroup = Vec<(usize, usize, usize)>;

/// Where a design variable is written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    Attachment {
        link: usize,
        axis: usize,
    },
    Vertex {
        link: usize,
        hull: usize,
        vertex: usize,
        axis: usize,
    },
    /// A linear blend (cage-based deformation, built outside the core):
    /// the coordinate is `Σ weight · d` over every variable with a `Blend`
    /// target on it (so [`DesignSpace::apply`] first zeroes blended
    /// coordinates), and its gradient is `weight · ∂L/∂x`. `rest` is the
    /// variable's value in the undeformed model (what
    /// [`DesignSpace::values`] returns for it).
    Blend {
        link: usize,
        hull: usize,
        vertex: usize,
        axis: usize,
        weight: f64,
        rest: f64,
    },
    /// A [`Target::Blend`] on vertex `vertex` of the link's contact
    /// surface ([`crate::model::Link::surface`]) instead of a hull vertex:
    /// the IPC baseline's source mesh moved by a cage. Gradient
    /// `weight · ∂L/∂s` from [`Gradients::surface`].
    SurfaceBlend {
        link: usize,
        vertex: usize,
        axis: usize,
        weight: f64,
        rest: f64,
    },
}

/// One scalar design variable.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignVar {
    pub targets: Vec<Target>,
    pub lower: f64,
    pub upper: f64,
    /// Human-readable name (`left/link3.attach.z`).
    pub name: String,
}

/// The design space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DesignSpace {
    pub vars: Vec<DesignVar>,
}

fn read(model: &Model, t: Target) -> f64 {
    match t {
        Target::Attachment { link, axis } => model.links[link].attach[(axis, 3)],
        Target::Vertex {
            link,
            hull,
            vertex,
            axis,
        } => model.links[link].hulls[hull].x_local[vertex][axis],
        Target::Blend { rest, .. } | Target::SurfaceBlend { rest, .. } => rest,
    }
}

fn find_vertex(model: &Model, link: usize, p: &Vector3<f64>) -> Option<(usize, usize)> {
    for (h, hull) in model.links[link].hulls.iter().enumerate() {
        if let Some(m) = hull.x_local.iter().position(|x| (x - p).norm() <= 1e-9) {
            return Some((h, m));
        }
    }
    None
}

/// Adds a massless vertex at `p` to the hull of `link` whose bounding box is
/// nearest to `p`; returns `(hull, vertex)`.
fn add_vertex(model: &mut Model, link: usize, p: Vector3<f64>) -> (usize, usize) {
    let dist = |h: &crate::model::Hull| {
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for x in &h.x_local {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        (lo - p).sup(&(p - hi)).sup(&Vector3::zeros()).norm()
    };
    let hulls = &mut model.links[link].hulls;
    let h = (0..hulls.len())
        .min_by(|&a, &b| dist(&hulls[a]).total_cmp(&dist(&hulls[b])))
        .unwrap_or(0);
    hulls[h].x_local.push(p);
    hulls[h].vertex_mass.push(0.0);
    (h, hulls[h].x_local.len() - 1)
}

impl DesignSpace {
    /// Builds the space for attachment points of `attachments` and all hull
    /// vertices of `vertex_links` (names `robot/link`), with box half-width
    /// `bound`. Adds the connectivity vertices to `model` (see the module
    /// docs).
    ///
    /// `ties` are groups of `(link index, hull, vertex)` that must stay one
    /// point (shared vertices of overlapping hulls, from the robots'
    /// `design.ties`): a designable vertex in a group becomes one variable
    /// written to every member.
    pub fn build(
        model: &mut Model,
        attachments: &[String],
        vertex_links: &[String],
        bound: f64,
        ties: &[TieGroup],
    ) -> Result<Self, NameError> {
        let mut vars: Vec<DesignVar> = Vec::new();
        let label = |m: &Model, l: usize| {
            format!("{}/{}", m.robots[m.links[l].robot].name, m.links[l].name)
        };
        let mut claimed: Vec<(usize, usize, usize)> = Vec::new();
        for name in attachments {
            let c = names::link(model, name)?;
            let t = model.links[c].attach.column(3).into_owned();
            let parent_vertex = model.links[c].parent.map(|p| {
                let (h, m) = find_vertex(model, p, &t).unwrap_or_else(|| add_vertex(model, p, t));
                (p, h, m)
            });
            if model.links[c].parent.is_some() && find_vertex(model, c, &Vector3::zeros()).is_none()
            {
                let hulls = &mut model.links[c].hulls;
                hulls[0].x_local.push(Vector3::zeros());
                hulls[0].vertex_mass.push(0.0);
            }
            if let Some(pv) = parent_vertex {
                claimed.push(pv);
            }
            if let Some((h, m)) =
                find_vertex(model, c, &Vector3::zeros()).filter(|_| model.links[c].parent.is_some())
            {
                claimed.push((c, h, m)); // the child-side joint vertex stays at the origin
            }
            for axis in 0..3 {
                let mut targets = vec![Target::Attachment { link: c, axis }];
                if let Some((p, h, m)) = parent_vertex {
                    targets.push(Target::Vertex {
                        link: p,
                        hull: h,
                        vertex: m,
                        axis,
                    });
                }
                vars.push(DesignVar {
                    targets,
                    lower: 0.0,
                    upper: 0.0,
                    name: format!(
                        "{}.attach.{}",
                        label(model, c),
                        "xyz".as_bytes()[axis] as char
                    ),
                });
            }
        }
        let group_of = |key: (usize, usize, usize)| ties.iter().position(|g| g.contains(&key));
        let mut done_groups: Vec<usize> = Vec::new();
        for name in vertex_links {
            let l = names::link(model, name)?;
            for (h, hull) in model.links[l].hulls.iter().enumerate() {
                for m in 0..hull.x_local.len() {
                    if claimed.contains(&(l, h, m)) {
                        continue;
                    }
                    let members = match group_of((l, h, m)) {
                        Some(g) if done_groups.contains(&g) => continue,
                        Some(g) => {
                            done_groups.push(g);
                            let x = hull.x_local[m];
                            for &(l2, h2, m2) in &ties[g] {
                                let y = model.links[l2].hulls[h2].x_local[m2];
                                if (x - y).norm() > 1e-9 {
                                    return Err(NameError {
                                        what: "tie",
                                        name: format!("{} hull {h} vertex {m}", label(model, l)),
                                        msg: format!("tied vertices differ: {x:?} vs {y:?}"),
                                    });
                                }
                            }
                            ties[g].clone()
                        }
                        None => vec![(l, h, m)],
                    };
                    for axis in 0..3 {
                        vars.push(DesignVar {
                            targets: members
                                .iter()
                                .map(|&(link, hull, vertex)| Target::Vertex {
                                    link,
                                    hull,
                                    vertex,
                                    axis,
                                })
                                .collect(),
                            lower: 0.0,
                            upper: 0.0,
                            name: format!(
                                "{}.hull{h}.v{m}.{}",
                                label(model, l),
                                "xyz".as_bytes()[axis] as char
                            ),
                        });
                    }
                }
            }
        }
        model.refresh_moments();
        for v in &mut vars {
            let x = read(model, v.targets[0]);
            v.lower = x - bound;
            v.upper = x + bound;
        }
        Ok(DesignSpace { vars })
    }

    pub fn len(&self) -> usize {
        self.vars.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vars.is_empty()
    }

    /// Current values (from each variable's first target).
    pub fn values(&self, model: &Model) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.vars.iter().map(|v| read(model, v.targets[0])),
        )
    }

    /// Writes `d` into every target (ties stay identical) and refreshes the
    /// mass moments.
    pub fn apply(&self, model: &mut Model, d: &DVector<f64>) {
        for t in self.vars.iter().flat_map(|v| &v.targets) {
            if let Target::Blend {
                link,
                hull,
                vertex,
                axis,
                ..
            } = *t
            {
                model.links[link].hulls[hull].x_local[vertex][axis] = 0.0;
            }
            if let Target::SurfaceBlend {
                link, vertex, axis, ..
            } = *t
            {
                model.links[link].surface[vertex][axis] = 0.0;
            }
        }
        for (v, &x) in self.vars.iter().zip(d.iter()) {
            for t in &v.targets {
                match *t {
                    Target::Attachment { link, axis } => model.links[link].attach[(axis, 3)] = x,
                    Target::Vertex {
                        link,
                        hull,
                        vertex,
                        axis,
                    } => model.links[link].hulls[hull].x_local[vertex][axis] = x,
                    Target::Blend {
                        link,
                        hull,
                        vertex,
                        axis,
                        weight,
                        ..
                    } => model.links[link].hulls[hull].x_local[vertex][axis] += weight * x,
                    Target::SurfaceBlend {
                        link,
                        vertex,
                        axis,
                        weight,
                        ..
                    } => model.links[link].surface[vertex][axis] += weight * x,
                }
            }
        }
        model.refresh_moments();
    }

    /// `dL/dd`: the sum over each variable's targets.
    pub fn gradient(&self, g: &Gradients) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.vars.iter().map(|v| {
                v.targets
                    .iter()
                    .map(|t| match *t {
                        Target::Attachment { link, axis } => g.attachments[link][axis],
                        Target::Vertex {
                            link,
                            hull,
                            vertex,
                            axis,
                        } => g.vertices[link][hull][vertex][axis],
                        Target::Blend {
                            link,
                            hull,
                            vertex,
                            axis,
                            weight,
                            ..
                        } => weight * g.vertices[link][hull][vertex][axis],
                        Target::SurfaceBlend {
                            link,
                            vertex,
                            axis,
                            weight,
                            ..
                        } => g
                            .surface
                            .get(link)
                            .and_then(|s| s.get(vertex))
                            .map_or(0.0, |gs| weight * gs[axis]),
                    })
                    .sum::<f64>()
            }),
        )
    }

    /// Projection onto `D` (a clamp to the box).
    pub fn project(&self, d: &mut DVector<f64>) {
        for (x, v) in d.iter_mut().zip(&self.vars) {
            *x = x.clamp(v.lower, v.upper);
        }
    }

    pub fn lower(&self) -> DVector<f64> {
        DVector::from_iterator(self.len(), self.vars.iter().map(|v| v.lower))
    }

    pub fn upper(&self) -> DVector<f64> {
        DVector::from_iterator(self.len(), self.vars.iter().map(|v| v.upper))
    }

    /// Links whose hull vertices are design variables (attachments alone
    /// do not count), sorted, each once.
    pub fn designed_links(&self) -> Vec<usize> {
        let mut links: Vec<usize> = self
            .vars
            .iter()
            .flat_map(|v| v.targets.iter())
            .filter_map(|t| match t {
                Target::Vertex { link, .. }
                | Target::Blend { link, .. }
                | Target::SurfaceBlend { link, .. } => Some(*link),
                Target::Attachment { .. } => None,
            })
            .collect();
        links.sort_unstable();
        links.dedup();
        links
    }

    /// Whether every tie holds exactly in `model` and every variable is
    /// within its bounds.
    pub fn check(&self, model: &Model) -> Result<(), String> {
        for v in &self.vars {
            if matches!(
                v.targets.first(),
                Some(Target::Blend { .. } | Target::SurfaceBlend { .. })
            ) {
                // Blended coordinates are sums over variables: no tie to check.
                continue;
            }
            let x = read(model, v.targets[0]);
            if !(v.lower..=v.upper).contains(&x) {
                return Err(format!(
                    "{} = {x} outside [{}, {}]",
                    v.name, v.lower, v.upper
                ));
            }
            for t in &v.targets[1..] {
                if read(model, *t) != x {
                    return Err(format!(
                        "{}: tied targets differ ({} vs {x})",
                        v.name,
                        read(model, *t)
                    ));
                }
            }
        }
        Ok(())
    }
}
