"""How a synthesis searches: one value made by :func:`~._synthesize.synthesize` and handed to
every task's search (the path's and motion's, the function's, the shape's)."""

from __future__ import annotations

import dataclasses

from ..errors import ModelError


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """The search of a synthesis: its random starts, their chunks and steps, what it keeps.

    Attributes:
        starts: random starts, spread over the linkage's assembly branches (>= 1).
        seed: the random generator's seed (the same seed, the same starts and outcome).
        chunk: starts solved together, one vectorized program compiled once (>= 1; at most
            ``starts`` are used).
        max_steps: Levenberg-Marquardt's steps at most per start (>= 1).
        keep: distinct candidates returned at most (>= 1).
        polish: with a dynamic weight in a path or motion task's objective, each outcome
            solved once more for the path alone from where the weighted search left it, then
            scored by the objective (:func:`~._synthesize.synthesize`).

    Raises:
        ModelError: a count below 1, naming its field.
    """

    starts: int = 2048
    seed: int = 0
    chunk: int = 512
    max_steps: int = 300
    keep: int = 10
    polish: bool = True

    def __post_init__(self):
        for name in ("starts", "chunk", "max_steps", "keep"):
            value = getattr(self, name)
            try:
                whole = int(value)
            except (TypeError, ValueError):
                whole = None
            if whole is None or whole != value or whole < 1:
                raise ModelError(
                    f"{name} must be a whole number of at least 1, got {value!r}", name
                )
            object.__setattr__(self, name, whole)
        object.__setattr__(self, "seed", int(self.seed))

    @property
    def chunk_size(self) -> int:
        """The starts of one chunk: ``chunk``, at most ``starts``."""
        return min(self.chunk, self.starts)


__all__ = ["SearchSettings"]
