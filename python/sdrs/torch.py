"""SDRS as a PyTorch operator.

:func:`rollout` is a ``torch.autograd.Function``: its forward pass simulates
the task's horizon at ``(design, controller, physics)`` (one Rust rollout,
the tape kept), its backward pass is one Rust adjoint pass (no finite
differences). Tensors are float64 on the CPU; inputs of other dtypes are
converted and the gradients are returned in the inputs' dtype.
"""

from __future__ import annotations

import numpy as np
import torch

from ._sdrs import Task

__all__ = ["rollout", "RolloutFunction"]


def _numpy(x: torch.Tensor | None) -> np.ndarray | None:
    if x is None:
        return None
    return np.ascontiguousarray(x.detach().to(device="cpu", dtype=torch.float64).numpy())


class RolloutFunction(torch.autograd.Function):
    """``(design, controller, physics) → loss`` or ``θ^H``; see :func:`rollout`."""

    @staticmethod
    def forward(ctx, task: Task, output: str, design, controller, physics):  # type: ignore[override]
        r = task.rollout(_numpy(design), _numpy(controller), _numpy(physics), output)
        ctx.rollout = r
        # Only dtype and device of each input are needed for the gradients.
        ctx.like = tuple(None if x is None else (x.dtype, x.device) for x in (design, controller, physics))
        value = r.value
        return torch.as_tensor(np.asarray(value, dtype=np.float64))

    @staticmethod
    def backward(ctx, grad):  # type: ignore[override]
        g = grad.detach().to(dtype=torch.float64)
        arg = float(g) if g.dim() == 0 else g.numpy().tolist()
        grads = ctx.rollout.backward(arg)
        out = []
        for key, like, need in zip(
            ("design", "controller", "physics"), ctx.like, ctx.needs_input_grad[2:]
        ):
            if like is None or not need:
                out.append(None)
            else:
                dtype, device = like
                out.append(torch.from_numpy(grads[key]).to(dtype=dtype, device=device))
        return (None, None, *out)


def rollout(
    task: Task,
    design: torch.Tensor | None = None,
    controller: torch.Tensor | None = None,
    physics: torch.Tensor | None = None,
    output: str = "loss",
) -> torch.Tensor:
    """Simulate ``task`` at ``(design, controller, physics)``.

    Each argument is a 1-D tensor of the length of ``task.design``,
    ``task.controller`` and ``task.physics`` (``None``: the task's own value,
    not differentiated). ``output="loss"`` returns the task's loss (a scalar
    tensor); ``output="state"`` returns ``θ^H``, the coordinates after the
    last step. ``backward()`` on anything computed from it runs one Rust
    adjoint pass and fills the inputs' ``.grad``.
    """
    return RolloutFunction.apply(task, output, design, controller, physics)
