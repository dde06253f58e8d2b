"""Function generation: a four-bar whose rocker angle follows its crank angle as asked.

The task (:class:`FunctionTask`) gives input-output angle pairs ``(theta2_i, theta4_i)``, the
crank's and the rocker's angles measured from the ground link, or measured from unknown start
angles (``free_start``: only their differences count), or a function ``y = f(x)`` over a range
mapped linearly onto an input and an output span at precision points (Chebyshev spacing by
default: :meth:`FunctionTask.from_function`). Only the links' ratios matter: the ground link
is ``r1 = 1``, the crank's pivot at the origin and the ground link along x.

The search is the path search's (:mod:`._solve`): random starts of the variables ``u = (r2,
r3, r4[, alpha, beta])`` (``alpha``, ``beta``: the start angles added to the inputs and
outputs with ``free_start``), half on each assembly branch, each solved by optimistix'
Levenberg-Marquardt through the assembly's implicit derivatives, ``jax.vmap`` over a chunk of
starts. The residuals: for each pair the rocker's unit vector against the asked one,
``e^{i phi4(theta2_i + alpha)} - e^{i (theta4_i + beta)}`` (two components: smooth across the
angle's wrap, ``|.| = 2 sin(|error| / 2)``); the loop's closure and transmission angle along
the motion from the first input to the last, the bounds and the Grashof type
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

from ._fourbar import FourBar, link_angles, transmission_cosine
from ._limits import grashof_gaps, penalty
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


@dataclasses.dataclass(frozen=True)
class FunctionCandidate:
    """One four-bar of a function generation (ground link 1, along x, crank pivot at the
    origin).

    Attributes:
        fourbar: its numbers (``r1 = 1``, ``theta0 = x0 = y0 = 0``; no coupler point).
        input_start, output_start: the start angles the task's angles count from [rad] (0
            unless the task's start is free).
        error: ``sum_i (theta4(theta2_i) - theta4_i)^2`` [rad**2], the differences wrapped
            to ``(-pi, pi]``.
        min_transmission: the least transmission angle from the first input to the last [rad].
    """

    fourbar: FourBar
    input_start: float
    output_start: float
    error: float
    min_transmission: float

    def output(self, inputs, near: float = 0.0) -> np.ndarray:
        """The rocker's angles [rad] at the crank's ``inputs`` (K,) [rad], both in the task's
        frame (from the start angles): continuous from one input to the next, the first
        within pi of ``near`` (angles are defined up to whole turns)."""
        theta = np.asarray(inputs, dtype=float) + self.input_start
        phi4 = jax.vmap(lambda t: link_angles(self.fourbar, t)[1])(jnp.asarray(theta))
        out = np.unwrap(np.asarray(phi4) - self.output_start)
        return out - 2 * np.pi * np.round((out[0] - near) / (2 * np.pi))


@dataclasses.dataclass(frozen=True)
class FunctionSynthesis(Ranked):
    """The outcome of a function generation (:func:`mixdyn.synthesize` of a
    :class:`FunctionTask`).

    Attributes:
        task: the task.
        candidates: the distinct feasible four-bars, least error first.
        starts: random starts solved.
        feasible: starts that ended feasible (closed loop from the first input to the last,
            the transmission angle, the bounds).
        seed: the random generator's seed.
        seconds: wall time [s] (compilation included).
    """

    task: FunctionTask
    candidates: tuple[FunctionCandidate, ...]
    starts: int
    feasible: int
    seed: int
    seconds: float

    def model(self, k: int = 0):
        """The :class:`mixdyn.Model` of candidate ``k`` (massless links, the ground link 1 m),
        its crank at the first input at t = 0 turning at 1 rad/s."""
        from .build import four_bar_model

        c = self.candidates[k]
        return four_bar_model(c.fourbar, None, start=float(self.task.inputs[0] + c.input_start))

    def model_file(self, k: int = 0, name: str = "function") -> str:
        """YAML text of candidate ``k``'s model file: its ground link 1 m, a kinematic run of
        the crank's and rocker's angles (``crank.phi``, ``rocker.phi``) from the first input
        to the last (``name``: named in the header)."""
        from .build import model_file_text

        c, task = self.candidates[k], self.task
        start, end = task.inputs[0] + c.input_start, task.inputs[-1] + c.input_start
        head = (
            f"A four-bar generating a function, synthesized by mixdyn ({name}, candidate "
            f"{k + 1} of {len(self.candidates)}, seed {self.seed}):\nangle error sum (theta4 - "
            f"asked)^2 = {c.error:.6g} rad^2; the angles count from the ground link, the "
            f"task's from {c.input_start:.6g} rad (crank) and {c.output_start:.6g} rad "
            "(rocker)\n\n  mixdyn run FILE"
        )
        return model_file_text(
            c.fourbar,
            None,
            start=float(start),
            end=float(end),
            speed=1.0 if end > start else -1.0,
            header=head,
            run=("angles", ["crank.phi", "rocker.phi"], "angles.png", []),
        )

    def write(self, path, k: int = 0) -> None:
        """Write :meth:`model_file` of candidate ``k`` to ``path``."""
        import pathlib

        pathlib.Path(path).write_text(self.model_file(k), encoding="utf-8")

    def table(self):
        """A pandas DataFrame: a row per candidate, its ratios, start angles and error."""
        import pandas as pd

        return pd.DataFrame(
            [
                {
                    "r2": float(c.fourbar.r2),
                    "r3": float(c.fourbar.r3),
                    "r4": float(c.fourbar.r4),
                    "branch": float(c.fourbar.branch),
                    "input_start": c.input_start,
                    "output_start": c.output_start,
                    "error": c.error,
                    "min_transmission_deg": np.rad2deg(c.min_transmission),
                }
                for c in self.candidates
            ]
        )


def _fourbar(u, branch) -> FourBar:
    one, zero = jnp.ones(()), jnp.zeros(())
    return FourBar(one, u[0], u[1], u[2], zero, zero, zero, zero, zero, jnp.asarray(branch))


def _residuals(task: FunctionTask, samples: int):
    """``r(u, branch)``: the residual vector of a candidate (see the module's documentation)."""
    inputs, outputs = jnp.asarray(task.inputs), jnp.asarray(task.outputs)
    cmax = min(float(np.cos(task.min_transmission)), CLOSURE_MARGIN)
    fractions = jnp.linspace(0.0, 1.0, samples)
    lo, hi = task.bounds

    def r(u, branch):
        fb = _fourbar(u, branch)
        alpha, beta = (u[3], u[4]) if task.free_start else (0.0, 0.0)
        theta = inputs + alpha
        phi4 = jax.vmap(lambda t: link_angles(fb, t)[1])(theta)
        want = outputs + beta
        angle = jnp.concatenate([jnp.cos(phi4) - jnp.cos(want), jnp.sin(phi4) - jnp.sin(want)])
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lambda t: transmission_cosine(fb, t))(grid)
        closure = PENALTY * jax.nn.relu(jnp.abs(cos_mu) - cmax)
        lengths = u[:3]
        bounds = PENALTY * jnp.concatenate([jax.nn.relu(lo - lengths), jax.nn.relu(lengths - hi)])
        grashof = penalty(grashof_gaps(fb, task.grashof))
        return jnp.concatenate([angle, closure, bounds, grashof])

    return r


