"""`sdrs.torch.rollout` as a torch.autograd.Function: gradcheck (float64)
through active contact and friction, equality with the Rust adjoint, and a
torch.optim.Adam loop equal to the Rust optimizer's Adam."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import sdrs
import sdrs.torch as st

TASK = "python/tests/data/push_task.yaml"


@pytest.fixture(scope="module")
def task(root):
    return sdrs.Task.load(root / TASK)


def t64(x):
    return torch.tensor(np.asarray(x), dtype=torch.float64, requires_grad=True)


def test_rollout_gradients_equal_the_rust_adjoint(task):
    d, c, p = t64(task.design), t64(task.controller), t64(task.physics)
    loss = st.rollout(task, d, c, p)
    loss.backward()
    g = task.evaluate()
    assert loss.item() == g["loss"]
    for x, key in ((d, "design"), (c, "controller"), (p, "physics")):
        assert np.allclose(x.grad.numpy(), g[key], rtol=1e-12, atol=0), key
    # The chain rule through torch: 3·loss gives 3× the adjoint gradient.
    d2 = t64(task.design)
    (3.0 * st.rollout(task, d2)).backward()
    assert np.allclose(d2.grad.numpy(), 3.0 * g["design"], rtol=1e-12, atol=0)


def test_gradcheck_loss_through_contact_and_friction(root, task):
    # Contact and friction are active at every step of this rollout.
    traj = sdrs.Scene.load(root / "python/tests/data/push.yaml").simulate(task.horizon)
    assert (traj.contact_pairs == 2).all()
    ix = traj.names.index("box/box:x")
    assert traj.q[-1, ix] - traj.q[0, ix] > 0.01  # the box slides (friction works)
    p0 = torch.tensor(task.physics, dtype=torch.float64)
    # Physics in units of each entry's size, so one finite-difference step
    # (1e-6) is relative for κ = 1e-5 and s = 0.01.
    scale = torch.clamp(p0.abs(), max=1.0)
    scale[scale == 0] = 1.0

    def f(d, c, z):
        return st.rollout(task, d, c, p0 + scale * z)

    inputs = (t64(task.design), t64(task.controller), torch.zeros(7, dtype=torch.float64, requires_grad=True))
    assert torch.autograd.gradcheck(f, inputs, eps=1e-6, atol=1e-6, rtol=1e-4)


def test_gradcheck_final_state_output(task):
    p0 = torch.tensor(task.physics, dtype=torch.float64)
    d0 = torch.tensor(task.design, dtype=torch.float64)
    state = st.rollout(task, d0, t64(task.controller), p0, output="state")
    assert state.shape == (7,)
    # The final state of the rollout is the simulation's last row.
    assert np.array_equal(state.detach().numpy(), task.rollout(output="state").value)

    def f(c, z):
        return st.rollout(task, d0, c, p0 + torch.nn.functional.pad(z, (3, 3)), output="state")

    inputs = (t64(task.controller), torch.zeros(1, dtype=torch.float64, requires_grad=True))
    assert torch.autograd.gradcheck(f, inputs, eps=1e-6, atol=1e-6, rtol=1e-4)


def test_rollout_backward_is_repeatable(task):
    """Torch may run backward once per output row: each pass over the kept
    tape gives bitwise the same gradients."""
    r = task.rollout()
    a, b = r.backward(1.0), r.backward(1.0)
    for key in ("design", "controller", "physics"):
        assert np.array_equal(a[key], b[key])
    assert np.array_equal(r.backward(2.0)["design"], 2.0 * a["design"])


def test_torch_adam_equals_the_rust_optimizer(task):
    """Five Adam iterations in torch (lr = the task's steps, design clamped to
    its box) reach the Rust optimizer's losses (`sdrs optimize` with
    `method: adam`) to 1e-10."""
    rust = task.optimize(iters=5)
    d, c = t64(task.design), t64(task.controller)
    lo, hi = torch.tensor(task.design_lower), torch.tensor(task.design_upper)
    opt = torch.optim.Adam([{"params": [d], "lr": 0.001}, {"params": [c], "lr": 0.01}])
    history = []
    for _ in range(6):
        opt.zero_grad()
        loss = st.rollout(task, d, c)
        loss.backward()
        history.append(loss.item())
        opt.step()
        with torch.no_grad():
            d.copy_(torch.maximum(torch.minimum(d, hi), lo))
    assert history[-1] < 0.9 * history[0]
    assert np.allclose(history, rust["history"], rtol=1e-10, atol=0)


def test_float32_inputs_get_float32_gradients(task):
    d = torch.tensor(task.design, dtype=torch.float32, requires_grad=True)
    loss = st.rollout(task, d)
    assert loss.dtype == torch.float64
    loss.backward()
    assert d.grad.dtype == torch.float32
    # The rollout ran at the float32-rounded design, in double precision.
    g = task.evaluate(design=d.detach().double().numpy())
    assert np.array_equal(d.grad.numpy(), g["design"].astype(np.float32))
