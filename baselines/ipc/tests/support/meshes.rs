//! Test meshes written as OBJ files: a U-shaped channel (non-convex), a UV
//! sphere (many triangles), tetrahedra and cubes with defects.

#![allow(dead_code)]

use std::fmt::Write;
use std::path::{Path, PathBuf};

pub type Mesh = (Vec<[f64; 3]>, Vec<[usize; 3]>);

/// A fresh scratch directory under the target dir.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sdrs-ipc-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn write_obj(path: &Path, (v, t): &Mesh) {
    let mut s = String::new();
    for p in v {
        writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for f in t {
        writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1).unwrap();
    }
    std::fs::write(path, s).unwrap();
}

/// A U-shaped channel along y (|y| ≤ 0.3): outer 0.6 (x) × 0.3 (z) from
/// z = 0, a slot 0.3 wide (|x| ≤ 0.15) from z = 0.1 to the top. Its convex
/// hull is the box `[-0.3, 0.3] × [-0.3, 0.3] × [0, 0.3]`.
pub fn channel() -> Mesh {
    extrude(
        &[
            (-0.3, 0.0),
            (0.3, 0.0),
            (0.3, 0.3),
            (0.15, 0.3),
            (0.15, 0.1),
            (-0.15, 0.1),
            (-0.15, 0.3),
            (-0.3, 0.3),
        ],
        &[
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [0, 4, 5],
            [0, 5, 7],
            [5, 6, 7],
        ],
        0.3,
    )
}

/// An L-shaped bar along y (|y| ≤ 0.1): a foot `[0, 0.2] × [0, 0.05]` and a
/// leg `[0, 0.05] × [0.05, 0.2]` in (x, z); its convex hulls are those two
/// boxes.
pub fn l_shape() -> Mesh {
    extrude(
        &[
            (0.0, 0.0),
            (0.2, 0.0),
            (0.2, 0.05),
            (0.05, 0.05),
            (0.05, 0.2),
            (0.0, 0.2),
        ],
        &[[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]],
        0.1,
    )
}

/// The prism of a polygon `p` (counter-clockwise in (x, z), triangulated by
/// `cap`) over `|y| ≤ hw`, outward.
pub fn extrude(p: &[(f64, f64)], cap: &[[usize; 3]], hw: f64) -> Mesh {
    let mut v = Vec::new();
    for y in [-hw, hw] {
        for &(x, z) in p {
            v.push([x, y, z]);
        }
    }
    let n = p.len();
    let mut t = Vec::new();
    // Counter-clockwise in (x, z) faces −y: the front cap (y = −hw).
    for c in cap {
        t.push(*c);
        t.push([c[0] + n, c[2] + n, c[1] + n]);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        t.push([j, i, i + n]);
        t.push([j, i + n, j + n]);
    }
    (v, t)
}

/// A UV sphere of radius `r` with `rings` latitude bands and `seg`
/// longitude segments: `2 seg (rings − 1)` triangles.
pub fn sphere(r: f64, rings: usize, seg: usize) -> Mesh {
    let mut v = vec![[0.0, 0.0, r], [0.0, 0.0, -r]];
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..seg {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
            v.push([
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ]);
        }
    }
    let id = |i: usize, j: usize| 2 + (i - 1) * seg + j % seg;
    let mut t = Vec::new();
    for j in 0..seg {
        t.push([0, id(1, j), id(1, j + 1)]);
        t.push([1, id(rings - 1, j + 1), id(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..seg {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (v, t)
}

/// The unit cube `[0, 1]³`, outward, 12 triangles.
pub fn cube() -> Mesh {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
        .collect();
    let t = vec![
        [0, 2, 3],
        [0, 3, 1], // z = 0
        [4, 5, 7],
        [4, 7, 6], // z = 1
        [0, 1, 5],
        [0, 5, 4], // y = 0
        [2, 6, 7],
        [2, 7, 3], // y = 1
        [0, 4, 6],
        [0, 6, 2], // x = 0
        [1, 3, 7],
        [1, 7, 5], // x = 1
    ];
    (v, t)
}

/// An outward tetrahedron.
pub fn tetra() -> Mesh {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
}
