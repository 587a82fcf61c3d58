//! The tunnelling suite of issue 19: fast, thin or spinning bodies against
//! thin obstacles, as scene text, with a *same-side* check per case.
//!
//! A body that tunnels through a thin obstacle in one step is separated at
//! every recorded step, so a distance check at the steps (python-fcl,
//! `tools/check/check_separation.py`) cannot see it; the side check can: for a
//! thin "sheet" hull (a wall, a plate, a spinning bar) and a point of
//! another body (its hull centroid), the point's signed offset along the
//! sheet's thin axis must not change sign between two consecutive steps
//! while the point lies within the sheet's extent in the other two axes
//! (passing around an edge is allowed). Shared by `tests/tunnelling.rs` (a
//! small grid) and `examples/tunnel_grid.rs` (the full grid).
#![allow(dead_code)]

use nalgebra::Vector3;
use sdrs::math::{Pose, rot, transform_point};
use sdrs::model::Model;

/// One scenario.
pub struct Case {
    pub name: String,
    pub yaml: String,
    /// Side checks: a sheet and a tracked point each.
    pub sides: Vec<SideCheck>,
}

/// A thin sheet on one link and a tracked point (centroid) on another.
#[derive(Clone, Debug)]
pub struct SideCheck {
    /// The sheet's link: `robot` (its first link: objects), `robot/link`,
    /// or an obstacle's name.
    pub sheet: String,
    /// Sheet centre in its link frame.
    pub centre: [f64; 3],
    /// Thin axis of the sheet (0, 1, 2 in its link frame).
    pub thin: usize,
    /// Half extents in the link frame (the thin one unused).
    pub half: [f64; 3],
    /// The link whose hull centroid is tracked (named as `sheet`).
    pub point: String,
}

fn link_index(model: &Model, name: &str) -> usize {
    let (robot, link) = match name.split_once('/') {
        Some((r, l)) => (r, Some(l)),
        None => (name, None),
    };
    let find = |robot: &str, link: Option<&str>| {
        model
            .links
            .iter()
            .position(|l| model.robots[l.robot].name == robot && link.is_none_or(|n| n == l.name))
    };
    // Obstacles are links of the environment robot `world`.
    find(robot, link)
        .or_else(|| find("world", Some(name)))
        .unwrap_or_else(|| panic!("no link {name}"))
}

fn centroid(model: &Model, link: usize) -> Vector3<f64> {
    let pts: Vec<&Vector3<f64>> = model.links[link]
        .hulls
        .iter()
        .flat_map(|h| h.x_local.iter())
        .collect();
    pts.iter().copied().sum::<Vector3<f64>>() / pts.len() as f64
}

/// Every violation of the case's side checks in a run's link poses
/// (`poses[step][link]`), described.
pub fn side_violations(case: &Case, model: &Model, poses: &[Vec<Pose>]) -> Vec<String> {
    let mut out = Vec::new();
    for s in &case.sides {
        let (ls, lp) = (link_index(model, &s.sheet), link_index(model, &s.point));
        let c = centroid(model, lp);
        let centre = Vector3::from(s.centre);
        // (signed offset along the thin axis, within the extent)
        let at = |a: &[Pose]| -> (f64, bool) {
            let p = transform_point(&a[lp], &c);
            let local = rot(&a[ls]).transpose() * (p - a[ls].column(3)) - centre;
            let inside = (0..3).all(|e| e == s.thin || local[e].abs() <= s.half[e]);
            (local[s.thin], inside)
        };
        for (k, w) in poses.windows(2).enumerate() {
            let ((a, ia), (b, ib)) = (at(&w[0]), at(&w[1]));
            if ia && ib && a * b < 0.0 {
                out.push(format!(
                    "{}: {} crossed {} between steps {k} and {} (offset {a:.4} → {b:.4} m)",
                    case.name,
                    s.point,
                    s.sheet,
                    k + 1
                ));
            }
        }
    }
    out
}

fn contact(ccd: bool) -> String {
    if ccd {
        "contact: {s: 0.01, kappa: 1.0, mu: 0.0}".into()
    } else {
        "contact: {s: 0.01, kappa: 1.0, mu: 0.0, ccd: {enabled: false}}".into()
    }
}

