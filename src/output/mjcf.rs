//! A scene's robots as MJCF (`sdrs export-mjcf`), for MuJoCo.
//!
//! Same kinematics, masses, centres of mass and inertias as the simulated
//! model (MuJoCo's `mj_fullM` of the written model equals
//! [`crate::sim::mass_matrix::mass_matrix`]; `tests/export_mjcf.rs`):
//! - every link is a body nested under its parent, at its attachment
//!   `C_i` (`pos`, `quat` in the parent body's frame); environment links
//!   (ground, obstacles) are bodies of the world without joints;
//! - `revolute` → `hinge`, `prismatic` → `slide` (axis in the body frame,
//!   anchor at the body origin, as `A_i = A_parent C_i J_i(θ)`), `ball`
//!   (two hinges) → two hinges `NAME_0`, `NAME_1` on the body, `spherical` →
//!   `ball`, `free` → `freejoint` (the body's pose is then `C_i J_i(θ⁰)`:
//!   MuJoCo's free coordinates are world poses), `fixed` → no joint;
//! - inertial: mass, COM and full inertia tensor of the link's mass model
//!   at the current design (`vertices`, `solid` or `given`), with
//!   `inertiafromgeom="false"`; a moving massless link gets a stand-in of
//!   1e-12 kg (MuJoCo refuses massless moving bodies; noted in a comment);
//! - every hull is a mesh geom (MuJoCo collides meshes as their convex
//!   hulls, which is what a hull is); links without contact, and every
//!   link of a scene without `contact:`, get `contype = conaffinity = 0`;
//!   excluded pairs become `<exclude>`;
//! - the initial state as keyframe `initial`, limits as `range`, the joint
//!   effects `joint_damping`, `armature`, `joint_friction`, `joint_spring`
//!   as `damping`, `armature`, `frictionloss`, `stiffness` + `springref`
//!   (a `stribeck_friction`'s Coulomb level adds to `frictionloss`; its
//!   breakaway excess is untranslated);
//!   contact `μ` (with a `contact_mu` effect applied) as the geoms' sliding
//!   friction; `payload` and `link_mass_scale` effects in the bodies'
//!   `inertial` (second moments `M₂ ← σ M₂ + m_p [p pᵀ, p; pᵀ, 1]`:
//!   mass, centre of mass and inertia of the link with its point payload
//!   `m_p` at `p`, link frame).
//!
//! Not translated (MuJoCo has its own): the SDRS barrier and friction
//! smoothing, PD controllers (unless asked for: [`pd_actuators`],
//! `--actuators`), mimic ties, the calibration effects listed by
//! [`untranslated`] (actuator gain and delay; encoder offsets; the
//! barrier's `κ` and `s`).

use crate::energy::effects::{EffectKind, Target};
use crate::math::{Pose, rot};
use crate::model::{Inertial, JointKind};
use crate::scene::Scene;
use nalgebra::{Matrix3, Matrix4, UnitQuaternion, Vector3};
use std::fmt::Write;

/// Mass (kg) and principal moments (kg m²) written for a massless link:
/// MuJoCo refuses moving bodies whose mass or inertia is below its
/// `mjMINVAL` (1e-15). Its effect on the mass matrix is ~1e-12 relative.
pub const MASSLESS_STANDIN: f64 = 1e-12;

fn f(x: f64) -> String {
    format!("{x}")
}

fn v3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

fn quat(r: &Matrix3<f64>) -> String {
    let q = UnitQuaternion::from_matrix(r);
    format!("{} {} {} {}", q.w, q.i, q.j, q.k)
}

fn pose_attrs(a: &Pose) -> String {
    format!(
        "pos=\"{}\" quat=\"{}\"",
        v3(&a.column(3).into_owned()),
        quat(&rot(a))
    )
}

/// The MJCF text of `scene` (all robots, objects and environment), without
/// actuators.
pub fn scene_to_mjcf(scene: &Scene, model_name: &str) -> String {
    scene_to_mjcf_with(scene, model_name, false)
}

