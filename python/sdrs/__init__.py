"""SDRS — shape-differentiable robot simulation, from Python.

The Rust core (``sdrs._sdrs``, PyO3) provides:

* :class:`Scene` — ``Scene.load(path)``, ``scene.simulate(steps)`` →
  :class:`Trajectory` (numpy ``t``, ``q``, link ``poses``, contact
  statistics), the ``design`` / ``controller`` / ``physics`` vectors with
  their ``*_names``, and ``scene.gradient(loss)`` (adjoint gradients of a
  loss in the task file's ``loss:`` format w.r.t. every group).
* :class:`Task` — a co-design task file: its spaces, ``evaluate``, the
  ``rollout``/``backward`` pair behind :func:`sdrs.torch.rollout`, and
  ``optimize`` (the Rust optimizer of ``sdrs optimize``).
* :func:`import_robot` — ``sdrs import`` as a function; :func:`calibrate` —
  ``sdrs calibrate`` as a function.

``sdrs.torch`` (needs PyTorch) wraps a rollout as a
``torch.autograd.Function``; ``sdrs.ray`` (needs Ray) runs sweeps of
rollouts and optimizations as Ray tasks. Errors raise :class:`SdrsError`
with the core's message (file, element, what is wrong). Simulations run
with the GIL released.
"""

from ._sdrs import (
    Rollout,
    Scene,
    SdrsError,
    Task,
    Trajectory,
    calibrate,
    import_robot,
    num_threads,
)

__all__ = [
    "Rollout",
    "Scene",
    "SdrsError",
    "Task",
    "Trajectory",
    "calibrate",
    "import_robot",
    "num_threads",
]
