"""Adjoint gradients from Python: against the Rust optimizer's adjoint (the
CLI), between the Scene and Task paths, and against central differences,
through active contact and friction (python/tests/data/push*.yaml)."""

from __future__ import annotations

import csv
import subprocess

import numpy as np
import pytest
import yaml

import sdrs
from conftest import rel_err

TASK = "python/tests/data/push_task.yaml"


@pytest.fixture(scope="module")
def task(root):
    return sdrs.Task.load(root / TASK)


@pytest.fixture(scope="module")
def grads(task):
    return task.evaluate()


def test_task_gradient_matches_the_cli_adjoint(root, cli, tmp_path, task, grads):
    out = tmp_path / "opt"
    subprocess.run(
        [str(cli), "optimize", str(root / TASK), "--iters", "0", "--out", str(out), "-q"],
        check=True,
        capture_output=True,
    )
    row = next(csv.DictReader((out / "history.csv").open()))
    # The loss is the CLI's, bit for bit; the gradient norms to 1e-12.
    assert float(row["loss"]) == grads["loss"]
    assert rel_err(np.linalg.norm(grads["design"]), float(row["grad_design_norm"]), 1e-300) <= 1e-12
    assert rel_err(np.linalg.norm(grads["controller"]), float(row["grad_controller_norm"]), 1e-300) <= 1e-12
    assert np.linalg.norm(grads["design"]) > 0.1 and np.linalg.norm(grads["controller"]) > 0.01


def test_scene_gradient_matches_task_gradient(root, task, grads):
    """`Scene.gradient` (the scene's full design and controller vectors)
    agrees with `Task.evaluate` on the variables both have."""
    spec = yaml.safe_load((root / TASK).read_text())
    scene = sdrs.Scene.load(root / "python/tests/data/push.yaml")
    g = scene.gradient(spec["loss"], steps=task.horizon)
    assert g["loss"] == grads["loss"]
    names = scene.design_names
    for i, n in enumerate(task.design_names):
        a, b = grads["design"][i], g["design"][names.index(n)]
        assert rel_err(a, b, 1e-300) <= 1e-12 or a == b, n
    cnames = scene.controller_names
    for i, n in enumerate(task.controller_names):
        a, b = grads["controller"][i], g["controller"][cnames.index(n)]
        assert rel_err(a, b, 1e-300) <= 1e-12 or a == b, n
    assert np.allclose(g["physics"], grads["physics"], rtol=1e-12, atol=0)
    assert g["q0"].shape == (len(scene.dof_names),) and g["attachments"].shape == (3, 3)
    # The loss alone (forward only) is the same number.
    assert scene.loss(spec["loss"], steps=task.horizon) == g["loss"]


def _central(f, x0, i, h):
    xp, xm = x0.copy(), x0.copy()
    xp[i] += h
    xm[i] -= h
    return (f(xp) - f(xm)) / (2 * h)


def test_task_gradients_match_central_differences(task, grads):
    """Every design, controller and physics entry within a relative error of
    1e-4 (steps 1e-6, relative for κ and s). Entries whose gradient is zero
    (finger vertices whose motion changes nothing along the slide) are
    checked against a floor of 1e-3 × the group's largest entry (an
    absolute error of 1e-7 × it): the differences' round-off is ~1e-9
    (Newton tolerance 1e-10, steps 1e-6)."""
    d0, c0, p0 = task.design, task.controller, task.physics
    groups = {
        "design": (d0, lambda x: task.evaluate(x, c0, p0)["loss"]),
        "controller": (c0, lambda x: task.evaluate(d0, x, p0)["loss"]),
        "physics": (p0, lambda x: task.evaluate(d0, c0, x)["loss"]),
    }
    worst = 0.0
    for key, (x0, f) in groups.items():
        floor = 1e-3 * np.abs(grads[key]).max()
        for i in range(len(x0)):
            h = 1e-6 * (abs(x0[i]) if key == "physics" and x0[i] != 0 else 1.0)
            fd = _central(f, x0, i, h)
            e = rel_err(grads[key][i], fd, floor)
            worst = max(worst, e)
            assert e <= 1e-4, (key, i, grads[key][i], fd)
    print(f"worst relative error {worst:.2e}")
    # Contact and friction matter here: the gradient w.r.t. μ and κ is not 0.
    assert abs(grads["physics"][4]) > 1e-3 and abs(grads["physics"][6]) > 0


def test_scene_initial_state_gradients_match_central_differences(root, task):
    spec = yaml.safe_load((root / TASK).read_text())["loss"]
    scene = sdrs.Scene.load(root / "python/tests/data/push.yaml")
    g = scene.gradient(spec, steps=task.horizon)
    q0, v0 = scene.q0, scene.qdot0

    def loss_at(q=q0, v=v0):
        scene.q0, scene.qdot0 = q, v
        return scene.loss(spec, steps=task.horizon)

    for k in (0, 1, 3):  # finger slide, box x, box z
        fd = _central(lambda x: loss_at(q=x), q0, k, 1e-6)
        assert rel_err(g["q0"][k], fd, 1e-8) <= 1e-4, (k, g["q0"][k], fd)
        fd = _central(lambda x: loss_at(v=x), v0, k, 1e-4)
        assert rel_err(g["qdot0"][k], fd, 1e-8) <= 1e-4, (k, g["qdot0"][k], fd)
    loss_at()
