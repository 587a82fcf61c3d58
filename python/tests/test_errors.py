"""Bad input raises sdrs.SdrsError with the core's message: file, element,
what is wrong."""

from __future__ import annotations

import numpy as np
import pytest

import sdrs


def test_bad_scene_names_file_and_element(data, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text((data / "push.yaml").read_text().replace("mass: 0.5", "mass: -0.5"))
    with pytest.raises(sdrs.SdrsError) as e:
        sdrs.Scene.load(bad)
    msg = str(e.value)
    assert str(bad) in msg and 'link "box".mass' in msg and "-0.5" in msg


def test_malformed_and_missing_scene(tmp_path):
    bad = tmp_path / "malformed.yaml"
    bad.write_text("dt: [1, 2\n")
    with pytest.raises(sdrs.SdrsError, match="malformed.yaml: malformed scene"):
        sdrs.Scene.load(bad)
    with pytest.raises(sdrs.SdrsError, match="missing.yaml: cannot read"):
        sdrs.Scene.load(tmp_path / "missing.yaml")


def test_bad_loss_and_task(data, tmp_path):
    scene = sdrs.Scene.load(data / "push.yaml")
    with pytest.raises(sdrs.SdrsError, match=r"push.yaml: loss\[0\].*nosuch"):
        scene.gradient({"type": "link_point", "link": "box/nosuch", "point": [0, 0, 0],
                        "target": [0, 0, 0]}, steps=2)
    with pytest.raises(sdrs.SdrsError, match="loss"):
        scene.gradient({"type": "no_such_term"}, steps=2)
    task = tmp_path / "task.yaml"
    task.write_text((data / "push_task.yaml").read_text().replace("bound: 0.02", "bound: -1")
                    .replace("scene: push.yaml", f"scene: {data / 'push.yaml'}"))
    with pytest.raises(sdrs.SdrsError, match=r"task.yaml: design.bound: must be positive"):
        sdrs.Task.load(task)


def test_bad_vectors(data):
    task = sdrs.Task.load(data / "push_task.yaml")
    with pytest.raises(sdrs.SdrsError, match="design: expected 27 values, got 2"):
        task.evaluate(np.zeros(2))
    p = task.physics
    p[6] = -1.0
    with pytest.raises(sdrs.SdrsError, match="contact.kappa > 0"):
        task.evaluate(physics=p)
    c = task.controller
    c[0] = np.nan
    with pytest.raises(sdrs.SdrsError, match=r"controller\[0\] is NaN"):
        task.evaluate(controller=c)
    with pytest.raises(sdrs.SdrsError, match="output must be"):
        task.rollout(output="nonsense")


def test_import_robot(root, tmp_path):
    out = tmp_path / "gripper.yaml"
    path = sdrs.import_robot(root / "robots/parallel_jaw_gripper/parallel_jaw_gripper.urdf", out,
                             max_hulls=2, resolution=16)
    assert path == out and out.is_file()
    scene = sdrs.Scene.load(out)
    assert len(scene.link_names) >= 3
    traj = scene.simulate(5)
    assert np.isfinite(traj.q).all()
    # Outputs are never replaced without force=True.
    before = out.read_text()
    with pytest.raises(sdrs.SdrsError, match="exist"):
        sdrs.import_robot(root / "robots/parallel_jaw_gripper/parallel_jaw_gripper.urdf", out)
    assert out.read_text() == before
    with pytest.raises(sdrs.SdrsError, match=r"decomposer: unknown value \"nope\""):
        sdrs.import_robot(root / "robots/parallel_jaw_gripper/parallel_jaw_gripper.urdf", out,
                          decomposer="nope")
