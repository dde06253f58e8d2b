"""Shared test setup: float64 JAX (enabled by importing mixdyn) and the fixture models.

Test modules in every folder ``from fixtures import ...`` (the package ``tests/fixtures``):
pytest puts ``tests/`` on ``sys.path`` (``pythonpath`` in pyproject.toml).
"""

import functools
import gc
import inspect
import os
import shutil
import tempfile

# mixdyn's persistent caches (its exported traces and JAX's compiled programs) are off while
# mixdyn is imported here (nothing written to the user's cache folder); pytest_configure turns
# them on in the session's own folder, unless MIXDYN_NO_CACHE was set by whoever runs the tests.
USER_NO_CACHE = os.environ.get("MIXDYN_NO_CACHE", "").strip() not in ("", "0")
os.environ.setdefault("MIXDYN_NO_CACHE", "1")
# The commands the tests run run in their own processes, not in a command server the user
# may have running (mixdyn.runtime._server); its own tests ask for one.
os.environ["MIXDYN_SERVER"] = "0"


def _one_core_per_worker() -> None:
    """Pin each xdist worker to one core of its own (gw0 -> the first, gw1 -> the second...)
    before JAX starts its CPU backend, whose thread pool then has one thread.

    XLA's CPU runtime runs one of mixdyn's programs on two threads handing work to each other
    (measured: 60 s of CPU for a 46 s run of the N = 40 four-bar); with two workers, four
    such threads on two cores slowed two N = 40 runs of the slow set from 21-46 s to past
    pytest's 900 s limit in CI. Pinned, the same two runs side by side took 34 s and 10 s."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    if not worker.startswith("gw") or not hasattr(os, "sched_setaffinity"):
        return
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) > 1:
        os.sched_setaffinity(0, {cores[int(worker[2:]) % len(cores)]})


_one_core_per_worker()

# The cyclic garbage collector at the command's pace (mixdyn._command.pace_collector): with
# Python's thresholds it ran through JAX's tracing in every test (1-6% of a module's time).
gc.set_threshold(50_000, 20, 100)

import jax  # noqa: E402
import pytest  # noqa: E402

import mixdyn  # noqa: F401, E402  (enables float64)
from mixdyn.runtime import _programs  # noqa: E402
from mixdyn.runtime._private import roomy, use_roomy_frames, whole_module_scheduler  # noqa: E402

use_roomy_frames()  # the test process is mixdyn's own: its tracing runs roomy, as the command's

assert jax.config.jax_enable_x64, "mixdyn must enable float64 on import"

#: JAX's persistent compilation cache (compiled XLA programs, not traces) for one test session,
#: shared by its xdist workers (the folder is made by the first process, the controller, before
#: the workers start, and inherited through the environment) and by a second session that is
#: given the same folder (.ci/run: the slow set after the default one). Every test still traces
#: what it runs; programs that two workers or two modules share are compiled once.
TEST_XLA_CACHE = "MIXDYN_TEST_XLA_CACHE"


def pytest_configure(config):
    folder = os.environ.get(TEST_XLA_CACHE)
    if not folder:
        folder = tempfile.mkdtemp(prefix="mixdyn-test-xla-")
        os.environ[TEST_XLA_CACHE] = folder
        config._mixdyn_made_xla_cache = folder  # removed at the end by who made it
    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    if not USER_NO_CACHE:
        # mixdyn's exported traces in the same folder: a structure traced by one test (one
        # worker, one session) is not traced again by the next; the CLI tests' runs and any
        # process they start use it too
        os.environ.pop("MIXDYN_NO_CACHE", None)
        os.environ["MIXDYN_CACHE_DIR"] = folder
        SESSION_CACHE["folder"] = _programs.set_cache(folder)


#: The folder of mixdyn's caches for this session (None: off), restored after each test.
SESSION_CACHE: dict = {"folder": None}


@pytest.fixture(autouse=True)
def _session_cache():
    """Put mixdyn's caches back to the session's folder after a test that moved or turned
    them off (the cache tests use folders of their own)."""
    yield
    if _programs.cache_folder() != SESSION_CACHE["folder"]:
        _programs.set_cache(SESSION_CACHE["folder"] or False)


#: Test modules whose module fixtures are long runs that most of their tests share: one xdist
#: worker takes the whole module, so that those runs are computed once, not once per worker.
#: (pytest-xdist's ``--dist loadgroup`` marks do not reach its scheduler under pytest 9: it
#: renames items through an attribute pytest no longer reads.)
WHOLE_MODULES = ("test_cli.py", "test_mixed.py", "test_mixed_files.py")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist load`` (the default here), but with :data:`WHOLE_MODULES` each one unit
    (where the installed pytest-xdist is a checked one; else xdist's own scheduling)."""
    if config.getvalue("dist") != "load":
        return None
    return whole_module_scheduler(config, log, WHOLE_MODULES)


