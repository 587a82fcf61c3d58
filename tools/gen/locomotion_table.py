#!/usr/bin/env python3
"""Markdown table of the locomotion benchmarks (tools/bench/bench_locomotion.sh)
from OUT/<robot>_<on|off>/summary.json, next to the paper's figures."""
import json
import sys
from pathlib import Path

PAPER = {
    ("spider", "on"): "5.33 (+8.78%)",
    ("spider", "off"): "4.90",
    ("biped", "on"): "keeps balance, walks",
    ("biped", "off"): "falls",
}


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/bench_locomotion")
    print("| task | design | iters | loss initial → final | distance initial → final (m) | upright at H | first fall (s) | wall (min) | fwd (s) | bwd (s) | bwd/fwd | paper |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    dist = {}
    for robot in ("spider", "biped"):
        for design in ("on", "off"):
            f = out / f"{robot}_{design}" / "summary.json"
            if not f.exists():
                print(f"| {robot} | {design} | (missing) |||||||||| {PAPER[(robot, design)]} |")
                continue
            s = json.loads(f.read_text())
            m = s["extra"]["metrics"]
            i, fin = m["initial"], m["final"]
            dist[(robot, design)] = fin["distance"]
            fall = fin["first_fall_time"]
            print(
                f"| {robot} | {design} | {s['iterations']} | {s['initial_loss']:.3f} → {s['final_loss']:.3f} "
                f"| {i['distance']:.3f} → {fin['distance']:.3f} | {'yes' if fin['upright_at_horizon'] else 'no'} "
                f"| {'—' if fall is None else f'{fall:.2f}'} | {s['wall_seconds'] / 60:.1f} "
                f"| {s['mean_forward_seconds']:.2f} | {s['mean_backward_seconds']:.2f} | {s['backward_over_forward']:.2f} "
                f"| {PAPER[(robot, design)]} |"
            )
    for robot in ("spider", "biped"):
        on, off = dist.get((robot, "on")), dist.get((robot, "off"))
        if on is not None and off is not None:
            rel = f"{100 * (on - off) / abs(off):+.1f}% of |controller-only|" if off != 0 else "n/a"
            print(f"\n{robot}: co-design − controller-only distance = {on - off:+.3f} m ({rel})")


if __name__ == "__main__":
    main()
