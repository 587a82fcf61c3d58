//! MJCF actuators → the scene's stable-PD controller (issue 32, item 1).
//!
//! **MuJoCo's force.** An actuator with a joint transmission on a hinge or
//! slide `q` (gear `g`), no activation dynamics (`dyntype none`), a fixed
//! gain and an affine (or no) bias has the length `L = g q`, the velocity
//! `L̇ = g q̇`, the actuator force `f = a₀ u + b₀ + b₁ L + b₂ L̇` (`a` =
//! `gainprm`, `b` = `biasprm`, `u` the control) and the joint force
//! `τ = g f = g (a₀ u + b₀) − k q − c q̇`, with the stiffness
//! `k = −g² b₁` (N·m/rad or N/m) and the damping `c = −g² b₂`
//! (N·m·s/rad or N·s/m). `<position kp kv>` is `a₀ = kp`, `b = (0, −kp,
//! −kv)`: `τ = g kp (u − g q) − g² kv q̇`; `<velocity kv>` is `a₀ = kv`,
//! `b = (0, 0, −kv)`; `<motor>` is `a₀ = 1`, no bias. Several actuators on
//! one joint add: `K = Σ k`, `C = Σ c`, `F = Σ g (a₀ u + b₀)`, so
//! `τ = F − K q − C q̇ = K (F/K − q) − C q̇`.
//!
//! **The scene's force** (`src/energy/pd.rs`, paper convention without ½):
//! `τ = 2 k_p (θ* − θ) + (2 k_d/Δt)(θ̇* − θ̇)`, `k_p` in J/rad² (J/m²),
//! `k_d` in J·s²/rad², `θ̇ = (θ^{t+1} − θ^t)/Δt`. Equal forces for every
//! `q`, `q̇` when
//!
//! `k_p = K/2`, `k_d = C Δt/2`, `θ* = F/K` (0 when `K = 0`), `θ̇* = 0`
//!
//! (`θ = qpos` for hinges and slides: the import folds `ref` into the
//! attachment). `k_d` carries the scene's `Δt`: a scene whose `dt` is
//! changed afterwards must scale `k_d` with it to keep MuJoCo's damping.
//!
//! **The control** `u` is MuJoCo's control at rest: `ctrl = 0` (what
//! `MjData` starts with; the import reads `qpos0`, not keyframes), clamped
//! to `ctrlrange` when `ctrllimited`, so a `<position>` servo holds its
//! joint at `θ* = u/g` as MuJoCo does with no control applied.
//!
//! **What wins.** A joint driven this way takes its gains and target from
//! its actuators, not from the import's PD hold (`super::super::ready`):
//! MuJoCo simulates that servo at rest, adding the hold on top would stiffen
//! the joint beyond the model, and the hold's target (the initial pose) is
//! not where the servo pulls. Joints without such an actuator (motors,
//! tendon-driven joints, none) keep the hold.
//!
//! **Report lines** (nothing is dropped silently): one per actuator, mapped
//! or left out and why — other transmissions (tendon, site, body, slider-crank),
//! ball and free joints, activation dynamics, state-dependent gains,
//! negative stiffness or damping, a constant force at rest (the scene has
//! no torque-input channel), a motor (no force at rest, and no channel for
//! one); `forcerange` (the scene's PD torque is not clamped) and
//! `ctrlrange` (it gives `u` but does not clamp later targets) get their
//! own lines; one line per driven joint gives the scene gains.

use super::dump::{Dump, DumpActuator};
use std::collections::BTreeMap;

/// The scene PD of one joint driven by its MJCF actuators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    /// `K/2` (J/rad² or J/m²).
    pub kp: f64,
    /// `C Δt/2` (J·s²/rad² or J·s²/m²).
    pub kd: f64,
    /// `F/K` (rad or m), 0 when `K = 0`.
    pub target: f64,
}

