"""One start per run: the model-file check makes the start and the mobility analysis a run
starts from (``Runner.prepare``), and the run, prepared from it
(``mixdyn.prepare(model, analysis, start=...)``), neither assembles nor analyses again; the
results are those of the analyses called directly; a start made for another set-up is
refused."""

import collections
import pathlib

import jax
import numpy as np
import pytest

import mixdyn as md
import mixdyn.analysis as an
import mixdyn.analysis._prepare as prepare_module
import mixdyn.analysis._start as start_module
import mixdyn.analysis._structure as structure_module
import mixdyn.io as mio
from fixtures import DATA, ROOT, antonya_mixed
from mixdyn.analyses import Forward, Kinematic, Mixed
from mixdyn.errors import DegreesOfFreedomError, ModelError
from mixdyn.runs import Runner, execute

ANTONYA = ROOT / "examples" / "antonya.yaml"
SLIDER_CRANK = ROOT / "examples" / "slider_crank.yaml"
PENDULUM = DATA / "pendulum_mixed.yaml"


def _short(path: pathlib.Path, old: str, new: str) -> mio.ModelFile:
    """The file with its runs' time spans shortened (the set-up is what is tested)."""
    text = path.read_text()
    assert old in text
    return mio.reads(text.replace(old, new), path.name)


@pytest.fixture
def counts(monkeypatch):
    """Calls of the assembly and of the rank analysis, wherever they are looked up."""
    n = collections.Counter()

    def counted(module, name, label):
        f = getattr(module, name)

        def wrapper(*args, **kwargs):
            n[label] += 1
            return f(*args, **kwargs)

        monkeypatch.setattr(module, name, wrapper)

    for module in (an, start_module, prepare_module):  # the runner's, the starts'
        counted(module, "assemble", "assemble")
    for module in (structure_module, prepare_module):  # degrees_of_freedom's, the set-ups'
        counted(module, "analyse", "analyse")
    return n


def _check_then_run(runner: Runner, counts) -> tuple[dict, dict, dict]:
    """``mixdyn run``'s order: every run checked, then executed; the calls per step."""
    checks, runs, results = {}, {}, {}
    for plan in runner.order():
        before = dict(counts)
        if plan.spec.kind != "kinematic":
            runner.check_masses(plan)
        runner.mobility(plan)
        checks[plan.name] = {k: counts[k] - before.get(k, 0) for k in ("assemble", "analyse")}
    for plan in runner.order():
        before = dict(counts)
        results[plan.name] = runner.execute_one(plan, results)
        runs[plan.name] = {k: counts[k] - before.get(k, 0) for k in ("assemble", "analyse")}
    return checks, runs, results


def _same(a, b, columns=()):
    np.testing.assert_allclose(a.t, b.t, rtol=0, atol=0)
    for x, y in ((a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(y).max()))
    for c in columns:
        y = b[c]
        np.testing.assert_allclose(a[c], y, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(y).max()))


def test_antonya_each_run_is_assembled_and_analysed_once(counts):
    """The paper's round trip (a forward run, then a mixed run replaying its slider motion):
    the forward run is checked and run on one set-up (before: an assembly and an analysis in
    the check, again in the run); the mixed run, which needs the forward result, is checked on
    stand-ins with one analysis (before: two, the dof count's and the solvability check's)
    and prepares itself when it runs. In all 4 assemblies and 3 rank analyses, down from 5
    and 5."""
    # the example's own time grid: its programs are those of the file's other tests (the
    # runs take milliseconds; tracing and compiling them is the cost)
    runner = Runner(mio.reads(ANTONYA.read_text(), ANTONYA.name))
    checks, runs, res = _check_then_run(runner, counts)
    assert checks["forward"] == {"assemble": 1, "analyse": 1}
    assert runs["forward"] == {"assemble": 0, "analyse": 0}
    assert checks["mixed"] == {"assemble": 2, "analyse": 1}  # joints closed, then the start
    assert runs["mixed"] == {"assemble": 1, "analyse": 1}  # from the forward run's motion
    assert dict(counts) == {"assemble": 4, "analyse": 3}

    # the same numbers as the analyses called directly, each preparing its own start
    model, plan = runner.model, runner.plans["forward"]
    q0, hold = runner.q_start(plan, model), runner.hold(plan)
    fwd = md.forward(model, plan.times, rtol=1e-10, atol=1e-10, q0=q0, hold=hold)
    _same(res["forward"], fwd, ["A.Fx", "energy.total"])
    mx = antonya_mixed(model, runner.plans["mixed"].times, fwd, q0=q0, hold=hold)
    _same(res["mixed"], mx, ["F1", "A.Fx"])


