"""Motion generation: a linkage's coupler carried through precision poses, in their order.

A pose is where the carried body is and how it is turned: its reference point ``P_i = (x_i,
y_i)`` [length] (the coupler point) and the angle ``alpha_i`` [rad] of a line fixed in it. The
body is the coupler (a four-bar's, a slider-crank's connecting rod with ``linkage=
"slider_crank"``, or a six-bar's tracer ``D E``, :mod:`._sixbar`), and that line makes an
unknown but constant angle ``gamma`` (the coupler angle of a result,
:attr:`~._search.Candidate.coupler_angle`) with the coupler's own line from its crank pin ``A``
towards its other pin ``B`` (a tracer's from ``D`` towards ``E``): at the crank's angle
``theta_i`` the body's angle is ``phi_i = phi3(theta_i) + gamma``. The crank's angle at each
pose is an unknown (one per pose), as in a timing-free path task; ``gamma`` is not a variable
of the search but the least-squares offset of the poses' unit vectors (variable projection,
:func:`offset`), ``gamma = arg sum_i e^{i (alpha_i - phi3_i)}``, so that only the differences
of the asked angles count.

The error of a candidate (:meth:`MotionTask.error`) is

    ``sum_i |C(theta_i) - P_i|^2 + L^2 sum_i wrap(phi_i - alpha_i)^2``   [length**2]

with ``wrap`` to ``(-pi, pi]`` and ``L`` the task's characteristic length
(:attr:`MotionTask.length`; default: the poses' size, the largest distance of their points
from their centre): an angle error of ``1/L`` rad weighs as much as a point missed by one
unit of length. The search's residuals use the chord ``L (e^{i phi_i} - e^{i alpha_i})``
instead of the wrapped difference (``|.| = 2 L sin(|error| / 2)``: smooth across the wrap,
the same to second order).

Defects (the choice made): the poses are reached on one assembly branch (fixed per start, as
for a path: no branch defect), in their order as the crank turns in the positive sense within
one turn (the increments of the crank's angle from pose to pose are >= 0 and sum to at most
2 pi: no order defect), and the loop closes along the whole traversed motion from the first
pose to the last with the least transmission angle (no circuit defect).

Three poses: Burmester's theory gives a two-parameter family of circle points on the body
(every point of it, each with its centre point, the circumcentre of its three positions), so
a four-bar through three poses is any pair of them; the search finds one (tested against
that construction).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._task import PathTask


@dataclasses.dataclass(frozen=True)
class MotionTask:
    """Motion generation: the coupler through ``N >= 3`` poses, in their order.

    Numbers are in one consistent unit system; the model and model file of a result read them
    as SI (m, kg, s), as for a :class:`PathTask`.

    Attributes:
        poses: (N, 3) ``[x, y, angle]`` per pose: the coupler point [length] and the angle of a
            line fixed in the coupler [rad], in the order the coupler reaches them as the crank
            turns in the positive sense; only the angles' differences count.
        bounds: ``name -> (low, high)`` of the four-bar's numbers, as for a :class:`PathTask`
            (default: lengths within ``[0.05, 5]`` times the poses' size, the pivots within
            three sizes of their centre).
        min_transmission: the least transmission angle along the traversed motion [rad].
        length: the characteristic length ``L`` [length] that weighs the angle error (None:
            the poses' size, the largest distance of their points from their centre).
        linkage: the linkage type, as for a :class:`PathTask` (``"four_bar"``, the default,
            ``"slider_crank"``, or a six-bar of :data:`~._task.LINKAGES`, whose carried body
            is the tracer ``D E``); held as the class.
        grashof: the Grashof type asked for, as for a :class:`PathTask` (default ``"any"``).
        pivots: the ground pivots' regions, as for a :class:`PathTask` (default none).
        path: the :class:`PathTask` of the poses' points (timing free), made and checked from
            the above: the bounds, the box and the size are its.
    """

    poses: np.ndarray
    bounds: dict = dataclasses.field(default_factory=dict)
    min_transmission: float = 0.0
    length: float | None = None
    linkage: str | type = "four_bar"
    grashof: str = "any"
    pivots: dict = dataclasses.field(default_factory=dict)
    path: PathTask = dataclasses.field(init=False, repr=False, compare=False)

    def __post_init__(self):
        poses = np.asarray(self.poses, dtype=float)
        if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) < 3:
            raise ModelError(
                f"poses must be three or more [x, y, angle] triples, got shape {poses.shape}",
                "poses",
            )
        if not np.all(np.isfinite(poses)):
            raise ModelError("poses must be finite numbers", "poses")
        object.__setattr__(self, "poses", poses)
        path = PathTask(
            poses[:, :2],
            bounds=self.bounds,
            min_transmission=self.min_transmission,
            linkage=self.linkage,
            grashof=self.grashof,
            pivots=self.pivots,
        )
        object.__setattr__(self, "path", path)
        object.__setattr__(self, "linkage", path.linkage)
        object.__setattr__(self, "pivots", path.pivots)
        if self.length is not None:
            if not (np.isfinite(self.length) and self.length > 0):
                raise ModelError(f"length must be > 0, got {self.length!r}", "length")
            object.__setattr__(self, "length", float(self.length))
        spread = np.max(np.linalg.norm(poses[:, :2] - poses[:, :2].mean(axis=0), axis=1))
        if not spread > 1e-9 * max(1.0, np.max(np.abs(poses[:, :2]))):
            raise ModelError(
                "the poses' points coincide: the coupler would only turn about that point, "
                "which no four-bar or slider-crank does (every centre point is that point); "
                "give poses at distinct points",
                "poses",
            )

    @property
    def points(self) -> np.ndarray:
        """(N, 2) the poses' points [length]."""
        return self.poses[:, :2]

    @property
    def angles(self) -> np.ndarray:
        """(N,) the poses' angles [rad]."""
        return self.poses[:, 2]

    @property
    def timing(self) -> None:
        """None: the crank's angles at the poses are unknowns (no prescribed timing)."""
        return None

    @property
    def weight_length(self) -> float:
        """``L`` [length]: :attr:`length`, or the poses' size."""
        return self.length if self.length is not None else self.path.size

    @property
    def size(self) -> float:
        """The search's scale [length]: the poses' size (:attr:`PathTask.size`)."""
        return self.path.size

    def box(self) -> np.ndarray:
        """(len(NAMES), 2) the bounds of every number (:meth:`PathTask.box` of the poses'
        points)."""
        return self.path.box()

    def error(self, linkage, angles) -> float:
        """The error of ``linkage`` (a :class:`~._fourbar.FourBar` or the task's other linkage
        type, unbatched) with the crank at ``angles`` (N,) [rad] at the poses [length**2] (the
        module's formula, ``gamma`` the least-squares offset)."""
        gaps, turns = _pose_gaps(linkage, jnp.asarray(angles, dtype=float), self.poses)
        return float(jnp.sum(gaps**2) + self.weight_length**2 * jnp.sum(turns**2))


def _safe_angle(x, y):
    """``atan2(y, x)`` with finite derivatives where ``x = y = 0`` (0 there)."""
    tiny = (x * x + y * y) < 1e-300
    return jnp.arctan2(jnp.where(tiny, 0.0, y), jnp.where(tiny, 1.0, x))


def offset(phi3, alpha):
    """``gamma`` [rad]: the angle of the body's line in the coupler's frame that best turns
    the coupler's angles ``phi3`` (N,) onto the asked ``alpha`` (N,) (least squares of the
    unit vectors: ``arg sum_i e^{i (alpha_i - phi3_i)}``)."""
    d = alpha - phi3
    return _safe_angle(jnp.sum(jnp.cos(d)), jnp.sum(jnp.sin(d)))


def body_angles(lk, theta) -> jax.Array:
    """(N,) the coupler's angles ``phi3`` [rad] of a linkage at the crank's angles ``theta``
    (N,) [rad]."""
    return jax.vmap(lk.coupler_angle)(theta)


def turn_gaps(lk, theta, alpha) -> jax.Array:
    """(N,) ``wrap(phi_i - alpha_i)`` [rad] of a linkage at the crank's angles ``theta`` (N,)
    [rad] against the asked angles ``alpha`` (N,) [rad], ``phi_i`` with the least-squares
    offset (:func:`offset`)."""
    phi3 = body_angles(lk, theta)
    phi = phi3 + offset(phi3, alpha)
    return jnp.angle(jnp.exp(1j * (phi - alpha)))


def pose_gaps(lk, theta, poses) -> tuple[jax.Array, jax.Array]:
    """``(C(theta_i) - P_i (N, 2) [length], wrap(phi_i - alpha_i) (N,) [rad])`` of a linkage
    at the crank's angles ``theta`` (N,) [rad] against ``poses`` (N, 3)."""
    poses = jnp.asarray(poses)
    c = jax.vmap(lk.coupler_point)(theta)
    return c - poses[:, :2], turn_gaps(lk, theta, poses[:, 2])


#: :func:`pose_gaps` compiled (once per linkage type and number of poses).
_pose_gaps = jax.jit(pose_gaps)


def angle_residuals(lk, theta, alpha) -> jax.Array:
    """(2N,) the chords ``e^{i phi_i} - e^{i alpha_i}`` (cosines, then sines) of a linkage at
    the crank's angles ``theta`` (N,) [rad] against the asked ``alpha`` (N,) [rad]
    (dimensionless: the search weighs them by ``L`` over its scale)."""
    phi3 = body_angles(lk, theta)
    phi = phi3 + offset(phi3, alpha)
    return jnp.concatenate([jnp.cos(phi) - jnp.cos(alpha), jnp.sin(phi) - jnp.sin(alpha)])


__all__ = ["MotionTask", "angle_residuals", "body_angles", "offset", "pose_gaps", "turn_gaps"]
