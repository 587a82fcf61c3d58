"""Chain-reaching co-design in a PyTorch training loop.

The design (8 attachment points of the left chain) and the cart's spline
controller are torch tensors; `sdrs.torch.rollout` simulates the 250-step
task and its backward pass is the Rust adjoint. torch.optim.Adam with the
task's step sizes (and the design clamped to its box after each step) is
the algorithm of `sdrs optimize` with `method: adam`, so both reach the same
loss; `--compare` runs the Rust optimizer too and prints both.

    .venv/bin/python examples/python/chain_reach_torch.py [--iters 60] [--compare]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch
import yaml

import sdrs
import sdrs.torch as st

HERE = Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", type=Path, default=HERE / "chain_reach_adam.yaml")
    ap.add_argument("--iters", type=int, default=None, help="default: the task's")
    ap.add_argument("--compare", action="store_true", help="also run the Rust optimizer")
    a = ap.parse_args()

    task = sdrs.Task.load(a.task)
    opt_spec = yaml.safe_load(a.task.read_text())["optimizer"]
    iters = a.iters if a.iters is not None else opt_spec["iters"]
    d = torch.tensor(task.design, dtype=torch.float64, requires_grad=True)
    c = torch.tensor(task.controller, dtype=torch.float64, requires_grad=True)
    lo = torch.tensor(task.design_lower)
    hi = torch.tensor(task.design_upper)
    opt = torch.optim.Adam(
        [
            {"params": [d], "lr": opt_spec["step_design"]},
            {"params": [c], "lr": opt_spec["step_controller"]},
        ]
    )
    print(f"{task}: {len(d)} design and {len(c)} controller variables")
    t0 = time.perf_counter()
    losses = []
    for it in range(iters + 1):
        opt.zero_grad()
        loss = st.rollout(task, d, c)  # forward: one Rust rollout
        losses.append(loss.item())
        if it == iters:
            break
        loss.backward()  # backward: one Rust adjoint pass
        opt.step()
        with torch.no_grad():  # the design box (the projection of sdrs optimize)
            d.copy_(torch.maximum(torch.minimum(d, hi), lo))
        if it % 10 == 0:
            print(f"  iteration {it:3d}  loss {losses[-1]:.6e}")
    wall = time.perf_counter() - t0
    print(f"torch.optim.Adam: loss {losses[0]:.6e} -> {losses[-1]:.6e} in {iters} iterations ({wall:.1f} s)")
    if a.compare:
        t0 = time.perf_counter()
        rust = task.optimize(iters=iters)
        wall = time.perf_counter() - t0
        # The last iterate's loss (rust["loss"] is the task's `optimizer.result`,
        # by default the lowest loss seen; the torch loop above ends at its last).
        last = rust["history"][-1]
        rel = abs(last - losses[-1]) / abs(last)
        print(f"sdrs optimize (Rust Adam): loss {rust['initial_loss']:.6e} -> {last:.6e} ({wall:.1f} s)")
        print(f"relative difference of the final losses: {rel:.2e}")


if __name__ == "__main__":
    main()
