"""A hyper-parameter × seed sweep of the chain-reaching co-design on Ray.

Each run (`sdrs.Task.optimize`, the Rust optimizer of `sdrs optimize`) is a
Ray task; the results are bitwise those of the same runs made serially
(`--check` runs them serially too and compares).

Local (this machine):     .venv/bin/python examples/python/ray_sweep.py
Multi-node cluster:       ray start --head                      (head node)
                          ray start --address=HEAD_IP:6379      (each worker)
                          .venv/bin/python examples/python/ray_sweep.py --address auto
Every node needs this repository (same path) with `bash tools/setup/setup_python.sh`
run, or a shared file system: the tasks read their files by path.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import ray

import sdrs.ray as sr

HERE = Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--address", default=None, help="Ray cluster address (default: start a local one)")
    ap.add_argument("--iters", type=int, default=20)
    ap.add_argument("--steps", type=float, nargs="+", default=[0.005, 0.01, 0.02], help="step_design values")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--noise", type=float, default=0.05, help="optimizer.init_noise of every variant")
    ap.add_argument("--check", action="store_true", help="also run serially and compare bitwise")
    a = ap.parse_args()

    ray.init(address=a.address)
    print(f"Ray cluster: {ray.cluster_resources().get('CPU', 0):.0f} CPUs")
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for k, step in enumerate(a.steps):
            variant = sr.task_variant(HERE / "chain_reach_adam.yaml", Path(tmp) / f"v{k}.yaml",
                                      step_design=step, init_noise=a.noise)
            runs += [(variant, seed) for seed in a.seeds]
        t0 = time.perf_counter()
        results = sr.sweep_runs(runs, iters=a.iters)
        wall = time.perf_counter() - t0
        print(f"{len(runs)} runs of {a.iters} iterations on Ray in {wall:.1f} s")
        for (task, seed), r in zip(runs, results):
            print(f"  {Path(task).name} seed {seed}: loss {r['initial_loss']:.4e} -> {r['loss']:.4e}")
        if a.check:
            t0 = time.perf_counter()
            serial = sr.serial_runs(runs, iters=a.iters)
            same = all(
                x["loss"] == y["loss"] and x["design"].tobytes() == y["design"].tobytes()
                and x["history"].tobytes() == y["history"].tobytes()
                for x, y in zip(results, serial)
            )
            print(f"serial: {time.perf_counter() - t0:.1f} s; bitwise equal to the Ray sweep: {same}")
            if not same:
                raise SystemExit(1)
    ray.shutdown()


if __name__ == "__main__":
    main()
