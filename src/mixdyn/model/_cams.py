"""A cam and its follower: translating (knife-edge, roller or flat-faced) or oscillating.

The cam (body ``cam``) turns about its centre ``center``; the follower's point ``point`` (its
knife edge, or its roller's centre) moves along the follower's axis ``axis`` (fixed in
``frame``, default the ground; the follower's guide, a translational joint, is a joint of its
own). The cam is designed by its displacement diagram: the follower's displacement
``s(theta)`` [length] as a law of the cam angle ``theta = phi_cam - phi_frame`` [rad], read
within the turn (``theta mod 2 pi``: give it over one turn; any law: harmonic, cycloidal by
an expression, polynomial, spline through samples), so

    (P_follower - C_cam) . u - (base + s(theta)) = 0        (1 equation)

with ``u`` the axis and ``base`` the distance at ``s = 0`` (the prime circle's radius:
the base circle's plus the roller's). The knife-edge, roller and flat-faced followers share
this motion; the cam profile that produces it differs (drawn by the animation: the pitch
curve minus the roller, or the envelope of the flat face; an oscillating follower's flat face
is the line through its point whose normal is ``axis`` at the start, turning with it).

The multiplier gives the force along the axis with which the cam pushes the follower,
``{name}.F`` [force] (the contact's component along the axis; > 0 while in contact): the cam
can only push, so a run where ``F`` turns negative has lost contact and fails with
:class:`mixdyn.errors.ContactLostError` at that time. The pressure angle
``{name}.alpha`` [rad] (knife-edge and roller: ``atan((s' - e) / x)`` with ``x`` the
follower point's distance along the axis and ``e`` its offset; flat-faced: 0) gives the
normal contact force ``{name}.Fn = F / cos(alpha)``.

An oscillating follower (``motion="oscillating"``) turns about ``pivot`` (a point of
``frame``) by the law, an angle [rad]: ``phi_follower - phi_frame = psi0 + sense * s(theta)``
(``psi0`` from the rough start; ``sense`` +1 if the follower's angle grows as the cam lifts
it, -1 if it falls). Its column ``{name}.M`` is the cam's moment on the follower in the
lifting sense [torque], > 0 while in contact (a run where it would pull fails the same way).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from . import _smoothness as smoothness
from ._declare import Variable, direction, element, option, quantity, reference
from ._element import Resolver, moving
from ._geometry import GROUND, angle, cross, point, vector
from ._joints import _UNBOUND, Joint, _f64
from ._laws import Law, as_law

FOLLOWERS = ("knife", "roller", "flat")
MOTIONS = ("translating", "oscillating")


#: The variable of a cam's law: the cam angle, ``theta`` in a file's expressions.
CAM_ANGLE = Variable("theta", "angle")


def _optional_f64(x):
    return None if x is None else _f64(x)


@element("cam_follower", "joints")
class CamFollower(Joint):
    """A cam (``cam``, turning about ``center``) driving a follower (``follower``, its point
    ``point``) by a displacement law of the cam angle ``theta`` [rad]: a translating follower
    along ``axis``, ``(P - C) . axis = base + law(theta)``, or one oscillating about
    ``pivot``. The follower's guide is a joint of its own. Columns ``name.F`` (the force
    along the axis, > 0 in contact; a run where it would pull fails, naming the time the
    follower leaves the cam), ``name.alpha`` (pressure angle), ``name.Fn`` (normal contact
    force); an oscillating follower's ``name.M`` (the cam's moment on it).

    Args:
        name: unique name.
        cam: the cam's body.
        follower: the follower's body.
        law: ``s(theta)`` [length], a law of the cam angle [rad].
        base: distance from the cam's centre to the follower's point at ``s = 0`` [length]
            (a translating follower needs it).
        axis: the follower's direction of motion (away from the cam), in ``frame``'s frame.
        follower_type: ``"knife"``, ``"roller"`` (give ``roller``) or ``"flat"``.
        roller: the roller's radius [length] (0 for knife-edge and flat-faced followers).
        frame: the body of the follower's guide (default the ground).
        center: the cam's centre, ``cam.point`` (default the cam's origin).
        point: the follower's point, ``follower.point`` (default its origin).
        motion: ``"translating"`` (default) or ``"oscillating"`` (give ``pivot``; the law is
            then an angle [rad]).
        pivot: an oscillating follower's pivot, a point of ``frame``.
        sense: +1 if an oscillating follower's angle grows as it lifts, -1 if it falls.
        continuity: ``"C2"`` (default: the law continuous with its slope and second
            derivative over the turn, as the follower's reported accelerations and forces
            need) or ``"C1"`` (its second derivative may jump: a constant-acceleration
            profile, whose accelerations and forces then jump, finite).
    """

    cam: str = reference("The cam's body.", what="body")
    follower: str = reference("The follower's body.", what="body")
    motion: str = option(
        "``translating`` (default: along ``axis``) or ``oscillating`` (about ``pivot``).",
        "translating",
        choices=MOTIONS,
        kw_only=True,
    )
    law: Law = quantity(
        ("length", "angle"),
        "Displacement (an oscillating follower: its angle) as a law of the cam angle "
        "``theta`` [rad], given over one turn: an expression of ``theta`` "
        "(``h/2*(1 - cos(theta))``), a polynomial or spline in ``theta``; smooth over the "
        "turn and across ``theta = 2 pi`` (``continuity``).",
        converter=as_law,
        law=True,
        variable=CAM_ANGLE,
        kw_only=True,
    )
    base: object = quantity(
        "length",
        "Distance from the cam's centre to the follower's point at zero displacement (the "
        "prime circle: base circle plus roller); a translating follower needs it.",
        None,
        converter=_optional_f64,
        above=0.0,
        kw_only=True,
    )
    follower_type: str = option(
        "``knife`` (default), ``roller`` (give ``roller``) or ``flat`` (flat-faced).",
        "knife",
        choices=FOLLOWERS,
        kw_only=True,
    )
    roller: object = quantity(
        "length",
        "The roller's radius (a roller follower: > 0, and less than ``base`` when it translates).",
        0.0,
        converter=_f64,
        at_least=0.0,
        kw_only=True,
    )
    frame: str = reference(
        "The body of the follower's guide. Default the ground.",
        what="body",
        default="ground",
        kw_only=True,
    )
    axis: str | tuple[float, ...] = direction(
        "Direction of the follower's motion away from the cam, in ``frame``'s frame.",
        (0.0, 1.0),
        on="frame",
        kw_only=True,
    )
    center: str | None = reference(
        "The cam's centre, ``cam.point`` (default its origin).", default=None, kw_only=True
    )
    point: str | None = reference(
        "The follower's point (knife edge or roller centre), ``follower.point`` (default "
        "its origin).",
        default=None,
        kw_only=True,
    )
    pivot: str | None = reference(
        "An oscillating follower's pivot, a point of ``frame``.", default=None, kw_only=True
    )
    sense: float = option(
        "+1 if an oscillating follower's angle grows as the cam lifts it, -1 if it falls.",
        1,
        choices=(1, -1),
        converter=float,
        kw_only=True,
    )
    continuity: str = option(
        smoothness.CONTINUITY_DOC, "C2", choices=tuple(smoothness.CONTINUITY), kw_only=True
    )
    a0: object = eqx.field(default=(0.0, 0.0), converter=_f64, kw_only=True)  # (theta, psi)
    draw0: tuple = eqx.field(static=True, default=(), kw_only=True)  # for profile()
    sp: object = eqx.field(default=None, kw_only=True)
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bc: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: object = eqx.field(default=None, kw_only=True)
    sj: object = eqx.field(default=None, kw_only=True)
    u: object = eqx.field(default=None, kw_only=True)
    body_fields: ClassVar[tuple[str, ...]] = ("bi", "bj", "bc")
    generic_reaction: ClassVar[bool] = False
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("cam",)

    @classmethod
    def field_kind(cls, field: str, values, element_class) -> str:
        """The law's kind: an angle for an oscillating follower, else a length."""
        return "angle" if values.get("motion") == "oscillating" else "length"

    def __post_init__(self):
        if self.base is None and self.motion != "oscillating":
            warnings.warn(
                f"{self.name}: a translating follower needs its base distance: give base "
                "(its default, 1 length unit, is deprecated)",
                DeprecationWarning,
                stacklevel=3,
            )
            self.base = _f64(1.0)

    @property
    def contact_kinds(self) -> dict[str, str]:
        if self.motion == "oscillating":
            return {"M": "torque"}
        return {"F": "force", "alpha": "angle", "Fn": "force"}

    @property
    def unilateral(self) -> str:
        """The contact column that must stay positive (the cam only pushes)."""
        return "M" if self.motion == "oscillating" else "F"

    def __check_init__(self):
        smoothness.check_continuity(self.continuity, self.name)
        if self.follower_type not in FOLLOWERS:
            raise ModelError(
                f"follower_type must be one of {', '.join(FOLLOWERS)}, got {self.follower_type!r}",
                self.name,
                field="follower_type",
            )
        if self.motion not in MOTIONS:
            raise ModelError(
                f"motion must be one of {', '.join(MOTIONS)}, got {self.motion!r}",
                self.name,
                field="motion",
            )
        if self.follower_type == "roller" and not float(self.roller) > 0:
            raise ModelError(
                "a roller follower needs its roller's radius > 0", self.name, field="roller"
            )
        if self.motion == "oscillating":
            if self.pivot is None:
                raise ModelError(
                    "an oscillating follower needs its pivot (a point of the frame): give pivot",
                    self.name,
                )
            if self.sense not in (1.0, -1.0):
                raise ModelError("sense must be +1 or -1", self.name, field="sense")
        elif float(self.roller) >= float(self.base):
            raise ModelError(
                f"the roller's radius {float(self.roller):g} must be smaller than the base "
                f"distance {float(self.base):g} (the prime circle: base circle plus roller)",
                self.name,
                field="roller",
            )

    def bind(self, r: Resolver):
        for field in ("cam", "follower"):
            if r.body(getattr(self, field), self.name) == GROUND:
                raise ModelError(f"the {field} cannot be the ground", self.name, field=field)
        bi, si = r.point(self.center or self.cam, self.name)
        bj, sj = r.point(self.point or self.follower, self.name)
        bc = r.body(self.frame, self.name)
        if len({bi, bj, bc}) < 3:
            raise ModelError(
                "the cam, the follower and the frame must be three bodies "
                "(the frame may be the ground)",
                self.name,
            )
        u = r.vector(self.axis, bc, self.name)
        extra = {}
        if self.motion == "oscillating":
            from ._contacts import _start

            b, sp = r.point(self.pivot, self.name)
            if b != bc:
                raise ModelError(
                    f"the pivot {self.pivot!r} must be a point of the frame {self.frame!r}",
                    self.name,
                )
            _, phi_c = _start(r, bc, np.zeros(2))
            _, phi_i = _start(r, bi, np.zeros(2))
            _, phi_j = _start(r, bj, np.zeros(2))
            s0 = float(self.law(jnp.asarray(phi_i - phi_c)))
            center, _ = _start(r, bi, si)
            pivot, _ = _start(r, bc, sp)
            pt, _ = _start(r, bj, sj)
            draw0 = (*(pivot - center), *(pt - pivot), phi_i - phi_c, s0)
            extra = {
                "sp": sp,
                "a0": _f64((phi_i - phi_c, phi_j - phi_c)),
                "draw0": tuple(float(v) for v in draw0),
            }
        smoothness.check(
            self.law,
            0.0,
            2 * math.pi,
            element=self.name,
            moved="the follower",
            variable="theta",
            periodic=True,
            order=smoothness.CONTINUITY[self.continuity],
        )
        return dataclasses.replace(self, bi=bi, bj=bj, bc=bc, si=si, sj=sj, u=u, **extra)

    def body_indices(self):
        return moving(self.bi, self.bj, self.bc)

    def reaction_point(self):
        return self.bj, self.sj

    @property
    def psi0(self):
        """An oscillating follower's angle relative to the frame at the law's zero [rad]:
        its angle at the rough start less ``sense`` times the law there."""
        return self.a0[1] - self.sense * self.law(self.a0[0])

    def theta(self, q):
        """The cam angle relative to the frame [rad]."""
        return angle(q, self.bi) - angle(q, self.bc)

    def turn(self, q):
        """The cam angle within its turn, ``theta mod 2 pi`` [rad]: a cam's law is read once
        per turn, so a law given over one turn (a spline, a ``where``) serves every turn."""
        return jnp.mod(self.theta(q), 2 * jnp.pi)

    def _geometry(self, q):
        u = vector(q, self.bc, self.u)
        d = point(q, self.bj, self.sj) - point(q, self.bi, self.si)
        return jnp.dot(d, u), cross(u, d)  # along the axis, offset (to the axis' left)

    def residual(self, q):
        if self.motion == "oscillating":
            psi = angle(q, self.bj) - angle(q, self.bc)
            return (psi - self.psi0 - self.sense * self.law(self.turn(q)))[None]
        x, _ = self._geometry(q)
        return (x - self.base - self.law(self.turn(q)))[None]

    def contact(self, q, lam):
        if self.motion == "oscillating":
            return {"M": -self.sense * lam[0]}
        F = -lam[0]
        if self.follower_type == "flat":
            alpha = jnp.zeros_like(F)
        else:
            x, e = self._geometry(q)
            ds = jax.jvp(self.law, (self.turn(q),), (jnp.ones_like(F),))[1]
            alpha = jnp.arctan2(ds - e, x)
        return {"F": F, "alpha": alpha, "Fn": F / jnp.cos(alpha)}

    def arrow(self, q, cols):
        """The cam's push on a translating follower, along its axis at the follower's point
        (an oscillating follower's moment has no arrow: None)."""
        if self.motion == "oscillating":
            return None

        def geo(qq):
            return point(qq, self.bj, self.sj), vector(qq, self.bc, self.u)

        P, u = (np.asarray(a) for a in jax.vmap(geo)(jnp.asarray(q)))
        return P, np.asarray(cols[f"{self.name}.F"])[:, None] * u

    def profile(self, n: int = 180) -> np.ndarray:
        """The cam's profile in its own frame, (n, 2) [length], at the frame angle 0 of the
        rough start: the pitch curve moved in by the roller (knife-edge: the pitch curve),
        or the envelope of the flat face's lines."""
        th = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
        s = np.asarray(jax.vmap(self.law)(jnp.asarray(th)))
        c, sn = np.cos(th), np.sin(th)

        def to_cam(v):  # global vectors (n, 2) seen from the cam turned by theta: A(-theta) v
            return np.stack([c * v[:, 0] + sn * v[:, 1], -sn * v[:, 0] + c * v[:, 1]], axis=1)

        if self.motion == "oscillating":
            px, py, ax, ay, _, s0 = self.draw0
            dpsi = self.sense * (s - s0)
            arm = np.stack(
                [np.cos(dpsi) * ax - np.sin(dpsi) * ay, np.sin(dpsi) * ax + np.cos(dpsi) * ay],
                axis=1,
            )
            pitch = to_cam(np.array([px, py]) + arm)
            if self.follower_type == "flat":  # the face's normal turns with the follower
                u0 = np.asarray(self.u, dtype=float)
                n_glob = np.stack(
                    [
                        np.cos(dpsi) * u0[0] - np.sin(dpsi) * u0[1],
                        np.sin(dpsi) * u0[0] + np.cos(dpsi) * u0[1],
                    ],
                    axis=1,
                )
                return _envelope(to_cam(n_glob), pitch, th)
        else:
            u = np.broadcast_to(np.asarray(self.u, dtype=float), (n, 2))
            dirs = to_cam(u)
            pitch = (float(self.base) + s)[:, None] * dirs
        if self.follower_type == "flat":  # envelope of the faces: (b + s) w + s' w_perp
            ds = np.gradient(s, th, edge_order=2)
            perp = np.stack([-dirs[:, 1], dirs[:, 0]], axis=1)
            return pitch - ds[:, None] * perp
        if self.follower_type == "roller":
            dp = np.gradient(pitch, th, axis=0, edge_order=2)
            normal = np.stack([dp[:, 1], -dp[:, 0]], axis=1)
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
            outward = np.sign(np.sum(normal * pitch, axis=1, keepdims=True))
            return pitch - float(self.roller) * outward * normal
        return pitch

    def drawing(self):
        out = {"shapes": [(self.bi, np.asarray(self.si) + self.profile())]}
        if self.follower_type == "roller":
            out["circles"] = [(self.bj, self.sj, self.roller)]
        out["pins"] = [(self.bj, self.sj)]
        return out


def _envelope(n, pitch, th) -> np.ndarray:
    """The envelope (k, 2) of the lines ``n_k . x = n_k . pitch_k`` over the cam angles
    ``th`` (k,): per angle the point on the line where it touches the next (``[n; n'] x =
    [h; h']``, derivatives by second-order differences)."""
    h = np.sum(n * pitch, axis=1)
    dn = np.gradient(n, th, axis=0, edge_order=2)
    dh = np.gradient(h, th, edge_order=2)
    A = np.stack([n, dn], axis=1)  # (k, 2, 2): rows n and n'
    return np.linalg.solve(A, np.stack([h, dh], axis=1)[..., None])[..., 0]
