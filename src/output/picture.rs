//! SVG pictures of convex hulls: an orthographic projection of each hull's
//! faces, drawn back to front (painter's order) with Lambert shading —
//! enough to compare shapes (e.g. initial vs optimized feet) until a viewer
//! exists.
//!
//! Camera: view direction `v = −(cos e cos a, cos e sin a, sin e)` for
//! azimuth `a` and elevation `e` (the camera sits at azimuth `a`, elevation
//! `e`, looking at the origin; world `+z` is up on the page). Screen axes:
//! `x̂ = (−sin a, cos a, 0)`, `ŷ = (−sin e cos a, −sin e sin a, cos e)`.
//! A face with outward normal `n` is drawn iff `n·v < 0` (front-facing)
//! with fill `base · (ambient + (1 − ambient) max(0, n·ℓ))`, `ℓ` the unit
//! light direction; faces are sorted by the depth of their centroid.

use nalgebra::Vector3;
use std::fmt::Write;

/// One panel: a set of hulls (point clouds; their convex hulls are drawn)
/// in one coordinate frame, with a title and a fill colour.
#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub hulls: Vec<Vec<Vector3<f64>>>,
    /// RGB fill of a fully lit face.
    pub color: [u8; 3],
}

/// Rendering options (defaults documented on each field).
#[derive(Clone, Debug)]
pub struct PictureOptions {
    /// Camera azimuth (degrees). Default 35.
    pub azimuth_deg: f64,
    /// Camera elevation (degrees). Default 25.
    pub elevation_deg: f64,
    /// Panels per row. Default 2.
    pub columns: usize,
    /// Panel size in px. Default 280.
    pub panel_px: f64,
    /// Light direction (world, need not be unit). Default (0.3, −0.5, 1).
    pub light: Vector3<f64>,
    /// Ambient fraction of the shading. Default 0.35.
    pub ambient: f64,
    /// One scale (m per px) for all panels of a row, so that shapes in a
    /// row compare at the same size. Default true.
    pub shared_scale_per_row: bool,
}

impl Default for PictureOptions {
    fn default() -> Self {
        PictureOptions {
            azimuth_deg: 35.0,
            elevation_deg: 25.0,
            columns: 2,
            panel_px: 280.0,
            light: Vector3::new(0.3, -0.5, 1.0),
            ambient: 0.35,
            shared_scale_per_row: true,
        }
    }
}

/// A projected, shaded triangle.
struct Face {
    depth: f64,
    pts: [(f64, f64); 3],
    fill: [u8; 3],
}