fn steps(dt: f64, seconds: f64) -> usize {
    (seconds / dt).ceil() as usize + 5
}

/// The side check of `point` against the 1 × 1 m sheet at x = 0 (thin
/// along x), the obstacle of the shots and the slider.
fn x_sheet(point: &str) -> SideCheck {
    SideCheck {
        sheet: "sheet".into(),
        centre: [0.0; 3],
        thin: 0,
        half: [0.0, 0.5, 0.5],
        point: point.into(),
    }
}

/// A 5 cm box (free body) shot along +x at `v` m/s from 0.5 m at a thin
/// obstacle of thickness `thick` (1 × 1 m) at x = 0.
pub fn shot(v: f64, dt: f64, thick: f64, ccd: bool) -> Case {
    let kind = if thick >= 0.01 { "wall" } else { "plate" };
    Case {
        name: format!("shot_{kind}_v{v}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\ngravity: [0, 0, 0]\n{}\nobjects:\n  - {{name: bullet, mass: 0.1, hulls: [{{box: {{size: [0.05, 0.05, 0.05]}}}}], initial: {{q: [-0.5, 0, 0, 0, 0, 0], qdot: [{v}, 0, 0, 0, 0, 0]}}}}\nobstacles:\n  - {{name: sheet, hulls: [{{box: {{size: [{thick}, 1.0, 1.0]}}}}]}}\n",
            steps(dt, 0.5 / v + 0.03),
            contact(ccd)
        ),
        sides: vec![x_sheet("bullet")],
    }
}

/// A 1 m bar (free body, 1 cm section) spinning at `w` rad/s about z next
/// to a 1 cm post 0.3 m from its centre; it starts a quarter turn away.
pub fn spin(w: f64, dt: f64, ccd: bool) -> Case {
    Case {
        name: format!("spin_w{w}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\ngravity: [0, 0, 0]\n{}\nobjects:\n  - {{name: bar, mass: 0.5, hulls: [{{box: {{size: [1.0, 0.01, 0.01]}}}}], initial: {{q: [0, 0, 0, 0, 0, 1.5707963267948966], qdot: [0, 0, 0, 0, 0, {w}]}}}}\nobstacles:\n  - {{name: post, origin: {{xyz: [0.3, 0, 0]}}, hulls: [{{box: {{size: [0.01, 0.01, 0.3]}}}}]}}\n",
            steps(dt, 2.0 * std::f64::consts::PI / w),
            contact(ccd)
        ),
        sides: vec![SideCheck {
            sheet: "bar".into(),
            centre: [0.0; 3],
            thin: 1,
            half: [0.5, 0.0, f64::INFINITY],
            point: "post".into(),
        }],
    }
}

/// Three revolute links (0.25 m, about z) whipped at `w` rad/s at the root
/// from pointing along −y into a 5 mm plate in the xz-plane (x from 0.1
/// to 1.1 m): every link must stay on the −y side.
pub fn whip(w: f64, dt: f64, ccd: bool) -> Case {
    let link = |name: &str, parent: &str, x: f64| {
        format!(
            "      - {{name: {name}, {parent}joint: {{type: revolute, axis: [0, 0, 1], origin: {{xyz: [{x}, 0, 0]}}}}, mass: 0.1, hulls: [{{box: {{size: [0.24, 0.03, 0.03], center: [0.125, 0, 0]}}}}]}}\n"
        )
    };
    Case {
        name: format!("whip_w{w}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\ngravity: [0, 0, 0]\n{}\nrobots:\n  - name: whip\n    links:\n{}{}{}    initial: {{l0: {{q: [-1.5707963267948966], qdot: [{w}]}}}}\nobstacles:\n  - {{name: sheet, origin: {{xyz: [0.6, 0, 0]}}, hulls: [{{box: {{size: [1.0, 0.005, 1.0]}}}}]}}\n",
            steps(dt, 4.0 / w),
            contact(ccd),
            link("l0", "", 0.0),
            link("l1", "parent: l0, ", 0.25),
            link("l2", "parent: l1, ", 0.25),
        ),
        sides: ["whip/l0", "whip/l1", "whip/l2"]
            .iter()
            .map(|p| SideCheck {
                sheet: "sheet".into(),
                centre: [0.0; 3],
                thin: 1,
                half: [0.5, 0.0, 0.5],
                point: (*p).into(),
            })
            .collect(),
    }
}

