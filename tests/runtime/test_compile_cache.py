"""Compiled once: traced programs kept per model structure (``mixdyn.runtime._programs``), in this
process and across processes, and progress callbacks that do not force a new program.

The test session keeps mixdyn's caches in a folder of its own (conftest); the tests here
point them at a fresh temporary folder (conftest puts the session's back after each test), or
run in a subprocess.
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import textwrap

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import ROOT, TESTS, new_traces, paper_mechanism, pendulum, traced_now
from mixdyn.runs import Runner
from mixdyn.runtime import _programs, _xla

TS = np.linspace(0.0, 0.2, 11)
HOLD = ("crank.phi", "coupler.phi")
#: ``sys.path`` additions of the subprocess scripts below, which import this module (its folder)
#: and through it the fixtures (the tests folder).
SCRIPT_PATH = [str(pathlib.Path(__file__).resolve().parent), str(TESTS)]


@pytest.fixture
def cache(tmp_path):
    """The persistent caches on, in a fresh folder, for one test."""
    folder = _programs.set_cache(tmp_path / "cache")
    assert folder is not None
    yield pathlib.Path(folder)
    _programs.set_cache(False)


def paper(T=500.0, F0=10.0, mass=0.0221):
    """The paper's mechanism under its loads; the numbers can be changed, not the structure."""
    model = paper_mechanism(
        forces=(
            md.Torque("M2", "crank", law=T),
            md.Torque("M3", "coupler", law=-T),
            md.PointForce("F1", "slider", along=(1, 0), law=md.Harmonic(F0, np.pi / 2)),
        )
    )
    return eqx.tree_at(lambda m: m.bodies[0].mass, model, np.float64(mass))


# ------------------------------------------------------------------ progress callbacks
@pytest.mark.parametrize("method", ["projection", "generalized-alpha"])
def test_a_new_progress_callback_is_not_a_new_program(method):
    """Each run with a progress bar gets a new callback: it must not trace (and compile) the
    integrator again; every callback is called, at the output times, with its own run."""
    model = pendulum(theta0=0.3)
    opts = {"dt": 0.01} if method == "generalized-alpha" else {}
    seen = {1: [], 2: []}
    md.forward(model, TS, method=method, progress=lambda t: seen[1].append(float(t)), **opts)
    before = traced_now()
    md.forward(model, TS, method=method, progress=lambda t: seen[2].append(float(t)), **opts)
    assert new_traces(before) == {}
    for k in (1, 2):
        assert seen[k], f"callback {k} was not called"
        assert seen[k][-1] == pytest.approx(TS[-1])
        assert set(np.round(seen[k], 9)) <= set(np.round(TS, 9))


def test_progress_registry_is_emptied():
    """A run's callback is dropped from the registry when the run ends (also on failure)."""
    from mixdyn.analysis.integrators import _common

    with _common.progress_hook(lambda t: None) as hook:
        assert int(hook.key) in _common._PROGRESS
    assert int(hook.key) not in _common._PROGRESS
    with pytest.raises(RuntimeError), _common.progress_hook(print) as hook:
        raise RuntimeError
    assert int(hook.key) not in _common._PROGRESS


