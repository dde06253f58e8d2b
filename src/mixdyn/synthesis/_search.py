"""The search: thousands of random starts at once, each refined by Levenberg-Marquardt.

The linkage is the task's (:attr:`PathTask.linkage`: a four-bar, a slider-crank or a six-bar).
A candidate's variables ``u`` are dimensionless: the linkage's lengths and placement divided by
the targets' size ``s`` (the crank's pivot from the targets' centre), ``theta0``, the crank's
angle at the first point ``theta_1`` and, where the timing is free, the increments
``theta_{i+1} - theta_i``. Its residuals (all divided by ``s``):

* the path: ``C(theta_i) - P_i`` for each target (2N);
* the loop's closure and transmission angle along the traversed motion (``samples`` input
  angles from the first point to the last, the points' arc only: a candidate whose loop opens
  between two points has a circuit defect and pays for it): ``10 relu(|cos mu| - c)`` with
  ``c = cos(min_transmission)`` (at most 0.999);
* the bounds: ``1000 relu(low - x)``, ``1000 relu(x - high)`` (a length over the targets'
  size; :data:`~._solve.BOUND_PENALTY`: an outcome the path pulls past a bound stops a
  hair beyond it and is then taken onto it);
* the Grashof type and the ground pivots' regions (:mod:`._limits`): ``30 relu(g / s + 0.001)``
  of each gap ``g`` [length] (a linear condition on the lengths, a rectangle's side: met
  where ``g <= 0``; the margin keeps a search that leans on it inside);
* the order (timing-free): ``10 relu(-increment)`` and ``10 relu(sum - 2 pi)``;
* the torque (with a torque weight): ``sqrt(weight) T / s``;
* the shaking force and moment (with their weights, :func:`~._dynamics.shaking`):
  ``sqrt(weight) F / s`` and ``sqrt(weight) M / s``;
* the joint reactions (with their weight, :func:`~._dynamics.reactions`): ``sqrt(weight) R / s``;
* a motion task's coupler angles (:mod:`._motion`): ``(L / s) (e^{i phi_i} - e^{i alpha_i})``
  (2N), the task a timing-free path task of the poses' points besides.

The branch (which side of ``A O4`` the pin ``B`` lies on; for a slider-crank, ahead of ``A``
along the slide or behind it; a six-bar's both loops', :mod:`._sixbar`) is fixed per start,
the starts spread evenly over the linkage's ``BRANCHES``, so that no candidate changes branch
between points. Every start is solved by
optimistix' Levenberg-Marquardt (a well-kept library; derivatives through the assembly's
implicit rule), ``jax.vmap`` over a chunk of starts, chunk after chunk (progress reported
after each). The task's numbers are the programs' array arguments (:class:`_Program` is their
static part), so a later search of the same form (as many targets, the same timing mode,
masses and torque measure) in the process runs the programs already compiled. Infeasible
starts cannot leak a NaN: the assembly returns the nearest configuration where the loop opens,
and the penalty is finite.

The outcomes are checked exactly (closure on a fine grid of the traversed motion, order,
bounds), ranked by their score, and near-equal ones (the same linkage from two starts) kept
once.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ..runtime._programs import cached_jit
from ._dynamics import DYNAMICS, Masses, motor_torque, reactions, shaking
from ._fourbar import FourBar
from ._limits import LIMIT_MARGIN, grashof_gaps, penalty, region_arrays, region_gaps
from ._linkage import Linkage, coupler_point, transmission_cosine
from ._motion import MotionTask, angle_residuals, body_angles, offset, turn_gaps
from ._settings import SearchSettings
from ._slidercrank import SliderCrank
from ._solve import (
    BOUND_PENALTY,
    CHECK_SAMPLES,
    CLOSURE_MARGIN,
    PENALTY,
    Ranked,
    levenberg_marquardt,
    solve_all,
)
from ._task import Objective, PathTask


@dataclasses.dataclass(frozen=True)
class _Layout:
    """How a candidate's variables ``u`` map to a linkage and its input angles: the
    linkage's ``m`` numbers (lengths, ``x0``, ``y0``, ``theta0``), then ``theta_1`` at
    ``u[m]``, then the free timing's increments."""

    n: int
    scale: float
    centre: np.ndarray
    timing: np.ndarray | None
    linkage: type[Linkage] = FourBar
    absolute: bool = False  # the timing is the crank's angle from the ground link
    fixed: np.ndarray | None = None  # (m,) the linkage's numbers fixed (NaN: searched)

    @property
    def m(self) -> int:
        """The linkage's numbers."""
        return len(self.linkage.NAMES)

    @property
    def size(self) -> int:
        return self.m + 1 + (0 if self.timing is not None else self.n - 1)

    def numbers(self, u, xp=np):
        """The linkage's ``m`` numbers (..., m) of variables ``u`` (..., size) (``xp``: NumPy
        or ``jax.numpy``): lengths in the targets' size, the pivot in sizes from their
        centre, ``theta0`` as it is; a fixed number's variable as it stands."""
        s, c, m = self.scale, self.centre, self.m
        return xp.concatenate(
            [u[..., : m - 3] * s, c + s * u[..., m - 3 : m - 1], u[..., m - 1 : m]], axis=-1
        )

    def variables(self, v) -> np.ndarray:
        """The first ``m`` variables (..., m) of the linkage's numbers ``v`` (..., m)
        (:meth:`numbers`' inverse; NumPy)."""
        s, c, m = self.scale, self.centre, self.m
        return np.concatenate(
            [v[..., : m - 3] / s, (v[..., m - 3 : m - 1] - c) / s, v[..., m - 1 :]], axis=-1
        )

    def make(self, u, branch) -> Linkage:
        """The linkage of variables ``u`` on ``branch``."""
        v = self.numbers(u, jnp)
        if self.fixed is not None:  # a number whose bounds are equal: their value
            v = jnp.where(jnp.isnan(self.fixed), v, jnp.nan_to_num(self.fixed))
        return self.linkage.from_vector(v, branch)

    def angles(self, u) -> jax.Array:
        """(N,) the input angles at the targets [rad]."""
        m = self.m
        if self.timing is not None and self.absolute:
            return jnp.asarray(self.timing) + 0.0 * u[m]  # theta_1 given: u[m] unused
        if self.timing is not None:
            return u[m] + jnp.asarray(self.timing - self.timing[0])
        return u[m] + jnp.concatenate([jnp.zeros(1), jnp.cumsum(u[m + 1 :])])

    def increments(self, u):
        """The free timing's increments of ``u`` (..., size)."""
        return u[..., self.m + 1 :]


