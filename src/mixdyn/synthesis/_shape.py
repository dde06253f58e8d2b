"""Shape-only path generation: a linkage whose coupler curve over a full crank turn has the
shape of a closed target curve, wherever it lies, however large and however turned.

The task (:class:`ShapeTask`) gives ordered points of a closed curve, taken at roughly even
steps along it (the curve is their trigonometric interpolant: :func:`~._fourier.resample`).
Target and candidate are described by their first ``H`` elliptic Fourier descriptors,
normalised for position, size, orientation and starting point (:mod:`._fourier`); the shape
error is

    ``e = sum_{n=1..H} |N_n(coupler curve) - N_n(target)|^2``   (dimensionless)

over the four entries of each normalised harmonic, the candidate's nearer normalisation of
the two (the ends of its first harmonic's major axis). With ``sense="either"`` (the default)
the target is compared as given and reversed, the nearer counting: the crank may then turn
negatively (:attr:`ShapeCandidate.sense`); with ``"positive"`` the coupler point runs through
the points in their order as the crank turns positively. The coupler curve is sampled at
``samples`` even steps of the crank's angle over a full turn, so the crank must turn fully:
the loop closes (with the least transmission angle) at every crank angle.

The error does not change when the linkage is moved, turned or scaled, so the search fixes
those: the linkage's first number is 1 (a four-bar's ground link, a slider-crank's crank),
its crank pivot at the origin and ``theta0 = 0``; the variables ``u`` are its other numbers
(a four-bar's ``r2, r3, r4, rcx, rcy``; a slider-crank's ``r3, e, rcx, rcy``). The search is
the path search's (:mod:`._solve`): random starts, half on each assembly branch, each solved
by optimistix' Levenberg-Marquardt through the assembly's implicit derivatives, ``jax.vmap``
over a chunk of starts (drawn so that most close over the whole turn with the asked
transmission angle); residuals: ``N_c - N_t`` (4H), the closure and transmission angle over the
turn ``10 relu(|cos mu| - c)`` with ``c = cos(min_transmission) - 0.001`` and the bounds ``10
relu(low' - u)``, ``10 relu(u - high')`` with the bounds moved 0.1 % inside (margins, so that
an outcome held at a penalty's edge still passes the exact check). Outcomes are checked
exactly (closure on a fine grid of the whole turn, bounds), ranked by the shape error and
deduplicated.

Each kept linkage is then placed onto the target by the similarity between the two curves'
descriptors (:func:`~._fourier.similarity`: the ratio of the first harmonics' semi-major
axes, the difference of their orientations, the mean points onto each other): its lengths
scaled, its crank pivot and ``theta0`` moved, so that its coupler curve lies on the target.
Its point-wise fit is reported too: the distance of each target point from the placed curve
(:attr:`ShapeCandidate.distance`), and the crank's angle at the nearest point of each.
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
from ._dynamics import motor_torque, reactions, shaking
from ._fourbar import FourBar
from ._fourier import Normalised, describe, normalise, resample, shape_gap, similarity
from ._linkage import Linkage, coupler_curve
from ._search import Candidate, Synthesis
from ._settings import SearchSettings
from ._slidercrank import SliderCrank
from ._solve import (
    CHECK_SAMPLES,
    CLOSURE_MARGIN,
    PENALTY,
    distinct,
    levenberg_marquardt,
    solve_all,
)
from ._task import LINKAGES, RATIO_BOUNDS, Objective

#: The target's samples for its descriptors (at least; more where it has more points).
TARGET_SAMPLES = 512

#: Each linkage type's starts: ``(low, high)`` of every variable (after the fixed first
#: number), drawn uniformly.
_STARTS = {
    FourBar: ((0.05, 0.8), (0.3, 3.0), (0.3, 3.0), (-2.0, 2.0), (-2.0, 2.0)),
    SliderCrank: ((1.2, 5.0), (-1.0, 1.0), (-2.0, 2.0), (-2.0, 2.0)),
}


@functools.partial(jax.jit, static_argnums=1)
def normalised(samples, harmonics: int) -> Normalised:
    """The normalised descriptors of the closed curve through ``samples`` (K, 2) [length]
    (:func:`~._fourier.describe` and :func:`~._fourier.normalise`, compiled once per shape)."""
    return normalise(describe(samples, harmonics))


@dataclasses.dataclass(frozen=True)
class ShapeTask:
    """Shape-only path generation: the coupler curve over a full crank turn shaped like the
    closed curve through ``points``; the linkage's place, size and orientation follow.

    Attributes:
        points: (N, 2) ordered points of the closed target curve [length], N > 2 H, taken at
            roughly even steps along it (16 or more: the curve is their trigonometric
            interpolant), in the sense the coupler point runs as the crank turns positively;
            a last point equal to the first is dropped.
        harmonics: ``H``, the elliptic Fourier harmonics compared (>= 2).
        ratios: ``(low, high)`` of the lengths as multiples of the linkage's first number
            (a four-bar's ground link, a slider-crank's crank; default ``(0.05, 20)``); the
            coupler point (and a slider-crank's offset) within ``high`` of zero.
        min_transmission: the least transmission angle over the turn [rad].
        linkage: ``"four_bar"`` (default) or ``"slider_crank"``, or the class; held as the
            class.
        samples: crank angles over the turn at which the candidate's curve is sampled for
            its descriptors and its closure.
        sense: ``"either"`` (the default: the curve run through in either sense, the crank
            turning negatively where reversed) or ``"positive"`` (in the points' order as the
            crank turns positively).
    """

    points: np.ndarray
    harmonics: int = 8
    ratios: tuple[float, float] = RATIO_BOUNDS
    min_transmission: float = 0.0
    linkage: str | type[Linkage] = "four_bar"
    samples: int = 128
    sense: str = "either"

    def __post_init__(self):
        kind = self.linkage
        if isinstance(kind, str):
            kind = LINKAGES.get(kind)
        if kind not in _STARTS:
            raise ModelError(
                f"no shape synthesis of a {self.linkage!r}; one of four_bar, slider_crank",
                "linkage",
            )
        object.__setattr__(self, "linkage", kind)
        h = int(self.harmonics)
        if h < 2:
            raise ModelError(f"harmonics must be at least 2, got {self.harmonics!r}", "harmonics")
        object.__setattr__(self, "harmonics", h)
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)):
            raise ModelError(f"points must be finite (x, y) pairs, got shape {pts.shape}", "points")
        spread = np.max(np.linalg.norm(pts - pts.mean(axis=0), axis=1)) if len(pts) else 0.0
        if len(pts) > 1 and np.linalg.norm(pts[-1] - pts[0]) <= 1e-12 * max(spread, 1e-300):
            pts = pts[:-1]  # the curve closed by repeating its first point
        if len(pts) <= 2 * h:
            raise ModelError(
                f"{len(pts)} points describe at most {(len(pts) - 1) // 2} harmonics, not {h}: "
                f"give more than {2 * h} points or fewer harmonics",
                "points",
            )
        if not spread > 0:
            raise ModelError("the points coincide: they describe no curve", "points")
        object.__setattr__(self, "points", pts)
        lo, hi = (float(b) for b in self.ratios)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise ModelError(f"ratios must be 0 < low < high, got {self.ratios!r}", "ratios")
        object.__setattr__(self, "ratios", (lo, hi))
        if not 0.0 <= self.min_transmission < np.pi / 2:
            raise ModelError("min_transmission must lie in [0, pi/2) rad", "min_transmission")
        if int(self.samples) < 4 * h:
            raise ModelError(f"samples must be at least 4 harmonics ({4 * h})", "samples")
        object.__setattr__(self, "samples", int(self.samples))
        if self.sense not in ("either", "positive"):
            raise ModelError(f"sense must be 'either' or 'positive', got {self.sense!r}", "sense")
        norm = normalised(resample(pts, max(TARGET_SAMPLES, 4 * len(pts))), h)
        if not np.all(np.isfinite(np.asarray(norm.coefficients))):
            raise ModelError("the points' curve has no finite descriptors", "points")

    @property
    def timing(self) -> None:
        """None: no timing (the shape alone counts)."""
        return None

    @property
    def grashof(self) -> str:
        """``"any"``: no Grashof type asked beyond a crank that turns fully."""
        return "any"

    @property
    def pivots(self) -> dict:
        """No ground pivots' regions (a shape fixes no place)."""
        return {}

    @property
    def size(self) -> float:
        """The targets' size: the largest distance from their centre [length]."""
        c = self.points.mean(axis=0)
        return float(np.max(np.linalg.norm(self.points - c, axis=1)))

    def target(self, reverse: bool = False) -> Normalised:
        """The target curve's normalised descriptors (its trigonometric interpolant's), run
        through in the points' order or, with ``reverse``, against it."""
        points = self.points[::-1] if reverse else self.points
        samples = resample(points, max(TARGET_SAMPLES, 4 * len(points)))
        return normalised(samples, self.harmonics)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` of the variables ``u`` (the linkage's numbers after the first,
        before the pivot): lengths within the ratios, the others within ``high`` of 0."""
        lo, hi = self.ratios
        names = self.linkage.NAMES[1:-3]
        low = np.array([lo if n in self.linkage.LENGTHS else -hi for n in names])
        return low, np.full(len(names), hi)


@dataclasses.dataclass(frozen=True)
class ShapeCandidate(Candidate):
    """One linkage of a shape synthesis, placed onto the target (a :class:`Candidate` whose
    ``error`` is the dimensionless shape error and whose ``angles`` (N,) are the crank's
    angles at the points of its curve nearest the targets).

    Attributes:
        distance: the largest distance of a target point from the placed coupler curve
            [length].
        scale: the similarity's scale (the placed linkage's first number).
        rotation: the similarity's angle [rad] (the placed linkage's ``theta0``).
        shift: (2,) the similarity's shift [length] (the placed crank pivot).
        sense: +1 where the coupler point runs through the points in their order as the crank
            turns positively, -1 where the crank turns negatively (the model's speed is then
            negative).
    """

    distance: float = float("nan")
    scale: float = float("nan")
    rotation: float = float("nan")
    shift: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    sense: float = 1.0


@dataclasses.dataclass(frozen=True)
class ShapeSynthesis(Synthesis):
    """The outcome of a shape synthesis (:func:`synthesize_shape`): its candidates are
    :class:`ShapeCandidate`\\ s, their models and files run a full crank turn from the first
    target's nearest point, in the candidate's sense."""

    def model(self, k: int = 0):
        """The :class:`mixdyn.Model` of candidate ``k``, its crank at the first target's
        nearest point at t = 0, turning at the objective's speed in the candidate's sense."""
        from .build import linkage_model

        c = self.candidates[k]
        speed = c.sense * self.objective.speed
        return linkage_model(
            c.fourbar, self.objective.masses, start=float(c.angles[0]), speed=speed
        )

    def model_file(self, k: int = 0) -> str:
        """YAML text of candidate ``k``'s model file: a kinematic and, with masses, an inverse
        run over a full turn of the crank."""
        from .build import model_file_text

        c = self.candidates[k]
        head = (
            f"A {c.fourbar.TITLE} synthesized by mixdyn (candidate {k + 1} of "
            f"{len(self.candidates)}, seed {self.seed}) for the shape of a closed curve:\n"
            f"shape error (normalised elliptic Fourier descriptors, {self.task.harmonics} "
            f"harmonics) {c.error:.6g}, farthest target {c.distance:.6g} m from the curve"
        )
        if np.isfinite(c.torque_rms):
            head += f", motor torque RMS {c.torque_rms:.6g} N*m, peak {c.torque_peak:.6g} N*m"
        start = float(c.angles[0])
        return model_file_text(
            c.fourbar,
            self.objective.masses,
            start=start,
            end=start + c.sense * 2 * np.pi,
            speed=c.sense * self.objective.speed,
            header=head + "\n\n  mixdyn run FILE",
            targets=self.task.points,
        )

    def table(self):
        """A pandas DataFrame: :meth:`Synthesis.table`'s, with the distance and placement."""
        out = super().table()
        out["distance"] = [c.distance for c in self.candidates]
        out["scale"] = [c.scale for c in self.candidates]
        return out


@dataclasses.dataclass(frozen=True)
class _Program:
    """What decides a shape search's programs (their static part)."""

    linkage: type[Linkage]
    harmonics: int
    samples: int
    max_steps: int
    either: bool = True


def _make(linkage: type[Linkage], u, branch) -> Linkage:
    """The linkage of variables ``u``: first number 1, pivot at the origin, ``theta0 = 0``."""
    v = jnp.concatenate([jnp.ones(1), u, jnp.zeros(3)])
    return linkage.from_vector(v, branch)


def _targets(data: dict) -> tuple[Normalised, Normalised]:
    """The target's normalised descriptors as given and reversed, from the data's arrays."""
    return tuple(
        Normalised(**{k: jnp.asarray(v) for k, v in data[key].items()})
        for key in ("target", "reverse")
    )


def _nearest_gap(program: _Program, norm: Normalised, targets):
    """``(gap (H, 2, 2), flip, reversed)``: :func:`~._fourier.shape_gap` against the target,
    or against the reversed target where that is nearer and either sense is allowed."""
    gap, flip = shape_gap(norm, targets[0])
    if not program.either:
        return gap, flip, jnp.zeros(())
    other, other_flip = shape_gap(norm, targets[1])
    back = jnp.sum(other**2) < jnp.sum(gap**2)
    return jnp.where(back, other, gap), jnp.where(back, other_flip, flip), back.astype(float)


def _residuals(program: _Program, data: dict):
    targets = _targets(data)
    angles = jnp.linspace(0.0, 2 * np.pi, program.samples, endpoint=False)
    lo, hi = jnp.asarray(data["low"]), jnp.asarray(data["high"])

    def r(u, branch):
        lk = _make(program.linkage, u, branch)
        curve = jax.vmap(lk.coupler_point)(angles)
        gap, _, _ = _nearest_gap(program, normalise(describe(curve, program.harmonics)), targets)
        cos_mu = jax.vmap(lk.transmission_cosine)(angles)
        closure = PENALTY * jax.nn.relu(jnp.abs(cos_mu) - data["cmax"])
        bounds = PENALTY * jnp.concatenate([jax.nn.relu(lo - u), jax.nn.relu(u - hi)])
        return jnp.concatenate([gap.ravel(), closure, bounds])

    return r


@eqx.filter_jit
def _solve_chunk(program: _Program, data: dict, u0, branches):
    return levenberg_marquardt(_residuals(program, data), program.max_steps)(u0, branches)


@eqx.filter_jit
def _figures(program: _Program, data: dict, u, branches):
    """``(shape error (C,), flip (C,), reversed (C,), worst |cos mu| (C,), normalised
    descriptors)`` of outcomes ``u`` (C, size) on the fine grid (:data:`CHECK_SAMPLES` crank
    angles)."""
    targets = _targets(data)
    angles = jnp.linspace(0.0, 2 * np.pi, CHECK_SAMPLES, endpoint=False)

    def one(u, branch):
        lk = _make(program.linkage, u, branch)
        norm = normalise(describe(jax.vmap(lk.coupler_point)(angles), program.harmonics))
        gap, flip, back = _nearest_gap(program, norm, targets)
        worst = jnp.max(jnp.abs(jax.vmap(lk.transmission_cosine)(angles)))
        return jnp.sum(gap**2), flip, back, worst, norm

    return jax.vmap(one)(u, branches)


@functools.partial(jax.jit, static_argnums=0)
def _worst(linkage: type[Linkage], u):
    """(C,) the largest ``|cos mu|`` of variables ``u`` (C, size) over 64 crank angles."""
    angles = jnp.linspace(0.0, 2 * np.pi, 64, endpoint=False)

    def one(u):
        lk = _make(linkage, u, 1.0)  # the transmission angle is the same on either branch
        return jnp.max(jnp.abs(jax.vmap(lk.transmission_cosine)(angles)))

    return jax.vmap(one)(u)


def _starts(linkage: type[Linkage], count: int, cmax: float, rng) -> np.ndarray:
    """(count, size) starts drawn uniformly in the linkage's start box (:data:`_STARTS`),
    those whose crank turns fully with the asked transmission angle first: eight times as
    many drawn, the ones that close at 64 crank angles with ``|cos mu| <= cmax`` taken, the
    rest filled with the others."""
    box = np.array(_STARTS[linkage])
    u = box[:, 0] + (box[:, 1] - box[:, 0]) * rng.random((8 * count, len(box)))
    closes = np.asarray(_worst(linkage, u)) <= cmax
    return np.concatenate([u[closes], u[~closes]])[:count]


def place(lk: Linkage, scale, angle, shift) -> Linkage:
    """``lk`` carried by the similarity ``p -> scale R(angle) p + shift``: its lengths times
    ``scale``, its crank pivot moved, its ``theta0`` turned (the branch kept)."""
    v = np.asarray(lk.vector(), dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    pivot = scale * np.array([c * v[-3] - s * v[-2], s * v[-3] + c * v[-2]]) + shift
    out = np.concatenate([scale * v[:-3], pivot, [v[-1] + angle]])
    return type(lk)(*(np.float64(x) for x in out), np.float64(lk.branch))


@jax.jit
def _nearest(lk: Linkage, points, guess):
    """(N,) crank angles [rad] of the curve's points nearest ``points`` (N, 2), by Newton's
    steps on ``(C - P) . C' = 0`` from ``guess`` (N,)."""

    def step(t, p):
        g = lambda t: jnp.dot(lk.coupler_point(t) - p, jax.jacfwd(lk.coupler_point)(t))  # noqa: E731
        value, slope = jax.jvp(g, (t,), (jnp.ones_like(t),))
        return t - value / jnp.where(slope > 0, slope, 1.0)

    def one(p, t):
        return jax.lax.fori_loop(0, 8, lambda _, t: step(t, p), t)

    return jax.vmap(one)(points, guess)


def fit(lk: Linkage, points) -> tuple[np.ndarray, np.ndarray]:
    """``(angles (N,) [rad], distances (N,) [length])``: the crank angle of the point of
    ``lk``'s coupler curve (over a full turn) nearest each of ``points`` (N, 2), and how far
    it is."""
    points = np.asarray(points, dtype=float)
    grid = np.linspace(0.0, 2 * np.pi, 2048, endpoint=False)
    curve = np.asarray(coupler_curve(lk, grid))
    guess = grid[np.argmin(np.linalg.norm(curve[None] - points[:, None], axis=2), axis=1)]
    angles = np.asarray(_nearest(lk, jnp.asarray(points), jnp.asarray(guess)))
    angles = np.where(np.abs(angles - guess) < 2 * np.pi / 2048, angles, guess)
    near = np.asarray(coupler_curve(lk, angles))
    return angles, np.linalg.norm(near - points, axis=1)


def _dynamics(lk: Linkage, objective: Objective, sense: float) -> dict:
    """The motor torque's, the shaking's and the joint reactions' RMS and peak over a full
    turn, the crank turning in ``sense`` (empty without masses)."""
    if objective.masses is None:
        return {}
    grid = np.linspace(0.0, 2 * np.pi, 256)
    m, w = objective.masses, sense * objective.speed
    tau = np.asarray(motor_torque(lk, m, grid, w))
    force, moment = (np.asarray(a) for a in shaking(lk, m, grid, w))
    size = np.hypot(force[:, 0], force[:, 1])
    loads = np.linalg.norm(np.asarray(reactions(lk, m, grid, w)[0]), axis=2)
    rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
    peak = lambda x: float(np.max(np.abs(x)))  # noqa: E731
    return {
        "torque_rms": rms(tau),
        "torque_peak": peak(tau),
        "shaking_force_rms": rms(size),
        "shaking_force_peak": peak(size),
        "shaking_moment_rms": rms(moment),
        "shaking_moment_peak": peak(moment),
        "reaction_rms": rms(loads),
        "reaction_peak": peak(loads),
    }


def synthesize_shape(
    task: ShapeTask,
    objective: Objective | None,
    search: SearchSettings,
    *,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> ShapeSynthesis:
    """Linkages whose coupler curve over a full crank turn has the shape of ``task``'s closed
    curve, least shape error first, each placed onto it (called by :func:`mixdyn.synthesize`
    for a :class:`ShapeTask`).

    Args:
        task: the shape task.
        objective: the links' masses and the crank's speed for the reported torques (its
            weights must be 0: the shape error alone is searched).
        search: the starts (half on each assembly branch), seed, chunk, steps and
            candidates kept (:class:`~._settings.SearchSettings`; ``polish`` unused).
        progress: called after each chunk with ``("search", starts done, starts, best sum
            of squared residuals so far)``.

    Returns:
        A :class:`ShapeSynthesis` of :class:`ShapeCandidate`\\ s.

    Raises:
        ModelError: a dynamic weight in the objective; a slider-crank's masses without a
            slider's mass.
    """
    objective = objective or Objective()
    if objective.dynamic:
        raise ModelError(
            "a shape task searches the shape error alone: give an objective without torque, "
            "shaking or reaction weights (its masses and speed give the reported figures)",
            "objective",
        )
    starts = search.starts
    masses = objective.masses
    if masses is not None and task.linkage is SliderCrank and not masses.slider > 0:
        raise ModelError(
            "a slider-crank's slider needs a mass > 0 with the links' masses: give "
            "Masses(slider=...)",
            "masses",
        )
    started = time.perf_counter()
    targets = (task.target(), task.target(reverse=True))
    low, high = task.bounds()
    data = {
        **{
            key: {f.name: np.asarray(getattr(t, f.name)) for f in dataclasses.fields(t)}
            for key, t in zip(("target", "reverse"), targets, strict=True)
        },
        "low": low + (1.0 - CLOSURE_MARGIN) * np.abs(low),  # the penalties' margins inside
        "high": high - (1.0 - CLOSURE_MARGIN) * np.abs(high),
        "cmax": np.float64(float(np.cos(task.min_transmission)) - (1.0 - CLOSURE_MARGIN)),
    }
    either = task.sense == "either"
    program = _Program(task.linkage, task.harmonics, task.samples, search.max_steps, either)
    rng = np.random.default_rng(search.seed)
    u0 = _starts(task.linkage, starts, float(data["cmax"]), rng)
    branches = np.where(np.arange(starts) % 2 == 0, 1.0, -1.0)
    report = None if progress is None else (lambda d, n, b: progress("search", d, n, b))
    solve = lambda u, b: _solve_chunk(program, data, u, b)  # noqa: E731
    u_all, scores = solve_all(solve, u0, branches, search.chunk_size, report)
    error, flip, back, worst, norms = _figures(program, data, u_all, branches)
    error, flip, back, worst = (np.asarray(a) for a in (error, flip, back, worst))
    slack = 1e-9 * high
    ok = np.isfinite(error) & np.isfinite(scores) & (worst <= np.cos(task.min_transmission))
    ok &= np.all((u_all >= low - slack) & (u_all <= high + slack), axis=1)
    kept = []
    for i in distinct(ok, error, u_all, branches, 1e-4):
        norm = jax.tree_util.tree_map(lambda a, i=i: a[i], norms)
        target, sense = (targets[1], -1.0) if back[i] > 0.5 else (targets[0], 1.0)
        scale, angle, shift = (np.asarray(x) for x in similarity(norm, target, flip[i]))
        lk = place(_make(task.linkage, u_all[i], branches[i]), float(scale), float(angle), shift)
        angles, distances = fit(lk, task.points)
        figures = {"torque_rms": float("nan"), "torque_peak": float("nan")}
        figures.update(_dynamics(lk, objective, sense))
        kept.append(
            ShapeCandidate(
                fourbar=lk,
                angles=angles,
                error=float(error[i]),
                score=float(scores[i]),
                min_transmission=float(np.arccos(min(float(worst[i]), 1.0))),
                distance=float(np.max(distances)),
                scale=float(scale),
                rotation=float(angle),
                shift=shift,
                sense=sense,
                **figures,
            )
        )
        if len(kept) == search.keep:
            break
    return ShapeSynthesis(
        task=task,
        objective=objective,
        candidates=tuple(kept),
        starts=starts,
        feasible=int(ok.sum()),
        seed=search.seed,
        seconds=time.perf_counter() - started,
    )


__all__ = [
    "ShapeCandidate",
    "ShapeSynthesis",
    "ShapeTask",
    "fit",
    "normalised",
    "place",
    "synthesize_shape",
]
