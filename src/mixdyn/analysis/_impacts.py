"""Forward and mixed dynamics with rigid impacts: the motion integrated from impact to impact, each
impact's instant found by diffrax's events and its velocity jump solved with Newton's
restitution over the constrained system.

A run is a sequence of segments, each one adaptive Runge–Kutta solve (the projection
method's ``rtol``, ``atol``, ``solver`` and ``max_steps``; one compiled program for every
segment and set of resting points) that ends at the first instant a rigid contact's gap
``g(q) = -delta(q)`` [length] falls to zero, or a resting point's normal force does (one
``diffrax.Event`` on the smaller of the smallest gap of the contact points apart or
separating at the segment's start, over the model's length, and the smallest normal force
of the resting points, over its value at the start; downcrossings only; the instant found
by bisection on the step's dense output to 1e-14 of the span). Within a segment the
index-1 equations of motion are integrated as they are; at its end the positions and
velocities are projected onto the constraints, and a segment is at most 2048 steps. A
contact point found more than :data:`MISSED` model lengths inside its contact at a
segment's end passed into it unseen: the run ends as a :class:`~mixdyn.errors.NumericalError`.

At an impact the velocities jump from ``qd-`` to ``qd+`` with impulses: for a contact point
whose normal velocity ``v- = G qd-`` approaches (``G = dg/dq`` (1, nq), ``v- < 0``)::

    [M   Phi_q^T  G^T] [qd+ - qd-]   [0              ]
    [Phi_q  0      0 ] [  -Lambda] = [-Phi_q qd- - Phi_t]
    [G      0      0 ] [  -P     ]   [-(1 + e) v-    ]

i.e. ``M (qd+ - qd-) = Phi_q^T Lambda + G^T P``, every joint's and driver's velocity
constraint kept (``Phi_q qd+ + Phi_t = 0``) and the normal velocity reversed by Newton's
law (``G qd+ = -e v-``); ``P >= 0`` the contact's normal impulse [force * time] and
``Lambda`` the constraints' impulses (solved through the Schur complement
``A M^-1 A^T``, ``A = [Phi_q; G]``, in the least-squares sense where rows are redundant).

A contact with a friction coefficient ``mu`` adds Coulomb's law on the impulses
(:mod:`._impact_friction`): its tangential row ``G_t`` (the sliding speed
``v_t = G_t qd`` along ``z x n``) beside ``G``, and a tangential impulse ``T`` along it,
``M (qd+ - qd-) = Phi_q^T Lambda + G^T P + G_t^T T``; the point sticks
(``G_t qd+ = 0``, where ``|T| <= mu P``) or else slides (``T = +-mu P``, in the direction
of the sticking impulse). Newton's law with friction can give energy where the normal and
tangential motions are coupled: an impact whose contact impulses would do positive work,
or whose sliding normal impulse would pull (jamming), ends the run as a
:class:`~mixdyn.errors.NumericalError`. Several points struck at one instant, or settling
together in a plastic impact (:func:`~._impulses.settle`), take Coulomb's law at each rough
point too. A resting point of a contact with ``mu > 0`` takes Coulomb's friction with stick
and slip (:class:`~._resting.RestFriction`: its normal force the held row's multiplier, its
stick band the rest speed, below). A segment also ends where a sliding friction row (a
resting point's, a joint's) slows into its stick band, and the next segment starts with the
rows that stick brought to rest (:func:`_halt`), so that a body that its friction stops
stays where it stopped.

In a mixed run (:mod:`.mixed`: ``p`` unknown forces of directions ``B`` (nq, p), ``p``
prescribed motions ``Psi``) a prescribed motion's velocity cannot jump: its unknown force
takes an impulse ``F`` [force * time] instead of a constraint's. The prescribed motions are
the constraints' last ``p`` rows, their impulses acting along ``B`` rather than along
``Psi_q^T``::

    M (qd+ - qd-) = Phi_q^T Lambda + G^T P + B F,   Phi_q qd+ + Phi_t = 0,
    Psi_q qd+ + Psi_t = 0,                           G qd+ = -e v-

(the same system, its Schur complement ``A M^-1 D^T`` with ``A = [Phi_q; Psi_q; G]`` and
``D = [Phi_q; B^T; G]``). An
impulse's work is its value times the mean of its velocities before and after: the unknown
forces' ``F . B^T (qd- + qd+) / 2`` counts with their work (``work.constraints``), the rest
of the kinetic energy's jump with the impacts' (``work.impacts``).

Several contact points touching at one instant (a row of balls, Newton's cradle) are
resolved one after the other (sequential impacts): the point approaching fastest first,
then again while any point within the gap tolerance approaches; each pairwise impact keeps
momentum and, at ``e = 1``, energy. Points that approach at one instant strike together
(a box landing flat, two blocks meeting face on:
:func:`~._impact_friction.coulomb_impulses`, Newton's law at each and Coulomb's at each rough
one, solved with the joints), where every impulse pushes, the constraints leave each point's
laws to it and the impulses take energy; otherwise one after the other. A point touching without
approaching (the next ball of the cradle, at rest against the one struck) takes no part.

Zeno: a ball coming to rest bounces infinitely often in a finite time (for a ball dropped
with ``e < 1``, at the sum of the geometric series ``t_inf = t_1 + 2 e v0 / (g (1 - e))``).
A contact point touching with a normal velocity below :data:`REST_SPEED` times the model's
length over the run's span (approaching, or leaving) comes to rest: a last perfectly
plastic impulse (``e = 0``, the same system) stops it, and it is held on its contact, its
penetration a constraint row appended to the joints and drivers (:mod:`._resting`: one
problem per set of resting points) whose multiplier is the normal force ``N`` [force]. The
next segments integrate that problem and end, besides at impacts, by an event when a
resting point's ``N`` falls to zero (the motion pulls it away: lift-off); the point is then
released and its gap watched again. A resting point whose ``N`` is tensile at a segment's
start, or whose row takes a pulling impulse in an impact elsewhere, is released at once. A
point struck a second time at one instant (a box landing flat rocks from corner to corner
in no time) settles with the other touching points together: one perfectly plastic impact
over all of them (:func:`~._impulses.settle`), the set chosen so that every impulse pushes and every
other touching point leaves; the set rests. A resting contact does no work (its row's
velocity is zero): the energy balance holds with the impacts' losses alone.

A run past :data:`MAX_IMPACTS` impacts (contacts chattering without slowing to the rest
speed) ends as an :class:`~mixdyn.errors.ImpactAccumulationError`, carrying the states
computed up to its time.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import _reaction_dependent as rd
from ..equations import force_directions
from ..errors import (
    ImpactAccumulationError,
    ModelError,
    NumericalError,
    SingularityError,
    StepSizeError,
)
from ..model._compliant import rigid_contacts
from ..runtime._programs import cached_jit
from ._assembly import length_scale
from ._impact_friction import coulomb_impulse, coulomb_impulses
from ._impulses import ENERGY_TOL, consistent, impulse, settle
from ._problem import Problem
from ._resting import friction_at, hold, hold_positions, holding, n_holds, normal_forces
from .methods import Projection
from .result import Partial, Result

#: An impact approaching slower than this many model lengths per run span ends the run as
#: accumulating impacts (see the module).
REST_SPEED = 1e-6
#: A run with more impacts ends as accumulating impacts.
MAX_IMPACTS = 10_000
#: Contact points within this many model lengths of touching take part in an impact.
GAP_TOL = 1e-9
#: A contact point found this many model lengths inside its contact at a segment's end
#: passed into it unseen: the run ends as a numerical failure.
MISSED = 1e-6
#: The impact instant's tolerance, relative to the run's span.
TIME_TOL = 1e-14
#: An impact whose normal velocity after misses Newton's law by more than this part of the
#: approach speed (at least the rest speed) is singular (the constraints fix the normal velocity).
IMPULSE_TOL = 1e-6
#: A resting point's held row pulls in an impact only where its impulse is below minus this
#: part of the impact's own (rounding leaves a row the impact does not load, a block resting
#: on the floor struck level against a wall, at ~1e-17 of it, of either sign).
PULL_TOL = 1e-9
#: The first step of a segment, relative to the run's span (at most the first output
#: interval, and shorter after an impact: see :func:`_first_step`).
FIRST_STEP = 1e-4
#: The part of the smallest contact radius a body point may move within one step.
PASS_FRACTION = 0.5
#: The steps of the longest length over which a segment's bound on the step holds as its
#: points accelerate (:func:`_longest_step`): the segment ends there.
HORIZON = 64
#: A contact point touching at rest is held only where its normal force exceeds this
#: many times the model's mass times its length over the run's span squared (a point that
#: nothing presses on its contact, as two balls touching in Newton's cradle, is apart).
FORCE_TOL = 1e-9
#: At a lift-off, the resting points whose normal forces are within this part of the
#: largest at the segment's start lift off together (a block pulled up at its centre).
LIFT_TOL = 1e-9
#: The most steps of one segment's solve (its dense output's size); a segment that runs out
#: goes on as the next.
SEGMENT_STEPS = 2048


def _nearest_gap(contacts, watched, origins, t, y, args, **kwargs):
    """The smallest gap [length] of the ``watched`` contact points (k,) in the state ``y``,
    each measured from its origin and raised by its lift (``origins``: the pair
    ``(origin (k,), lift (k,))`` [length] of :func:`_origins`; infinite where none is
    watched)."""
    origin, lift = origins
    return jnp.min(jnp.where(watched, (_gaps(contacts, y[0]) - origin) + lift, jnp.inf))


def _least_normal(problem, t, y):
    """The smallest normal force [force] of the contact points ``problem`` holds at rest
    in the state ``y`` (infinite where none is held)."""
    forces = normal_forces(problem, y[0], y[1], t)
    return jnp.min(forces, initial=jnp.inf)


def _row_speeds(problem, q, qd):
    """The relative speeds (nf,) of ``problem``'s reaction-dependent rows at ``(q, qd)``."""
    return rd.directions(problem.model, problem.reaction_dependent, q).T @ qd


