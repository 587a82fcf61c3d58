//! Validation of a parsed scene and construction of the model.

use super::schema::*;
use super::{Invalid, Scene, chain, environment};
use crate::control::{ControlChannel, Controller, PoseTarget};
use crate::math::{pose_from, rpy_to_matrix, so3};
use crate::model::{
    Hull, Inertial, JointKind, JointLimit, Link, MassModel, MimicTie, Model, RobotInfo,
};
use crate::sim::SimSettings;
use nalgebra::{DVector, Matrix3, Vector3};
use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

pub(super) fn check_finite(element: &str, what: &str, v: &[f64]) -> Result<(), Invalid> {
    if finite(v) {
        Ok(())
    } else {
        Err(Invalid::new(
            element,
            format!("`{what}` must be finite, got {v:?}"),
        ))
    }
}

/// Builds a scene from its specification.
/// Most degrees of freedom a scene may have: the step Hessian is a dense
/// `|θ|×|θ|` matrix (800 MB at this size).
pub const MAX_DOF: usize = 10_000;

/// Most links one robot (or generated chain) may have.
pub const MAX_LINKS: usize = 10_000;

/// Longest time step a scene may have (s). Every step adds `Δt²·g` and
/// `Δt·q̇` terms to the incremental potential: beyond minutes they carry
/// no meaning for a robot (and at `Δt ≳ 1e154 s`, `Δt²` overflows).
pub const MAX_DT: f64 = 1.0e3;

/// Checks a time step and a step count together: `0 < Δt ≤` [`MAX_DT`],
/// the end time `t_H = H·Δt` finite and still advancing by `Δt` at its end
/// (`t_H + Δt > t_H`, else the `t` column would stall). `steps_key` names
/// where `H` came from (`steps`, or `--steps` on the command line).
pub fn check_duration(dt: f64, steps: usize, steps_key: &str) -> Result<(), Invalid> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(Invalid::new(
            "dt",
            format!("the time step must be positive and finite, got {dt}"),
        ));
    }
    if dt > MAX_DT {
        return Err(Invalid::new(
            "dt",
            format!(
                "a time step of {dt:e} s is physically meaningless for a robot simulation (at most {MAX_DT:e} s)"
            ),
        ));
    }
    let end = dt * steps as f64;
    if !(end.is_finite() && end + dt > end) {
        return Err(Invalid::new(
            steps_key,
            format!(
                "{steps} steps of dt = {dt:e} s end at t = {end:e} s, where time no longer advances by dt in double precision"
            ),
        ));
    }
    Ok(())
}

pub fn build_scene(spec: SceneSpec, path: &Path) -> Result<Scene, Invalid> {
    check_settings(&spec)?;
    let all_robots = environment::expand_bodies(&spec)?;
    let mut seen = HashMap::new();
    for (i, r) in all_robots.iter().enumerate() {
        if let Some(j) = seen.insert(r.name.clone(), i) {
            return Err(Invalid::new(
                format!("robots[{i}]"),
                format!("robot name \"{}\" is already used by robots[{j}]", r.name),
            ));
        }
    }

    let mut links = Vec::new();
    let mut robots = Vec::new();
    for (ri, r) in all_robots.iter().enumerate() {
        let first = links.len();
        build_robot(ri, r, &mut links)?;
        robots.push(RobotInfo {
            name: r.name.clone(),
            links: first..links.len(),
        });
    }
    let mut model = Model::new(links, robots);
    if model.ndof() > MAX_DOF {
        return Err(Invalid::new(
            "robots",
            format!(
                "the scene has {} degrees of freedom; the maximum is {MAX_DOF} (the step Hessian is a dense |θ|×|θ| matrix: {:.1} GB here)",
                model.ndof(),
                (model.ndof() as f64).powi(2) * 8e-9
            ),
        ));
    }

    // Controller and initial state, by joint name per robot.
    let n = model.ndof();
    let mut q0 = DVector::zeros(n);
    let mut qdot0 = DVector::zeros(n);
    let mut charts = vec![Matrix3::identity(); model.nchart];
    let mut controller = Controller::default();
    for (ri, r) in all_robots.iter().enumerate() {
        let rj = RobotJoints::new(&r.name, &model, ri);
        add_targets(r, &rj, &model, &mut controller)?;
        set_initial(r, &rj, &model, &mut q0, &mut qdot0, &mut charts)?;
    }
    model.mimics = mimic_ties(&all_robots, &model, &mut q0, &mut qdot0)?;
    check_initial_limits(&model, &q0)?;
    let contact = spec
        .contact
        .as_ref()
        .map(|c| environment::contact_settings(c, &model))
        .transpose()?;
    let effects =
        crate::energy::effects::resolve(&spec.effects, &model, contact.is_some(), "effects")?;
    let settings = SimSettings {
        dt: spec.dt,
        gravity: Vector3::from(spec.gravity),
        newton: spec.solver.clone(),
    };
    Ok(Scene {
        source: path.to_path_buf(),
        model,
        settings,
        controller,
        q0,
        qdot0,
        charts,
        steps: spec.steps,
        contact,
        effects,
        spec,
    })
}