/// One actuator's contribution to its joint (MuJoCo's joint force at rest
/// `τ = f − k q − c q̇`, see the module doc).
#[derive(Clone, Copy, Debug, Default)]
struct Servo {
    /// N·m/rad or N/m.
    k: f64,
    /// N·m·s/rad or N·s/m.
    c: f64,
    /// N·m or N.
    f: f64,
}

/// The drives of every joint that has mappable actuators, keyed by joint
/// name; `dt` (s) is the scene's time step. Every actuator gets a report
/// line in `notes`.
pub fn drives(d: &Dump, dt: f64, notes: &mut Vec<String>) -> BTreeMap<String, Drive> {
    let kinds: BTreeMap<&str, &str> = d
        .bodies
        .iter()
        .flat_map(|b| &b.joints)
        .map(|j| (j.name.as_str(), j.kind.as_str()))
        .collect();
    let mut sums: BTreeMap<String, Servo> = BTreeMap::new();
    let mut left_out = Vec::new();
    for a in &d.actuators {
        let u = rest_control(a);
        match servo(a, &kinds, u) {
            Ok((joint, s)) => {
                let (stiff, damp, force) = units(kinds.get(joint.as_str()).copied());
                notes.push(format!(
                    "actuator \"{}\" ({}) {} → the scene's PD controller: stiffness g²·(−biasprm₁) = {} {stiff}, damping g²·(−biasprm₂) = {} {damp}, force at rest g·(gainprm₀·u + biasprm₀) = {} {force} with u = {u} (ctrl 0{})",
                    a.name,
                    describe(a),
                    on(a),
                    s.k,
                    s.c,
                    s.f,
                    if a.ctrlrange.is_some() { " clamped to ctrlrange" } else { "" }
                ));
                limit_notes(a, u, notes);
                let sum = sums.entry(joint).or_default();
                sum.k += s.k;
                sum.c += s.c;
                sum.f += s.f;
            }
            Err(why) => left_out.push((a, why)),
        }
    }
    for (a, why) in left_out {
        let holds = match &a.joint {
            Some(j) if sums.contains_key(j) => {
                format!("; joint \"{j}\" is driven by its other actuators")
            }
            Some(_) => {
                "; the joint is held by the import's PD hold when on (report: ready.gains)".into()
            }
            None => String::new(),
        };
        notes.push(format!(
            "actuator \"{}\" ({}) {} left out: {why}{holds}",
            a.name,
            describe(a),
            on(a)
        ));
    }
    sums.into_iter()
        .map(|(joint, s)| {
            let drive = Drive {
                kp: s.k / 2.0,
                kd: s.c * dt / 2.0,
                target: if s.k > 0.0 { s.f / s.k } else { 0.0 },
            };
            notes.push(format!(
                "joint \"{joint}\" is driven by its actuators instead of the import's PD hold: k_p = K/2 = {} J/rad², k_d = C·Δt/2 = {} J s²/rad² (Δt = {dt} s; k_d scales with the scene's dt), target θ* = F/K = {} (rad or m)",
                drive.kp, drive.kd, drive.target
            ));
            (joint, drive)
        })
        .collect()
}

/// MuJoCo's control at rest: 0, clamped to `ctrlrange` when limited.
fn rest_control(a: &DumpActuator) -> f64 {
    match a.ctrlrange {
        Some([lo, hi]) if lo <= hi => 0.0f64.clamp(lo, hi),
        _ => 0.0,
    }
}

