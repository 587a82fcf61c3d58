//! glTF 2.0 binary (`.glb`) of a [`Playback`]: the animated robot for
//! Blender or any glTF viewer.
//!
//! Layout: a root node `sdrs` turns the simulator's z-up world into glTF's
//! y-up one (rotation `−90°` about x: `(x, y, z) ↦ (x, z, −y)`); its
//! children are one node per link (in model order, named `robot/link`),
//! each with a mesh of its hulls (one primitive per hull: the convex hull's
//! triangles in the link frame; no normals, so viewers shade them flat, as
//! the glTF specification requires) in the link's robot colour. One
//! animation `trajectory` holds, per link node, a translation and a
//! rotation channel (linear interpolation) sampled at the recorded times,
//! shifted to start at 0 (s), so its duration is the trajectory's.
//! Quaternions keep a consistent sign along time (`q` and `−q` are the
//! same rotation; interpolating between opposite signs would spin).
//!
//! Binary layout: one buffer; every buffer view starts 4-byte aligned;
//! floats are little-endian `f32`, indices `u32`.

use super::playback::{Playback, hull_mesh, pose_trs};
use serde_json::{Value, json};

/// RGB in `[0, 1]` of robot number `k` (a fixed palette; environment
/// links are grey).
pub fn robot_color(k: usize, environment: bool) -> [f64; 3] {
    const PALETTE: [[f64; 3]; 6] = [
        [0.90, 0.45, 0.20],
        [0.25, 0.55, 0.85],
        [0.35, 0.70, 0.35],
        [0.80, 0.30, 0.55],
        [0.85, 0.75, 0.25],
        [0.50, 0.40, 0.80],
    ];
    if environment {
        [0.78, 0.78, 0.78]
    } else {
        PALETTE[k % PALETTE.len()]
    }
}

/// Binary chunk under construction, with the buffer views and accessors
/// pointing into it.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends a view of `data` and an accessor over it; returns the accessor index.
    fn push(
        &mut self,
        data: &[u8],
        component: u32,
        kind: &str,
        count: usize,
        minmax: Option<(Vec<f64>, Vec<f64>)>,
        target: Option<u32>,
    ) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut view =
            json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.bytes.extend_from_slice(data);
        self.views.push(view);
        let mut acc = json!({
            "bufferView": self.views.len() - 1,
            "componentType": component,
            "count": count,
            "type": kind,
        });
        if let Some((lo, hi)) = minmax {
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }
}

const FLOAT: u32 = 5126;
const UINT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

fn f32_bytes(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter()
        .flat_map(|x| (x as f32).to_le_bytes())
        .collect()
}

/// Component-wise min and max of `f32`-rounded vectors (glTF requires the
/// accessor bounds to match the stored values).
fn bounds<const N: usize>(v: &[[f64; N]]) -> (Vec<f64>, Vec<f64>) {
    let mut lo = vec![f64::INFINITY; N];
    let mut hi = vec![f64::NEG_INFINITY; N];
    for x in v {
        for k in 0..N {
            let y = x[k] as f32 as f64;
            lo[k] = lo[k].min(y);
            hi[k] = hi[k].max(y);
        }
    }
    (lo, hi)
}

