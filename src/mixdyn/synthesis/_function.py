"""Function generation: a linkage whose output follows its crank angle as asked.

The task (:class:`FunctionTask`) gives input-output pairs ``(theta2_i, y_i)``: the crank's
angle and the linkage's output (:meth:`~._linkage.Linkage.output`: a four-bar's rocker
angle, a slider-crank's slider position along its slide, a Stephenson III's or a Watt II's
follower angle), measured from the ground link (a slider's from the slide's point ``P0``), or
from unknown starts (``free_start``: only their differences count), or a function ``y =
f(x)`` over a range mapped linearly onto an input and an output span at precision points
(Chebyshev spacing by default: :meth:`FunctionTask.from_function`). The linkage is placed
with the crank's pivot at the origin and the ground link (the slide) along x. Where the
output is an angle only the links' ratios matter: the ground link is ``r1 = 1``; a
slider-crank's lengths are found in the outputs' span (:attr:`FunctionTask.scale`).

The search is the path search's (:mod:`._solve`): random starts of the variables ``u`` (the
linkage's lengths but ``r1`` and its signed numbers but the coupler point and the placement,
in the task's scale: a four-bar's ``r2, r3, r4``, a slider-crank's ``r2, r3, e``, a
six-bar's ``r2..r6, dx, dy, gx, gy``; then ``alpha, beta`` with ``free_start``, the starts
added to the inputs and outputs), spread over the linkage's assembly branches, each solved by
optimistix' Levenberg-Marquardt through the assembly's implicit derivatives, ``jax.vmap``
over a chunk of starts. The residuals: for each pair, an angle output's unit vector against
the asked one, ``e^{i y(theta2_i + alpha)} - e^{i (y_i + beta)}`` (two components: smooth
across the angle's wrap, ``|.| = 2 sin(|error| / 2)``), a length's difference in the task's
scale, ``(y(theta2_i + alpha) - y_i - beta) / scale``; the loops' closure and transmission
angle along the motion from the first input to the last, the bounds and the Grashof type
(:attr:`FunctionTask.grashof`, :mod:`._limits`), as penalties (as for a path).

Three precision points with absolute angles and three unknowns are Freudenstein's classic
problem: ``K1 cos theta4 - K2 cos theta2 + K3 = cos(theta2 - theta4)`` with ``K1 = r1/r2``,
``K2 = r1/r4``, ``K3 = (r2^2 - r3^2 + r4^2 + r1^2) / (2 r2 r4)``, linear in the ``K``'s; the
search finds its one solution (tested against the closed form).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

from ._limits import grashof_gaps, penalty
from ._linkage import Linkage
from ._settings import SearchSettings
from ._solve import (
    CHECK_SAMPLES,
    CLOSURE_MARGIN,
    PENALTY,
    Ranked,
    distinct,
    levenberg_marquardt,
    solve_all,
)
from ._task import FunctionTask

#: The numbers a function search never varies: the coupler point and the placement (the
#: crank's pivot at the origin, the ground link along x).
_PLACED = ("rcx", "rcy", "x0", "y0", "theta0")

#: Random draws per start of a two-loop linkage (:attr:`_Layout.screen`).
SCREEN = 32


@dataclasses.dataclass(frozen=True)
class _Layout:
    """How a function search's variables ``u`` make a linkage: its lengths but ``r1`` (the
    ground link, 1 where it has one), then its signed numbers but :data:`_PLACED`, both in
    the task's scale, then with ``free_start`` the input's start ``alpha`` [rad] and the
    output's ``beta`` (an angle [rad], or a length in the task's scale)."""

    linkage: type[Linkage]
    scale: float
    free: bool
    low: float
    high: float

    @classmethod
    def of(cls, task: FunctionTask) -> _Layout:
        lo, hi = task.bounds
        return cls(task.linkage, task.scale, task.free_start, lo, hi)

    @property
    def positive(self) -> tuple[str, ...]:
        """The lengths varied (bounded by ``low``, ``high``)."""
        return tuple(n for n in self.linkage.LENGTHS if n != "r1")

    @property
    def signed(self) -> tuple[str, ...]:
        """The signed numbers varied (within ``±high``)."""
        lengths = self.linkage.LENGTHS
        return tuple(n for n in self.linkage.NAMES if n not in lengths and n not in _PLACED)

    @property
    def names(self) -> tuple[str, ...]:
        """The linkage's numbers varied, in the order of ``u``."""
        return self.positive + self.signed

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def screen(self) -> int:
        """Random draws per start: a two-loop linkage's (a six-bar's,
        :attr:`~._linkage.Linkage.BRANCHES` of four) random numbers seldom close both
        loops, and most of its solves would end stuck against the closure; it draws
        :data:`SCREEN` times the starts and solves those of the least residuals (one draw
        per start for the others)."""
        return SCREEN if len(self.linkage.BRANCHES) > 2 else 1

    @property
    def angle(self) -> bool:
        """Whether the output is an angle (else a length)."""
        return self.linkage.OUTPUT == "angle"

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` (n,) of the varied numbers, in the task's scale."""
        p, s = len(self.positive), len(self.signed)
        low = np.concatenate([np.full(p, self.low), np.full(s, -self.high)])
        return low, np.full(p + s, self.high)

    def make(self, u, branch) -> Linkage:
        """The linkage of variables ``u`` (size,) on ``branch``."""
        one, zero = jnp.ones(()), jnp.zeros(())
        numbers = {n: zero for n in self.linkage.NAMES} | {"r1": one}
        for k, name in enumerate(self.names):
            numbers[name] = u[k] if self.scale == 1.0 else u[k] * self.scale
        return self.linkage(*(numbers[n] for n in self.linkage.NAMES), jnp.asarray(branch))

    def numbers(self, u, branch) -> Linkage:
        """The linkage of variables ``u`` (size,) on ``branch``, its numbers NumPy scalars."""
        v = np.asarray(self.make(jnp.asarray(u), branch).vector(), dtype=float)
        return self.linkage(*(np.float64(x) for x in v), np.float64(branch))

    def shifts(self, u):
        """``(alpha, beta)``: the input's and the output's starts (the output's in its own
        unit), or zeros without ``free_start``."""
        if not self.free:
            return 0.0, 0.0
        beta = u[self.n + 1]
        return u[self.n], beta if self.angle else beta * self.scale

    def starts(self, rng, count: int) -> tuple[np.ndarray, np.ndarray]:
        """``(u0 (count, size), branches (count,))``: the lengths log-uniform within the
        bounds, the signed numbers uniform within ``±min(high, 1)``, the starts uniform over
        a turn (a length's over ``±1`` in the task's scale), the branches in turn."""
        u0 = np.exp(rng.uniform(np.log(self.low), np.log(self.high), (count, len(self.positive))))
        if self.signed:
            reach = min(self.high, 1.0)
            u0 = np.concatenate([u0, rng.uniform(-reach, reach, (count, len(self.signed)))], 1)
        if self.free:
            ab = rng.uniform(-np.pi, np.pi, (count, 2))
            if not self.angle:
                ab[:, 1] /= np.pi
            u0 = np.concatenate([u0, ab], axis=1)
        branches = np.asarray(self.linkage.BRANCHES)
        return u0, branches[np.arange(count) % len(branches)]


@dataclasses.dataclass(frozen=True)
class FunctionCandidate:
    """One linkage of a function generation (the crank's pivot at the origin, the ground
    link along x; no coupler point).

    Attributes:
        linkage: its numbers (NumPy scalars): a :class:`~._fourbar.FourBar` (``r1 = 1``), a
            :class:`~._slidercrank.SliderCrank` (lengths [length]) or a six-bar
            (:class:`~._stephenson.StephensonIII`, :class:`~._watt.WattII`; ``r1 = 1``);
            ``theta0 = x0 = y0 = 0``. Also :attr:`fourbar`.
        input_start: the crank's start angle the task's inputs count from [rad] (0 unless
            the task's start is free).
        output_start: the output's start the task's outputs count from (0 unless the task's
            start is free): an angle [rad], a slider's position [length].
        error: ``sum_i (y(theta2_i) - y_i)^2``: [rad**2] for an angle output (the
            differences wrapped to ``(-pi, pi]``), [length**2] for a slider's position.
        min_transmission: the least transmission angle from the first input to the last [rad]
            (a six-bar's: both loops').
    """

    linkage: Linkage
    input_start: float
    output_start: float
    error: float
    min_transmission: float

    @property
    def fourbar(self) -> Linkage:
        """The linkage (:attr:`linkage`; a four-bar where the task's is)."""
        return self.linkage

    def output(self, inputs, near: float = 0.0) -> np.ndarray:
        """The outputs at the crank's ``inputs`` (K,) [rad], both in the task's frame (from
        the starts): an angle output's [rad] continuous from one input to the next, the first
        within pi of ``near`` (angles are defined up to whole turns); a slider's positions
        [length] (``near`` unused)."""
        lk = self.linkage
        theta = np.asarray(inputs, dtype=float) + self.input_start
        y = np.asarray(jax.vmap(lambda t: lk.output(t))(jnp.asarray(theta))) - self.output_start
        if lk.OUTPUT != "angle":
            return y
        out = np.unwrap(y)
        return out - 2 * np.pi * np.round((out[0] - near) / (2 * np.pi))


@dataclasses.dataclass(frozen=True)
class FunctionSynthesis(Ranked):
    """The outcome of a function generation (:func:`mixdyn.synthesize` of a
    :class:`FunctionTask`).

    Attributes:
        task: the task.
        candidates: the distinct feasible linkages (the task's type), least error first.
        starts: random starts solved.
        feasible: starts that ended feasible (closed loops from the first input to the
            last, the transmission angle, the bounds, the Grashof type).
        seed: the random generator's seed.
        seconds: wall time [s] (compilation included).
    """

    task: FunctionTask
    candidates: tuple[FunctionCandidate, ...]
    starts: int
    feasible: int
    seed: int
    seconds: float

    @property
    def varied(self) -> tuple[str, ...]:
        """The linkage's numbers the search varies, by name (:meth:`table`'s first columns):
        a four-bar's ``r2, r3, r4``, a slider-crank's ``r2, r3, e``, a six-bar's ``r2``..``r6,
        dx, dy, gx, gy``."""
        return _Layout.of(self.task).names

    def model(self, k: int = 0):
        """The :class:`mixdyn.Model` of candidate ``k`` (massless links; a four-bar's or a
        six-bar's ground link 1 m, a slider-crank's lengths in m), its crank at the first
        input at t = 0 turning at 1 rad/s."""
        from .build import linkage_model

        c = self.candidates[k]
        return linkage_model(c.linkage, None, start=float(self.task.inputs[0] + c.input_start))

    def model_file(self, k: int = 0, name: str = "function") -> str:
        """YAML text of candidate ``k``'s model file (:meth:`model`): a kinematic run of the
        crank's angle ``crank.phi`` and the output (:data:`~.build.FUNCTION_OUTPUTS`: a
        four-bar's ``rocker.phi``, a slider-crank's ``slider.x``, a six-bar's
        ``follower.phi``) from the first input to the last (``name``: named in the
        header)."""
        from .build import FUNCTION_OUTPUTS, model_file_text

        c, task = self.candidates[k], self.task
        lk = c.linkage
        start, end = task.inputs[0] + c.input_start, task.inputs[-1] + c.input_start
        column = FUNCTION_OUTPUTS[type(lk)]
        if lk.OUTPUT == "angle":
            what = "angle error sum (y - asked)^2", "rad^2", "rad", "angles"
        else:
            what = "position error sum (s - asked)^2", "m^2", "m", "positions"
        error, error_unit, unit, run = what
        head = (
            f"A {lk.TITLE} generating a function, synthesized by mixdyn ({name}, candidate "
            f"{k + 1} of {len(self.candidates)}, seed {self.seed}):\n{error} = {c.error:.6g} "
            f"{error_unit}; the crank's angle counts from the ground link, the output "
            f"({column}) from {_origin(lk)}, the task's from {c.input_start:.6g} rad (crank) "
            f"and {c.output_start:.6g} {unit} (output)\n\n  mixdyn run FILE"
        )
        return model_file_text(
            lk,
            None,
            start=float(start),
            end=float(end),
            speed=1.0 if end > start else -1.0,
            header=head,
            run=(run, ["crank.phi", column], f"{run}.png", []),
        )

    def write(self, path, k: int = 0) -> None:
        """Write :meth:`model_file` of candidate ``k`` to ``path``."""
        import pathlib

        pathlib.Path(path).write_text(self.model_file(k), encoding="utf-8")

    def table(self):
        """A pandas DataFrame: a row per candidate, its varied numbers (a four-bar's and a
        six-bar's as multiples of the ground link, a slider-crank's [length]), branch, starts
        and error (:attr:`FunctionCandidate.error`'s unit)."""
        import pandas as pd

        return pd.DataFrame(
            [
                {
                    **{n: float(getattr(c.linkage, n)) for n in self.varied},
                    "branch": float(c.linkage.branch),
                    "input_start": c.input_start,
                    "output_start": c.output_start,
                    "error": c.error,
                    "min_transmission_deg": np.rad2deg(c.min_transmission),
                }
                for c in self.candidates
            ]
        )


def _origin(lk: Linkage) -> str:
    """Where the output of ``lk`` counts from, in words."""
    return "the ground link" if lk.OUTPUT == "angle" else "the crank's pivot's foot on the slide"


def _residuals(task: FunctionTask, samples: int):
    """``r(u, branch)``: the residual vector of a candidate (see the module's documentation)."""
    lay = _Layout.of(task)
    inputs, outputs = jnp.asarray(task.inputs), jnp.asarray(task.outputs)
    cmax = min(float(np.cos(task.min_transmission)), CLOSURE_MARGIN)
    fractions = jnp.linspace(0.0, 1.0, samples)
    lo, hi = lay.bounds()

    def r(u, branch):
        lk = lay.make(u, branch)
        alpha, beta = lay.shifts(u)
        theta = inputs + alpha
        y = jax.vmap(lk.output)(theta)
        want = outputs + beta
        if lay.angle:
            fit = jnp.concatenate([jnp.cos(y) - jnp.cos(want), jnp.sin(y) - jnp.sin(want)])
        else:
            fit = (y - want) / lay.scale
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lk.transmission_cosine)(grid)
        closure = PENALTY * jax.nn.relu(jnp.abs(cos_mu) - cmax)
        v = u[: lay.n]
        bounds = PENALTY * jnp.concatenate([jax.nn.relu(lo - v), jax.nn.relu(v - hi)])
        grashof = penalty(grashof_gaps(lk, task.grashof) / lay.scale)
        return jnp.concatenate([fit, closure, bounds, grashof])

    return r


def _figures(task: FunctionTask):
    """``(u, branch) -> (error [rad**2 or length**2], worst |cos mu|)`` of one outcome,
    exactly (the closure on a fine grid from the first input to the last)."""
    lay = _Layout.of(task)
    inputs, outputs = jnp.asarray(task.inputs), jnp.asarray(task.outputs)
    fractions = jnp.linspace(0.0, 1.0, CHECK_SAMPLES)

    def one(u, branch):
        lk = lay.make(u, branch)
        alpha, beta = lay.shifts(u)
        theta = inputs + alpha
        y = jax.vmap(lk.output)(theta)
        gap = y - outputs - beta
        if lay.angle:
            gap = jnp.angle(jnp.exp(1j * gap))
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lk.transmission_cosine)(grid)
        return jnp.sum(gap**2), jnp.max(jnp.abs(cos_mu))

    return jax.jit(jax.vmap(one))


def synthesize_function(
    task: FunctionTask,
    search: SearchSettings,
    *,
    samples: int = 48,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> FunctionSynthesis:
    """Linkages of ``task``'s type whose output follows its input-output pairs, least error
    first (called by :func:`mixdyn.synthesize` for a :class:`FunctionTask`).

    Args:
        task: the function task.
        search: the starts (the lengths log-uniform within the bounds, the signed numbers
            uniform within ``±min(high, 1)`` in the task's scale, the starts uniform over a
            turn; spread over the linkage's assembly branches; a six-bar's the least
            residuals of :data:`SCREEN` times as many draws), seed, chunk, steps and
            candidates kept (:class:`~._settings.SearchSettings`; ``polish`` unused).
        samples: input angles of the closure penalty from the first input to the last.
        progress: called after each chunk with ``("search", starts done, starts, best sum
            of squared residuals so far)``.

    Returns:
        A :class:`FunctionSynthesis`.
    """
    starts = search.starts
    started = time.perf_counter()
    rng = np.random.default_rng(search.seed)
    lay = _Layout.of(task)
    residuals = _residuals(task, int(samples))
    u0, branches = lay.starts(rng, starts * lay.screen)
    if lay.screen > 1:  # the draws of the least residuals, in their order
        squares = jax.jit(jax.vmap(lambda u, b: (u, jnp.sum(residuals(u, b) ** 2))))
        _, score = solve_all(squares, u0, branches, search.chunk_size, None)
        keep = np.sort(np.argsort(np.nan_to_num(score, nan=np.inf), kind="stable")[:starts])
        u0, branches = u0[keep], branches[keep]
    report = None if progress is None else (lambda d, n, b: progress("search", d, n, b))
    solve = jax.jit(levenberg_marquardt(residuals, search.max_steps))
    u_all, _ = solve_all(solve, u0, branches, search.chunk_size, report)
    error, worst = (np.asarray(a) for a in _figures(task)(u_all, branches))
    lo, hi = lay.bounds()
    slack = 1e-9 * lay.high
    ok = np.isfinite(error) & (worst <= np.cos(task.min_transmission))
    ok &= np.all((u_all[:, : lay.n] >= lo - slack) & (u_all[:, : lay.n] <= hi + slack), axis=1)
    linkages = jax.vmap(lay.make)(jnp.asarray(u_all), jnp.asarray(branches))
    gaps = grashof_gaps(linkages, task.grashof) / lay.scale
    ok &= np.all(np.asarray(gaps) <= 1e-9, axis=1)
    starts_at = np.zeros((starts, 2))
    if task.free_start:
        starts_at = u_all[:, lay.n : lay.n + 2].copy()
        turns = 2 if lay.angle else 1  # a slider's start is a length: not wrapped
        starts_at[:, :turns] = np.angle(np.exp(1j * starts_at[:, :turns]))
    keys = np.concatenate([u_all[:, : lay.n], starts_at], axis=1)
    kept = []
    for i in distinct(ok, error, keys, branches, 1e-6):
        alpha, beta = (float(x) for x in starts_at[i])
        kept.append(
            FunctionCandidate(
                linkage=lay.numbers(u_all[i], branches[i]),
                input_start=alpha,
                output_start=beta * (1.0 if lay.angle else lay.scale),
                error=float(error[i]),
                min_transmission=float(np.arccos(min(float(worst[i]), 1.0))),
            )
        )
        if len(kept) == search.keep:
            break
    return FunctionSynthesis(
        task=task,
        candidates=tuple(kept),
        starts=starts,
        feasible=int(ok.sum()),
        seed=search.seed,
        seconds=time.perf_counter() - started,
    )


__all__ = ["FunctionCandidate", "FunctionSynthesis", "synthesize_function"]
