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

Dynamics (masses and inertias as published, or as stated in each builder):

* :func:`pendulum` — a compound pendulum on a revolute joint to the ground.
* :func:`spring_slider` — a mass on a slider with a spring–damper to the ground.
* :func:`pendulum_chain` — ``n`` links hanging from the ground (benchmarks).
* :func:`horizontal_chain` — ``n`` short links pinned in a horizontal line (the sparse path's
  tests and scaling benchmarks).
* :func:`double_four_bar` — the IFToMM double four-bar (parallelograms, singular positions).
* :func:`andrews_mechanism` — Andrews' squeezing mechanism (seven bodies, spring, torque),
  with :func:`andrews_angles` / :func:`andrews_body_angles` converting to and from the
  test set's angles.

Tracing: :func:`traced_now` and :func:`new_traces` count the traces of mixdyn's compiled
functions (``mixdyn._compile.traces``) between two points of a test.
"""

from __future__ import annotations

import math

import mixdyn as md
from mixdyn import _compile

__all__ = [
    "ANDREWS",
    "ANDREWS_BODIES",
    "ANDREWS_Q0",
    "PAPER_COM",
    "PAPER_INERTIA",
    "PAPER_MASS",
    "andrews_angles",
    "andrews_body_angles",
    "andrews_mechanism",
    "double_four_bar",
    "four_bar",
    "four_bar_pose",
    "horizontal_chain",
    "new_traces",
    "paper_mechanism",
    "parallelogram_with_extra_link",
    "pendulum",
    "pendulum_chain",
    "slider_crank",
    "spring_slider",
    "traced_now",
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


def paper_under_loads() -> md.Model:
    """:func:`paper_mechanism` under the paper's loads (section 3 of
    ``shared/paper/README.md``): torques ``T2`` = 500 on the crank and ``T3`` = -500 on the
    coupler [kg mm^2/s^2], and ``F1`` = 10 sin(pi t / 2) [kg mm/s^2] on the slider along x."""
    return paper_mechanism(
        forces=[
            md.Torque("T2", "crank", law=500.0),
            md.Torque("T3", "coupler", law=-500.0),
            md.PointForce("F1", "slider", along=(1.0, 0.0), law=md.Harmonic(10.0, math.pi / 2)),
        ]
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


# ----------------------------------------------------------------------------- dynamics
def pendulum(
    length: float = 0.5,
    mass: float = 2.0,
    inertia: float = 0.01,
    theta0: float = 0.0,
    *,
    g: float = 9.81,
    name: str = "pendulum",
) -> md.Model:
    """A compound pendulum under gravity ``(0, -g)``, SI units, no drivers.

    Body ``bob`` (mass ``mass``, inertia ``inertia`` about its centre of mass) hangs from the
    ground origin (``ground.O``) by its point ``O`` at ``(0, length)`` in its frame; revolute
    joint ``pin`` (ground - bob, so its reaction is the force on the bob). The bob's ``phi`` is
    the angle of the pendulum from the downward vertical, counter-clockwise; the centre of mass
    is at ``length (sin phi, -cos phi)``. Equation of motion:
    ``phi'' = -(m g length / J_O) sin phi`` with ``J_O = inertia + mass length**2``, i.e. a
    simple pendulum of length ``J_O / (mass length)``. Starts at ``phi = theta0``.
    """
    s, c = math.sin(theta0), math.cos(theta0)
    return md.Model(
        bodies=[
            md.Body(
                "bob",
                mass,
                inertia,
                q0=(length * s, -length * c, theta0),
                points={"O": (0.0, length)},
            )
        ],
        joints=[md.Revolute("pin", "ground.O", "bob.O")],
        ground={"O": (0.0, 0.0)},
        gravity=(0.0, -g),
        units=md.SI,
        name=name,
    )


def spring_slider(
    mass: float = 2.0,
    stiffness: float = 800.0,
    damping: float = 4.0,
    free_length: float = 0.5,
    x0: float = 0.6,
    *,
    name: str = "spring-slider",
) -> md.Model:
    """A mass on a horizontal slider, tied to the ground by a spring–damper, SI units.

    Body ``slider`` (its centre of mass at ``(x0, 0)``) slides along the ground x axis
    (translational joint ``slide`` from ``ground.O``, no rotation); ``spring``: spring–damper
    between ``ground.O`` and the slider's centre, free length ``free_length``. Gravity acts
    along -y and is carried by the joint. While ``x > 0``:
    ``m x'' + c x' + k (x - free_length) = 0``.
    """
    return md.Model(
        bodies=[md.Body("slider", mass, 0.01, q0=(x0, 0.0, 0.0))],
        joints=[md.Translational("slide", "ground.O", "slider", axis=(1.0, 0.0))],
        forces=[
            md.SpringDamper(
                "spring",
                "ground.O",
                "slider",
                stiffness=stiffness,
                damping=damping,
                free_length=free_length,
            )
        ],
        ground={"O": (0.0, 0.0)},
        gravity=(0.0, -9.81),
        units=md.SI,
        name=name,
    )


def pendulum_chain(n: int, link: float = 1.0, mass: float = 1.0, theta0: float = 0.5):
    """A chain of ``n`` uniform links hanging from the ground origin, SI units, gravity -y.

    Link ``k`` (body ``link{k}``, points ``A`` upper, ``B`` lower, length ``link``, mass
    ``mass``, inertia ``mass link**2 / 12``) is pinned to the one above (``j{k}``: ``link{k-1}.B``
    – ``link{k}.A``; ``j0``: ``ground.O`` – ``link0.A``). Every link starts straight, at angle
    ``theta0`` from the downward vertical (the bodies' ``phi = theta0 - pi/2``).
    """
    s, c = math.sin(theta0), math.cos(theta0)
    bodies, joints = [], []
    for k in range(n):
        bodies.append(
            md.Body(
                f"link{k}",
                mass,
                mass * link**2 / 12,
                q0=((k + 0.5) * link * s, -(k + 0.5) * link * c, theta0 - math.pi / 2),
                points={"A": (-link / 2, 0.0), "B": (link / 2, 0.0)},
            )
        )
        upper = "ground.O" if k == 0 else f"link{k - 1}.B"
        joints.append(md.Revolute(f"j{k}", upper, f"link{k}.A"))
    return md.Model(
        bodies=bodies,
        joints=joints,
        ground={"O": (0.0, 0.0)},
        gravity=(0.0, -9.81),
        units=md.SI,
        name=f"chain-{n}",
    )


def double_four_bar(n: int = 2, omega0: float = 1.0) -> tuple[md.Model, list[float]]:
    """The IFToMM "double four-bar" (``n = 2``; the N-four-bar for other ``n``), SI units.

    ``n + 1`` vertical cranks ``crank{i}`` (points ``O`` at the ground pivot ``ground.P{i}`` =
    ``(i, 0)``, ``B`` at the top) and ``n`` horizontal couplers ``coupler{i}`` (``L``, ``R``),
    all uniform bars of 1 m and 1 kg (inertia 1/12 kg m^2); revolute joints ``O{i}`` (ground –
    crank), ``L{i}`` (``crank{i}.B`` – ``coupler{i}.L``), ``R{i}`` (``crank{i+1}.B`` –
    ``coupler{i}.R``); gravity 9.81 m/s^2 along -y. Source of the model: Exudyn's
    ``TestModels/fourBarMechanismIftomm.py`` (IFToMM benchmark "Double four bar mechanism").

    Returns:
        ``(model, qd0)``: the model and its initial velocities, the crank tips moving along +x
        at ``omega0`` m/s (cranks turning at ``-omega0`` rad/s, couplers translating).
    """
    bodies, joints, ground = [], [], {}
    for i in range(n + 1):
        ground[f"P{i}"] = (float(i), 0.0)
        bodies.append(
            md.Body(
                f"crank{i}",
                1.0,
                1.0 / 12.0,
                q0=(float(i), 0.5, math.pi / 2),
                points={"O": (-0.5, 0.0), "B": (0.5, 0.0)},
            )
        )
        joints.append(md.Revolute(f"O{i}", f"ground.P{i}", f"crank{i}.O"))
    for i in range(n):
        bodies.append(
            md.Body(
                f"coupler{i}",
                1.0,
                1.0 / 12.0,
                q0=(i + 0.5, 1.0, 0.0),
                points={"L": (-0.5, 0.0), "R": (0.5, 0.0)},
            )
        )
        joints.append(md.Revolute(f"L{i}", f"crank{i}.B", f"coupler{i}.L"))
        joints.append(md.Revolute(f"R{i}", f"crank{i + 1}.B", f"coupler{i}.R"))
    model = md.Model(
        bodies=bodies,
        joints=joints,
        ground=ground,
        gravity=(0.0, -9.81),
        units=md.SI,
        name=f"double-four-bar-{n}",
    )
    qd0 = [0.5 * omega0, 0.0, -omega0] * (n + 1) + [omega0, 0.0, 0.0] * n
    return model, qd0


# ------------------------------------------------------------------ Andrews' squeezer
#: Parameters of Andrews' squeezing mechanism (SI), as in the Test Set for IVP Solvers
#: (Mazzia & Iavernaro, ``andrews.f``; Hairer & Wanner, *Solving ODEs II*, sec. VII.7).
ANDREWS = dict(
    m1=0.04325, m2=0.00365, m3=0.02373, m4=0.00706, m5=0.07050, m6=0.00706, m7=0.05498,
    i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7, i7=1.912e-5,
    xa=-0.06934, ya=-0.00227, xb=-0.03635, yb=0.03273, xc=0.014, yc=0.072,
    c0=4530.0, l0=0.07785, mom=0.033,
    d=0.028, da=0.0115, e=0.02, ea=0.01421, rr=0.007, ra=0.00092, ss=0.035, sa=0.01874,
    sb=0.01043, sc=0.018, sd=0.02, ta=0.02308, tb=0.00916, u=0.04, ua=0.01228, ub=0.00449,
    zf=0.02, zt=0.04, fa=0.01421,
)  # fmt: skip
#: The test set's consistent initial angles (beta, Theta, gamma, Phi, delta, Omega, epsilon).
ANDREWS_Q0 = (
    -0.0617138900142764496358948458001,
    0.0,
    0.455279819163070380255912382449,
    0.222668390165885884674473185609,
    0.487364979543842550225598953530,
    -0.222668390165885884674473185609,
    1.23054744454982119249735015568,
)
#: Bodies of :func:`andrews_mechanism`, in order.
ANDREWS_BODIES = ("crank", "rodFE", "triangle", "rodEG", "rodGA", "rodEH", "rodHA")


def andrews_body_angles(angles):
    """Absolute body angles (7,) [rad] from the test set's ``(beta, Theta, gamma, Phi, delta,
    Omega, epsilon)`` (relative angles: ``Theta``, ``Phi``, ``Omega``)."""
    beta, Theta, gamma, Phi, delta, Omega, eps = angles
    return (beta, beta + Theta, gamma, Phi + delta, delta, Omega + eps, eps)


def andrews_angles(phi):
    """The test set's ``(beta, Theta, gamma, Phi, delta, Omega, epsilon)`` from the absolute
    body angles ``phi`` (7, ...) of :data:`ANDREWS_BODIES`."""
    p1, p2, p3, p4, p5, p6, p7 = phi
    return (p1, p2 - p1, p3, p4 - p5, p5, p6 - p7, p7)


def andrews_mechanism(angles=ANDREWS_Q0) -> md.Model:
    """Andrews' squeezing mechanism in absolute coordinates, SI units, no gravity.

    Seven bodies (:data:`ANDREWS_BODIES`), frames at their centres of mass, ``phi`` of each the
    test set's absolute angle (``crank``: beta, ``rodFE``: beta + Theta, ``triangle``: gamma,
    ``rodEG``: Phi + delta, ``rodGA``: delta, ``rodEH``: Omega + epsilon, ``rodHA``:
    epsilon). The points, read from the test set's constraint equations and mass matrix (each
    body's own axes, before the shift to the centre of mass):

    * crank: ``O (0, 0)``, ``F (rr, 0)``, centre of mass ``(ra, 0)``;
    * rodFE: ``F (0, 0)``, ``E (-d, 0)``, centre ``(-da, 0)``;
    * triangle: ``B (0, 0)``, ``D (sd, -sc)``, ``E (0, -ss)``, centre ``(sb, -sa)``;
    * rodEG: ``G (0, 0)``, ``E (0, -e)``, centre ``(0, -(e - ea))``;
    * rodGA: ``A (0, 0)``, ``G (zt, 0)``, centre ``(ta, tb)``;
    * rodEH: ``H (0, 0)``, ``E (zf, 0)``, centre ``(zf - fa, 0)``;
    * rodHA: ``A (0, 0)``, ``H (0, -u)``, centre ``(ub, -ua)``.

    The test set fixes only the distance of the centres of the triangle, rodGA and rodHA from
    their ground pivots (their directions do not matter without gravity). Revolute joints
    ``O``, ``F``, ``B``, ``A5``, ``A7``, ``G``, ``H``, and ``E1``, ``E2``, ``E3`` joining the
    four bodies that meet at ``E``; torque ``motor`` (``mom``) on the crank; ``spring``
    between ``ground.C`` and ``triangle.D`` (``c0``, free length ``l0``). One degree of
    freedom. The poses are those of the test-set ``angles``.
    """
    p = ANDREWS
    A, B = (p["xa"], p["ya"]), (p["xb"], p["yb"])
    phi = andrews_body_angles(angles)
    beta, delta, eps = phi[0], phi[4], phi[6]

    def on(origin, ang, v):  # global position of body-axes point v of a body at origin, ang
        c, s = math.cos(ang), math.sin(ang)
        return (origin[0] + c * v[0] - s * v[1], origin[1] + s * v[0] + c * v[1])

    F = on((0.0, 0.0), beta, (p["rr"], 0.0))
    G = on(A, delta, (p["zt"], 0.0))
    H = on(A, eps, (0.0, -p["u"]))
    # (name, mass, inertia, origin of the body's axes, {points}, centre of mass), body axes
    spec = (
        ("crank", "m1", "i1", (0.0, 0.0), {"O": (0, 0), "F": (p["rr"], 0)}, (p["ra"], 0)),
        ("rodFE", "m2", "i2", F, {"F": (0, 0), "E": (-p["d"], 0)}, (-p["da"], 0)),
        (
            "triangle", "m3", "i3", B,
            {"B": (0, 0), "D": (p["sd"], -p["sc"]), "E": (0, -p["ss"])}, (p["sb"], -p["sa"]),
        ),
        ("rodEG", "m4", "i4", G, {"G": (0, 0), "E": (0, -p["e"])}, (0, -(p["e"] - p["ea"]))),
        ("rodGA", "m5", "i5", A, {"A": (0, 0), "G": (p["zt"], 0)}, (p["ta"], p["tb"])),
        ("rodEH", "m6", "i6", H, {"H": (0, 0), "E": (p["zf"], 0)}, (p["zf"] - p["fa"], 0)),
        ("rodHA", "m7", "i7", A, {"A": (0, 0), "H": (0, -p["u"])}, (p["ub"], -p["ua"])),
    )  # fmt: skip
    bodies = []
    for (name, m, i, origin, points, com), ang in zip(spec, phi, strict=True):
        cx, cy = on(origin, ang, com)
        bodies.append(
            md.Body(
                name,
                p[m],
                p[i],
                q0=(cx, cy, ang),
                points={k: (v[0] - com[0], v[1] - com[1]) for k, v in points.items()},
            )
        )
    return md.Model(
        bodies=bodies,
        joints=[
            md.Revolute("O", "ground.O", "crank.O"),
            md.Revolute("F", "crank.F", "rodFE.F"),
            md.Revolute("B", "ground.B", "triangle.B"),
            md.Revolute("E1", "rodFE.E", "triangle.E"),
            md.Revolute("E2", "triangle.E", "rodEG.E"),
            md.Revolute("E3", "triangle.E", "rodEH.E"),
            md.Revolute("G", "rodEG.G", "rodGA.G"),
            md.Revolute("A5", "ground.A", "rodGA.A"),
            md.Revolute("A7", "ground.A", "rodHA.A"),
            md.Revolute("H", "rodHA.H", "rodEH.H"),
        ],
        forces=[
            md.Torque("motor", "crank", law=p["mom"]),
            md.SpringDamper(
                "spring", "ground.C", "triangle.D", stiffness=p["c0"], free_length=p["l0"]
            ),
        ],
        ground={"O": (0.0, 0.0), "A": A, "B": B, "C": (p["xc"], p["yc"])},
        gravity=(0.0, 0.0),
        units=md.SI,
        name="andrews",
    )


def horizontal_chain(n: int, length: float = 0.1, mass_step: float = 0.1) -> md.Model:
    """``n`` links of length ``length`` [m] pinned end to end from the ground origin, lying
    along +x (bodies ``b{i}``, points ``A``/``B``, joints ``J{i}``), SI units, gravity -y; link
    ``i`` has mass ``1 + mass_step i`` [kg] (graded, so that the mass matrix is not a multiple
    of the identity) and inertia ``length**2 / 12`` [kg m^2]."""
    h = length / 2
    bodies = [
        md.Body(
            f"b{i}",
            mass=1.0 + mass_step * i,
            inertia=length**2 / 12,
            q0=(h + i * length, 0.0, 0.0),
            points={"A": (-h, 0.0), "B": (h, 0.0)},
        )
        for i in range(n)
    ]
    joints = [md.Revolute("J0", "ground", "b0.A")]
    joints += [md.Revolute(f"J{i}", f"b{i - 1}.B", f"b{i}.A") for i in range(1, n)]
    return md.Model(
        bodies=bodies, joints=joints, gravity=(0.0, -9.81), units=md.UnitSystem("m", "kg", "s")
    )


def antonya_mixed(model: md.Model, t, forward: md.Result, **kwargs) -> md.Result:
    """The mixed run of ``examples/antonya.yaml`` through the Python API: ``F1`` unknown, the
    slider's x replayed from ``forward``, the paper's partition solver with ``coupler.phi``
    independent, tolerances 1e-10; ``kwargs`` (``hold``, ``q0``...) passed on."""
    return md.mixed(
        model,
        t,
        prescribed=[md.prescribe(forward, "slider.x")],
        unknown=["F1"],
        solver="partition",
        independent=["coupler.phi"],
        rtol=1e-10,
        atol=1e-10,
        **kwargs,
    )


# ----------------------------------------------------------------------------- tracing
def traced_now() -> dict:
    """The traces so far of each of mixdyn's compiled functions, by name."""
    return dict(_compile.traces)


def new_traces(before: dict) -> dict:
    """The functions traced since ``before`` (:func:`traced_now`) and how often."""
    return {k: v - before.get(k, 0) for k, v in _compile.traces.items() if v != before.get(k, 0)}