/// A tumbling 5 cm box dropped from `h` m onto a 2 mm plate at z = 0.
pub fn drop(h: f64, dt: f64, ccd: bool) -> Case {
    let fall = (2.0 * h / 9.81).sqrt();
    Case {
        name: format!("drop_h{h}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\n{}\nobjects:\n  - {{name: box, mass: 0.1, hulls: [{{box: {{size: [0.05, 0.05, 0.05]}}}}], initial: {{q: [0, 0, {h}, 0, 0, 0], qdot: [0, 0, 0, 7, 3, 0]}}}}\nobstacles:\n  - {{name: sheet, hulls: [{{box: {{size: [1.0, 1.0, 0.002]}}}}]}}\n",
            steps(dt, fall + 0.03),
            contact(ccd)
        ),
        sides: vec![SideCheck {
            sheet: "sheet".into(),
            centre: [0.0; 3],
            thin: 2,
            half: [0.5, 0.5, 0.0],
            point: "box".into(),
        }],
    }
}

/// A 5 cm box on a prismatic joint (along x) driven at `v` m/s into a
/// 1 cm wall.
pub fn slider(v: f64, dt: f64, ccd: bool) -> Case {
    Case {
        name: format!("prismatic_v{v}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\ngravity: [0, 0, 0]\n{}\nrobots:\n  - name: slider\n    base: {{xyz: [-0.5, 0, 0]}}\n    links:\n      - {{name: carriage, joint: {{type: prismatic, axis: [1, 0, 0]}}, mass: 0.1, hulls: [{{box: {{size: [0.05, 0.05, 0.05]}}}}]}}\n    initial: {{carriage: {{qdot: [{v}]}}}}\nobstacles:\n  - {{name: sheet, hulls: [{{box: {{size: [0.01, 1.0, 1.0]}}}}]}}\n",
            steps(dt, 0.5 / v + 0.03),
            contact(ccd)
        ),
        sides: vec![x_sheet("slider")],
    }
}

/// A 0.6 m arm on a spherical joint spinning at `w` rad/s about z into a
/// 1 cm post 0.4 m from the joint; the arm is the sheet.
pub fn spherical(w: f64, dt: f64, ccd: bool) -> Case {
    Case {
        name: format!("spherical_w{w}_dt{dt}"),
        yaml: format!(
            "version: 1\ndt: {dt}\nsteps: {}\ngravity: [0, 0, 0]\n{}\nrobots:\n  - name: arm\n    links:\n      - {{name: arm, joint: {{type: spherical}}, mass: 0.2, hulls: [{{box: {{size: [0.6, 0.01, 0.01], center: [0.3, 0, 0]}}}}]}}\n    initial: {{arm: {{qdot: [0, 0, {w}]}}}}\nobstacles:\n  - {{name: post, origin: {{xyz: [0, 0.4, 0]}}, hulls: [{{box: {{size: [0.01, 0.01, 0.3]}}}}]}}\n",
            steps(dt, 2.0 * std::f64::consts::PI / w),
            contact(ccd)
        ),
        sides: vec![SideCheck {
            sheet: "arm".into(),
            centre: [0.3, 0.0, 0.0],
            thin: 1,
            half: [0.3, 0.0, f64::INFINITY],
            point: "post".into(),
        }],
    }
}

/// The reproducers of issue 19 (`tests/data/tunnel/`), with their checks.
pub fn reproducers() -> Vec<(&'static str, SideCheck)> {
    vec![
        (
            "tunnel_shot_wall_v20_dt0.01.yaml",
            SideCheck {
                sheet: "wall".into(),
                centre: [0.0; 3],
                thin: 0,
                half: [0.0, 0.5, 0.5],
                point: "bullet".into(),
            },
        ),
        (
            "tunnel_spin_w50_dt0.005.yaml",
            SideCheck {
                sheet: "bar".into(),
                centre: [0.0; 3],
                thin: 1,
                half: [0.5, 0.0, f64::INFINITY],
                point: "post".into(),
            },
        ),
    ]
}
