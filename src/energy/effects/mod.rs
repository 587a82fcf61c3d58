//! The library of candidate effects that calibration can add to a model.
//!
//! Each effect is either a term of the step objective (paper, eq. `SDRS`)
//! behind the [`Energy`] trait — [`damping`], [`coulomb`], [`stribeck`]
//! (Coulomb level and breakaway excess), [`armature`], [`extra_mass`]
//! (payload, link mass scale), [`deadband`]
//! (a correction of the PD term) — or a parameter of an existing
//! part of the model — [`gain`] (controller gains), [`delay`] (actuation delay), [`crate::contact::params`]
//! (`μ`, `κ`, `s`) — or of the measurement — [`offset`] (encoder bias).
//! Every parameter has an adjoint gradient: energy terms write
//! `∂Φ/∂p` into the generic effect channel of the adjoint pass
//! ([`crate::diff::VjpAccumulator::effect`], by parameter *slot*), the
//! others map existing gradients ([`crate::diff::effects::gradient`]).
//!
//! Layering: the terms and their data live here (`energy`); installing them
//! into a simulator is [`crate::sim::effects::install`], applying the contact
//! parameters to a scene's settings is [`crate::scene::contact_settings`], and
//! the contact parameters themselves are [`crate::contact::params`].
//!
//! Effects appear in scene files under `effects:` (see
//! [`crate::scene::schema`]) as `{effect: NAME, on: TARGET, values: [...]}`
//! where `TARGET` is `all`, a joint coordinate's column name (`hinge`,
//! `arm/elbow`, `j0:1`) or, for link effects, a link (`hand`, `arm/hand`).
//!
//! # Adding an effect
//!
//! Write one file here with an [`Energy`] term: `accumulate` adds its value,
//! `dof_grad`/`dof_hess` (coordinates) or `link_grad`/`link_hess`/
//! `link_moment` (pose space), and `vjp` adds `∂Φ/∂θ^{t−1}`, `∂Φ/∂θ^{t−2}`
//! (or the pose equivalents) and `∂Φ/∂p` through `out.effect(slot)`; put
//! the formula and units in its module doc, and a finite-difference test in
//! `tests/calibrate_effects.rs`. Then add a variant to [`EffectKind`] (its
//! name, parameter names, scope, neutral value and bounds below) and one arm
//! in [`crate::sim::effects::install`]. Fitting, ranking, outputs and the scene schema pick it up.

pub mod armature;
pub mod coulomb;
pub mod damping;
pub mod deadband;
pub mod delay;
pub mod extra_mass;
pub mod gain;
pub mod offset;
pub mod spring;
pub mod stribeck;

use crate::model::Model;
use serde::{Deserialize, Serialize};

/// Every effect of the library, by its documented name.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// Viscous joint damping `c` (N·m·s/rad): [`damping`].
    JointDamping,
    /// Smoothed Coulomb joint friction `f` (N·m): [`coulomb`].
    JointFriction,
    /// Rotor inertia `a` (kg·m²): [`armature`].
    Armature,
    /// Actuator gain `g` (scale of `k_p`, `k_d`): [`gain`].
    ActuatorGain,
    /// Encoder bias `b` (rad or m): [`offset`].
    JointOffset,
    /// Point mass `m` (kg) at `p` (m, link frame): [`extra_mass`].
    Payload,
    /// Scale `σ` of a link's mass: [`extra_mass`].
    LinkMassScale,
    /// Contact friction coefficient `μ`: [`crate::contact::params`].
    ContactMu,
    /// Barrier stiffness `κ` (J·m): [`crate::contact::params`].
    ContactKappa,
    /// Barrier support `s` (m): [`crate::contact::params`].
    ContactS,
    /// Joint spring: stiffness `k` (N·m/rad) and rest value `r` (rad):
    /// [`spring`] (MuJoCo's `stiffness`, `springref`). Not a calibration
    /// candidate (not in [`EffectKind::ALL`]): a model property the import
    /// writes.
    JointSpring,
    /// Actuation delay `d` (s) of the PD channels: [`delay`].
    ActuationDelay,
    /// Stribeck joint friction: Coulomb level `f_c` and breakaway excess
    /// `Δf` (N·m): [`stribeck`]. Offered when named (not in
    /// [`EffectKind::ALL`]): [`EffectKind::OPT_IN`].
    StribeckFriction,
    /// Deadband half-width `b` (rad or m) of the PD position error:
    /// [`deadband`]. Offered when named: [`EffectKind::OPT_IN`].
    ActuatorDeadband,
}