#: Cases of parametrized tests that are long runs, marked slow here (CI runs them after the
#: README's test command, with ``-m slow``): their test's other cases check the same property
#: by default, and the command stays within its 6 minutes on a 2-core machine.
LONG_CASES = frozenset(
    {
        "tests/analyses/test_solver_contract.py::test_kkt_solution_and_gradients[mixed-banded]",
        "tests/analyses/test_solver_contract.py::test_kkt_solution_and_gradients[forward-banded]",
        "tests/analyses/test_solver_contract.py::test_rank_deficient_minimum_norm[banded]",
        "tests/validation/test_failed_gradients.py::"
        "test_a_failed_run_gives_nan_value_and_nan_derivatives[reverse]",
        "tests/analyses/test_sweep.py::test_forward_members_equal_single_runs[member-by-member]",
        "tests/analyses/test_forward.py::"
        "test_generalized_alpha_stiff_spring_falls_back_to_full_newton[contracting-slowly]",
        "tests/validation/test_friction_hold.py::"
        "test_a_block_launched_up_an_incline_stops_where_it_should_and_stays[partitioning]",
        "tests/validation/test_friction_hold.py::"
        "test_a_block_launched_up_an_incline_stops_where_it_should_and_stays[projection-fixed]",
        "tests/validation/test_friction_hold.py::"
        "test_a_braked_flywheel_stops_and_is_held_by_its_pin[partitioning]",
        "tests/elements/test_friction.py::"
        "test_a_block_slides_above_the_friction_angle_at_g_sin_minus_mu_cos[0.0]",
        "tests/analyses/test_sparse_all.py::"
        "test_sparse_equations_equal_the_dense_ones[andrews_mechanism]",
        "tests/analyses/test_sparse.py::"
        "test_jacobian_gamma_and_accelerations_agree[paper_mechanism]",
        "tests/elements/test_cams.py::test_oscillating_follower[-1.0]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_from_perturbed_starts[dopri8-loose-1]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_from_perturbed_starts[tsit5-default-1]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_whatever_the_first_step[partitioning-1e-07]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_from_perturbed_starts[partitioning-1]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_whatever_the_first_step[dopri8-tight-0.00037]",
        "tests/command/test_cli.py::test_example_runs_from_the_cli_like_the_api[pendulum]",
        "tests/command/test_cli.py::test_example_runs_from_the_cli_like_the_api[four_bar]",
        "tests/analyses/test_sparse.py::test_jacobian_gamma_and_accelerations_agree[four_bar]",
        "tests/analyses/test_solver_contract.py::test_solver_square_system[banded]",
        "tests/analyses/test_sparse_all.py::"
        "test_sparse_equations_equal_the_dense_ones[pendulum_chain]",
        "tests/elements/test_belt_drive.py::"
        "test_speeds_tensions_and_pin_loads_follow_the_spans[50.0-True]",
        "tests/elements/test_belt_drive.py::"
        "test_speeds_tensions_and_pin_loads_follow_the_spans[0.0-True]",
        "tests/elements/test_belt_drive.py::"
        "test_speeds_tensions_and_pin_loads_follow_the_spans[50.0-False]",
        "tests/validation/test_gear_pin_reactions.py::test_a_pin_in_mm_carries_the_same_force",
        "tests/validation/test_gear_pin_reactions.py::"
        "test_inverse_dynamics_pin_reaction_is_the_whole_tooth_force[reversed]",
        "tests/validation/test_gear_pin_reactions.py::test_the_radial_force_leaves_the_motion_alone",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_from_perturbed_starts[tsit5-tight-1]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_whatever_the_first_step[tsit5-tight-1e-07]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_whatever_the_first_step[partitioning-0.02]",
        "tests/validation/test_singular_positions.py::"
        "test_fixed_step_methods_follow_the_branch_from_perturbed_starts[gen-alpha-2ms-1]",
        "tests/elements/test_friction.py::"
        "test_a_flywheel_sticks_until_the_torque_passes_mu_r_m_g_then_turns",
        "tests/validation/test_friction_hold.py::"
        "test_a_block_launched_up_an_incline_stops_where_it_should_and_stays[baumgarte]",
        "tests/validation/test_friction_hold.py::"
        "test_a_braked_flywheel_stops_and_is_held_by_its_pin[baumgarte]",
        "tests/validation/test_singular_positions.py::"
        "test_adaptive_methods_follow_the_branch_whatever_the_first_step[dopri8-tight-1e-07]",
    }
)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Mark :data:`LONG_CASES` slow before ``-m`` selects."""
    for item in items:
        if item.nodeid in LONG_CASES:
            item.add_marker(pytest.mark.slow)


def pytest_unconfigure(config):
    folder = getattr(config, "_mixdyn_made_xla_cache", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop the compiled programs held in memory (mixdyn's and JAX's:
    :func:`mixdyn.runtime._programs.release`) after a test module once the process holds more
    than half the memory mappings it may: every compiled program keeps a few dozen mappings
    (its code), a whole session compiles thousands of them, and at the system's limit (65530)
    XLA cannot map the next one and crashes (segmentation faults in XLA's compiler, in JAX's
    cache write and in loading a stored executable). JAX's programs alone are not enough:
    mixdyn's own, kept by each :func:`~mixdyn.runtime.cached_jit` function, stayed (measured
    in the slow set: 32,000 mappings cleared only to 14,000-25,000, the crash late in the
    set). Below the threshold the programs are kept, so that later modules reuse what they
    share (clearing after every module cost minutes of recompiling)."""
    yield
    _programs.release_if_crowded()


@pytest.hookimpl(wrapper=True)
def pytest_pyfunc_call(pyfuncitem):
    """Each test runs on a roomy frame stack (:func:`mixdyn.runtime._private.roomy`), as
    mixdyn's own tracing does: JAX's tracing in a test's body otherwise maps and unmaps a
    chunk of frames at every call that crosses a chunk's end (~48,000 times in
    ``test_gradients.py``)."""
    test = pyfuncitem.obj
    pyfuncitem.obj = functools.wraps(test)(lambda **kwargs: roomy(test, **kwargs))
    try:
        return (yield)
    finally:
        pyfuncitem.obj = test


@pytest.hookimpl(wrapper=True)
def pytest_fixture_setup(fixturedef, request):
    """A fixture that is a plain function (the module fixtures' long runs) runs roomy too;
    generator fixtures are left as they are (their bodies run where they are resumed)."""
    func = fixturedef.func
    plain = not (inspect.isgeneratorfunction(func) or inspect.iscoroutinefunction(func))
    if not plain or request.instance is not None:  # (a method is bound by pytest)
        return (yield)
    fixturedef.func = functools.wraps(func)(lambda *a, **kw: roomy(func, *a, **kw))
    try:
        return (yield)
    finally:
        fixturedef.func = func