/// The joint and the servo of a mappable actuator at control `u`, or why it
/// is left out.
fn servo(
    a: &DumpActuator,
    kinds: &BTreeMap<&str, &str>,
    u: f64,
) -> Result<(String, Servo), String> {
    let joint = match (&a.joint, a.transmission.as_str()) {
        (Some(j), "joint" | "jointinparent" | "") => j.clone(),
        _ => {
            return Err(format!(
                "only joint transmissions map to the scene's PD controller ({} transmissions are not represented)",
                a.transmission
            ));
        }
    };
    match kinds.get(joint.as_str()) {
        Some(&("hinge" | "slide")) => {}
        kind => {
            return Err(format!(
                "the scene's PD controller takes hinge and slide joints here, \"{joint}\" is a {} joint",
                kind.unwrap_or(&"unknown")
            ));
        }
    }
    if !matches!(a.dyntype.as_str(), "none" | "") {
        return Err(format!(
            "activation dynamics (dyntype {}) are not represented",
            a.dyntype
        ));
    }
    if !matches!(a.gaintype.as_str(), "fixed" | "") {
        return Err(format!(
            "gaintype {} (a state-dependent gain) is not represented",
            a.gaintype
        ));
    }
    let bias = match a.biastype.as_str() {
        "none" | "" => [0.0; 3],
        "affine" => std::array::from_fn(|i| a.biasprm.get(i).copied().unwrap_or(0.0)),
        other => return Err(format!("biastype {other} is not represented")),
    };
    let g = a.gear;
    let a0 = a.gainprm.first().copied().unwrap_or(1.0);
    // `+ 0.0` turns a −0 (from a zero bias) into 0 for the report and scene.
    let s = Servo {
        k: -g * g * bias[1] + 0.0,
        c: -g * g * bias[2] + 0.0,
        f: g * (a0 * u + bias[0]) + 0.0,
    };
    if s.k < 0.0 || s.c < 0.0 {
        return Err(format!(
            "negative stiffness {} or damping {} is not represented",
            s.k, s.c
        ));
    }
    if s.k == 0.0 && s.f != 0.0 {
        return Err(format!(
            "at rest (u = {u}) it applies the constant force g·(gainprm₀·u + biasprm₀) = {}, and the scene has no torque-input channel",
            s.f
        ));
    }
    if s.k == 0.0 && s.c == 0.0 {
        return Err(
            "no force at rest (ctrl 0), and the scene has no torque-input channel for the force it would apply under control".into(),
        );
    }
    Ok((joint, s))
}

/// `forcerange` and `ctrlrange` lines of a mapped actuator.
fn limit_notes(a: &DumpActuator, u: f64, notes: &mut Vec<String>) {
    if let Some([lo, hi]) = a.forcerange {
        notes.push(format!(
            "actuator \"{}\": forcerange [{lo}, {hi}] not represented (the scene's PD force is not clamped)",
            a.name
        ));
    }
    if let Some([lo, hi]) = a.ctrlrange {
        notes.push(format!(
            "actuator \"{}\": ctrlrange [{lo}, {hi}] gives the control at rest u = {u}; it does not clamp targets set in the scene later",
            a.name
        ));
    }
}

/// Units of stiffness, damping and force on a hinge (else a slide).
fn units(kind: Option<&str>) -> (&'static str, &'static str, &'static str) {
    if kind == Some("slide") {
        ("N/m", "N·s/m", "N")
    } else {
        ("N·m/rad", "N·m·s/rad", "N·m")
    }
}

/// Where the actuator acts, for its report line.
fn on(a: &DumpActuator) -> String {
    match (&a.joint, &a.target) {
        (Some(j), _) => format!("on joint \"{j}\""),
        (None, Some(t)) => format!("with {} transmission \"{t}\"", a.transmission),
        (None, None) => format!("with {} transmission", a.transmission),
    }
}

/// The actuator as the report names it: kind, gear, gains, control range.
fn describe(a: &DumpActuator) -> String {
    let mut what = format!("{}, gear {}", a.kind, a.gear);
    if let Some(kp) = a.kp {
        what.push_str(&format!(", kp {kp}"));
    }
    if let Some(kv) = a.kv {
        what.push_str(&format!(", kv {kv}"));
    }
    if a.kind == "general" {
        what.push_str(&format!(
            ", dyntype {}, gaintype {} gainprm {:?}, biastype {} biasprm {:?}",
            a.dyntype, a.gaintype, a.gainprm, a.biastype, a.biasprm
        ));
    }
    if let Some([lo, hi]) = a.ctrlrange {
        what.push_str(&format!(", ctrlrange [{lo}, {hi}]"));
    }
    what
}
