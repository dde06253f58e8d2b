"""A sweep's members set up and run: each member prepared like a single run, or given the
first member's set-up where the varied numbers do not enter the start, the members of one
structure checked, then integrated by :mod:`._schedule` (forward and mixed) or run whole,
member by member (kinematic, inverse, quasi-static).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable, Sequence

import equinox as eqx
import jax
import numpy as np

from ..errors import MixdynError, ModelError
from ..model import Model
from ..model._compliant import rigid_contacts
from ._schedule import Outcome, _batched, _default_batch_size, _finish, _in_threads
from ._setup import Analysis, prepare, run
from ._simulate import Case, integrate, require_masses


def model_swapper(problem):
    """A function ``model -> problem`` with that model (of the same structure) in place of
    ``problem``'s own: the problem's leaves are the model's followed by the constraint set's,
    read once here (one unflatten a member; ``eqx.tree_at`` takes 2.5 ms)."""
    c_leaves = jax.tree_util.tree_leaves(problem.c)
    treedef = jax.tree_util.tree_structure(problem)
    n_model = len(jax.tree_util.tree_leaves(problem.model))
    if treedef.num_leaves != n_model + len(c_leaves):  # pragma: no cover - a new field
        return lambda model: eqx.tree_at(lambda p: p.model, problem, model)
    return lambda model: jax.tree_util.tree_unflatten(
        treedef, jax.tree_util.tree_leaves(model) + c_leaves
    )


def _input_error(err: ModelError, i: int, describe: str) -> ModelError:
    err.add_note(f"in member {i} of the sweep{describe}")
    return err


def run_members(
    members: Sequence[Model],
    t,
    analysis: Analysis | Sequence[Analysis],
    *,
    recorded: dict | Sequence[dict | None] | None = None,
    batch_size: int | None = None,
    threads: int | None = None,
    on_member: Callable[[int], None] | None = None,
    describe: Callable[[int], str] = lambda i: "",
    offset: int = 0,
    same_start: bool = False,
    seconds: dict | None = None,
) -> list[Outcome]:
    """Each member's ``(Result, None)`` or ``(None, its numerical error)``, in order.

    Args:
        members: the member models, of one structure.
        t: (N,) output times [time].
        analysis: the analysis value, the same for every member, or one value per member
            (of one class: the model-file layer's members may differ in their settings,
            :func:`~._keywords.member_values`).
        recorded: the integrator options the members' results record (``stats["options"]``;
            default: the method object's own), for every member or one per member.
        batch_size, threads: as in :func:`sweep`.
        on_member: called with a member's index when it is done (from any thread).
        describe: member index -> words naming it in an error (its varied values).
        offset: the sweep's index of ``members[0]`` (a chunk of a larger sweep), for errors.
        same_start: the members differ only in numbers that do not enter a forward or mixed
            run's start (:func:`shares_start`): the first member is set up and the others
            take its start and constraint set with their own model (their masses checked). A
            mixed run whose unknown forces are not collocated with its prescribed motions is
            still set up member by member (its solvability, the rank of ``C M^-1 G``, may
            depend on the masses).
        seconds: if given, filled with the wall time of the set-up, the integration and the
            finishing [s].

    Raises:
        ModelError: a member's input error (named with its index), or members of different
            structures.
    """
    threads = threads or os.cpu_count() or 1
    one = isinstance(analysis, Analysis)
    values = [analysis] * len(members) if one else list(analysis)
    if isinstance(recorded, (list, tuple)):
        records = list(recorded)
    else:
        records = [recorded] * len(members)
    if not values:
        return []
    first_value = values[0]
    t0 = float(np.atleast_1d(np.asarray(t, dtype=float))[0])

    def setup_of(i: int):
        setup = prepare(members[i], values[i], t0=t0)
        if records[i] is not None:
            setup = dataclasses.replace(setup, recorded=records[i])
        return setup

    if not first_value.integrated:

        def whole(i: int) -> Outcome:
            try:
                return run(setup_of(i), t), None
            except ModelError as err:
                raise _input_error(err, offset + i, describe(i)) from None
            except MixdynError as err:
                return None, err

        if batch_size is not None:
            raise ModelError(
                f"a {first_value.name} sweep runs member by member: no batch_size", "batch_size"
            )
        return _in_threads(whole, list(range(len(members))), threads, on_member)

    cases: dict[int, Case] = {}
    outcomes: dict[int, Outcome] = {}
    clock = time.perf_counter()
    shared = same_start
    swap = None
    first_setup = None
    for i, m in enumerate(members):
        try:
            if shared and first_setup is not None:
                shared = first_value._shares_setup(first_setup)
            if shared and cases:
                require_masses(m)
                first = cases[next(iter(cases))]
                swap = swap or model_swapper(first.problem)
                cases[i] = dataclasses.replace(first, problem=swap(m))
            elif shared and outcomes:  # the shared start could not be made
                outcomes[i] = outcomes[next(iter(outcomes))]
                if on_member is not None:
                    on_member(i)
            else:
                setup = setup_of(i)
                first_setup = first_setup or setup
                cases[i] = values[i]._case(setup, t)
        except ModelError as err:
            raise _input_error(err, offset + i, describe(i)) from None
        except MixdynError as err:  # a start that cannot be made: this member fails
            outcomes[i] = (None, err)
            if on_member is not None:
                on_member(i)
    if seconds is not None:
        seconds["setup"] = time.perf_counter() - clock
    if cases:
        k0 = next(iter(cases))
        first = cases[k0]
        tree = jax.tree.structure(first.problem)
        for i, c in cases.items():
            if jax.tree.structure(c.problem) != tree or c.options != first.options:
                raise ModelError(
                    f"member {i} differs from member {k0} in structure (its bodies, elements, "
                    "kinds of laws or constraint rows): a sweep varies numbers only",
                    "models",
                )
        order = list(cases)
        if rigid_contacts(first.problem.model):  # integrated impact by impact, one by one
            done = _in_threads(lambda i: _simulated(cases[i]), order, threads, on_member)
        elif batch_size is None and _default_batch_size() is None:
            done = _in_threads(
                lambda i: _finish(cases[i], integrate(cases[i])), order, threads, on_member
            )
        else:
            done = _batched([cases[i] for i in order], batch_size or _default_batch_size(), seconds)
            if on_member is not None:
                for i in order:
                    on_member(i)
        outcomes.update(zip(order, done, strict=True))
    return [outcomes[i] for i in range(len(members))]


def _simulated(case: Case) -> Outcome:
    """A member with rigid contacts run whole, impact by impact
    (:func:`~._impacts.simulate_impacts`), its failure kept as its outcome."""
    from ._impacts import simulate_impacts

    try:
        return simulate_impacts(case), None
    except MixdynError as err:
        return None, err
