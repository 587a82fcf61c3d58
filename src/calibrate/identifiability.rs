//! Identifiability of each candidate on the given data, measured at its
//! start, before any fitting step (issue 33, item 4).
//!
//! With `J = ∂r/∂p` the Jacobian of the training residuals (all
//! recordings) at the candidate's first start — the one the fit's first
//! Levenberg–Marquardt step uses ([`super::fit::Fit::gauss_newton_start`],
//! so the check costs no simulation) — and `D = diag(typical)` the
//! candidate's typical magnitudes (SI), the scaled Gauss–Newton matrix is
//!
//! ```text
//! A = D JᵀJ D     (units of r², per "one typical magnitude" of each parameter)
//! ```
//!
//! Its eigenvalues `λ_i` (eigenvectors `v_i`) are the residual's squared
//! response to moving the parameters a typical amount along `v_i`. The
//! condition number is `κ = λ_max/λ_min` of the candidate's own `A`. A
//! direction is **near-singular** when `λ_i < RELATIVE_EIGEN · λ_ref`, where
//! `λ_ref` is the largest `λ_max` over all candidates (the best-excited
//! direction of any effect on these data): a relative threshold, so that a
//! single-parameter effect the data barely see (the damping of a joint that
//! never moves) is caught as well as two parameters the data cannot tell
//! apart. The parameters named are those whose component in a
//! near-singular eigenvector is at least [`NAME_COMPONENT`] of its largest
//! component.
//!
//! Thresholds: `RELATIVE_EIGEN = 1e-8` (a parameter moved by its typical
//! magnitude changes the residual by 10⁻⁴ of what the best-seen one does),
//! chosen before the first run; `NAME_COMPONENT = 0.5`, first applied to
//! the unit eigenvector's absolute components: for the pair
//! `joint_damping/shoulder + joint_damping/all` on data where the elbow
//! never moves (the two act identically), the null direction is
//! `∝ (d_all, −d_shoulder)` in scaled units and the shoulder's component
//! came out 0.47, so only `all` was named although neither can be told
//! from the other; now relative to the largest component.
//!
//! An excitation suggestion names, for a joint effect on specific joints,
//! how little the joint moves in the scene's simulation of the data (its
//! largest speed and acceleration at the sample times, against the most
//! moving joint's). A candidate with an unidentifiable parameter is still
//! fitted and ranked, but flagged in the ranking and, if chosen, in the
//! verdict's reason ([`flag_reason`]).

use super::problem::{Problem, Simulated};
use super::select::Scored;
use crate::energy::effects::{Scope, Target};
use nalgebra::{DMatrix, SymmetricEigen};
use serde::Serialize;

/// A direction whose eigenvalue is below this fraction of the largest one
/// over all candidates is near-singular (see the module doc).
pub const RELATIVE_EIGEN: f64 = 1e-8;
/// A parameter is named in a near-singular direction when its component in
/// the eigenvector is at least this fraction of the largest component.
pub const NAME_COMPONENT: f64 = 0.5;

/// The identifiability of one candidate's parameters at its start.
#[derive(Clone, Debug, Serialize)]
pub struct Identifiability {
    pub candidate: String,
    /// `κ = λ_max/λ_min` of the scaled Gauss–Newton matrix (`null`: not
    /// computed, or `λ_min ≤ 0`).
    pub condition: Option<f64>,
    /// `λ_min/λ_ref` (see the module doc).
    pub min_relative_eigenvalue: f64,
    /// Parameter keys in a near-singular direction (empty: identifiable).
    pub unidentifiable: Vec<String>,
    /// What to excite (`null` when identifiable).
    pub suggestion: Option<String>,
}

/// Eigenvalues (ascending) and eigenvectors of `D JᵀJ D`.
fn scaled_eigen(s: &Scored) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let a = s.fit.gauss_newton_start.as_ref()?;
    let d = &s.candidate.typical;
    let k = d.len();
    let scaled = DMatrix::from_fn(k, k, |i, j| d[i] * a[(i, j)] * d[j]);
    let e = SymmetricEigen::new(scaled);
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&x, &y| e.eigenvalues[x].total_cmp(&e.eigenvalues[y]));
    let values = order.iter().map(|&i| e.eigenvalues[i]).collect();
    let vectors = DMatrix::from_fn(k, k, |r, c| e.eigenvectors[(r, order[c])]);
    Some((values, vectors))
}

/// Largest speed and acceleration of coordinate `dof` in `sim` at the
/// sample times of the first recording.
fn motion(pb: &Problem, sim: &Simulated, dof: usize) -> (f64, f64) {
    pb.measured.times.iter().fold((0.0, 0.0), |(v, a), &t| {
        let (dv, da) = sim.rates(dof, t);
        (f64::max(v, dv.abs()), f64::max(a, da.abs()))
    })
}

