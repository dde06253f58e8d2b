"""A quasi-static sweep held as arrays.

The first member whose start can be made is prepared like its single run
(:meth:`~.statics.QuasiStatic._prepare`: the structure, the rows kept, the names). Every
member's start is then made by one vectorized program, :data:`~._schedule.CHUNK` members a
call, as its set-up makes it: its rough pose assembled (:func:`~._assembly.assemble`'s
damped Gauss-Newton steps, the held coordinates kept) and its rank analysed; where the
varied numbers reach only masses, inertias and forces (which do not enter the start) every
member takes member 0's start instead. The same program runs the single run's time loop
(:func:`_equilibria`): at each output time the joints closed again from the equilibrium
before, Newton's method on ``R(q, lambda) = 0`` with the single run's scales, steps and step
halving (:func:`~.statics._equilibrium`), then the joints' reactions and contact forces.

The program flags a member where its single run would act otherwise: the joints not closed,
the constraint rows at a start not clearly independent (the single run's rank analysis
there, :data:`~._structure.FULL_RANK_RATIO`), or Newton's method not converged. A flagged
member is run like a single run (its error, an :class:`~mixdyn.errors.AssemblyError` or a
:class:`~mixdyn.errors.ConvergenceError` with its time, kept as its outcome); every other
member's set-up and :class:`~.result.Result` are made when it is read
(:class:`~._stacked.LazyResults`: its stiffness' smallest eigenvalues by
:func:`~.statics._reduced_stiffness` then).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints, applied_forces, largest_load
from ..errors import MixdynError, ModelError
from ..linalg import min_norm_step
from ..model import Model
from ..runtime._programs import cached_jit
from . import _setup
from ._assembly import length_scale, start_q
from ._prepared_members import finished, in_chunks, prepare_each, stack_leaves
from ._prepared_members import stack as stack_trees
from ._reactions import (
    contact_columns,
    driver_efforts,
    joint_reactions,
    reaction_columns,
    reaction_kinds,
)
from ._schedule import CHUNK, batched_map, collector_paused
from ._stacked import LazyResults, add_points, body_columns
from ._structure import FULL_RANK_RATIO
from .kinematic import output_times
from .result import Result, in_units
from .statics import QuasiStatic, _reduced_stiffness, _residual_of

#: The assembly's tolerance, relative to the model's size (:func:`~._assembly.assemble`).
ASSEMBLY_TOL = 1e-12
#: Most iterations of the assembly (:func:`~._assembly.assemble`'s default).
ASSEMBLY_MAX_ITER = 100
#: Most halvings of a Newton step (the single run's stop at a step below 1e-6 after 20).
MAX_HALVINGS = 60


def _equilibria(model, c, q_start, L, ts, tol, max_iter, held=()):
    """One member's equilibria at the times ``ts``, each from the one before, as
    :class:`~.statics.QuasiStatic` finds them.

    Args:
        model, c: the member's model and its constraint set of independent rows (every row).
        q_start: (nq,) the rough start [model units], assembled here as the set-up
            assembles it (:func:`~._prepare.kinematic_start`: the joints closed at t = 0
            with the coordinates ``held`` kept, the rank analysed at ``ts[0]``), or the
            set-up's assembled start (then kept).
        L: the model's length scale [length] (:func:`~._assembly.length_scale`).
        ts: (N,) the output times [time].
        tol, max_iter: the analysis' Newton tolerance [-] and iterations at most per time.
        held: the indices of the coordinates the first assembly holds (static).

    Returns:
        Per time (leading axis N): ``q`` (nq,), ``lam`` (m,), the Newton iterations, the
        joints' reactions (n_joints, 3), the joints' contact columns, and ``ok``: False
        where the single run would act otherwise (module docstring).
    """
    nq, m = model.nq, c.m
    D = jnp.tile(jnp.stack([L, L, jnp.ones_like(L)]), len(model.bodies))

    def R(x, t):
        return _residual_of(model, c, t, x)

    def rank_certain(q, t):
        """The full set's rows clearly independent (:func:`~._structure._full_row_rank`)."""
        if c.n_full == 0:
            return jnp.array(True)
        J = c.jacobian(q, t).dense()
        norms = jnp.linalg.norm(J, axis=1)
        An = J / norms[:, None]
        d = jnp.diag(jnp.linalg.cholesky(An @ An.T)) ** 2
        fine = jnp.all(jnp.isfinite(d)) & jnp.all(d > 0) & jnp.all(norms > 0)
        return fine & (jnp.sqrt(jnp.min(d) / jnp.max(d)) > FULL_RANK_RATIO)

    joints = Constraints(c.joints, (), nq)  # the assembly's: the joints alone, at t = 0
    t_joints = jnp.zeros(())

    def assembled(q, held=()):
        """The joints closed from ``q`` as :func:`~._assembly.assemble` closes them
        (damped Gauss-Newton, its step halved while the residual grows), the coordinates
        ``held`` kept at their values in ``q``, and whether they closed."""
        if joints.n_full == 0:
            return q, jnp.array(True)
        tol_a = ASSEMBLY_TOL * L
        idx = np.asarray(held, dtype=int)
        kept, rows = q[idx], jnp.eye(nq)[idx]  # the held coordinates' rows

        def residual(q):
            r = jnp.concatenate([joints.full(q, t_joints), q[idx] - kept])
            return r, jnp.max(jnp.abs(r), initial=0.0)

        def jacobian(q):
            return jnp.concatenate([joints.phi_q(q, t_joints), rows])

        def gauss_newton(s):
            q, r, err, it, _ = s
            damping = jnp.minimum(err / L, 1.0) * 1e-3
            step = min_norm_step(jacobian(q), r, damping=damping)
            r_new, err_new = residual(q + step)

            def halve(h):
                alpha = 0.5 * h[0]
                return (alpha, *residual(q + alpha * step))

            alpha, r_new, err_new = jax.lax.while_loop(
                lambda h: (h[2] > err) & (h[0] > 1e-3), halve, (1.0, r_new, err_new)
            )
            finite = jnp.isfinite(err_new)
            q_new = jnp.where(finite, q + alpha * step, q)
            return (
                q_new,
                jnp.where(finite, r_new, r),
                jnp.where(finite, err_new, err),
                it + 1,
                ~finite,
            )

        q, _, err, _, _ = jax.lax.while_loop(
            lambda s: (s[2] > tol_a) & (s[3] < ASSEMBLY_MAX_ITER) & ~s[4],
            gauss_newton,
            (q, *residual(q), 0, jnp.array(False)),
        )
        return q, err <= tol_a

    def at(q, t):
        """The equilibrium at ``t`` from the assembled start ``q``
        (:func:`~.statics._equilibrium`)."""
        Q0 = applied_forces(model, q, jnp.zeros_like(q), t)
        F0 = largest_load(model, q, t, D) / L
        if m:
            J0 = c.jacobian(q, t).dense()
            rows = jnp.max(jnp.abs(J0) * D, axis=1)
            rows = jnp.where(rows > 0.0, rows, 1.0)
            lam = jnp.linalg.lstsq(D[:, None] * J0.T, D * Q0)[0]
        else:
            rows, lam = jnp.ones(0), jnp.zeros(0)

        def scaled(r):
            work = jnp.abs(r[:nq]) * D / L
            most = jnp.max(work, initial=0.0)
            force = jnp.maximum(jnp.maximum(F0, most), 1e-300)
            return jnp.maximum(most / force, jnp.max(jnp.abs(r[nq:]) / rows, initial=0.0))

        energy = jnp.maximum(F0, 1e-300) * L
        row_w = jnp.concatenate([D / energy, 1.0 / rows])
        col_w = jnp.concatenate([D, energy / rows])
        x = jnp.concatenate([q, lam])
        r = R(x, t)

        def newton(s):
            x, r, err, it = s
            K = jax.jacfwd(lambda y: R(y, t))(x)
            step = col_w * jnp.linalg.lstsq(row_w[:, None] * K * col_w[None, :], -row_w * r)[0]

            def halved(s):  # the step at 1, 1/2, 1/4...: the first accepted taken
                a = 0.5 * s[0]
                rt = R(x + a * step, t)
                et = scaled(rt)
                accepted = jnp.all(jnp.isfinite(rt)) & ((et < err) | (a < 1e-6))
                return a, x + a * step, rt, et, s[4] + 1, accepted

            _, x, r, err, _, _ = jax.lax.while_loop(
                lambda s: ~s[5] & (s[4] < MAX_HALVINGS),
                halved,
                (2.0, x, r, err, 0, jnp.array(False)),
            )
            return x, r, err, it + 1

        x, r, err, it = jax.lax.while_loop(
            lambda s: (s[2] > tol) & (s[3] < max_iter), newton, (x, r, scaled(r), 0)
        )
        ok = (err <= tol) & jnp.all(jnp.isfinite(x)) & jnp.all(jnp.isfinite(r))
        return x[:nq], x[nq:], it, ok

    def one(carry, k):
        t = ts[k]
        start, closed = assembled(carry)  # an assembled start is kept (no iteration)
        q, lam, it, ok = at(start, t)
        reactions = joint_reactions(c, q, t, lam)
        contacts = contact_columns(c, q, lam[:m])
        ok = ok & closed & rank_certain(start, t)
        return q, (q, lam, it, reactions, contacts, ok)

    closed = jnp.array(True)
    if held:  # the first start's holds (the later starts hold nothing)
        q_start, closed = assembled(q_start, held)
    out = jax.lax.scan(one, q_start, jnp.arange(len(ts)))[1]
    return (*out[:-1], out[-1] & closed)


