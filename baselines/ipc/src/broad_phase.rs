//! Primitive broad phase between the surfaces of two links: axis-aligned
//! boxes inflated by a margin (`d̂` for the potential; the swept extent plus
//! the CCD gap for continuous collision detection). First the two link
//! boxes are intersected into an overlap region; only vertices, edges and
//! triangles whose box meets that region are paired, then pairs are tested
//! box against box. Exact (no candidate with overlapping inflated boxes is
//! missed), deterministic (index order). [`build_for_pairs`] builds the
//! edge and triangle boxes only of links whose box meets a partner's, and
//! the box arithmetic is inlined here: on the hand's mesh-baseline row the
//! two took the forward pass from 2.30 to 0.86 s per iteration with the
//! same candidates (`notes/performance.md`, sixteenth session).

use nalgebra::Vector3;
/// The core's axis-aligned box (one box type for core and baseline).
pub use sdrs::geometry::Aabb;

/// Primitive candidates of one link pair.
#[derive(Clone, Debug, Default)]
pub struct Candidates {
    /// (vertex of a, triangle of b).
    pub vt_ab: Vec<(u32, u32)>,
    /// (vertex of b, triangle of a).
    pub vt_ba: Vec<(u32, u32)>,
    /// (edge of a, edge of b).
    pub ee: Vec<(u32, u32)>,
}

impl Candidates {
    pub fn clear(&mut self) {
        self.vt_ab.clear();
        self.vt_ba.clear();
        self.ee.clear();
    }
    pub fn len(&self) -> usize {
        self.vt_ab.len() + self.vt_ba.len() + self.ee.len()
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Per-primitive boxes of one link's surface (world frame), each the box of
/// the primitive's points at one or two configurations (swept for CCD).
#[derive(Clone, Debug, Default)]
pub struct PrimitiveBoxes {
    pub vert: Vec<Aabb>,
    pub edge: Vec<Aabb>,
    pub tri: Vec<Aabb>,
    pub all: Option<Aabb>,
}

impl PrimitiveBoxes {
    /// Boxes of the points `x0` (and `x1`, for swept boxes), inflated by `m`.
    pub fn build(
        &mut self,
        mesh: &crate::mesh::LinkMesh,
        x0: &[Vector3<f64>],
        x1: Option<&[Vector3<f64>]>,
        m: f64,
    ) {
        self.build_vertices(x0, x1, m);
        self.build_faces(mesh, x0, x1, m);
    }

    /// The vertex boxes and the link's box `all` only (the edge and
    /// triangle boxes are left as they were): what [`candidates`] reads of a
    /// link whose box meets no partner's.
    pub fn build_vertices(&mut self, x0: &[Vector3<f64>], x1: Option<&[Vector3<f64>]>, m: f64) {
        self.vert.clear();
        self.vert
            .extend((0..x0.len()).map(|i| pad(point_box(x0, x1, i), m)));
        self.all = Some(self.vert.iter().fold(Aabb::EMPTY, |a, b| join(&a, b)));
    }

    /// The edge and triangle boxes (after [`PrimitiveBoxes::build_vertices`]
    /// with the same points and margin).
    pub fn build_faces(
        &mut self,
        mesh: &crate::mesh::LinkMesh,
        x0: &[Vector3<f64>],
        x1: Option<&[Vector3<f64>]>,
        m: f64,
    ) {
        let pt = |i: u32| point_box(x0, x1, i as usize);
        self.edge.clear();
        self.edge.extend(
            mesh.edges
                .iter()
                .map(|e| pad(join(&pt(e[0]), &pt(e[1])), m)),
        );
        self.tri.clear();
        self.tri.extend(
            mesh.tris
                .iter()
                .map(|t| pad(join(&join(&pt(t[0]), &pt(t[1])), &pt(t[2])), m)),
        );
    }
}

/// `b` grown by `m` on every side (the core's [`Aabb::padded`], inlined
/// here: the core's helpers cannot be inlined across crates, and the
/// boxes are the baseline's hottest loop).
#[inline]
fn pad(b: Aabb, m: f64) -> Aabb {
    let d = Vector3::repeat(m);
    Aabb {
        lo: b.lo - d,
        hi: b.hi + d,
    }
}

/// The smallest box containing both ([`Aabb::union`], inlined).
#[inline]
fn join(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb {
        lo: a.lo.inf(&b.lo),
        hi: a.hi.sup(&b.hi),
    }
}

/// Whether the boxes intersect ([`Aabb::intersects`], inlined).
#[inline]
fn meets(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|e| a.lo[e] <= b.hi[e] && b.lo[e] <= a.hi[e])
}

/// The box of point `i` at `x0` (and `x1`).
#[inline]
fn point_box(x0: &[Vector3<f64>], x1: Option<&[Vector3<f64>]>, i: usize) -> Aabb {
    let mut b = Aabb::point(&x0[i]);
    if let Some(x1) = x1 {
        b.lo = b.lo.inf(&x1[i]);
        b.hi = b.hi.sup(&x1[i]);
    }
    b
}

/// Boxes of every link's primitives for the link pairs `pairs`: every
/// link's vertex boxes and link box, and the edge and triangle boxes only of
/// links in a pair whose link boxes meet (the only ones [`candidates`]
/// reads; a far link's are left stale). `points(i)` gives link `i`'s points
/// (`x0`, and `x1` for swept boxes) and margin; empty meshes are skipped.
pub fn build_for_pairs<'a>(
    boxes: &mut [PrimitiveBoxes],
    meshes: &[crate::mesh::LinkMesh],
    pairs: &[(usize, usize)],
    points: impl Fn(usize) -> (&'a [Vector3<f64>], Option<&'a [Vector3<f64>]>, f64),
) {
    for (i, m) in meshes.iter().enumerate() {
        if !m.is_empty() {
            let (x0, x1, margin) = points(i);
            boxes[i].build_vertices(x0, x1, margin);
        } else {
            boxes[i].all = None;
        }
    }
    let mut near = vec![false; meshes.len()];
    for &(a, b) in pairs {
        if let (Some(ba), Some(bb)) = (boxes[a].all, boxes[b].all)
            && meets(&ba, &bb)
        {
            near[a] = true;
            near[b] = true;
        }
    }
    for (i, m) in meshes.iter().enumerate() {
        if near[i] {
            let (x0, x1, margin) = points(i);
            boxes[i].build_faces(m, x0, x1, margin);
        }
    }
}

