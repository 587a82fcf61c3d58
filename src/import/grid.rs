//! The block design space (paper, `evaluation.tex`: "we evenly divide the
//! gripper into 156 convex blocks"): `--decomposer grid` divides a link's
//! mesh into equal axis-aligned boxes.
//!
//! The mesh's bounding box `[lo, hi]` is cut into `n_x × n_y × n_z` cells of
//! edge `h_k = (hi_k − lo_k)/n_k`; a cell is kept when its centre is inside
//! the mesh (ray parity). `n_k = max(1, round((hi_k − lo_k)/h))` for a
//! common target edge `h`, which is searched so that the number of kept
//! cells is as close as possible to the requested count (`--max-hulls`).
//!
//! Neighbouring blocks share corners exactly. Two connectivities:
//! - [`face_ties`] (default, the paper's): each pair of **face neighbours**
//!   (blocks whose boxes touch along a face of positive area; blocks that
//!   meet only along an edge or at a corner are not a pair) shares one
//!   auxiliary vertex at the centre of their common face, appended to both
//!   blocks; the 8 corners of every block are free. A block can then shrink
//!   away from any edge or corner of the lattice (down to the hull of its
//!   auxiliary vertices), so a hole can open where four blocks meet.
//! - [`corner_ties`] (`--ties corners`): every two blocks' coincident
//!   corners are one design variable; the blocks stay one hexahedral
//!   lattice whatever the design, and no hole can open.

use super::connectivity::{DesignHull, LinkConnectivity, SharedVertex, TieKind};
use super::mesh::TriMesh;
use super::polytope::{Polytope, bounds, convex_hull};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Whether `p` is inside the closed mesh: parity of crossings of a ray in a
/// fixed generic direction (Möller–Trumbore).
pub fn inside(mesh: &TriMesh, p: &Vector3<f64>) -> bool {
    let d = Vector3::new(0.5773, 0.5774, 0.5770).normalize();
    let mut n = 0usize;
    for t in &mesh.triangles {
        let (a, b, c) = (
            mesh.vertices[t[0]],
            mesh.vertices[t[1]],
            mesh.vertices[t[2]],
        );
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(&e2);
        let det = e1.dot(&pv);
        if det.abs() < 1e-15 {
            continue;
        }
        let s = p - a;
        let u = s.dot(&pv) / det;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let qv = s.cross(&e1);
        let v = d.dot(&qv) / det;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        if e2.dot(&qv) / det > 0.0 {
            n += 1;
        }
    }
    n % 2 == 1
}

/// Cells of `mesh` for target edge `h`: `(counts, kept cell indices)`.
fn cells(mesh: &TriMesh, h: f64) -> ([usize; 3], Vec<[usize; 3]>) {
    let (lo, hi) = bounds(&mesh.vertices);
    let ext = hi - lo;
    let n = [0, 1, 2].map(|k| ((ext[k] / h).round() as usize).max(1));
    let mut kept = Vec::new();
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let c = Vector3::new(
                    lo.x + ext.x * (i as f64 + 0.5) / n[0] as f64,
                    lo.y + ext.y * (j as f64 + 0.5) / n[1] as f64,
                    lo.z + ext.z * (k as f64 + 0.5) / n[2] as f64,
                );
                if inside(mesh, &c) {
                    kept.push([i, j, k]);
                }
            }
        }
    }
    (n, kept)
}

/// Divides `mesh` into about `count` equal boxes (see the module docs).
pub fn grid_blocks(mesh: &TriMesh, count: usize) -> Result<Vec<Polytope>, String> {
    if count == 0 {
        return Err("the grid needs at least one block".into());
    }
    let (lo, hi) = bounds(&mesh.vertices);
    let ext = hi - lo;
    let vol = mesh
        .volume()
        .filter(|v| *v > 0.0)
        .ok_or("the grid decomposer needs a closed mesh with volume")?;
    // Search h on a geometric ladder around (V/N)^(1/3); keep the closest count.
    let h0 = (vol / count as f64).cbrt();
    let mut best: Option<(usize, [usize; 3], Vec<[usize; 3]>)> = None;
    for s in 0..=80 {
        let h = h0 * 0.5 * 1.02f64.powi(s);
        let (n, kept) = cells(mesh, h);
        let err = kept.len().abs_diff(count);
        if !kept.is_empty() && best.as_ref().is_none_or(|b| err < b.0) {
            best = Some((err, n, kept));
        }
    }
    let (_, n, kept) = best.ok_or("no grid cell centre lies inside the mesh")?;
    let corner = |i: usize, j: usize, k: usize| {
        Vector3::new(
            lo.x + ext.x * i as f64 / n[0] as f64,
            lo.y + ext.y * j as f64 / n[1] as f64,
            lo.z + ext.z * k as f64 / n[2] as f64,
        )
    };
    kept.iter()
        .map(|&[i, j, k]| {
            let pts: Vec<Vector3<f64>> = (0..8)
                .map(|c| corner(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)))
                .collect();
            convex_hull(&pts)
        })
        .collect()
}