/// [`scene_to_mjcf`]; with `actuators`, the PD channels as MuJoCo actuators
/// ([`pd_actuators`], `sdrs export-mjcf --actuators`).
pub fn scene_to_mjcf_with(scene: &Scene, model_name: &str, actuators: bool) -> String {
    let model = &scene.model;
    let mut x = String::new();
    let _ = writeln!(
        x,
        "<!-- Written by `sdrs export-mjcf` from {} (see src/output/mjcf.rs for what is translated). -->",
        scene.source.display()
    );
    let _ = writeln!(x, "<mujoco model=\"{model_name}\">");
    let _ = writeln!(
        x,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\" autolimits=\"true\"/>"
    );
    let g = scene.settings.gravity;
    let _ = writeln!(
        x,
        "  <option timestep=\"{}\" gravity=\"{}\"/>",
        scene.settings.dt,
        v3(&g)
    );
    // Joint effects by coordinate: damping, armature, friction, Σk, Σk·r
    // (springs on one coordinate add up to one spring of stiffness Σk at
    // rest Σk·r / Σk, the same energy up to a constant).
    let mut joint_effect = vec![[0.0f64; 5]; model.ndof()];
    for e in &scene.spec.effects {
        let slot = match e.effect {
            EffectKind::JointDamping => 0,
            EffectKind::Armature => 1,
            // A Stribeck friction's Coulomb level (`values[0]`); its
            // excess is listed as untranslated.
            EffectKind::JointFriction | EffectKind::StribeckFriction => 2,
            EffectKind::JointSpring => 3,
            _ => continue,
        };
        for (k, d) in model.dofs.iter().enumerate() {
            let one = matches!(
                model.links[d.link].joint,
                JointKind::Revolute { .. } | JointKind::Prismatic { .. } | JointKind::Ball { .. }
            );
            let bare = d.name.rsplit_once('/').map(|(_, n)| n).unwrap_or(&d.name);
            if one && (e.on == "all" || e.on == d.name || e.on == bare) {
                joint_effect[k][slot] += e.values[0];
                if slot == 3 {
                    joint_effect[k][4] += e.values[0] * e.values[1];
                }
            }
        }
    }
    let mu = scene
        .contact
        .as_ref()
        .map(|c| crate::scene::contact_settings(&scene.effects, c.clone()).mu)
        .unwrap_or(0.0);
    // Meshes.
    let _ = writeln!(x, "  <asset>");
    for (i, l) in model.links.iter().enumerate() {
        for (h, hull) in l.hulls.iter().enumerate() {
            let verts: Vec<String> = hull.x_local.iter().map(v3).collect();
            let _ = writeln!(
                x,
                "    <mesh name=\"m{i}_{h}\" vertex=\"{}\"/>",
                verts.join("  ")
            );
        }
    }
    let _ = writeln!(x, "  </asset>");
    let _ = writeln!(x, "  <worldbody>");
    let roots: Vec<usize> = (0..model.links.len())
        .filter(|&i| model.links[i].parent.is_none())
        .collect();
    let mut bodies = BodyWriter {
        scene,
        mu,
        joint_effect: &joint_effect,
        key_qpos: Vec::new(),
        x,
    };
    for r in roots {
        bodies.body(r, 2);
    }
    let (key_qpos, mut x) = (bodies.key_qpos, bodies.x);
    let _ = writeln!(x, "  </worldbody>");
    if let Some(c) = &scene.contact {
        let pairs: Vec<_> = c
            .excluded
            .iter()
            .filter(|(a, b)| {
                model.links[*a].parent != Some(*b) && model.links[*b].parent != Some(*a)
            })
            .collect();
        if !pairs.is_empty() {
            let _ = writeln!(x, "  <contact>");
            for (a, b) in pairs {
                let _ = writeln!(
                    x,
                    "    <exclude body1=\"{}\" body2=\"{}\"/>",
                    body_name(scene, *a),
                    body_name(scene, *b)
                );
            }
            let _ = writeln!(x, "  </contact>");
        }
    }
    let mut ctrl_attr = String::new();
    if actuators {
        let (block, ctrl) = pd_actuators(scene);
        x.push_str(&block);
        if !ctrl.is_empty() {
            let c: Vec<String> = ctrl.iter().map(|v| f(*v)).collect();
            ctrl_attr = format!(" ctrl=\"{}\"", c.join(" "));
        }
    }
    let q: Vec<String> = key_qpos.iter().map(|v| f(*v)).collect();
    let _ = writeln!(x, "  <keyframe>");
    let _ = writeln!(
        x,
        "    <key name=\"initial\" qpos=\"{}\"{ctrl_attr}/>",
        q.join(" ")
    );
    let _ = writeln!(x, "  </keyframe>");
    let _ = writeln!(x, "</mujoco>");
    x
}

