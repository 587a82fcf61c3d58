//! COLLADA (`.dae`) meshes, the format most ROS robot descriptions use for
//! visual and collision geometry.
//!
//! Two readers share the work:
//!
//! - the geometry (`<library_geometries>`: sources, accessors, `<triangles>`,
//!   `<polylist>`, `<polygons>`) is parsed by the `mesh-loader` crate
//!   (openrr's asset reader, pure Rust, over `roxmltree`), one geometry at a
//!   time in its own coordinates;
//! - the scene graph and the unit are applied here ([`scene`]): each
//!   `<instance_geometry>` is placed at `s · M_root ⋯ M_node · p`, with `s`
//!   the `<asset><unit meter=…>`.
//!
//! Why not let mesh-loader place the geometry too: version 0.1.13 composes
//! nested nodes child-before-parent (a `<translate>` in a parent node and a
//! `<rotate>` in its child come out rotated about the wrong point), applies
//! the unit inside the root node (a translated node's offset is not
//! scaled), and keeps one instance per geometry. Those cases are tests
//! below and in `tests/import_collada.rs`.
//!
pub mod scene;

use super::guard;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::path::Path;

/// Triangles of a COLLADA file, in metres, before welding, and the file's
/// declared `<up_axis>` when it is not `Z_UP`.
pub struct ColladaMesh {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
    pub up_axis: Option<String>,
}

/// Reads every mesh instanced in the file's scene into one triangle soup.
///
/// Errors (as text, the caller adds file and element): unreadable file, not
/// XML / not COLLADA, a reader failure on malformed content, non-finite
/// coordinates.
pub fn read_collada(path: &Path) -> Result<ColladaMesh, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let text = std::str::from_utf8(&bytes).map_err(|e| format!("not UTF-8 text: {e}"))?;
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not well-formed XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err(format!(
            "the root element is <{}>, not <COLLADA>",
            root.tag_name().name()
        ));
    }
    let asset = read_asset(root)?;
    let geometry_ids: Vec<&str> = root
        .children()
        .filter(|n| n.has_tag_name("library_geometries"))
        .flat_map(|l| l.children().filter(|n| n.has_tag_name("geometry")))
        .filter_map(|g| g.attribute("id"))
        .collect();
    // Without a visual scene, every geometry once, where it is.
    let instances = scene::instances(root)?.unwrap_or_else(|| {
        geometry_ids
            .iter()
            .map(|id| scene::Instance {
                geometry: id.to_string(),
                transform: nalgebra::Matrix4::identity(),
            })
            .collect()
    });
    let local = local_geometries(text, root, &geometry_ids)?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for inst in &instances {
        let Some(g) = local.get(inst.geometry.as_str()) else {
            return Err(format!(
                "<instance_geometry url=\"#{}\"> names no mesh geometry",
                inst.geometry
            ));
        };
        let m = nalgebra::Matrix4::new_nonuniform_scaling(&Vector3::repeat(asset.meter))
            * inst.transform;
        let base = vertices.len();
        vertices.extend(g.vertices.iter().map(|p| {
            let q = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            m.transform_point(&q).coords
        }));
        for f in &g.faces {
            let t = f.map(|i| i as usize + base);
            if t.iter().any(|&i| i >= vertices.len()) {
                return Err(format!(
                    "geometry \"{}\": face index out of range",
                    inst.geometry
                ));
            }
            triangles.push(t);
        }
        if vertices.len() > super::limits::MAX_MESH_VERTICES {
            return Err(format!(
                "more than {} vertices after placing the scene's instances",
                super::limits::MAX_MESH_VERTICES
            ));
        }
    }
    if vertices.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(
            "non-finite vertex coordinates (after the file's unit and node transforms)".into(),
        );
    }
    Ok(ColladaMesh {
        vertices,
        triangles,
        up_axis: asset.up_axis,
    })
}

/// Each geometry's triangles in its own coordinates (file units), by id.
///
/// mesh-loader places only instanced geometries, so it is handed the file
/// with `<library_visual_scenes>` replaced by one untransformed node per
/// geometry and the unit set to 1.
fn local_geometries(
    text: &str,
    root: roxmltree::Node,
    ids: &[&str],
) -> Result<HashMap<String, mesh_loader::Mesh>, String> {
    let escape = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('"', "&quot;")
    };
    let mut flat = String::from("<library_visual_scenes><visual_scene id=\"sdrs-flat\">");
    for id in ids {
        flat += &format!("<node><instance_geometry url=\"#{}\"/></node>", escape(id));
    }
    flat += "</visual_scene></library_visual_scenes>";
    // Top-level elements only (their ranges are disjoint; a nested copy
    // inside one of them goes with it): every <library_visual_scenes>, and
    // the <unit> of the document's <asset>.
    let mut edits: Vec<(std::ops::Range<usize>, String)> = root
        .children()
        .filter(|n| n.has_tag_name("library_visual_scenes"))
        .map(|n| (n.range(), String::new()))
        .collect();
    if let Some(unit) = root
        .children()
        .find(|n| n.has_tag_name("asset"))
        .and_then(|a| a.children().find(|n| n.has_tag_name("unit")))
    {
        edits.push((unit.range(), "<unit meter=\"1\"/>".to_string()));
    }
    // The flat scene goes right after <library_geometries>, inside the
    // root element; without one there is nothing to read.
    let Some(insert_at) = root
        .children()
        .find(|n| n.has_tag_name("library_geometries"))
        .map(|n| n.range().end)
    else {
        return Ok(HashMap::new());
    };
    edits.push((insert_at..insert_at, flat));
    // From the end of the text backwards, so earlier ranges stay valid; at
    // equal starts the removal (longer range) goes before the insertion.
    edits.sort_by_key(|(r, _)| std::cmp::Reverse((r.start, r.end)));
    let mut s = text.to_string();
    for (r, with) in edits {
        s.replace_range(r, &with);
    }
    let scene = guard::quietly(|| mesh_loader::collada::from_str(&s))
        .map_err(|panic| format!("malformed COLLADA ({panic})"))?
        .map_err(|e| format!("not a readable COLLADA file: {e}"))?;
    Ok(scene
        .meshes
        .into_iter()
        .map(|m| (m.name.clone(), m))
        .collect())
}