# ------------------------------------------------------------------ in one process
@pytest.mark.slow  # long: run by CI's slow set (the README's command within 6 min)
def test_the_same_structure_traces_nothing_again(cache):
    """A second run of the same structure, and a run with other numbers (loads, a mass, the
    tolerances), traces none of the cached functions; the numbers are those of a fresh run."""
    md.forward(paper(), TS, hold=HOLD, rtol=1e-9, atol=1e-9)
    before = traced_now()
    again = md.forward(paper(), TS, hold=HOLD, rtol=1e-9, atol=1e-9)
    assert new_traces(before) == {}
    other = md.forward(paper(T=300.0, F0=4.0, mass=0.03), TS, hold=HOLD, rtol=1e-8, atol=1e-8)
    assert new_traces(before) == {}
    assert not np.allclose(other.q, again.q)  # other numbers did change the motion
    _programs.set_cache(False)
    fresh = md.forward(paper(T=300.0, F0=4.0, mass=0.03), TS, hold=HOLD, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(other.q, fresh.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        other.extra["energy.total"], fresh.extra["energy.total"], rtol=1e-12, atol=1e-12
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_exported_program_gives_the_traced_numbers(cache):
    """Round trip: a program exported, written, read back (a new wrapper, as in a new
    process) gives the numbers the traced program gives."""
    from mixdyn.analysis._problem import Problem
    from mixdyn.analysis._simulate import _post_arrays
    from mixdyn.analysis._start import _velocity_fix
    from mixdyn.equations import Constraints

    model = paper()
    c = Constraints.of(model)
    q = np.asarray(md.assemble(model, hold=HOLD).q)
    qd = np.linspace(-1.0, 1.0, model.nq)
    weights = np.ones(model.nq)
    weights[[2, 5]] = 0.0  # two coordinates held
    args = (c, q, qd, np.asarray(0.1), weights)
    traced = eqx.filter_jit(_velocity_fix.fn)(*args)
    first = _programs.cached_jit(_velocity_fix.fn.__wrapped__)
    exported = first(*args)
    assert _programs.stats["exported"] >= 1
    loaded_before = _programs.stats["loaded"]
    reread = _programs.cached_jit(_velocity_fix.fn.__wrapped__)(*args)
    assert _programs.stats["loaded"] == loaded_before + 1
    for a, b, r in zip(traced, exported, reread, strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
        np.testing.assert_array_equal(np.asarray(a), np.asarray(r))
    problem = Problem(model, c)
    Q = np.tile(q, (3, 1))
    QD = np.tile(qd, (3, 1)) * 0.0
    ts = np.array([0.0, 0.1, 0.2])
    want = eqx.filter_jit(_post_arrays.fn)(problem, ts, Q, QD)
    got = _programs.cached_jit(_post_arrays.fn.__wrapped__)(problem, ts, Q, QD)
    assert jax.tree.structure(want) == jax.tree.structure(got)
    for a, b in zip(jax.tree.leaves(want), jax.tree.leaves(got), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_a_quick_program_is_compiled_so_with_the_cache_on_and_off(cache):
    """``cached_jit(fn, optimize=False)``: XLA gets ``QUICK`` (LLVM at -O0) whether the
    program is exported, read back in a new wrapper or traced with the cache off
    (``filter_jit``): the three give the same bits, and the stored executable was built
    with those options. An optimized compile agrees to the last bits only (~1e-12)."""
    from mixdyn.analysis._start import _velocity_fix
    from mixdyn.equations import Constraints

    model = paper()
    c = Constraints.of(model)
    q = np.asarray(md.assemble(model, hold=HOLD).q)
    qd = np.linspace(-1.0, 1.0, model.nq)
    weights = np.ones(model.nq)
    weights[[2, 5]] = 0.0
    args = (c, q, qd, np.asarray(0.1), weights)
    fn = _velocity_fix.fn.__wrapped__
    # declared so in mixdyn.analysis._start; with mixdyn's XLA options (runtime._xla)
    assert _velocity_fix.options == {**_xla.compile_options(), **_programs.QUICK}
    off = eqx.filter_jit(fn, compiler_options=_velocity_fix.options)(*args)
    exported = _programs.cached_jit(fn, optimize=False)(*args)
    reread = _programs.cached_jit(optimize=False)(fn)(*args)
    optimized = eqx.filter_jit(fn)(*args)
    for a, b, r, o in zip(off, exported, reread, optimized, strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
        np.testing.assert_array_equal(np.asarray(a), np.asarray(r))
        np.testing.assert_allclose(np.asarray(a), np.asarray(o), rtol=1e-11, atol=1e-13)


@pytest.mark.slow  # long: run by CI's slow set (the README's command within 6 min)
def test_a_program_prepared_ahead_is_the_one_called(cache):
    """``ahead`` prepares a program in a second thread from arguments of the same structure
    and shapes (zeros): the call with the real arguments then traces nothing more and gives
    the numbers of the traced function; a run prepares its post-processing that way."""
    from mixdyn.analysis._problem import Problem
    from mixdyn.analysis._simulate import _post_arrays
    from mixdyn.equations import Constraints

    model = paper()
    c = Constraints.of(model)
    q = np.asarray(md.assemble(model, hold=HOLD).q)
    problem = Problem(model, c)
    ts = np.array([0.0, 0.1, 0.2])
    Q = np.tile(q, (3, 1))
    QD = np.tile(np.linspace(-1.0, 1.0, model.nq), (3, 1))
    name = "mixdyn.analysis._simulate._post_arrays"
    before = _programs.traces[name]
    zeros = np.zeros_like(Q)
    _post_arrays.ahead(problem, ts, zeros, zeros)
    got = _post_arrays(problem, ts, Q, QD)
    assert _programs.traces[name] == before + 1  # traced once, in the other thread
    want = eqx.filter_jit(_post_arrays.fn)(problem, ts, Q, QD)
    for a, b in zip(jax.tree.leaves(want), jax.tree.leaves(got), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    # a forward run on a fresh structure: its post-processing traced once, not twice
    runs = dict(_programs.traces)
    md.forward(paper_mechanism(), np.linspace(0.0, 0.1, 7), hold=HOLD, rtol=1e-8, atol=1e-8)
    assert _programs.traces[name] - runs.get(name, 0) == 1


def test_a_manifest_says_so_for_its_own_job_only(cache):
    """Within a job whose manifest lists programs, preparing them in advance is skipped
    (they are on disk); after it, another job or run of the same process prepares again."""
    assert not _programs.reading_ahead()
    manifest = _programs._manifest(str(cache), "first")  # as a first run of the job leaves it
    manifest.parent.mkdir(exist_ok=True)
    manifest.write_text("velocity_fix-0123.bin\n")
    with _programs.job("first"):
        assert _programs.reading_ahead()
    assert not _programs.reading_ahead()
    with _programs.job("another"):
        assert not _programs.reading_ahead()


def test_a_files_next_run_is_prepared_while_the_first_computes(cache):
    """mixdyn run's runner prepares the next run's integrator and post-processing in second
    threads while a run computes (the paper's file: the mixed run, replaying the forward
    run's slider, set up with its checks' stand-ins): each program is traced once, the
    mixed run finds its programs ready, and it still recovers the paper's F1."""
    import mixdyn.io as mio
    from mixdyn.analysis import _simulate
    from mixdyn.analysis._structure import _values

    for fn in (_simulate._integrator("projection"), _simulate._post_arrays, _values):
        fn.programs.clear()  # as in a new process (the folder is new: nothing on disk)
    runner = Runner(mio.read(ROOT / "examples" / "antonya.yaml"))
    plans = runner.order()
    for plan in plans:  # the checks mixdyn run makes first
        runner.mobility(plan)
    before, ahead = dict(_programs.traces), _programs.stats["ahead"]
    results = runner.execute()
    new = {k: v - before.get(k, 0) for k, v in _programs.traces.items()}
    integrator = "mixdyn.analysis.integrators.projection.projection"
    assert new[integrator] == 2  # the forward run's and the mixed run's, each once
    assert new["mixdyn.analysis._simulate._post_arrays"] == 2
    assert _programs.stats["ahead"] - ahead >= 3  # both post-processings, the mixed integrator
    mixed = results["mixed"]
    np.testing.assert_allclose(mixed["F1"], 10.0 * np.sin(np.pi * mixed.t / 2.0), rtol=0, atol=1e-6)


class _Local(eqx.Module):
    scale: float = eqx.field(static=True)


def _scaled(m: _Local, x):
    return m.scale * x


def test_code_outside_mixdyn_is_not_keyed(cache):
    """A static part naming code that the key's versions do not cover (a class or function of
    a test, a script) is traced as by filter_jit, never looked up by its name on disk."""
    f = _programs.cached_jit(_scaled)
    fallback = _programs.stats["fallback"]
    assert float(f(_Local(2.0), jnp.asarray(3.0))) == 6.0
    assert float(f(_Local(5.0), jnp.asarray(3.0))) == 15.0
    assert _programs.stats["fallback"] == fallback + 2
    assert not list((cache / _programs.EXPORTED).iterdir())


def test_cache_switch(tmp_path):
    """set_cache turns mixdyn's caches on (a folder) and off (None); JAX's own compilation
    cache stays as it was set (here, by the test session), on or off."""
    session = jax.config.jax_compilation_cache_dir
    try:
        assert _programs.set_cache(tmp_path / "c") == str(tmp_path / "c")
        assert (tmp_path / "c" / _programs.EXPORTED).is_dir()
        assert jax.config.jax_compilation_cache_dir == session
    finally:
        assert _programs.set_cache(False) is None
    assert _programs.cache_folder() is None
    assert jax.config.jax_compilation_cache_dir == session


# ------------------------------------------------------------------ across processes
SCRIPT = textwrap.dedent(
    """
    import contextlib, json, sys
    import numpy as np
    sys.path[:0] = {path!r}
    import mixdyn as md
    from mixdyn.runtime import _programs
    from test_compile_cache import paper, TS, HOLD
    T = float(sys.argv[1])
    job = sys.argv[3] if len(sys.argv) > 3 else None
    with _programs.job(job) if job else contextlib.nullcontext():
        res = md.forward(paper(T=T), TS, hold=HOLD, rtol=1e-9, atol=1e-9)
    np.save(sys.argv[2], res.q)
    print(json.dumps({{"folder": _programs.cache_folder(), "stats": _programs.stats,
                      "traces": dict(_programs.traces)}}))
    """
)


def _run(script: pathlib.Path, env: dict, *args) -> dict:
    out = subprocess.run(
        [sys.executable, str(script), *map(str, args)],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
@pytest.mark.timeout(900)
def test_a_second_process_traces_nothing(tmp_path):
    """A first process exports the programs of the paper's mechanism; a second one, with
    other numbers, reads them back and traces none of them, and gets the numbers a process
    without the cache gets; a third one, told the first one's job, reads them ahead
    (:func:`mixdyn.runtime._programs.prefetch`) and gets the same numbers."""
    script = tmp_path / "run.py"
    script.write_text(SCRIPT.format(path=SCRIPT_PATH))
    env = dict(os.environ, MIXDYN_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("MIXDYN_NO_CACHE", None)
    first = _run(script, env, 500.0, tmp_path / "a.npy", "job")
    assert first["folder"] == str(tmp_path / "cache")
    assert first["stats"]["exported"] > 0 and first["stats"]["fallback"] == 0
    assert first["stats"]["prefetched"] == 0  # no manifest yet
    second = _run(script, env, 350.0, tmp_path / "b.npy")
    assert second["stats"]["exported"] == 0 and second["stats"]["fallback"] == 0
    assert second["stats"]["loaded"] == first["stats"]["exported"]
    assert second["traces"] == {}
    assert second["stats"]["executables"] == first["stats"]["exported"]  # nothing lowered
    off = dict(env, MIXDYN_NO_CACHE="1")
    reference = _run(script, off, 350.0, tmp_path / "c.npy")
    assert reference["folder"] is None and reference["traces"]
    np.testing.assert_array_equal(np.load(tmp_path / "b.npy"), np.load(tmp_path / "c.npy"))
    assert not np.allclose(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    # The job's manifest: a third process reads every program ahead, in a second thread.
    third = _run(script, env, 350.0, tmp_path / "d.npy", "job")
    assert third["stats"]["prefetched"] == first["stats"]["exported"]
    assert third["stats"]["loaded"] == third["stats"]["exported"] == 0
    assert third["traces"] == {}
    np.testing.assert_array_equal(np.load(tmp_path / "d.npy"), np.load(tmp_path / "c.npy"))


EARLY_SCRIPT = textwrap.dedent(
    """
    import json, sys
    sys.argv = [{argv0!r}, "run", {file!r}, "--no-figures", "--out", {out!r}]
    import mixdyn
    from mixdyn.runtime import _programs
    queued = sorted(p.rsplit("/", 1)[-1] for p in _programs._prefetched)
    print(json.dumps(queued))
    sys.stdout.flush()
    if {command!r}:
        from mixdyn.cli import main
        main()
    """
)


@pytest.mark.slow  # long: run by CI's slow set (the README's command within 6 min)
def test_the_run_command_reads_its_programs_from_the_import_on(tmp_path):
    """``mixdyn run FILE`` queues the programs its last run of the file used (its manifest)
    while mixdyn is imported, before the command line is parsed (``_command.job_tag``): all of
    them, and the run then finds them read; a program that only imports mixdyn queues none."""
    env = dict(os.environ, MIXDYN_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("MIXDYN_NO_CACHE", None)
    file, out = str(ROOT / "examples" / "pendulum.yaml"), str(tmp_path / "out")

    def run(argv0, command):
        script = tmp_path / "early.py"
        script.write_text(EARLY_SCRIPT.format(argv0=argv0, file=file, out=out, command=command))
        proc = subprocess.run(
            [sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=300
        )
        assert proc.returncode == 0, proc.stderr
        return json.loads(proc.stdout.splitlines()[0])

    assert run("/usr/bin/mixdyn", True) == []  # the first run: no manifest yet
    (manifest,) = (tmp_path / "cache" / "manifests").glob("*.txt")
    used = sorted(set(manifest.read_text().split()))
    assert used and run("/usr/bin/mixdyn", True) == used
    assert run(sys.executable, False) == []


EXE_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    sys.path[:0] = {path!r}
    import mixdyn as md
    from mixdyn.runtime import _programs
    from mixdyn.analysis._start import _velocity_fix
    from mixdyn.equations import Constraints
    from test_compile_cache import paper, HOLD
    model = paper()
    q = np.asarray(md.assemble(model, hold=HOLD).q)
    qd = np.linspace(-1.0, 1.0, model.nq)
    weights = np.ones(model.nq)
    weights[[2, 5]] = 0.0
    out, err = _velocity_fix(Constraints.of(model), q, qd, np.asarray(0.1), weights)
    np.save(sys.argv[1], np.append(np.asarray(out), float(err)))
    print(json.dumps({{"stats": _programs.stats, "traces": dict(_programs.traces)}}))
    """
)


def test_a_new_process_runs_the_stored_executables(tmp_path):
    """An exported program's executable is stored once compiled, and a new process runs it
    without lowering or compiling (``mixdyn.runtime._executables``), with the same numbers (a
    least-norm velocity fix: LAPACK inside, set up although nothing is lowered). Damaged stored
    executables are compiled again and stored anew, and then run too."""
    script = tmp_path / "fix.py"
    script.write_text(EXE_SCRIPT.format(path=SCRIPT_PATH))
    env = dict(os.environ, MIXDYN_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("MIXDYN_NO_CACHE", None)
    exes = tmp_path / "cache" / "executables"
    first = _run(script, env, tmp_path / "a.npy")
    n = first["stats"]["exported"]  # the assembly's programs and the velocity fix
    assert n >= 2 and first["stats"]["executables"] == 0
    assert len(list(exes.glob("*.exe"))) == n
    second = _run(script, env, tmp_path / "b.npy")
    assert second["stats"]["executables"] == second["stats"]["loaded"] == n
    assert second["traces"] == {}
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    for exe in exes.glob("*.exe"):
        exe.write_bytes(b"not an executable")
    third = _run(script, env, tmp_path / "c.npy")
    assert third["stats"]["executables"] == 0 and third["stats"]["loaded"] == n
    fourth = _run(script, env, tmp_path / "d.npy")
    assert fourth["stats"]["executables"] == n and fourth["traces"] == {}
    for name in "cd":
        np.testing.assert_array_equal(
            np.load(tmp_path / "a.npy"), np.load(tmp_path / f"{name}.npy")
        )


def test_an_executable_is_keyed_by_the_xla_flags_and_the_processor(monkeypatch):
    """Another ``$XLA_FLAGS`` or another processor names another executable (one built for
    other flags or instructions must not run)."""
    from mixdyn.runtime import _executables

    here = _executables.environment.__wrapped__()
    assert _executables.environment.__wrapped__() == here
    flags = os.environ.get("XLA_FLAGS", "") + " --xla_cpu_use_xnnpack=false"
    monkeypatch.setenv("XLA_FLAGS", flags)
    assert _executables.environment.__wrapped__() != here
    monkeypatch.undo()
    monkeypatch.setattr(_executables, "_processor", lambda: "another processor")
    assert _executables.environment.__wrapped__() != here


# ------------------------------------------------------------------ figures while computing
def _motion():
    model = pendulum(theta0=0.4)
    t = np.linspace(0.0, 1.0, 21)
    q = np.tile(np.asarray(model.q0), (len(t), 1))
    q[:, 2] = 0.4 * np.cos(3 * t)
    return model, t, q


def test_the_figure_worker_draws_what_this_process_draws(tmp_path):
    """mixdyn run's worker process (no JAX) writes the same bytes as drawing here."""
    from mixdyn.viz import _draw, movie_data, plot_columns
    from mixdyn.viz.painter import Painter

    model, t, q = _motion()
    data = movie_data(model=model, t=t, q=q, frames=10, trace=["bob.O"])
    table = {"t": t, "bob.phi": q[:, 2]}
    painter = Painter()
    try:
        assert painter.proc is not None
        # On Linux the worker forks: the plot goes to the first channel, the movie to the
        # second (the copy), which must draw as this process does too.
        assert len(painter.channels) == (2 if sys.platform.startswith("linux") else 1)
        painter.draw("plot", table, ["bob.phi"], tmp_path / "w.png", units={"t": "s"}, title="a")
        painter.draw("movie", data, tmp_path / "w.gif", fps=10)
        assert [k for *_, k in painter.tasks] == [0, len(painter.channels) - 1]
        painter.done(tmp_path / "x.html")
        assert painter.results() == [tmp_path / "w.png", tmp_path / "w.gif", tmp_path / "x.html"]
    finally:
        painter.close()
    plot_columns(table, ["bob.phi"], tmp_path / "h.png", units={"t": "s"}, title="a")
    _draw.movie(data, tmp_path / "h.gif", fps=10)
    assert (tmp_path / "w.png").read_bytes() == (tmp_path / "h.png").read_bytes()
    assert (tmp_path / "w.gif").read_bytes() == (tmp_path / "h.gif").read_bytes()


def test_a_figure_failure_in_the_worker_is_raised_here(tmp_path):
    from mixdyn.viz.painter import Painter

    t = np.linspace(0.0, 1.0, 5)
    painter = Painter()
    try:
        painter.draw("plot", {"t": t, "y": t}, ["y"], tmp_path / "bad.txt")
        with pytest.raises(ValueError, match="cannot write a plot"):
            painter.results()
    finally:
        painter.close()


def test_a_lost_worker_leaves_the_figures_to_this_process(tmp_path):
    from mixdyn.viz.painter import Painter

    t = np.linspace(0.0, 1.0, 5)
    painter = Painter()
    try:
        painter.proc.kill()
        painter.proc.wait()
        painter.draw("plot", {"t": t, "y": t}, ["y"], tmp_path / "a.png")
        assert painter.results() == [tmp_path / "a.png"]
        assert (tmp_path / "a.png").stat().st_size > 0
    finally:
        painter.close()


def test_a_worker_that_cannot_fork_serves_one_channel(monkeypatch):
    """Without ``os.fork`` (or when it fails) the worker closes the second channel's ends,
    so that the tasks sent there come back to mixdyn run, and serves the first one."""
    import importlib.util

    from mixdyn import runtime

    spec = importlib.util.spec_from_file_location(
        "_worker_for_test", pathlib.Path(runtime.__file__).with_name("_worker.py")
    )
    worker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(worker)

    def no_fork():
        raise OSError("no fork here")

    monkeypatch.setattr(os, "fork", no_fork)
    tasks_r, tasks_w = os.pipe()
    replies_r, replies_w = os.pipe()
    try:
        assert worker._fork((tasks_r, replies_w)) == (sys.stdin, sys.stdout)
        with pytest.raises(BrokenPipeError):  # nobody reads the second channel's tasks
            os.write(tasks_w, b"task\n")
        assert os.read(replies_r, 10) == b""  # and nobody will write its replies
    finally:
        os.close(tasks_w)
        os.close(replies_r)


def test_a_worker_with_nothing_to_draw_is_stopped_not_awaited():
    """mixdyn run starts its figure worker before it knows whether the runs draw; when they
    draw nothing the worker is stopped at once (killed while importing), not waited for."""
    from mixdyn.viz.painter import Painter

    painter = Painter()
    proc, folder = painter.proc, painter.tmp
    assert proc is not None and proc.poll() is None
    painter.abort()
    assert painter.proc is None
    assert proc.returncode is not None and proc.returncode < 0  # ended by a signal
    assert not os.path.exists(folder)


def test_imports_ahead_run_beside_the_caller_and_leave_failures_to_it():
    """``mixdyn run``'s first compile imports what tracing needs in a thread of its own: the
    module is imported once the thread ends, the caller was not held, and a module that cannot
    be imported raises nothing there (the tracing meets it and reports it)."""
    script = textwrap.dedent(
        """
        import importlib.util, sys, threading
        path = {path!r}  # by its path: the module imports neither mixdyn nor JAX
        spec = importlib.util.spec_from_file_location("_command", path)
        command = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(command)
        import_ahead = command.import_ahead
        assert "xml.dom.minidom" not in sys.modules
        import_ahead(("no_such_module_for_mixdyn", "xml.dom.minidom"))
        (t,) = [t for t in threading.enumerate() if t.name == "mixdyn-imports"]
        t.join(60)
        print("xml.dom.minidom" in sys.modules, "no_such_module_for_mixdyn" in sys.modules)
        """
    ).format(path=str(ROOT / "src" / "mixdyn" / "runtime" / "_command.py"))
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["True", "False"]


@pytest.mark.slow  # long: run by CI's slow set (a run with rigid impacts and resting friction)
def test_a_run_with_rigid_contacts_exports_every_program(cache):
    """A block thrown on rough rigid ground (impacts' events, its corners held at rest, their
    friction sliding to a stop): every program of the run is exported to the cache (none
    falls back to tracing in each process: the segments' solve holds no host callback)."""
    from mixdyn.analysis import _impacts

    for name in ("_segment", "_impact_state", "_normals", "_halt", "_first_step"):
        getattr(_impacts, name).programs.clear()  # as in a new process
    box = md.Body("box", 2.0, 2.0 * (0.2**2 + 0.1**2) / 12, q0=(0.0, 0.05, 0.0))
    floor = md.BoxLineContact("floor", "box", 0.2, 0.1, 0.01, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=0.5, mu=0.4)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0.0, -9.81))
    exported, fallback = _programs.stats["exported"], _programs.stats["fallback"]
    r = md.forward(model, np.linspace(0.0, 0.5, 6), qd0=np.array([1.0, 0.0, 0.0]))
    assert r.stats["segments"] > 1  # the stop ends a segment
    assert _programs.stats["fallback"] == fallback
    assert _programs.stats["exported"] > exported
    names = {p.name.split("-")[0] for p in (cache / _programs.EXPORTED).iterdir()}
    assert {"_segment", "_halt", "_normals"} <= names


def _cubed_plus_sine(x):
    return x**3 + jnp.sin(x)


def _mappings() -> int:
    return _programs.memory_mappings()[0]


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="no /proc (not Linux)")
def test_released_programs_give_back_their_memory_and_are_read_again(cache):
    """``release`` drops the compiled programs of a cached_jit function (each keeps memory
    mappings, of which a process may hold 65530): the process gives back most of the
    mappings their compiling took, and the next calls read the programs back from the cache
    folder, tracing nothing, with the same numbers."""
    f = _programs.cached_jit(_cubed_plus_sine)
    xs = [jnp.linspace(0.0, 1.0, n) for n in range(2, 22)]
    f(jnp.zeros(1))  # JAX's and XLA's own first allocations, before counting
    _programs.release()
    start = _mappings()
    first = [np.asarray(f(x)) for x in xs]
    for x, y in zip(xs, first, strict=True):
        np.testing.assert_allclose(y, np.asarray(x) ** 3 + np.sin(np.asarray(x)), rtol=1e-15)
    assert len(f.programs) == len(xs)
    held = _mappings()
    jax.clear_caches()  # JAX's programs only: mixdyn's still hold their mappings
    assert held - _mappings() < len(xs)
    assert _programs.release() >= len(xs)
    assert not f.programs
    assert held - _mappings() >= 0.8 * (held - start) >= 2 * len(xs)
    loaded, traced = _programs.stats["loaded"], dict(_programs.traces)
    again = [np.asarray(f(x)) for x in xs]
    assert _programs.stats["loaded"] == loaded + len(xs)
    assert dict(_programs.traces) == traced
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="no /proc (not Linux)")
def test_a_crowded_process_and_the_command_server_give_their_programs_back(cache, monkeypatch):
    """``release_if_crowded`` releases only above its share of ``vm.max_map_count`` (a
    process holds fewer mappings than the limit, more than none); the command server calls
    it after each command it answers."""
    from mixdyn.runtime import _server

    mappings, limit = _programs.memory_mappings()
    assert 0 < mappings < limit
    f = _programs.cached_jit(_cubed_plus_sine)
    f(jnp.ones(3))
    assert not _programs.release_if_crowded(share=1.0) and f.programs
    assert _programs.release_if_crowded(share=0.0) and not f.programs
    f(jnp.ones(3))
    monkeypatch.setattr(_programs, "CROWDED", 0.0)
    assert _server._release_if_crowded() and not f.programs
