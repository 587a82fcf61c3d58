//! `sdrs plot`: co-design against controller-only on one plot, labelled by
//! task and mode, with a titled, ticked loss axis; bad input named.

use crate::support;

use support::{robots, scratch_dir, sdrs};

#[test]
fn codesign_and_controller_only_on_one_labelled_plot() {
    let dir = scratch_dir("plot");
    for mode in ["on", "off"] {
        let o = sdrs()
            .args(["optimize", "-q", "--iters", "3", "--design", mode, "--out"])
            .arg(dir.join(mode))
            .arg(robots("chain_reach/task.yaml"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let svg = dir.join("cmp.svg");
    let o = sdrs()
        .arg("plot")
        .arg(dir.join("on"))
        .arg(dir.join("off"))
        .arg("--out")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&svg).unwrap();
    for s in [
        "chain_reach: co-design",
        "chain_reach: controller-only",
        "chain_reach: best loss per iteration",
        "best task loss",
        "iteration",
    ] {
        assert!(text.contains(s), "missing `{s}`");
    }
    assert!(y_ticks(&text) >= 2, "{} y tick label(s)", y_ticks(&text));
    // Every plot `optimize` writes: titled with the task and mode, and at
    // least two labelled ticks on the loss axis.
    for (mode, label) in [
        ("on", "chain_reach: co-design"),
        ("off", "chain_reach: controller-only"),
    ] {
        let conv = std::fs::read_to_string(dir.join(mode).join("convergence.svg")).unwrap();
        assert!(
            conv.contains(&format!("{label}, best loss per iteration")),
            "{mode}: title"
        );
        assert!(
            y_ticks(&conv) >= 2,
            "{mode}: {} y tick label(s)",
            y_ticks(&conv)
        );
    }
    // Not an optimize output: named.
    let o = sdrs()
        .arg("plot")
        .arg(dir.join("nowhere"))
        .arg("--out")
        .arg(dir.join("x.svg"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("nowhere") && e.contains("history.csv"),
        "{e}"
    );
}

/// Labelled ticks on the y axis: text elements left of the plot area
/// (x < 75 px) other than the axis title.
fn y_ticks(svg: &str) -> usize {
    svg.split("<text")
        .skip(1)
        .filter(|t| {
            t.split("x=\"")
                .nth(1)
                .and_then(|r| r.split('"').next())
                .and_then(|x| x.parse::<f64>().ok())
                .is_some_and(|x| x < 75.0)
                && !t.contains("best task loss")
        })
        .count()
}