/// The paper's connectivity for grid blocks (see the module docs): one
/// auxiliary vertex per face-neighbour pair, at the centre of the common
/// face, appended to both blocks (a point of both boundaries, so no shape or
/// volume changes). Face neighbours are found from the blocks' bounding boxes:
/// `hi_a[k] = lo_b[k]` (to `1e-12·L`, `L` the link's extent) on one axis `k`
/// and overlaps longer than `1e-9·L` on the two others.
pub fn face_ties(hulls: &mut [DesignHull]) -> LinkConnectivity {
    let boxes: Vec<_> = hulls.iter().map(|h| bounds(&h.poly.vertices)).collect();
    let (mut lo, mut hi) = boxes.first().copied().unwrap_or_default();
    for (l, h) in &boxes {
        lo = lo.inf(l);
        hi = hi.sup(h);
    }
    let scale = (hi - lo).norm().max(1e-12);
    let mut parent: Vec<usize> = (0..hulls.len()).collect();
    let mut shared = Vec::new();
    for a in 0..hulls.len() {
        for b in a + 1..hulls.len() {
            let Some(p) = common_face_centre(&boxes[a], &boxes[b], scale) else {
                continue;
            };
            let va = hulls[a].add_point(p);
            let vb = hulls[b].add_point(p);
            shared.push(SharedVertex {
                hulls: [a, b],
                vertices: [va, vb],
                kind: TieKind::Touch,
                depth: 0.0,
            });
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra] = rb;
        }
    }
    let components = (0..hulls.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count();
    LinkConnectivity { shared, components }
}

type Aabb = (Vector3<f64>, Vector3<f64>);

/// Centre of the face shared by two touching boxes, if they are face
/// neighbours (see [`face_ties`]).
fn common_face_centre(a: &Aabb, b: &Aabb, scale: f64) -> Option<Vector3<f64>> {
    let (touch, overlap) = (1e-12 * scale, 1e-9 * scale);
    let mut p = Vector3::zeros();
    let mut touching_axis = None;
    for k in 0..3 {
        let (l, h) = (a.0[k].max(b.0[k]), a.1[k].min(b.1[k]));
        if h - l > overlap {
            p[k] = 0.5 * (l + h);
        } else if (h - l).abs() <= touch && touching_axis.is_none() {
            p[k] = 0.5 * (l + h);
            touching_axis = Some(k);
        } else {
            return None;
        }
    }
    touching_axis.map(|_| p)
}

fn find(p: &mut [usize], i: usize) -> usize {
    let mut r = i;
    while p[r] != r {
        r = p[r];
    }
    p[i] = r;
    r
}

