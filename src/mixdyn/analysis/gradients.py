"""A dynamic run as a pure JAX function of some of its model's numbers, to differentiate.

:func:`differentiable` sets a run up once (options, consistent start, equations: like
:func:`~mixdyn.forward`) and returns ``f(theta) -> {"q", "qd", "w"}``: the motion at the
output times as a function of the chosen numbers ``theta`` (masses, inertias, the numbers of
force elements and their laws). ``f`` is traced by JAX like any function: ``jax.grad``,
``jax.jacfwd``, ``jax.jit`` and ``jax.vmap`` apply.

Derivatives go through the integrators' ``diffrax.diffeqsolve`` loop (projection,
partitioning, Baumgarte; their inner Newton iterations have a fixed count), in the mode chosen
when the function is made:

- ``derivatives="reverse"`` (default): ``jax.grad``, ``jax.jacrev``, ``jax.vjp``, through
  diffrax's checkpointed adjoint, the outputs in diffrax's write-only buffers; for a scalar
  of many numbers (measured, ``benchmarks/gradient.py``: about 4.4 times the run for 11
  numbers);
- ``derivatives="forward"``: ``jax.jvp``, ``jax.jacfwd`` (diffrax's ``ForwardMode``); for
  many outputs of few numbers (a least-squares fit's Jacobian).

An inverse run (``analysis=Inverse(...)``) is differentiable too: its motion comes from the
drivers alone (the kinematic analysis, made once: the numbers of bodies and forces do not move
it), and ``f(theta)`` gives the reactions and driver efforts of that motion as functions of
the numbers (the multipliers' solve, per output time, traced). A kinematic run depends on no
number of a body or force: refused.

Generalized-alpha (its Newton iteration is a ``while_loop``) is refused. The derivative is that
of the discrete solution with the step sizes held (the controller's choice is not
differentiated, as in diffrax's PID controller), the linear solves and the position projection
differentiated implicitly (as exact solves and an exact projection onto the constraints); it
agrees with the exact sensitivity to the order of the tolerances (tested against central
finite differences to 1e-6, through singular positions too).

A run that fails inside ``f`` (step limit, step collapse, non-finite state) cannot raise
there: its outputs are NaN, and so are their derivatives in both modes (``jax.grad``,
``jax.jacrev``, ``jax.jvp``, ``jax.jacfwd``): the failure flag enters the outputs through
:func:`nan_if_failed`, whose derivative is the tangent times 1 after a good run and times NaN
after a failed one (a plain ``jnp.where(ok, y, nan)`` would give the failed run a zero
derivative). No finite wrong number or derivative comes out of a failed run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import paths
from ..errors import ModelError
from ..model import Model
from ..model._compliant import refuse_rigid
from ._keywords import study_analysis
from ._setup import Analysis, Setup
from .forward import Forward
from .integrators import INTEGRATORS
from .inverse import Inverse
from .kinematic import Kinematic, output_times
from .mixed import Mixed


@jax.custom_jvp
def nan_if_failed(ok, y):
    """``y`` where ``ok``, NaN elsewhere, with the derivative NaN where not ``ok``.

    Args:
        ok: () or broadcastable to ``y``, bool: whether the run succeeded.
        y: (...) the run's output (any units).

    Returns:
        (...) ``y``, or NaN after a failed run. Its tangent is ``dy * s`` with ``s = 1`` where
        ``ok`` and NaN elsewhere: linear in ``dy``, so reverse mode (its transpose) gives the
        cotangent times ``s`` too, NaN for a failed run and exactly the cotangent for a good
        one (no NaN leaks into a good run's derivative, as ``where``'s unused branch would).
    """
    return jnp.where(ok, y, jnp.nan)


@nan_if_failed.defjvp
def _nan_if_failed_jvp(primals, tangents):
    ok, y = primals
    _, dy = tangents
    return nan_if_failed(ok, y), dy * jnp.where(ok, 1.0, jnp.nan)


def differentiable(
    model: Model,
    t,
    params: Sequence[str],
    *,
    analysis: Analysis | str | None = None,
    derivatives: str = "reverse",
    **kwargs,
) -> tuple[Callable[[jax.Array], dict[str, jax.Array]], np.ndarray]:
    """The run of ``model`` over ``t`` as a function of the numbers named by ``params``.

    Args:
        model: the mechanism at the nominal numbers (where the run is set up).
        t: (N,) output times [time].
        params: paths of scalar numbers of bodies or force elements (``"slider.mass"``,
            ``"crank.inertia"``, ``"F1.law.amplitude"``, ``"spring.stiffness"``: see
            :mod:`mixdyn.paths`), model units. Numbers of joints and drivers (they shape the
            constraints and the start) are refused.
        analysis: the analysis value (:mod:`mixdyn.analyses`): ``Forward(...)`` (default:
            ``Forward()``), ``Mixed(...)`` or ``Inverse(...)``, e.g.
            ``analysis=md.analyses.Forward(method=md.Projection(rtol=1e-10))``.
        derivatives: ``"reverse"`` (default: ``jax.grad``, ``jax.jacrev``) or ``"forward"``
            (``jax.jacfwd``, ``jax.jvp``).
        **kwargs: deprecated (a DeprecationWarning names the value to give instead): the
            analysis' keywords (``method``, ``rtol``, ``prescribed``...) with ``analysis`` an
            analysis' name (``"forward"``, ``"mixed"`` or ``"inverse"``).

    Returns:
        ``(f, theta0)``: ``f(theta)`` with ``theta`` (P,) gives ``{"q": (N, nq), "qd": (N, nq),
        "w": (N, 2)}`` (positions, velocities and accumulated works at the output times,
        model units; NaN if the run failed, and so are their derivatives); for an inverse
        run ``{"q", "qd", "qdd"}`` (the prescribed motion) and every reaction and
        driver-effort column by name, each (N,)
        (``"B.Fx"``, ``"motor"``, as in :func:`~mixdyn.inverse`'s result); ``theta0`` (P,)
        the nominal numbers.

    Raises:
        ModelError: an analysis that is not differentiable (kinematic, static, a
            generalized-alpha run), a bad path, or a number of a joint or driver.
    """
    value, _ = study_analysis("md.differentiable", analysis, t, kwargs)
    make = _DIFFERENTIABLE.get(type(value))
    if make is None:
        raise ModelError(
            f"a {value.name} analysis is not differentiable here; use Forward(...), "
            "Mixed(...) or Inverse(...)",
            "analysis",
        )
    if derivatives not in ("reverse", "forward"):
        raise ModelError(
            f"derivatives must be 'reverse' or 'forward', got {derivatives!r}", "derivatives"
        )
    if isinstance(params, str) or not params:
        raise ModelError("give params as a list of paths, e.g. ['slider.mass']", "params")
    getters, theta0 = [], []
    for path in params:
        get, shape = paths.getter(model, path)
        if paths.group(model, path) not in ("bodies", "forces"):
            raise ModelError(
                "a joint's or driver's numbers shape the constraints and the consistent start: "
                "not differentiable here; name a number of a body or a force element",
                f"params {path!r}",
            )
        if shape != ():
            raise ModelError(f"a scalar number is needed, this one has shape {shape}", path)
        getters.append(get)
        theta0.append(float(get(model)))
    return make(value, model, t, getters, derivatives), np.asarray(theta0)


def _kinematic(value: Kinematic, model, t, getters, derivatives):
    raise ModelError(
        "a kinematic run depends on no number of a body or force (only on the geometry "
        "and the drivers): nothing to differentiate; use analysis=Inverse(...) for efforts "
        "and reactions",
        "analysis",
    )


def _integrated(value: Forward | Mixed, model: Model, t, getters, derivatives):
    """``theta -> {"q", "qd", "w"}`` of a forward or mixed run: set up once, the integrator
    traced (see the module's documentation)."""
    if not value.method.differentiable:
        raise ModelError(
            f"{value.method.method} is not differentiable (its Newton iteration is a "
            "while_loop); use method='projection', 'partitioning' or 'baumgarte'",
            "method",
        )
    refuse_rigid(model, "md.differentiable (an impact's instant and jump are not differentiated)")
    ts = output_times(t)
    setup: Setup = value._prepare(model, float(ts[0]))
    case = value._case(setup, ts)
    integrate_one = INTEGRATORS[case.options.method]
    ts = jnp.asarray(case.ts, dtype=jnp.float64)
    options = case.options.as_argument()

    def f(theta):
        theta = jnp.asarray(theta, dtype=jnp.float64)
        m = case.problem.model
        for k, get in enumerate(getters):
            m = eqx.tree_at(get, m, theta[k])
        problem = eqx.tree_at(lambda p: p.model, case.problem, m)
        traj = integrate_one(
            problem, ts, case.q0, case.qd0, options, progress=None, derivatives=derivatives
        )
        ok = traj.status == 0
        return {k: nan_if_failed(ok, getattr(traj, k)) for k in ("q", "qd", "w")}

    return f


def _inverse(value: Inverse, model: Model, t, getters, derivatives):
    """``theta -> columns`` of an inverse run: the kinematics made once, the multipliers'
    solve traced (see the module's documentation)."""
    from ._reactions import driver_efforts, reaction_columns
    from ._simulate import _post_arrays

    ts = output_times(t)
    setup = value._prepare(model, float(ts[0]))
    kin = value._kinematics(setup, ts)
    problem = setup.problem
    Q, QD, QDD = (jnp.asarray(a) for a in (kin.q, kin.qd, kin.qdd))
    tj = jnp.asarray(ts)
    n_drivers = len(model.drivers)

    def f(theta):
        theta = jnp.asarray(theta, dtype=jnp.float64)
        m = problem.model
        for k, get in enumerate(getters):
            m = eqx.tree_at(get, m, theta[k])
        p = eqx.tree_at(lambda p: p.model, problem, m)
        _, mu, _, R, powers, *_ = _post_arrays(p, tj, Q, QD)
        out = {"q": Q, "qd": QD, "qdd": QDD}
        out.update(reaction_columns(p.c, R))
        out.update(
            {k: v for k, v in driver_efforts(p.c, mu, powers, n_drivers).items() if "." not in k}
        )
        return out

    return f


#: The analyses :func:`differentiable` makes a function of, by class.
_DIFFERENTIABLE = {
    Forward: _integrated,
    Mixed: _integrated,
    Inverse: _inverse,
    Kinematic: _kinematic,
}

__all__ = ["differentiable", "nan_if_failed"]