/// The `.glb` bytes of `p` (see the module docs).
pub fn glb(p: &Playback) -> Vec<u8> {
    let mut bin = Bin::default();
    let (robots, materials) = materials(p);
    let (meshes, mut nodes) = link_nodes(p, &robots, &mut bin);
    let n = nodes.len();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    nodes.push(json!({"name": "sdrs", "rotation": [-h, 0.0, 0.0, h], "children": (0..n).collect::<Vec<_>>()}));
    let animation = (!p.times.is_empty() && n > 0).then(|| animation(p, n, &mut bin));
    while !bin.bytes.len().is_multiple_of(4) {
        bin.bytes.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("sdrs ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [n]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": bin.bytes.len()}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    if let Some(a) = animation {
        doc["animations"] = json!([a]);
    }
    container(&doc, &bin.bytes)
}

/// The robots in order of first appearance, and one material per robot
/// (its colour; the environment's grey).
fn materials(p: &Playback) -> (Vec<&str>, Vec<serde_json::Value>) {
    let mut robots: Vec<&str> = Vec::new();
    let mut materials = Vec::new();
    for l in &p.links {
        if !robots.contains(&l.robot.as_str()) {
            robots.push(&l.robot);
            let env = l.robot == crate::scene::environment::ENVIRONMENT;
            let [r, g, b] = robot_color(robots.len() - 1, env);
            materials.push(json!({
                "name": l.robot,
                "pbrMetallicRoughness": {"baseColorFactor": [r, g, b, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
            }));
        }
    }
    (robots, materials)
}

/// One node per link (at its first pose), with a mesh of one primitive per
/// hull when it has hulls; the vertex and index data into `bin`.
fn link_nodes(
    p: &Playback,
    robots: &[&str],
    bin: &mut Bin,
) -> (Vec<serde_json::Value>, Vec<serde_json::Value>) {
    let (mut meshes, mut nodes) = (Vec::new(), Vec::new());
    let first = p.poses.first();
    for (i, l) in p.links.iter().enumerate() {
        let material = robots.iter().position(|r| *r == l.robot).unwrap_or(0);
        let mut prims = Vec::new();
        for h in &l.hulls {
            let (v, t) = hull_mesh(h);
            if t.is_empty() {
                continue;
            }
            let pos = bin.push(
                &f32_bytes(v.iter().flatten().copied()),
                FLOAT,
                "VEC3",
                v.len(),
                Some(bounds(&v)),
                Some(ARRAY_BUFFER),
            );
            let idx: Vec<u8> = t.iter().flatten().flat_map(|k| k.to_le_bytes()).collect();
            let ind = bin.push(
                &idx,
                UINT,
                "SCALAR",
                3 * t.len(),
                None,
                Some(ELEMENT_ARRAY_BUFFER),
            );
            prims.push(
                json!({"attributes": {"POSITION": pos}, "indices": ind, "material": material}),
            );
        }
        let mut node = json!({"name": format!("{}/{}", l.robot, l.name)});
        if !prims.is_empty() {
            meshes.push(json!({"name": format!("{}/{}", l.robot, l.name), "primitives": prims}));
            node["mesh"] = json!(meshes.len() - 1);
        }
        if let Some(a) = first.map(|f| &f[i]) {
            let (t, q) = pose_trs(a);
            node["translation"] = json!(t);
            node["rotation"] = json!(q);
        }
        nodes.push(node);
    }
    (meshes, nodes)
}

/// The trajectory as one animation: per link node, a translation and a
/// rotation channel sampled at the playback's times (from 0), each
/// quaternion's sign chosen next to the previous one (linear interpolation
/// takes the short way).
fn animation(p: &Playback, n: usize, bin: &mut Bin) -> serde_json::Value {
    let t0 = p.times[0];
    let times: Vec<[f64; 1]> = p.times.iter().map(|t| [t - t0]).collect();
    let input = bin.push(
        &f32_bytes(times.iter().map(|t| t[0])),
        FLOAT,
        "SCALAR",
        times.len(),
        Some(bounds(&times)),
        None,
    );
    let (mut samplers, mut channels) = (Vec::new(), Vec::new());
    for i in 0..n {
        let mut tr = Vec::with_capacity(p.times.len());
        let mut rot: Vec<[f64; 4]> = Vec::with_capacity(p.times.len());
        for step in &p.poses {
            let (t, mut q) = pose_trs(&step[i]);
            if let Some(prev) = rot.last()
                && prev.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>() < 0.0
            {
                q = q.map(|x| -x);
            }
            tr.push(t);
            rot.push(q);
        }
        for (path, data, kind) in [
            (
                "translation",
                f32_bytes(tr.iter().flatten().copied()),
                "VEC3",
            ),
            ("rotation", f32_bytes(rot.iter().flatten().copied()), "VEC4"),
        ] {
            let out = bin.push(&data, FLOAT, kind, p.times.len(), None, None);
            samplers.push(json!({"input": input, "output": out, "interpolation": "LINEAR"}));
            channels
                .push(json!({"sampler": samplers.len() - 1, "target": {"node": i, "path": path}}));
        }
    }
    json!({"name": "trajectory", "samplers": samplers, "channels": channels})
}

/// The binary glTF container: the 12-byte header, the JSON chunk (padded
/// with spaces to 4 bytes) and the BIN chunk (`bin`, already 4-aligned).
fn container(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut js = serde_json::to_vec(doc).expect("plain data serializes");
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::LinkExport;

    #[test]
    fn glb_header_chunks_and_animation_bounds() {
        let cube: Vec<[f64; 3]> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let mut a = crate::math::pose_identity();
        let mut poses = vec![vec![a]];
        a[(2, 3)] = 1.5;
        poses.push(vec![a]);
        let p = Playback {
            links: vec![LinkExport {
                robot: "r".into(),
                name: "l".into(),
                hulls: vec![cube],
            }],
            times: vec![0.25, 0.75],
            poses,
            contacts: vec![],
        };
        let b = glb(&p);
        assert_eq!(&b[..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes(b[8..12].try_into().unwrap()) as usize,
            b.len()
        );
        let jl = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
        assert_eq!(&b[16..20], b"JSON");
        let doc: Value = serde_json::from_slice(&b[20..20 + jl]).unwrap();
        assert_eq!(&b[20 + jl + 4..20 + jl + 8], b"BIN\0");
        assert_eq!(doc["nodes"].as_array().unwrap().len(), 2);
        let input = doc["animations"][0]["samplers"][0]["input"]
            .as_u64()
            .unwrap() as usize;
        assert_eq!(doc["accessors"][input]["max"][0], json!(0.5));
        // 12 triangles of a cube, 8 vertices.
        let prim = &doc["meshes"][0]["primitives"][0];
        let ind = prim["indices"].as_u64().unwrap() as usize;
        assert_eq!(doc["accessors"][ind]["count"], json!(36));
        let pos = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
        assert_eq!(doc["accessors"][pos]["max"], json!([1.0, 1.0, 1.0]));
    }
}
