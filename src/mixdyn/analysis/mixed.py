"""Mixed dynamics: some forces unknown, as many motions prescribed, the rest free.

Two solvers share one problem definition (see :mod:`._problem`):

* ``"partition"`` — the paper's method, equations (28)–(29): each unknown force acts along one
  coordinate ``j`` whose motion is prescribed; the independent coordinates ``i`` are chosen
  automatically by pivoted LU (or given, as the paper gives "the rotation of body 3") and
  chosen again where ``Phi_qk`` becomes ill-conditioned.
* ``"augmented"`` — the general form ``[M, Phi_q^T, -B; Phi_q, 0, 0; Psi_q, 0, 0]``: any
  driver type as prescribed motion, any force element of unknown magnitude, collocated or not.

Both integrate with the forward-dynamics integrators; the prescribed motions are rheonomic
constraints. Before running, solvability is checked: as many unknown forces as prescribed
motions, each prescribed motion free of the joints, and the unknown forces able to produce the
prescribed accelerations (the matrix ``W = Psi_q N (N^T M N)^-1 N^T B`` non-singular, with ``N``
a basis of the motions the joints allow).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import ClassVar

import equinox as eqx
import numpy as np

from .._arrays import as_f64
from .._hints import count, listed
from ..equations import Constraints, force_directions
from ..errors import ModelError, SolvabilityError
from ..linalg import BandedSolver, DenseSolver, LinearSolver, as_linear_solver
from ..model import CoordinateDriver, Driver, Model, PointDriver, QuinticHermite
from ..model._compliant import rigid_contacts
from ..model._element import Resolver
from ..runtime._programs import cached_jit
from . import _setup
from ._prepare import Prepared, dynamic_start
from ._problem import Problem
from ._setup import Setup, keyword_setup
from ._simulate import (
    ENERGY_TOL,
    Integrated,
    output_times,
    refuse_reaction_dependent_in,
    require_masses,
    simulate,
)
from ._structure import _jac
from .methods import IntegratorOptions
from .result import Result

SOLVERS = ("augmented", "partition")

#: ``B`` at one state, compiled once per model structure and list of names.
_directions = cached_jit(force_directions, optimize=False)  # once per mixed run


def prescribe(result: Result, coordinate: str, name: str | None = None) -> Driver:
    """A prescribed motion that replays a coordinate of an earlier result.

    The law is a quintic Hermite interpolant of the result's positions, velocities and
    accelerations at its output times, so the replayed motion is C2 and matches the samples'
    derivatives exactly.

    Args:
        result: an earlier result (forward, kinematic...).
        coordinate: ``"body.x"``, ``"body.y"``, ``"body.phi"`` or a point coordinate
            ``"body.point.x"`` / ``"body.point.y"``.
        name: the driver's name (default ``"prescribed <coordinate>"``).
    """
    name = name or f"prescribed {coordinate}"
    parts = coordinate.split(".")
    if len(parts) == 2:
        k = result.model.coordinate_index(coordinate)
        law = QuinticHermite(result.t, result.q[:, k], result.qd[:, k], result.qdd[:, k])
        return CoordinateDriver(name, parts[0], parts[1], law=law)
    if len(parts) == 3 and parts[2] in ("x", "y"):
        ref = f"{parts[0]}.{parts[1]}"
        p, v, a = result.point(ref)
        c = "xy".index(parts[2])
        return PointDriver(
            name, ref, parts[2], law=QuinticHermite(result.t, p[:, c], v[:, c], a[:, c])
        )
    raise ModelError("use 'body.x', 'body.y', 'body.phi' or 'body.point.x'", coordinate)


def bind_prescribed(model: Model, prescribed) -> tuple[Driver, ...]:
    """The prescribed motions bound to the bodies of ``model``: the constraints that
    :func:`mixed` and :func:`check_mixed` add to the joints (checks made before a run use
    this too, so that they constrain the same coordinates as the run)."""
    r = Resolver(model.ground, model.bodies)
    return tuple(d.bind(r) for d in prescribed)


def _null_space(A):
    """An orthonormal basis (n, n - rank) of the null space of ``A`` (m, n): the right
    singular vectors of the singular values at most ``eps * max(m, n) * s_max`` (the rule of
    ``scipy.linalg.null_space``, by NumPy's SVD)."""
    if not A.size:
        return np.eye(A.shape[1])
    _, s, vh = np.linalg.svd(A, full_matrices=True)
    tol = np.amax(s, initial=0.0) * np.finfo(s.dtype).eps * max(A.shape)
    return vh[int(np.sum(s > tol)) :, :].T.conj()


def _mobility(problem_c: Constraints, model: Model, q, qd, t, mk: int, names):
    """``W`` (p, len(names)): prescribed accelerations produced per unit of each force."""
    J = np.asarray(_jac(problem_c, as_f64(q), as_f64(t)))
    Phi_q, Psi_q = J[:mk], J[mk:]
    N = _null_space(Phi_q)
    Mdiag = np.asarray(model.mass_diagonal)
    B = np.asarray(_directions(model, tuple(names), as_f64(q), as_f64(qd), as_f64(t)))
    red = N.T @ (Mdiag[:, None] * N)
    # Accelerations of the prescribed motions per unit generalized force, (p, nq); its norm
    # times |B| is the scale against which W is judged singular.
    A = Psi_q @ N @ np.linalg.solve(red, N.T)
    scale = np.linalg.norm(A, 2) * max(np.max(np.linalg.norm(B, axis=0), initial=0.0), 1e-300)
    return A @ B, Psi_q @ N, scale


def _check_solvable(model, c, q, qd, t, mk, unknown, prescribed):
    p = len(unknown)
    W, PsiN, scale = _mobility(c, model, q, qd, t, mk, unknown)
    pnames = [d.name for d in prescribed]
    # Prescribed motions must be independent of the joints and of each other.
    s_psi = np.linalg.svd(PsiN, compute_uv=False) if PsiN.size else np.zeros(0)
    if p and (s_psi.size < p or s_psi[-1] < 1e-9 * max(s_psi[0], 1e-300)):
        raise SolvabilityError(
            "the prescribed motions are not independent: the joints (or the "
            "other prescribed motions) already fix them; prescribe another "
            "coordinate",
            ", ".join(pnames),
        )
    s = np.linalg.svd(W, compute_uv=False)
    if s[-1] > 1e-9 * scale:
        return
    # Name what cannot act on what, and suggest forces of the model that could.
    candidates = [f.name for f in model.forces if f.has_magnitude]
    Wc, _, cscale = _mobility(c, model, q, qd, t, mk, candidates) if candidates else (None,) * 3
    suggestion = ""
    if candidates:
        working = []
        for combo in itertools.combinations(range(len(candidates)), p):
            sv = np.linalg.svd(Wc[:, combo], compute_uv=False)
            if sv[-1] > 1e-6 * cscale:
                working.append(", ".join(candidates[i] for i in combo))
        if working:
            suggestion = (
                " Forces of the model that could produce these motions: "
                + "; or ".join(working[:5])
                + "."
            )
    for a, name in enumerate(unknown):
        if np.abs(W[:, a]).max() <= 1e-9 * scale:
            raise SolvabilityError(
                f"the unknown force cannot affect the {listed(pnames, 'prescribed motion')} "
                f"(it acts only on motions the joints or the prescribed "
                f"motions already fix).{suggestion}",
                name,
            )
    for b, pname in enumerate(pnames):
        if np.abs(W[b]).max() <= 1e-9 * scale:
            raise SolvabilityError(
                f"no unknown force ({', '.join(unknown)}) can act on this prescribed motion."
                f"{suggestion}",
                pname,
            )
    raise SolvabilityError(
        f"the unknown forces {', '.join(unknown)} cannot produce the prescribed motions "
        f"{', '.join(pnames)} independently (the pairing matrix is singular).{suggestion}",
        ", ".join(unknown),
    )


def _collocation(model, unknown, prescribed, q, qd, t):
    """Coordinates ``j`` of the partition solver, checking each unknown force is collocated."""
    B = np.asarray(_directions(model, tuple(unknown), as_f64(q), as_f64(qd), as_f64(t)))
    driven = {d.index: d.name for d in prescribed if isinstance(d, CoordinateDriver)}
    j = []
    for a, name in enumerate(unknown):
        col = B[:, a]
        nz = np.flatnonzero(np.abs(col) > 1e-12 * max(np.abs(col).max(), 1e-300))
        if nz.size != 1 or int(nz[0]) not in driven:
            raise SolvabilityError(
                "the partition solver needs every unknown force to act along a single "
                "coordinate (x, y force at a centre of mass, or a torque) whose motion is "
                "prescribed by a coordinate driver; use solver='augmented' for this problem",
                name,
            )
        j.append(int(nz[0]))
    if len(set(j)) != len(j) or set(j) != set(driven):
        raise SolvabilityError(
            "each prescribed coordinate needs exactly one unknown force "
            "along it for the partition solver; use solver='augmented'",
            ", ".join(unknown),
        )
    return j


def _collocated(model, c: Constraints, q, qd, t, mk: int, unknown):
    """For each unknown force ``a``, the prescribed motion ``b`` (0..p-1) along whose gradient
    it acts, ``B[:, a] = s_a Psi_q[b]^T`` (a force along the coordinate or the distance it
    prescribes, a torque on the body whose angle it prescribes); None where some force has no
    such partner. Checked at the start and at two perturbed states, so that a direction that
    is parallel only by coincidence of the start pose is not taken."""
    p = len(unknown)
    rng = np.random.default_rng(0)
    q, qd = np.asarray(q), np.asarray(qd)
    ok = np.ones((p, p), dtype=bool)
    for k in range(3):
        dq = 0.0 if k == 0 else 1e-2 * (np.abs(q) + 1.0) * rng.normal(size=q.size)
        dqd = 0.0 if k == 0 else rng.normal(size=q.size)
        qk, qdk, tk = q + dq, qd + dqd, t
        Psi = np.asarray(_jac(c, as_f64(qk), as_f64(tk)))[mk:]
        B = np.asarray(_directions(model, tuple(unknown), as_f64(qk), as_f64(qdk), as_f64(tk)))
        nB = np.linalg.norm(B, axis=0)
        nP = np.linalg.norm(Psi, axis=1)
        dot = B.T @ Psi.T  # (p unknowns, p prescribed)
        ok &= (nB[:, None] > 0) & (nP[None, :] > 0)
        ok &= np.abs(dot) >= (1.0 - 1e-12) * nB[:, None] * nP[None, :]
    for perm in itertools.permutations(range(p)):
        if all(ok[a, perm[a]] for a in range(p)):
            return perm
    return None


def _drivers(value) -> tuple[Driver, ...]:
    """``prescribed``: a tuple of drivers (one driver alone: a tuple of one)."""
    out = (value,) if isinstance(value, Driver) else tuple(value)
    for d in out:
        if not isinstance(d, Driver):
            raise ModelError(
                f"a prescribed motion is a driver (md.CoordinateDriver(...), md.prescribe(...)), "
                f"got {type(d).__name__}",
                "prescribed",
            )
    return out


def _solver(value) -> str:
    if value not in SOLVERS:
        raise ModelError(
            f"unknown mixed solver {value!r}; use 'augmented' or 'partition'", "solver"
        )
    return str(value)


def _independent(value) -> tuple[str, ...] | None:
    return None if value is None else _setup.names(value, "independent")


class Mixed(Integrated):
    """Mixed dynamics as a value: the unknown forces that produce the prescribed motions
    while the rest of the mechanism moves freely (``md.mixed``'s options, for
    :func:`~mixdyn.prepare` and the studies).

    Preparing it runs every check of :func:`check_mixed` (the counts, the names, the
    solvability, the partition) and makes the consistent start.

    Attributes:
        prescribed: drivers (any type) prescribing ``p`` motions; see also :func:`prescribe`.
        unknown: names of ``p`` force elements of the model whose magnitude is unknown.
        solver: ``"augmented"`` (default, general) or ``"partition"`` (the paper's method).
        independent: for ``"partition"``, the independent coordinates (``["coupler.phi"]``),
            or None (default: chosen by pivoted LU).
        method, energy_tol, q0, qd0, hold, linear_solver: as in
            :class:`~mixdyn.analyses.Forward` (the Runge–Kutta method of an adaptive
            integrator is chosen by its object, ``method=md.Projection(solver="dopri8")``;
            the sparse linear solver takes the ``"augmented"`` solver only, see
            :func:`~mixdyn.mixed`).
    """

    name: ClassVar[str] = "mixed"

    _: dataclasses.KW_ONLY
    prescribed: tuple[Driver, ...] = eqx.field(converter=_drivers)
    unknown: tuple[str, ...] = eqx.field(converter=lambda v: _setup.names(v, "unknown"))
    solver: str = eqx.field(default="augmented", converter=_solver)
    independent: tuple[str, ...] | None = eqx.field(default=None, converter=_independent)

    def _start_forces(self) -> tuple[str, ...]:
        return self.unknown

    def _shares_setup(self, setup: Setup) -> bool:
        # collocated forces (the partition solver takes only those): the solvability is
        # structural, not a matter of the masses; members with rigid contacts run one by
        # one (each impact by impact)
        if rigid_contacts(setup.model):
            return False
        return bool(setup.problem.collocated) or self.solver == "partition"

    def _initial(self, model: Model, t0: float, given: Prepared | None = None) -> Prepared:
        """The start with the model's drivers and the prescribed motions bound to its
        bodies (:func:`bind_prescribed`)."""
        prescribed = bind_prescribed(model, self.prescribed)
        return dynamic_start(
            model, t0, given, drivers=(*model.drivers, *prescribed), **self._start()
        )

    def _prepare(self, model: Model, t0: float, given: Prepared | None = None) -> Setup:
        """Everything a mixed run does before integrating: checks, consistent start,
        problem (the start and its mobility analysis checked on ``given`` where given)."""
        solver, method = self.solver, self.method
        if rigid_contacts(model):  # (the impacts' module is loaded where there are some)
            from ._impacts import refuse_rigid_method

            refuse_rigid_method(model, method)
        refuse_reaction_dependent_in(model, method)
        require_masses(model)
        unknown = self.unknown
        prescribed = bind_prescribed(model, self.prescribed)
        if len(unknown) != len(prescribed):
            raise SolvabilityError(
                f"{count(len(unknown), 'unknown force')} but "
                f"{count(len(prescribed), 'prescribed motion')}; "
                "a mixed problem needs one prescribed motion per unknown force",
                ", ".join(unknown) or "unknown",
            )
        if not unknown:
            raise SolvabilityError("no unknown force: use forward dynamics instead", "unknown")
        existing = {e.name for e in (*model.joints, *model.drivers, *model.forces)}
        for d in prescribed:
            if d.name in existing:
                raise ModelError("a prescribed motion needs a name not used by the model", d.name)
        if len(set(unknown)) != len(unknown):
            raise SolvabilityError("an unknown force is named twice", ", ".join(unknown))
        for name in unknown:
            f = model.element(name)
            if not getattr(f, "has_magnitude", False):
                raise SolvabilityError(
                    "only a force element with a magnitude (point force, torque, "
                    "actuator) can be unknown",
                    name,
                )
        prep = dynamic_start(
            model, t0, given, drivers=(*model.drivers, *prescribed), **self._start()
        )
        q, qd, report = prep.q, prep.qd, prep.report
        bad = [n for n in report.redundant_drivers if n in {d.name for d in prescribed}]
        if bad:
            raise SolvabilityError(
                "this prescribed motion is already fixed by the joints or other "
                "drivers; prescribe a coordinate that is free",
                ", ".join(bad),
            )
        partition = solver == "partition"
        c = prep.constraints(independent_rows_only=partition or method.independent_rows)
        mk = c.m - len(prescribed)
        _check_solvable(model, c, q, qd, t0, mk, unknown, prescribed)
        j_index, i_index = (), ()
        independent = self.independent
        if partition:
            j_index = _collocation(model, unknown, prescribed, q, qd, t0)
            n_i = model.nq - len(j_index) - mk
            if independent is not None:
                i_index = [model.coordinate_index(x) for x in independent]
                if len(i_index) != n_i:
                    raise SolvabilityError(
                        f"the partition needs {n_i} independent coordinate(s) (3n - j - k), "
                        f"got {len(i_index)}",
                        ", ".join(independent),
                    )
                if set(i_index) & set(j_index):
                    raise SolvabilityError(
                        "an independent coordinate cannot be prescribed", ", ".join(independent)
                    )
                k_index = sorted(set(range(model.nq)) - set(i_index) - set(j_index))
                J = np.asarray(_jac(c, as_f64(q), as_f64(t0)))[:mk]
                sv = np.linalg.svd(J[:, k_index], compute_uv=False)
                if sv.size and sv[-1] < 1e-9 * sv[0]:
                    raise SolvabilityError(
                        "with these independent coordinates the dependent block Phi_qk is "
                        "singular (the remaining coordinates cannot be solved from the "
                        "joints); choose other independent coordinates or leave the choice "
                        "automatic",
                        ", ".join(independent),
                    )
        collocated = None
        if not partition:
            collocated = _collocated(model, c, q, qd, t0, mk, unknown)
        linear_solver = self.linear_solver
        path = c.with_linear_solver(linear_solver).linear_solver
        if path.banded and partition:
            if isinstance(as_linear_solver(linear_solver), BandedSolver):
                raise ModelError(
                    "the sparse linear solver cannot solve this mixed problem: the partition "
                    "solver is dense; use solver='augmented', or linear_solver='dense' or "
                    "'auto'",
                    ", ".join(unknown),
                )
            path = DenseSolver()
        c = c.with_linear_solver(path)
        problem = Problem(model, c, unknown, solver, j_index, i_index, collocated or ())
        stats = dict(
            solver=solver,
            independent=tuple(independent or ()),
            prescribed=tuple(d.name for d in prescribed),
            collocated=bool(problem.collocated),
        )
        return Setup(self, model, t0, prep, problem, stats)

    def _run(self, setup: Setup, t, progress=None) -> Result:
        if rigid_contacts(setup.model):  # integrated impact by impact
            from ._impacts import simulate_impacts

            return simulate_impacts(self._case(setup, t), progress)
        return simulate(self._case(setup, t), progress)


def check_mixed(
    model: Model,
    prescribed,
    unknown,
    *,
    t0: float = 0.0,
    solver: str = "augmented",
    independent=None,
    q0=None,
    qd0=None,
    hold=(),
    linear_solver: str | LinearSolver = "auto",
    prepared: Prepared | None = None,
) -> None:
    """Check that a mixed problem is solvable, without integrating it.

    Runs every check of :func:`mixed` at the start time ``t0`` [time]: the counts, the unknown
    forces' names, a consistent start, the prescribed motions' independence, the pairing of
    forces and motions, and (for ``solver="partition"``) the collocation and the partition.
    Returns None; raises the same errors as :func:`mixed`. The same checks are made by
    ``mixdyn.prepare(model, mixdyn.analyses.Mixed(...), t0=t0)``, which also returns the
    set-up to run. ``prepared`` (deprecated): a start made beforehand, as in :func:`mixed`.
    """
    analysis = Mixed(
        prescribed=prescribed,
        unknown=unknown,
        solver=solver,
        independent=independent,
        q0=q0,
        qd0=qd0,
        hold=hold,
        linear_solver=linear_solver,
    )
    keyword_setup(model, analysis, float(t0), prepared=prepared)


def mixed(
    model: Model,
    t,
    *,
    prescribed,
    unknown,
    solver: str = "augmented",
    independent=None,
    method: str | IntegratorOptions = "projection",
    rtol: float | None = None,
    atol: float | None = None,
    dt: float | None = None,
    q0=None,
    qd0=None,
    hold=(),
    progress=None,
    linear_solver: str | LinearSolver = "auto",
    energy_tol: float | str | None = ENERGY_TOL,
    prepared: Prepared | None = None,
    **options,
) -> Result:
    """Mixed dynamics: find the unknown forces that produce the prescribed motions while the
    rest of the mechanism moves freely under its known forces.

    Args:
        model: the mechanism (every body with mass and inertia > 0).
        t: (N,) increasing output times [time].
        prescribed: drivers (any type) prescribing ``p`` motions; see also :func:`prescribe`.
        unknown: names of ``p`` force elements of the model whose magnitude is unknown (their
            law in the model is ignored; an actuator's spring and damper still act).
        solver: ``"augmented"`` (general) or ``"partition"`` (the paper's method).
        independent: for ``"partition"``, the independent coordinates ``i`` (e.g.
            ``["coupler.phi"]``); default: chosen by pivoted LU.
        method, rtol, atol, dt, q0, qd0, hold, progress, energy_tol, **options: as in
            :func:`~mixdyn.forward` (``solver`` is the mixed solver: the Runge–Kutta method
            of an adaptive integrator is chosen by an options object,
            ``method=md.Projection(solver="dopri8")``).
        linear_solver: a :class:`~mixdyn.LinearSolver`, or its name: ``"dense"``, ``"sparse"`` or
            ``"auto"`` (the default: sparse for large mechanisms of small bandwidth, see
            :mod:`mixdyn.linalg`). The sparse path (banded Cholesky of the Schur complement ``C M^-1
            C^T``) takes the ``"augmented"`` solver: *collocated* unknown forces, each acting along
            the gradient of one prescribed motion (``B = Psi_q^T`` up to a scale per force: a force
            along the coordinate or distance it prescribes, a torque on the body whose angle it
            prescribes, as in the paper's example), solve the symmetric system directly; other
            unknown forces (``G != C^T``, a non-symmetric Schur complement ``C M^-1 G``) by a
            rank-``p`` Sherman–Morrison–Woodbury update of the symmetric one. The ``"partition"``
            solver stays on the dense path: ``"auto"`` takes it silently, ``"sparse"`` raises a
            :class:`ModelError`. The consistent start (assembly, velocities) takes the path asked
            for in any case; the solvability checks of the start state are dense.
        prepared: deprecated (a DeprecationWarning names the new spelling): the start of an
            earlier set-up (``setup.start``) with the model's drivers followed by the
            prescribed motions bound to the bodies (:func:`bind_prescribed`), from the same
            start time, ``q0``, ``qd0``, ``hold`` and ``linear_solver``, as
            ``mixdyn.prepare(model, mixdyn.analyses.Mixed(...), t0=t[0], start=...)`` takes
            it; a start made otherwise (other prescribed motions included) is refused
            (:class:`~mixdyn.errors.ModelError`); the solvability checks are run on it in
            any case.

    Returns:
        A :class:`Result` with the motion, a column per unknown force (named after it, in force
        or torque units) and its power (``{name}.power``), joint reactions and energies.
        A model with rigid contacts (``contact_model="rigid"``, ``method="projection"``) is
        integrated from impact to impact as in :func:`~mixdyn.forward`
        (:mod:`mixdyn.analysis._impacts`): at an impact the prescribed motions' velocities
        are kept, the unknown forces taking impulses, accumulated in ``{name}.impulse``
        [force * time] (each impact's in ``stats["impacts"]["unknown"]``) and their work in
        ``work.constraints``; the contacts' columns as in a forward run.

    Raises:
        SolvabilityError: the counts differ, an unknown force cannot affect the prescribed
            motions, a prescribed motion is already fixed, or the partition is singular.
        ModelError: ``linear_solver="sparse"`` for a problem the sparse path cannot solve
            (see above), or a bad option.
    """
    ts = output_times(t)
    analysis, recorded = Mixed._from_keywords(
        ts,
        dict(
            prescribed=prescribed,
            unknown=unknown,
            solver=solver,
            independent=independent,
            method=method,
            rtol=rtol,
            atol=atol,
            dt=dt,
            q0=q0,
            qd0=qd0,
            hold=hold,
            linear_solver=linear_solver,
            energy_tol=energy_tol,
            **options,
        ),
    )
    setup = keyword_setup(model, analysis, float(ts[0]), recorded, prepared)
    return analysis._run(setup, ts, progress)


__all__ = ["Mixed", "bind_prescribed", "check_mixed", "mixed", "prescribe"]
