//! Writes the paper's benchmark robots (URDF + OBJ) into `robots/`:
//! `cargo run --example make_robots [-- OUT_DIR]`. Deterministic: running it
//! again reproduces the committed files byte for byte.
//!
//! Every robot is `robots/<name>/<name>.urdf` with meshes in
//! `robots/<name>/meshes/` and, for grippers, objects in
//! `robots/<name>/objects/` (bare OBJ meshes: `sdrs import` makes each a
//! free body). 2-DOF joints are written the URDF way, as two orthogonal
//! revolute joints through a massless, geometry-less link; `sdrs import`
//! turns such pairs back into one `ball` joint. Floating bases hang from a
//! geometry-less `world` link through a `floating` joint.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

type V3 = [f64; 3];

/// A triangle mesh being authored.
#[derive(Default, Clone)]
struct Mesh {
    v: Vec<V3>,
    f: Vec<[usize; 3]>,
}

impl Mesh {
    fn obj(&self, comment: &str) -> String {
        let mut s = format!("# {comment}\n# written by examples/make_robots.rs\n");
        for p in &self.v {
            let _ = writeln!(s, "v {} {} {}", fmt(p[0]), fmt(p[1]), fmt(p[2]));
        }
        for t in &self.f {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }
    fn translate(mut self, d: V3) -> Mesh {
        for p in &mut self.v {
            for k in 0..3 {
                p[k] += d[k];
            }
        }
        self
    }
}

fn fmt(x: f64) -> String {
    let r = (x * 1e12).round() / 1e12;
    if r == 0.0 { "0".into() } else { format!("{r}") }
}

/// Axis-aligned box between `lo` and `hi` (outward-facing triangles).
fn box_mesh(lo: V3, hi: V3) -> Mesh {
    let mut v = Vec::new();
    for i in 0..8 {
        v.push([
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]);
    }
    let quads = [
        [0, 2, 3, 1], // z-
        [4, 5, 7, 6], // z+
        [0, 1, 5, 4], // y-
        [2, 6, 7, 3], // y+
        [0, 4, 6, 2], // x-
        [1, 3, 7, 5], // x+
    ];
    let mut f = Vec::new();
    for q in quads {
        f.push([q[0], q[1], q[2]]);
        f.push([q[0], q[2], q[3]]);
    }
    Mesh { v, f }
}

/// Ear-clipping triangulation of a simple counter-clockwise polygon.
fn ear_clip(poly: &[[f64; 2]]) -> Vec<[usize; 3]> {
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    // Vertices on the candidate triangle's boundary block it too.
    let inside = |p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        p != a
            && p != b
            && p != c
            && cross(a, b, p) >= -1e-12
            && cross(b, c, p) >= -1e-12
            && cross(c, a, p) >= -1e-12
    };
    let mut idx: Vec<usize> = (0..poly.len()).collect();
    let mut out = Vec::new();
    while idx.len() > 3 {
        let n = idx.len();
        let mut clipped = false;
        for k in 0..n {
            let (i0, i1, i2) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
            let (a, b, c) = (poly[i0], poly[i1], poly[i2]);
            if cross(a, b, c) <= 1e-12 {
                continue;
            }
            if idx
                .iter()
                .any(|&j| j != i0 && j != i1 && j != i2 && inside(poly[j], a, b, c))
            {
                continue;
            }
            out.push([i0, i1, i2]);
            idx.remove(k);
            clipped = true;
            break;
        }
        assert!(clipped, "polygon is not simple");
    }
    out.push([idx[0], idx[1], idx[2]]);
    out
}

