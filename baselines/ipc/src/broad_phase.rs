//! Primitive broad phase between the surfaces of two links: axis-aligned
//! boxes inflated by a margin (`d̂` for the potential; the swept extent plus
//! the CCD gap for continuous collision detection). First the two link
//! boxes are intersected into an overlap region; only vertices, edges and
//! triangles whose box meets that region are paired, then pairs are tested
//! box against box. Exact (no candidate with overlapping inflated boxes is
//! missed), deterministic (index order).

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
        let pt = |i: u32| -> Aabb {
            let i = i as usize;
            let mut b = Aabb::point(&x0[i]);
            if let Some(x1) = x1 {
                b.lo = b.lo.inf(&x1[i]);
                b.hi = b.hi.sup(&x1[i]);
            }
            b
        };
        let join = |a: Aabb, b: Aabb| a.union(&b);
        self.vert.clear();
        self.vert
            .extend((0..x0.len() as u32).map(|i| pt(i).padded(m)));
        self.edge.clear();
        self.edge.extend(
            mesh.edges
                .iter()
                .map(|e| join(pt(e[0]), pt(e[1])).padded(m)),
        );
        self.tri.clear();
        self.tri.extend(
            mesh.tris
                .iter()
                .map(|t| join(join(pt(t[0]), pt(t[1])), pt(t[2])).padded(m)),
        );
        self.all = Some(self.vert.iter().fold(Aabb::EMPTY, |a, b| join(a, *b)));
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
    if !ba.intersects(&bb) {
        return;
    }
    let region = ba.intersection(&bb);
    let sel = |boxes: &[Aabb]| -> Vec<u32> {
        (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].intersects(&region))
            .collect()
    };
    let (va, vb) = (sel(&a.vert), sel(&b.vert));
    let (ta, tb) = (sel(&a.tri), sel(&b.tri));
    let (ea, eb) = (sel(&a.edge), sel(&b.edge));
    for &v in &va {
        for &t in &tb {
            if a.vert[v as usize].intersects(&b.tri[t as usize]) {
                out.vt_ab.push((v, t));
            }
        }
    }
    for &v in &vb {
        for &t in &ta {
            if b.vert[v as usize].intersects(&a.tri[t as usize]) {
                out.vt_ba.push((v, t));
            }
        }
    }
    for &i in &ea {
        for &j in &eb {
            if a.edge[i as usize].intersects(&b.edge[j as usize]) {
                out.ee.push((i, j));
            }
        }
    }
}