/// What an effect acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    /// Joint coordinates (one, or `all` sharing one value).
    Joints,
    /// One link, or `all` links sharing one value.
    Links,
    /// The scene's contact settings (`on: all`).
    Contact,
}

impl EffectKind {
    /// The contact parameter this effect sets, if it is one.
    pub fn contact_param(self) -> Option<crate::contact::params::ContactParam> {
        use crate::contact::params::ContactParam;
        match self {
            EffectKind::ContactMu => Some(ContactParam::Mu),
            EffectKind::ContactKappa => Some(ContactParam::Kappa),
            EffectKind::ContactS => Some(ContactParam::S),
            _ => None,
        }
    }

    pub const ALL: [EffectKind; 11] = [
        EffectKind::JointDamping,
        EffectKind::JointFriction,
        EffectKind::Armature,
        EffectKind::ActuatorGain,
        EffectKind::JointOffset,
        EffectKind::Payload,
        EffectKind::LinkMassScale,
        EffectKind::ContactMu,
        EffectKind::ContactKappa,
        EffectKind::ContactS,
        EffectKind::ActuationDelay,
    ];

    /// Calibration candidates offered only when named (`--effects`,
    /// [`crate::calibrate::CalibrateOptions::effects`]): effects added after
    /// the hidden-effect and clean-data suites were tuned on
    /// [`EffectKind::ALL`]. Both are fitted and ranked like the others.
    pub const OPT_IN: [EffectKind; 2] =
        [EffectKind::StribeckFriction, EffectKind::ActuatorDeadband];

