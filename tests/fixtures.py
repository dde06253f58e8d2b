"""Small mechanism models shared by the tests: import with ``from fixtures import ...``.

Every builder returns a fresh :class:`mixdyn.Model`. Body frames sit at the centres of mass
(the middle of each link), so each link's ``phi`` is the angle of the line through its two
pins. In the SI models every body has a placeholder mass of 1 kg and inertia 0.01 kg m^2.
Builders that take lengths keep the *structure* of the model (names, joint and driver
types) independent of the numbers, so models built with different lengths share compiled
code. The starting poses ``q0`` are only guesses; the analyses assemble them.

Models:

* :func:`slider_crank` — crank ``O``-``A`` pinned to the ground origin, rod ``A``-``B``,
  slider on the ground x axis; one degree of freedom, driven by the crank angle.
* :func:`four_bar` — crank, coupler, rocker on ground pivots ``(0, 0)`` and ``(d, 0)``; one
  degree of freedom, driven by the crank angle.
* :func:`paper_mechanism` — the worked example of Antonya's paper (``shared/paper``,
  section 3): two degrees of freedom, in mm, kg, s, without drivers or loads.
* :func:`parallelogram_with_extra_link` — a parallelogram four-bar with a third parallel
  link: one degree of freedom and one redundant joint equation.
"""

from __future__ import annotations

import math

import mixdyn as md

__all__ = [
    "PAPER_COM",
    "PAPER_INERTIA",
    "PAPER_MASS",
    "four_bar",
    "four_bar_pose",
    "paper_mechanism",
    "parallelogram_with_extra_link",
    "slider_crank",
]


def slider_crank(
    r: float = 0.1,
    l: float = 0.3,
    omega: float = 2.0,
    *,
    theta0: float = 0.0,
    drivers=None,
    name: str = "slider-crank",
) -> md.Model:
    """An in-line slider–crank, SI units.

    Bodies ``crank`` (points ``O``, ``A``), ``rod`` (``A``, ``B``) and ``slider`` (its origin).
    Joints: ``O`` (ground origin – ``crank.O``), ``A``, ``B`` (``rod.B`` – slider origin) and
    ``slide`` (translational along the ground x axis). Driver ``motor``: crank angle
    ``theta0 + omega t`` [rad]. The slider's x coordinate is
    ``x = r cos th + sqrt(l**2 - r**2 sin(th)**2)``.

    Args:
        r: crank length [m].
        l: rod length [m], ``l > r``.
        omega: crank speed [rad/s].
        theta0: crank angle at t = 0 [rad]; the starting guess is placed there.
        drivers: drivers instead of the crank motor (``()`` for none).
        name: the model's name.
    """
    c, s = math.cos(theta0), math.sin(theta0)
    beta = -math.asin(r * s / l)  # rod angle
    ax, ay = r * c, r * s
    bx = ax + l * math.cos(beta)
    if drivers is None:
        drivers = [md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(theta0, omega))]
    return md.Model(
        bodies=[
            md.Body(
                "crank",
                1.0,
                0.01,
                q0=(ax / 2, ay / 2, theta0),
                points={"O": (-r / 2, 0), "A": (r / 2, 0)},
            ),
            md.Body(
                "rod",
                1.0,
                0.01,
                q0=((ax + bx) / 2, ay / 2, beta),
                points={"A": (-l / 2, 0), "B": (l / 2, 0)},
            ),
            md.Body("slider", 1.0, 0.01, q0=(bx, 0.0, 0.0)),
        ],
        joints=[
            md.Revolute("O", "ground", "crank.O"),
            md.Revolute("A", "crank.A", "rod.A"),
            md.Revolute("B", "rod.B", "slider"),
            md.Translational("slide", "ground", "slider", axis=(1, 0)),
        ],
        drivers=drivers,
        units=md.SI,
        name=name,
    )


def four_bar_pose(a, b, c, d, theta2):
    """Pin positions ``(A, B)`` of the four-bar at crank angle ``theta2`` (open circuit, ``B``
    left of the line from ``A`` to ``O4`` looking from ``A``), by intersecting two circles."""
    A = (a * math.cos(theta2), a * math.sin(theta2))
    ex, ey = d - A[0], -A[1]  # A -> O4
    e = math.hypot(ex, ey)
    along = (b**2 - c**2 + e**2) / (2 * e)  # from A towards O4
    h = math.sqrt(max(b**2 - along**2, 0.0))
    ux, uy = ex / e, ey / e
    B = (A[0] + along * ux - h * uy, A[1] + along * uy + h * ux)
    return A, B


