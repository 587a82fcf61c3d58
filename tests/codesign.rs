//! Co-design on the paper's chain-reaching task.

mod common;

use common::robots;
use sdrs::optimize::{Problem, optimize};

fn task() -> std::path::PathBuf {
    robots("chain_reach/task.yaml")
}

#[test]
fn ties_and_bounds_hold_after_every_optimizer_iteration() {
    let p = Problem::load(&task(), true).unwrap();
    assert_eq!(p.design.len(), 24, "8 attachment points × 3");
    // Every attachment variable also moves a parent hull vertex (its tie).
    assert!(p.design.vars.iter().all(|v| v.targets.len() == 2));
    let mut checked = 0;
    optimize(&p, 12, |_, d| {
        let mut model = p.model.clone();
        p.design.apply(&mut model, d);
        p.design.check(&model).unwrap();
        checked += 1;
    })
    .unwrap();
    assert_eq!(checked, 13);
}

#[test]
fn chain_reaching_codesign_beats_controller_only_by_ninety_percent() {
    let co = Problem::load(&task(), true).unwrap();
    let ctrl = Problem::load(&task(), false).unwrap();
    let iters = co.task.optimizer.iters;
    let a = optimize(&co, iters, |_, _| {}).unwrap();
    let b = optimize(&ctrl, iters, |_, _| {}).unwrap();
    assert_eq!(a.initial_loss, b.initial_loss, "same start");
    let link = 0.25;
    let reach = a.loss.sqrt();
    let improvement = 1.0 - a.loss / b.loss;
    eprintln!(
        "chain reach: initial {:.4e}; controller-only {:.4e} (error {:.3} m = {:.2} links); co-design {:.4e} (error {:.2e} m = {:.4} links); co-design lower by {:.4}%",
        a.initial_loss,
        b.loss,
        b.loss.sqrt(),
        b.loss.sqrt() / link,
        a.loss,
        reach,
        reach / link,
        100.0 * improvement
    );
    assert!(
        b.loss.sqrt() > link,
        "the target must be out of reach without co-design"
    );
    assert!(improvement >= 0.9);
    assert!(reach <= 0.3 * link);
}