@pytest.mark.slow  # long: run by CI's slow set (the README's command within 6 min)
def test_mixed_runs_by_law_share_the_checks_set_up(counts):
    """Mixed runs whose motion is a law are checked (counts, solvability) on the set-up they
    run from: one assembly and one analysis each, none in the run (before: 7 assemblies and
    6 analyses for the two runs)."""
    runner = Runner(mio.read(PENDULUM))
    checks, runs, res = _check_then_run(runner, counts)
    for name in ("constant_speed", "samples"):
        assert checks[name] == {"assemble": 1, "analyse": 1}
        assert runs[name] == {"assemble": 0, "analyse": 0}
    plan = runner.plans["constant_speed"]
    model = runner.model
    direct = md.mixed(
        model,
        plan.times,
        prescribed=[md.CoordinateDriver("prescribed rod.phi", "rod", "phi", law=md.Ramp(0, 2))],
        unknown=["motor"],
        solver="partition",
        rtol=1e-10,
        atol=1e-12,
        q0=runner.q_start(plan, model),
        hold=runner.hold(plan),
    )
    _same(res["constant_speed"], direct, ["motor", "pivot.Fy"])


def test_kinematic_and_inverse_runs_share_one_set_up(counts):
    """A kinematic and an inverse run from the same start share one assembly and one
    analysis, check and runs together (before: 3 and 3)."""
    spec = _short(SLIDER_CRANK, "time: {span: [0, pi], n: 181}", "time: {span: [0, 1], n: 11}")
    runner = Runner(spec)
    checks, runs, res = _check_then_run(runner, counts)
    assert checks == {
        "kinematics": {"assemble": 1, "analyse": 1},
        "inverse": {"assemble": 0, "analyse": 0},
    }
    assert runs == {
        "kinematics": {"assemble": 0, "analyse": 0},
        "inverse": {"assemble": 0, "analyse": 0},
    }
    model = runner.model
    _same(res["kinematics"], md.kinematic(model, runner.plans["kinematics"].times))
    _same(res["inverse"], md.inverse(model, runner.plans["inverse"].times), ["motor", "O.Fx"])


def test_execute_without_the_check_prepares_each_run_itself(counts):
    """``mixdyn.runs.execute`` (no check first): each run makes its own set-up, once."""
    spec = _short(SLIDER_CRANK, "time: {span: [0, pi], n: 181}", "time: {span: [0, 1], n: 3}")
    execute(spec, ["kinematics"])
    assert dict(counts) == {"assemble": 1, "analyse": 1}


# ------------------------------------------------------------------ a start for another set-up
@pytest.fixture(scope="module")
def antonya():
    model = mio.load(ANTONYA)
    hold = ("crank.phi", "coupler.phi")
    return model, hold, md.prepare(model, Forward(hold=hold)).start