def _equilibria_batch(width: int, model, c, q_start, L, ts, tol, max_iter, held=()):
    """:func:`_equilibria` of a batch of members (leading axis: the member), ``width`` at a
    time vectorized."""

    def one(x):
        mm, cc, q, length, tl = x
        return _equilibria(mm, cc, q, length, ts, tl, max_iter, held)

    return batched_map(one, (model, c, q_start, L, tol), width)


_equilibria_batch_jit = cached_jit(_equilibria_batch)


@dataclasses.dataclass(frozen=True)
class StaticStack:
    """The members of a quasi-static sweep, each set up, as arrays.

    Attributes:
        setup: member ``i`` -> its set-up (:class:`~._setup.Setup`, its single run's, made
            when first asked for; a start that cannot be made raises its error).
        count: M, the number of members.
        ts: (N,) the output times [time].
        arrays: each member's ``(q, lam, iterations, reactions, contacts, ok)`` at each
            time, leading axes (member, time) (:func:`_equilibria`);
            a failed member's rows are its copy of another member's.
        models: each member's model (M,), or the one model whose points every member
            shares.
    """

    setup: Callable[[int], _setup.Setup | None]
    count: int
    ts: np.ndarray
    arrays: tuple
    models: Model | Sequence[Model]

    kind = "statics"

    @property
    def model(self) -> Model:
        """A member's model (the names, units and structure every member shares)."""
        return self.models if isinstance(self.models, Model) else self.models[0]

    def flagged(self) -> np.ndarray:
        """(M,) the members to run like a single run (module docstring)."""
        return ~np.asarray(self.arrays[-1]).all(axis=1)

    def run(self, i: int) -> Result:
        """Member ``i`` run like its single run (its named error raised)."""
        return _setup.run(self.setup(i), self.ts)

    def result(self, i: int) -> Result:
        """Member ``i``'s result from the arrays, as :meth:`~.statics.QuasiStatic._run`
        makes it."""
        setup = self.setup(i)
        model, prep = setup.model, setup.start
        c = prep.constraints(independent_rows_only=True)
        q, lam, it = (np.asarray(a[i]) for a in self.arrays[:3])
        extra, kinds = _extra(c, prep.drivers, lam, self.arrays[3][i], self.arrays[4], i)
        eig = [_smallest(model, c, float(t), q[k], lam[k]) for k, t in enumerate(self.ts)]
        zeros = np.zeros_like(q)
        stable = [bool(np.isnan(e) or e > 0) for e in eig]
        return Result(
            kind="statics",
            model=model,
            t=np.asarray(self.ts),
            q=q,
            qd=zeros,
            qdd=zeros,
            extra=extra,
            kinds=kinds,
            stats={
                "newton_iterations": int(np.sum(it)),
                "min_eigenvalue": [float(e) for e in eig],
                "min_eigenvalue_unit": model.units.unit("energy"),
                "stable": all(stable),
                "unstable_at": [float(t) for t, s in zip(self.ts, stable, strict=True) if not s],
            },
        )

    def columns(
        self,
        arrays,
        results: LazyResults,
        errors: dict,
        output_units=None,
        points: Sequence[str] = (),
    ) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """Every result column of every member, (M, N) each (``t``: (N,)), with the points'
        columns, in ``output_units``, and their units; a failed member's rows NaN (as
        :func:`~._stacked.columns`); a member run like its single run (flagged) has its
        result's rows."""
        first = next((i for i in range(self.count) if i not in errors), None)
        if first is None:
            raise ValueError("no member of the sweep succeeded: there is nothing to label")
        result: Result = results[first]
        setup = self.setup(first)
        c = setup.start.constraints(independent_rows_only=True)
        q, lam = np.array(self.arrays[0]), np.asarray(self.arrays[1])
        redone = [int(i) for i in np.flatnonzero(self.flagged()) if i not in errors]
        for i in redone:
            q[i] = results[i].q
        zeros = np.zeros_like(q)
        cols, units = body_columns(result.model, self.ts, q, zeros, zeros), result.units()
        extra, _ = _extra(c, setup.start.drivers, lam, np.asarray(self.arrays[3]), self.arrays[4])
        for k in extra if redone else ():
            extra[k] = np.array(extra[k], dtype=float)
            for i in redone:
                extra[k][i] = results[i][k]
        cols.update(extra)
        if set(cols) != set(result.columns()):  # pragma: no cover - a column made elsewhere
            raise RuntimeError("the stacked columns differ from a member's result's")
        if points:
            add_points(cols, units, self.models, points, q, zeros, zeros)
        if errors:
            bad = np.asarray(sorted(errors))
            for k, v in cols.items():
                if k != "t":
                    v = np.array(v, dtype=float)
                    v[bad] = np.nan
                    cols[k] = v
        return in_units(result, cols, units, output_units)