/// Renders `panels` into one SVG document (see the module docs).
pub fn render_hulls_svg(panels: &[Panel], o: &PictureOptions) -> String {
    let (a, e) = (o.azimuth_deg.to_radians(), o.elevation_deg.to_radians());
    let view = -Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
    let sx = Vector3::new(-a.sin(), a.cos(), 0.0);
    let sy = Vector3::new(-e.sin() * a.cos(), -e.sin() * a.sin(), e.cos());
    let light = if o.light.norm() > 0.0 {
        o.light.normalize()
    } else {
        Vector3::z()
    };
    let cols = o.columns.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    let title_px = 22.0;
    let (w, h) = (
        cols as f64 * o.panel_px,
        rows as f64 * (o.panel_px + title_px),
    );
    // Faces and screen extents of every panel.
    let shaded: Vec<(Vec<Face>, [f64; 4])> = panels
        .iter()
        .map(|p| {
            let mut faces = Vec::new();
            let mut ext = [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            for pts in &p.hulls {
                if pts.len() < 4 {
                    continue;
                }
                let cloud: Vec<_> = pts
                    .iter()
                    .map(|x| parry3d_f64::math::Vector::new(x.x, x.y, x.z))
                    .collect();
                let (v, tris) = parry3d_f64::transformation::convex_hull(&cloud);
                let v: Vec<Vector3<f64>> = v.iter().map(|p| Vector3::new(p.x, p.y, p.z)).collect();
                for x in &v {
                    let (u, w) = (x.dot(&sx), x.dot(&sy));
                    ext = [ext[0].min(u), ext[1].max(u), ext[2].min(w), ext[3].max(w)];
                }
                for t in &tris {
                    let [p0, p1, p2] = [v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]];
                    let n = (p1 - p0).cross(&(p2 - p0));
                    if n.norm() == 0.0 || n.dot(&view) >= 0.0 {
                        continue;
                    }
                    let n = n.normalize();
                    let k = o.ambient + (1.0 - o.ambient) * n.dot(&light).max(0.0);
                    let fill = p
                        .color
                        .map(|c| (c as f64 * k).round().clamp(0.0, 255.0) as u8);
                    let proj = |x: Vector3<f64>| (x.dot(&sx), x.dot(&sy));
                    faces.push(Face {
                        depth: ((p0 + p1 + p2) / 3.0).dot(&view),
                        pts: [proj(p0), proj(p1), proj(p2)],
                        fill,
                    });
                }
            }
            // Far faces first: larger depth along the view direction is farther.
            faces.sort_by(|x, y| y.depth.total_cmp(&x.depth));
            (faces, ext)
        })
        .collect();
    let span = |x: &[f64; 4]| (x[1] - x[0]).max(x[3] - x[2]);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#
    );
    let _ = writeln!(svg, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    for (i, (p, (faces, ext))) in panels.iter().zip(&shaded).enumerate() {
        let (r, c) = (i / cols, i % cols);
        let row = r * cols..((r + 1) * cols).min(panels.len());
        let s = if o.shared_scale_per_row {
            shaded[row]
                .iter()
                .map(|(_, x)| span(x))
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max)
        } else {
            span(ext)
        };
        let scale = if s > 0.0 { 0.85 * o.panel_px / s } else { 1.0 };
        let (x0, y0) = (c as f64 * o.panel_px, r as f64 * (o.panel_px + title_px));
        let (cu, cw) = ((ext[0] + ext[1]) / 2.0, (ext[2] + ext[3]) / 2.0);
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" font-family="sans-serif" font-size="14" text-anchor="middle">{}</text>"#,
            x0 + o.panel_px / 2.0,
            y0 + 16.0,
            xml_escape(&p.title)
        );
        for f in faces {
            let pts: Vec<String> = f
                .pts
                .iter()
                .map(|(u, w)| {
                    format!(
                        "{:.2},{:.2}",
                        x0 + o.panel_px / 2.0 + (u - cu) * scale,
                        y0 + title_px + o.panel_px / 2.0 - (w - cw) * scale
                    )
                })
                .collect();
            let [cr, cg, cb] = f.fill;
            let _ = writeln!(
                svg,
                r##"<polygon points="{}" fill="#{cr:02x}{cg:02x}{cb:02x}" stroke="#333" stroke-width="0.3"/>"##,
                pts.join(" ")
            );
        }
    }
    svg.push_str("</svg>\n");
    svg
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(h: f64) -> Vec<Vector3<f64>> {
        (0..8)
            .map(|i| {
                Vector3::new(
                    if i & 1 == 0 { -h } else { h },
                    if i & 2 == 0 { -h } else { h },
                    if i & 4 == 0 { -h } else { h },
                )
            })
            .collect()
    }

    #[test]
    fn cube_shows_three_faces_lit_top_brightest() {
        let p = Panel {
            title: "cube".into(),
            hulls: vec![cube(0.5)],
            color: [200, 200, 200],
        };
        let svg = render_hulls_svg(&[p], &PictureOptions::default());
        // A cube seen from above at an oblique angle shows 3 faces = 6 triangles.
        assert_eq!(svg.matches("<polygon").count(), 6, "{svg}");
        // The top face (normal +z) gets the most light: its fill is the largest.
        let fills: Vec<u8> = svg
            .match_indices("fill=\"#")
            .map(|(i, _)| u8::from_str_radix(&svg[i + 7..i + 9], 16).unwrap())
            .collect();
        let top = 200.0 * (0.35 + 0.65 * (1.0 / Vector3::new(0.3f64, -0.5, 1.0).norm()));
        assert!(
            fills.iter().any(|&f| (f as f64 - top).abs() <= 1.0),
            "{fills:?}"
        );
        assert!(fills.iter().all(|&f| f as f64 <= top + 1.0));
    }

    #[test]
    fn painter_order_draws_the_far_hull_first() {
        // Two cubes along the view direction: the far one must come first.
        let o = PictureOptions {
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            ..Default::default()
        };
        let near: Vec<_> = cube(0.2)
            .iter()
            .map(|x| x + Vector3::new(1.0, 0.0, 0.0))
            .collect();
        // The far cube is larger, so its projection differs from the near one's.
        let far: Vec<_> = cube(0.3)
            .iter()
            .map(|x| x - Vector3::new(1.0, 0.0, 0.0))
            .collect();
        let p = Panel {
            title: "two".into(),
            hulls: vec![near, far],
            color: [100, 150, 200],
        };
        let svg = render_hulls_svg(&[p], &o);
        // Camera on +x: only the +x faces (2 triangles each) face it.
        assert_eq!(svg.matches("<polygon").count(), 4);
        // The far cube must be drawn first (the near one on top): its polygons,
        // rendered alone at the same scale and centre, are the first two.
        let alone = render_hulls_svg(
            &[Panel {
                title: "two".into(),
                hulls: vec![
                    cube(0.3)
                        .iter()
                        .map(|x| x - Vector3::new(1.0, 0.0, 0.0))
                        .collect(),
                ],
                color: [100, 150, 200],
            }],
            &o,
        );
        let polys = |s: &str| {
            s.lines()
                .filter(|l| l.starts_with("<polygon"))
                .map(String::from)
                .collect::<Vec<_>>()
        };
        assert_eq!(polys(&svg)[..2], polys(&alone)[..]);
    }
}