def _figures(task: FunctionTask):
    """``(u, branch) -> (error [rad**2], worst |cos mu|)`` of one outcome, exactly (the
    closure on a fine grid from the first input to the last)."""
    inputs, outputs = jnp.asarray(task.inputs), jnp.asarray(task.outputs)
    fractions = jnp.linspace(0.0, 1.0, CHECK_SAMPLES)

    def one(u, branch):
        fb = _fourbar(u, branch)
        alpha, beta = (u[3], u[4]) if task.free_start else (0.0, 0.0)
        theta = inputs + alpha
        phi4 = jax.vmap(lambda t: link_angles(fb, t)[1])(theta)
        wrapped = jnp.angle(jnp.exp(1j * (phi4 - outputs - beta)))
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lambda t: transmission_cosine(fb, t))(grid)
        return jnp.sum(wrapped**2), jnp.max(jnp.abs(cos_mu))

    return jax.jit(jax.vmap(one))


def synthesize_function(
    task: FunctionTask,
    search: SearchSettings,
    *,
    samples: int = 48,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> FunctionSynthesis:
    """Four-bars whose rocker follows ``task``'s input-output pairs, least error first
    (called by :func:`mixdyn.synthesize` for a :class:`FunctionTask`).

    Args:
        task: the function task.
        search: the starts (the ratios log-uniform within the bounds, the start angles
            uniform over a turn; half on each assembly branch), seed, chunk, steps and
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
    lo, hi = task.bounds
    u0 = np.exp(rng.uniform(np.log(lo), np.log(hi), (starts, 3)))
    if task.free_start:
        u0 = np.concatenate([u0, rng.uniform(-np.pi, np.pi, (starts, 2))], axis=1)
    branches = np.where(np.arange(starts) % 2 == 0, 1.0, -1.0)
    report = None if progress is None else (lambda d, n, b: progress("search", d, n, b))
    residuals = _residuals(task, int(samples))
    solve = jax.jit(levenberg_marquardt(residuals, search.max_steps))
    u_all, _ = solve_all(solve, u0, branches, search.chunk_size, report)
    error, worst = (np.asarray(a) for a in _figures(task)(u_all, branches))
    slack = 1e-9 * hi
    ok = np.isfinite(error) & (worst <= np.cos(task.min_transmission))
    ok &= np.all((u_all[:, :3] >= lo - slack) & (u_all[:, :3] <= hi + slack), axis=1)
    gaps = grashof_gaps(jax.vmap(_fourbar)(jnp.asarray(u_all), jnp.asarray(branches)), task.grashof)
    ok &= np.all(np.asarray(gaps) <= 1e-9, axis=1)
    starts_at = np.angle(np.exp(1j * u_all[:, 3:5])) if task.free_start else np.zeros((starts, 2))
    kept = []
    for i in distinct(ok, error, np.concatenate([u_all[:, :3], starts_at], axis=1), branches, 1e-6):
        u = u_all[i]
        fb = FourBar(np.float64(1.0), *(np.float64(x) for x in u[:3]), *(np.float64(0.0),) * 5,
                     np.float64(branches[i]))  # fmt: skip
        kept.append(
            FunctionCandidate(
                fourbar=fb,
                input_start=float(starts_at[i, 0]),
                output_start=float(starts_at[i, 1]),
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