#: A reaction-dependent row within this many stick bands at a segment's start has stopped:
#: the stop event's tolerance on a row that slowed into its band (:func:`_halt`,
#: :func:`_sliding_rows`).
HALT_BANDS = 2.0


def _stopped_rows(problem, q, qd):
    """The rows' relative speeds (nf,) and whether each has stopped (within
    :data:`HALT_BANDS` stick bands) at ``(q, qd)``."""
    v = _row_speeds(problem, q, qd)
    return v, jnp.abs(v) <= HALT_BANDS * rd.bands(problem.reaction_dependent)


def _slowest(problem, sliding, t, y):
    """How far the reaction-dependent rows moving at the segment's start are from their
    stick bands: the smallest over them of ``(sign(v0) v - b) / |v0|`` (``v0``: a row's
    speed at the start, ``b`` its stick band, ``sliding`` (nf,): the rows' ``v0``, 0 for
    those inside their bands at the start). It falls to zero where a row slows into its
    band (where its stick force would hold its speed), and the next segment's start halts
    it (:func:`_halt`). Infinite where no row moves."""
    elements = problem.reaction_dependent
    v = _row_speeds(problem, y[0], y[1])
    moving = sliding != 0.0
    speed = jnp.where(moving, jnp.abs(sliding), 1.0)
    ahead = (jnp.sign(sliding) * v - rd.bands(elements)) / speed
    return jnp.min(jnp.where(moving, ahead, jnp.inf), initial=jnp.inf)


def _sliding_rows(problem, y):
    """The speeds (nf,) of the reaction-dependent rows beyond twice their stick bands in
    the state ``y`` (the tolerance of :func:`_halt`), 0 for the rows within (see
    :func:`_slowest`): a row that stopped but that its limit cannot hold (it slides on the
    other way) is not watched for a stop it has just made."""
    v, stopped = _stopped_rows(problem, y[0], y[1])
    return jnp.where(stopped, 0.0, v)


@cached_jit(optimize=False)  # once a segment of a run with reaction-dependent forces
def _halt(problem: Problem, q, qd, w, t):
    """The velocities and works ``(qd, w)`` with the reaction-dependent rows that stick at
    ``(q, qd, t)`` (within twice their stick bands, the event's tolerance on a row that
    slowed into its band at a segment's end, :func:`_slowest`; within their limits)
    brought to rest (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so that a
    row stays where it stopped."""
    return problem.halt_sticking(q, qd, w, t, q, qd, _stopped_rows(problem, q, qd)[1])


