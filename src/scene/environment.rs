//! Bodies that are not articulated robots — free objects, the ground and
//! static obstacles — expressed as robots so one code path handles all, and
//! the contact settings.

use super::build::{check_finite, unit};
use super::schema::*;
use super::{ContactSettings, Invalid};
use crate::model::Model;
use nalgebra::Vector3;
use std::collections::{BTreeMap, BTreeSet};

/// Name of the robot that holds the ground and the obstacles.
pub const ENVIRONMENT: &str = "world";

/// Objects become one-link robots on a free joint named after the object;
/// the ground and the obstacles become fixed root links of the
/// [`ENVIRONMENT`] robot (no coordinates, constant poses).
pub fn expand_bodies(spec: &SceneSpec) -> Result<Vec<RobotSpec>, Invalid> {
    let mut out = spec.robots.clone();
    for (i, o) in spec.objects.iter().enumerate() {
        for (what, v) in [("q", &o.initial.q), ("qdot", &o.initial.qdot)] {
            if !v.is_empty() && v.len() != 6 {
                return Err(Invalid::new(
                    format!("objects[{i}] (\"{}\").initial.{what}", o.name),
                    format!(
                        "a free object takes 6 values [x, y, z, rx, ry, rz], got {}",
                        v.len()
                    ),
                ));
            }
        }
        let mut initial = BTreeMap::new();
        initial.insert(o.name.clone(), o.initial.clone());
        out.push(RobotSpec {
            name: o.name.clone(),
            base: Origin::default(),
            links: vec![LinkSpec {
                name: o.name.clone(),
                parent: None,
                joint: fixed_or_free(JointType::Free, Origin::default()),
                mass: o.mass,
                vertex_mass: o.vertex_mass,
                mass_model: o.mass_model.clone(),
                hulls: o.hulls.clone(),
                collide: true,
                surface_mesh: o.surface_mesh.clone(),
            }],
            chain: None,
            controller: ControllerSpec::default(),
            initial,
            design: None,
        });
    }
    let mut env = Vec::new();
    if let Some(g) = &spec.ground {
        let a = g.slope_axis;
        check_finite(
            "ground",
            "height/slope_deg/slope_axis",
            &[g.height, g.slope_deg, a[0], a[1], a[2]],
        )?;
        if !(g.half_size > 0.0 && g.thickness > 0.0) {
            return Err(Invalid::new(
                "ground",
                "half_size and thickness must be positive",
            ));
        }
        let axis = unit("ground", "slope_axis", a)?;
        let rot = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(axis),
            g.slope_deg.to_radians(),
        );
        let (roll, pitch, yaw) = rot.euler_angles();
        let normal = rot * Vector3::z();
        let size = [2.0 * g.half_size, 2.0 * g.half_size, g.thickness];
        env.push(LinkSpec {
            name: "ground".into(),
            parent: None,
            joint: fixed_or_free(
                JointType::Fixed,
                Origin {
                    xyz: (normal * g.height).into(),
                    rpy: [roll, pitch, yaw],
                },
            ),
            mass: Some(1.0),
            vertex_mass: None,
            mass_model: None,
            hulls: vec![HullSpec::cuboid(size, [0.0, 0.0, -g.thickness / 2.0])],
            collide: true,
            surface_mesh: None,
        });
    }
    for o in &spec.obstacles {
        env.push(LinkSpec {
            name: o.name.clone(),
            parent: None,
            joint: fixed_or_free(JointType::Fixed, o.origin.clone()),
            mass: Some(1.0),
            vertex_mass: None,
            mass_model: None,
            hulls: o.hulls.clone(),
            collide: true,
            surface_mesh: o.surface_mesh.clone(),
        });
    }
    if !env.is_empty() {
        out.push(RobotSpec {
            name: ENVIRONMENT.into(),
            base: Origin::default(),
            links: env,
            chain: None,
            controller: ControllerSpec::default(),
            initial: BTreeMap::new(),
            design: None,
        });
    }
    Ok(out)
}

fn fixed_or_free(kind: JointType, origin: Origin) -> JointSpec {
    JointSpec {
        name: None,
        kind,
        axis: None,
        axes: None,
        origin,
        limit: None,
        mimic: None,
    }
}

/// Validated contact settings with excluded link pairs resolved to indices.
pub fn contact_settings(c: &ContactSpec, model: &Model) -> Result<ContactSettings, Invalid> {
    let moved = [
        ("surface", &c.moved_surface),
        ("dhat", &c.moved_dhat),
        ("eps_v", &c.moved_eps_v),
    ];
    if let Some((key, _)) = moved.iter().find(|(_, v)| v.is_some()) {
        return Err(Invalid::new(
            format!("contact.{key}"),
            format!(
                "the IPC baseline's `{key}` now lives in its own section: write it as `contact: {{ipc: {{{key}: ...}}}}` (moved on 2026-11-26, with `surface`, `dhat` and `eps_v`)"
            ),
        ));
    }
    if !(c.s > 0.0 && c.s < 1.0) {
        return Err(Invalid::new(
            "contact.s",
            format!("the barrier support must lie in (0, 1), got {}", c.s),
        ));
    }
    let kappa = c.kappa.unwrap_or_else(ContactSpec::default_kappa);
    if !(kappa > 0.0 && kappa.is_finite()) {
        return Err(Invalid::new(
            "contact.kappa",
            format!("must be positive and finite, got {kappa}"),
        ));
    }
    if !(c.mu >= 0.0 && c.mu.is_finite()) {
        return Err(Invalid::new(
            "contact.mu",
            format!("must be finite and ≥ 0, got {}", c.mu),
        ));
    }
    if !(c.eps > 0.0 && c.eps.is_finite()) {
        return Err(Invalid::new(
            "contact.eps",
            format!("must be positive and finite, got {}", c.eps),
        ));
    }
    if let Some(msg) = c.ccd.problem() {
        return Err(Invalid::new("contact.ccd", msg));
    }
    let find = |name: &str, k: usize| -> Result<usize, Invalid> {
        let el = format!("contact.exclude[{k}]");
        let (robot, link) = name.split_once('/').ok_or_else(|| {
            Invalid::new(&el, format!("\"{name}\" is not of the form robot/link"))
        })?;
        model
            .links
            .iter()
            .position(|l| l.name == link && model.robots[l.robot].name == robot)
            .ok_or_else(|| Invalid::new(&el, format!("no link \"{link}\" in a robot \"{robot}\"")))
    };
    let mut excluded = BTreeSet::new();
    for (k, [a, b]) in c.exclude.iter().enumerate() {
        let (i, j) = (find(a, k)?, find(b, k)?);
        excluded.insert((i.min(j), i.max(j)));
    }
    if c.exclude_adjacent {
        for (i, l) in model.links.iter().enumerate() {
            if let Some(p) = l.parent {
                excluded.insert((p.min(i), p.max(i)));
            }
        }
    }
    // Static links never interact with each other.
    let fixed: Vec<usize> = (0..model.links.len())
        .filter(|&i| model.ancestor_dofs[i].is_empty())
        .collect();
    for (a, &i) in fixed.iter().enumerate() {
        for &j in &fixed[a + 1..] {
            excluded.insert((i, j));
        }
    }
    Ok(ContactSettings {
        model: c.model,
        ipc: c.ipc.clone(),
        s: c.s,
        kappa,
        kappa_given: c.kappa.is_some(),
        mu: c.mu,
        eps: c.eps,
        ccd: c.ccd.clone(),
        eps_force: c.eps_force,
        excluded,
    })
}
