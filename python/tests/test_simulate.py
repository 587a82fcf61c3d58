"""`Scene.simulate` against the CLI: the same run, bit for bit."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import sdrs


def read_csv(path):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    return header, np.array(rows)


@pytest.mark.parametrize(
    "scene,steps",
    [
        ("python/tests/data/push.yaml", 40),  # contact and friction
        ("robots/four_chains.yaml", 60),  # four chains, ball joints (charts)
        ("robots/triple_pendulum.yaml", 100),
        ("robots/box_on_slope_mu08.yaml", 50),  # a free body resting with friction
    ],
)
def test_simulate_equals_cli_csv_bitwise(root, cli, tmp_path, scene, steps):
    out = tmp_path / "traj.csv"
    subprocess.run(
        [str(cli), "simulate", str(root / scene), "--steps", str(steps), "--out", str(out), "-q"],
        check=True,
        capture_output=True,
    )
    s = sdrs.Scene.load(root / scene)
    traj = s.simulate(steps)
    # The same text as the CLI's writer ...
    assert traj.to_csv() == out.read_text()
    # ... and the numpy arrays are bitwise the CLI's numbers.
    header, table = read_csv(out)
    assert header == ["t", *traj.names] == ["t", *s.dof_names]
    assert traj.q.shape == (steps + 1, len(s.dof_names))
    assert np.array_equal(traj.t, table[:, 0])
    assert np.array_equal(traj.q, table[:, 1:])
    assert traj.q.tobytes() == np.ascontiguousarray(table[:, 1:]).tobytes()
    # The run moves (a test of a frozen scene would prove little).
    assert np.abs(traj.q[-1] - traj.q[0]).max() > 1e-4


def test_trajectory_poses_and_contact_statistics(root):
    s = sdrs.Scene.load(root / "python/tests/data/push.yaml")
    traj = s.simulate(40)
    assert traj.poses.shape == (41, len(s.link_names), 3, 4)
    box = s.link_names.index("box/box")
    # The box's pose translation is its free-joint position.
    iz = traj.names.index("box/box:z")
    assert np.allclose(traj.poses[:, box, 2, 3], traj.q[:, iz], atol=1e-12)
    # Rotations are orthonormal.
    r = traj.poses[:, box, :, :3]
    assert np.allclose(r @ np.swapaxes(r, 1, 2), np.eye(3), atol=1e-12)
    # Box–ground and finger–box in contact at every step, never penetrating.
    assert traj.contact_pairs.shape == (40,)
    assert (traj.contact_pairs == 2).all()
    assert (traj.min_distance > 0).all() and (traj.min_distance < 0.02).all()
    assert (traj.newton_iterations >= 1).all()
    # Without poses recorded, the coordinates are the same.
    bare = s.simulate(40, poses=False)
    assert bare.poses.shape == (0, len(s.link_names), 3, 4)
    assert np.array_equal(bare.q, traj.q)


def test_design_controller_physics_vectors_change_the_run(root):
    s = sdrs.Scene.load(root / "python/tests/data/push.yaml")
    base = s.simulate(40, poses=False).q
    names = s.design_names
    assert len(names) == len(s.design) and "finger/pusher.attach.x" in names
    ix = names.index("finger/pusher.attach.x")
    d = s.design
    d[ix] += 0.004  # the finger starts 4 mm closer to the box
    s.design = d
    assert s.design[ix] == d[ix]
    moved = s.simulate(40, poses=False).q
    bx = s.dof_names.index("box/box:x")
    assert moved[-1, bx] > base[-1, bx] + 1e-3
    # Physics: no friction lets the pushed box slide farther.
    p = s.physics
    assert s.physics_names == [
        "mass_scale", "gravity.x", "gravity.y", "gravity.z",
        "contact.mu", "contact.s", "contact.kappa",
    ]
    assert p[4] == 0.4
    p[4] = 0.0
    s.physics = p
    assert s.simulate(40, poses=False).q[-1, bx] > moved[-1, bx]
    # Controller: a stiffer spline target pushes farther.
    c = s.controller
    assert s.controller_names[-2:] == ["finger/slide.kp", "finger/slide.kd"]
    with pytest.raises(sdrs.SdrsError, match="expected"):
        s.controller = c[:-1]


def test_simulate_releases_the_gil(root):
    import threading

    s = sdrs.Scene.load(root / "robots/four_chains.yaml")
    count = 0
    result = {}
    th = threading.Thread(target=lambda: result.setdefault("t", s.simulate(150, poses=False)))
    th.start()
    # While the simulation runs, this thread keeps running Python code: with
    # the GIL held by the simulation it could not count at all.
    while th.is_alive():
        count += 1
    th.join()
    assert len(result["t"]) == 151
    assert count > 10_000, count


def test_threads_run_simulations_concurrently_with_equal_results(root):
    from concurrent.futures import ThreadPoolExecutor

    s = sdrs.Scene.load(root / "python/tests/data/push.yaml")
    serial = [s.simulate(40, poses=False).q for _ in range(3)]
    with ThreadPoolExecutor(3) as ex:
        parallel = list(ex.map(lambda _: s.simulate(40, poses=False).q, range(3)))
    for a, b in zip(serial, parallel):
        assert np.array_equal(a, b)
    assert sdrs.num_threads() >= 1


def test_rayon_pool_is_configurable_and_results_do_not_depend_on_it(root):
    """The core's rayon pool runs inside `simulate` from Python:
    RAYON_NUM_THREADS sets its size, and the contact sums are reduced in pair
    order, so one thread and two give the same bits on a scene with contact."""
    import os
    import subprocess
    import sys

    code = (
        "import sys, sdrs; s = sdrs.Scene.load(sys.argv[1]); "
        "sys.stdout.write(str(sdrs.num_threads()) + ' '); "
        "sys.stdout.write(s.simulate(40, poses=False).q.tobytes().hex())"
    )
    out = {}
    for n in ("1", "2"):
        r = subprocess.run([sys.executable, "-c", code, str(root / "python/tests/data/push.yaml")],
                           env=dict(os.environ, RAYON_NUM_THREADS=n), check=True,
                           capture_output=True, text=True)
        threads, q = r.stdout.split()
        assert threads == n
        out[n] = q
    assert out["1"] == out["2"]


def test_design_off_twin_keeps_the_co_design_starts_robot(root, tmp_path):
    """``Task.load(…, design=False, seed=S)`` of a task with
    ``optimizer.design_init_noise``: the controller-only twin's robot is the
    co-design start's for the same seed (the same loss at the start, bitwise),
    and another seed gives another robot (as ``sdrs optimize --design off``)."""
    import yaml

    src = root / "examples/python/chain_reach_adam.yaml"
    spec = yaml.safe_load(src.read_text())
    spec["scene"] = str((src.parent / spec["scene"]).resolve())
    spec["optimizer"]["design_init_noise"] = 0.01
    path = tmp_path / "task.yaml"
    path.write_text(yaml.safe_dump(spec))
    on = sdrs.Task.load(path)
    d, c = on.start(seed=3)
    twin = sdrs.Task.load(path, design=False, seed=3)
    assert len(twin.design) == 0
    assert twin.evaluate(controller=c)["loss"] == on.evaluate(design=d, controller=c)["loss"]
    other = sdrs.Task.load(path, design=False, seed=4)
    assert other.evaluate(controller=c)["loss"] != twin.evaluate(controller=c)["loss"]