@dataclasses.dataclass(frozen=True)
class _Program:
    """What decides a path search's programs (their static part and the key of their
    persistent cache: :func:`mixdyn.runtime._programs.cached_jit`); the task's numbers are
    arrays (:func:`_data`), so that another task of the same form reuses the programs.

    Attributes:
        n: the targets.
        timed: the timing is prescribed.
        linkage: the linkage type.
        samples: input angles of the closure and torque terms along the motion.
        masses: how the links weigh (None: no torque term).
        torque: the torque measure of the residuals (``"rms"``, ``"peak"``), None: none.
        shaking: the shaking force's and moment's measure, None: neither weighs.
        reaction: the joint reactions' measure, None: they do not weigh.
        max_steps: Levenberg-Marquardt's steps at most per start.
        motion: a motion task (the coupler's angles at the points count too).
        grashof: the Grashof type asked for (:mod:`._limits`).
        regions: the ground pivots with a region (their rectangles are data).
        absolute: the timing is the crank's angle from the ground link (``timing_from``).
    """

    n: int
    timed: bool
    linkage: type[Linkage]
    samples: int
    masses: Masses | None
    torque: str | None
    max_steps: int
    motion: bool = False
    shaking: str | None = None
    reaction: str | None = None
    grashof: str = "any"
    regions: tuple[str, ...] = ()
    absolute: bool = False


