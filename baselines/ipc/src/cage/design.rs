//! Cage vertices as design variables: for each caged link, the mean value
//! coordinates `φ_ij` of its hull vertices `x_i` w.r.t. the rest cage are
//! computed once; a design `c` (every cage vertex, 3 entries each, links in
//! order) is applied as `x_i = Σ_j φ_ij c_j` and a hull-vertex gradient is
//! pulled back as `∂L/∂c_j = Σ_i φ_ij ∂L/∂x_i`. Bounds: each coordinate
//! within `± bound` (m) of its rest value.

use super::mvc::mean_value_coordinates;
use super::validate::{CageError, validate_cage};
use super::{Cage, box_cage};
use nalgebra::{DVector, Vector3};
use sdrs::diff::Gradients;
use sdrs::model::Model;
use sdrs::optimize::design::{DesignSpace, DesignVar, Target};

/// One link's cage and its fixed coordinates.
#[derive(Clone, Debug)]
pub struct LinkCage {
    pub link: usize,
    pub cage: Cage,
    /// `(hull, vertex, φ)`: the coordinates of each hull vertex (length =
    /// cage vertices).
    pub weights: Vec<(usize, usize, Vec<f64>)>,
    /// `ψ_k`: the coordinates of each vertex `k` of the link's source-mesh
    /// contact surface (`Link::surface`), when the IPC surface is the
    /// source mesh ([`LinkCage::with_surface`]); empty otherwise.
    pub surface_weights: Vec<Vec<f64>>,
}

/// The cage design space over several links.
#[derive(Clone, Debug, Default)]
pub struct CageDesign {
    pub cages: Vec<LinkCage>,
    /// Allowed move of every cage coordinate from its rest value (m).
    pub bound: f64,
}

fn link_name(model: &Model, link: usize) -> String {
    let l = &model.links[link];
    format!("{}/{}", model.robots[l.robot].name, l.name)
}

fn hull_points(model: &Model, link: usize) -> Vec<(usize, usize, Vector3<f64>)> {
    model.links[link]
        .hulls
        .iter()
        .enumerate()
        .flat_map(|(h, hull)| {
            hull.x_local
                .iter()
                .enumerate()
                .map(move |(v, x)| (h, v, *x))
        })
        .collect()
}

impl LinkCage {
    /// Coordinates of link `link`'s hull vertices in `cage` (validated:
    /// closed, non-degenerate, enclosing every vertex).
    pub fn new(model: &Model, link: usize, cage: Cage) -> Result<LinkCage, CageError> {
        let pts = hull_points(model, link);
        validate_cage(&cage, &link_name(model, link), &pts)?;
        let mut weights = Vec::with_capacity(pts.len());
        for (h, v, x) in pts {
            let mut w = vec![0.0; cage.vertices.len()];
            if !mean_value_coordinates(&x, &cage.vertices, &cage.tris, &mut w) {
                return Err(CageError::NotEnclosing {
                    link: link_name(model, link),
                    hull: h,
                    vertex: v,
                    point: [x.x, x.y, x.z],
                    winding: super::validate::winding_number(&cage, &x),
                });
            }
            weights.push((h, v, w));
        }
        Ok(LinkCage {
            link,
            cage,
            weights,
            surface_weights: Vec::new(),
        })
    }

    /// Adds the coordinates `ψ_k` of the source-surface vertices `surface`
    /// (link frame), which the cage must enclose too: the design then
    /// moves `s_k = Σ_j ψ_kj c_j` with the hull vertices.
    pub fn with_surface(
        mut self,
        model: &Model,
        surface: &[Vector3<f64>],
    ) -> Result<LinkCage, CageError> {
        let name = link_name(model, self.link);
        self.surface_weights = Vec::with_capacity(surface.len());
        for (k, x) in surface.iter().enumerate() {
            let wn = super::validate::winding_number(&self.cage, x);
            let mut w = vec![0.0; self.cage.vertices.len()];
            if (wn - 1.0).abs() > 1e-6
                || !mean_value_coordinates(x, &self.cage.vertices, &self.cage.tris, &mut w)
            {
                return Err(CageError::NotEnclosingSurface {
                    link: name,
                    vertex: k,
                    point: [x.x, x.y, x.z],
                    winding: wn,
                });
            }
            self.surface_weights.push(w);
        }
        Ok(self)
    }

    /// The automatic box cage with `k` segments per edge around link
    /// `link`'s hulls, inflated by 5 % of their extent.
    pub fn automatic(model: &Model, link: usize, k: u32) -> Result<LinkCage, CageError> {
        Self::automatic_around(model, link, k, &[])
    }

