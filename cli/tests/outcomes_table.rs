//! `tools/gen/outcomes_table.py` (the outcome tables of
//! `docs/paper-benchmarks.md` from `sdrs optimize` folders) reports each
//! run's own figures: a grasping run (the parallel jaw on its stand, no
//! iteration: 0/4 grasped, no through-hole) and a chain-reaching run of
//! three iterations, read back against their `summary.json`; a folder
//! without one is listed as missing, not skipped.

use crate::support;

use support::{root, run_ok, scratch_dir};

fn optimize(task: &str, iters: &str, out: &std::path::Path) -> serde_json::Value {
    run_ok(support::sdrs().current_dir(root()).args([
        "optimize",
        task,
        "--iters",
        iters,
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]));
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The cells of the table row that starts with `| label |`.
fn cells<'a>(table: &'a str, label: &str) -> Vec<&'a str> {
    let line = table
        .lines()
        .find(|l| l.starts_with(&format!("| {label} |")))
        .unwrap_or_else(|| panic!("no row {label}:\n{table}"));
    line.trim_matches('|').split('|').map(str::trim).collect()
}

/// The two losses of a `a → b` cell.
fn losses(cell: &str) -> (f64, f64) {
    let (a, b) = cell.split_once(" → ").unwrap_or_else(|| panic!("{cell}"));
    (a.parse().unwrap(), b.parse().unwrap())
}

/// A figure printed with four significant digits (`%.4g`) against the
/// summary's.
fn close(printed: f64, exact: f64) {
    assert!(
        (printed - exact).abs() <= 5e-4 * exact.abs(),
        "{printed} vs {exact}"
    );
}

#[test]
fn outcome_rows_are_the_runs_own_figures() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("outcomes-table");
    let (stand, chain) = (dir.join("stand"), dir.join("chain"));
    let s_stand = optimize("robots/parallel_jaw_stand/task.yaml", "0", &stand);
    let s_chain = optimize("robots/chain_reach/task.yaml", "3", &chain);
    let o = run_ok(
        support::python()
            .arg(root().join("tools/gen/outcomes_table.py"))
            .arg(format!("--label=stand={}", stand.display()))
            .arg(format!("--label=chain={}", chain.display()))
            .arg(format!("--label=none={}", dir.join("missing").display())),
    );
    let table = String::from_utf8_lossy(&o.stdout).into_owned();

    let row = cells(&table, "stand");
    assert_eq!(row[1], "on");
    assert_eq!(row[2], "0");
    let (from, to) = losses(row[3]);
    close(from, s_stand["initial_loss"].as_f64().unwrap());
    close(to, s_stand["final_loss"].as_f64().unwrap());
    assert_eq!(row[5], "grasped 0/4 → 0/4; holes 0+0 → 0+0", "{row:?}");
    assert_eq!(row[6], "0", "failed trials");

    let row = cells(&table, "chain");
    assert_eq!(row[2], "3");
    let (from, to) = losses(row[3]);
    close(from, s_chain["initial_loss"].as_f64().unwrap());
    close(to, s_chain["final_loss"].as_f64().unwrap());
    assert_eq!(row[8], "—", "three iterations have no 100-iteration window");
    let iterate = &s_chain["extra"]["result"];
    assert_eq!(
        row[4],
        format!(
            "{} ({})",
            iterate["iterate"].as_str().unwrap(),
            iterate["iteration"]
        )
    );
    let wall = s_chain["wall_seconds"].as_f64().unwrap();
    assert_eq!(row[9], format!("{wall:.0}"));

    assert!(cells(&table, "none")[1].starts_with("(missing:"), "{table}");
}