def four_bar(
    a: float = 0.2,
    b: float = 0.55,
    c: float = 0.4,
    d: float = 0.6,
    omega: float = 1.0,
    *,
    theta0: float = 0.0,
    name: str = "four-bar",
) -> md.Model:
    """A four-bar linkage, SI units (default: a Grashof crank–rocker).

    Ground pivots ``O2 = (0, 0)`` (point ``ground.O2``) and ``O4 = (d, 0)`` (``ground.O4``).
    Bodies ``crank`` (``O``, ``A``; length ``a``), ``coupler`` (``A``, ``B``, and a coupler
    point ``P`` at ``(0, b/3)`` off the line of its pins; length ``b``) and ``rocker`` (``O``
    at ``O4``, ``B``; length ``c``). The rocker's angle is the angle of ``O4 -> B``. Joints
    ``O2``, ``A``, ``B``, ``O4`` (revolute); driver ``motor``: crank angle ``theta0 + omega t``.
    The starting guess is the open circuit (see :func:`four_bar_pose`).
    """
    (ax, ay), (bx, by) = four_bar_pose(a, b, c, d, theta0)
    th3 = math.atan2(by - ay, bx - ax)
    th4 = math.atan2(by, bx - d)
    return md.Model(
        bodies=[
            md.Body(
                "crank",
                1.0,
                0.01,
                q0=(ax / 2, ay / 2, theta0),
                points={"O": (-a / 2, 0), "A": (a / 2, 0)},
            ),
            md.Body(
                "coupler",
                1.0,
                0.01,
                q0=((ax + bx) / 2, (ay + by) / 2, th3),
                points={"A": (-b / 2, 0), "B": (b / 2, 0), "P": (0, b / 3)},
            ),
            md.Body(
                "rocker",
                1.0,
                0.01,
                q0=((d + bx) / 2, by / 2, th4),
                points={"O": (-c / 2, 0), "B": (c / 2, 0)},
            ),
        ],
        joints=[
            md.Revolute("O2", "ground.O2", "crank.O"),
            md.Revolute("A", "crank.A", "coupler.A"),
            md.Revolute("B", "coupler.B", "rocker.B"),
            md.Revolute("O4", "ground.O4", "rocker.O"),
        ],
        drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(theta0, omega))],
        ground={"O2": (0.0, 0.0), "O4": (d, 0.0)},
        units=md.SI,
        name=name,
    )


#: Masses [kg] and inertias about the centre of mass [kg mm^2] of the paper's bodies 2-5.
PAPER_MASS = {"crank": 0.0221, "coupler": 0.0221, "link": 0.0221, "slider": 0.00786}
PAPER_INERTIA = {"crank": 20.2313, "coupler": 20.2313, "link": 20.2313, "slider": 50.63}
#: Printed (rounded) start coordinates [mm] of the centres of mass, all angles 0.
PAPER_COM = {
    "crank": (0.0, 25.0),
    "coupler": (25.0, 50.0),
    "link": (62.5, 28.3494),
    "slider": (80.0, 6.6987),
}