/// Candidate primitive pairs of two links: those whose boxes intersect.
/// With each side's boxes inflated by `m/2`, every pair of primitives closer
/// than `m` is kept (their un-inflated boxes are then within `m` on every
/// axis).
pub fn candidates(a: &PrimitiveBoxes, b: &PrimitiveBoxes, out: &mut Candidates) {
    out.clear();
    let (Some(ba), Some(bb)) = (a.all, b.all) else {
        return;
    };
    if !meets(&ba, &bb) {
        return;
    }
    let region = ba.intersection(&bb);
    let sel = |boxes: &[Aabb]| -> Vec<u32> {
        (0..boxes.len() as u32)
            .filter(|&i| meets(&boxes[i as usize], &region))
            .collect()
    };
    let (va, vb) = (sel(&a.vert), sel(&b.vert));
    let (ta, tb) = (sel(&a.tri), sel(&b.tri));
    let (ea, eb) = (sel(&a.edge), sel(&b.edge));
    for &v in &va {
        for &t in &tb {
            if meets(&a.vert[v as usize], &b.tri[t as usize]) {
                out.vt_ab.push((v, t));
            }
        }
    }
    for &v in &vb {
        for &t in &ta {
            if meets(&b.vert[v as usize], &a.tri[t as usize]) {
                out.vt_ba.push((v, t));
            }
        }
    }
    for &i in &ea {
        for &j in &eb {
            if meets(&a.edge[i as usize], &b.edge[j as usize]) {
                out.ee.push((i, j));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::LinkMesh;

    /// A tetrahedron with its first vertex at `o` (edge 0.1 m).
    fn tet(o: [f64; 3]) -> LinkMesh {
        let o = Vector3::from(o);
        let v = [
            o,
            o + Vector3::new(0.1, 0.0, 0.0),
            o + Vector3::new(0.0, 0.1, 0.0),
            o + Vector3::new(0.0, 0.0, 0.1),
        ];
        let mut m = LinkMesh::default();
        m.add_closed(0, &v, &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
            .unwrap();
        m
    }

    /// The lazy build gives every pair the candidates of a full build, on
    /// near, touching-margin and far pairs, after a first evaluation at
    /// other points left stale face boxes behind (swept boxes too).
    #[test]
    fn boxes_built_for_pairs_give_the_candidates_of_a_full_build() {
        let meshes = vec![
            tet([0.0, 0.0, 0.0]),
            tet([0.1005, 0.0, 0.0]),
            tet([5.0, 0.0, 0.0]),
            LinkMesh::default(),
            tet([-0.2, 0.0, 0.0]),
        ];
        let pairs = [(0, 1), (0, 2), (1, 2), (0, 3), (2, 4), (0, 4)];
        let shift = |d: f64| -> Vec<Vec<Vector3<f64>>> {
            meshes
                .iter()
                .map(|m| {
                    m.x_local
                        .iter()
                        .map(|x| x + Vector3::new(d, 0.0, 0.0))
                        .collect()
                })
                .collect()
        };
        let (x0, x1) = (shift(0.0), shift(0.003));
        for swept in [false, true] {
            let mut lazy = vec![PrimitiveBoxes::default(); meshes.len()];
            // A first build at far-away points: stale faces for every link.
            let far = shift(-3.0);
            build_for_pairs(&mut lazy, &meshes, &pairs, |i| (&far[i][..], None, 1e-3));
            build_for_pairs(&mut lazy, &meshes, &pairs, |i| {
                (&x0[i][..], swept.then(|| &x1[i][..]), 1e-3)
            });
            let mut full = vec![PrimitiveBoxes::default(); meshes.len()];
            for (i, m) in meshes.iter().enumerate() {
                if !m.is_empty() {
                    full[i].build(m, &x0[i], swept.then(|| &x1[i][..]), 1e-3);
                }
            }
            let mut found = 0;
            for &(a, b) in &pairs {
                let (mut cl, mut cf) = (Candidates::default(), Candidates::default());
                candidates(&lazy[a], &lazy[b], &mut cl);
                candidates(&full[a], &full[b], &mut cf);
                assert_eq!(
                    (&cl.vt_ab, &cl.vt_ba, &cl.ee),
                    (&cf.vt_ab, &cf.vt_ba, &cf.ee),
                    "pair {a}-{b}, swept {swept}"
                );
                found += cf.len();
            }
            assert!(
                found > 0,
                "no pair had candidates: the test would not see a difference"
            );
        }
    }
}