    /// [`LinkCage::automatic`] around the hulls and the points `extra`
    /// (a source-mesh surface, link frame).
    pub fn automatic_around(
        model: &Model,
        link: usize,
        k: u32,
        extra: &[Vector3<f64>],
    ) -> Result<LinkCage, CageError> {
        let mut pts: Vec<Vector3<f64>> =
            hull_points(model, link).into_iter().map(|p| p.2).collect();
        pts.extend_from_slice(extra);
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for p in &pts {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let margin = 0.05 * (hi - lo).norm();
        LinkCage::new(model, link, box_cage(&pts, k, margin))
    }
}

impl CageDesign {
    /// Number of design variables (3 per cage vertex).
    pub fn len(&self) -> usize {
        self.cages.iter().map(|c| 3 * c.cage.vertices.len()).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rest design (the cages' vertices).
    pub fn initial(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.cages
                .iter()
                .flat_map(|c| c.cage.vertices.iter().flat_map(|v| [v.x, v.y, v.z])),
        )
    }

    /// Lower and upper bounds (rest ± `bound`).
    pub fn bounds(&self) -> (DVector<f64>, DVector<f64>) {
        let x = self.initial();
        (x.add_scalar(-self.bound), x.add_scalar(self.bound))
    }

    /// Writes `x_i = Σ_j φ_ij c_j` into the model's hull vertices (and
    /// refreshes the mass moments, which depend on vertex positions).
    pub fn apply(&self, model: &mut Model, c: &DVector<f64>) {
        let mut off = 0;
        for lc in &self.cages {
            let n = lc.cage.vertices.len();
            let cv =
                |j: usize| Vector3::new(c[off + 3 * j], c[off + 3 * j + 1], c[off + 3 * j + 2]);
            for (h, v, w) in &lc.weights {
                let x: Vector3<f64> = w.iter().enumerate().map(|(j, &wj)| cv(j) * wj).sum();
                model.links[lc.link].hulls[*h].x_local[*v] = x;
            }
            let surface: Vec<Vector3<f64>> = lc
                .surface_weights
                .iter()
                .map(|w| w.iter().enumerate().map(|(j, &wj)| cv(j) * wj).sum())
                .collect();
            if !surface.is_empty() {
                model.links[lc.link].surface = surface;
            }
            off += 3 * n;
        }
        model.refresh_moments();
    }

    /// `∂L/∂c = Φᵀ ∂L/∂x` from the backward pass's hull-vertex gradients.
    pub fn gradient(&self, g: &Gradients) -> DVector<f64> {
        let mut out = DVector::zeros(self.len());
        let mut off = 0;
        for lc in &self.cages {
            for (h, v, w) in &lc.weights {
                let gx = g.vertices[lc.link][*h][*v];
                for (j, &wj) in w.iter().enumerate() {
                    for e in 0..3 {
                        out[off + 3 * j + e] += wj * gx[e];
                    }
                }
            }
            for (k, w) in lc.surface_weights.iter().enumerate() {
                let Some(gs) = g.surface.get(lc.link).and_then(|s| s.get(k)) else {
                    continue;
                };
                for (j, &wj) in w.iter().enumerate() {
                    for e in 0..3 {
                        out[off + 3 * j + e] += wj * gs[e];
                    }
                }
            }
            off += 3 * lc.cage.vertices.len();
        }
        out
    }
}

impl CageDesign {
    /// The cage vertices as the core's design space (so `sdrs optimize`
    /// runs them like any other design): one variable per cage-vertex
    /// coordinate, named `robot/link.cage[j].x`, bounded by rest ± `bound`,
    /// with a [`Target::Blend`] of weight `φ_ij` on coordinate `axis` of
    /// every hull vertex `i` and a [`Target::SurfaceBlend`] of weight `ψ_kj`
    /// on every source-surface vertex `k` (weights below 1e-15 are dropped;
    /// MVC weights in a box cage are all positive). Size: cage vertices ×
    /// (hull + surface vertices) × 3 targets.
    pub fn design_space(&self, model: &Model) -> DesignSpace {
        let mut vars = Vec::with_capacity(self.len());
        for lc in &self.cages {
            let name = link_name(model, lc.link);
            for (j, c) in lc.cage.vertices.iter().enumerate() {
                for axis in 0..3 {
                    let targets = lc
                        .weights
                        .iter()
                        .filter(|(_, _, w)| w[j].abs() > 1e-15)
                        .map(|(h, v, w)| Target::Blend {
                            link: lc.link,
                            hull: *h,
                            vertex: *v,
                            axis,
                            weight: w[j],
                            rest: c[axis],
                        })
                        .collect::<Vec<_>>();
                    let mut targets = targets;
                    targets.extend(
                        lc.surface_weights
                            .iter()
                            .enumerate()
                            .filter(|(_, w)| w[j].abs() > 1e-15)
                            .map(|(k, w)| Target::SurfaceBlend {
                                link: lc.link,
                                vertex: k,
                                axis,
                                weight: w[j],
                                rest: c[axis],
                            }),
                    );
                    let targets = if targets.is_empty() {
                        // Keep the variable readable (`values`): a zero-weight
                        // blend on the first vertex.
                        let (h, v, _) = &lc.weights[0];
                        vec![Target::Blend {
                            link: lc.link,
                            hull: *h,
                            vertex: *v,
                            axis,
                            weight: 0.0,
                            rest: c[axis],
                        }]
                    } else {
                        targets
                    };
                    vars.push(DesignVar {
                        targets,
                        lower: c[axis] - self.bound,
                        upper: c[axis] + self.bound,
                        name: format!("{name}.cage[{j}].{}", ["x", "y", "z"][axis]),
                    });
                }
            }
        }
        DesignSpace { vars }
    }
}