/// What `<COLLADA><asset>` says about units and axes.
struct Asset {
    /// Metres per file unit (`<unit meter=…>`; 1 when absent).
    meter: f64,
    /// `<up_axis>` when present and not `Z_UP`.
    up_axis: Option<String>,
}

fn read_asset(root: roxmltree::Node) -> Result<Asset, String> {
    let asset = root.children().find(|n| n.has_tag_name("asset"));
    let child = |name: &str| asset.and_then(|a| a.children().find(|n| n.has_tag_name(name)));
    let meter = match child("unit").and_then(|u| u.attribute("meter")) {
        Some(m) => {
            let meter: f64 = m
                .trim()
                .parse()
                .map_err(|_| format!("<unit meter=\"{m}\">: not a number"))?;
            if !(meter.is_finite() && meter > 0.0) {
                return Err(format!(
                    "<unit meter=\"{m}\">: must be a positive finite number"
                ));
            }
            meter
        }
        None => 1.0,
    };
    let up_axis = child("up_axis")
        .and_then(|n| n.text())
        .map(|t| t.trim().to_string())
        .filter(|t| t != "Z_UP");
    Ok(Asset { meter, up_axis })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube (8 positions, 12 triangles) under a node that scales by
    /// 2 and translates by (1, 0, 0), in a file whose unit is centimetres.
    fn cube_dae(unit: &str, up: &str) -> String {
        let p = "0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1";
        let tris = "0 2 1 0 3 2 4 5 6 4 6 7 0 1 5 0 5 4 1 2 6 1 6 5 2 3 7 2 7 6 3 0 4 3 4 7";
        format!(
            r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
 <asset><unit meter="{unit}" name="u"/><up_axis>{up}</up_axis></asset>
 <library_geometries><geometry id="g"><mesh>
  <source id="g-pos"><float_array id="g-pos-a" count="24">{p}</float_array>
   <technique_common><accessor source="#g-pos-a" count="8" stride="3">
    <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
   </accessor></technique_common></source>
  <vertices id="g-v"><input semantic="POSITION" source="#g-pos"/></vertices>
  <triangles count="12"><input semantic="VERTEX" source="#g-v" offset="0"/><p>{tris}</p></triangles>
 </mesh></geometry></library_geometries>
 <library_visual_scenes><visual_scene id="s"><node id="n">
  <translate>1 0 0</translate><scale>2 2 2</scale>
  <instance_geometry url="#g"/>
 </node></visual_scene></library_visual_scenes>
 <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##
        )
    }

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("sdrs-collada-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn unit_and_node_transform_are_applied() {
        let p = write("cube.dae", &cube_dae("0.01", "Z_UP"));
        let m = read_collada(&p).unwrap();
        assert_eq!(m.triangles.len(), 12);
        assert!(m.up_axis.is_none());
        // node: x ↦ 2x + (1,0,0), then centimetres → metres.
        let (lo, hi) = m.vertices.iter().fold(
            (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN)),
            |(lo, hi), v| (lo.inf(v), hi.sup(v)),
        );
        for (got, want) in lo.iter().zip([0.01, 0.0, 0.0]) {
            assert!((got - want).abs() < 1e-7, "min {lo:?}");
        }
        for (got, want) in hi.iter().zip([0.03, 0.02, 0.02]) {
            assert!((got - want).abs() < 1e-7, "max {hi:?}");
        }
    }

    #[test]
    fn y_up_is_reported_not_applied() {
        let p = write("cube_y.dae", &cube_dae("1", "Y_UP"));
        let m = read_collada(&p).unwrap();
        assert_eq!(m.up_axis.as_deref(), Some("Y_UP"));
        let zmax = m.vertices.iter().map(|v| v.z).fold(f64::MIN, f64::max);
        assert!((zmax - 2.0).abs() < 1e-7);
    }

    #[test]
    fn malformed_files_are_errors_not_panics() {
        let good = cube_dae("1", "Z_UP");
        let cases = [
            ("not_xml.dae", "this is not xml".to_string(), "XML"),
            (
                "bad_index.dae",
                good.replace("3 4 7</p>", "3 4 70</p>"),
                "malformed",
            ),
            (
                "bad_unit.dae",
                good.replace("meter=\"1\"", "meter=\"x\""),
                "<unit",
            ),
            (
                "zero_unit.dae",
                good.replace("meter=\"1\"", "meter=\"0\""),
                "positive",
            ),
            (
                "nan.dae",
                good.replace("1 1 1 0 1 1", "nan 1 1 0 1 1"),
                "non-finite",
            ),
            ("truncated.dae", good[..good.len() / 2].to_string(), "XML"),
            (
                "not_collada.dae",
                "<robot name=\"r\"/>".to_string(),
                "<COLLADA>",
            ),
        ];
        for (name, text, why) in cases {
            let p = write(name, &text);
            match read_collada(&p) {
                Ok(_) => panic!("{name} was accepted"),
                Err(e) => assert!(e.contains(why), "{name}: {e}"),
            }
        }
    }
}