/// Extrudes a CCW polygon in the (u, v) plane by `depth` along the third
/// axis; `axes` maps (u, v, w) to the output coordinates.
fn extrude(poly: &[[f64; 2]], depth: f64, axes: [usize; 3]) -> Mesh {
    let n = poly.len();
    let mut v = Vec::new();
    for w in [-depth / 2.0, depth / 2.0] {
        for p in poly {
            let mut x = [0.0; 3];
            x[axes[0]] = p[0];
            x[axes[1]] = p[1];
            x[axes[2]] = w;
            v.push(x);
        }
    }
    let mut f = Vec::new();
    let caps = ear_clip(poly);
    for t in &caps {
        f.push([t[0] + n, t[1] + n, t[2] + n]); // top, CCW seen from +w
        f.push([t[0], t[2], t[1]]); // bottom
    }
    for i in 0..n {
        let j = (i + 1) % n;
        f.push([i, j, j + n]);
        f.push([i, j + n, i + n]);
    }
    // Orientation: (u, v, w) must be right-handed in output space.
    let handed = matches!(axes, [0, 1, 2] | [1, 2, 0] | [2, 0, 1]);
    if !handed {
        for t in &mut f {
            t.swap(1, 2);
        }
    }
    Mesh { v, f }
}

/// A closed tube: `rings` circles (radius `r(s)`, `segs` points each) along
/// the centreline `c(s)`, `s ∈ [0, 1]`, capped at both ends.
fn tube(rings: usize, segs: usize, c: impl Fn(f64) -> V3, r: impl Fn(f64) -> (f64, f64)) -> Mesh {
    let mut v = Vec::new();
    for i in 0..rings {
        let s = i as f64 / (rings - 1) as f64;
        let p = c(s);
        let (s0, s1) = ((s - 1e-3).max(0.0), (s + 1e-3).min(1.0));
        let (a, b) = (c(s0), c(s1));
        let t = norm([b[0] - a[0], b[1] - a[1], b[2] - a[2]]);
        // Frame: a fixed up vector not parallel to the tangent.
        let up = if t[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let n1 = norm(cross(up, t));
        let n2 = cross(t, n1);
        let (ra, rb) = r(s);
        for k in 0..segs {
            let th = 2.0 * PI * k as f64 / segs as f64;
            let (x, y) = (ra * th.cos(), rb * th.sin());
            v.push([
                p[0] + x * n1[0] + y * n2[0],
                p[1] + x * n1[1] + y * n2[1],
                p[2] + x * n1[2] + y * n2[2],
            ]);
        }
    }
    let mut f = Vec::new();
    for i in 0..rings - 1 {
        for k in 0..segs {
            let (a, b) = (i * segs + k, i * segs + (k + 1) % segs);
            let (c2, d) = (a + segs, b + segs);
            f.push([a, b, d]);
            f.push([a, d, c2]);
        }
    }
    let last = (rings - 1) * segs;
    for k in 1..segs - 1 {
        f.push([0, k + 1, k]);
        f.push([last, last + k, last + k + 1]);
    }
    let mut m = Mesh { v, f };
    if signed_volume(&m) < 0.0 {
        for t in &mut m.f {
            t.swap(1, 2);
        }
    }
    m
}

fn signed_volume(m: &Mesh) -> f64 {
    m.f.iter()
        .map(|t| {
            let (a, b, c) = (m.v[t[0]], m.v[t[1]], m.v[t[2]]);
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        })
        .sum::<f64>()
        / 6.0
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V3) -> V3 {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Regular polygon prism (cylinder-like) along z.
fn prism(r: f64, h: f64, n: usize) -> Mesh {
    let poly: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / n as f64;
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    extrude(&poly, h, [0, 1, 2])
}

/// Icosphere-like ball: a UV sphere with `rings` × `segs` points + poles.
fn ball(r: f64, rings: usize, segs: usize) -> Mesh {
    tube(
        rings,
        segs,
        |s| [0.0, 0.0, -(r * (PI * (0.5 + 0.45 * (2.0 * s - 1.0))).cos())],
        |s| {
            let th = PI * (0.5 + 0.45 * (2.0 * s - 1.0));
            (r * th.sin(), r * th.sin())
        },
    )
}

/// Plus-shaped polygon with arm half-width `w` and half-length `l`,
/// rotated by `rot`.
fn plus(w: f64, l: f64, rot: f64) -> Vec<[f64; 2]> {
    let p = [
        [l, -w],
        [l, w],
        [w, w],
        [w, l],
        [-w, l],
        [-w, w],
        [-l, w],
        [-l, -w],
        [-w, -w],
        [-w, -l],
        [w, -l],
        [w, -w],
    ];
    p.iter()
        .map(|q| {
            [
                q[0] * rot.cos() - q[1] * rot.sin(),
                q[0] * rot.sin() + q[1] * rot.cos(),
            ]
        })
        .collect()
}

// ---------------------------------------------------------------- URDF

struct Urdf {
    name: String,
    body: String,
}

fn v3(a: V3) -> String {
    format!("{} {} {}", fmt(a[0]), fmt(a[1]), fmt(a[2]))
}

impl Urdf {
    fn new(name: &str) -> Self {
        Urdf {
            name: name.into(),
            body: String::new(),
        }
    }
    /// A link with mesh collision geometry (and the same as visual).
    fn link(&mut self, name: &str, mass: f64, com: V3, meshes: &[&str]) {
        let _ = writeln!(self.body, "  <link name=\"{name}\">");
        let i = mass * 1e-3;
        let _ = writeln!(
            self.body,
            "    <inertial>\n      <origin xyz=\"{}\" rpy=\"0 0 0\"/>\n      <mass value=\"{}\"/>\n      <inertia ixx=\"{i}\" ixy=\"0\" ixz=\"0\" iyy=\"{i}\" iyz=\"0\" izz=\"{i}\"/>\n    </inertial>",
            v3(com),
            fmt(mass)
        );
        for kind in ["visual", "collision"] {
            for m in meshes {
                let _ = writeln!(
                    self.body,
                    "    <{kind}>\n      <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n      <geometry>\n        <mesh filename=\"meshes/{m}.obj\"/>\n      </geometry>\n    </{kind}>"
                );
            }
        }
        let _ = writeln!(self.body, "  </link>");
    }
    fn empty_link(&mut self, name: &str) {
        let _ = writeln!(self.body, "  <link name=\"{name}\"/>");
    }
    #[allow(clippy::too_many_arguments)]
    fn joint(
        &mut self,
        name: &str,
        kind: &str,
        parent: &str,
        child: &str,
        xyz: V3,
        rpy: V3,
        axis: V3,
        limit: (f64, f64),
    ) {
        let _ = writeln!(self.body, "  <joint name=\"{name}\" type=\"{kind}\">");
        let _ = writeln!(
            self.body,
            "    <parent link=\"{parent}\"/>\n    <child link=\"{child}\"/>"
        );
        let _ = writeln!(
            self.body,
            "    <origin xyz=\"{}\" rpy=\"{}\"/>",
            v3(xyz),
            v3(rpy)
        );
        if kind != "fixed" && kind != "floating" {
            let _ = writeln!(self.body, "    <axis xyz=\"{}\"/>", v3(axis));
        }
        if kind == "revolute" || kind == "prismatic" {
            let _ = writeln!(
                self.body,
                "    <limit lower=\"{}\" upper=\"{}\" effort=\"100\" velocity=\"10\"/>",
                fmt(limit.0),
                fmt(limit.1)
            );
        }
        let _ = writeln!(self.body, "  </joint>");
    }
    /// Two orthogonal hinges (x then y) through a massless gimbal link.
    fn ball(&mut self, name: &str, parent: &str, child: &str, xyz: V3) {
        let g = format!("{name}_gimbal");
        self.empty_link(&g);
        self.joint(
            &format!("{name}_x"),
            "revolute",
            parent,
            &g,
            xyz,
            [0.0; 3],
            [1.0, 0.0, 0.0],
            (-1.5, 1.5),
        );
        self.joint(
            &format!("{name}_y"),
            "revolute",
            &g,
            child,
            [0.0; 3],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            (-1.5, 1.5),
        );
    }
    fn text(&self) -> String {
        format!(
            "<?xml version=\"1.0\"?>\n<!-- {} — written by examples/make_robots.rs -->\n<robot name=\"{}\">\n{}</robot>\n",
            self.name, self.name, self.body
        )
    }
}

struct Out {
    dir: PathBuf,
}

impl Out {
    fn write(&self, rel: &str, text: &str) {
        let p = self.dir.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    fn mesh(&self, robot: &str, name: &str, m: &Mesh) {
        self.write(
            &format!("{robot}/meshes/{name}.obj"),
            &m.obj(&format!("{robot}: {name}")),
        );
    }
    fn object(&self, robot: &str, name: &str, m: &Mesh) {
        self.write(
            &format!("{robot}/objects/{name}.obj"),
            &m.obj(&format!("{robot}: object {name}")),
        );
    }
    fn urdf(&self, u: &Urdf) {
        self.write(&format!("{}/{}.urdf", u.name, u.name), &u.text());
    }
}

// ---------------------------------------------------------------- robots

/// Four chains of 4 links, each joint a 2-DOF ball joint (|θ| = 4·2·4 = 32).
fn rotating_chains(o: &Out) {
    let name = "rotating_chains";
    let (len, w) = (0.5, 0.1);
    o.mesh(
        name,
        "link",
        &box_mesh(
            [-w / 2.0, -w / 2.0, -len - w / 4.0],
            [w / 2.0, w / 2.0, w / 4.0],
        ),
    );
    let mut u = Urdf::new(name);
    u.empty_link("world");
    for c in 0..4 {
        let mut parent = "world".to_string();
        for l in 0..4 {
            let link = format!("chain{c}_link{l}");
            u.link(&link, 0.1, [0.0, 0.0, -len / 2.0], &["link"]);
            let xyz = if l == 0 {
                [0.6 * c as f64, 0.0, 2.5]
            } else {
                [0.0, 0.0, -len]
            };
            u.ball(&format!("chain{c}_joint{l}"), &parent, &link, xyz);
            parent = link;
        }
    }
    o.urdf(&u);
}

/// An I-beam link profile (non-convex): flanges at both ends, thinner web.
fn ibeam(len: f64, w: f64) -> Mesh {
    let (h, t) = (w / 2.0, w / 5.0);
    let f = w / 4.0; // flange thickness
    let z0 = w / 4.0;
    let z1 = -len - w / 4.0;
    // Polygon in (x, z), CCW.
    let poly = vec![
        [-h, z1],
        [h, z1],
        [h, z1 + f],
        [t, z1 + f],
        [t, z0 - f],
        [h, z0 - f],
        [h, z0],
        [-h, z0],
        [-h, z0 - f],
        [-t, z0 - f],
        [-t, z1 + f],
        [-h, z1 + f],
    ];
    // u = x, v = z, w = y: (x, z, y) is left-handed, extrude() fixes it.
    extrude(&poly, w, [0, 2, 1])
}

/// Three 8-link chains: the left one on a horizontal prismatic carriage,
/// the other two passive; ball joints throughout.
fn chains_8link(o: &Out) {
    let name = "chains_8link";
    let (len, w) = (0.25, 0.08);
    o.mesh(name, "link", &ibeam(len, w));
    o.mesh(
        name,
        "carriage",
        &box_mesh([-0.1, -0.06, -0.03], [0.1, 0.06, 0.06]),
    );
    let mut u = Urdf::new(name);
    u.empty_link("world");
    u.link("carriage", 1.0, [0.0; 3], &["carriage"]);
    u.joint(
        "slide",
        "prismatic",
        "world",
        "carriage",
        [0.0, 0.0, 2.5],
        [0.0; 3],
        [1.0, 0.0, 0.0],
        (-1.0, 1.0),
    );
    for c in 0..3 {
        let mut parent = if c == 0 {
            "carriage".to_string()
        } else {
            "world".to_string()
        };
        for l in 0..8 {
            let link = format!("chain{c}_link{l}");
            u.link(&link, 0.05, [0.0, 0.0, -len / 2.0], &["link"]);
            let xyz = match (c, l) {
                (0, 0) => [0.0; 3],
                (_, 0) => [0.5 * c as f64 + 0.5, 0.0, 2.5],
                _ => [0.0, 0.0, -len],
            };
            u.ball(&format!("chain{c}_joint{l}"), &parent, &link, xyz);
            parent = link;
        }
    }
    o.urdf(&u);
}

/// A bent foot of 8 rings × 12 points = 96 vertices, curling downward.
fn spider_foot() -> Mesh {
    tube(
        8,
        12,
        |s| {
            let a = s * PI / 2.0;
            // Quarter arc: starts going down (−z), ends pointing outward (+x).
            [0.08 * (1.0 - a.cos()), 0.0, -0.08 * a.sin() - 0.25]
        },
        |s| {
            let r = 0.03 * (1.0 - 0.4 * s);
            (r, r)
        },
    )
}

/// Spider: floating body, 4 legs × (upper, lower+foot), 8 ball joints
/// (16 joint DOF; 9 links).
fn spider(o: &Out) {
    let name = "spider";
    o.mesh(name, "body", &prism(0.2, 0.08, 16));
    o.mesh(
        name,
        "upper_leg",
        &box_mesh([-0.025, -0.025, -0.02], [0.3, 0.025, 0.025]),
    );
    o.mesh(
        name,
        "shin",
        &box_mesh([-0.025, -0.025, -0.26], [0.025, 0.025, 0.025]),
    );
    o.mesh(name, "foot", &spider_foot());
    let mut u = Urdf::new(name);
    u.empty_link("world");
    u.link("body", 2.0, [0.0; 3], &["body"]);
    u.joint(
        "root",
        "floating",
        "world",
        "body",
        [0.0, 0.0, 0.5],
        [0.0; 3],
        [0.0; 3],
        (0.0, 0.0),
    );
    for k in 0..4 {
        let a = PI / 4.0 + PI / 2.0 * k as f64;
        let upper = format!("leg{k}_upper");
        let lower = format!("leg{k}_lower");
        // Hip: on the body rim, the leg frame rotated to point outward.
        let hip = format!("leg{k}_hip");
        let g = format!("{hip}_gimbal");
        u.empty_link(&g);
        u.joint(
            &format!("{hip}_z"),
            "revolute",
            "body",
            &g,
            [0.17 * a.cos(), 0.17 * a.sin(), 0.0],
            [0.0, 0.0, a],
            [0.0, 0.0, 1.0],
            (-1.0, 1.0),
        );
        u.joint(
            &format!("{hip}_y"),
            "revolute",
            &g,
            &upper,
            [0.0; 3],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            (-1.0, 1.0),
        );
        u.link(&upper, 0.2, [0.15, 0.0, 0.0], &["upper_leg"]);
        u.ball(&format!("leg{k}_knee"), &upper, &lower, [0.28, 0.0, 0.0]);
        u.link(&lower, 0.2, [0.0, 0.0, -0.2], &["shin", "foot"]);
    }
    o.urdf(&u);
}

/// Short, smooth, slightly toe-up foot: 8 rings × 12 = 96 vertices.
fn biped_foot() -> Mesh {
    tube(
        8,
        12,
        |s| {
            let x = -0.04 + 0.16 * s;
            [x, 0.0, -0.03 + 0.03 * (2.0 * s - 1.0).powi(2)]
        },
        |s| {
            let e = (PI * (0.08 + 0.84 * s)).sin().sqrt();
            (0.045 * e, 0.025 * e)
        },
    )
}

/// Biped: floating torso; per leg hip, knee, ankle ball joints
/// (12 joint DOF; 7 links).
fn biped(o: &Out) {
    let name = "biped";
    o.mesh(
        name,
        "torso",
        &box_mesh([-0.1, -0.15, -0.05], [0.1, 0.15, 0.25]),
    );
    o.mesh(
        name,
        "thigh",
        &box_mesh([-0.04, -0.04, -0.42], [0.04, 0.04, 0.04]),
    );
    o.mesh(
        name,
        "shin",
        &box_mesh([-0.035, -0.035, -0.42], [0.035, 0.035, 0.035]),
    );
    o.mesh(name, "foot", &biped_foot().translate([0.0, 0.0, 0.02]));
    let mut u = Urdf::new(name);
    u.empty_link("world");
    u.link("torso", 5.0, [0.0, 0.0, 0.1], &["torso"]);
    u.joint(
        "root",
        "floating",
        "world",
        "torso",
        [0.0, 0.0, 0.95],
        [0.0; 3],
        [0.0; 3],
        (0.0, 0.0),
    );
    for (side, y) in [("left", 0.09), ("right", -0.09)] {
        let (thigh, shin, foot) = (
            format!("{side}_thigh"),
            format!("{side}_shin"),
            format!("{side}_foot"),
        );
        u.link(&thigh, 1.0, [0.0, 0.0, -0.2], &["thigh"]);
        u.ball(&format!("{side}_hip"), "torso", &thigh, [0.0, y, -0.03]);
        u.link(&shin, 0.8, [0.0, 0.0, -0.2], &["shin"]);
        u.ball(&format!("{side}_knee"), &thigh, &shin, [0.0, 0.0, -0.4]);
        u.link(&foot, 0.3, [0.04, 0.0, -0.03], &["foot"]);
        u.ball(&format!("{side}_ankle"), &shin, &foot, [0.0, 0.0, -0.4]);
    }
    o.urdf(&u);
}

/// Single-jaw gripper: one C-shaped link on a floating base, and an X object.
fn single_jaw_gripper(o: &Out) {
    let name = "single_jaw_gripper";
    // C profile in (x, z), opening downward, extruded along y.
    let c = vec![
        [-0.15, -0.12],
        [-0.11, -0.12],
        [-0.11, 0.0],
        [0.11, 0.0],
        [0.11, -0.12],
        [0.15, -0.12],
        [0.15, 0.05],
        [-0.15, 0.05],
    ];
    o.mesh(name, "jaw", &extrude(&c, 0.12, [0, 2, 1]));
    o.object(
        name,
        "x_object",
        &extrude(&plus(0.02, 0.1, PI / 4.0), 0.04, [0, 1, 2]).translate([0.0, 0.0, 0.02]),
    );
    let mut u = Urdf::new(name);
    u.empty_link("world");
    u.link("jaw", 1.0, [0.0, 0.0, 0.0], &["jaw"]);
    u.joint(
        "base",
        "floating",
        "world",
        "jaw",
        [0.0, 0.0, 0.4],
        [0.0; 3],
        [0.0; 3],
        (0.0, 0.0),
    );
    o.urdf(&u);
}

/// Parallel-jaw gripper: palm on a vertical prismatic lift, two jaws on
/// 2-DOF ball joints (5 DOF, 3 links); four objects.
fn parallel_jaw_gripper(o: &Out) {
    let name = "parallel_jaw_gripper";
    o.mesh(
        name,
        "palm",
        &box_mesh([-0.12, -0.04, -0.02], [0.12, 0.04, 0.04]),
    );
    // L-shaped jaw in (x, z): a finger pointing down with an inward tip.
    let l = vec![
        [-0.015, 0.015],
        [-0.015, -0.16],
        [0.03, -0.16],
        [0.03, -0.13],
        [0.015, -0.13],
        [0.015, 0.015],
    ];
    o.mesh(name, "jaw_left", &extrude(&l, 0.06, [0, 2, 1]));
    let r: Vec<[f64; 2]> = l.iter().rev().map(|p| [-p[0], p[1]]).collect();
    o.mesh(name, "jaw_right", &extrude(&r, 0.06, [0, 2, 1]));
    o.object(name, "cube", &box_mesh([-0.03; 3], [0.03; 3]));
    o.object(name, "cylinder", &prism(0.03, 0.08, 24));
    o.object(name, "ball", &ball(0.035, 10, 16));
    o.object(
        name,
        "plus",
        &extrude(&plus(0.012, 0.04, 0.0), 0.05, [0, 1, 2]),
    );
    let mut u = Urdf::new(name);
    u.empty_link("world");
    u.link("palm", 0.5, [0.0; 3], &["palm"]);
    u.joint(
        "lift",
        "prismatic",
        "world",
        "palm",
        [0.0, 0.0, 0.4],
        [0.0; 3],
        [0.0, 0.0, 1.0],
        (-0.3, 0.3),
    );
    u.link("jaw_left", 0.1, [0.0, 0.0, -0.07], &["jaw_left"]);
    u.ball("jaw_left_pivot", "palm", "jaw_left", [-0.09, 0.0, 0.0]);
    u.link("jaw_right", 0.1, [0.0, 0.0, -0.07], &["jaw_right"]);
    u.ball("jaw_right_pivot", "palm", "jaw_right", [0.09, 0.0, 0.0]);
    o.urdf(&u);
}

/// Centreline of a curved phalanx of length `len` and radius `r`: a 36°
/// arc curling toward +x, starting `0.6 r` above the joint.
fn phalanx_centre(len: f64, r: f64, s: f64) -> V3 {
    let arc = PI / 5.0;
    let big = len / arc.sin();
    let a = s * arc;
    [big * (1.0 - a.cos()), 0.0, 0.6 * r - big * a.sin()]
}

/// A curved phalanx: 6 rings × 10 points along [`phalanx_centre`].
fn phalanx(len: f64, r: f64) -> Mesh {
    tube(6, 10, move |s| phalanx_centre(len, r, s), move |_| (r, r))
}

/// Three-fingered hand: three fingers of two phalanges on the hand's base
/// (the palm is the robot base), revolute joints (6 DOF, 6 links).
fn three_finger_hand(o: &Out) {
    let name = "three_finger_hand";
    o.mesh(name, "proximal", &phalanx(0.08, 0.015));
    o.mesh(name, "distal", &phalanx(0.06, 0.013));
    o.object(name, "ball", &ball(0.04, 10, 16));
    o.object(name, "cube", &box_mesh([-0.03; 3], [0.03; 3]));
    o.object(name, "cylinder", &prism(0.025, 0.1, 24));
    let mut u = Urdf::new(name);
    u.empty_link("world");
    for k in 0..3 {
        let a = 2.0 * PI * k as f64 / 3.0;
        let (p, d) = (format!("finger{k}_proximal"), format!("finger{k}_distal"));
        u.link(&p, 0.05, [0.0, 0.0, -0.04], &["proximal"]);
        u.joint(
            &format!("finger{k}_base"),
            "revolute",
            "world",
            &p,
            [0.05 * a.cos(), 0.05 * a.sin(), 0.3],
            [0.0, 0.0, a + PI],
            [0.0, 1.0, 0.0],
            (-0.5, 1.2),
        );
        u.link(&d, 0.03, [0.0, 0.0, -0.03], &["distal"]);
        let tip = phalanx_centre(0.08, 0.015, 0.9);
        u.joint(
            &format!("finger{k}_mid"),
            "revolute",
            &p,
            &d,
            tip,
            [0.0, 0.3, 0.0],
            [0.0, 1.0, 0.0],
            (0.0, 1.5),
        );
    }
    o.urdf(&u);
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("robots"));
    write_all(&dir);
    println!("robots written to {}", dir.display());
}

/// Writes every robot under `dir`. `tests/import_robots.rs` includes this
/// file as a module and calls it in-process (a nested `cargo run` would build
/// the crate again with the root package's feature set).
pub fn write_all(dir: &Path) {
    let o = Out {
        dir: dir.to_path_buf(),
    };
    rotating_chains(&o);
    chains_8link(&o);
    spider(&o);
    biped(&o);
    single_jaw_gripper(&o);
    parallel_jaw_gripper(&o);
    three_finger_hand(&o);
}
