//! The topology-change demonstration (issue 30, item 2;
//! `robots/topology_peg/`): design gradients of the paper's connectivity
//! (one shared vertex per face-neighbour pair of grid blocks) against
//! central differences, at the initial design and with one block shrunk
//! to a sliver, and ties and bounds after optimizer iterations for both
//! connectivities. Cheap (seconds): the task is 40 steps of one fixed
//! plate and one peg on a prismatic joint.

use crate::common;

use common::robots;
use nalgebra::DVector;
use sdrs::optimize::design::Target;
use sdrs::optimize::{Problem, optimize};

fn problem(task: &str, tol: f64) -> Problem {
    let mut p = Problem::load(&robots(&format!("topology_peg/{task}")), true).unwrap();
    p.first_mut().scene.settings.newton.tol = tol;
    p
}

/// Variables with a target on hull `h` of the plate.
fn vars_of_block(p: &Problem, h: usize) -> Vec<usize> {
    (0..p.design.len())
        .filter(|&i| {
            p.design.vars[i]
                .targets
                .iter()
                .any(|t| matches!(*t, Target::Vertex { link: 0, hull, .. } if hull == h))
        })
        .collect()
}

fn env<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The optimizer's iterate after `k` iterations of the committed task.
fn iterate(p: &Problem, k: usize) -> DVector<f64> {
    let mut last = p.design.values(&p.first().model);
    optimize(p, k, |_, d: &DVector<f64>| last = d.clone()).unwrap();
    last
}

/// The hull vertex `(hull, vertex)` a design variable moves first.
fn vertex_of(p: &Problem, i: usize) -> (usize, usize) {
    match p.design.vars[i].targets[0] {
        Target::Vertex { hull, vertex, .. } => (hull, vertex),
        t => panic!("not a vertex variable: {t:?}"),
    }
}

/// Richardson-extrapolated central differences `(4D(h) − D(2h))/3` at
/// `h = 1e-7` (`FD_EPS` overrides; Newton tolerance 1e-11) against the
/// adjoint at design `d`: for each of the 12 hull vertices with the largest
/// gradients, its largest component, plus the variables `extra`. Returns
/// `(variable, relative error)` for each.
fn check(p: &Problem, d: &DVector<f64>, extra: &[usize], label: &str) -> Vec<(usize, f64)> {
    let c = p.controls.values(&p.first().controller);
    let ev = p.evaluate(d, &c).unwrap();
    let g = &ev.grad_design;
    let mut best: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
    for i in 0..p.design.len() {
        let e = best.entry(vertex_of(p, i)).or_insert(i);
        if g[i].abs() > g[*e].abs() {
            *e = i;
        }
    }
    let mut idx: Vec<usize> = best.into_values().filter(|&i| g[i] != 0.0).collect();
    idx.sort_by(|&a, &b| g[b].abs().total_cmp(&g[a].abs()));
    eprintln!("{label}: {} vertices with a gradient", idx.len());
    idx.truncate(12);
    for &e in extra {
        if !idx.contains(&e) {
            idx.push(e);
        }
    }
    let eps = env("FD_EPS", 1e-7);
    let central = |i: usize, h: f64| {
        let mut dp = d.clone();
        dp[i] += h;
        let mut dm = d.clone();
        dm[i] -= h;
        (p.loss_value(&dp, &c).unwrap() - p.loss_value(&dm, &c).unwrap()) / (2.0 * h)
    };
    idx.iter()
        .map(|&i| {
            let fd = (4.0 * central(i, eps) - central(i, 2.0 * eps)) / 3.0;
            let rel = (fd - g[i]).abs() / g[i].abs().max(fd.abs()).max(1e-300);
            eprintln!(
                "{label}: {} analytic {:.9e} central {fd:.9e} rel {rel:.2e}",
                p.design.vars[i].name, g[i]
            );
            (i, rel)
        })
        .collect()
}

/// Iteration of the committed task at which the gradients are checked
/// (`FD_ITER` overrides). Not the initial design: there the peg's point
/// sits exactly on the corner four blocks share, a vertex-on-vertex
/// contact whose loss is smooth but curved on a ≈ 1e-7 m scale in the
/// horizontal directions (measured: the differences of a corner's x
/// component are 2.7e1, 3.1, 1.3, 0.94, 1.005 × the adjoint at h = 1e-5,
/// 1e-6, 3e-7, 1e-7, 3e-8, converging onto it; the z components agree to
/// 6e-7 at h = 1e-7). Iteration 3 was chosen after measuring iterations
/// 3, 5 and 8 (2026-11-26): the peg touches 4, 1 and 3 plate vertices
/// there, every checked component agreeing to ≤ 4.5e-7. This scene has at
/// most four vertices in contact, so the acceptance's "≥ 10 vertices" is
/// checked on the grasping scenes, which use the same connectivity
/// (`tests/grasping.rs`: single jaw 12 of 12, parallel jaw 12 of 12).
const CHECK_ITER: usize = 3;