def _program(task: PathTask, objective: Objective, max_steps: int, torque: bool) -> _Program:
    """The program of a search of ``task`` (with the torque term where ``torque``)."""
    dynamic = torque and objective.dynamic
    return _Program(
        n=len(task.points),
        timed=task.timing is not None,
        linkage=task.linkage,
        samples=int(objective.samples),
        masses=objective.masses if dynamic else None,
        torque=objective.torque if dynamic and objective.torque_weight > 0 else None,
        max_steps=int(max_steps),
        motion=isinstance(task, MotionTask),
        shaking=objective.shaking if dynamic and objective.shakes else None,
        reaction=objective.reaction if dynamic and objective.reaction_weight > 0 else None,
        grashof=task.grashof,
        regions=tuple(task.pivots),
        absolute=getattr(task, "timing_from", "first") == "ground",
    )


def _data(layout: _Layout, task: PathTask, objective: Objective, box: np.ndarray) -> dict:
    """The task's numbers the programs take as arrays (NumPy float64)."""
    motion = isinstance(task, MotionTask)
    finite = np.isfinite(box)
    f64 = np.float64
    # The bounds' penalties start at the bounds themselves, with a weight that leaves an
    # outcome leaning on one a hair past it, where it is taken onto it (_kept_within): a
    # linkage whose best lies on a bound reaches it. The transmission angle's and the
    # closure's, which no clip can meet, aim LIMIT_MARGIN inside.
    return {
        "targets": np.asarray(task.points, dtype=float),
        "timing": np.zeros(layout.n) if task.timing is None else np.asarray(task.timing),
        "scale": f64(layout.scale),
        "centre": np.asarray(layout.centre, dtype=float),
        "low": np.where(finite[:, 0], box[:, 0], 0.0),
        "high": np.where(finite[:, 1], box[:, 1], 0.0),
        "low_on": finite[:, 0].astype(float),
        "high_on": finite[:, 1].astype(float),
        "fixed": layout.fixed,
        "cmax": f64(min(float(np.cos(task.min_transmission)) - LIMIT_MARGIN, CLOSURE_MARGIN)),
        "weight": f64(objective.torque_weight),
        "force_weight": f64(objective.shaking_force_weight),
        "moment_weight": f64(objective.shaking_moment_weight),
        "reaction_weight": f64(objective.reaction_weight),
        "speed": f64(objective.speed),
        "angles": task.angles if motion else np.zeros(layout.n),  # a motion's poses [rad]
        "length": f64(task.weight_length / layout.scale if motion else 0.0),  # L / s
        **dict(zip(("region_low", "region_high"), region_arrays(task.pivots), strict=True)),
    }


def _fixed(box: np.ndarray) -> np.ndarray:
    """(m,) the numbers that equal bounds fix, NaN where searched."""
    return np.where(box[:, 0] == box[:, 1], box[:, 0], np.nan)


def _layout_of(program: _Program, data: dict) -> _Layout:
    timing = data["timing"] if program.timed else None
    return _Layout(
        program.n,
        data["scale"],
        data["centre"],
        timing,
        program.linkage,
        program.absolute,
        data["fixed"],
    )


