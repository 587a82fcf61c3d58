//! Topological and metric checks of a triangle mesh: finite coordinates,
//! non-degenerate triangles, closed and consistently oriented (every
//! undirected edge in exactly two triangles, which run it in opposite
//! directions), connected components, and the enclosed signed volume.

use super::SurfaceError;
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::Path;

/// Checks coordinates and triangle areas (`area ≤ 10⁻¹² · extent²` or NaN
/// is degenerate, `extent` the bounding-box diagonal).
pub fn check_metric(
    file: &Path,
    v: &[Vector3<f64>],
    tris: &[[usize; 3]],
) -> Result<(), SurfaceError> {
    if tris.is_empty() {
        return Err(SurfaceError::Empty {
            file: file.to_path_buf(),
        });
    }
    if let Some((i, p)) = v
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(SurfaceError::NonFinite {
            file: file.to_path_buf(),
            vertex: i,
            point: [p.x, p.y, p.z],
        });
    }
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in v {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent = (hi - lo).norm();
    for (i, t) in tris.iter().enumerate() {
        let area = 0.5 * (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]])).norm();
        if area.is_nan() || area <= 1e-12 * extent * extent {
            return Err(SurfaceError::Degenerate {
                file: file.to_path_buf(),
                tri: i,
                vertices: *t,
                points: Box::new(t.map(|k| super::xyz(&v[k]))),
                area,
                extent,
            });
        }
    }
    Ok(())
}

/// Checks that the mesh is closed and consistently oriented (the first
/// offending edge, in `(min, max)` vertex order, is reported).
pub fn check_closed_oriented(
    file: &Path,
    v: &[Vector3<f64>],
    tris: &[[usize; 3]],
) -> Result<(), SurfaceError> {
    // Undirected edge → the triangles using it and the direction each runs it.
    let mut edges: BTreeMap<(usize, usize), Vec<(usize, bool)>> = BTreeMap::new();
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((i, a < b));
        }
    }
    for (&(a, b), uses) in &edges {
        if uses.len() != 2 {
            return Err(SurfaceError::Open {
                file: file.to_path_buf(),
                a,
                b,
                pa: super::xyz(&v[a]),
                pb: super::xyz(&v[b]),
                count: uses.len(),
                tris: uses.iter().map(|u| u.0).collect(),
            });
        }
        if uses[0].1 == uses[1].1 {
            let (a, b) = if uses[0].1 { (a, b) } else { (b, a) };
            return Err(SurfaceError::Orientation {
                file: file.to_path_buf(),
                a,
                b,
                pa: super::xyz(&v[a]),
                pb: super::xyz(&v[b]),
                t1: uses[0].0,
                t2: uses[1].0,
            });
        }
    }
    Ok(())
}

/// Connected components of triangles (sharing a vertex), each as the
/// sorted list of its triangle indices, ordered by their first triangle.
pub fn components(nv: usize, tris: &[[usize; 3]]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..nv).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in tris {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut by_root: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, t) in tris.iter().enumerate() {
        let r = find(&mut parent, t[0]);
        by_root.entry(r).or_default().push(i);
    }
    let mut out: Vec<Vec<usize>> = by_root.into_values().collect();
    out.sort_by_key(|c| c[0]);
    out
}

/// Signed volume enclosed by closed triangles (positive when they are
/// counter-clockwise seen from outside): `Σ x₀ · (x₁ × x₂) / 6`.
pub fn signed_volume(v: &[Vector3<f64>], tris: &[[usize; 3]]) -> f64 {
    tris.iter()
        .map(|t| v[t[0]].dot(&v[t[1]].cross(&v[t[2]])))
        .sum::<f64>()
        / 6.0
}