def test_a_start_is_taken_by_an_analysis_that_makes_the_same(antonya, counts):
    """A forward analysis with another integration method, the same model and start
    settings, takes the start of a set-up: neither assembled nor analysed again, the same
    start and equations, bit for bit, as the set-up that makes its own."""
    model, hold, start = antonya
    other = Forward(method=md.Baumgarte(dt=1e-3), hold=hold)
    before = dict(counts)
    setup = md.prepare(model, other, start=start)
    assert dict(counts) == before  # nothing assembled or analysed
    assert setup.start is start
    own = md.prepare(model, other)
    assert dict(counts) != before  # the set-up without a start makes its own
    for a, b in ((setup.start.q, own.start.q), (setup.start.qd, own.start.qd)):
        np.testing.assert_array_equal(a, b)
    assert setup.start.keep == own.start.keep
    mine, theirs = (jax.tree_util.tree_flatten(x.problem) for x in (setup, own))
    assert mine[1] == theirs[1]
    for a, b in zip(mine[0], theirs[0], strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_start_made_otherwise_is_refused(antonya):
    model, hold, start = antonya
    wrong = {
        "another model": dict(model=model.replace(gravity=np.array([0.0, -9.81]))),
        "another start time": dict(t0=0.5),
        "another rough start": dict(q0=np.asarray(model.q0) + 0.1),
        "other held coordinates": dict(hold=("crank.phi",)),
        "another linear solver": dict(linear_solver="dense"),
        "other drivers": dict(
            model=model.replace(drivers=[md.CoordinateDriver("m", "crank", "phi", law=0.0)])
        ),
    }
    for why, change in wrong.items():
        kw = dict(model=model, t0=0.0, hold=hold)
        kw.update(change)
        m, t0 = kw.pop("model"), kw.pop("t0")
        with pytest.raises(ModelError, match=r"start: the start was made for another") as e:
            md.prepare(m, Forward(**kw), t0=t0, start=start)
        assert "start settings (q0, qd0, hold" in str(e.value), why
    with pytest.raises(ModelError, match="start: the start was made for another"):
        md.prepare(model, Kinematic(hold=hold), start=start)  # a dynamic start
    with pytest.raises(ModelError, match=r"start: .*setup\.start.*got dict"):
        md.prepare(model, Forward(hold=hold), start={})
    t = np.linspace(0.0, 0.1, 3)
    with (
        pytest.warns(DeprecationWarning, match=r"start=\.\.\."),  # the deprecated spelling
        pytest.raises(ModelError, match="start: the start was made for another"),
    ):
        md.forward(model, t, hold=("crank.phi",), prepared=start)


def test_a_mixed_run_refuses_a_start_for_other_prescribed_motions(antonya):
    model, _, _ = antonya
    hold = ("crank.phi",)  # the slider follows its prescribed motion
    motion = md.CoordinateDriver("x", "slider", "x", law=80.0)
    start = md.prepare(model, Mixed(prescribed=[motion], unknown=["F1"], hold=hold)).start
    other = md.CoordinateDriver("x", "slider", "x", law=81.0)
    with pytest.raises(ModelError, match=r"start: .*other drivers"):
        md.prepare(model, Mixed(prescribed=[other], unknown=["F1"], hold=hold), start=start)
    with (
        pytest.warns(DeprecationWarning, match="prepared= is deprecated"),
        pytest.raises(ModelError, match=r"start: .*other drivers"),
    ):
        md.check_mixed(model, [other], ["F1"], hold=hold, prepared=start)
    with pytest.warns(DeprecationWarning, match="prepared= is deprecated"):
        md.check_mixed(model, [motion], ["F1"], hold=hold, prepared=start)  # its own: checked


def test_a_kinematic_start_that_is_not_balanced_is_refused():
    """A start made without the balance check (the runner reports the balance itself,
    :meth:`Analysis._initial`) is refused by the analysis as its own start would be."""
    model = mio.load(SLIDER_CRANK)
    free = model.replace(drivers=())
    start = Kinematic()._initial(free, 0.0)
    with pytest.raises(DegreesOfFreedomError, match="1 degree"):
        md.prepare(free, Kinematic(), start=start)
    with pytest.raises(DegreesOfFreedomError, match="1 degree"):
        md.kinematic(free, [0.0, 0.1])