def paper_mechanism(*, exact: bool = False, drivers=(), forces=()) -> md.Model:
    """The worked example of the paper (section 3 of ``shared/paper/README.md``), mm/kg/s.

    Bodies (the paper's numbers in brackets): ``crank`` [2], ``coupler`` [3], ``link`` [4],
    ``slider`` [5], with the table's masses and inertias; their starting guesses are the
    printed, rounded centres of mass with all angles 0 (:data:`PAPER_COM`). Ground points
    ``A``, ``E``, ``F``. Revolute joints ``A`` (ground–crank), ``B`` (crank–coupler), ``C``
    (coupler–link), ``D`` (link–slider); translational joint ``EF``: the slider's point ``E``
    on the ground line through ``E`` with direction (1, 0). Two degrees of freedom. No
    drivers or loads unless given.

    Args:
        exact: use ``25 sin 60°`` for the printed ``21.6506`` and ``50 - 50 sin 60°`` for the
            printed ``6.6987`` in the point table; by default the printed values are used.
        drivers: drivers of the model.
        forces: force elements of the model.
    """
    h = 25.0 * math.sin(math.pi / 3) if exact else 21.6506
    y_line = 50.0 - 50.0 * math.sin(math.pi / 3) if exact else 6.6987
    bodies = [
        md.Body(
            name,
            PAPER_MASS[name],
            PAPER_INERTIA[name],
            q0=(*PAPER_COM[name], 0.0),
            points=points,
        )
        for name, points in (
            ("crank", {"A": (0.0, -25.0), "B": (0.0, 25.0)}),
            ("coupler", {"B": (-25.0, 0.0), "C": (25.0, 0.0)}),
            ("link", {"C": (-12.5, h), "D": (12.5, -h)}),
            ("slider", {"D": (-5.0, 0.0), "E": (-20.0, 0.0), "F": (20.0, 0.0)}),
        )
    ]
    return md.Model(
        bodies=bodies,
        joints=[
            md.Revolute("A", "ground.A", "crank.A"),
            md.Revolute("B", "crank.B", "coupler.B"),
            md.Revolute("C", "coupler.C", "link.C"),
            md.Revolute("D", "link.D", "slider.D"),
            md.Translational("EF", "ground.E", "slider.E", axis=(1, 0)),
        ],
        drivers=drivers,
        forces=forces,
        ground={"A": (0.0, 0.0), "E": (60.0, y_line), "F": (100.0, y_line)},
        units=md.UnitSystem("mm", "kg", "s"),
        name="antonya-example",
    )


def parallelogram_with_extra_link(
    a: float = 0.3,
    L: float = 0.5,
    e: float = 0.2,
    omega: float = 1.0,
    *,
    theta0: float = math.pi / 6,
    name: str = "parallelogram",
) -> md.Model:
    """A parallelogram four-bar with an extra link parallel to its cranks, SI units.

    Three links of length ``a`` — ``crank`` on ground pivot ``O1 = (0, 0)``, ``follower`` on
    ``O2 = (L, 0)``, ``extra`` on ``O3 = (e, 0)`` — are pinned to the ``coupler`` at points
    ``P1``, ``P2``, ``P3`` spaced like the ground pivots. Revolute joints ``O1``, ``O2``,
    ``O3``, ``P1``, ``P2``, ``P3``: 12 equations on 12 coordinates, of rank 11 (one is
    redundant), one degree of freedom. Driver ``motor``: crank angle ``theta0 + omega t``.
    The coupler translates on a circle of radius ``a``: its centre is at
    ``(L/2 + a cos th, a sin th)`` with ``phi = 0``. Avoid ``th = 0`` or ``pi``, where every
    link lies on the ground line and the mechanism can bifurcate.
    """
    c, s = math.cos(theta0), math.sin(theta0)
    link_points = {"O": (-a / 2, 0.0), "P": (a / 2, 0.0)}

    def link(name, x0):
        return md.Body(name, 1.0, 0.01, q0=(x0 + a / 2 * c, a / 2 * s, theta0), points=link_points)

    return md.Model(
        bodies=[
            link("crank", 0.0),
            link("follower", L),
            link("extra", e),
            md.Body(
                "coupler",
                1.0,
                0.01,
                q0=(L / 2 + a * c, a * s, 0.0),
                points={"P1": (-L / 2, 0.0), "P2": (L / 2, 0.0), "P3": (e - L / 2, 0.0)},
            ),
        ],
        joints=[
            md.Revolute("O1", "ground.O1", "crank.O"),
            md.Revolute("O2", "ground.O2", "follower.O"),
            md.Revolute("O3", "ground.O3", "extra.O"),
            md.Revolute("P1", "crank.P", "coupler.P1"),
            md.Revolute("P2", "follower.P", "coupler.P2"),
            md.Revolute("P3", "extra.P", "coupler.P3"),
        ],
        drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(theta0, omega))],
        ground={"O1": (0.0, 0.0), "O2": (L, 0.0), "O3": (e, 0.0)},
        units=md.SI,
        name=name,
    )
