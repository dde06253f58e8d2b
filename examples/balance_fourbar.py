"""Counterweight balancing of a four-bar: the RMS shaking force minimized with JAX gradients,
against the Berkof-Lowen full force-balance conditions.

A crank-rocker four-bar (ground O2-O4, crank O2-A, coupler A-B with its centre of mass off the
line AB, rocker O4-B) turns at a constant crank speed. The shaking force, the force the moving
links put on the frame, is the total mass times the acceleration of the total centre of mass:
``F_s = sum_i m_i a_i``. Counterweights on the crank and the rocker are described by their first
moments about the fixed pivots in the link's frame, ``u2`` and ``u4`` [kg*m] (a mass ``m_c`` at
``s_c``: ``u = m_c s_c``), four numbers ``theta = (u2x, u2y, u4x, u4y)``.

1. **Kinematics once** (``md.kinematic``): balancing does not change the motion.
2. **The objective**: the RMS of ``F_s`` over a crank revolution, a JAX function of ``theta``
   (a counterweight's acceleration from the crank's or rocker's ``phi``, ``omega``, ``alpha``);
   its mean square minimized by scipy's L-BFGS-B within bounds, the gradient by
   ``jax.value_and_grad``.
3. **Closed form** (Berkof and Lowen, 1969, the linearly independent vectors): with
   ``a2 e^{i phi2} + a3 e^{i phi3} = a1 + a4 e^{i phi4}`` the total first moment is
   ``e^{i phi2} [m2 r2 e^{i th2} + m3 a2 (1 - r3/a3 e^{i th3})] + e^{i phi4} [m4 r4 e^{i th4} +
   m3 r3 a4/a3 e^{i th3}] + const``; it is constant when both brackets vanish:
   ``m2 r2 e^{i th2} = m3 a2 (r3/a3 e^{i th3} - 1)`` and
   ``m4 r4 e^{i th4} = -m3 r3 (a4/a3) e^{i th3}`` (``r_i e^{i th_i}``: a link's centre of mass
   from its fixed pivot, or from A for the coupler, in the link's frame).
4. **A second method**: the balanced mechanism is built (each counterweight merged into its
   link: mass, centre of mass, inertia by the parallel-axis rule) and run by ``md.inverse``:
   the sum of the reactions at the two ground pivots is the shaking force, from the Lagrange
   multipliers instead of Newton's ``sum m a``.

Units: SI (m, kg, s, N). Run: ``python examples/balance_fourbar.py``.
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np

import mixdyn as md

# Lengths [m]: ground O2-O4, crank O2-A, coupler A-B, rocker O4-B (Grashof crank-rocker).
A1, A2, A3, A4 = 0.30, 0.10, 0.35, 0.25
# Masses [kg], inertias about the centres of mass [kg*m^2].
M2, M3, M4 = 0.5, 1.2, 0.9
J2, J3, J4 = 6e-4, 1.5e-2, 5e-3
# The coupler's centre of mass from A, in its frame (x along A->B): r3 e^{i th3}.
R3, TH3 = 0.2, np.deg2rad(20.0)
OMEGA = 2.0 * np.pi  # crank speed [rad/s]: one revolution a second


@dataclasses.dataclass(frozen=True)
class Counterweights:
    """First moments of the counterweights about the fixed pivots, in the links' frames
    [kg*m], and the counterweights' mass [kg] (it only places them: ``s = u / mass``)."""

    u2: tuple[float, float] = (0.0, 0.0)
    u4: tuple[float, float] = (0.0, 0.0)
    mass: float = 0.5