/// The excitation suggestion for the unidentifiable parameters `keys` of
/// `s` (`base`: the scene's simulation of the first recording).
fn suggestion(pb: &Problem, s: &Scored, base: &Simulated, keys: &[String], rel: f64) -> String {
    let model = &pb.scene.model;
    let mut out = format!(
        "{} not identifiable from these data (scaled Gauss–Newton eigenvalue {rel:.1e} of the best-excited direction, < {RELATIVE_EIGEN:e})",
        keys.iter()
            .map(|k| format!("`{k}`"))
            .collect::<Vec<_>>()
            .join(" and "),
    );
    let specs = s.candidate.specs(&s.fit.params);
    let Some(sc) = pb.scene_with(&specs) else {
        return out;
    };
    let first = sc.effects.len() - specs.len();
    let most = (0..model.ndof())
        .map(|k| (motion(pb, base, k).0, k))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let mut joints = Vec::new();
    for e in &sc.effects[first..] {
        if let (Scope::Joints, Target::Dofs(d)) = (e.kind.scope(), &e.target)
            && d.len() == 1
        {
            let (v, a) = motion(pb, base, d[0]);
            let unit = match model.links[model.dofs[d[0]].link].joint {
                crate::model::JointKind::Prismatic { .. } => "m",
                _ => "rad",
            };
            joints.push(format!(
                "joint `{}` never moves faster than {v:.3e} {unit}/s (|accel.| ≤ {a:.3e} {unit}/s²){}",
                model.dofs[d[0]].name,
                most.filter(|m| m.1 != d[0])
                    .map(|m| format!(", `{}` reaches {:.3e}", model.dofs[m.1].name, m.0))
                    .unwrap_or_default()
            ));
        }
    }
    if joints.is_empty() {
        out.push_str(": excite the motion these effects act on, or fit them on data that move it");
    } else {
        out.push_str(&format!(
            ": {}; excite it (a target that moves that joint) or leave the effect out",
            joints.join("; ")
        ));
    }
    out
}

/// The identifiability of every candidate of `ranking` (in its order);
/// `base` is the scene's simulation of the first recording.
pub fn assess(pb: &Problem, ranking: &[Scored], base: &Simulated) -> Vec<Identifiability> {
    let eig: Vec<Option<(Vec<f64>, DMatrix<f64>)>> = ranking.iter().map(scaled_eigen).collect();
    let reference = eig
        .iter()
        .flatten()
        .filter_map(|(v, _)| v.last().copied())
        .fold(0.0, f64::max);
    ranking
        .iter()
        .zip(&eig)
        .map(|(s, e)| {
            let label = s.candidate.label.clone();
            let Some((values, vectors)) = e.as_ref().filter(|_| reference > 0.0) else {
                return Identifiability {
                    candidate: label,
                    condition: None,
                    min_relative_eigenvalue: f64::NAN,
                    unidentifiable: Vec::new(),
                    suggestion: None,
                };
            };
            let keys: Vec<String> = super::report::param_list(pb, s)
                .into_iter()
                .map(|(k, _)| k)
                .collect();
            let mut bad: Vec<String> = Vec::new();
            for (i, &l) in values.iter().enumerate() {
                if l < RELATIVE_EIGEN * reference {
                    let v = vectors.column(i);
                    let top = v.amax();
                    for (k, key) in keys.iter().enumerate() {
                        if v[k].abs() >= NAME_COMPONENT * top && !bad.contains(key) {
                            bad.push(key.clone());
                        }
                    }
                }
            }
            let (lo, hi) = (values[0], values[values.len() - 1]);
            let rel = lo / reference;
            Identifiability {
                candidate: label,
                condition: (lo > 0.0).then(|| hi / lo),
                min_relative_eigenvalue: rel,
                suggestion: (!bad.is_empty()).then(|| suggestion(pb, s, base, &bad, rel)),
                unidentifiable: bad,
            }
        })
        .collect()
}

/// Appends to the verdict's reason that the chosen candidate had an
/// unidentifiable parameter before fitting (it is never chosen silently).
pub fn flag_reason(reason: &mut String, chosen: &Identifiability) {
    if let Some(s) = &chosen.suggestion {
        reason.push_str(&format!(
            "; WARNING: before fitting, {s} — the fitted value of {} is not determined by the data",
            chosen.unidentifiable.join(", ")
        ));
    }
}

/// The "Identifiability" section of `report.md`.
pub fn markdown(all: &[Identifiability], chosen: Option<&str>) -> String {
    let mut s = format!(
        "## Identifiability (before fitting)\n\nScaled Gauss–Newton matrix `D JᵀJ D` of each candidate at its start (`calibrate::identifiability`); a direction is near-singular below {RELATIVE_EIGEN:e} of the best-excited one over all candidates.\n\n"
    );
    if let Some(c) = chosen.and_then(|c| all.iter().find(|i| i.candidate == c)) {
        s.push_str(&format!(
            "Chosen `{}`: condition number {}, smallest relative eigenvalue {:.2e}.\n\n",
            c.candidate,
            c.condition
                .map_or("∞ (singular)".into(), |k| format!("{k:.3e}")),
            c.min_relative_eigenvalue
        ));
    }
    let flagged: Vec<&Identifiability> = all
        .iter()
        .filter(|i| !i.unidentifiable.is_empty())
        .collect();
    if flagged.is_empty() {
        s.push_str("Every candidate's parameters are identifiable from these data.\n\n");
        return s;
    }
    s.push_str("| candidate | condition | not identifiable | suggestion |\n|---|---:|---|---|\n");
    for i in flagged {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} |\n",
            i.candidate,
            i.condition.map_or("∞".into(), |k| format!("{k:.2e}")),
            i.unidentifiable.join(", "),
            i.suggestion.as_deref().unwrap_or("")
        ));
    }
    s.push('\n');
    s
}
