"""Sweeps of SDRS runs (rollouts, co-design optimizations, calibrations) as
Ray tasks.

Each sweep entry runs in a Ray worker process as a remote function that
loads the task or scene file itself (files are read by path, so every node
of a multi-node cluster needs the repository at the same path, or a shared
file system) and returns plain numbers and numpy arrays. The runs are
deterministic, so a sweep gives bitwise the same results as the same runs
made serially with :func:`optimize_serial` / :func:`evaluate_serial`, for
the same ``RAYON_NUM_THREADS`` in every worker.

Cluster use: start Ray on the head node (``ray start --head``) and on each
worker (``ray start --address=HEAD:6379``), then call ``ray.init(address="auto")``
before the sweep instead of a local ``ray.init()``; the code below is
unchanged. See ``examples/python/ray_sweep.py`` and the README.
"""

from __future__ import annotations

import os
from typing import Any, Iterable

import numpy as np
import ray

from ._sdrs import Task, calibrate

__all__ = [
    "task_variant",
    "sweep_runs",
    "serial_runs",
    "optimize_one",
    "evaluate_one",
    "sweep_optimize",
    "sweep_evaluate",
    "optimize_serial",
    "evaluate_serial",
    "calibrate_one",
    "sweep_calibrate",
    "calibrate_serial",
]


def task_variant(task_path: str | os.PathLike, out_path: str | os.PathLike,
                 **optimizer: Any) -> str:
    """Writes a copy of a task file with ``optimizer`` settings replaced
    (e.g. ``step_design=0.02, method="adam"``) and the scene path made
    absolute; returns ``out_path``. For hyper-parameter sweeps."""
    import yaml
    from pathlib import Path

    src = Path(task_path).resolve()
    spec = yaml.safe_load(src.read_text())
    if spec.get("scene"):
        spec["scene"] = str((src.parent / spec["scene"]).resolve())
    spec.setdefault("optimizer", {}).update(optimizer)
    Path(out_path).write_text(yaml.safe_dump(spec, sort_keys=False))
    return str(out_path)


def sweep_runs(runs: Iterable[tuple[str, int]], iters: int | None = None,
               num_cpus: float = 1) -> list[dict[str, Any]]:
    """Co-design runs ``(task_path, seed)`` (e.g. task variants × seeds),
    one Ray task each, results in order."""
    f = _remote(optimize_one, num_cpus)
    return ray.get([f.remote(str(t), s, iters) for t, s in runs])


def serial_runs(runs: Iterable[tuple[str, int]], iters: int | None = None) -> list[dict[str, Any]]:
    """:func:`sweep_runs` in this process, one run after another."""
    return [optimize_one(str(t), s, iters) for t, s in runs]


def optimize_one(task_path: str, seed: int = 0, iters: int | None = None,
                 design: bool = True) -> dict[str, Any]:
    """One co-design run of ``task_path`` (``Task.optimize``) with ``seed``."""
    out = Task.load(str(task_path), design=design).optimize(iters=iters, seed=seed)
    out["seed"] = seed
    out["iters"] = iters
    return out


def evaluate_one(task_path: str, design=None, controller=None, physics=None) -> dict[str, Any]:
    """Loss and gradients of ``task_path`` at one parameter point."""
    arr = lambda x: None if x is None else np.asarray(x, dtype=np.float64)  # noqa: E731
    return Task.load(str(task_path)).evaluate(arr(design), arr(controller), arr(physics))


def _remote(fn, num_cpus: float):
    threads = os.environ.get("RAYON_NUM_THREADS")
    env = {"env_vars": {"RAYON_NUM_THREADS": threads}} if threads else None
    return ray.remote(num_cpus=num_cpus, runtime_env=env)(fn)


def sweep_optimize(task_path: str, seeds: Iterable[int], iters: int | None = None,
                   design: bool = True, num_cpus: float = 1) -> list[dict[str, Any]]:
    """A seed sweep of co-design runs, one Ray task per seed (results in
    ``seeds`` order). Needs ``ray.init(...)`` first."""
    f = _remote(optimize_one, num_cpus)
    return ray.get([f.remote(str(task_path), s, iters, design) for s in seeds])


def sweep_evaluate(task_path: str, points: Iterable[dict[str, Any]],
                   num_cpus: float = 1) -> list[dict[str, Any]]:
    """Loss and gradients at many points (dicts with ``design``,
    ``controller``, ``physics``), one Ray task each."""
    f = _remote(evaluate_one, num_cpus)
    return ray.get([f.remote(str(task_path), p.get("design"), p.get("controller"),
                             p.get("physics")) for p in points])


def optimize_serial(task_path: str, seeds: Iterable[int], iters: int | None = None,
                    design: bool = True) -> list[dict[str, Any]]:
    """:func:`sweep_optimize` in this process, one run after another."""
    return [optimize_one(str(task_path), s, iters, design) for s in seeds]


def evaluate_serial(task_path: str, points: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """:func:`sweep_evaluate` in this process."""
    return [evaluate_one(str(task_path), p.get("design"), p.get("controller"),
                         p.get("physics")) for p in points]


def calibrate_one(scene: str, measured: str, out: str, effects: list[str] | None = None,
                  holdout: float = 0.3) -> dict[str, Any]:
    """One calibration (``sdrs.calibrate``): ``calibration.json`` as a dict."""
    return calibrate(str(scene), str(measured), str(out), effects=effects, holdout=holdout)


def sweep_calibrate(runs: Iterable[dict[str, Any]], num_cpus: float = 1) -> list[dict[str, Any]]:
    """Calibrations (dicts of :func:`calibrate_one`'s arguments: ``scene``,
    ``measured``, ``out``, optional ``effects``, ``holdout``), e.g. one per
    measured data set, one Ray task each. Each run writes its own ``out``."""
    f = _remote(calibrate_one, num_cpus)
    return ray.get([f.remote(**r) for r in runs])


def calibrate_serial(runs: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """:func:`sweep_calibrate` in this process."""
    return [calibrate_one(**r) for r in runs]
