"""Type stubs of the Rust extension module ``sdrs._sdrs`` (PyO3)."""

from os import PathLike
from typing import Any, Literal, Mapping, Sequence

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_I64 = npt.NDArray[np.int64]
_Path = str | PathLike[str]
_LossSpec = Mapping[str, Any] | Sequence[Mapping[str, Any]]

class SdrsError(Exception):
    """An error of the SDRS core; the message names the file, the element and what is wrong."""

class Trajectory:
    """A simulated run as numpy arrays (row ``k`` = the state after ``k`` steps)."""

    @property
    def t(self) -> _F64:
        """Times (s), shape ``(K+1,)``."""
    @property
    def q(self) -> _F64:
        """Reported coordinates, shape ``(K+1, ndof)`` (the CLI CSV's columns after ``t``)."""
    @property
    def names(self) -> list[str]:
        """Coordinate names."""
    @property
    def link_names(self) -> list[str]:
        """Link names ``robot/link``."""
    @property
    def poses(self) -> _F64:
        """World link poses ``[R | p]``, shape ``(K+1, nlinks, 3, 4)`` (``(0, …)`` without poses)."""
    @property
    def contact_pairs(self) -> _I64:
        """Hull pairs in contact after each step, shape ``(K,)``."""
    @property
    def min_distance(self) -> _F64:
        """Smallest candidate-pair distance after each step (m), shape ``(K,)``."""
    @property
    def newton_iterations(self) -> _I64:
        """Newton iterations per step, shape ``(K,)``."""
    def to_csv(self) -> str:
        """The trajectory CSV exactly as ``sdrs simulate --out`` writes it."""
    def __len__(self) -> int: ...

class Scene:
    """A scene file loaded and validated."""

    @staticmethod
    def load(path: _Path) -> Scene:
        """Reads and validates a scene YAML (raises :class:`SdrsError`)."""
    @property
    def path(self) -> str:
        """The scene file."""
    @property
    def steps(self) -> int:
        """The scene's default number of steps."""
    @property
    def dt(self) -> float:
        """Time step (s)."""
    @property
    def dof_names(self) -> list[str]:
        """Coordinate names."""
    @property
    def link_names(self) -> list[str]:
        """Link names ``robot/link``."""
    def simulate(self, steps: int | None = None, poses: bool = True) -> Trajectory:
        """Runs ``steps`` steps with the GIL released, exactly as ``sdrs simulate``."""
    design: _F64
    """Every attachment point and hull vertex (m); names in :attr:`design_names`."""
    @property
    def design_names(self) -> list[str]:
        """``robot/link.attach.x`` …, ``robot/link.hull<h>.v<k>.x`` …"""
    controller: _F64
    """Per controller channel: signal parameters, ``kp``, ``kd``."""
    @property
    def controller_names(self) -> list[str]:
        """Names of the controller vector."""
    physics: _F64
    """``[mass_scale, gravity.x, gravity.y, gravity.z, contact.mu, contact.s, contact.kappa]``."""
    @property
    def physics_names(self) -> list[str]:
        """Names of the physics vector."""
    q0: _F64
    """Initial coordinates."""
    qdot0: _F64
    """Initial velocities."""
    def gradient(self, loss: _LossSpec, steps: int | None = None) -> dict[str, Any]:
        """Adjoint gradients of ``loss`` (task-file ``loss:`` format): ``loss``, ``design``,
        ``controller``, ``physics``, ``q0``, ``qdot0``, ``attachments``."""
    def loss(self, loss: _LossSpec, steps: int | None = None) -> float:
        """The loss alone (forward pass only)."""

class Rollout:
    """A recorded rollout awaiting its backward pass (:meth:`Task.rollout`)."""

    @property
    def value(self) -> float | _F64:
        """The loss, or ``θ^H`` for ``output="state"``."""
    def backward(self, grad: float | Sequence[float]) -> dict[str, _F64]:
        """One adjoint pass: ``{design, controller, physics}`` vector–Jacobian products."""

class Task:
    """A co-design task file, as ``sdrs optimize`` loads it."""

    @staticmethod
    def load(path: _Path, design: bool = True, seed: int = 0) -> Task:
        """Loads a task and its scene (``design=False``: the controller alone,
        on the co-design start's robot for ``seed`` when the task sets
        ``optimizer.design_init_noise``)."""
    @property
    def path(self) -> str: ...
    @property
    def horizon(self) -> int:
        """Steps per rollout."""
    @property
    def design(self) -> _F64:
        """Initial design vector."""
    @property
    def design_names(self) -> list[str]: ...
    @property
    def design_lower(self) -> _F64: ...
    @property
    def design_upper(self) -> _F64: ...
    @property
    def controller(self) -> _F64:
        """Initial controller vector."""
    @property
    def controller_names(self) -> list[str]: ...
    @property
    def physics(self) -> _F64:
        """The scene's physics vector."""
    @property
    def physics_names(self) -> list[str]: ...
    def start(self, seed: int = 0) -> tuple[_F64, _F64]:
        """The optimizer's starting ``(design, controller)`` for ``seed``."""
    def evaluate(
        self,
        design: _F64 | None = None,
        controller: _F64 | None = None,
        physics: _F64 | None = None,
    ) -> dict[str, Any]:
        """Loss and gradients ``{loss, design, controller, physics}`` (one forward, one backward)."""
    def rollout(
        self,
        design: _F64 | None = None,
        controller: _F64 | None = None,
        physics: _F64 | None = None,
        output: Literal["loss", "state"] = "loss",
    ) -> Rollout:
        """The forward pass of :func:`sdrs.torch.rollout`, keeping the tape."""
    def optimize(self, iters: int | None = None, seed: int = 0) -> dict[str, Any]:
        """The Rust optimizer of ``sdrs optimize``: ``{loss, initial_loss, history, design, controller}``.

        ``design``, ``controller`` and ``loss`` are the iterate the task's ``optimizer.result``
        selects (default ``best``: the lowest loss seen); ``history`` holds every iterate's loss."""

def import_robot(
    input: _Path,
    out: _Path,
    *,
    decomposer: str = "vhacd",
    max_hulls: int = 16,
    resolution: int = 64,
    threshold: float | None = None,
    designable: Sequence[str] | None = None,
    mass: str = "urdf",
    density: float = 1000.0,
    report: _Path | None = None,
    force: bool = False,
    bridge: bool = True,
    ties: str = "shared_vertex",
    base: str = "auto",
    ground: bool | None = None,
    contact: bool = True,
    hold: bool = True,
    pose: Mapping[str, float] | None = None,
) -> str:
    """``sdrs import INPUT --out OUT`` as a function; returns ``out``."""

def calibrate(
    scene: _Path,
    measured: _Path,
    out: _Path,
    *,
    effects: Sequence[str] | None = None,
    holdout: float = 0.3,
    topic: str | None = None,
    rename: Mapping[str, str] | None = None,
    fit_contact_resolution: bool = False,
) -> dict[str, Any]:
    """``sdrs calibrate SCENE --measured CSV --out OUT`` as a function; returns ``calibration.json``.
    ``topic``, ``rename`` ({log joint: scene coordinate, "" ignores it}) and
    ``fit_contact_resolution`` are ``--topic``, ``--rename`` and
    ``--fit-contact-resolution``."""

def num_threads() -> int:
    """Threads of the core's rayon pool."""