/// The `<actuator>` block of the scene's PD channels and the controls of
/// keyframe `initial`: the inverse of the MJCF import's mapping
/// (`crate::import::mjcf::actuators`). A channel on a hinge or slide with a
/// constant target `θ*` exerts `τ = 2 k_p (θ* − θ) − (2 k_d/Δt) θ̇`
/// (`crate::energy::pd`), which is MuJoCo's `<position kp="2 k_p"
/// kv="2 k_d/Δt">` (gear 1) at `ctrl = θ*`, or `<velocity kv="2 k_d/Δt">`
/// at `ctrl = 0` when `k_p = 0`. Other channels (time-varying targets,
/// multi-coordinate joints, the free root's pose target) are listed in a
/// comment, not written. Actuator gain and delay effects are not applied
/// (see [`untranslated`]).
pub fn pd_actuators(scene: &Scene) -> (String, Vec<f64>) {
    let model = &scene.model;
    let dt = scene.settings.dt;
    let mut x = String::from("  <actuator>\n");
    let mut ctrl = Vec::new();
    for ch in &scene.controller.channels {
        let link = model.dofs[ch.dof].link;
        let jn = joint_name(scene, link);
        let one_dof = matches!(
            model.links[link].joint,
            JointKind::Revolute { .. } | JointKind::Prismatic { .. }
        );
        let (kp, kv) = (2.0 * ch.kp, 2.0 * ch.kd / dt);
        match (&ch.signal, one_dof) {
            (crate::control::Signal::Constant { value }, true) if kp > 0.0 => {
                let _ = writeln!(
                    x,
                    "    <position name=\"pd_{jn}\" joint=\"{jn}\" kp=\"{kp}\" kv=\"{kv}\"/>"
                );
                ctrl.push(*value);
            }
            (crate::control::Signal::Constant { .. }, true) => {
                let _ = writeln!(
                    x,
                    "    <velocity name=\"pd_{jn}\" joint=\"{jn}\" kv=\"{kv}\"/>"
                );
                ctrl.push(0.0);
            }
            (_, true) => {
                let _ = writeln!(
                    x,
                    "    <!-- PD on \"{jn}\" not written: its target is not constant -->"
                );
            }
            (_, false) => {
                let _ = writeln!(
                    x,
                    "    <!-- PD on \"{}\" not written: only hinge and slide coordinates -->",
                    model.dofs[ch.dof].name
                );
            }
        }
    }
    if ctrl.is_empty() && scene.controller.channels.is_empty() {
        return (String::new(), ctrl);
    }
    x.push_str("  </actuator>\n");
    (x, ctrl)
}

/// Link `i`'s second moments (link frame) with the scene's
/// `link_mass_scale` (`σ`, factors multiply) and `payload` (`m_p` at `p`)
/// effects: `σ M₂ + Σ m_p [p pᵀ, p; pᵀ, 1]`.
fn second_moment_with_effects(scene: &Scene, i: usize) -> Matrix4<f64> {
    let mut scale = 1.0;
    let mut extra = Matrix4::zeros();
    for e in &scene.effects {
        let Target::Links(l) = &e.target else {
            continue;
        };
        if !l.contains(&i) {
            continue;
        }
        match e.kind {
            EffectKind::LinkMassScale => scale *= e.values[0],
            EffectKind::Payload => {
                let p = nalgebra::Vector4::new(e.values[1], e.values[2], e.values[3], 1.0);
                extra += e.values[0] * p * p.transpose();
            }
            _ => {}
        }
    }
    scene.model.second_moment[i] * scale + extra
}

