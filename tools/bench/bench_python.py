#!/usr/bin/env python3
"""Overhead of the Python package: a 1000-step four-chain rollout
(robots/four_chains.yaml) from Python vs the `sdrs simulate` CLI.

Runs alternate (CLI, Python, CLI, …) `--repeats` times each and reports
medians of
  * simulation time: the CLI's own measured run time (its stderr line
    "… in X s") vs the time around `Scene.simulate(steps)` in Python;
  * end to end: the whole `sdrs simulate` process vs a whole Python process
    (`import sdrs`, `Scene.load`, `simulate`).
Both use the same rayon thread count (RAYON_NUM_THREADS, default: cores).
Run with `nice -n 5` on a shared machine:

    nice -n 5 .venv/bin/python tools/bench/bench_python.py [--steps 1000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PY_RUN = """
import sys, time
t0 = time.perf_counter()
import sdrs
s = sdrs.Scene.load(sys.argv[1])
t1 = time.perf_counter()
traj = s.simulate(int(sys.argv[2]), poses=False)
t2 = time.perf_counter()
print(t2 - t1, len(traj))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "robots/four_chains.yaml"))
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    exe = ROOT / os.environ.get("CARGO_TARGET_DIR", "target") / "release" / "sdrs"
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "sdrs-cli"], cwd=ROOT, check=True)
    cli_sim, cli_total, py_sim, py_total = [], [], [], []
    for k in range(a.repeats):
        t0 = time.perf_counter()
        r = subprocess.run([str(exe), "simulate", a.scene, "--steps", str(a.steps), "-q"],
                           check=True, capture_output=True, text=True)
        cli_total.append(time.perf_counter() - t0)
        m = re.search(r"steps of \S+ s in ([0-9.]+) s", r.stderr)
        assert m, r.stderr
        cli_sim.append(float(m.group(1)))
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-c", PY_RUN, a.scene, str(a.steps)],
                           check=True, capture_output=True, text=True)
        py_total.append(time.perf_counter() - t0)
        sim, n = r.stdout.split()
        assert int(n) == a.steps + 1
        py_sim.append(float(sim))
        print(f"run {k + 1}: simulation CLI {cli_sim[-1]:.3f} s, Python {py_sim[-1]:.3f} s; "
              f"process CLI {cli_total[-1]:.3f} s, Python {py_total[-1]:.3f} s", flush=True)
    med = statistics.median
    print(f"\n{a.steps} steps of {Path(a.scene).name}, median of {a.repeats}:")
    print(f"  simulation: CLI {med(cli_sim):.3f} s, Python {med(py_sim):.3f} s "
          f"({100 * (med(py_sim) / med(cli_sim) - 1):+.1f}%)")
    print(f"  whole process: CLI {med(cli_total):.3f} s, Python {med(py_total):.3f} s "
          f"({100 * (med(py_total) / med(cli_total) - 1):+.1f}%, Python start-up and imports included)")


if __name__ == "__main__":
    main()
