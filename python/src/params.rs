//! The three parameter groups the adjoint differentiates, as flat vectors:
//! design `d` (attachment points and hull vertices), controller `c`
//! (target-signal parameters and PD gains) and physics `φ`.
//!
//! Physics `φ = [ρ, g_x, g_y, g_z, μ, s, κ]` (the last three only for scenes
//! with contact): `ρ` scales every vertex mass of the scene (`m = ρ m₀`,
//! `ρ₀ = 1`), `g` is gravity (m/s²), `μ` the friction coefficient, `s` the
//! barrier support (m) and `κ` the barrier stiffness. The core reports
//! `∂L/∂ρ'` at `ρ' = 1` for masses `ρ' (ρ m₀)`, so `dL/dρ = (∂L/∂ρ')/ρ`.
//! With `μ = 0` the scene has no friction term and `dL/dμ` is reported as 0
//! (the one-sided derivative at `μ = 0⁺` is not).

use nalgebra::DVector;
use sdrs::diff::Gradients;
use sdrs::model::Model;
use sdrs::optimize::controls::ControlTarget;
use sdrs::optimize::design::{DesignVar, Target};
use sdrs::optimize::{ControlSpace, DesignSpace};
use sdrs::scene::Scene;

/// Names of the physics vector of `scene`.
pub fn physics_names(scene: &Scene) -> Vec<String> {
    let mut n: Vec<String> = ["mass_scale", "gravity.x", "gravity.y", "gravity.z"]
        .map(String::from)
        .to_vec();
    if scene.contact.is_some() {
        n.extend(["contact.mu", "contact.s", "contact.kappa"].map(String::from));
    }
    n
}

/// The physics vector of `scene` (`ρ = 1`).
pub fn physics_values(scene: &Scene) -> Vec<f64> {
    let g = scene.settings.gravity;
    let mut v = vec![1.0, g.x, g.y, g.z];
    if let Some(c) = &scene.contact {
        v.extend([c.mu, c.s, c.kappa]);
    }
    v
}

/// Writes `p` into `scene` (masses scaled only when `ρ ≠ 1`, so the scene's
/// own values leave it bitwise unchanged). Checks length and ranges.
pub fn apply_physics(scene: &mut Scene, p: &[f64]) -> Result<(), String> {
    let names = physics_names(scene);
    if p.len() != names.len() {
        return Err(format!(
            "physics: expected {} values ({}), got {}",
            names.len(),
            names.join(", "),
            p.len()
        ));
    }
    if let Some(k) = p.iter().position(|x| !x.is_finite()) {
        return Err(format!(
            "physics: {} is {} (must be finite)",
            names[k], p[k]
        ));
    }
    let rho = p[0];
    if rho <= 0.0 {
        return Err(format!("physics: mass_scale must be positive, got {rho}"));
    }
    if rho != 1.0 {
        for l in &mut scene.model.links {
            for h in &mut l.hulls {
                h.vertex_mass.iter_mut().for_each(|m| *m *= rho);
            }
        }
        scene.model.refresh_moments();
    }
    scene.settings.gravity = nalgebra::Vector3::new(p[1], p[2], p[3]);
    if let Some(c) = scene.contact.as_mut() {
        let (mu, s, kappa) = (p[4], p[5], p[6]);
        if mu < 0.0 || s <= 0.0 || kappa <= 0.0 {
            return Err(format!(
                "physics: need contact.mu >= 0, contact.s > 0 and contact.kappa > 0, got {mu}, {s}, {kappa}"
            ));
        }
        c.mu = mu;
        c.s = s;
        c.kappa = kappa;
    }
    Ok(())
}

/// `dL/dφ` from the core's gradients (see the module docs for `ρ`).
pub fn physics_gradient(scene_has_contact: bool, p: &[f64], g: &Gradients) -> Vec<f64> {
    let ph = &g.physical;
    let mut v = vec![
        ph.mass_scale / p[0],
        ph.gravity[0],
        ph.gravity[1],
        ph.gravity[2],
    ];
    if scene_has_contact {
        v.extend([ph.mu, ph.s, ph.kappa]);
    }
    v
}

/// The full design space of a scene: every link's attachment point
/// (`robot/link.attach.x|y|z`, parent frame; world for roots) and every hull
/// vertex (`robot/link.hull<h>.v<k>.x|y|z`, link frame), unbounded.
pub fn scene_design(model: &Model) -> DesignSpace {
    let mut vars = Vec::new();
    let axes = ["x", "y", "z"];
    for (l, link) in model.links.iter().enumerate() {
        let label = format!("{}/{}", model.robots[link.robot].name, link.name);
        for (axis, a) in axes.iter().enumerate() {
            vars.push(var(
                Target::Attachment { link: l, axis },
                format!("{label}.attach.{a}"),
            ));
        }
        for (h, hull) in link.hulls.iter().enumerate() {
            for v in 0..hull.x_local.len() {
                for (axis, a) in axes.iter().enumerate() {
                    vars.push(var(
                        Target::Vertex {
                            link: l,
                            hull: h,
                            vertex: v,
                            axis,
                        },
                        format!("{label}.hull{h}.v{v}.{a}"),
                    ));
                }
            }
        }
    }
    DesignSpace { vars }
}

fn var(t: Target, name: String) -> DesignVar {
    DesignVar {
        targets: vec![t],
        lower: f64::NEG_INFINITY,
        upper: f64::INFINITY,
        name,
    }
}

/// The full controller space of a scene: every channel's signal parameters,
/// then its `kp` and `kd` (gains are clamped at 0 when written).
pub fn scene_controls(controller: &sdrs::control::Controller) -> ControlSpace {
    let mut entries = Vec::new();
    for (ch, c) in controller.channels.iter().enumerate() {
        for param in 0..c.signal.nparams() {
            entries.push(ControlTarget::Signal { channel: ch, param });
        }
        entries.push(ControlTarget::Kp { channel: ch });
        entries.push(ControlTarget::Kd { channel: ch });
    }
    ControlSpace { entries }
}

/// `x` as a vector of length `n` (`what` names it in the error).
pub fn vector(what: &str, x: &[f64], n: usize) -> Result<DVector<f64>, String> {
    if x.len() != n {
        return Err(format!("{what}: expected {n} values, got {}", x.len()));
    }
    if let Some(k) = x.iter().position(|v| !v.is_finite()) {
        return Err(format!("{what}[{k}] is {} (must be finite)", x[k]));
    }
    Ok(DVector::from_column_slice(x))
}