def _link(name, m, j, pivot, length, com, q0, cw=None, cw_mass=0.0, ends=("P", "Q")):
    """A straight link from ``pivot`` (local x along the link), its own centre of mass at
    ``com`` from the pivot, optionally merged with a point counterweight of first moment ``cw``
    about the pivot: the body frame at the combined centre of mass."""
    com = np.asarray(com, dtype=float)
    mass, inertia, c = m, j, com
    if cw is not None and cw_mass > 0:
        s = np.asarray(cw, dtype=float) / cw_mass
        mass = m + cw_mass
        c = (m * com + cw_mass * s) / mass
        inertia = j + m * np.sum((com - c) ** 2) + cw_mass * np.sum((s - c) ** 2)
    p, q = -c, np.array([length, 0.0]) - c
    phi = q0[2]
    rot = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    origin = np.asarray(pivot, dtype=float) + rot @ c
    return md.Body(
        name, mass, inertia, q0=(*origin, phi), points={ends[0]: tuple(p), ends[1]: tuple(q)}
    )


def four_bar(cw: Counterweights | None = None) -> md.Model:
    """The four-bar driven at ``OMEGA``, with the counterweights ``cw`` merged in (None: none)."""
    cw = cw or Counterweights()
    # A rough start at phi2 = 0 (the assembly closes it with the crank held).
    phi2, phi3, phi4 = 0.0, np.deg2rad(60.0), np.deg2rad(100.0)
    a = A2 * np.array([np.cos(phi2), np.sin(phi2)])
    com3 = (R3 * np.cos(TH3), R3 * np.sin(TH3))
    bodies = [
        _link("crank", M2, J2, (0, 0), A2, (A2 / 2, 0), (0, 0, phi2), cw.u2, cw.mass, ("O", "A")),
        _link("coupler", M3, J3, a, A3, com3, (0, 0, phi3), ends=("A", "B")),
        _link("rocker", M4, J4, (A1, 0), A4, (A4 / 2, 0), (0, 0, phi4), cw.u4, cw.mass, ("O", "B")),
    ]
    return md.Model(
        bodies=bodies,
        ground={"O2": (0.0, 0.0), "O4": (A1, 0.0)},
        joints=[
            md.Revolute("O2", "ground.O2", "crank.O"),
            md.Revolute("A", "crank.A", "coupler.A"),
            md.Revolute("B", "coupler.B", "rocker.B"),
            md.Revolute("O4", "ground.O4", "rocker.O"),
        ],
        drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.0, OMEGA))],
        units=md.SI,
        name="four-bar to balance",
    )


def berkof_lowen() -> np.ndarray:
    """The counterweights' first moments of full force balance, ``(u2x, u2y, u4x, u4y)``
    [kg*m], from the closed form (module docstring, item 3)."""
    e3 = np.exp(1j * TH3)
    total2 = M3 * A2 * (R3 / A3 * e3 - 1.0)  # crank: m2 r2 e^{i th2} with the counterweight
    total4 = -M3 * R3 * (A4 / A3) * e3
    u2 = total2 - M2 * A2 / 2
    u4 = total4 - M4 * A4 / 2
    return np.array([u2.real, u2.imag, u4.real, u4.imag])


