"""The velocity jumps of rigid impacts without friction, and the plastic settling of several
points at once (with friction where the points have it); Coulomb's law at one point or at
several struck together is :mod:`._impact_friction`. The run that uses them:
:mod:`._impacts`.

At a contact point whose normal velocity ``v- = G qd-`` approaches (``G = dg/dq`` (nq,), the
gap's gradient), an impact with Newton's restitution ``e`` over the constrained system::

    [M   Phi_q^T  G^T] [qd+ - qd-]   [0              ]
    [Phi_q  0      0 ] [  -Lambda] = [-Phi_q qd- - Phi_t]
    [G      0      0 ] [  -P     ]   [-(1 + e) v-    ]

solved through the Schur complement ``A M^-1 D^T`` (``A = [Phi_q; G]``, ``D`` the rows along
which the constraints' impulses act: ``Phi_q``, or a mixed problem's prescribed motions along
the unknown forces' directions), in the least-squares sense where rows are redundant.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._impact_friction import coulomb_impulses, solve_rows

#: Impacts whose contact impulses' work exceeds this part of their size
#: (``|P v-| + |T v_t-|``) give the bodies energy (Newton's law with friction).
ENERGY_TOL = 1e-9


def impulse(Minv, J, phit, G, qd, e, D=None):
    """The velocity jump of one frictionless impact at a contact point (see the module).

    Args:
        Minv: (nq,) inverse of the diagonal mass matrix.
        J: (m, nq) constraint Jacobian ``Phi_q``; phit: (m,) ``Phi_t``.
        G: (nq,) the gap's gradient; qd: (nq,) velocities before; e: restitution.
        D: (m, nq) the rows along which the constraints' impulses act (default ``J``; a
            mixed problem's prescribed motions: the unknown forces' directions ``B^T``).

    Returns:
        ``(qd+ (nq,), Lambda (m,), P)``: the velocities after, the constraints' impulses and
        the normal impulse [force * time], with ``M (qd+ - qd-) = D^T Lambda + G^T P`` and
        ``J qd+ + Phi_t = 0``.
    """
    A = np.vstack([J, G[None, :]])
    Dg = A if D is None else np.vstack([D, G[None, :]])
    b = np.concatenate([-(J @ qd + phit), [-(1.0 + e) * float(G @ qd)]])
    after, x, _ = solve_rows(Minv, A, Dg, b, qd)
    return after, x[:-1], float(x[-1])


def consistent(found, G, Gt, qd) -> bool:
    """Whether simultaneous impacts (:func:`~._impact_friction.coulomb_impulses`' outcome at
    points of rows ``G``, ``Gt``) take energy from the bodies (within :data:`ENERGY_TOL` of
    their impulses' scale): otherwise they are struck one by one, each checked on its own."""
    scale = np.abs(found.P) @ np.abs(G @ qd) + np.abs(found.T) @ np.abs(Gt @ qd)
    return found.work <= ENERGY_TOL * scale


class Settled(NamedTuple):
    """A plastic impact at several points (:func:`settle`).

    Attributes:
        qd: (nq,) the velocities after.
        points: the indices of the points that took an impulse (and rest).
        P: (len(points),) their normal impulses [force * time].
        lam: (m,) the constraints' impulses, along the rows ``D``.
        T: (len(points),) their friction impulses along ``z x n`` [force * time].
        sticks: (len(points),) whether each leaves without sliding (false if frictionless).
    """

    qd: np.ndarray
    points: list
    P: np.ndarray
    lam: np.ndarray
    T: np.ndarray
    sticks: np.ndarray


def settle(Minv, J, phit, G, qd, touching, tol, D=None, Gt=None, mu=None) -> Settled | None:
    """A perfectly plastic impact at several contact points at once: the set ``A`` of the
    ``touching`` points (k,) whose normal velocities are all brought to zero with
    non-negative impulses while every other touching point leaves (a linear
    complementarity problem, solved by adding the most approaching point and dropping the
    most pulling one, at most ``4 k`` times), with Coulomb's law at each point of ``A``
    where ``mu > 0`` (:func:`~._impact_friction.coulomb_impulses`; frictionless where the
    frictional impulses find no state or would give energy).

    Args:
        Minv: (nq,) inverse mass diagonal; J (m, nq), phit (m,): the constraints.
        G: (k, nq) the gaps' gradients; qd: (nq,) velocities before.
        touching: (k,) bool, the points that may take an impulse; tol: the normal velocity
            [velocity] below which a point counts as approaching.
        D: (m, nq) the rows along which the constraints' impulses act (:func:`impulse`).
        Gt: (k, nq) the points' tangential velocities' rows; mu: (k,) their friction
            coefficients (NaN or 0: frictionless; both None: all frictionless).

    Returns:
        :class:`Settled`, or None where no set is found.
    """
    k, m = len(G), len(phit)
    rough = mu is not None and bool(np.any(np.nan_to_num(mu) > 0.0))
    active: list[int] = []
    after, lam = qd, np.zeros(m)
    T, sticks = np.zeros(0), np.zeros(0, bool)
    for _ in range(4 * k + 4):
        if active:
            found = None
            if rough:
                found = coulomb_impulses(Minv, J, phit, G[active], Gt[active], qd,
                                         np.zeros(len(active)), mu[active], D)  # fmt: skip
                if found is not None and not consistent(found, G[active], Gt[active], qd):
                    found = None
            if found is not None:
                after, lam, push, T, sticks = found.qd, found.lam, found.P, found.T, found.sticks
            else:
                rows = np.vstack([J, G[active[:-1]]])
                along = None if D is None else np.vstack([D, G[active[:-1]]])
                rhs = np.concatenate([phit, np.zeros(len(active) - 1)])
                after, lam, P = impulse(Minv, rows, rhs, G[active[-1]], qd, 0.0, along)
                push, lam = np.concatenate([lam[m:], [P]]), lam[:m]
                T, sticks = np.zeros(len(active)), np.zeros(len(active), bool)
            if push.min() < 0.0:  # pulling: that point leaves
                active.pop(int(np.argmin(push)))
                continue
        v = np.where(touching, G @ after, np.inf)
        v[active] = np.inf
        if v.min() >= -tol:
            if not active:
                return Settled(after, active, np.zeros(0), lam, T, sticks)
            return Settled(after, active, push, lam, T, sticks)
        active.append(int(np.argmin(v)))
    return None


__all__ = ["ENERGY_TOL", "Settled", "consistent", "impulse", "settle"]