def _smallest(model, c, t, q, lam) -> float:
    """The reduced stiffness' smallest eigenvalue at one equilibrium, NaN without free
    degrees of freedom (:func:`~.statics._reduced_stiffness`)."""
    eig = _reduced_stiffness(model, c, t, q, lam)
    return float(eig[0]) if eig.size else float("nan")


def _extra(c, drivers, lam, reactions, contacts, i=None) -> tuple[dict, dict]:
    """The reactions', contacts' and drivers' columns (:func:`~.statics._result`) and their
    kinds, from the multipliers ``lam`` (..., m), the reactions (..., n_joints, 3) and the
    contact columns (each (M, N); member ``i``'s where given)."""
    extra = {k: np.asarray(v) for k, v in reaction_columns(c, reactions).items()}
    extra.update({k: np.asarray(v if i is None else v[i]) for k, v in contacts.items()})
    efforts = driver_efforts(c, lam, np.zeros_like(lam), len(drivers))
    kinds = reaction_kinds(c)
    for d in drivers:
        extra[d.name] = np.asarray(efforts[d.name])
        kinds[d.name] = d.effort_kind
    return extra, kinds


def run(
    members: Sequence[Model],
    value: QuasiStatic | Sequence[QuasiStatic],
    t,
    threads: int,
    on_member: Callable[[int], None] | None,
    describe: Callable[[int], str],
    shared: bool = False,
    seconds: dict | None = None,
) -> tuple[StaticStack, LazyResults, dict[int, MixdynError]] | None:
    """The members of a quasi-static sweep started, run by one vectorized program and
    screened (module docstring): ``(stack, results, errors)``; None where their constraint
    sets or models differ in structure, their values in ``max_iter`` or ``hold``, the first
    start keeps fewer than every constraint row, or a joint is a gear mesh (then member by
    member). ``value``: the analysis value, or one per member; ``threads``: unused (the
    program makes the starts; the signature is :func:`._kinematic_members.run`'s);
    ``shared``: the members differ only in masses, inertias and forces (and share one
    value), member 0's start is every member's (``members`` may then be a
    :class:`VariedModels`: the members' models stacked from its columns, each member's model
    made only when its result is read); ``seconds``: if given, filled with the wall times of
    the set-up, the program (``equilibria``) and the finishing [s].

    Raises:
        ModelError: a member's input error (with its index in a note).
    """
    clock = time.perf_counter()
    seconds = {} if seconds is None else seconds
    ts = output_times(t, minimum=1)
    t0, count = float(ts[0]), len(members)
    values = [value] * count if isinstance(value, QuasiStatic) else list(value)
    if len({v.max_iter for v in values}) > 1:
        return None
    if any(hasattr(j, "separation") for j in members[0].joints):
        return None  # a mesh's separation is checked at every start

    def setup_of(i: int) -> _setup.Setup:
        setup = _setup.prepare(members[i], values[i], t0=t0)
        _setup.check_start(setup, ts, accelerations=False)
        return setup

    # The first member whose start can be made is prepared now (the structure, the rows
    # kept, the names); every other member's start is made by the program, its set-up
    # when its result is read or its single run is needed.
    made: dict[int, _setup.Setup] = {}
    errors: dict[int, MixdynError] = {}
    for i in range(1 if shared else count):
        done, failed = prepare_each(1, lambda _, i=i: setup_of(i), 1, lambda _, i=i: describe(i))
        if not failed:
            made[i] = done[0]
            break
        errors[i] = failed[0]
    first = next(iter(made.values()), None)
    if shared and errors:
        errors = dict.fromkeys(range(count), errors[0])

    def setup(i: int) -> _setup.Setup:
        """Member ``i``'s set-up (its single run's), made once.

        Raises:
            MixdynError: its start cannot be made (a ModelError with its index in a note).
        """
        if i not in made:
            if shared:
                start = dataclasses.replace(first.start, model=members[i])
                made[i] = dataclasses.replace(first, model=members[i], start=start)
            else:  # a start that cannot be made raises its error
                try:
                    made[i] = setup_of(i)
                except ModelError as err:
                    err.add_note(f"in member {i} of the sweep{describe(i)}")
                    raise
        return made[i]

    models = members[0] if shared else list(members)
    if first is None:
        stack = StaticStack(setup, count, ts, (), models)
        return (stack, *finished(count, np.zeros(0), stack.run, errors, on_member))
    c0 = first.start.constraints(independent_rows_only=True)
    if c0.m != c0.n_full:
        return None  # a redundant row: the members' rows kept may differ
    if shared and isinstance(members, VariedModels):
        flat, stacked_models = None, members.stacked
    else:
        with collector_paused():
            flat = [jax.tree_util.tree_flatten(m) for m in members]  # once a member

        def stacked_models(idx):
            return stack_leaves(flat[0][1], [flat[i][0] for i in idx])

    treedef = jax.tree_util.tree_structure(c0)
    if shared:
        cs = [jax.tree_util.tree_leaves(c0)] * count
        rough, L = [first.start.q] * count, [length_scale(first.model)] * count
        held = ()
    else:
        with collector_paused():
            for i in range(count):
                if i not in made and i not in errors:
                    _checked(members[i], ts, lambda i=i: describe(i), i)
            if any(d != flat[0][1] for _, d in flat):
                return None
            cs = _constraint_sets(c0, members)
            rough = [_rough(m, v) for m, v in zip(members, values, strict=True)]
            L = [length_scale(m) for m in members]
        held = tuple(first.model.coordinate_index(ref) for ref in values[0].hold)
        if len({v.hold for v in values}) > 1:
            return None  # other coordinates held
    if cs is None:
        return None
    alive = [None if i in errors else cs[i] for i in range(count)]
    L, tol = np.asarray(L, dtype=float), np.array([v.tol for v in values])

    def program(idx: list[int]) -> tuple:
        q0 = stack_trees([rough[i] for i in idx])
        model = stacked_models(idx)
        c = stack_leaves(treedef, [cs[i] for i in idx])
        max_iter = jnp.asarray(values[0].max_iter)
        return _equilibria_batch_jit(
            CHUNK, model, c, q0, L[idx], jnp.asarray(ts), tol[idx], max_iter, held
        )

    seconds["setup"] = time.perf_counter() - clock
    stack = StaticStack(setup, count, ts, in_chunks(program, alive, CHUNK), models)
    seconds["equilibria"] = time.perf_counter() - clock - seconds["setup"]
    done = finished(count, stack.flagged(), _built(stack), errors, on_member)
    seconds["finishing"] = time.perf_counter() - clock - seconds["setup"] - seconds["equilibria"]
    return (stack, *done)