def _rotation_second_derivative(phi, omega, alpha):
    """d^2/dt^2 of the rotation matrix R(phi): (N, 2, 2)."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    dr = jnp.stack([jnp.stack([-s, -c], -1), jnp.stack([c, -s], -1)], -2)  # dR/dphi
    r = jnp.stack([jnp.stack([c, -s], -1), jnp.stack([s, c], -1)], -2)
    return alpha[:, None, None] * dr - (omega**2)[:, None, None] * r


def shaking_force_function(kin: md.Result):
    """``theta -> (N, 2)`` shaking force [N] of the mechanism of ``kin`` (no counterweights)
    with counterweights of first moments ``theta`` about the fixed pivots."""
    links = sum(
        float(b.mass) * np.stack([kin[f"{b.name}.ax"], kin[f"{b.name}.ay"]], -1)
        for b in kin.model.bodies
    )
    ddr2 = _rotation_second_derivative(kin["crank.phi"], kin["crank.omega"], kin["crank.alpha"])
    ddr4 = _rotation_second_derivative(kin["rocker.phi"], kin["rocker.omega"], kin["rocker.alpha"])

    def force(theta):
        return links + ddr2 @ theta[:2] + ddr4 @ theta[2:]

    return force


def optimize(kin: md.Result, bound: float = 1.0):
    """The counterweights minimizing the mean square shaking force over ``kin``'s times, each
    first moment within ``[-bound, bound]`` [kg*m]: (4,) [kg*m], and scipy's result.

    scipy's L-BFGS-B with the objective and its gradient compiled by JAX (measured on this
    problem: 7 ms and 17 iterations to the closed form within 6e-17, where optimistix'
    Levenberg-Marquardt took 115 ms, tracing its solve again at each call, to the same
    answer; and L-BFGS-B takes bounds)."""
    import scipy.optimize

    force = shaking_force_function(kin)
    value_and_grad = jax.jit(jax.value_and_grad(lambda th: jnp.mean(jnp.sum(force(th) ** 2, -1))))

    def fun(x):
        v, g = value_and_grad(jnp.asarray(x))
        return float(v), np.asarray(g, dtype=float)

    sol = scipy.optimize.minimize(
        fun,
        np.zeros(4),
        jac=True,
        method="L-BFGS-B",
        bounds=[(-bound, bound)] * 4,
        options={"ftol": 1e-30, "gtol": 1e-14, "maxiter": 1000},
    )
    return np.asarray(sol.x), sol


def rms(force) -> float:
    """RMS magnitude of a (N, 2) force history."""
    return float(np.sqrt(np.mean(np.sum(np.asarray(force) ** 2, axis=-1))))


def reaction_shaking_force(model: md.Model, t) -> np.ndarray:
    """(N, 2) the shaking force from ``md.inverse``: the sum of the ground pivots' reactions."""
    res = md.inverse(model, t)
    return np.stack([res["O2.Fx"] + res["O4.Fx"], res["O2.Fy"] + res["O4.Fy"]], axis=-1)


def main() -> dict[str, float]:
    """Optimize, compare and print; returns the figures of merit."""
    t = np.linspace(0.0, 1.0, 361)[:-1]  # one crank revolution
    start = time.perf_counter()
    kin = md.kinematic(four_bar(), t)
    theta, sol = optimize(kin)
    seconds = time.perf_counter() - start
    exact = berkof_lowen()
    force = shaking_force_function(kin)
    before, after = rms(force(jnp.zeros(4))), rms(force(jnp.asarray(theta)))
    balanced = four_bar(Counterweights(u2=tuple(theta[:2]), u4=tuple(theta[2:])))
    by_reactions = reaction_shaking_force(balanced, t)
    unbalanced_reactions = reaction_shaking_force(four_bar(), t)
    names = ("u2x", "u2y", "u4x", "u4y")
    print("counterweight first moments about the fixed pivots [kg*m]")
    print(f"{'':5} {'optimized':>14} {'Berkof-Lowen':>14} {'difference':>11}")
    for k, n in enumerate(names):
        print(f"{n:5} {theta[k]:14.10f} {exact[k]:14.10f} {theta[k] - exact[k]:11.2e}")
    rel = float(np.max(np.abs(theta - exact)) / np.max(np.abs(exact)))
    print(f"largest difference / largest moment: {rel:.2e}")
    print(
        f"RMS shaking force [N]: unbalanced {before:.4f}, balanced {after:.2e} "
        f"(ratio {after / before:.1e}); {sol.nit} L-BFGS-B "
        f"iterations, {seconds:.2f} s with the kinematics"
    )
    react_ratio = rms(by_reactions) / rms(unbalanced_reactions)
    print(
        f"md.inverse of the balanced mechanism: RMS of the ground reactions' sum "
        f"{rms(by_reactions):.2e} N ({react_ratio:.1e} of the unbalanced "
        f"{rms(unbalanced_reactions):.4f} N)"
    )
    return {
        "relative_difference": rel,
        "ratio": after / before,
        "reaction_ratio": react_ratio,
        "unbalanced_by_reactions": rms(unbalanced_reactions),
        "unbalanced": before,
    }


if __name__ == "__main__":
    main()