def _event_terms(problem, contacts, watched, origin, length, force, sliding, t, y):
    """The event's terms (3,): the watched contact points' smallest gap (from ``origin``,
    :func:`_origins`) relative to ``length`` [length], the held points' smallest normal
    force relative to ``force`` [force] (the one at the segment's start) and the moving
    reaction-dependent rows' smallest relative speed (:func:`_slowest`); each falls to zero
    at its event: an impact, a lift-off, a stop."""
    gap = _nearest_gap(contacts, watched, origin, t, y, None) / length
    lift = _least_normal(problem, t, y) / force if n_holds(problem) else jnp.inf
    stop = _slowest(problem, sliding, t, y) if problem.reaction_dependent else jnp.inf
    return jnp.stack([gap, jnp.asarray(lift, gap.dtype), jnp.asarray(stop, gap.dtype)])


def _contact_event(problem, contacts, watched, origin, length, force, sliding, t, y, args,
                   **kwargs):  # fmt: skip
    """The event's condition: the smallest of :func:`_event_terms`."""
    terms = _event_terms(problem, contacts, watched, origin, length, force, sliding, t, y)
    return jnp.min(terms)


def _origins(contacts, q0, length):
    """Where each contact point's gap is measured from in a segment starting at ``q0``, and
    what it is raised by, ``(origin (k,), lift (k,))`` [length]: zero for a point apart; for
    a point touching at the start (gap within :data:`GAP_TOL`), its gap there where it is a
    rounding below zero, and the smallest positive number, so that its condition starts
    positive and a point touching and leaving does not hide another point's gap falling to
    zero in the first step (a downcrossing is a condition positive at one step's end and not
    at the next). No point is met below where it started: a margin would give energy."""
    g0 = _gaps(contacts, q0)
    touching = g0 <= GAP_TOL * length
    tiny = jnp.finfo(g0.dtype).tiny
    return jnp.where(touching, jnp.minimum(g0, 0.0), 0.0), jnp.where(touching, tiny, 0.0)


def _gaps(contacts, q):
    """The gaps ``g = -delta`` (k,) [length] of every rigid contact point, in order."""
    return jnp.concatenate([-jnp.atleast_1d(c.penetration(q)) for c in contacts])


def _slidings(contacts, q, qd):
    """The sliding speeds (k,) [velocity] of every rigid contact point along ``z x n``, in
    order (linear in ``qd``)."""
    return jnp.concatenate([jnp.atleast_1d(c.sliding(q, qd)) for c in contacts])


@cached_jit
def _segment(
    problem: Problem,
    contacts,
    watched,
    length,
    t0,
    t1,
    y0,
    ts,
    dt0,
    dtmax,
    rtol,
    atol,
    solver: str,
    steps: int,
):
    """One segment from ``t0`` to the first impact, lift-off or ``t1``: the states at
    ``ts`` (N,) clipped to the segment (``dt0``: the first step, ``dtmax`` the longest
    [time]; the ``watched`` contact points (k,): those apart or separating at ``t0``; the
    points ``problem`` holds at rest, :mod:`._resting`), the end time and state, which
    event ended it (2,): an impact (a watched gap falls to zero), a lift-off (a held
    point's normal force falls to zero), whether the solve failed (but for running out of
    its ``steps``) and its step count."""
    import diffrax
    import optimistix as optx

    from .integrators import _constrained as cs

    f = cs.equations_of_motion(problem)
    span = t1 - t0
    force = jnp.maximum(_least_normal(problem, t0, y0), jnp.finfo(y0[0].dtype).tiny)
    origin = _origins(contacts, y0[0], length)
    sliding = _sliding_rows(problem, y0) if problem.reaction_dependent else jnp.zeros(0)
    terms = (problem, contacts, watched, origin, length, force, sliding)
    condition = functools.partial(_contact_event, *terms)
    event = diffrax.Event(
        condition,
        # flip: the condition falls within the step (a downcrossing), so that the bisection
        # need not evaluate both ends to find out (nor check it by a host callback)
        root_finder=optx.Bisection(rtol=0.0, atol=TIME_TOL * jnp.maximum(span, 1.0), flip=True),
        direction=False,
    )
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(f),
        cs.runge_kutta(solver),
        t0,
        t1,
        None,
        y0,
        stepsize_controller=cs.FirstStep(rtol=rtol, atol=atol, dtmax=dtmax, first=dt0),
        saveat=diffrax.SaveAt(t1=True, dense=True),
        event=event,
        max_steps=steps,
        throw=False,
    )
    t_end = sol.ts[-1]
    y_end = jax.tree.map(lambda a: a[-1], sol.ys)
    inside = jnp.clip(ts, t0, t_end)
    ys = jax.vmap(sol.evaluate)(inside)
    which = jnp.argmin(_event_terms(*terms, t_end, y_end))
    hit = jnp.asarray(sol.event_mask) & (jnp.arange(3) == which)
    ran_out = sol.result == diffrax.RESULTS.max_steps_reached
    ended = (sol.result == diffrax.RESULTS.successful) | (
        sol.result == diffrax.RESULTS.event_occurred
    )
    failed = ~ended & ~ran_out
    return ys, t_end, y_end, hit, failed, sol.stats["num_steps"], sol.result._value


@cached_jit(optimize=False)  # a few times per run
def _impact_state(problem: Problem, contacts, q, qd, t, tol):
    """At an impact: the positions and velocities projected on the constraints, the
    constraint Jacobian (m, nq), the rows along which the constraints' impulses act (m, nq:
    the Jacobian's, but for a mixed problem's last ``p`` rows, the prescribed motions, whose
    impulses act along the unknown forces' directions ``B^T``), ``Phi_t`` (m,), the gaps (k,),
    their gradients (k, nq) and the tangential velocities' rows (k, nq): ``v_t = G_t qd``,
    the sliding speeds of :meth:`~mixdyn.model._compliant._Compliant.sliding`."""
    q, _ = problem.project_positions(q, t, tol)
    qd = problem.project_velocities(q, qd, t)
    c = problem.c
    J = c.phi_q(q, t) if c.m else jnp.zeros((0, q.shape[0]))
    D = J
    if problem.p:
        B = force_directions(problem.model, problem.unknown, q, qd, t)
        D = J.at[c.m - problem.p :].set(B.T)
    phit = c.phi_t(q, t) if c.m else jnp.zeros(0)
    g = _gaps(contacts, q)
    G = jax.jacfwd(lambda x: _gaps(contacts, x))(q)
    Gt = jax.jacfwd(lambda v: _slidings(contacts, q, v))(qd)
    return q, qd, J, D, phit, g, G, Gt