/// Every vertex with a gradient (the four block corners under the peg)
/// within 1e-4 relative, at the optimizer's iterate `CHECK_ITER`.
#[test]
fn design_gradient_of_the_shared_vertex_space_matches_central_differences() {
    let p = problem("task.yaml", 1e-11);
    let d = iterate(&p, env("FD_ITER", CHECK_ITER));
    let r = check(&p, &d, &[], "iterate");
    let within = r.iter().filter(|x| x.1 <= 1e-4).count();
    assert!(
        r.len() >= 4 && within == r.len(),
        "{within} of {} vertices within 1e-4",
        r.len()
    );
}

/// At the same iterate, the block holding the vertex with the largest
/// gradient is flattened towards its top to a sliver (every vertex of it,
/// its shared face-centre vertices included: `z ← top − 1e-4 (top − z)`,
/// thickness 1e-4 of its own): every checked vertex within 1e-4, among
/// them every component of the sliver's vertices with |g| ≥ 1e-3 max|g|
/// (at least two).
#[test]
fn design_gradient_with_a_block_shrunk_to_a_sliver_matches_central_differences() {
    let p = problem("task.yaml", 1e-11);
    let mut d = iterate(&p, env("FD_ITER", CHECK_ITER));
    let c = p.controls.values(&p.first().controller);
    let g0 = p.evaluate(&d, &c).unwrap().grad_design;
    let h = vertex_of(&p, g0.iamax()).0;
    let zs: Vec<usize> = vars_of_block(&p, h)
        .into_iter()
        .filter(|&i| p.design.vars[i].name.ends_with(".z"))
        .collect();
    assert!(zs.len() >= 9, "{} z variables on block {h}", zs.len());
    let top = zs.iter().map(|&i| d[i]).fold(f64::MIN, f64::max);
    let bottom = zs.iter().map(|&i| d[i]).fold(f64::MAX, f64::min);
    for &i in &zs {
        d[i] = top - 1e-4 * (top - d[i]);
    }
    let mut model = p.first().model.clone();
    p.design.apply(&mut model, &d);
    p.design.check(&model).unwrap();
    let x = &model.links[0].hulls[h].x_local;
    let (lo, hi) = x
        .iter()
        .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(v.z), a.1.max(v.z)));
    eprintln!(
        "block {h}: thickness {:.3e} m (was {:.3e})",
        hi - lo,
        top - bottom
    );
    assert!(
        hi - lo <= 1.01e-4 * (top - bottom),
        "sliver thickness {}",
        hi - lo
    );
    let g = p.evaluate(&d, &c).unwrap().grad_design;
    let gmax = g.amax();
    let sliver: Vec<usize> = vars_of_block(&p, h)
        .into_iter()
        .filter(|&i| g[i].abs() >= 1e-3 * gmax)
        .collect();
    assert!(
        sliver.len() >= 2,
        "sliver components with a gradient: {}",
        sliver.len()
    );
    let r = check(&p, &d, &sliver, "sliver");
    let within = r.iter().filter(|x| x.1 <= 1e-4).count();
    assert!(within == r.len(), "{within} of {} within 1e-4", r.len());
    for (i, e) in &r {
        if sliver.contains(i) {
            assert!(
                *e <= 1e-4,
                "sliver component {}: {e:.2e}",
                p.design.vars[*i].name
            );
        }
    }
}

/// Ties and bounds at every iterate of the committed task's 40 iterations
/// (or up to the iteration at which the run converged; ≈ 1 s), for both connectivities; the shared-vertex space has one
/// auxiliary point per face-neighbour pair (24 in a 4 × 4 plate) tied
/// between exactly two blocks, the corner space points shared by up to 4
/// blocks; in both, some tied point moves (so the tie is exercised).
#[test]
fn ties_and_bounds_hold_at_every_iterate_for_both_connectivities() {
    for (task, most_shared) in [("task.yaml", 2), ("task_corners.yaml", 4)] {
        let p = problem(task, 1e-6);
        let shared = p.design.vars.iter().map(|v| v.targets.len()).max().unwrap();
        assert_eq!(shared, most_shared, "{task}");
        let points = p.design.len() / 3;
        match task {
            "task.yaml" => assert_eq!(points, 16 * 8 + 24, "{task}: corners + face points"),
            _ => assert_eq!(points, 5 * 5 * 2, "{task}: lattice points"),
        }
        let d0 = p.design.values(&p.first().model);
        let tied: Vec<usize> = (0..p.design.len())
            .filter(|&i| p.design.vars[i].targets.len() >= 2)
            .collect();
        let (mut checked, mut moved) = (0, false);
        let out = optimize(&p, 40, |_, d: &DVector<f64>| {
            let mut model = p.first().model.clone();
            p.design.apply(&mut model, d);
            p.design.check(&model).unwrap();
            checked += 1;
            moved |= tied.iter().any(|&i| d[i] != d0[i]);
        })
        .unwrap();
        // Every iterate, the start included; a run that converged early
        // (its trial rounds to the iterate: `Outcome::converged`) has fewer.
        assert_eq!(checked, out.history.len(), "{task}");
        assert!(
            checked == 41 || out.converged.is_some(),
            "{task}: {checked}"
        );
        assert!(moved, "{task}: no tied point moved");
    }
}