/// The scene-wide settings: schema version, `dt` and `steps` together,
/// gravity, the solver's tolerances and iteration cap, and a non-empty scene.
fn check_settings(spec: &SceneSpec) -> Result<(), Invalid> {
    if spec.version != 1 {
        return Err(Invalid::new(
            "version",
            format!(
                "unsupported schema version {} (this build reads version 1)",
                spec.version
            ),
        ));
    }
    check_duration(spec.dt, spec.steps, "steps")?;
    check_finite("gravity", "gravity", &spec.gravity)?;
    let s = &spec.solver;
    if !(s.tol > 0.0 && s.tol.is_finite()) {
        return Err(Invalid::new(
            "solver.tol",
            format!("must be positive, got {}", s.tol),
        ));
    }
    if !(s.eig_clamp > 0.0 && s.eig_clamp.is_finite()) {
        return Err(Invalid::new(
            "solver.eig_clamp",
            format!("must be positive, got {}", s.eig_clamp),
        ));
    }
    if s.max_iters == 0 {
        return Err(Invalid::new("solver.max_iters", "must be at least 1"));
    }
    if spec.robots.is_empty() && spec.objects.is_empty() {
        return Err(Invalid::new(
            "robots",
            "the scene has no robots and no objects",
        ));
    }
    Ok(())
}

