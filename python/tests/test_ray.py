"""Sweeps on a local Ray cluster (started here with 2 CPUs) equal the same
runs made serially, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
import ray

import sdrs
import sdrs.ray as sr


@pytest.fixture(scope="module")
def cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    assert ray.cluster_resources()["CPU"] == 2
    yield
    ray.shutdown()


def test_seed_sweep_of_codesign_runs_equals_serial(cluster, data):
    task = data / "push_sweep.yaml"
    seeds = [0, 1, 2, 3]
    remote = sr.sweep_optimize(task, seeds, iters=3)
    serial = sr.optimize_serial(task, seeds, iters=3)
    assert [r["seed"] for r in remote] == seeds
    for a, b in zip(remote, serial):
        assert a["loss"] == b["loss"] and a["initial_loss"] == b["initial_loss"]
        for key in ("history", "design", "controller"):
            assert a[key].tobytes() == b[key].tobytes(), key
        assert len(a["history"]) == 4 and a["loss"] < a["initial_loss"]
    # The seeds matter (a sweep of identical runs would prove nothing).
    starts = {tuple(sdrs.Task.load(task).start(s)[1]) for s in seeds}
    assert len(starts) == len(seeds)
    assert len({r["loss"] for r in remote}) == len(seeds)


def test_physics_sweep_of_gradients_equals_serial(cluster, data):
    task = data / "push_task.yaml"
    p0 = sdrs.Task.load(task).physics
    points = []
    for mu in (0.2, 0.4, 0.6):
        p = p0.copy()
        p[4] = mu
        points.append({"physics": p})
    remote = sr.sweep_evaluate(task, points)
    serial = sr.evaluate_serial(task, points)
    for a, b in zip(remote, serial):
        assert a["loss"] == b["loss"]
        for key in ("design", "controller", "physics"):
            assert a[key].tobytes() == b[key].tobytes(), key
    assert len({r["loss"] for r in remote}) == 3
    # The μ = 0.4 point is the task itself.
    assert remote[1]["loss"] == sdrs.Task.load(task).evaluate()["loss"]
