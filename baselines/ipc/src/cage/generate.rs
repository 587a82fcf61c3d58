//! Automatic cages: the axis-aligned bounding box of a point set inflated
//! by a margin, each face subdivided into `k × k` quads split into two
//! triangles (`6k² + 2` vertices, `12k²` triangles). A box is convex, so
//! mean value coordinates inside it are positive, and it encloses the mesh
//! by construction.

use super::Cage;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Cage resolution: `coarse` (k = 2: 26 vertices, the paper's biped-foot
/// coarse cage), `fine` (k = 4: 98 vertices) or `k` segments per box edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CageResolution {
    Coarse,
    Fine,
    Segments(u32),
}

impl CageResolution {
    /// Segments per box edge.
    pub fn segments(self) -> u32 {
        match self {
            CageResolution::Coarse => 2,
            CageResolution::Fine => 4,
            CageResolution::Segments(k) => k,
        }
    }

    /// Parses `coarse`, `fine` or a positive integer `k`.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "coarse" => Ok(CageResolution::Coarse),
            "fine" => Ok(CageResolution::Fine),
            n => match n.parse::<u32>() {
                Ok(k) if (1..=64).contains(&k) => Ok(CageResolution::Segments(k)),
                _ => Err(format!(
                    "--cage {n:?}: expected coarse, fine or segments per box edge (1 to 64)"
                )),
            },
        }
    }
}

/// The box cage of `points` with `k` segments per edge, inflated by
/// `margin` (m) on every side (plus `1e-3` of the diagonal, so a flat point
/// set still gets a solid cage).
pub fn box_cage(points: &[Vector3<f64>], k: u32, margin: f64) -> Cage {
    let k = k.max(1) as i64;
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let pad = margin + 1e-3 * (hi - lo).norm();
    lo -= Vector3::repeat(pad);
    hi += Vector3::repeat(pad);
    let mut index: BTreeMap<[i64; 3], u32> = BTreeMap::new();
    let mut vertices = Vec::new();
    let mut id = |g: [i64; 3], vertices: &mut Vec<Vector3<f64>>| -> u32 {
        *index.entry(g).or_insert_with(|| {
            vertices.push(Vector3::from_fn(|e, _| {
                lo[e] + (hi[e] - lo[e]) * (g[e] as f64) / (k as f64)
            }));
            (vertices.len() - 1) as u32
        })
    };
    let mut tris = Vec::new();
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for side in [0, k] {
            for u in 0..k {
                for v in 0..k {
                    let g = |du: i64, dv: i64| {
                        let mut p = [0; 3];
                        p[a] = side;
                        p[b] = u + du;
                        p[c] = v + dv;
                        p
                    };
                    let q = [g(0, 0), g(1, 0), g(1, 1), g(0, 1)].map(|p| id(p, &mut vertices));
                    // e_b × e_c = e_a: counter-clockwise from +a.
                    if side == k {
                        tris.push([q[0], q[1], q[2]]);
                        tris.push([q[0], q[2], q[3]]);
                    } else {
                        tris.push([q[0], q[2], q[1]]);
                        tris.push([q[0], q[3], q[2]]);
                    }
                }
            }
        }
    }
    Cage { vertices, tris }
}