/// The scene's effects that have no MuJoCo equivalent in this writer, each
/// as `(effect/on, why)`.
pub fn untranslated(scene: &Scene) -> Vec<(String, String)> {
    scene
        .spec
        .effects
        .iter()
        .filter_map(|e| {
            let why = match e.effect {
                EffectKind::ActuatorGain => {
                    "the PD controller is not written (no actuators); scale the controller's gains by this factor"
                }
                EffectKind::ActuationDelay => {
                    "no actuators are written; MuJoCo has no actuation delay attribute"
                }
                EffectKind::JointOffset => "an encoder offset is on the measurement side, not the model",
                EffectKind::StribeckFriction => {
                    "its Coulomb level is written as frictionloss; MuJoCo has no attribute for the breakaway excess"
                }
                EffectKind::ActuatorDeadband => {
                    "no actuators are written; MuJoCo has no actuator deadband attribute"
                }
                EffectKind::ContactKappa | EffectKind::ContactS => {
                    "a parameter of the SDRS contact barrier; MuJoCo's contacts are soft constraints (solref/solimp)"
                }
                _ => return None,
            };
            Some((format!("{}/{}", e.effect.name(), e.on), why.to_string()))
        })
        .collect()
}

/// MuJoCo body name of link `i`: `robot/link` when the scene has several
/// robots (as in trajectory columns), else the link name.
pub fn body_name(scene: &Scene, i: usize) -> String {
    scoped(scene, i, &scene.model.links[i].name)
}

/// MuJoCo joint name of link `i`'s joint (as in trajectory columns).
fn joint_name(scene: &Scene, i: usize) -> String {
    scoped(scene, i, &scene.model.links[i].joint_name)
}

/// `name` prefixed by link `i`'s robot when the scene has several robots.
fn scoped(scene: &Scene, i: usize, name: &str) -> String {
    let m = &scene.model;
    if m.robots.len() > 1 {
        format!("{}/{name}", m.robots[m.links[i].robot].name)
    } else {
        name.to_string()
    }
}

/// The `<worldbody>` writer: each body with its joints, inertial and geoms,
/// its children nested inside; the joints' initial values collected for
/// the `<key>`.
struct BodyWriter<'a> {
    scene: &'a Scene,
    /// Ground friction written on every geom.
    mu: f64,
    /// Per coordinate: damping, armature, friction loss, stiffness and
    /// stiffness × reference (the fitted joint effects).
    joint_effect: &'a [[f64; 5]],
    /// `qpos` of the `<key>`, in MuJoCo's order.
    key_qpos: Vec<f64>,
    x: String,
}

