//! Topology of a link's shape: connected components, through-holes and
//! cavities of the union of its convex hulls, measured on a voxelization.
//!
//! The union `U = ∪_h conv(h)` is sampled on a grid of cubic voxels of edge
//! `e = ext_max / resolution` (`ext_max` the longest side of the hulls'
//! bounding box), padded by one empty layer; a voxel is occupied when its
//! centre lies in some hull (`n·x ≤ b` for every face plane). The occupied
//! voxels as closed unit cubes form a cubical complex `K` with
//! - `b₀` = connected components (cubes sharing a face, edge or corner),
//! - `b₂` = cavities = components of the complement (face-adjacent empty
//!   voxels) − 1 (the outside),
//! - `χ = V − E + F − C` (vertices, edges, faces and cubes of `K`),
//! - `b₁ = b₀ + b₂ − χ` = through-holes (tunnels; the genus of a single
//!   closed component without cavities), by Euler–Poincaré.
//!
//! Features thinner than a voxel may be missed; holes narrower than a voxel
//! may close. A topology change is a change of `(b₀, b₁, b₂)`.

use crate::math::polytope::convex_hull;
use nalgebra::Vector3;
use serde::Serialize;

/// Betti numbers of a shape (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Topology {
    pub components: usize,
    pub holes: usize,
    pub cavities: usize,
    pub euler: i64,
    /// Occupied voxels.
    pub voxels: usize,
}

/// Errors of the topology measure.
#[derive(Debug, thiserror::Error)]
pub enum TopologyError {
    #[error("hull {hull}: {msg}")]
    Hull { hull: usize, msg: String },
    #[error("no hulls")]
    Empty,
}

/// Measures the union of `hulls` (vertex lists, one frame) at `resolution`
/// voxels along the longest side (≥ 4).
pub fn measure(hulls: &[Vec<Vector3<f64>>], resolution: usize) -> Result<Topology, TopologyError> {
    let all: Vec<&Vector3<f64>> = hulls.iter().flatten().collect();
    if all.is_empty() {
        return Err(TopologyError::Empty);
    }
    let planes: Vec<Vec<(Vector3<f64>, f64)>> = hulls
        .iter()
        .enumerate()
        .map(|(i, h)| {
            convex_hull(h)
                .map(|p| p.planes)
                .map_err(|msg| TopologyError::Hull { hull: i, msg })
        })
        .collect::<Result<_, _>>()?;
    let (mut lo, mut hi) = (*all[0], *all[0]);
    for v in &all {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let res = resolution.max(4);
    let e = (hi - lo).max() / res as f64;
    let n = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / e).ceil().max(1.0) as usize + 2);
    let origin = lo - Vector3::repeat(e);
    let idx = |i: usize, j: usize, k: usize| (i * n[1] + j) * n[2] + k;
    let mut occ = vec![false; n[0] * n[1] * n[2]];
    let tol = 1e-12 * e;
    for i in 1..n[0] - 1 {
        for j in 1..n[1] - 1 {
            for k in 1..n[2] - 1 {
                let c = origin + e * Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                occ[idx(i, j, k)] = planes
                    .iter()
                    .any(|p| p.iter().all(|(nn, b)| nn.dot(&c) <= b + tol));
            }
        }
    }
    let voxels = occ.iter().filter(|&&o| o).count();
    let components = count_components(&occ, n, true, true);
    let outside_and_cavities = count_components(&occ, n, false, false);
    let cavities = outside_and_cavities.saturating_sub(1);
    // χ of the cubical complex: mark cells on the doubled grid (a cell of
    // dimension d has d odd coordinates).
    let m = [2 * n[0] + 1, 2 * n[1] + 1, 2 * n[2] + 1];
    let mut cell = vec![false; m[0] * m[1] * m[2]];
    let cidx = |a: usize, b: usize, c: usize| (a * m[1] + b) * m[2] + c;
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                if !occ[idx(i, j, k)] {
                    continue;
                }
                for a in 2 * i..=2 * i + 2 {
                    for b in 2 * j..=2 * j + 2 {
                        for c in 2 * k..=2 * k + 2 {
                            cell[cidx(a, b, c)] = true;
                        }
                    }
                }
            }
        }
    }
    let mut euler = 0i64;
    for a in 0..m[0] {
        for b in 0..m[1] {
            for c in 0..m[2] {
                if cell[cidx(a, b, c)] {
                    let dim = (a % 2) + (b % 2) + (c % 2);
                    euler += if dim % 2 == 0 { 1 } else { -1 };
                }
            }
        }
    }
    let holes = (components as i64 + cavities as i64 - euler).max(0) as usize;
    Ok(Topology {
        components,
        holes,
        cavities,
        euler,
        voxels,
    })
}

