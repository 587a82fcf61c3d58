//! The self-contained viewer HTML: the vendored three.js
//! (`cli/assets/three/`, see `tools/setup/vendor_three.sh`) and OrbitControls as
//! `data:` URLs in an import map, the viewer module (`cli/assets/viewer.js`)
//! inline, and the run as JSON in `<script id="sdrs-data">`. Nothing is
//! fetched at view time.
//!
//! Data layout (`DATA`): `{title, kind, scenes, iterations, iteration_scene}`;
//! each scene is `{label, offset: [x, y, z] (m, world), steps, times, poses,
//! links, contacts?}` with base64 little-endian arrays: `times` `f32[steps]`
//! (s), `poses` `f32[steps × links × 7]` = translation (m) and unit
//! quaternion `(x, y, z, w)` per link per step; each link is `{robot, name,
//! env, color: [r, g, b] ∈ [0, 1], hulls: [{p: f32[3 n] (link frame, m),
//! i: u32[3 m] (triangles)}]}`; `contacts` is `{start: u32[steps + 1],
//! planes: f32[7 × pairs]}` where the pairs of step `k` are
//! `start[k]..start[k+1]` and each pair is its plane's patch: centre `c`
//! (the midpoint of the two hulls' centroids projected onto the plane, m),
//! unit normal `n̂`, and side length (m, the smaller hull's diameter).
//! `iterations` (optimize results) is `[{iteration, loss, poses: [[t, q] per link], links: {index:
//! [hull]}}]`: the designed links' hulls at every recorded iteration, shown
//! on scene `iteration_scene`. Positions and poses are `f32`: ~0.1 µm at
//! 1 m, far below anything visible.

use base64::Engine;
use base64::engine::general_purpose::STANDARD as B64;
use sdrs::output::gltf::robot_color;
use sdrs::output::playback::{Playback, centroid, hull_mesh, pose_trs};
use sdrs::scene::environment::ENVIRONMENT;
use serde_json::{Value, json};

const THREE: &str = include_str!("../../assets/three/three.module.min.js");
const ORBIT: &str = include_str!("../../assets/three/OrbitControls.js");
const VIEWER: &str = include_str!("../../assets/viewer.js");

/// First line of every viewer file (`sdrs view` overwrites only files that start with it).
pub const MARKER: &str = "<!doctype html><!-- written by sdrs view -->";

/// A scene to show: a playback, its label and where to place it.
pub struct SceneData<'a> {
    pub label: String,
    pub playback: &'a Playback,
    pub offset: [f64; 3],
}

fn f32_b64(v: impl IntoIterator<Item = f64>) -> String {
    let bytes: Vec<u8> = v
        .into_iter()
        .flat_map(|x| (x as f32).to_le_bytes())
        .collect();
    B64.encode(bytes)
}

fn u32_b64(v: impl IntoIterator<Item = u32>) -> String {
    let bytes: Vec<u8> = v.into_iter().flat_map(|x| x.to_le_bytes()).collect();
    B64.encode(bytes)
}

/// `{p, i}` of one hull (see the module docs).
pub fn hull_json(points: &[[f64; 3]]) -> Value {
    let (v, t) = hull_mesh(points);
    json!({
        "p": f32_b64(v.iter().flatten().copied()),
        "i": u32_b64(t.iter().flatten().copied()),
    })
}

fn scene_json(s: &SceneData) -> Value {
    let p = s.playback;
    let mut robots: Vec<&str> = Vec::new();
    let links: Vec<Value> = p
        .links
        .iter()
        .map(|l| {
            if !robots.contains(&l.robot.as_str()) {
                robots.push(&l.robot);
            }
            let env = l.robot == ENVIRONMENT;
            json!({
                "robot": l.robot,
                "name": l.name,
                "env": env,
                "color": robot_color(robots.len() - 1, env),
                "hulls": l.hulls.iter().map(|h| hull_json(h)).collect::<Vec<_>>(),
            })
        })
        .collect();
    let poses = p.poses.iter().flatten().flat_map(|a| {
        let (t, q) = pose_trs(a);
        t.into_iter().chain(q)
    });
    let mut out = json!({
        "label": s.label,
        "offset": s.offset,
        "steps": p.times.len(),
        "times": f32_b64(p.times.iter().copied()),
        "poses": f32_b64(poses),
        "links": links,
    });
    if !p.contacts.is_empty() {
        out["contacts"] = contacts_json(p);
    }
    out
}