class VariedModels(Sequence):
    """The member models of a sweep that varies some of a model's leaves, made one by one
    when read (one unflatten a member), and stacked for a batch of members without making
    them (:meth:`stacked`).

    Args:
        model: the nominal model.
        positions: the indices, among ``model``'s leaves, of the varied leaves.
        values: for each of ``positions``, its (M, ...) values [model units].
    """

    def __init__(self, model: Model, positions: Sequence[int], values: Sequence[np.ndarray]):
        self.leaves, self.treedef = jax.tree_util.tree_flatten(model)
        self.columns = dict(zip(positions, (np.asarray(v) for v in values), strict=True))
        self.count = len(values[0])

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = range(self.count)[i]
        row = [jnp.asarray(self.columns[k][i]) if k in self.columns else leaf
               for k, leaf in enumerate(self.leaves)]  # fmt: skip
        return jax.tree_util.tree_unflatten(self.treedef, row)

    def stacked(self, idx: Sequence[int]):
        """The models of the members ``idx`` (K,) as one model with a leading member axis:
        the varied leaves' rows, every other leaf broadcast."""
        n = len(idx)
        rows = [self.columns[k][np.asarray(idx)] if k in self.columns
                else np.broadcast_to(np.asarray(leaf), (n, *np.shape(leaf)))
                for k, leaf in enumerate(self.leaves)]  # fmt: skip
        return jax.tree_util.tree_unflatten(self.treedef, rows)