    /// The documented name (as in scene files and `calibration.json`).
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::JointDamping => "joint_damping",
            EffectKind::JointFriction => "joint_friction",
            EffectKind::Armature => "armature",
            EffectKind::ActuatorGain => "actuator_gain",
            EffectKind::JointOffset => "joint_offset",
            EffectKind::Payload => "payload",
            EffectKind::LinkMassScale => "link_mass_scale",
            EffectKind::ContactMu => "contact_mu",
            EffectKind::ContactKappa => "contact_kappa",
            EffectKind::ContactS => "contact_s",
            EffectKind::JointSpring => "joint_spring",
            EffectKind::ActuationDelay => "actuation_delay",
            EffectKind::StribeckFriction => "stribeck_friction",
            EffectKind::ActuatorDeadband => "actuator_deadband",
        }
    }

    /// The calibration candidate of that name (one of [`EffectKind::ALL`]
    /// or [`EffectKind::OPT_IN`]).
    pub fn from_name(s: &str) -> Option<EffectKind> {
        Self::ALL
            .into_iter()
            .chain(Self::OPT_IN)
            .find(|k| k.name() == s)
    }

    pub fn scope(self) -> Scope {
        match self {
            EffectKind::Payload | EffectKind::LinkMassScale => Scope::Links,
            EffectKind::ContactMu | EffectKind::ContactKappa | EffectKind::ContactS => {
                Scope::Contact
            }
            _ => Scope::Joints,
        }
    }

    /// Names of the parameters (suffixes in `calibration.json`; empty for a
    /// single parameter).
    pub fn param_names(self) -> &'static [&'static str] {
        match self {
            EffectKind::Payload => &["mass", "x", "y", "z"],
            EffectKind::JointSpring => &["stiffness", "springref"],
            EffectKind::StribeckFriction => &["coulomb", "excess"],
            _ => &[""],
        }
    }

    /// SI unit of each parameter, for reports.
    pub fn units(self) -> &'static [&'static str] {
        match self {
            EffectKind::JointDamping => &["N·m·s/rad"],
            EffectKind::JointFriction => &["N·m"],
            EffectKind::StribeckFriction => &["N·m", "N·m"],
            EffectKind::Armature => &["kg·m²"],
            EffectKind::ActuatorGain | EffectKind::LinkMassScale | EffectKind::ContactMu => &["1"],
            EffectKind::JointOffset | EffectKind::ActuatorDeadband => &["rad"],
            EffectKind::Payload => &["kg", "m", "m", "m"],
            EffectKind::ContactKappa => &["J·m"],
            EffectKind::ContactS => &["m"],
            EffectKind::JointSpring => &["N·m/rad", "rad"],
            EffectKind::ActuationDelay => &["s"],
        }
    }

    /// Whether the effect changes the simulated trajectory (all but the
    /// measurement-side offset).
    pub fn is_dynamic(self) -> bool {
        self != EffectKind::JointOffset
    }

    /// Checks one parameter value; `Err` explains the admissible range.
    pub fn check(self, k: usize, v: f64) -> Result<(), String> {
        let ok = v.is_finite()
            && match (self, k) {
                (EffectKind::ActuatorGain | EffectKind::LinkMassScale, _) => v > 0.0,
                (EffectKind::ContactKappa, _) => v > 0.0,
                (EffectKind::ContactS, _) => v > 0.0 && v < 1.0,
                (EffectKind::JointOffset, _)
                | (EffectKind::Payload, 1..)
                | (EffectKind::JointSpring, 1) => true,
                _ => v >= 0.0,
            };
        if ok {
            Ok(())
        } else {
            Err(format!(
                "{}{} must be {}, got {v}",
                self.name(),
                match self.param_names()[k] {
                    "" => String::new(),
                    n => format!(".{n}"),
                },
                match self {
                    EffectKind::ActuatorGain
                    | EffectKind::LinkMassScale
                    | EffectKind::ContactKappa => "finite and > 0",
                    EffectKind::ContactS => "in (0, 1)",
                    EffectKind::JointOffset | EffectKind::Payload | EffectKind::JointSpring
                        if k > 0 =>
                    {
                        "finite"
                    }
                    _ => "finite and ≥ 0",
                }
            ))
        }
    }
}

/// An effect as written in a scene file (`effects:` section).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EffectSpec {
    /// The effect's name ([`EffectKind::name`]).
    pub effect: EffectKind,
    /// `all` (default), a joint coordinate's column name, or a link name.
    #[serde(default = "EffectSpec::default_on")]
    pub on: String,
    /// Parameter values (SI; payload: `[mass, x, y, z]`).
    pub values: Vec<f64>,
    /// Joint and Stribeck friction only: velocity smoothing `ε`
    /// ((rad/s)²). Default [`coulomb::DEFAULT_EPS`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps: Option<f64>,
}

impl EffectSpec {
    fn default_on() -> String {
        "all".into()
    }
}

/// What a resolved effect acts on.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// Joint coordinates (indices into `θ`), sharing the value.
    Dofs(Vec<usize>),
    /// Links, sharing the value.
    Links(Vec<usize>),
    /// The contact settings.
    Contact,
}

/// A validated effect bound to a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Effect {
    pub kind: EffectKind,
    /// The target as written (`all`, a column name, a link name).
    pub on: String,
    pub target: Target,
    pub values: Vec<f64>,
    /// Joint (and Stribeck) friction smoothing `ε`.
    pub eps: f64,
    /// Index of the first parameter in the effect-parameter vector (the
    /// slot of [`crate::diff::VjpAccumulator::effect`]).
    pub slot: usize,
}

/// Coordinates and coefficients of a per-coordinate term, with the
/// effect-parameter slot of each coefficient.
#[derive(Clone, Debug, Default)]
pub struct JointCoeffs {
    pub dofs: Vec<usize>,
    pub values: Vec<f64>,
    pub slots: Vec<Option<usize>>,
}