impl BodyWriter<'_> {
    /// Link `i` and its subtree, indented by `depth`.
    fn body(&mut self, i: usize, depth: usize) {
        let scene = self.scene;
        let l = &scene.model.links[i];
        let pad = "  ".repeat(depth);
        // A free body's frame is its world pose at θ⁰.
        let frame = if matches!(l.joint, JointKind::Free) {
            let c = scene.charts[l.chart.expect("free joints have a chart")];
            let o = l.dof_offset;
            let j = l.joint.transform(&c, &scene.q0.as_slice()[o..o + 6]);
            crate::math::compose(&l.attach, &j)
        } else {
            l.attach
        };
        let _ = writeln!(
            self.x,
            "{pad}<body name=\"{}\" {}>",
            body_name(scene, i),
            pose_attrs(&frame)
        );
        self.joints(i, &pad, &frame);
        self.inertial(i, &pad);
        self.geoms(i, &pad);
        let model = &scene.model;
        for c in (0..model.links.len()).filter(|&c| model.links[c].parent == Some(i)) {
            self.body(c, depth + 1);
        }
        let _ = writeln!(self.x, "{pad}</body>");
    }

    /// The fitted joint effects of coordinate `k` as joint attributes.
    fn extras(&self, k: usize) -> String {
        let [d, a, fl, sk, skr] = self.joint_effect[k];
        let mut s = String::new();
        if d > 0.0 {
            let _ = write!(s, " damping=\"{d}\"");
        }
        if a > 0.0 {
            let _ = write!(s, " armature=\"{a}\"");
        }
        if fl > 0.0 {
            let _ = write!(s, " frictionloss=\"{fl}\"");
        }
        if sk > 0.0 {
            let _ = write!(s, " stiffness=\"{sk}\" springref=\"{}\"", skr / sk);
        }
        s
    }

    /// Link `i`'s joint (a ball joint as three hinges on its axes) and its
    /// initial value in the key (`frame`: the body's frame, for a free joint).
    fn joints(&mut self, i: usize, pad: &str, frame: &Pose) {
        let scene = self.scene;
        let l = &scene.model.links[i];
        let (o, q0) = (l.dof_offset, &scene.q0);
        let jn = joint_name(scene, i);
        match &l.joint {
            JointKind::Fixed => {}
            JointKind::Revolute { axis } | JointKind::Prismatic { axis } => {
                let t = if matches!(l.joint, JointKind::Revolute { .. }) {
                    "hinge"
                } else {
                    "slide"
                };
                let range = l
                    .limit
                    .as_ref()
                    .map(|lim| format!(" range=\"{} {}\"", lim.lower, lim.upper))
                    .unwrap_or_default();
                let extras = self.extras(o);
                let _ = writeln!(
                    self.x,
                    "{pad}  <joint name=\"{jn}\" type=\"{t}\" axis=\"{}\"{range}{extras}/>",
                    v3(axis),
                );
                self.key_qpos.push(q0[o]);
            }
            JointKind::Ball { axes } => {
                for (k, a) in axes.iter().enumerate() {
                    let extras = self.extras(o + k);
                    let _ = writeln!(
                        self.x,
                        "{pad}  <joint name=\"{jn}_{k}\" type=\"hinge\" axis=\"{}\"{extras}/>",
                        v3(a),
                    );
                    self.key_qpos.push(q0[o + k]);
                }
            }
            JointKind::Spherical => {
                let _ = writeln!(self.x, "{pad}  <joint name=\"{jn}\" type=\"ball\"/>");
                let c = scene.charts[l.chart.expect("spherical joints have a chart")];
                let j = l.joint.transform(&c, &q0.as_slice()[o..o + 3]);
                let u = UnitQuaternion::from_matrix(&rot(&j));
                self.key_qpos.extend([u.w, u.i, u.j, u.k]);
            }
            JointKind::Free => {
                let _ = writeln!(self.x, "{pad}  <freejoint name=\"{jn}\"/>");
                let u = UnitQuaternion::from_matrix(&rot(frame));
                self.key_qpos
                    .extend([frame[(0, 3)], frame[(1, 3)], frame[(2, 3)]]);
                self.key_qpos.extend([u.w, u.i, u.j, u.k]);
            }
        }
    }

    /// Link `i`'s mass properties (with the fitted effects); a stand-in mass
    /// on a massless moving body, which MuJoCo rejects.
    fn inertial(&mut self, i: usize, pad: &str) {
        let scene = self.scene;
        let m2 = second_moment_with_effects(scene, i);
        if m2[(3, 3)] > 0.0 {
            let inr = Inertial::from_second_moment(&m2);
            let t = &inr.inertia;
            let _ = writeln!(
                self.x,
                "{pad}  <inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{} {} {} {} {} {}\"/>",
                v3(&inr.com),
                inr.mass,
                t[(0, 0)],
                t[(1, 1)],
                t[(2, 2)],
                t[(0, 1)],
                t[(0, 2)],
                t[(1, 2)]
            );
        } else if !scene.model.ancestor_dofs[i].is_empty() {
            let _ = writeln!(
                self.x,
                "{pad}  <!-- massless in sdrs; MuJoCo needs a mass on moving bodies -->"
            );
            let _ = writeln!(
                self.x,
                "{pad}  <inertial pos=\"0 0 0\" mass=\"{MASSLESS_STANDIN}\" diaginertia=\"{0} {0} {0}\"/>",
                MASSLESS_STANDIN
            );
        }
    }

    /// One mesh geom per hull of link `i`.
    fn geoms(&mut self, i: usize, pad: &str) {
        let scene = self.scene;
        let l = &scene.model.links[i];
        // A scene without `contact:` simulates none: MuJoCo must not either.
        let (ct, ca) = if l.collides && scene.contact.is_some() {
            (1, 1)
        } else {
            (0, 0)
        };
        let mu = self.mu;
        for h in 0..l.hulls.len() {
            let _ = writeln!(
                self.x,
                "{pad}  <geom type=\"mesh\" mesh=\"m{i}_{h}\" contype=\"{ct}\" conaffinity=\"{ca}\" friction=\"{mu} 0.005 0.0001\"/>"
            );
        }
    }
}