/// Every limited joint's initial coordinate lies strictly inside its limit
/// (the limit's barrier is infinite on the boundary).
fn check_initial_limits(model: &Model, q0: &DVector<f64>) -> Result<(), Invalid> {
    for link in &model.links {
        if let Some(lim) = &link.limit {
            let x = q0[link.dof_offset];
            if !(x > lim.lower && x < lim.upper) {
                return Err(Invalid::new(
                    format!(
                        "robot \"{}\" joint \"{}\"",
                        model.robots[link.robot].name, link.joint_name
                    ),
                    format!(
                        "the initial coordinate {x} must lie strictly inside the joint limit [{}, {}] (set `initial`)",
                        lim.lower, lim.upper
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A robot's joints by name, for look-ups and messages while building.
struct RobotJoints<'a> {
    robot: &'a str,
    joints: BTreeMap<&'a str, usize>,
}

impl<'a> RobotJoints<'a> {
    fn new(robot: &'a str, model: &'a Model, ri: usize) -> Self {
        let joints = model.robots[ri]
            .links
            .clone()
            .map(|l| (model.links[l].joint_name.as_str(), l))
            .collect();
        RobotJoints { robot, joints }
    }

    /// The element path `robot "<name>": <what>.<joint>`.
    fn el(&self, what: &str, joint: &str) -> String {
        format!("robot \"{}\": {what}.{joint}", self.robot)
    }

    /// The link of joint `joint`, or an error listing the robot's joints.
    fn find(&self, what: &str, joint: &str) -> Result<usize, Invalid> {
        self.joints.get(joint).copied().ok_or_else(|| {
            let known: Vec<&str> = self.joints.keys().copied().collect();
            Invalid::new(
                self.el(what, joint),
                format!("no joint named \"{joint}\" (joints: {})", known.join(", ")),
            )
        })
    }
}

/// The controller channels of robot `r`'s `controller:` section: gains
/// checked, one channel per coordinate of each target joint, a pose target
/// for a free root's six signals.
fn add_targets(
    r: &RobotSpec,
    rj: &RobotJoints,
    model: &Model,
    controller: &mut Controller,
) -> Result<(), Invalid> {
    let c = &r.controller;
    check_finite(
        &format!("robot \"{}\": controller", r.name),
        "kp/kd",
        &[c.kp, c.kd],
    )?;
    for joint in c.gains.keys() {
        rj.find("controller.gains", joint)?;
    }
    for (joint, signals) in &c.targets {
        let l = rj.find("controller.targets", joint)?;
        let link = &model.links[l];
        // A free root's six signals are one pose target (chart-free,
        // `control::pose_target`); other charted joints have none.
        let pose = matches!(link.joint, JointKind::Free) && link.parent.is_none();
        if link.joint.has_chart() && !pose {
            return Err(Invalid::new(
                rj.el("controller.targets", joint),
                format!(
                    "PD targets are supported on free joints of a robot's root link only, not on {} joints{}",
                    link.joint.type_name(),
                    if matches!(link.joint, JointKind::Free) {
                        " below a parent link"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let sigs = signals.as_slice();
        if sigs.len() != link.ndof() {
            return Err(Invalid::new(
                rj.el("controller.targets", joint),
                format!(
                    "joint has {} coordinate(s) but {} signal(s) were given",
                    link.ndof(),
                    sigs.len()
                ),
            ));
        }
        let g = c.gains.get(joint).cloned().unwrap_or_default();
        let (kp, kd) = (g.kp.unwrap_or(c.kp), g.kd.unwrap_or(c.kd));
        if !(kp >= 0.0 && kd >= 0.0 && kp.is_finite() && kd.is_finite()) {
            return Err(Invalid::new(
                rj.el("controller.gains", joint),
                format!("gains must be finite and ≥ 0, got kp={kp}, kd={kd}"),
            ));
        }
        if pose {
            controller.pose_targets.push(PoseTarget {
                link: l,
                first: controller.channels.len(),
                frame: link.attach,
            });
        }
        for (k, s) in sigs.iter().enumerate() {
            s.validate().map_err(|e| {
                Invalid::new(
                    format!("{}[{k}]", rj.el("controller.targets", joint)),
                    e.to_string(),
                )
            })?;
            controller.channels.push(ControlChannel {
                dof: link.dof_offset + k,
                kp,
                kd,
                signal: s.clone(),
                delay: 0.0,
            });
        }
    }
    Ok(())
}

/// Robot `r`'s `initial:` section into `q0`, `qdot0` and the charts
/// (charted joints: the initial rotation goes into the chart, `φ⁰ = 0`).
fn set_initial(
    r: &RobotSpec,
    rj: &RobotJoints,
    model: &Model,
    q0: &mut DVector<f64>,
    qdot0: &mut DVector<f64>,
    charts: &mut [Matrix3<f64>],
) -> Result<(), Invalid> {
    for (joint, init) in &r.initial {
        let l = rj.find("initial", joint)?;
        let link = &model.links[l];
        let nd = link.ndof();
        for (what, v) in [("q", &init.q), ("qdot", &init.qdot)] {
            if !v.is_empty() && v.len() != nd {
                return Err(Invalid::new(
                    format!("{}.{what}", rj.el("initial", joint)),
                    format!("joint has {nd} coordinate(s), got {} value(s)", v.len()),
                ));
            }
            check_finite(&rj.el("initial", joint), what, v)?;
        }
        let o = link.dof_offset;
        for (k, v) in init.q.iter().enumerate() {
            q0[o + k] = *v;
        }
        for (k, v) in init.qdot.iter().enumerate() {
            qdot0[o + k] = *v;
        }
        // Charted joints: the initial rotation goes into the chart, φ⁰ = 0.
        if let (Some(c), false) = (link.chart, init.q.is_empty()) {
            let co = o + link.joint.chart_offset();
            let phi = Vector3::new(q0[co], q0[co + 1], q0[co + 2]);
            charts[c] = so3::exp(&phi);
            q0.rows_mut(co, 3).fill(0.0);
        }
    }
    Ok(())
}

pub(super) fn unit(element: &str, field: &str, v: [f64; 3]) -> Result<Vector3<f64>, Invalid> {
    let a = Vector3::from(v);
    if !finite(&v) || a.norm() < 1e-12 {
        return Err(Invalid::new(
            element,
            format!("`{field}` must be a finite non-zero vector, got {v:?}"),
        ));
    }
    Ok(a.normalize())
}

fn joint_kind(element: &str, j: &JointSpec) -> Result<JointKind, Invalid> {
    let needs_axis = matches!(j.kind, JointType::Revolute | JointType::Prismatic);
    if j.axis.is_some() && !needs_axis {
        return Err(Invalid::new(
            element,
            format!(
                "`axis` is not used by a {:?} joint (use `axes` for ball joints)",
                j.kind
            )
            .to_lowercase(),
        ));
    }
    if j.axes.is_some() && j.kind != JointType::Ball {
        return Err(Invalid::new(element, "`axes` is only used by ball joints"));
    }
    Ok(match j.kind {
        JointType::Fixed => JointKind::Fixed,
        JointType::Spherical => JointKind::Spherical,
        JointType::Free => JointKind::Free,
        JointType::Revolute | JointType::Prismatic => {
            let axis = unit(
                element,
                "axis",
                j.axis
                    .ok_or_else(|| Invalid::new(element, "this joint type needs an `axis`"))?,
            )?;
            if j.kind == JointType::Revolute {
                JointKind::Revolute { axis }
            } else {
                JointKind::Prismatic { axis }
            }
        }
        JointType::Ball => {
            let [a, b] = j.axes.unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            let (a, b) = (unit(element, "axes[0]", a)?, unit(element, "axes[1]", b)?);
            if a.dot(&b).abs() > 1e-9 {
                return Err(Invalid::new(
                    element,
                    format!(
                        "ball joint axes must be orthogonal (cos = {:.3e})",
                        a.dot(&b)
                    ),
                ));
            }
            JointKind::Ball { axes: [a, b] }
        }
    })
}

/// Orders `links` so parents precede children (stable otherwise); reports
/// unknown parents and kinematic cycles.
fn topo_order(robot: &str, links: &[LinkSpec]) -> Result<Vec<usize>, Invalid> {
    let mut index = HashMap::new();
    for (i, l) in links.iter().enumerate() {
        if let Some(j) = index.insert(l.name.as_str(), i) {
            return Err(Invalid::new(
                format!("robot \"{robot}\": links[{i}]"),
                format!("link name \"{}\" is already used by links[{j}]", l.name),
            ));
        }
    }
    let mut parent = vec![None; links.len()];
    for (i, l) in links.iter().enumerate() {
        if let Some(p) = &l.parent {
            let pi = *index.get(p.as_str()).ok_or_else(|| {
                Invalid::new(
                    format!("robot \"{robot}\": link \"{}\".parent", l.name),
                    format!("no link named \"{p}\""),
                )
            })?;
            parent[i] = Some(pi);
        }
    }
    // Cycle detection in O(n): walk up from each unvisited link, marking the
    // walk; reaching a link marked by the same walk closes a cycle, reaching
    // one finished earlier ends the walk.
    const UNSEEN: usize = usize::MAX;
    const DONE: usize = usize::MAX - 1;
    let mut mark = vec![UNSEEN; links.len()];
    for start in 0..links.len() {
        let mut cur = start;
        while mark[cur] == UNSEEN {
            mark[cur] = start;
            match parent[cur] {
                Some(p) if mark[p] == start => {
                    // Parent to child around the cycle, back to `p`.
                    let mut names = vec![links[p].name.as_str()];
                    let mut k = parent[p].expect("on the cycle");
                    while k != p {
                        names.push(links[k].name.as_str());
                        k = parent[k].expect("on the cycle");
                    }
                    names.push(links[p].name.as_str());
                    names.reverse();
                    return Err(Invalid::new(
                        format!("robot \"{robot}\": link \"{}\"", links[start].name),
                        format!("kinematic cycle: {}", names.join(" → ")),
                    ));
                }
                Some(p) => cur = p,
                None => break,
            }
        }
        let mut k = start;
        while mark[k] == start {
            mark[k] = DONE;
            match parent[k] {
                Some(p) => k = p,
                None => break,
            }
        }
    }
    // Parents before children, in O(n): breadth first from the roots, with
    // children in file order.
    let mut children = vec![Vec::new(); links.len()];
    for (i, p) in parent.iter().enumerate() {
        if let Some(p) = p {
            children[*p].push(i);
        }
    }
    let mut order: Vec<usize> = (0..links.len()).filter(|&i| parent[i].is_none()).collect();
    let mut k = 0;
    while k < order.len() {
        let i = order[k];
        order.extend_from_slice(&children[i]);
        k += 1;
    }
    Ok(order)
}

fn build_robot(ri: usize, r: &RobotSpec, out: &mut Vec<Link>) -> Result<(), Invalid> {
    let el = format!("robot \"{}\"", r.name);
    let specs = link_specs(&el, r)?;
    let specs: &[LinkSpec] = &specs;
    check_finite(
        &format!("{el}: base"),
        "xyz/rpy",
        &[r.base.xyz, r.base.rpy].concat(),
    )?;
    let base = pose_from(&rpy_to_matrix(&r.base.rpy), &Vector3::from(r.base.xyz));
    let order = topo_order(&r.name, specs)?;
    let first = out.len();
    let mut new_index = vec![0; specs.len()];
    let mut joint_names = HashMap::new();
    for &si in &order {
        let l = &specs[si];
        let lel = format!("{el}: link \"{}\"", l.name);
        let joint_name = l.joint.name.clone().unwrap_or_else(|| l.name.clone());
        if let Some(other) = joint_names.insert(joint_name.clone(), l.name.clone()) {
            return Err(Invalid::new(
                format!("{lel}.joint.name"),
                format!("joint name \"{joint_name}\" is already used by link \"{other}\""),
            ));
        }
        let kind = joint_kind(&format!("{lel}.joint"), &l.joint)?;
        let limit = joint_limit(&format!("{lel}.joint.limit"), &kind, l.joint.limit.as_ref())?;
        let o = &l.joint.origin;
        check_finite(
            &format!("{lel}.joint.origin"),
            "xyz/rpy",
            &[o.xyz, o.rpy].concat(),
        )?;
        let attach_local = pose_from(&rpy_to_matrix(&o.rpy), &Vector3::from(o.xyz));
        let parent = l.parent.as_ref().map(|_| {
            new_index[specs
                .iter()
                .position(|s| Some(&s.name) == l.parent.as_ref())
                .unwrap()]
        });
        let attach = if parent.is_some() {
            attach_local
        } else {
            crate::math::compose(&base, &attach_local)
        };
        if l.hulls.is_empty() {
            return Err(Invalid::new(
                format!("{lel}.hulls"),
                "a link needs at least one hull",
            ));
        }
        let spec_model = l.mass_model.clone().unwrap_or(MassModelSpec::Vertices);
        let vertex_mass = vertex_mass(&lel, l, &spec_model)?;
        let mut hulls = Vec::with_capacity(l.hulls.len());
        for (hi, h) in l.hulls.iter().enumerate() {
            hulls.push(build_hull(&format!("{lel}.hulls[{hi}]"), h, vertex_mass)?);
        }
        let mass_model = mass_model(&lel, &spec_model, l.mass, &hulls)?;
        new_index[si] = out.len();
        out.push(Link {
            name: l.name.clone(),
            robot: ri,
            parent,
            joint_name,
            joint: kind,
            limit,
            attach,
            hulls,
            mass_model,
            solid_triangles: Vec::new(),
            surface: Vec::new(),
            dof_offset: 0,
            chart: None,
            collides: l.collide,
        });
    }
    debug_assert!(
        out[first..]
            .iter()
            .all(|l| l.parent.is_none_or(|p| p >= first))
    );
    Ok(())
}

/// The robot's link specifications: its `links`, or its generated `chain`
/// (checked: not both, at most [`MAX_LINKS`], positive sizes, ball or
/// revolute chain joints).
fn link_specs<'a>(el: &str, r: &'a RobotSpec) -> Result<Cow<'a, [LinkSpec]>, Invalid> {
    let specs = match (&r.chain, r.links.is_empty()) {
        (Some(_), false) => {
            return Err(Invalid::new(
                el.to_string(),
                "give either `links` or `chain`, not both",
            ));
        }
        (Some(c), true) => {
            if c.links > MAX_LINKS {
                return Err(Invalid::new(
                    format!("{el}: chain.links"),
                    format!("{} links: the maximum is {MAX_LINKS} per robot", c.links),
                ));
            }
            if c.links == 0 || !(c.link_length > 0.0 && c.link_width > 0.0 && c.link_mass > 0.0) {
                return Err(Invalid::new(
                    format!("{el}: chain"),
                    "links must be ≥ 1 and length, width, mass positive",
                ));
            }
            if !matches!(c.joint, JointType::Ball | JointType::Revolute) {
                return Err(Invalid::new(
                    format!("{el}: chain.joint"),
                    "chain joints must be `ball` or `revolute`",
                ));
            }
            Cow::Owned(chain::expand(c))
        }
        (None, true) => return Err(Invalid::new(el.to_string(), "the robot has no links")),
        (None, false) if r.links.len() > MAX_LINKS => {
            return Err(Invalid::new(
                format!("{el}: links"),
                format!(
                    "{} links: the maximum is {MAX_LINKS} per robot",
                    r.links.len()
                ),
            ));
        }
        (None, false) => Cow::Borrowed(&r.links[..]),
    };
    Ok(specs)
}

/// The mass of each implicitly weighted vertex of a `vertices`-model link
/// (`mass` spread over the vertices without their own `vertex_masses`, or
/// `vertex_mass`); 0 for the other mass models, which take neither key.
fn vertex_mass(lel: &str, l: &LinkSpec, spec_model: &MassModelSpec) -> Result<f64, Invalid> {
    let lumped = matches!(spec_model, MassModelSpec::Vertices);
    if !lumped {
        if l.vertex_mass.is_some() {
            return Err(Invalid::new(
                format!("{lel}.vertex_mass"),
                "only the `vertices` mass model takes `vertex_mass`",
            ));
        }
        if let Some(hi) = l.hulls.iter().position(|h| h.vertex_masses.is_some()) {
            return Err(Invalid::new(
                format!("{lel}.hulls[{hi}].vertex_masses"),
                "only the `vertices` mass model takes `vertex_masses`",
            ));
        }
    }
    let explicit = lumped && l.hulls.iter().all(|h| h.vertex_masses.is_some());
    let vertex_mass = match (l.mass, l.vertex_mass) {
        _ if !lumped => 0.0,
        (Some(_), Some(_)) => {
            return Err(Invalid::new(
                lel,
                "give either `mass` or `vertex_mass`, not both",
            ));
        }
        (None, None) if explicit => 0.0,
        (None, None) => {
            return Err(Invalid::new(
                lel,
                "the link needs a `mass` (kg) or a `vertex_mass` (kg per vertex)",
            ));
        }
        (Some(m), None) => {
            if !(m > 0.0 && m.is_finite()) {
                return Err(Invalid::new(
                    format!("{lel}.mass"),
                    format!("must be positive and finite, got {m}"),
                ));
            }
            let nimplicit: usize = l
                .hulls
                .iter()
                .filter(|h| h.vertex_masses.is_none())
                .map(|h| h.vertices.as_ref().map_or(8, Vec::len))
                .sum();
            m / nimplicit.max(1) as f64
        }
        (None, Some(m)) => {
            if !(m > 0.0 && m.is_finite()) {
                return Err(Invalid::new(
                    format!("{lel}.vertex_mass"),
                    format!("must be positive and finite, got {m}"),
                ));
            }
            m
        }
    };
    Ok(vertex_mass)
}

/// One hull of a link (`hel`: its element path) from its `vertices` or
/// `box`, with its vertex masses.
fn build_hull(hel: &str, h: &HullSpec, vertex_mass: f64) -> Result<Hull, Invalid> {
    let verts = match (&h.vertices, &h.cuboid) {
        (Some(_), Some(_)) => {
            return Err(Invalid::new(
                hel.to_string(),
                "give either `vertices` or `box`, not both",
            ));
        }
        (None, None) => {
            return Err(Invalid::new(
                hel.to_string(),
                "a hull needs `vertices` or `box`",
            ));
        }
        (Some(v), None) => v.iter().map(|p| Vector3::from(*p)).collect(),
        (None, Some(BoxSpec { size, center })) => {
            check_finite(hel, "box", &[*size, *center].concat())?;
            if size.iter().any(|s| *s <= 0.0) {
                return Err(Invalid::new(
                    hel,
                    format!("box size must be positive, got {size:?}"),
                ));
            }
            Hull::cuboid(Vector3::from(*size), Vector3::from(*center))
        }
    };
    let mut hull = Hull::new(verts, vertex_mass).map_err(|e| Invalid::new(hel, e.to_string()))?;
    if let Some(ms) = &h.vertex_masses {
        if ms.len() != hull.x_local.len() {
            let msg = format!(
                "{} vertex_masses for {} vertices",
                ms.len(),
                hull.x_local.len()
            );
            return Err(Invalid::new(hel.to_string(), msg));
        }
        hull.vertex_mass = ms.clone();
        hull.validate()
            .map_err(|e| Invalid::new(hel, e.to_string()))?;
    }
    Ok(hull)
}

/// The link's [`MassModel`] from its spec (`mass`: the link's `mass` key).
fn mass_model(
    lel: &str,
    spec: &MassModelSpec,
    mass: Option<f64>,
    hulls: &[Hull],
) -> Result<MassModel, Invalid> {
    let el = format!("{lel}.mass_model");
    match spec {
        MassModelSpec::Vertices => Ok(MassModel::Vertices),
        MassModelSpec::Solid { density } => {
            let density = match (density, mass) {
                (Some(_), Some(_)) => {
                    return Err(Invalid::new(
                        lel,
                        "a `solid` link takes either `mass` or `mass_model.density`, not both",
                    ));
                }
                (None, None) => {
                    return Err(Invalid::new(
                        lel,
                        "a `solid` link needs `mass` (kg) or `mass_model.density` (kg/m³)",
                    ));
                }
                (Some(d), None) => *d,
                (None, Some(m)) => {
                    let mut volume = 0.0;
                    for (hi, h) in hulls.iter().enumerate() {
                        let tris = crate::model::mass::solid_triangles(&h.x_local)
                            .map_err(|e| Invalid::new(format!("{lel}.hulls[{hi}]"), e))?;
                        volume += crate::model::mass::solid_volume(&h.x_local, &tris);
                    }
                    m / volume
                }
            };
            if !(density > 0.0 && density.is_finite()) {
                return Err(Invalid::new(
                    el,
                    format!("density must be positive and finite, got {density}"),
                ));
            }
            for (hi, h) in hulls.iter().enumerate() {
                crate::model::mass::solid_triangles(&h.x_local)
                    .map_err(|e| Invalid::new(format!("{lel}.hulls[{hi}]"), e))?;
            }
            Ok(MassModel::Solid { density })
        }
        MassModelSpec::Given {
            mass: m,
            com,
            inertia,
        } => {
            if mass.is_some() {
                return Err(Invalid::new(
                    lel,
                    "a `given` link takes its mass from `mass_model.mass`; remove the link's `mass`",
                ));
            }
            let [xx, xy, xz, yy, yz, zz] = *inertia;
            let g = Inertial {
                mass: *m,
                com: Vector3::from(*com),
                inertia: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
            };
            g.check().map_err(|e| Invalid::new(el, e))?;
            Ok(MassModel::Given(g))
        }
    }
}

/// Default barrier support of a joint limit (rad or m).
pub const DEFAULT_LIMIT_SUPPORT: f64 = 0.02;
/// Default barrier stiffness of a joint limit (J·rad or J·m).
pub const DEFAULT_LIMIT_STIFFNESS: f64 = 1.0e-3;

/// A joint's [`JointLimit`] from its spec: revolute/prismatic only,
/// finite `lower < upper`, positive support (capped at a quarter of the
/// range) and stiffness.
fn joint_limit(
    el: &str,
    kind: &JointKind,
    spec: Option<&JointLimitSpec>,
) -> Result<Option<JointLimit>, Invalid> {
    let Some(sp) = spec else { return Ok(None) };
    if !matches!(
        kind,
        JointKind::Revolute { .. } | JointKind::Prismatic { .. }
    ) {
        return Err(Invalid::new(
            el,
            "only revolute and prismatic joints take a `limit`",
        ));
    }
    check_finite(el, "lower/upper", &[sp.lower, sp.upper])?;
    if sp.lower >= sp.upper {
        return Err(Invalid::new(
            el,
            format!("lower {} must be below upper {}", sp.lower, sp.upper),
        ));
    }
    let support = sp.support.unwrap_or(DEFAULT_LIMIT_SUPPORT);
    let stiffness = sp.stiffness.unwrap_or(DEFAULT_LIMIT_STIFFNESS);
    for (what, v) in [("support", support), ("stiffness", stiffness)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Invalid::new(
                format!("{el}.{what}"),
                format!("must be positive and finite, got {v}"),
            ));
        }
    }
    for (what, v) in [("velocity", sp.velocity), ("effort", sp.effort)] {
        if let Some(v) = v.filter(|v| !(*v >= 0.0 && v.is_finite())) {
            return Err(Invalid::new(
                format!("{el}.{what}"),
                format!("must be non-negative and finite, got {v}"),
            ));
        }
    }
    Ok(Some(JointLimit {
        lower: sp.lower,
        upper: sp.upper,
        support: support.min(0.25 * (sp.upper - sp.lower)),
        stiffness,
        velocity: sp.velocity,
        effort: sp.effort,
    }))
}

/// Default stiffness of a mimic tie (J/rad² or J/m²).
pub const DEFAULT_MIMIC_STIFFNESS: f64 = 1.0e4;

/// The mimic ties of every robot; a mimic joint that `initial` does not set
/// starts on its relation (`q0`, `qdot0` updated).
fn mimic_ties(
    robots: &[RobotSpec],
    model: &Model,
    q0: &mut DVector<f64>,
    qdot0: &mut DVector<f64>,
) -> Result<Vec<MimicTie>, Invalid> {
    let mut ties = Vec::new();
    for (ri, r) in robots.iter().enumerate() {
        let range = model.robots[ri].links.clone();
        let by_joint = |name: &str| range.clone().find(|&l| model.links[l].joint_name == name);
        for l in &r.links {
            let Some(m) = &l.joint.mimic else { continue };
            let jname = l.joint.name.clone().unwrap_or_else(|| l.name.clone());
            let el = format!("robot \"{}\" joint \"{jname}\".mimic", r.name);
            let me = by_joint(&jname).expect("built above");
            let Some(master) = by_joint(&m.joint) else {
                return Err(Invalid::new(
                    el,
                    format!("no joint named \"{}\" in this robot", m.joint),
                ));
            };
            let one_dof = |k: &JointKind| {
                matches!(k, JointKind::Revolute { .. } | JointKind::Prismatic { .. })
            };
            if !one_dof(&model.links[me].joint) || !one_dof(&model.links[master].joint) {
                return Err(Invalid::new(
                    el,
                    "mimic joints and the joints they follow must be revolute or prismatic",
                ));
            }
            if master == me {
                return Err(Invalid::new(el, "a joint cannot mimic itself"));
            }
            let (a, b) = (m.multiplier.unwrap_or(1.0), m.offset.unwrap_or(0.0));
            let k = m.stiffness.unwrap_or(DEFAULT_MIMIC_STIFFNESS);
            check_finite(&el, "multiplier/offset", &[a, b])?;
            if !(k > 0.0 && k.is_finite()) {
                return Err(Invalid::new(
                    format!("{el}.stiffness"),
                    format!("must be positive and finite, got {k}"),
                ));
            }
            let (dof, mdof) = (model.links[me].dof_offset, model.links[master].dof_offset);
            if !r.initial.contains_key(&jname) {
                q0[dof] = a * q0[mdof] + b;
                qdot0[dof] = a * qdot0[mdof];
            }
            ties.push(MimicTie {
                dof,
                master: mdof,
                multiplier: a,
                offset: b,
                stiffness: k,
            });
        }
    }
    Ok(ties)
}