impl JointCoeffs {
    /// `(coordinate, coefficient, slot)`.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64, Option<usize>)> + '_ {
        self.dofs
            .iter()
            .zip(&self.values)
            .zip(&self.slots)
            .map(|((k, v), s)| (*k, *v, *s))
    }

    /// Adds `Σ_k ½ c_k w s_k²` with `s_k = stencil(k)` (a finite difference
    /// of coordinate `k` whose derivative w.r.t. `θ_k` is 1) and its
    /// diagonal gradient `c_k w s_k` and Hessian `c_k w` — the shape of the
    /// damping (`s = θ − θ^t`, `w = 1/Δt`) and armature (`s = θ − 2θ^t +
    /// θ^{t−1}`, `w = 1/Δt²`) terms.
    pub fn accumulate_diagonal_quadratic(
        &self,
        w: f64,
        stencil: impl Fn(usize) -> f64,
        need: crate::energy::Need,
        acc: &mut crate::energy::EnergyAccumulator,
    ) {
        use crate::energy::Need;
        for (k, c, _) in self.iter() {
            let s = stencil(k);
            acc.value += 0.5 * c * s * s * w;
            if need >= Need::Gradient {
                acc.dof_grad[k] += c * s * w;
            }
            if need >= Need::Hessian {
                acc.dof_hess[(k, k)] += c * w;
            }
        }
    }

    /// One shared value on `dofs`, differentiated into `slot`.
    pub fn shared(dofs: &[usize], value: f64, slot: usize) -> Self {
        JointCoeffs {
            dofs: dofs.to_vec(),
            values: vec![value; dofs.len()],
            slots: vec![Some(slot); dofs.len()],
        }
    }
}

/// Coordinates an effect on joints may act on: those of revolute,
/// prismatic and ball joints (not the charted rotations of spherical and
/// free joints).
pub fn joint_dofs(model: &Model) -> Vec<usize> {
    (0..model.ndof())
        .filter(|&k| !model.links[model.dofs[k].link].joint.has_chart())
        .collect()
}

/// A link's name as used in `on:` (`link`, or `robot/link` with several
/// robots or objects).
pub fn link_label(model: &Model, i: usize) -> String {
    let l = &model.links[i];
    if model.robots.len() > 1 {
        format!("{}/{}", model.robots[l.robot].name, l.name)
    } else {
        l.name.clone()
    }
}

/// Links with mass that can move (some coordinate moves them; static
/// obstacles and the ground are excluded).
pub fn massive_links(model: &Model) -> Vec<usize> {
    (0..model.links.len())
        .filter(|&i| model.first_moment[i][3] > 0.0 && !model.ancestor_dofs[i].is_empty())
        .collect()
}

/// An effect entry that does not fit the model: the element (`effects[2].on`)
/// and what is wrong. The scene loader attaches the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{element}: {msg}")]
pub struct Invalid {
    pub element: String,
    pub msg: String,
}

impl Invalid {
    pub fn new(element: impl Into<String>, msg: impl Into<String>) -> Self {
        Invalid {
            element: element.into(),
            msg: msg.into(),
        }
    }
}

/// Validates `specs` against `model` (`element` prefixes the messages,
/// e.g. `effects`), assigning parameter slots in order.
pub fn resolve(
    specs: &[EffectSpec],
    model: &Model,
    has_contact: bool,
    element: &str,
) -> Result<Vec<Effect>, Invalid> {
    let mut out = Vec::new();
    let mut slot = 0;
    for (i, s) in specs.iter().enumerate() {
        let el = format!("{element}[{i}]");
        let kind = s.effect;
        let np = kind.param_names().len();
        if s.values.len() != np {
            let names = kind.param_names().join(", ");
            let names = if np > 1 {
                format!(" ({names})")
            } else {
                String::new()
            };
            return Err(Invalid::new(
                format!("{el}.values"),
                format!(
                    "{} takes {np} value(s){names}, got {}",
                    kind.name(),
                    s.values.len()
                ),
            ));
        }
        for (k, v) in s.values.iter().enumerate() {
            kind.check(k, *v)
                .map_err(|m| Invalid::new(format!("{el}.values[{k}]"), m))?;
        }
        let eps = s.eps.unwrap_or(coulomb::DEFAULT_EPS);
        if !(eps > 0.0 && eps.is_finite()) {
            return Err(Invalid::new(
                format!("{el}.eps"),
                format!("must be finite and > 0, got {eps}"),
            ));
        }
        let target = resolve_target(kind, &s.on, model, has_contact)
            .map_err(|m| Invalid::new(format!("{el}.on"), m))?;
        out.push(Effect {
            kind,
            on: s.on.clone(),
            target,
            values: s.values.clone(),
            eps,
            slot,
        });
        slot += np;
    }
    Ok(out)
}

