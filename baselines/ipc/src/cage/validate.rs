//! Checks that a cage can deform a link's surface: closed and consistently
//! oriented (every directed edge once, its reverse once), no degenerate
//! (zero-area) triangle, no out-of-range index, and every surface vertex
//! inside (generalized winding number `Σ Ω_t / 4π = 1`, with `Ω_t` the
//! signed solid angle of triangle `t` seen from the vertex, Van Oosterom &
//! Strackee 1983).

use super::Cage;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Why a cage is unusable; `link` names the link the cage belongs to.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CageError {
    #[error(
        "cage of link \"{link}\": triangle {tri} uses vertex {vertex}, but the cage has {count} vertices"
    )]
    Index {
        link: String,
        tri: usize,
        vertex: u32,
        count: usize,
    },
    #[error(
        "cage of link \"{link}\": triangle {tri} is degenerate (area {area:.3e} m² for a cage of extent {extent:.3e} m)"
    )]
    Degenerate {
        link: String,
        tri: usize,
        area: f64,
        extent: f64,
    },
    #[error(
        "cage of link \"{link}\": not a closed, consistently oriented surface (directed edge {a}→{b} is used {count} times, its reverse {reverse} times; each must be used once)"
    )]
    Open {
        link: String,
        a: u32,
        b: u32,
        count: usize,
        reverse: usize,
    },
    #[error(
        "cage of link \"{link}\" does not enclose hull {hull} vertex {vertex} at {point:?} (winding number {winding:.3}, inside needs 1)"
    )]
    NotEnclosing {
        link: String,
        hull: usize,
        vertex: usize,
        point: [f64; 3],
        winding: f64,
    },
    #[error(
        "cage of link \"{link}\" does not enclose source-surface vertex {vertex} at {point:?} (winding number {winding:.3}, inside needs 1)"
    )]
    NotEnclosingSurface {
        link: String,
        vertex: usize,
        point: [f64; 3],
        winding: f64,
    },
}

/// Signed solid angle of triangle `(a, b, c)` seen from `x` (sr).
pub fn solid_angle(x: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
    let (ra, rb, rc) = (a - x, b - x, c - x);
    let (la, lb, lc) = (ra.norm(), rb.norm(), rc.norm());
    let num = ra.dot(&rb.cross(&rc));
    let den = la * lb * lc + ra.dot(&rb) * lc + rb.dot(&rc) * la + rc.dot(&ra) * lb;
    2.0 * num.atan2(den)
}

/// Generalized winding number of `cage` around `x` (1 inside a
/// counter-clockwise closed cage, 0 outside).
pub fn winding_number(cage: &Cage, x: &Vector3<f64>) -> f64 {
    let v = &cage.vertices;
    cage.tris
        .iter()
        .map(|t| solid_angle(x, &v[t[0] as usize], &v[t[1] as usize], &v[t[2] as usize]))
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI)
}

/// Checks `cage` for link `link` against the surface points
/// `points[(hull, vertex)]`.
pub fn validate_cage(
    cage: &Cage,
    link: &str,
    points: &[(usize, usize, Vector3<f64>)],
) -> Result<(), CageError> {
    let n = cage.vertices.len();
    let name = || link.to_string();
    for (ti, t) in cage.tris.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
            return Err(CageError::Index {
                link: name(),
                tri: ti,
                vertex: v,
                count: n,
            });
        }
    }
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in &cage.vertices {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent = (hi - lo).norm();
    for (ti, t) in cage.tris.iter().enumerate() {
        let p = t.map(|i| cage.vertices[i as usize]);
        let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        if area.is_nan() || area <= 1e-12 * extent * extent {
            return Err(CageError::Degenerate {
                link: name(),
                tri: ti,
                area,
                extent,
            });
        }
    }
    let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for t in &cage.tris {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        let reverse = directed.get(&(b, a)).copied().unwrap_or(0);
        if count != 1 || reverse != 1 {
            return Err(CageError::Open {
                link: name(),
                a,
                b,
                count,
                reverse,
            });
        }
    }
    for &(hull, vertex, x) in points {
        let w = winding_number(cage, &x);
        if (w - 1.0).abs() > 1e-6 {
            return Err(CageError::NotEnclosing {
                link: name(),
                hull,
                vertex,
                point: [x.x, x.y, x.z],
                winding: w,
            });
        }
    }
    Ok(())
}
