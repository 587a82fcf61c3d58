#!/usr/bin/env python3
"""One markdown row per `sdrs optimize` output folder, from its summary.json:
the task, design on/off, iterations, the loss (initial → the returned
iterate's, and which iterate that is), the task's own metrics (distance,
upright at H and first fall for locomotion; grasped before → after and the
links' through-holes before → after for grasping), failed trials, the
optimizer's own convergence flag, the best loss's relative change over the
last 100 iterations (history.csv), and the run's wall time. So the outcome
tables of docs/paper-benchmarks.md come from the run folders, not from
figures copied by hand. (tools/gen/locomotion_table.py is the locomotion
benchmarks' own table, with the paper's figures and the ratio.)

    tools/gen/outcomes_table.py [--label NAME=DIR ...] DIR ...

A DIR that has no summary.json is listed as missing (an unfinished run).
"""
import argparse
import json
from pathlib import Path


def holes(topology, when):
    """Through-holes per link, `a+b` over the links, at `when`."""
    links = topology.get(when) or {}
    return "+".join(str(v.get("holes", 0)) for _, v in sorted(links.items())) or "—"


def outcome(metrics):
    """The task's own outcome from `extra.metrics` (locomotion or grasping)."""
    parts = []
    f = metrics.get("final") or {}
    if "distance" in f:
        state = "upright" if f.get("upright_at_horizon") else "falls"
        if state == "falls" and f.get("first_fall_time") is not None:
            state += f" at {f['first_fall_time']:.2f} s"
        parts.append(f"{metrics['initial']['distance']:.3f} → {f['distance']:.3f} m, {state}")
    g = metrics.get("grasp") or {}
    if g.get("trajectories"):
        n = g["trajectories"]
        parts.append(f"grasped {g['grasped_before']}/{n} → {g['grasped_after']}/{n}")
        if "topology" in metrics:
            t = metrics["topology"]
            parts.append(f"holes {holes(t, 'before')} → {holes(t, 'after')}")
    return "; ".join(parts) or "—"


def last_change(folder, window=100):
    """Relative change of the best loss over the last `window` iterations
    (history.csv), the convergence reading of the locomotion runs."""
    h = Path(folder) / "history.csv"
    if not h.exists():
        return "—"
    best = [float(l.split(",")[2]) for l in h.read_text().splitlines()[1:] if l]
    if len(best) <= window:
        return "—"
    a, b = best[-1 - window], best[-1]
    return f"{(a - b) / abs(a) * 100:.3f} %"


def row(label, folder):
    f = Path(folder) / "summary.json"
    if not f.exists():
        return f"| {label} | (missing: {folder}) ||||||||"
    s = json.loads(f.read_text())
    x = s.get("extra", {})
    res = x.get("result") or {}
    it = f"{res.get('iterate', '?')} ({res.get('iteration', '?')})"
    failed = (x.get("failed_trials") or {}).get("count", 0)
    conv = x.get("converged")
    conv = "—" if conv is None else str(conv)
    return (
        f"| {label} | {x.get('design', '?')} | {s['iterations']} | "
        f"{s['initial_loss']:.4g} → {s['final_loss']:.4g} | {it} | "
        f"{outcome(x.get('metrics') or {})} | {failed} | {conv} | {last_change(folder)} | {s['wall_seconds']:.0f} |"
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--label", action="append", default=[], help="NAME=DIR: a run folder with its row label")
    ap.add_argument("dirs", nargs="*", help="run folders (labelled by their path)")
    a = ap.parse_args()
    runs = [tuple(l.split("=", 1)) for l in a.label] + [(d, d) for d in a.dirs]
    print("| run | design | iterations | loss initial → returned | returned iterate (iteration) | outcome | failed trials | converged | best loss, change over the last 100 | wall s |")
    print("|---|---|---:|---|---|---|---:|---|---:|---:|")
    for label, d in runs:
        print(row(label, d))


if __name__ == "__main__":
    main()
