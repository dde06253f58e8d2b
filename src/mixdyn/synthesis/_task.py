"""What a synthesis asks for: the path or function task and the objective, checked when made.

:class:`PathTask` holds the target points, the timing (prescribed input angles, or free), the
bounds of the four-bar's numbers and the least transmission angle. :class:`FunctionTask` holds
input-output angle pairs (or a function over a range at precision points). :class:`Objective`
says how the path error and the motor torque are weighed. All are plain, immutable values; the
search (:mod:`._search`, :mod:`._function`) turns them into one residual function of a
candidate's variables.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ..errors import ModelError
from ._dynamics import Masses
from ._fourbar import FourBar
from ._limits import check_grashof, check_pivots
from ._linkage import Linkage
from ._slidercrank import SliderCrank
from ._stephenson import StephensonI, StephensonIII
from ._watt import WattI, WattII

#: The linkage types of a path task by name (``PathTask(linkage=...)``, ``linkage:`` in files).
LINKAGES: dict[str, type[Linkage]] = {
    "four_bar": FourBar,
    "slider_crank": SliderCrank,
    "stephenson1": StephensonI,
    "stephenson3": StephensonIII,
    "watt1": WattI,
    "watt2": WattII,
}


@dataclasses.dataclass(frozen=True)
class PathTask:
    """Path generation: a linkage's coupler point through target points, in their order.

    Numbers are in one consistent unit system; the model and model file of a result
    (:meth:`~._search.Synthesis.model`, :meth:`~._search.Synthesis.write`) read them as SI
    (m, kg, s).

    Attributes:
        points: (N, 2) the target points [length], N >= 2, in the order the coupler point
            passes them as the crank turns in the positive sense.
        timing: None (timing-free: the input angles are found too, increasing, within one
            turn) or (N,) prescribed input angles [rad], increasing; only their differences
            count (the crank's angle at the first point is found) unless ``timing_from`` is
            ``"ground"``.
        timing_from: ``"first"`` (the default: the timing counts from the crank's angle at the
            first point, which the search finds) or ``"ground"`` (the timing is the crank's
            angle from the ground link, a slider-crank's from its slide, as it is: the
            literature's prescribed-timing cases).
        bounds: ``name -> (low, high)`` for numbers of the linkage's ``NAMES`` (lengths in
            [length], ``theta0`` in [rad]; ``low == high`` fixes the number: the crank's
            pivot at the origin, the ground link along x); by default the link lengths lie within
            ``[0.05, 5]`` times the targets' size, the other lengths (coupler point, a
            slider-crank's offset) within five sizes of zero and the crank's pivot within
            three sizes of the targets' centre.
        min_transmission: the least transmission angle along the traversed motion [rad]
            (0: the loop only has to close).
        linkage: the linkage type: ``"four_bar"`` (:class:`~._fourbar.FourBar`, the
            default), ``"slider_crank"`` (:class:`~._slidercrank.SliderCrank`),
            ``"stephenson1"`` (:class:`~._stephenson.StephensonI`), ``"stephenson3"``
            (:class:`~._stephenson.StephensonIII`), ``"watt1"``
            (:class:`~._watt.WattI`) or ``"watt2"`` (:class:`~._watt.WattII`), or the class
            itself; held as the class (:data:`LINKAGES`).
        grashof: the Grashof type asked for (:mod:`._limits`): ``"any"`` (the default: the
            loop has only to close along the traversed motion), ``"crank_rocker"`` (the crank
            the shortest link of a Grashof four-bar: it turns a full revolution; a
            slider-crank's crank turns fully, ``r2 + |e| <= r3``), ``"double_crank"`` (the
            ground the shortest; four-bars only) or ``"grashof"`` (any link the shortest,
            ``s + l <= p + q``; a slider-crank's ``min(r2, r3) + |e| <= max(r2, r3)``).
        pivots: ``name -> ((x_lo, x_hi), (y_lo, y_hi))`` [length]: rectangles in which the
            ground pivots lie, ``"O2"`` (the crank's pivot; the bounds of ``x0``, ``y0``,
            which are then not given) and a four-bar's ``"O4"``; held as tuples of floats.
    """

    points: np.ndarray
    timing: np.ndarray | None = None
    bounds: dict = dataclasses.field(default_factory=dict)
    min_transmission: float = 0.0
    linkage: str | type[Linkage] = "four_bar"
    grashof: str = "any"
    pivots: dict = dataclasses.field(default_factory=dict)
    timing_from: str = "first"

    def __post_init__(self):
        if self.timing_from not in ("first", "ground"):
            raise ModelError(
                f"timing_from must be 'first' or 'ground', got {self.timing_from!r}", "timing_from"
            )
        if self.timing_from == "ground" and self.timing is None:
            raise ModelError(
                "timing_from 'ground' needs a timing (the crank's angle at each point)",
                "timing_from",
            )
        kind = self.linkage
        if isinstance(kind, str):
            if kind not in LINKAGES:
                raise ModelError(f"no linkage {kind!r}; one of {', '.join(LINKAGES)}", "linkage")
            object.__setattr__(self, "linkage", LINKAGES[kind])
        elif kind not in LINKAGES.values():
            raise ModelError(f"no linkage {kind!r}; one of {', '.join(LINKAGES)}", "linkage")
        names = self.linkage.NAMES
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or not np.all(np.isfinite(pts)):
            raise ModelError(
                f"points must be two or more finite (x, y) pairs, got shape {pts.shape}", "points"
            )
        object.__setattr__(self, "points", pts)
        if self.timing is not None:
            tim = np.asarray(self.timing, dtype=float)
            if tim.shape != (len(pts),) or not np.all(np.isfinite(tim)):
                raise ModelError(f"timing must be {len(pts)} input angles [rad]", "timing")
            if not np.all(np.diff(tim) > 0) or tim[-1] - tim[0] > 2 * np.pi:
                raise ModelError("timing must increase, within one turn (2*pi rad)", "timing")
            object.__setattr__(self, "timing", tim)
        for name, ends in self.bounds.items():
            if name not in names:
                raise ModelError(
                    f"no number {name!r} of a {self.linkage.TITLE}; one of {', '.join(names)}",
                    "bounds",
                )
            lo, hi = (float(x) for x in ends)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ModelError(
                    f"bounds (low, high) with low <= high (equal: the number fixed), got {ends!r}",
                    name,
                )
            if name in self.linkage.LENGTHS and lo <= 0:
                raise ModelError(f"a length's low bound must be > 0, got {lo!r}", name)
        if not 0.0 <= self.min_transmission < np.pi / 2:
            raise ModelError("min_transmission must lie in [0, pi/2) rad", "min_transmission")
        check_grashof(self.linkage, self.grashof)
        object.__setattr__(self, "pivots", check_pivots(self.linkage, self.pivots))
        if "O2" in self.pivots and {"x0", "y0"} & set(self.bounds):
            raise ModelError(
                "the crank's pivot is bounded twice: give its region (pivots O2) or the bounds "
                "of x0 and y0, not both",
                "O2",
            )

    @property
    def size(self) -> float:
        """The targets' size: the largest distance from their centre [length] (> 0)."""
        c = self.points.mean(axis=0)
        return float(max(np.max(np.linalg.norm(self.points - c, axis=1)), 1e-12))

    def box(self) -> np.ndarray:
        """(len(NAMES), 2) the bounds of every number (the linkage's ``NAMES``' order);
        ``theta0`` unbounded (``-inf, inf``) unless given."""
        s, c = self.size, self.points.mean(axis=0)
        out = {n: (-5 * s, 5 * s) for n in self.linkage.NAMES[:-3]}
        out.update({n: (0.05 * s, 5.0 * s) for n in self.linkage.LENGTHS})
        out.update({"x0": (c[0] - 3 * s, c[0] + 3 * s), "y0": (c[1] - 3 * s, c[1] + 3 * s)})
        out["theta0"] = (-np.inf, np.inf)
        out.update({k: tuple(float(x) for x in v) for k, v in self.bounds.items()})
        if "O2" in self.pivots:  # the crank's pivot's region: the bounds of x0, y0
            out.update(x0=tuple(self.pivots["O2"][0]), y0=tuple(self.pivots["O2"][1]))
        return np.array([out[n] for n in self.linkage.NAMES], dtype=float)


@dataclasses.dataclass(frozen=True)
class Objective:
    """How a candidate is scored: path error, plus the motor torque, the shaking force and
    moment and the joint reactions by weight.

    The score is ``sum_i |C(theta_i) - P_i|^2 + torque_weight * T^2 + shaking_force_weight *
    F^2 + shaking_moment_weight * M^2 + reaction_weight * R^2`` with ``T`` the RMS
    (``torque="rms"``) or a smooth stand-in for the peak (``"peak"``: the mean 8-norm
    ``mean(|tau|^8)^(1/8)``, at most the peak and dominated by it) of the motor torque over
    the traversed input angles, the crank turning at ``speed``; ``F`` and ``M`` the same
    measure (``shaking``) of the shaking force's magnitude and of the shaking moment about
    the crank's pivot (:func:`~._dynamics.shaking`); ``R`` the ``reaction`` measure
    (``"peak"`` by default) of the joints' forces' magnitudes over the joints and the
    motion, gravity included (:func:`~._dynamics.reactions`).

    Attributes:
        masses: how the links weigh (None: no dynamics; the torque is not computed).
        speed: the crank's constant speed [rad / time].
        torque_weight: [length**2 / torque**2] the weight of ``T^2`` (0: kinematics only).
        torque: ``"rms"`` or ``"peak"``.
        shaking_force_weight: [length**2 / force**2] the weight of ``F^2``.
        shaking_moment_weight: [length**2 / torque**2] the weight of ``M^2``.
        shaking: ``"rms"`` or ``"peak"``: the shaking force's and moment's measure.
        reaction_weight: [length**2 / force**2] the weight of ``R^2``.
        reaction: ``"peak"`` or ``"rms"``: the joint reactions' measure.
        samples: input angles over the traversed motion at which the torque and the
            transmission angle are evaluated.
    """

    masses: Masses | None = None
    speed: float = 1.0
    torque_weight: float = 0.0
    torque: str = "rms"
    samples: int = 48
    shaking_force_weight: float = 0.0
    shaking_moment_weight: float = 0.0
    shaking: str = "rms"
    reaction_weight: float = 0.0
    reaction: str = "peak"

    @property
    def dynamic(self) -> bool:
        """Whether a dynamic term weighs in the score."""
        return max(self.torque_weight, self.reaction_weight, self.shaking_force_weight,
                   self.shaking_moment_weight) > 0  # fmt: skip

    @property
    def shakes(self) -> bool:
        """Whether the shaking force or moment weighs in the score."""
        return max(self.shaking_force_weight, self.shaking_moment_weight) > 0

    def __post_init__(self):
        for key in ("torque", "shaking", "reaction"):
            if getattr(self, key) not in ("rms", "peak"):
                raise ModelError(f"{key} must be 'rms' or 'peak', got {getattr(self, key)!r}", key)
        for key in ("torque_weight", "shaking_force_weight", "shaking_moment_weight",
                    "reaction_weight"):  # fmt: skip
            w = getattr(self, key)
            if not (np.isfinite(w) and w >= 0):
                raise ModelError(f"{key} must be a finite number >= 0", key)
        if self.dynamic and self.masses is None:
            raise ModelError(
                "a torque, shaking or reaction objective needs the links' masses: give "
                "masses=Masses(density=...)",
                "masses",
            )
        if not (np.isfinite(self.speed) and self.speed > 0):
            raise ModelError("speed must be a finite number > 0 [rad/time]", "speed")
        if int(self.samples) < 4:
            raise ModelError("samples must be at least 4", "samples")


#: The default bounds of the crank, coupler and rocker as multiples of the ground link.
RATIO_BOUNDS = (0.05, 20.0)

#: The linkage types of a function task by name (``FunctionTask(linkage=...)``): those with
#: a grounded output (:attr:`~._linkage.Linkage.OUTPUT`).
FUNCTION_LINKAGES: dict[str, type[Linkage]] = {
    k: v for k, v in LINKAGES.items() if v.OUTPUT is not None
}


def function_linkage(kind: str | type[Linkage]) -> type[Linkage]:
    """The linkage type of a function task named ``kind`` (or the type itself); a
    :class:`~mixdyn.errors.ModelError` at ``linkage`` for a linkage without a grounded output
    of its own (a Watt I, a Stephenson I) or an unknown one, saying the choices."""
    cls = LINKAGES.get(kind) if isinstance(kind, str) else kind
    if cls in FUNCTION_LINKAGES.values():
        return cls
    if cls in LINKAGES.values():
        raise ModelError(
            f"a {cls.TITLE} cannot generate a function: its follower ends on the rocker, so "
            "its only grounded output is the rocker, which the four-bar alone sets: give "
            "linkage 'four_bar'",
            "linkage",
        )
    raise ModelError(
        f"no function-generating linkage {kind!r}; one of {', '.join(FUNCTION_LINKAGES)}",
        "linkage",
    )


def chebyshev(low: float, high: float, n: int) -> np.ndarray:
    """Chebyshev's ``n`` precision points over ``[low, high]``, increasing:
    ``(low + high)/2 - (high - low)/2 cos((2j - 1) pi / (2n))``, ``j = 1..n``."""
    j = np.arange(1, n + 1)
    return 0.5 * (low + high) - 0.5 * (high - low) * np.cos((2 * j - 1) * np.pi / (2 * n))


@dataclasses.dataclass(frozen=True)
class FunctionTask:
    """Function generation: a linkage's output at given crank angles.

    The output (:meth:`~._linkage.Linkage.output`) is, by ``linkage``: a four-bar's rocker
    angle, a slider-crank's slider position along its slide, a Stephenson III's or a Watt
    II's follower angle (the link pivoted at the third ground pivot ``O6``); the angles
    count from the ground link (the slide's direction for a slider-crank's crank).

    Attributes:
        inputs: (N,) the crank's angles ``theta2`` [rad], N >= 2, strictly monotone, within
            a turn: from the ground link, or with ``free_start`` from the crank's unknown
            start angle.
        outputs: (N,) the outputs at them: angles [rad] from the ground link, or a
            slider-crank's positions [length] along the slide from its point ``P0`` nearest
            the crank's pivot; with ``free_start`` from the output's unknown start (an angle,
            or a slider's position).
        free_start: the inputs and outputs count from starts found by the search (two more
            unknowns) instead of from the ground link (the slide's ``P0``).
        bounds: ``(low, high)`` of the link lengths as multiples of the ground link (a
            four-bar's crank, coupler and rocker, a six-bar's ``r2``..``r6``; default ``(0.05,
            20)``), or of a slider-crank's crank and rod as multiples of the outputs' span
            (:attr:`scale`). A six-bar's points ``dx, dy, gx, gy`` and a slider-crank's offset
            ``e`` lie within ``±high`` of zero (in the same measure).
        min_transmission: the least transmission angle from the first input to the last [rad]
            (a six-bar's: both loops').
        grashof: the Grashof type asked for, as for a :class:`PathTask`: ``"any"`` (the
            default), ``"grashof"``, ``"crank_rocker"`` or ``"double_crank"`` (a four-bar's;
            a slider-crank's as a path task's: ``"crank_rocker"``, ``r2 + |e| <= r3``, or
            ``"grashof"``; a six-bar's ``"any"`` only).
        linkage: ``"four_bar"`` (the default), ``"slider_crank"``, ``"stephenson3"`` or
            ``"watt2"`` (:data:`FUNCTION_LINKAGES`), or the class itself; held as the class.
            A Watt I's and a Stephenson I's follower ends on the rocker: their only grounded
            output is the rocker's, which the four-bar alone sets, and they are refused.
    """

    inputs: np.ndarray
    outputs: np.ndarray
    free_start: bool = False
    bounds: tuple[float, float] = RATIO_BOUNDS
    min_transmission: float = 0.0
    grashof: str = "any"
    linkage: str | type[Linkage] = "four_bar"

    def __post_init__(self):
        object.__setattr__(self, "linkage", function_linkage(self.linkage))
        x = np.asarray(self.inputs, dtype=float)
        y = np.asarray(self.outputs, dtype=float)
        if x.ndim != 1 or len(x) < 2 or y.shape != x.shape:
            raise ModelError(
                f"inputs and outputs must be two or more angles each, as many of one as of the "
                f"other; got shapes {x.shape} and {y.shape}",
                "inputs",
            )
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ModelError("inputs and outputs must be finite numbers", "inputs")
        steps = np.diff(x)
        if not (np.all(steps > 0) or np.all(steps < 0)) or abs(x[-1] - x[0]) >= 2 * np.pi:
            raise ModelError("inputs must increase (or decrease) within one turn", "inputs")
        lo, hi = (float(b) for b in self.bounds)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise ModelError(f"bounds must be 0 < low < high, got {self.bounds!r}", "bounds")
        if not 0.0 <= self.min_transmission < np.pi / 2:
            raise ModelError("min_transmission must lie in [0, pi/2) rad", "min_transmission")
        if self.linkage.OUTPUT == "length" and not np.ptp(y) > 0:
            raise ModelError(
                f"a {self.linkage.TITLE}'s outputs are positions [length]: give two or more "
                "different ones (their span sets the linkage's size)",
                "outputs",
            )
        check_grashof(self.linkage, self.grashof)
        object.__setattr__(self, "inputs", x)
        object.__setattr__(self, "outputs", y)
        object.__setattr__(self, "bounds", (lo, hi))

    @property
    def scale(self) -> float:
        """The unit of the linkage's lengths in the search: 1 (the ground link) where the
        output is an angle, the outputs' span ``max - min`` [length] where it is a length."""
        return float(np.ptp(self.outputs)) if self.linkage.OUTPUT == "length" else 1.0

    @classmethod
    def from_function(
        cls,
        f: Callable,
        x_range: tuple[float, float],
        input_span: float,
        output_span: float,
        *,
        points: int = 3,
        input_start: float = 0.0,
        output_start: float = 0.0,
        spacing: str = "chebyshev",
        **options,
    ) -> FunctionTask:
        """The task of generating ``y = f(x)`` over ``x_range``: ``x`` mapped linearly onto
        the crank's angles ``input_start + input_span (x - x0) / (x1 - x0)`` [rad] and ``y``
        onto the outputs ``output_start + output_span (y - f(x0)) / (f(x1) - f(x0))``, at
        ``points`` precision points (``"chebyshev"`` or ``"even"`` spacing, ends excluded
        for Chebyshev's). ``output_start`` and ``output_span`` are angles [rad], or lengths
        [length] for a slider-crank (``linkage="slider_crank"``: the slider's positions).
        ``options``: the other attributes (``free_start``, ``linkage``...)."""
        x0, x1 = (float(v) for v in x_range)
        if not (np.isfinite(x0) and np.isfinite(x1) and x1 > x0):
            raise ModelError(f"x_range must be (low, high), low < high, got {x_range!r}", "x")
        if int(points) < 2:
            raise ModelError("points must be at least 2", "points")
        if spacing == "chebyshev":
            x = chebyshev(x0, x1, int(points))
        elif spacing == "even":
            x = np.linspace(x0, x1, int(points))
        else:
            raise ModelError(f"spacing must be 'chebyshev' or 'even', got {spacing!r}", "spacing")
        y0, y1 = float(f(x0)), float(f(x1))
        if not (np.isfinite(y0) and np.isfinite(y1) and y1 != y0):
            raise ModelError("f must take different finite values at the range's ends", "f")
        y = np.asarray(f(x), dtype=float)
        inputs = input_start + input_span * (x - x0) / (x1 - x0)
        outputs = output_start + output_span * (y - y0) / (y1 - y0)
        return cls(inputs, outputs, **options)


__all__ = [
    "FUNCTION_LINKAGES",
    "LINKAGES",
    "RATIO_BOUNDS",
    "FunctionTask",
    "Objective",
    "PathTask",
    "chebyshev",
    "function_linkage",
]
