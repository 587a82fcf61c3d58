//! The COLLADA scene graph: which geometry is placed where.
//!
//! A `<visual_scene>` is a tree of `<node>`s. Each node's local transform is
//! the product of its transform elements in document order,
//! `M_node = E_1 · E_2 ⋯ E_k` (`<translate>`, `<rotate>` axis + angle in
//! degrees, `<scale>`, `<matrix>` in row-major order), and a geometry
//! instanced in a node sits at `M_root ⋯ M_parent · M_node · p` — parents
//! left of children. `<instance_node>` places a node of
//! `<library_nodes>` as a child. The file's scene is the visual scene named
//! by `<scene><instance_visual_scene url>`, or the first one.

use nalgebra::{Matrix4, Rotation3, Unit, Vector3};
use roxmltree::Node;

/// Most nested `<node>`/`<instance_node>` levels followed.
pub const MAX_DEPTH: usize = 64;
/// Most geometry instances placed (an `<instance_node>` DAG can multiply
/// them).
pub const MAX_INSTANCES: usize = 100_000;

/// One `<instance_geometry>`: the geometry id and its transform in the
/// file's frame (file units).
#[derive(Clone, Debug)]
pub struct Instance {
    pub geometry: String,
    pub transform: Matrix4<f64>,
}

/// Every geometry instance of the file's visual scene; `None` when the file
/// has no visual scene at all.
pub fn instances(root: Node) -> Result<Option<Vec<Instance>>, String> {
    let lib = |name: &str| root.children().find(|n| n.has_tag_name(name));
    let Some(scenes) = lib("library_visual_scenes") else {
        return Ok(None);
    };
    let wanted = lib("scene")
        .and_then(|s| {
            s.children()
                .find(|n| n.has_tag_name("instance_visual_scene"))
        })
        .and_then(|i| i.attribute("url"))
        .map(|u| u.trim_start_matches('#'));
    let all: Vec<Node> = scenes
        .children()
        .filter(|n| n.has_tag_name("visual_scene"))
        .collect();
    let scene = match wanted {
        Some(id) => all.iter().find(|s| s.attribute("id") == Some(id)).copied(),
        None => all.first().copied(),
    };
    let Some(scene) = scene else {
        return match wanted {
            Some(id) => Err(format!(
                "<instance_visual_scene url=\"#{id}\"> names no <visual_scene>"
            )),
            None => Ok(None),
        };
    };
    let library_nodes: Vec<Node> = root
        .children()
        .filter(|n| n.has_tag_name("library_nodes"))
        .flat_map(|l| l.children().filter(|n| n.has_tag_name("node")))
        .collect();
    let mut out = Vec::new();
    // Depth-first over (node, parent transform, depth).
    let mut stack: Vec<(Node, Matrix4<f64>, usize)> = scene
        .children()
        .filter(|n| n.has_tag_name("node"))
        .map(|n| (n, Matrix4::identity(), 1))
        .collect();
    stack.reverse();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err(format!(
                "nodes nested deeper than {MAX_DEPTH} levels (a cycle of <instance_node>?)"
            ));
        }
        let m = parent * local_transform(node)?;
        let mut children = Vec::new();
        for c in node.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "instance_geometry" => {
                    let url = c.attribute("url").unwrap_or("");
                    out.push(Instance {
                        geometry: url.trim_start_matches('#').to_string(),
                        transform: m,
                    });
                    if out.len() > MAX_INSTANCES {
                        return Err(format!("more than {MAX_INSTANCES} geometry instances"));
                    }
                }
                "node" => children.push(c),
                "instance_node" => {
                    let id = c.attribute("url").unwrap_or("").trim_start_matches('#');
                    let target = library_nodes
                        .iter()
                        .find(|n| n.attribute("id") == Some(id))
                        .ok_or_else(|| {
                            format!(
                                "<instance_node url=\"#{id}\"> names no node of <library_nodes>"
                            )
                        })?;
                    children.push(*target);
                }
                _ => {}
            }
        }
        for c in children.into_iter().rev() {
            stack.push((c, m, depth + 1));
        }
    }
    Ok(Some(out))
}

fn numbers(e: Node, n: usize) -> Result<Vec<f64>, String> {
    let text = e.text().unwrap_or("");
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            format!(
                "<{}>{}</{}>: not numbers",
                e.tag_name().name(),
                text.trim(),
                e.tag_name().name()
            )
        })?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "<{}> needs {n} finite numbers, got \"{}\"",
            e.tag_name().name(),
            text.trim()
        ));
    }
    Ok(v)
}

/// `M_node = E_1 ⋯ E_k` over the node's transform elements.
fn local_transform(node: Node) -> Result<Matrix4<f64>, String> {
    let name = node
        .attribute("id")
        .or(node.attribute("name"))
        .unwrap_or("?");
    let mut m = Matrix4::identity();
    for e in node.children().filter(Node::is_element) {
        let step = match e.tag_name().name() {
            "translate" => {
                let v = numbers(e, 3)?;
                Matrix4::new_translation(&Vector3::new(v[0], v[1], v[2]))
            }
            "scale" => {
                let v = numbers(e, 3)?;
                Matrix4::new_nonuniform_scaling(&Vector3::new(v[0], v[1], v[2]))
            }
            "rotate" => {
                let v = numbers(e, 4)?;
                let axis = Unit::try_new(Vector3::new(v[0], v[1], v[2]), 1e-12)
                    .ok_or_else(|| format!("node \"{name}\": <rotate> with a zero axis"))?;
                Rotation3::from_axis_angle(&axis, v[3].to_radians()).to_homogeneous()
            }
            "matrix" => Matrix4::from_row_slice(&numbers(e, 16)?),
            t @ ("lookat" | "skew") => {
                return Err(format!(
                    "node \"{name}\": <{t}> transforms are not supported"
                ));
            }
            _ => continue,
        };
        m *= step;
    }
    Ok(m)
}
