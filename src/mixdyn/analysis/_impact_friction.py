"""Coulomb friction in a rigid impact at one contact point: Newton's restitution on the
normal velocity and Coulomb's law on the impulses (the algebraic, impulse-level model of
Brach, "Rigid body collisions", J. Appl. Mech. 56 (1989) 133-138).

At a contact point with the friction coefficient ``mu`` whose normal velocity ``v = G qd``
approaches (``G = dg/dq`` (nq,), the gap's gradient), the tangential velocity
``v_t = G_t qd`` is the sliding speed of body j on body i at the contact point along
``t = z x n`` (``G_t`` (nq,): its gradient in the velocities, the row beside ``G``), and
the impulses are the normal ``P >= 0`` along ``n`` and the tangential ``T`` along ``t`` on
body j (the opposite on body i) [force * time]::

    M (qd+ - qd-) = D^T Lambda + G^T P + G_t^T T,   Phi_q qd+ + Phi_t = 0,   G qd+ = -e v-

with one of (the standard one-point algorithm, stick tried first):

- **stick**: ``G_t qd+ = 0`` (the contact point leaves without sliding), the system of
  :func:`~._impulses.impulse` with the row ``G_t`` beside ``G``; valid where
  ``|T| <= mu P``;
- **slip**: ``T = s mu P``, the impulse acting along ``G + s mu G_t``, ``s`` the sign of
  the stick impulse ``T`` (where the constraints leave no sticking solution, as for a
  pendulum whose contact point moves on a circle: ``s = -sign(v_t-)``).

The constraints' impulses ``Lambda`` act along the rows ``D`` (:func:`~._impulses.impulse`:
the Jacobian's, a mixed problem's prescribed motions along the unknown forces'
directions).

Limits of the model (stated by the literature and guarded here): Newton's law fixes the
normal velocity after the impact whatever the friction does, so that in a system whose
normal and tangential motions are coupled, where the slip reverses during the impact, the
impulses can give the bodies energy (Kane's double pendulum; Stronge, "Unraveling
paradoxical theories for rigid body collisions", J. Appl. Mech. 58 (1991) 1049-1055;
Glocker, "Energetic consistency conditions for standard impacts, Part II: Poisson-type
inequality impact laws", Multibody Syst. Dyn. (2013), doi:10.1007/s11044-013-9387-2, whose
introduction names Newton's law with friction, Kane's observation, as energetically
inconsistent). The contact's impulses' work
``P (v- + v+) / 2 + T (v_t- + v_t+) / 2`` (the impact's jump of kinetic energy where the
joints and drivers do not move in time) is returned, so that the run ends as a named
failure where it is positive; likewise a slip whose normal impulse would pull (``P < 0``:
the friction jams the contact, Painlevé's case at the impulse level).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

#: The stick solution holds where its rows are met within this part of the contact
#: point's speed (otherwise the constraints fix the tangential velocity with the normal).
FEASIBLE_TOL = 1e-9


class Frictional(NamedTuple):
    """One frictional impact's outcome.

    Attributes:
        qd: (nq,) the velocities after.
        lam: (m,) the constraints' impulses, along the rows ``D``.
        P: the normal impulse [force * time].
        T: the tangential (friction) impulse on body j along ``z x n`` [force * time].
        sticks: whether the contact point leaves without sliding (``|T| <= mu P``).
        work: the contact's impulses' work ``P (v- + v+) / 2 + T (v_t- + v_t+) / 2``
            [energy]: at most zero for an energetically consistent impact.
    """

    qd: np.ndarray
    lam: np.ndarray
    P: float
    T: float
    sticks: bool
    work: float


def solve_rows(Minv, A, Dg, b, qd):
    """The velocities after ``qd + M^-1 Dg^T x`` and the impulses ``x`` meeting the rows
    ``A`` (``A M^-1 Dg^T x = b``, least squares where rows are redundant), and the rows'
    largest residual."""
    S = (A * Minv) @ Dg.T
    x = np.linalg.lstsq(S, b, rcond=1e-13)[0]
    return qd + Minv * (Dg.T @ x), x, float(np.max(np.abs(S @ x - b), initial=0.0))


def coulomb_impulse(Minv, J, phit, G, Gt, qd, e, mu, D=None) -> Frictional:
    """The velocity jump of one impact with Coulomb friction at a contact point (see the
    module).

    Args:
        Minv: (nq,) inverse of the diagonal mass matrix.
        J: (m, nq) constraint Jacobian ``Phi_q``; phit: (m,) ``Phi_t``.
        G: (nq,) the gap's gradient; Gt: (nq,) the tangential velocity's row.
        qd: (nq,) velocities before; e: restitution; mu: friction coefficient (>= 0).
        D: (m, nq) the rows along which the constraints' impulses act (default ``J``).

    Returns:
        :class:`Frictional`, with ``M (qd+ - qd-) = D^T Lambda + G^T P + G_t^T T``,
        ``J qd+ + Phi_t = 0`` and ``G qd+ = -e v-``.
    """
    D = J if D is None else D
    v, vt = float(G @ qd), float(Gt @ qd)
    kept = -(J @ qd + phit)
    speed = max(abs(v), abs(vt), float(np.max(np.abs(kept), initial=0.0)))
    A = np.vstack([J, G[None, :], Gt[None, :]])
    after, x, residual = solve_rows(Minv, A, np.vstack([D, G[None, :], Gt[None, :]]),
                                np.concatenate([kept, [-(1.0 + e) * v, -vt]]), qd)  # fmt: skip
    P, T = float(x[-2]), float(x[-1])
    feasible = residual <= FEASIBLE_TOL * speed
    if feasible and abs(T) <= mu * P:
        work = 0.5 * P * (v + G @ after) + 0.5 * T * (vt + Gt @ after)
        return Frictional(after, x[:-2], P, T, True, float(work))
    if feasible and T != 0.0:
        s = float(np.sign(T))
    else:  # no sticking solution: against the sliding before (or the frictionless one's)
        s = -float(np.sign(vt))
        if s == 0.0:
            free, _, _ = solve_rows(Minv, A[:-1], np.vstack([D, G[None, :]]),
                                np.concatenate([kept, [-(1.0 + e) * v]]), qd)  # fmt: skip
            s = -float(np.sign(Gt @ free))
    along = G + s * mu * Gt
    after, x, _ = solve_rows(Minv, A[:-1], np.vstack([D, along[None, :]]),
                         np.concatenate([kept, [-(1.0 + e) * v]]), qd)  # fmt: skip
    P = float(x[-1])
    T = s * mu * P
    work = 0.5 * P * (v + G @ after) + 0.5 * T * (vt + Gt @ after)
    return Frictional(after, x[:-1], P, T, False, float(work))


class Simultaneous(NamedTuple):
    """The outcome of impacts at ``k`` contact points at one instant.

    Attributes:
        qd: (nq,) the velocities after.
        lam: (m,) the constraints' impulses, along the rows ``D``.
        P: (k,) the normal impulses [force * time].
        T: (k,) the tangential (friction) impulses, each on its body j along ``z x n``
            [force * time] (zero at a frictionless point).
        sticks: (k,) whether each point leaves without sliding (``|T| <= mu P``).
        work: the contact impulses' work, summed over the points as in :class:`Frictional`
            [energy].
    """

    qd: np.ndarray
    lam: np.ndarray
    P: np.ndarray
    T: np.ndarray
    sticks: np.ndarray
    work: float


def coulomb_impulses(Minv, J, phit, G, Gt, qd, e, mu, D=None) -> Simultaneous | None:
    """The velocity jump of impacts at ``k`` contact points at one instant (a box landing
    flat on a rough floor): Newton's law at each point (``G_k qd+ = -e_k G_k qd-``), the
    joints kept, and Coulomb's law at each point with ``mu_k > 0``, each sticking or
    sliding as at one point (see the module), all solved together.

    The points' states are found by an active set: every rough point tried sticking; the
    sticking point whose friction most exceeds ``mu P`` slides (in the direction of its
    sticking impulse); a sliding point that its friction turns past the end of its slip
    (``s G_t qd+ > 0``, ``T = s mu P``) sticks again; at most ``4 k + 4`` solves.

    Args:
        Minv: (nq,) inverse mass diagonal; J (m, nq), phit (m,): the constraints.
        G, Gt: (k, nq) the points' gaps' gradients and tangential velocities' rows.
        qd: (nq,) velocities before; e: (k,) restitutions; mu: (k,) friction coefficients
            (0 or NaN: frictionless).
        D: (m, nq) the rows along which the constraints' impulses act (default ``J``).

    Returns:
        :class:`Simultaneous` (a normal impulse may pull: the caller decides), or None where
        no state of the points meets both laws (the constraints fix a point's normal or
        tangential velocity, or the states cycle).
    """
    D = J if D is None else D
    k, m = len(G), len(phit)
    v, vt = G @ qd, Gt @ qd
    mu = np.nan_to_num(np.asarray(mu, float), nan=0.0)
    kept = -(J @ qd + phit)
    speed = max(float(np.max(np.abs(v))), float(np.max(np.abs(vt))),
                float(np.max(np.abs(kept), initial=0.0)))  # fmt: skip
    stick = mu > 0.0
    s = np.zeros(k)  # a sliding point's direction of friction impulse (0: frictionless)
    for _ in range(4 * k + 4):
        along = G + (s * mu)[:, None] * Gt
        A = np.vstack([J, G, Gt[stick]])
        Dg = np.vstack([D, along, Gt[stick]])
        b = np.concatenate([kept, -(1.0 + e) * v, -vt[stick]])
        after, x, residual = solve_rows(Minv, A, Dg, b, qd)
        if residual > FEASIBLE_TOL * speed:
            return None
        P = x[m : m + k]
        T = s * mu * P
        T[stick] = x[m + k :]
        excess = np.where(stick, np.abs(T) - mu * P, -np.inf)
        overshoot = np.where(~stick & (s != 0.0), s * (Gt @ after), -np.inf)
        if excess.max() > FEASIBLE_TOL * np.abs(P).max():
            j = int(np.argmax(excess))
            stick[j], s[j] = False, float(np.sign(T[j]))
        elif overshoot.max() > FEASIBLE_TOL * speed:
            j = int(np.argmax(overshoot))
            stick[j], s[j] = True, 0.0
        else:
            work = 0.5 * (P @ (v + G @ after) + T @ (vt + Gt @ after))
            return Simultaneous(after, x[:m], P, T, stick.copy(), float(work))
    return None


__all__ = ["Frictional", "Simultaneous", "coulomb_impulse", "coulomb_impulses", "solve_rows"]