@cached_jit(optimize=False)  # a few times per run
def _normals(problem: Problem, q, qd, t):
    """The normal forces (k,) [force] of the contact points ``problem`` holds at rest."""
    return normal_forces(problem, q, qd, t)


@cached_jit(optimize=False)  # a few times per run
def _first_step(problem: Problem, contacts, watched, q, qd, t, h, tol):
    """The first step [time] of a segment from ``(q, qd)`` at ``t``: ``h``, or shorter where
    a ``watched`` contact point (k,) (apart or separating; not one held at rest) that touches
    (gap within ``tol``) separates and will close again: at most the time ``g' / |g''|`` to
    the apex of its gap, so that the step's end sees the gap open (an event is a gap that
    falls to zero from above, seen at the ends of steps), and at least ``1e-10 h`` (and 16
    rounding units of ``t``: a step that leaves the time as it is never ends). And the
    accelerations ``qdd`` (nq,) at the start (:func:`_longest_step`)."""
    qdd = problem.accelerations(q, qd, t)[0]

    def gaps(s):
        return _gaps(contacts, q + s * qd + 0.5 * s**2 * qdd)

    s0 = jnp.zeros((), q.dtype)
    rate = jax.jacfwd(gaps)(s0)
    accel = jax.jacfwd(jax.jacfwd(gaps))(s0)
    closing = watched & (gaps(s0) <= tol) & (rate > 0.0) & (accel < 0.0)
    apex = jnp.where(closing, rate / jnp.where(closing, -accel, 1.0), h)
    floor = jnp.maximum(1e-10 * h, 16.0 * jnp.finfo(q.dtype).eps * jnp.abs(t))
    return jnp.clip(jnp.min(apex), floor, h), qdd


def _point_rates(x, scale) -> float:
    """The largest rate of a body point (NumPy): of the (nq,) ``x`` (velocities or
    accelerations), its centre's plus its angular rate times the model's length ``scale``."""
    v = np.asarray(x).reshape(-1, 3)
    return float(np.max(np.hypot(v[:, 0], v[:, 1]) + np.abs(v[:, 2]) * scale)) if v.size else 0.0


def _longest_step(contacts, qd, qdd, dt_out, scale, gap=0.0) -> tuple[float, float]:
    """The longest step [time] of a segment starting at the velocities ``qd`` and
    accelerations ``qdd`` (nq,), and the segment's horizon [time]: no step longer than the
    shortest output interval, nor than the time in which the fastest body point moves
    :data:`PASS_FRACTION` of the smallest contact's effective radius ``d``, so that no pair
    passes through the other within a step (a pair seen apart at both ends of a step whose
    gap closed and opened again inside it would be missed; a thin shape, a segment, would be
    passed through). The point's speed may grow: with ``v0`` and ``a0`` its largest speed
    and acceleration at the start, the step ``h`` holds for a horizon of :data:`HORIZON`
    steps, ``(v0 + a0 HORIZON h) h = d``; the segment ends there (infinite where nothing
    accelerates) and the next takes the speed it reached.

    ``gap`` [length]: the least distance a body point must move for a watched point to touch
    (its gap against the ground, half its gap between two moving bodies). No pair touches
    before ``T`` with ``v0 T + a0 T**2 / 2 = gap``: where that is longer than the bounded
    segment, the segment runs to ``T`` with steps up to the output interval (a contact out
    of reach costs no steps), and the next one bounds them again from its own gaps."""
    v0, a0 = _point_rates(qd, scale), _point_rates(qdd, scale)
    d = PASS_FRACTION * min(float(np.min(np.asarray(c.effective_radius()))) for c in contacts)
    if v0 <= 0.0 and a0 <= 0.0:
        return dt_out, math.inf
    h = 2.0 * d / (v0 + math.sqrt(v0 * v0 + 4.0 * a0 * HORIZON * d))
    horizon = HORIZON * h if a0 > 0.0 else math.inf
    if gap > 0.0:
        free = 2.0 * gap / (v0 + math.sqrt(v0 * v0 + 2.0 * a0 * gap))  # v0 T + a0 T^2/2 = gap
        if free > min(horizon, HORIZON * h):
            return dt_out, free
    return min(dt_out, h), horizon


def _refuse_penetration(owner, gaps, scale) -> None:
    """A rigid contact that penetrates at the start (beyond :data:`GAP_TOL`) is an input
    error: its bodies would pass through each other unseen."""
    deep = np.flatnonzero(gaps < -GAP_TOL * scale)
    if deep.size:
        i = int(deep[np.argmin(gaps[deep])])
        raise ModelError(
            f"the rigid contact penetrates by {-gaps[i]:.4g} [length] at the start: place its "
            "bodies apart or touching (q0), or give it a compliant contact_model",
            owner[i].name,
        )


def _refuse_frictional(found, v, vt, name, t, fail) -> None:
    """End the run (``fail``) where a frictional impact (:func:`coulomb_impulse`'s
    ``found``, at the normal and tangential velocities ``v``, ``vt`` before) at the contact
    ``name`` jams (its normal impulse would pull) or gives the bodies energy (Newton's law
    with friction, see :mod:`._impact_friction`)."""
    if found.P < 0.0:
        fail(
            NumericalError(
                f"the impact at {name} jams: sliding with mu, its normal impulse would pull "
                f"(P = {found.P:.4g}; the friction's impulse drives the contact point into its "
                "contact); lower mu, or give the contact a compliant contact_model",
                t,
                (name,),
            )
        )
    if found.work > ENERGY_TOL * (abs(found.P * v) + abs(found.T * vt)):
        fail(
            NumericalError(
                f"the frictional impact at {name} would give the bodies energy "
                f"({found.work:.4g} [energy]: Newton's restitution with Coulomb friction where "
                "the slip reverses during the impact, see Stronge 1991); lower mu or the "
                "restitution, or give the contact a compliant contact_model",
                t,
                (name,),
            )
        )


