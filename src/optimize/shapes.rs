//! `shapes.svg`: the designed links' hulls before and after optimization,
//! one row per link (initial left, optimized right, same scale), drawn by
//! [`crate::output::picture::render_hulls_svg`] in each link's own frame.

use super::Problem;
use super::design::Target;
use crate::output::picture::{Panel, PictureOptions, render_hulls_svg};
use nalgebra::DVector;

/// Links whose hull vertices or attachments are design variables.
pub fn designed_links(p: &Problem) -> Vec<usize> {
    let mut links: Vec<usize> = p
        .design
        .vars
        .iter()
        .flat_map(|v| v.targets.iter())
        .filter_map(|t| match t {
            Target::Vertex { link, .. }
            | Target::Blend { link, .. }
            | Target::SurfaceBlend { link, .. } => Some(*link),
            Target::Attachment { .. } => None,
        })
        .collect();
    links.sort_unstable();
    links.dedup();
    links
}

/// The SVG (None when nothing is designed).
pub fn initial_vs_optimized_svg(
    p: &Problem,
    initial: &DVector<f64>,
    optimized: &DVector<f64>,
) -> Option<String> {
    let links = designed_links(p);
    if links.is_empty() {
        return None;
    }
    let (mut m0, mut m1) = (p.model.clone(), p.model.clone());
    p.design.apply(&mut m0, initial);
    p.design.apply(&mut m1, optimized);
    let mut panels = Vec::new();
    for &l in &links {
        let name = format!(
            "{}/{}",
            p.model.robots[p.model.links[l].robot].name, p.model.links[l].name
        );
        for (m, what, color) in [
            (&m0, "initial", [170, 170, 170]),
            (&m1, "optimized", [90, 150, 220]),
        ] {
            panels.push(Panel {
                title: format!("{name} ({what})"),
                hulls: m.links[l].hulls.iter().map(|h| h.x_local.clone()).collect(),
                color,
            });
        }
    }
    Some(render_hulls_svg(&panels, &PictureOptions::default()))
}
