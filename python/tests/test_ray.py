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


def _measured(root, tmp_path, damping: float) -> str:
    """A 'measured' CSV: arm2 with a hidden joint damping, every 10th step."""
    hidden = tmp_path / f"hidden_{damping}.yaml"
    hidden.write_text((root / "robots/calibrate/arm2.yaml").read_text()
                      + f"effects:\n  - {{effect: joint_damping, on: all, values: [{damping}]}}\n")
    lines = sdrs.Scene.load(hidden).simulate(600, poses=False).to_csv().splitlines()
    out = tmp_path / f"measured_{damping}.csv"
    out.write_text("\n".join([lines[0], *lines[1::10]]) + "\n")
    return str(out)


def test_calibration_sweep_equals_serial(cluster, root, tmp_path):
    scene = str(root / "robots/calibrate/arm2.yaml")
    effects = ["joint_damping", "armature"]
    data = [_measured(root, tmp_path, c) for c in (0.02, 0.05)]
    runs = [dict(scene=scene, measured=m, out=str(tmp_path / f"ray{k}"), effects=effects)
            for k, m in enumerate(data)]
    serial_runs = [dict(r, out=str(tmp_path / f"serial{k}")) for k, r in enumerate(runs)]
    remote = sr.sweep_calibrate(runs)
    serial = sr.calibrate_serial(serial_runs)
    assert remote == serial
    for r, c in zip(remote, (0.02, 0.05)):
        assert r["effect"] == "joint_damping", r["verdict"]
        (value,) = r["parameters"].values()
        assert abs(value - c) < 0.05 * c, r["parameters"]
        assert r["gap_after"]["overall"] < 0.1 * r["gap_before"]["overall"]
    assert (tmp_path / "ray0" / "calibrated.yaml").is_file()