/// Components of voxels whose occupancy equals `value`: 26-adjacency when
/// `full`, else 6-adjacency (flood fill with an explicit stack).
fn count_components(occ: &[bool], n: [usize; 3], value: bool, full: bool) -> usize {
    let idx = |i: usize, j: usize, k: usize| (i * n[1] + j) * n[2] + k;
    let mut seen = vec![false; occ.len()];
    let mut count = 0;
    let mut stack = Vec::new();
    let offsets: Vec<[i64; 3]> = (-1..=1)
        .flat_map(|a| (-1..=1).flat_map(move |b| (-1..=1).map(move |c| [a, b, c])))
        .filter(|o: &[i64; 3]| {
            let s = o.iter().map(|x| x.abs()).sum::<i64>();
            s > 0 && (full || s == 1)
        })
        .collect();
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                if occ[idx(i, j, k)] != value || seen[idx(i, j, k)] {
                    continue;
                }
                count += 1;
                seen[idx(i, j, k)] = true;
                stack.push([i, j, k]);
                while let Some([a, b, c]) = stack.pop() {
                    for o in &offsets {
                        let (x, y, z) = (a as i64 + o[0], b as i64 + o[1], c as i64 + o[2]);
                        if x < 0
                            || y < 0
                            || z < 0
                            || x >= n[0] as i64
                            || y >= n[1] as i64
                            || z >= n[2] as i64
                        {
                            continue;
                        }
                        let q = idx(x as usize, y as usize, z as usize);
                        if occ[q] == value && !seen[q] {
                            seen[q] = true;
                            stack.push([x as usize, y as usize, z as usize]);
                        }
                    }
                }
            }
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(lo: [f64; 3], hi: [f64; 3]) -> Vec<Vector3<f64>> {
        (0..8)
            .map(|c| {
                Vector3::new(
                    if c & 1 == 0 { lo[0] } else { hi[0] },
                    if c & 2 == 0 { lo[1] } else { hi[1] },
                    if c & 4 == 0 { lo[2] } else { hi[2] },
                )
            })
            .collect()
    }

    #[test]
    fn a_box_is_one_solid_without_holes() {
        let t = measure(&[block([0.0; 3], [1.0, 0.5, 0.3])], 32).unwrap();
        assert_eq!((t.components, t.holes, t.cavities, t.euler), (1, 0, 0, 1));
    }

    #[test]
    fn a_ring_of_blocks_has_one_hole() {
        // Four bars around a square opening (a picture frame), blocks touching.
        let ring = vec![
            block([0.0, 0.0, 0.0], [3.0, 1.0, 1.0]),
            block([0.0, 2.0, 0.0], [3.0, 3.0, 1.0]),
            block([0.0, 1.0, 0.0], [1.0, 2.0, 1.0]),
            block([2.0, 1.0, 0.0], [3.0, 2.0, 1.0]),
        ];
        let t = measure(&ring, 30).unwrap();
        assert_eq!((t.components, t.holes, t.cavities, t.euler), (1, 1, 0, 0));
        // Filling the opening removes the hole: a topology change.
        let mut filled = ring.clone();
        filled.push(block([1.0, 1.0, 0.0], [2.0, 2.0, 1.0]));
        let f = measure(&filled, 30).unwrap();
        assert_eq!((f.components, f.holes), (1, 0));
    }

    #[test]
    fn two_separate_blocks_are_two_components() {
        let t = measure(
            &[
                block([0.0; 3], [1.0; 3]),
                block([2.0, 0.0, 0.0], [3.0, 1.0, 1.0]),
            ],
            30,
        )
        .unwrap();
        assert_eq!((t.components, t.holes, t.cavities), (2, 0, 0));
    }

    #[test]
    fn a_hollow_box_has_a_cavity() {
        let mut walls = Vec::new();
        for axis in 0..3 {
            for side in [0.0, 2.0] {
                let (mut lo, mut hi) = ([0.0; 3], [3.0; 3]);
                lo[axis] = side;
                hi[axis] = side + 1.0;
                walls.push(block(lo, hi));
            }
        }
        let t = measure(&walls, 30).unwrap();
        assert_eq!((t.components, t.holes, t.cavities, t.euler), (1, 0, 1, 2));
    }
}