def _residuals(program: _Program, data: dict):
    """``r(u, branch)``: the residual vector of a candidate (see the module's documentation)."""
    layout = _layout_of(program, data)
    s = data["scale"]
    targets = jnp.asarray(data["targets"])
    fractions = jnp.linspace(0.0, 1.0, program.samples)
    lo, hi = jnp.asarray(data["low"]), jnp.asarray(data["high"])
    lo_on, hi_on = jnp.asarray(data["low_on"]), jnp.asarray(data["high_on"])
    scale_of = jnp.where(jnp.arange(layout.m) == layout.m - 1, 1.0, s)  # theta0 last

    def r(u, branch):
        fb = layout.make(u, branch)
        theta = layout.angles(u)
        path = (jax.vmap(lambda t: coupler_point(fb, t))(theta) - targets).ravel() / s
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lambda t: transmission_cosine(fb, t))(grid)
        closure = PENALTY * jax.nn.relu(jnp.abs(cos_mu) - data["cmax"])
        v = fb.vector()
        bounds = BOUND_PENALTY * jnp.concatenate(
            [lo_on * jax.nn.relu(lo - v) / scale_of, hi_on * jax.nn.relu(v - hi) / scale_of]
        )
        limits = jnp.concatenate([grashof_gaps(fb, program.grashof), region_gaps(
            fb, program.regions, data["region_low"], data["region_high"])])  # fmt: skip
        parts = [path, closure, bounds, penalty(limits / s)]
        if not program.timed:
            inc = layout.increments(u)
            parts.append(PENALTY * jax.nn.relu(-inc))
            parts.append(PENALTY * jax.nn.relu(jnp.sum(inc) - 2 * jnp.pi)[None])
        if program.motion:
            parts.append(data["length"] * angle_residuals(fb, theta, jnp.asarray(data["angles"])))
        if program.torque is not None:
            tau = motor_torque(fb, program.masses, grid, data["speed"])
            measure = _torque_measure(tau, program.torque)
            parts.append(jnp.sqrt(data["weight"]) * measure[None] / s)
        if program.shaking is not None:
            force, moment = shaking(fb, program.masses, grid, data["speed"])
            f = _force_measure(force, program.shaking)
            m = _torque_measure(moment, program.shaking)
            parts.append(jnp.stack([jnp.sqrt(data["force_weight"]) * f,
                                    jnp.sqrt(data["moment_weight"]) * m]) / s)  # fmt: skip
        if program.reaction is not None:
            forces, _ = reactions(fb, program.masses, grid, data["speed"])
            size = _force_measure(forces.reshape(-1, 2), program.reaction)
            parts.append(jnp.sqrt(data["reaction_weight"]) * size[None] / s)
        return jnp.concatenate(parts)

    return r


@eqx.filter_jit
def _solve_chunk(program: _Program, data: dict, u0, branches):
    """A chunk of starts solved: one program per ``program`` and chunk size, reused by every
    search of that form in the process (not kept between processes: optimistix' error
    checks are host callbacks, which :mod:`jax.export` refuses)."""
    return levenberg_marquardt(_residuals(program, data), program.max_steps)(u0, branches)


@eqx.filter_jit
def _scores(program: _Program, data: dict, u, branches):
    """(C,) the sums of squared residuals of outcomes ``u`` (C, size)."""
    residuals = _residuals(program, data)
    return jax.vmap(lambda x, b: jnp.sum(residuals(x, b) ** 2))(u, branches)


def _torque_measure(tau, kind: str):
    """The RMS of ``tau`` (K,), or its mean 8-norm (``"peak"``)."""
    if kind == "rms":
        return jnp.sqrt(jnp.mean(tau**2))
    big = jnp.max(jnp.abs(tau)) + 1e-300
    return big * jnp.mean((tau / big) ** 8) ** (1 / 8)


