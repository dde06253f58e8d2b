"""One set-up per run: the model-file check makes the start and the mobility analysis a run
starts from (``Runner.prepare``), and the analysis, handed it (``prepared=``), neither
assembles nor analyses again; the results are those of the analyses called directly; a set-up
made for another call is refused."""

import collections
import pathlib

import numpy as np
import pytest

import mixdyn as md
import mixdyn.analysis as an
import mixdyn.analysis._prepare as prepare_module
import mixdyn.analysis._start as start_module
import mixdyn.analysis._structure as structure_module
import mixdyn.io as mio
from fixtures import DATA, ROOT, antonya_mixed
from mixdyn.analysis._prepare import prepare_dynamic, prepare_kinematic
from mixdyn.analysis.mixed import bind_prescribed
from mixdyn.errors import DegreesOfFreedomError, ModelError

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


def _check_then_run(runner: mio.Runner, counts) -> tuple[dict, dict, dict]:
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
    runner = mio.Runner(mio.reads(ANTONYA.read_text(), ANTONYA.name))
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


def test_mixed_runs_by_law_share_the_checks_set_up(counts):
    """Mixed runs whose motion is a law are checked (counts, solvability) on the set-up they
    run from: one assembly and one analysis each, none in the run (before: 7 assemblies and
    6 analyses for the two runs)."""
    runner = mio.Runner(mio.read(PENDULUM))
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
    runner = mio.Runner(spec)
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
    """``mixdyn.io.execute`` (no check first): each run makes its own set-up, once."""
    spec = _short(SLIDER_CRANK, "time: {span: [0, pi], n: 181}", "time: {span: [0, 1], n: 3}")
    mio.execute(spec, ["kinematics"])
    assert dict(counts) == {"assemble": 1, "analyse": 1}


# ------------------------------------------------------------------ a set-up for another call
@pytest.fixture(scope="module")
def antonya():
    model = mio.load(ANTONYA)
    hold = ("crank.phi", "coupler.phi")
    return model, hold, prepare_dynamic(model, 0.0, hold=hold)


def test_a_mismatched_set_up_is_refused(antonya):
    model, hold, prep = antonya
    t = np.linspace(0.0, 0.1, 3)
    wrong = {
        "another model": dict(model=model.replace(gravity=np.array([0.0, -9.81]))),
        "another start time": dict(t=t + 0.5),
        "another rough start": dict(q0=np.asarray(model.q0) + 0.1),
        "another rough start ": dict(hold=("crank.phi",)),
        "the linear solver": dict(linear_solver="dense"),
        "other drivers": dict(
            model=model.replace(drivers=[md.CoordinateDriver("m", "crank", "phi", law=0.0)])
        ),
    }
    for why, change in wrong.items():
        kw = dict(model=model, t=t, hold=hold)
        kw.update(change)
        with pytest.raises(ModelError, match=f"prepared: .*{why.strip()}"):
            md.forward(kw.pop("model"), kw.pop("t"), prepared=prep, **kw)
    with pytest.raises(ModelError, match="a dynamic run's start"):
        md.kinematic(model, t, hold=hold, prepared=prep)
    with pytest.raises(ModelError, match=r"prepared: .*Prepared\), got dict"):
        md.forward(model, t, hold=hold, prepared={})


def test_a_mixed_run_refuses_a_set_up_for_other_prescribed_motions(antonya):
    model, _, _ = antonya
    hold = ("crank.phi",)  # the slider follows its prescribed motion
    motion = md.CoordinateDriver("x", "slider", "x", law=80.0)
    bound = bind_prescribed(model, [motion])
    prep = prepare_dynamic(model, 0.0, drivers=(*model.drivers, *bound), hold=hold)
    other = md.CoordinateDriver("x", "slider", "x", law=81.0)
    t = np.linspace(0.0, 0.1, 3)
    kw = dict(unknown=["F1"], hold=hold, prepared=prep)
    with pytest.raises(ModelError, match=r"prepared: .*other drivers"):
        md.mixed(model, t, prescribed=[other], **kw)
    with pytest.raises(ModelError, match=r"prepared: .*other drivers"):
        md.check_mixed(model, [other], ["F1"], hold=hold, prepared=prep)
    md.check_mixed(model, [motion], ["F1"], hold=hold, prepared=prep)  # its own: checked


def test_a_kinematic_set_up_that_is_not_balanced_is_refused():
    """A set-up made without the balance check (the runner reports the balance itself) is
    refused by the analysis as the analysis' own set-up would be."""
    model = mio.load(SLIDER_CRANK)
    free = model.replace(drivers=())
    prep = prepare_kinematic(free, 0.0, balanced=False)
    with pytest.raises(DegreesOfFreedomError, match="1 degree"):
        md.kinematic(free, [0.0, 0.1], prepared=prep)
    with pytest.raises(DegreesOfFreedomError, match="1 degree"):
        md.kinematic(free, [0.0, 0.1])