/// Plane patches per step (see the module docs).
fn contacts_json(p: &Playback) -> Value {
    let mut start = vec![0u32; p.times.len() + 1];
    let mut planes = Vec::with_capacity(7 * p.contacts.len());
    let mut recs: Vec<_> = p.contacts.iter().collect();
    recs.sort_by_key(|r| r.step);
    for r in &recs {
        start[r.step + 1] += 1;
        let world_centroid = |(l, h): (usize, usize)| {
            let a = &p.poses[r.step][l];
            let c = centroid(&p.links[l].hulls[h]);
            a.fixed_view::<3, 3>(0, 0) * c + a.column(3)
        };
        let radius = |(l, h): (usize, usize)| {
            let c = centroid(&p.links[l].hulls[h]);
            p.links[l].hulls[h]
                .iter()
                .map(|x| (nalgebra::Vector3::from(*x) - c).norm())
                .fold(0.0, f64::max)
        };
        let n = nalgebra::Vector3::from(r.normal);
        let m = 0.5 * (world_centroid(r.a) + world_centroid(r.b));
        let c = m - (n.dot(&m) + r.offset) * n;
        let size = 2.0 * radius(r.a).min(radius(r.b));
        planes.extend([c.x, c.y, c.z, n.x, n.y, n.z, size]);
    }
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    json!({"start": u32_b64(start), "planes": f32_b64(planes)})
}

fn data_url(js: &str) -> String {
    format!("data:text/javascript;base64,{}", B64.encode(js))
}

/// Escapes `</` so that JSON cannot close its `<script>` element.
fn script_safe(s: &str) -> String {
    s.replace("</", "<\\/")
}

/// The HTML document (see the module docs).
pub fn html(
    title: &str,
    kind: &str,
    scenes: &[SceneData],
    iterations: Vec<Value>,
    iteration_scene: usize,
) -> String {
    let data = json!({
        "title": title,
        "kind": kind,
        "scenes": scenes.iter().map(scene_json).collect::<Vec<_>>(),
        "iterations": iterations,
        "iteration_scene": iteration_scene,
    });
    let imports = json!({"imports": {
        "three": data_url(THREE),
        "three/addons/controls/OrbitControls.js": data_url(ORBIT),
    }});
    let title_html = title
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    format!(
        r#"{MARKER}
<html lang="en"><head><meta charset="utf-8"><title>{title_html}</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
html, body {{ margin: 0; height: 100%; font: 13px sans-serif; color: #222; }}
body {{ display: flex; flex-direction: column; }}
#bar {{ display: flex; flex-wrap: wrap; gap: 10px; align-items: center; padding: 6px 10px; background: #e8eaee; border-bottom: 1px solid #ccc; }}
#bar input[type=range] {{ flex: 1; min-width: 200px; }}
#view {{ flex: 1; min-height: 200px; position: relative; }}
#view canvas {{ width: 100%; height: 100%; display: block; }}
#labels {{ position: absolute; top: 6px; left: 10px; pointer-events: none; }}
#errors {{ color: #b00; white-space: pre-wrap; }}
</style>
<script>
// Errors of any script land in the page (tests read them from the DOM).
window.sdrsErrors = [];
function sdrsError(m) {{
  window.sdrsErrors.push(String(m));
  document.documentElement.dataset.errors = window.sdrsErrors.length;
  const e = document.getElementById('errors'); if (e) e.textContent = window.sdrsErrors.join('\n');
}}
window.addEventListener('error', (e) => sdrsError(e.message));
window.addEventListener('unhandledrejection', (e) => sdrsError(e.reason));
const sdrsConsoleError = console.error.bind(console);
console.error = (...a) => {{ sdrsError(a.join(' ')); sdrsConsoleError(...a); }};
</script>
<script type="importmap">{imports}</script>
</head><body data-errors="0">
<div id="bar">
<b>{title_html}</b>
<button id="play">play</button>
<label>speed <select id="speed"><option>0.25</option><option>0.5</option><option selected>1</option><option>2</option><option>4</option></select></label>
<input id="time" type="range" min="0" max="0" value="0" step="1" aria-label="time">
<span id="tlabel"></span>
<label><input id="planes" type="checkbox"> contact planes</label>
<label><input id="trails" type="checkbox"> trails</label>
<span id="iterBox" hidden><input id="iter" type="range" min="0" max="0" step="1" aria-label="iteration"> <span id="iterLabel"></span></span>
</div>
<div id="view"><div id="labels">{labels}</div></div>
<div id="errors"></div>
<script type="application/json" id="sdrs-data">{data}</script>
<script type="module" onerror="sdrsError('the viewer module failed to load')">
{viewer}
</script>
</body></html>
"#,
        imports = script_safe(&imports.to_string()),
        labels = scenes
            .iter()
            .map(|s| s.label.replace('<', "&lt;"))
            .collect::<Vec<_>>()
            .join(" &nbsp;|&nbsp; "),
        data = script_safe(&data.to_string()),
        viewer = VIEWER,
    )
}