fn resolve_target(
    kind: EffectKind,
    on: &str,
    model: &Model,
    has_contact: bool,
) -> Result<Target, String> {
    match kind.scope() {
        Scope::Joints => {
            let dofs = joint_dofs(model);
            if on == "all" {
                if dofs.is_empty() {
                    return Err("the scene has no revolute, prismatic or ball joints".into());
                }
                return Ok(Target::Dofs(dofs));
            }
            // A coordinate's column name; or, in a scene with several
            // robots, the bare joint name when one robot alone has it.
            let bare: Vec<usize> = dofs
                .iter()
                .copied()
                .filter(|&k| {
                    model.dofs[k]
                        .name
                        .split_once('/')
                        .is_some_and(|(_, j)| j == on)
                })
                .collect();
            dofs.iter()
                .find(|&&k| model.dofs[k].name == on)
                .copied()
                .or(if bare.len() == 1 { Some(bare[0]) } else { None })
                .map(|k| Target::Dofs(vec![k]))
                .ok_or_else(|| {
                    let names: Vec<&str> =
                        dofs.iter().map(|&k| model.dofs[k].name.as_str()).collect();
                    format!(
                        "no joint coordinate \"{on}\" (coordinates: all, {})",
                        names.join(", ")
                    )
                })
        }
        Scope::Links => {
            if on == "all" {
                if kind == EffectKind::Payload {
                    return Err("a payload sits on one named link, not `all`".into());
                }
                return Ok(Target::Links(massive_links(model)));
            }
            (0..model.links.len())
                .find(|&i| link_label(model, i) == on)
                .map(|i| Target::Links(vec![i]))
                .ok_or_else(|| {
                    let names: Vec<String> = (0..model.links.len())
                        .map(|i| link_label(model, i))
                        .collect();
                    format!("no link \"{on}\" (links: {})", names.join(", "))
                })
        }
        Scope::Contact => {
            if !has_contact {
                return Err(format!(
                    "{} needs contact (the scene has no `contact:` section)",
                    kind.name()
                ));
            }
            if on != "all" {
                return Err(format!(
                    "{} acts on the whole scene: use `on: all`",
                    kind.name()
                ));
            }
            Ok(Target::Contact)
        }
    }
}

/// The offsets `(dofs, b)` of measurement-side effects.
pub fn offsets(effects: &[Effect]) -> impl Iterator<Item = (&[usize], f64)> {
    effects.iter().filter_map(|e| match (&e.target, e.kind) {
        (Target::Dofs(d), EffectKind::JointOffset) => Some((d.as_slice(), e.values[0])),
        _ => None,
    })
}

/// Keys of the effect's parameters in `calibration.json`:
/// `<effect>/<on>` or `<effect>/<on>:<param>`.
pub fn param_keys(e: &Effect) -> Vec<String> {
    e.kind
        .param_names()
        .iter()
        .map(|p| {
            if p.is_empty() {
                format!("{}/{}", e.kind.name(), e.on)
            } else {
                format!("{}/{}:{p}", e.kind.name(), e.on)
            }
        })
        .collect()
}

impl Effect {
    /// Back to the scene-file form.
    pub fn spec(&self) -> EffectSpec {
        EffectSpec {
            effect: self.kind,
            on: self.on.clone(),
            values: self.values.clone(),
            eps: matches!(
                self.kind,
                EffectKind::JointFriction | EffectKind::StribeckFriction
            )
            .then_some(self.eps),
        }
    }
}