def _message(code) -> str:
    """diffrax's message of its result ``code``."""
    import diffrax

    return diffrax.RESULTS._index_to_message[int(code)]


def refuse_rigid_method(model, options) -> None:
    """Rigid impacts are integrated by the projection method's Runge–Kutta solvers."""
    if rigid_contacts(model) and not isinstance(options, Projection):
        raise ModelError(
            f"rigid contacts are integrated with the projection method, not {options.method}: "
            "use method='projection' (the default), or give the contacts a compliant "
            "contact_model",
            rigid_contacts(model)[0].name,
            field="contact_model",
        )
    if rigid_contacts(model) and options.dt is not None:
        raise ModelError(
            "rigid contacts need the adaptive steps (their impacts are found by events): remove dt",
            rigid_contacts(model)[0].name,
        )


def simulate_impacts(case, progress=None) -> Result:
    """Integrate a forward or mixed ``case`` (:class:`~._simulate.Case`) whose model has rigid
    contacts, impact by impact, and build its result: the forward columns, ``work.impacts``
    (the kinetic energy the impacts took, accumulated [energy]), ``{contact}.impulse``
    (the contact's normal impulses accumulated [force * time]), with ``mu``
    ``{contact}.friction_impulse`` (its friction impulses on body j along ``z x n``,
    accumulated [force * time]) and ``{contact}.normal`` (its normal force while it rests
    [force], summed over its contact points; 0 while apart); ``stats["impacts"]``: each
    impact's ``t``, ``contact``, ``impulse``, ``normal_velocity_before`` and ``_after``,
    ``friction_impulse`` (on body j along ``z x n``; 0 without ``mu``),
    ``tangential_velocity_before`` and ``_after`` (the sliding speed along ``z x n``),
    ``sticks`` (whether the friction held the contact point; false without ``mu``), the
    constraints' impulses ``reactions`` (by constraint row), the positions ``q`` and the
    velocities ``qd_before`` and ``qd_after`` (model units); ``stats["rests"]``: each rest's
    ``contact``, ``start`` and ``end`` (its lift-off, or the run's end) [time]. A mixed run
    adds ``{force}.impulse`` per unknown force (its impulses accumulated [force * time],
    their work in ``work.constraints``) and each impact's unknown forces' impulses
    ``unknown`` (by name). ``progress``: an optional ``f(t)`` called at each output time
    once the run is done."""
    from ._simulate import (
        _post,
        _post_arrays,
        check_energy_balance,
        energy_tolerance,
        post_columns,
        post_kinds,
    )

    problem, ts, options = case.problem, np.asarray(case.ts, float), case.options
    model = problem.model
    contacts = rigid_contacts(model)
    sizes = [int(np.size(np.asarray(c.penetration(case.q0)))) for c in contacts]
    owner = [c for c, n in zip(contacts, sizes, strict=True) for _ in range(n)]
    # the part of a point's gap that one body's motion may close: all of it against the
    # ground, half of it between two moving bodies (a set's points: between two moving)
    closes = np.array([1.0 if len(c.body_indices()) == 1 else 0.5 for c in owner])
    holds = [hold(c, k, n) for c, n in zip(contacts, sizes, strict=True) for k in range(n)]
    index = {(c.name, k): i for i, (c, k) in enumerate(
        (c, k) for c, n in zip(contacts, sizes, strict=True) for k in range(n))}  # fmt: skip
    problems = {(): problem}

    def held_problem(resting):
        if resting not in problems:
            problems[resting] = holding(
                problem, tuple(holds[i] for i in resting), frictions(resting)
            )
        return problems[resting]

    def frictions(resting):
        """The held points' frictions: one element a contact with ``mu > 0``."""
        out = []
        for c, n in zip(contacts, sizes, strict=True):
            points = tuple(k for k in range(n) if index[c.name, k] in resting)
            if points and c.mu is not None and float(c.mu) > 0.0:
                out.append(friction_at(c, points, n, rest))
        return tuple(out)

    e_point = np.array([float(c.restitution) for c in owner])
    mu_point = np.array([np.nan if c.mu is None else float(c.mu) for c in owner])
    Minv = np.asarray(problem.Minv, float)
    span = float(ts[-1] - ts[0])
    scale = length_scale(model)
    rest = REST_SPEED * scale / span
    mass = float(sum(np.asarray(b.mass) for b in model.bodies))
    pressed = FORCE_TOL * mass * scale / span**2
    tol_pos = 1e-12 * max(scale, 1.0)
    N, nq = len(ts), int(np.size(case.q0))
    Q, QD, W = np.full((N, nq), np.nan), np.full((N, nq), np.nan), np.zeros((N, 2))
    W_imp, W_unk = np.zeros(N), np.zeros(N)
    P_acc = {c.name: np.zeros(N) for c in contacts}
    T_acc = {c.name: np.zeros(N) for c in contacts if c.mu is not None}
    unknown, p = problem.unknown, problem.p
    first_hold = problem.c.m - p  # the held points' rows: the len(resting) from here
    F_acc = {name: np.zeros(N) for name in unknown}
    impacts = {"t": [], "contact": [], "impulse": [], "normal_velocity_before": [],
               "normal_velocity_after": [], "friction_impulse": [],
               "tangential_velocity_before": [], "tangential_velocity_after": [], "sticks": [],
               "reactions": [], "q": [], "qd_before": [], "qd_after": []}  # fmt: skip
    if p:
        impacts["unknown"] = []
    rests = {"contact": [], "start": [], "end": []}
    t0 = float(ts[0])
    y = (jnp.asarray(case.q0), jnp.asarray(case.qd0), jnp.zeros(2))
    lost, worked, steps, segments = 0.0, 0.0, 0, 1
    carried = 0.0  # the mean step [time] of a segment that ran to its horizon, for the next
    totals = {c.name: 0.0 for c in contacts}
    T_totals = dict.fromkeys(T_acc, 0.0)
    F_totals = dict.fromkeys(unknown, 0.0)
    filled = np.zeros(N, bool)
    held_at: dict[tuple, list] = {}  # the output times of each set of resting points
    dt_out = float(np.min(np.diff(ts))) if N > 1 else span
    resting: tuple[int, ...] = ()  # the contact points at rest, held on their contacts
    started: dict[int, float] = {}
    released = np.zeros(len(owner), bool)  # points lifted off at t0 (separating from rest)

    def fail(err):
        err.partial = Partial.before(model, ts[filled], Q[filled], QD[filled], err.time)
        raise err

    def state_at(q, qd):
        """The impact state (:func:`_impact_state`) of the points resting now at ``t0``."""
        found = _impact_state(held_problem(resting), contacts, jnp.asarray(q), jnp.asarray(qd),
                              jnp.asarray(t0), tol_pos)  # fmt: skip
        return tuple(np.asarray(a) for a in found)

    def jump(qd, qd_new, lam, D):
        """Book a velocity jump ``qd -> qd_new`` with the constraints' impulses ``lam``
        (along the rows ``D``): the unknown forces' impulses (the last ``p``) and their
        work ``lam_F . B^T (qd- + qd+) / 2`` [energy] accumulated, the rest of the kinetic
        energy's change to the impacts. Returns the unknown forces' impulses (p,)."""
        nonlocal lost, worked
        F = lam[len(lam) - p :] if p else np.zeros(0)
        w = 0.5 * float(F @ (D[len(D) - p :] @ (qd + qd_new))) if p else 0.0
        for name, f in zip(unknown, F, strict=True):
            F_totals[name] += float(f)
        worked += w
        lost += 0.5 * (qd_new @ (qd_new / Minv) - qd @ (qd / Minv)) - w
        return F

    def record(i, P, lam, labels, q, qd, qd_new, G_i, F, Gt_i, T=0.0, sticks=False):
        """Record contact point ``i``'s impact: its impulse ``P``, normal velocities, the
        constraints' impulses ``lam`` by row ``labels``, the unknown forces' ``F``, the
        friction impulse ``T``, the tangential velocities (row ``Gt_i``) and whether the
        point sticks."""
        totals[owner[i].name] += P
        if owner[i].name in T_totals:
            T_totals[owner[i].name] += T
        impacts["t"].append(t0)
        impacts["contact"].append(owner[i].name)
        impacts["impulse"].append(float(P))
        impacts["normal_velocity_before"].append(float(G_i @ qd))
        impacts["normal_velocity_after"].append(float(G_i @ qd_new))
        impacts["friction_impulse"].append(float(T))
        impacts["tangential_velocity_before"].append(float(Gt_i @ qd))
        impacts["tangential_velocity_after"].append(float(Gt_i @ qd_new))
        impacts["sticks"].append(bool(sticks))
        n = len(lam) - p
        impacts["reactions"].append(dict(zip(labels[:n], lam[:n].tolist(), strict=False)))
        if p:
            impacts["unknown"].append(dict(zip(unknown, F.tolist(), strict=True)))
        impacts["q"].append(q)
        impacts["qd_before"].append(qd)
        impacts["qd_after"].append(qd_new)

    def release(i, t, watch=True):
        """Point ``i`` no longer rests at ``t``; ``watch``: its gap opens (it lifts off)."""
        nonlocal resting
        resting = tuple(j for j in resting if j != i)
        released[i] = watch
        start = started.pop(i)
        if t > start:  # a rest of no duration is none
            rests["contact"].append(owner[i].name)
            rests["start"].append(start)
            rests["end"].append(t)

    _refuse_penetration(owner, np.asarray(_gaps(contacts, jnp.asarray(case.q0))), scale)
    while True:
        # the impacts at t0: sequential, the fastest approach first; a point approaching
        # slower than the rest speed comes to rest (a plastic impulse, then held)
        q, qd, J, D, phit, g, G, Gt = state_at(y[0], y[1])
        struck: set[int] = set()  # the points struck at t0
        deep = np.flatnonzero(g < -MISSED * scale)
        if deep.size:
            i = int(deep[np.argmin(g[deep])])
            fail(
                NumericalError(
                    f"a contact point of {owner[i].name} passed into its contact unseen "
                    f"(penetration {-g[i]:.3g} [length]): an impact was missed; lower rtol "
                    "and atol",
                    t0,
                    (owner[i].name,),
                )
            )
        while True:  # ends: no approach left, or too many impacts
            v = G @ qd
            # a point lifted off at t0 is not held again unless an impulse turned it back
            free = ~(released & (v > -rest)) & ~np.isin(np.arange(len(owner)), resting)
            near = (g <= GAP_TOL * scale) & (v < rest) & free  # approaching, or at rest
            if not near.any():
                break
            i = int(np.argmin(np.where(near, v, np.inf)))
            if v[i] >= 0.0:  # touching, leaving slower than the rest speed: held as it is
                qd_new, lam, _ = impulse(Minv, J, phit, G[i], qd, 0.0, D)
                jump(qd, qd_new, lam, D)
                resting = tuple(sorted((*resting, i)))
                started[i] = t0
                q, qd, J, D, phit, g, G, Gt = state_at(q, qd_new)
                continue
            if len(impacts["t"]) >= MAX_IMPACTS:
                fail(
                    ImpactAccumulationError(
                        f"impacts accumulate at {owner[i].name} ({len(impacts['t'])} "
                        f"impacts, approach speed {-v[i]:.3g} still above the rest speed "
                        f"{rest:.3g} [velocity] = {REST_SPEED:g} model lengths per span): "
                        "the contacts chatter without coming to rest; use a compliant "
                        "contact_model",
                        t0,
                        (owner[i].name,),
                    )
                )
            if i in struck:  # struck again at t0: the touching points settle together
                held = np.isin(np.arange(len(owner)), resting)
                touching = (g <= GAP_TOL * scale) & ((v < rest) | held)
                # the joints', drivers' and prescribed motions' rows (not the held points')
                keep = np.r_[0:first_hold, first_hold + len(resting) : len(phit)]
                found = settle(Minv, J[keep], phit[keep], G, qd, touching, rest, D[keep],
                               Gt, mu_point)  # fmt: skip
                if found is not None:
                    qd_new, settled, lam = found.qd, found.points, found.lam
                    F = jump(qd, qd_new, lam, D[keep])
                    labels = problem.c.active_labels
                    for j, push, T_j, stuck in zip(settled, found.P, found.T, found.sticks,
                                                   strict=True):  # fmt: skip
                        started.setdefault(j, t0)
                        record(j, push, lam, labels, q, qd, qd_new, G[j], F, Gt[j], T_j,
                               bool(stuck))  # fmt: skip
                    for j in set(resting) - set(settled):
                        release(j, t0)
                    resting = tuple(sorted(settled))
                    q, qd, J, D, phit, g, G, Gt = state_at(q, qd_new)
                    struck.clear()
                    continue
            # the points approaching at this instant struck together (a box landing flat,
            # two blocks meeting face on): Newton's and Coulomb's laws at each
            together = np.flatnonzero(near & (v < -rest))
            together = together[~np.isin(together, list(struck))]
            if i in together and len(together) > 1:
                found = coulomb_impulses(Minv, J, phit, G[together], Gt[together], qd,
                                         e_point[together], mu_point[together], D)  # fmt: skip
                if (
                    found is not None
                    and found.P.min() >= 0.0
                    and consistent(found, G[together], Gt[together], qd)
                ):
                    qd_new, lam = found.qd, found.lam
                    pull = -PULL_TOL * float(np.max(found.P))
                    if all(lam[first_hold + k] >= pull for k in range(len(resting))):
                        F = jump(qd, qd_new, lam, D)
                        labels = held_problem(resting).c.active_labels
                        for j, P_j, T_j, stuck in zip(together, found.P, found.T, found.sticks,
                                                      strict=True):  # fmt: skip
                            record(j, P_j, lam, labels, q, qd, qd_new, G[j], F, Gt[j], T_j,
                                   bool(stuck))  # fmt: skip
                        struck.update(together.tolist())
                        # a perfectly plastic point (e = 0) stays on its contact: it rests
                        for j in together[e_point[together] == 0.0].tolist():
                            resting = tuple(sorted((*resting, j)))
                            started[j] = t0
                        q, qd, J, D, phit, g, G, Gt = state_at(q, qd_new)
                        continue
            struck.add(i)
            comes_to_rest = -v[i] < rest
            e_i = 0.0 if comes_to_rest else e_point[i]
            T, sticks = 0.0, False
            if np.isnan(mu_point[i]) or comes_to_rest:  # friction at rest: RestFriction
                qd_new, lam, P = impulse(Minv, J, phit, G[i], qd, e_i, D)
            else:
                found = coulomb_impulse(Minv, J, phit, G[i], Gt[i], qd, e_i, mu_point[i], D)
                qd_new, lam, P, T, sticks = found[:5]
                _refuse_frictional(found, v[i], float(Gt[i] @ qd), owner[i].name, t0, fail)
            pull = -PULL_TOL * abs(float(P))
            pulled = [j for k, j in enumerate(resting) if lam[first_hold + k] < pull]
            if pulled:  # a resting point the impact pulls away lifts off: again without it
                release(pulled[0], t0)
                q, qd, J, D, phit, g, G, Gt = state_at(q, qd)
                continue
            if abs(G[i] @ qd_new + e_i * v[i]) > IMPULSE_TOL * max(abs(v[i]), rest):
                fail(
                    SingularityError(
                        f"the impact at {owner[i].name} cannot reverse its normal velocity: "
                        "the joints, drivers and prescribed motions fix it (a driven "
                        "mechanism against a rigid stop takes an infinite impulse); free the "
                        "driven or prescribed coordinate, or give the contact a compliant "
                        "contact_model",
                        t0,
                        (owner[i].name,),
                    )
                )
            F = jump(qd, qd_new, lam, D)
            labels = held_problem(resting).c.active_labels
            record(i, P, lam, labels, q, qd, qd_new, G[i], F, Gt[i], T, sticks)
            qd = qd_new
            if comes_to_rest or e_i == 0.0:  # stopped on its contact (plastic): it rests
                resting = tuple(sorted((*resting, i)))
                started[i] = t0
                q, qd, J, D, phit, g, G, Gt = state_at(q, qd)
        # a resting point that the motion pulls away (a tensile normal force) lifts off; one
        # touching without a normal force (nothing presses it on) is apart
        forces = np.zeros(0)
        while resting:
            forces = np.asarray(_normals(held_problem(resting), jnp.asarray(q),
                                         jnp.asarray(qd), jnp.asarray(t0)))  # fmt: skip
            if not np.all(np.isfinite(forces)):
                fail(
                    NumericalError(
                        "the resting points' normal forces are not finite: the frictions "
                        "at them and at the joints find no forces (self-locking)",
                        t0,
                        tuple(sorted({owner[j].name for j in resting})),
                    )
                )
            if forces.min() > pressed:
                break
            k = int(np.argmin(forces))  # pulled away (N < 0), or touching without a force
            release(resting[k], t0, watch=bool(forces[k] < -pressed))
        current, pressing = held_problem(resting), float(np.max(forces, initial=0.0))
        y = (jnp.asarray(q), jnp.asarray(qd), y[2])
        if current.reaction_dependent:  # the rows that stopped held where they stopped
            y = (y[0], *_halt(current, *y, jnp.asarray(t0)))
            qd = np.asarray(y[1])
        h = min(max(FIRST_STEP * span, carried), float(ts[1] - ts[0]) if N > 1 else span)
        apart = (g > GAP_TOL * scale) | (G @ qd > 0.0) | released
        watched = apart & ~np.isin(np.arange(len(owner)), resting)
        dt0, qdd0 = _first_step(current, contacts, jnp.asarray(watched), y[0], y[1],
                                jnp.asarray(t0), h, GAP_TOL * scale)  # fmt: skip
        gap = float(np.min((closes * g)[watched])) if watched.any() else 0.0
        dtmax, horizon = _longest_step(contacts, qd, np.asarray(qdd0), dt_out, scale, gap)
        dt0 = jnp.minimum(dt0, dtmax)
        t1 = min(float(ts[-1]), t0 + horizon)
        ys, t_end, y_end, hit, failed, n, code = _segment(
            current, contacts, jnp.asarray(watched), jnp.asarray(scale), jnp.asarray(t0),
            jnp.asarray(t1), y, jnp.asarray(ts), dt0, jnp.asarray(dtmax),
            jnp.asarray(options.rtol, float),
            jnp.asarray(options.atol, float), options.solver,
            min(SEGMENT_STEPS, int(options.max_steps)),
        )  # fmt: skip
        t_end, steps, hit = float(t_end), steps + int(n), np.asarray(hit)
        # a segment that ran to its horizon (no impact, no event) hands its mean step on: the
        # next goes on from there rather than from a first step sized for an impact
        carried = (t_end - t0) / max(int(n), 1) if t_end >= t1 and not hit.any() else 0.0
        last = t_end >= ts[-1]
        take = (ts >= t0) & ((ts <= t_end) if last else (ts < t_end)) & ~filled
        Q[take], QD[take], W[take] = (np.asarray(a)[take] for a in ys)
        W_imp[take], W_unk[take] = lost, worked
        for name in P_acc:
            P_acc[name][take] = totals[name]
        for name in T_acc:
            T_acc[name][take] = T_totals[name]
        for name in F_acc:
            F_acc[name][take] = F_totals[name]
        if resting:
            held_at.setdefault(resting, []).extend(np.flatnonzero(take).tolist())
        filled |= take
        if bool(failed):
            fail(NumericalError(f"the integration between impacts failed: {_message(code)}", t_end))
        if steps > options.max_steps:
            fail(StepSizeError(f"more than max_steps = {options.max_steps} steps", t_end))
        if not np.all(np.isfinite(np.asarray(y_end[1]))):
            fail(NumericalError("the velocities are not finite", t_end))
        if last:
            break
        if t_end <= t0 and not hit.any():
            fail(StepSizeError("the integration did not advance", t0))
        segments += 1
        released[:] = False
        if hit[1] and resting:  # lift-off: the points whose normal forces fell to zero
            forces = np.asarray(_normals(current, y_end[0], y_end[1], jnp.asarray(t_end)))
            lifted = forces <= LIFT_TOL * pressing
            lifted[int(np.argmin(forces))] = True  # together, within the event's tolerance
            for i in [j for j, up in zip(resting, lifted, strict=True) if up]:
                release(i, t_end)
        t0, y = t_end, y_end
    for i in list(resting):
        release(i, float(ts[-1]))

    if progress is not None:
        for t in ts:
            progress(float(t))
    qdd, _, ratio, cols = _post(problem, ts, Q, QD, case.n_drivers)
    qdd, ratio = np.array(qdd), np.array(ratio)
    extra = {k: np.array(v) for k, v in cols.items()}
    normals = {c.name: np.zeros(N) for c in contacts}
    rubbed = {c.name: np.zeros(N) for c in contacts if c.mu is not None and float(c.mu) > 0}
    for held, rows in held_at.items():  # the resting times: their own constrained problem
        rows = np.asarray(rows, int)
        hp = held_problem(held)
        arrays = _post_arrays(hp, ts[rows], Q[rows], QD[rows])
        qdd_h, mu_h, ratio_h, cols_h = post_columns(hp, arrays, case.n_drivers)
        qdd[rows], ratio[rows] = np.asarray(qdd_h), np.asarray(ratio_h)
        for key, col in extra.items():
            if key in cols_h:
                col[rows] = np.asarray(cols_h[key])
        for pos, i in zip(hold_positions(hp), held, strict=True):
            normals[owner[i].name][rows] += np.asarray(mu_h)[:, pos]
        for name in rubbed:
            if f"{name}.friction" in cols_h:
                rubbed[name][rows] = np.asarray(cols_h[f"{name}.friction"])
    extra["work.nonconservative"], extra["work.constraints"] = W[:, 0], W[:, 1] + W_unk
    extra["work.impacts"] = W_imp
    for name, acc in P_acc.items():
        extra[f"{name}.impulse"] = acc
        extra[f"{name}.normal"] = normals[name]
    for name, acc in T_acc.items():
        extra[f"{name}.friction_impulse"] = acc
    for name, col in rubbed.items():
        extra[f"{name}.friction"] = col
    for name, acc in F_acc.items():
        extra[f"{name}.impulse"] = acc
    balance_cols = dict(extra, **{"work.nonconservative": W[:, 0] + W_imp})
    tol = energy_tolerance(case.energy_tol, options)
    balance = check_energy_balance(problem, ts, Q, balance_cols, ratio, options, tol)
    kinds = post_kinds(problem, case.n_drivers)
    kinds["work.impacts"] = "energy"
    kinds.update({f"{c.name}.impulse": "impulse" for c in contacts})
    kinds.update({f"{name}.friction_impulse": "impulse" for name in T_acc})
    kinds.update({f"{name}.impulse": "impulse" for name in unknown})
    kinds.update({f"{c.name}.normal": "force" for c in contacts})
    kinds.update({f"{name}.friction": "force" for name in rubbed})
    stats = {
        "method": options.method,
        "options": dict(options.recorded() if case.recorded is None else case.recorded),
        "segments": segments,
        "steps": steps,
        "impacts": {
            k: (v if k in ("reactions", "contact", "unknown") else np.asarray(v))
            for k, v in impacts.items()
        },
        "rests": {k: (v if k == "contact" else np.asarray(v)) for k, v in rests.items()},
        "max_violation": float(np.max(extra["constraint.violation"])),
        "min_pivot_ratio": float(np.min(ratio)),
        "energy_balance_error": balance,
        "constraint_rows": problem.c.active_labels,
        "unknown_forces": problem.unknown,
        "linear_solver": problem.c.linear_solver.name,
    }
    stats.update(case.stats)
    return Result(
        kind=case.kind,
        model=model,
        t=ts,
        q=Q,
        qd=QD,
        qdd=qdd,
        extra=extra,
        kinds=kinds,
        stats=stats,
    )


__all__ = ["impulse", "refuse_rigid_method", "simulate_impacts"]