def _constraint_sets(c0: Constraints, members: Sequence[Model]) -> list | None:
    """Each member's constraint set of every row as its leaves: ``c0``'s (the first
    set-up's, every row kept) with the member's joints and drivers, in order (the members of
    one structure). None where they do not match."""
    treedef = jax.tree_util.tree_structure(c0)
    first = jax.tree_util.tree_structure((members[0].joints, members[0].drivers))
    if first.num_leaves != treedef.num_leaves:  # pragma: no cover - a new field
        return None
    return [jax.tree_util.tree_leaves((m.joints, m.drivers)) for m in members]


def _rough(model: Model, value: QuasiStatic) -> np.ndarray:
    """(nq,) the rough start the set-up assembles: the value's ``q0``, else the bodies'."""
    return start_q(model) if value.q0 is None else np.asarray(value.q0, dtype=float)


def _checked(model: Model, ts: np.ndarray, describe: Callable[[], str], i: int) -> None:
    """A member's drivers' laws checked over ``ts`` (:func:`~._setup.check_start`).

    Raises:
        ModelError: a law that jumps, with the member's index in a note.
    """
    try:
        for driver in model.drivers:
            # Read from the class: equinox makes a method read from a module a module of
            # its own (~40 us, most of the check of a smooth law).
            type(driver).check_law(driver, float(ts[0]), float(ts[-1]), False)
    except ModelError as err:
        err.add_note(f"in member {i} of the sweep{describe()}")
        raise


def _built(stack: StaticStack) -> Callable[[int], Result]:
    """Member ``i``'s result: run like its single run where the program flagged it, else
    read from the arrays."""
    flagged = stack.flagged()

    def build(i: int) -> Result:
        return stack.run(i) if flagged[i] else stack.result(i)

    return build


__all__ = ["StaticStack", "VariedModels", "run"]
