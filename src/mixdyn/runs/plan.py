"""A file's run once checked (:class:`Plan`): what the checks (:mod:`.checks`) and the
runner (:mod:`.runner`) both read."""

from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np

from .. import model as m
from ..io import schema as s
from ..io.load import Builder


@dataclasses.dataclass(frozen=True)
class Plan:
    """A checked run ready to execute.

    Attributes:
        spec: the run's description.
        index: its position in the file's ``runs``.
        times: (N,) output times [model time unit].
        depends: names of the runs whose results it needs (``from_run``).
    """

    spec: s.KinematicRunSpec | s.ForwardRunSpec | s.InverseRunSpec | s.MixedRunSpec
    index: int
    times: np.ndarray
    depends: tuple[str, ...]

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def path(self) -> tuple:
        return ("runs", self.index)


class Checker(Protocol):
    """What a run's checks (:mod:`.checks`) read of the runner (:class:`.runner.Runner`):
    its model, its builder, its plans, and how it reports a problem."""

    model: m.Model
    b: Builder
    plans: dict[str, Plan]

    def fail(self, path, problem: str, hint: str = "") -> None: ...

    def _prescribed_driver(self, p: s.PrescribedSpec, path) -> m.Driver: ...