/// Ties every pair of coincident vertices of different blocks (exactly
/// equal coordinates: neighbouring grid cells compute shared corners from
/// the same integer indices). Returns the link's connectivity.
pub fn corner_ties(hulls: &[DesignHull]) -> LinkConnectivity {
    let key = |v: &Vector3<f64>| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let mut at: BTreeMap<[u64; 3], Vec<(usize, usize)>> = BTreeMap::new();
    for (h, hull) in hulls.iter().enumerate() {
        for (m, v) in hull.vertices.iter().enumerate() {
            at.entry(key(v)).or_default().push((h, m));
        }
    }
    let mut shared = Vec::new();
    let mut parent: Vec<usize> = (0..hulls.len()).collect();
    for group in at.values() {
        for w in group.windows(2) {
            let ((ha, va), (hb, vb)) = (w[0], w[1]);
            if ha == hb {
                continue;
            }
            shared.push(SharedVertex {
                hulls: [ha, hb],
                vertices: [va, vb],
                kind: TieKind::Touch,
                depth: 0.0,
            });
            let (ra, rb) = (find(&mut parent, ha), find(&mut parent, hb));
            parent[ra] = rb;
        }
    }
    let components = (0..hulls.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count();
    LinkConnectivity { shared, components }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_shape() -> TriMesh {
        // An L: a 0.03 × 0.06 × 0.175 bar with a 0.045-long foot (the parallel jaw).
        let v = [
            [-0.015, -0.03, 0.015],
            [-0.015, -0.03, -0.16],
            [0.03, -0.03, -0.16],
            [0.03, -0.03, -0.13],
            [0.015, -0.03, -0.13],
            [0.015, -0.03, 0.015],
        ];
        let mut vertices: Vec<Vector3<f64>> = v.iter().map(|p| Vector3::from(*p)).collect();
        vertices.extend(v.iter().map(|p| Vector3::new(p[0], 0.03, p[2])));
        // Side polygons (fan from a reflex-free split) and the side walls.
        let mut triangles = vec![
            [0, 1, 4],
            [0, 4, 5],
            [1, 2, 3],
            [1, 3, 4],
            [6, 10, 7],
            [6, 11, 10],
            [7, 9, 8],
            [7, 10, 9],
        ];
        for i in 0..6 {
            let j = (i + 1) % 6;
            triangles.push([i, j + 6, j]);
            triangles.push([i, i + 6, j + 6]);
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    #[test]
    fn grid_of_an_l_shape_is_connected_and_fills_it() {
        let mesh = l_shape();
        let vol = mesh.volume().unwrap();
        assert!(vol > 0.0, "test mesh orientation");
        let blocks = grid_blocks(&mesh, 156).unwrap();
        assert!(
            blocks.len().abs_diff(156) <= 20,
            "{} blocks for 156 requested (grid counts are coarse: 140 is the closest here)",
            blocks.len()
        );
        let total: f64 = blocks.iter().map(|b| b.volume()).sum();
        // Cells are kept by their centres: the union is within one cell layer
        // of the L (here the cells tile it to within 10%).
        assert!((total - vol).abs() < 0.1 * vol, "{total} vs {vol}");
        let hulls: Vec<DesignHull> = blocks.into_iter().map(DesignHull::new).collect();
        let c = corner_ties(&hulls);
        assert_eq!(c.components, 1);
        // Face neighbours share 4 corners: far more pairs than blocks.
        assert!(c.shared.len() > 2 * hulls.len());
        for s in &c.shared {
            assert_eq!(
                hulls[s.hulls[0]].vertices[s.vertices[0]],
                hulls[s.hulls[1]].vertices[s.vertices[1]]
            );
        }
    }

    #[test]
    fn face_ties_share_one_point_per_face_neighbour_pair() {
        let mesh = l_shape();
        let blocks = grid_blocks(&mesh, 156).unwrap();
        let vols: Vec<f64> = blocks.iter().map(|b| b.volume()).collect();
        let mut hulls: Vec<DesignHull> = blocks.into_iter().map(DesignHull::new).collect();
        let corners = corner_ties(&hulls);
        let c = face_ties(&mut hulls);
        assert_eq!(c.components, 1);
        // Count face neighbours independently: two blocks whose 8 corners
        // have exactly 4 coincident positions share a face.
        let key = |v: &Vector3<f64>| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let mut faces = 0;
        for a in 0..hulls.len() {
            for b in a + 1..hulls.len() {
                let common = hulls[a].vertices[..8]
                    .iter()
                    .filter(|v| hulls[b].vertices[..8].iter().any(|w| key(w) == key(v)))
                    .count();
                faces += usize::from(common == 4);
            }
        }
        assert_eq!(c.shared.len(), faces);
        assert!(c.shared.len() < corners.shared.len() / 2);
        for s in &c.shared {
            let (ha, hb) = (&hulls[s.hulls[0]], &hulls[s.hulls[1]]);
            let p = ha.vertices[s.vertices[0]];
            assert_eq!(p, hb.vertices[s.vertices[1]]);
            // One new point per pair, on the boundary of both blocks.
            assert!(s.vertices[0] >= 8 && s.vertices[1] >= 8);
            assert!(ha.poly.violation(&p).abs() < 1e-15 && hb.poly.violation(&p).abs() < 1e-15);
        }
        for (h, v) in hulls.iter().zip(&vols) {
            assert!((super::super::connectivity::hull_volume(&h.vertices) - v).abs() < 1e-15);
            assert!(h.vertices.len() <= 8 + 6);
        }
    }

    #[test]
    fn edge_and_corner_neighbours_are_not_face_neighbours() {
        let cube = |o: [f64; 3]| {
            DesignHull::new(
                convex_hull(
                    &(0..8)
                        .map(|c| {
                            Vector3::new(
                                o[0] + (c & 1) as f64,
                                o[1] + ((c >> 1) & 1) as f64,
                                o[2] + (c >> 2) as f64,
                            )
                        })
                        .collect::<Vec<_>>(),
                )
                .unwrap(),
            )
        };
        // Face, edge and corner neighbours of the unit cube.
        let mut hs = vec![
            cube([0.0; 3]),
            cube([1.0, 0.0, 0.0]),
            cube([1.0, 1.0, 0.0]),
            cube([-1.0, -1.0, -1.0]),
        ];
        let c = face_ties(&mut hs);
        assert_eq!(
            c.shared.len(),
            2,
            "0–1 and 1–2 share faces; 0–2 an edge, 0–3 a corner"
        );
        assert_eq!(hs[0].vertices[8], Vector3::new(1.0, 0.5, 0.5));
        assert_eq!(hs[2].vertices[8], Vector3::new(1.5, 1.0, 0.5));
        assert_eq!(c.components, 2);
    }

    #[test]
    fn separate_boxes_stay_separate() {
        let a = DesignHull::new(
            convex_hull(
                &(0..8)
                    .map(|c| Vector3::new((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64))
                    .collect::<Vec<_>>(),
            )
            .unwrap(),
        );
        let mut b = a.clone();
        for v in &mut b.vertices {
            v.x += 3.0;
        }
        assert_eq!(corner_ties(&[a, b]).components, 2);
    }
}