def _force_measure(force, kind: str):
    """The RMS of the magnitudes of ``force`` (K, 2), or their mean 8-norm (``"peak"``),
    from the squared magnitudes (smooth where a force vanishes)."""
    squared = jnp.sum(force**2, axis=1)
    if kind == "rms":
        return jnp.sqrt(jnp.mean(squared))
    big = jnp.max(squared) + 1e-300
    return jnp.sqrt(big) * jnp.mean((squared / big) ** 4) ** (1 / 8)


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One synthesized linkage.

    Attributes:
        fourbar: the linkage's numbers (NumPy scalars), model units: a
            :class:`~._fourbar.FourBar`, or the task's other linkage type
            (:class:`~._slidercrank.SliderCrank`, a six-bar of :mod:`._sixbar`); also
            :attr:`linkage`.
        angles: (N,) its input angles at the targets [rad].
        error: ``sum_i |C(theta_i) - P_i|^2`` [length**2] (a motion task's plus its angle
            term, :meth:`MotionTask.error`).
        score: the objective (error plus the weighted torque term) [length**2].
        torque_rms, torque_peak: the motor torque over the traversed motion [torque] (NaN
            without masses).
        shaking_force_rms, shaking_force_peak: the shaking force's magnitude over it [force]
            (NaN without masses).
        shaking_moment_rms, shaking_moment_peak: the shaking moment about the crank's pivot
            over it [torque] (NaN without masses).
        reaction_rms, reaction_peak: the joints' forces' magnitudes over the joints and the
            motion, gravity included [force] (NaN without masses).
        min_transmission: the least transmission angle over the traversed motion [rad].
        coupler_angle: a motion task's ``gamma`` [rad]: the angle of the carried body's line
            from the coupler's line ``A -> B`` (the poses' angles are the coupler's plus it);
            0 for a path.
    """

    fourbar: Linkage
    angles: np.ndarray
    error: float
    score: float
    torque_rms: float
    torque_peak: float
    min_transmission: float
    coupler_angle: float = 0.0
    shaking_force_rms: float = float("nan")
    shaking_force_peak: float = float("nan")
    shaking_moment_rms: float = float("nan")
    shaking_moment_peak: float = float("nan")
    reaction_rms: float = float("nan")
    reaction_peak: float = float("nan")

    @property
    def linkage(self) -> Linkage:
        """The synthesized linkage (a four-bar, a slider-crank or a six-bar: the task's type)."""
        return self.fourbar

    def numbers(self) -> dict[str, float]:
        """The linkage's numbers by name (its ``NAMES``) and its branch."""
        out = {n: float(getattr(self.fourbar, n)) for n in self.fourbar.NAMES}
        out["branch"] = float(self.fourbar.branch)
        return out


@dataclasses.dataclass(frozen=True)
class Synthesis(Ranked):
    """The outcome of :func:`~._synthesize.synthesize`.

    Attributes:
        task: the path task, or the motion task.
        objective: the objective.
        candidates: the distinct feasible linkages, best score first.
        starts: random starts solved.
        feasible: starts that ended feasible (closed loop along the motion, in order, within
            bounds).
        seed: the random seed.
        seconds: wall time [s] (compilation included).
    """

    task: PathTask | MotionTask
    objective: Objective
    candidates: tuple[Candidate, ...]
    starts: int
    feasible: int
    seed: int
    seconds: float

    def model(self, k: int = 0):
        """The :class:`mixdyn.Model` of candidate ``k``, its crank at the first target's input
        angle at t = 0, turning at the objective's speed."""
        from .build import linkage_model

        c = self.candidates[k]
        return linkage_model(
            c.fourbar,
            self.objective.masses,
            start=float(c.angles[0]),
            speed=self.objective.speed,
            coupler_angle=c.coupler_angle,
        )

    def model_file(self, k: int = 0) -> str:
        """YAML text of candidate ``k``'s model file (a kinematic and, with masses, an inverse
        run over the traversed motion; a motion task's coupler body turned so that its angle
        ``coupler.phi`` is the poses')."""
        from .build import BUILDERS, model_file_text

        c = self.candidates[k]
        motion = isinstance(self.task, MotionTask)
        error = (
            f"pose error sum |C - P|^2 + L^2 sum (phi - alpha)^2 = {c.error:.6g} m^2 (L = "
            f"{self.task.weight_length:.6g} m)"
            if motion
            else f"path error sum |C - P|^2 = {c.error:.6g} m^2"
        )
        head = (
            f"A {c.fourbar.TITLE} synthesized by mixdyn (candidate {k + 1} of "
            f"{len(self.candidates)}, seed {self.seed}):\n{error}"
        )
        if np.isfinite(c.torque_rms):
            head += f", motor torque RMS {c.torque_rms:.6g} N*m, peak {c.torque_peak:.6g} N*m"
        options = {"targets": self.task.points}
        if motion:
            body = BUILDERS[type(c.fourbar)][1]
            poses = [f"  [{x:.6g}, {y:.6g}, {a:.6g}]" for x, y, a in self.task.poses]
            head += f"\nposes ({body}.P.x, {body}.P.y [m], {body}.phi [rad]):\n" + "\n".join(poses)
            options = {"coupler_angle": c.coupler_angle}
        return model_file_text(
            c.fourbar,
            self.objective.masses,
            start=float(c.angles[0]),
            end=float(c.angles[-1]),
            speed=self.objective.speed,
            header=head + "\n\n  mixdyn run FILE",
            **options,
        )

    def write(self, path, k: int = 0) -> None:
        """Write :meth:`model_file` of candidate ``k`` to ``path``."""
        import pathlib

        pathlib.Path(path).write_text(self.model_file(k), encoding="utf-8")

    def table(self):
        """A pandas DataFrame: a row per candidate, its numbers, error, score and torques."""
        import pandas as pd

        rows = []
        for c in self.candidates:
            row = c.numbers()
            row.update(
                error=c.error,
                score=c.score,
                torque_rms=c.torque_rms,
                torque_peak=c.torque_peak,
                shaking_force_rms=c.shaking_force_rms,
                shaking_force_peak=c.shaking_force_peak,
                shaking_moment_rms=c.shaking_moment_rms,
                shaking_moment_peak=c.shaking_moment_peak,
                reaction_rms=c.reaction_rms,
                reaction_peak=c.reaction_peak,
                min_transmission_deg=np.rad2deg(c.min_transmission),
            )
            if isinstance(self.task, MotionTask):
                row["coupler_angle"] = c.coupler_angle
            rows.append(row)
        return pd.DataFrame(rows)


def _starts(layout: _Layout, task: PathTask, box: np.ndarray, count: int, rng) -> np.ndarray:
    """(count, size) random starts within the bounds (``theta0`` over a turn where unbounded),
    the input angles spread over up to a turn."""
    lo, hi = box[:, 0].copy(), box[:, 1].copy()
    m = layout.m  # theta0 last, after the pivot (m - 3, m - 2)
    if not (np.isfinite(lo[m - 1]) and np.isfinite(hi[m - 1])):
        lo[m - 1], hi[m - 1] = -np.pi, np.pi
    v = lo + (hi - lo) * rng.random((count, m))
    if "O4" in task.pivots:  # the rocker's pivot within its region: r1 and theta0 from it
        region = np.array(task.pivots["O4"])
        d = region[:, 0] + (region[:, 1] - region[:, 0]) * rng.random((count, 2)) - v[:, -3:-1]
        r1 = layout.linkage.NAMES.index("r1")
        v[:, r1] = np.clip(np.hypot(d[:, 0], d[:, 1]), box[r1, 0], box[r1, 1])
        v[:, -1] = np.clip(np.arctan2(d[:, 1], d[:, 0]), box[-1, 0], box[-1, 1])
    first = 2 * np.pi * rng.random((count, 1))
    u = np.concatenate([layout.variables(v), first], axis=1)
    if layout.timing is None:
        n = layout.n
        total = rng.uniform(0.25, 1.0, (count, 1)) * 2 * np.pi
        inc = rng.dirichlet(np.ones(n), count)[:, : n - 1] * total
        u = np.concatenate([u, inc], axis=1)
    return u


def _kept_within(layout: _Layout, box: np.ndarray, program, data, u_all, branches, scores):
    """The outcomes at the nearest point within the bounds (each number clipped into its
    ``box`` row) and, with free timing, passing the targets in order (every increment of the
    input angle >= 0), their scores recomputed where they moved. Bounds and order are
    penalties in the search, which a start may end leaning on: a number fixed by a narrow
    bound left 1e-5 outside it, a target passed a hair before the one ahead of it (-1e-5
    rad, where two targets lie close). Moved onto the bound or to the angle of the target
    ahead, the linkage is all but the same and meets them exactly."""
    u_all, m = np.array(u_all), layout.m
    v = layout.numbers(u_all)
    w = np.clip(v, box[:, 0], box[:, 1])
    moved = np.any(w != v, axis=1)
    u_all[:, :m] = layout.variables(w)
    if layout.timing is None:
        inc = layout.increments(u_all)
        moved |= np.any(inc < 0.0, axis=1)
        u_all[:, m + 1 :] = np.maximum(inc, 0.0)
    if not np.any(moved):
        return u_all, scores
    fixed = np.asarray(_scores(program, data, u_all, branches))
    return u_all, np.where(moved, fixed, scores)


def synthesize_path(
    task: PathTask | MotionTask,
    objective: Objective | None,
    search: SearchSettings,
    *,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> Synthesis:
    """The search of a path or motion task (:func:`~._synthesize.synthesize`'s, whose
    docstring gives the arguments)."""
    objective = objective or Objective()
    starts, max_steps = search.starts, search.max_steps
    masses = objective.masses
    if masses is not None and task.linkage not in DYNAMICS:
        raise ModelError(
            f"a {task.linkage.TITLE}'s dynamics (motor torque, shaking, reactions) are not "
            "part of synthesis: search it for its path alone (give no masses)",
            "masses",
        )
    if masses is not None and task.linkage is SliderCrank and not masses.slider > 0:
        raise ModelError(
            "a slider-crank's slider needs a mass > 0 with the links' masses (its model's "
            "inverse dynamics): give Masses(slider=...)",
            "masses",
        )
    started = time.perf_counter()
    chunk = search.chunk_size
    box = task.box()
    layout = _Layout(
        len(task.points),
        task.size,
        task.points.mean(axis=0),
        task.timing,
        task.linkage,
        getattr(task, "timing_from", "first") == "ground",  # a motion task's timing is free
        _fixed(box),
    )
    data = _data(layout, task, objective, box)
    weighed = _program(task, objective, max_steps, torque=True)
    rng = np.random.default_rng(search.seed)
    u0 = _starts(layout, task, box, starts, rng)
    codes = np.asarray(task.linkage.BRANCHES)
    branches = codes[np.arange(starts) % len(codes)]
    s2 = layout.scale**2
    report = None if progress is None else (lambda d, n, b: progress("search", d, n, b * s2))
    solve = functools.partial(_solve_chunk, weighed, data)
    u_all, score_all = solve_all(solve, u0, branches, chunk, report)
    if search.polish and objective.dynamic:
        path_only = _program(task, objective, max_steps, torque=False)
        report = None if progress is None else (lambda d, n, b: progress("polish", d, n, b * s2))
        solve = functools.partial(_solve_chunk, path_only, data)
        u_all, _ = solve_all(solve, u_all, branches, chunk, report)
        score_all = np.asarray(_scores(weighed, data, u_all, branches))
    u_all, score_all = _kept_within(layout, box, weighed, data, u_all, branches, score_all)
    score_all = score_all * s2
    candidates, feasible = _rank(
        layout, task, objective, box, u_all, branches, score_all, search.keep, (weighed, data)
    )
    return Synthesis(
        task=task,
        objective=objective,
        candidates=tuple(candidates),
        starts=starts,
        feasible=feasible,
        seed=search.seed,
        seconds=time.perf_counter() - started,
    )


@cached_jit
def _figures(program: _Program, data: dict, u, branches):
    """``(error (C,), worst |cos mu| (C,))`` of outcomes ``u`` (C, size), exactly: the path
    error ``sum |C - P|^2`` [length**2] (a motion's plus ``L^2 sum wrap(phi - alpha)^2``,
    :mod:`._motion`) and the largest ``|cos mu|`` over the traversed motion on a fine grid
    (above 1: the loop opens between two points)."""
    layout = _layout_of(program, data)
    targets = jnp.asarray(data["targets"])
    fractions = jnp.linspace(0.0, 1.0, CHECK_SAMPLES)
    alpha, weight = jnp.asarray(data["angles"]), (data["length"] * data["scale"]) ** 2

    def one(u, branch):
        fb = layout.make(u, branch)
        theta = layout.angles(u)
        c = jax.vmap(lambda t: coupler_point(fb, t))(theta)
        grid = theta[0] + (theta[-1] - theta[0]) * fractions
        cos_mu = jax.vmap(lambda t: transmission_cosine(fb, t))(grid)
        error = jnp.sum((c - targets) ** 2)
        if program.motion:
            error = error + weight * jnp.sum(turn_gaps(fb, theta, alpha) ** 2)
        return error, jnp.max(jnp.abs(cos_mu))

    return jax.vmap(one)(u, branches)


def _rank(layout, task, objective, box, u_all, branches, scores, keep, programs):
    """The distinct feasible outcomes, best score first, and the count of feasible ones;
    ``programs``: the search's ``(program, data)``."""
    s = layout.scale
    program, data = programs
    error, worst = (np.asarray(a) for a in _figures(program, data, u_all, branches))
    m = layout.m
    v_all = np.asarray(jax.vmap(lambda u: layout.make(u, 1.0).vector())(u_all))
    theta_all = np.asarray(jax.vmap(layout.angles)(u_all))
    slack = np.array([1e-6 * s] * (m - 1) + [1e-9])
    ok = np.isfinite(scores) & np.isfinite(error) & (worst <= np.cos(task.min_transmission))
    ok &= np.all(v_all >= box[:, 0] - slack, axis=1) & np.all(v_all <= box[:, 1] + slack, axis=1)
    batch = layout.linkage.from_vector(v_all, branches)
    limits = np.concatenate(
        [np.asarray(grashof_gaps(batch, task.grashof)),
         np.asarray(region_gaps(batch, tuple(task.pivots), data["region_low"],
                                data["region_high"]))], axis=1)  # fmt: skip
    ok &= np.all(limits <= 1e-9 * s, axis=1)
    if layout.timing is None:  # order defect: the points not passed in order within a turn
        inc = layout.increments(u_all)
        ok &= np.all(inc >= -1e-9, axis=1) & (np.sum(inc, axis=1) <= 2 * np.pi + 1e-9)
    scale_of = np.array([s] * (m - 1) + [1.0])
    kept, keys = [], []
    for i in np.argsort(np.where(ok, scores, np.inf))[: int(ok.sum())]:
        v, theta = v_all[i], theta_all[i]
        key = np.concatenate([v / scale_of, [theta[0]]])
        key[m - 1 :] = np.angle(np.exp(1j * key[m - 1 :]))
        if any(np.max(np.abs(key - k)) < 1e-4 and b == branches[i] for k, b in keys):
            continue  # the same linkage from another start
        keys.append((key, branches[i]))
        fb = layout.linkage(*(np.float64(x) for x in v), np.float64(branches[i]))
        rms = peak = float("nan")
        shakes = {}
        if objective.masses is not None:
            grid = np.linspace(theta[0], theta[-1], 256)
            tau = np.asarray(motor_torque(fb, objective.masses, grid, objective.speed))
            rms, peak = float(np.sqrt(np.mean(tau**2))), float(np.max(np.abs(tau)))
            force, moment = (np.asarray(a) for a in shaking(fb, objective.masses, grid,
                                                               objective.speed))  # fmt: skip
            size = np.hypot(force[:, 0], force[:, 1])
            shakes = {
                "shaking_force_rms": float(np.sqrt(np.mean(size**2))),
                "shaking_force_peak": float(np.max(size)),
                "shaking_moment_rms": float(np.sqrt(np.mean(moment**2))),
                "shaking_moment_peak": float(np.max(np.abs(moment))),
            }
            forces, _ = reactions(fb, objective.masses, grid, objective.speed)
            loads = np.linalg.norm(np.asarray(forces), axis=2)
            shakes["reaction_rms"] = float(np.sqrt(np.mean(loads**2)))
            shakes["reaction_peak"] = float(np.max(loads))
        gamma = 0.0
        if isinstance(task, MotionTask):
            gamma = float(offset(body_angles(fb, jnp.asarray(theta)), jnp.asarray(task.angles)))
        kept.append(
            Candidate(
                fourbar=fb,
                angles=theta,
                error=float(error[i]),
                score=float(scores[i]),
                torque_rms=rms,
                torque_peak=peak,
                min_transmission=float(np.arccos(min(float(worst[i]), 1.0))),
                coupler_angle=gamma,
                **shakes,
            )
        )
        if len(kept) == keep:
            break
    return kept, int(ok.sum())


__all__ = ["Candidate", "Synthesis", "synthesize_path"]
