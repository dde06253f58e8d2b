"""Sweeps (``md.sweep``): every member equals the single run with its numbers, on both paths
(member by member from threads; one vectorized program); a failed member is reported by
index and cause without losing the others; bad input is refused before any computing."""

from __future__ import annotations

import importlib
import importlib.util
import pickle

import numpy as np
import pytest

import mixdyn as md
from fixtures import new_traces, paper_mechanism, paper_under_loads, slider_crank, traced_now
from mixdyn.analysis.sweep import vary_models

TS = np.linspace(0.0, 1.0, 51)
OPTS = dict(rtol=1e-8, atol=1e-10)
#: Columns compared with the single runs: motion, a reaction, the work of the loads.
COLUMNS = ("slider.x", "crank.phi", "B.Fx", "EF.M", "work.nonconservative")


@pytest.fixture(scope="module")
def paper():
    """The paper's mechanism under its loads (T2, T3 constant, F1 = 10 sin(pi t / 2))."""
    return paper_under_loads()


VARY = md.grid(**{"slider.mass": [0.00786, 0.02], "F1.law.amplitude": [10.0, -25.0]})


def _same(a: md.Result, b: md.Result, rel=1e-10):
    for c in COLUMNS:
        scale = max(float(np.max(np.abs(b[c]))), 1e-300)
        assert float(np.max(np.abs(a[c] - b[c]))) <= rel * scale, c


def test_grid_is_every_combination():
    g = md.grid(a=[1, 2], b=[10, 20, 30])
    assert list(zip(g["a"], g["b"], strict=True)) == [
        (1, 10),
        (1, 20),
        (1, 30),
        (2, 10),
        (2, 20),
        (2, 30),
    ]


@pytest.mark.timeout(600)
@pytest.mark.parametrize("batch_size", [None, 2], ids=["member-by-member", "vectorized"])
def test_forward_members_equal_single_runs(paper, batch_size):
    """Each member, on both paths (the vectorized one under a timeout: a vmapped
    ``while_loop`` has deadlocked XLA's CPU runtime), equals ``md.forward`` of its model."""
    sw = md.sweep(paper, TS, vary=VARY, batch_size=batch_size, **OPTS)
    assert len(sw) == 4 and not sw.errors
    if batch_size is not None:  # held as arrays: no member's Result built before it is read
        assert repr(sw.results) == "<4 results, 0 built>"
    members = vary_models(paper, VARY)
    for i, m in enumerate(members):
        assert float(m.bodies[3].mass) == VARY["slider.mass"][i]
        _same(sw[i], md.forward(m, TS, **OPTS))
    # the members differ: the numbers reached the equations
    assert abs(sw[0]["slider.x"][-1] - sw[3]["slider.x"][-1]) > 1.0
    table = sw.table(["slider.x"])
    assert list(table.columns) == ["member", "slider.mass", "F1.law.amplitude", "t", "slider.x"]
    assert len(table) == 4 * len(TS)
    assert table.attrs["units"]["slider.x"] == "mm"
    if batch_size is not None:
        _held_as_arrays(paper, sw)


def _held_as_arrays(paper, sw):
    """The vectorized sweep is held as arrays: its results are built when read, each equal
    (every column, 1e-12 of its scale) to the member finished at once from the same
    integration (the member-by-member finishing of one program: ``_members.run_members``);
    its (member, t) columns are those results'; its Dataset's coordinates are the varied
    values and its units the results' (in ``output_units`` where asked)."""
    members_module = importlib.import_module("mixdyn.analysis._members")
    eager = members_module.run_members(vary_models(paper, VARY), TS, _forward(), batch_size=2)
    cols, units = sw.columns()
    for i, (res, err) in enumerate(eager):
        assert err is None
        for c, v in res.columns().items():
            scale = max(float(np.max(np.abs(v))), 1e-300)
            assert float(np.max(np.abs(sw[i][c] - v))) <= 1e-12 * scale, c
            got = cols[c] if c == "t" else cols[c][i]
            assert float(np.max(np.abs(got - v))) <= 1e-12 * scale, c
        assert res.units() == units
    assert cols["slider.x"].shape == (4, len(TS))
    kept = pickle.loads(pickle.dumps(sw.results))  # pickled as the list of its results
    assert isinstance(kept, list) and np.array_equal(kept[3]["slider.x"], sw[3]["slider.x"])
    table = sw.table(["slider.x"], output_units={"length": "m"})  # read from the arrays
    for i in range(4):
        rows = table[table["member"] == i]
        assert float(rows["slider.mass"].iloc[0]) == VARY["slider.mass"][i]
        np.testing.assert_array_equal(rows["slider.x"].to_numpy(), sw[i]["slider.x"] / 1000)
    if importlib.util.find_spec("xarray") is None:
        return
    ds = sw.to_xarray(["slider.x", "EF.M"], output_units={"length": "m"})
    for name in VARY:
        np.testing.assert_array_equal(ds[name].values, VARY[name])
    assert ds["slider.x"].attrs["units"] == "m" and ds["EF.M"].attrs["units"] == units["EF.M"]
    np.testing.assert_allclose(ds["slider.x"].values, cols["slider.x"] / 1000, rtol=1e-15)
    assert list(ds["status"].values) == ["ok"] * 4 and ds.attrs["analysis"] == "forward"


def _forward():
    return md.analyses.Forward(method=md.Projection(**OPTS))


def test_a_second_sweep_with_other_numbers_traces_nothing(paper):
    vary = {"T2.law.value": [400.0, 600.0, 700.0]}
    md.sweep(paper, TS, vary=vary, **OPTS)
    before = traced_now()
    sw = md.sweep(paper, TS, vary={"T2.law.value": [450.0, 550.0, 650.0]}, **OPTS)
    assert new_traces(before) == {}
    assert not sw.errors


def _count_setups(monkeypatch, analysis: str) -> list:
    """A list that grows by one at each set-up of a member of a sweep of ``analysis``."""
    members_module = importlib.import_module("mixdyn.analysis._members")
    calls, real = [], members_module.prepare

    def counting(model, value, **k):
        if value.name == analysis:
            calls.append(1)
        return real(model, value, **k)

    monkeypatch.setattr(members_module, "prepare", counting)
    return calls


@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.timeout(900)
@pytest.mark.parametrize("batch_size", [None, 2], ids=["member-by-member", "vectorized"])
def test_mixed_members_equal_single_runs(paper, monkeypatch, batch_size):
    """The paper's mixed run (F1 unknown, the slider's x prescribed) over the crank's torque:
    each member equals ``md.mixed``; at the paper's numbers F1 = 10 sin(pi t / 2). The
    torque does not enter the start, and F1 is collocated with the slider's motion: the
    members share one set-up (the unknown force's own numbers would not be shared)."""
    sweep_module = importlib.import_module("mixdyn.analysis.sweep")
    assert sweep_module.shares_start(paper, {"T2.law.value": [1]}, unknown=["F1"])
    assert not sweep_module.shares_start(paper, {"F1.law.amplitude": [1]}, unknown=["F1"])
    calls = _count_setups(monkeypatch, "mixed")
    fwd = md.forward(paper, TS, rtol=1e-10, atol=1e-10)
    kw = dict(
        prescribed=[md.prescribe(fwd, "slider.x")],
        unknown=["F1"],
        solver="partition",
        independent=["coupler.phi"],
        rtol=1e-10,
        atol=1e-10,
    )
    vary = {"T2.law.value": [500.0, 520.0]}
    sw = md.sweep(paper, TS, vary=vary, analysis="mixed", batch_size=batch_size, **kw)
    assert not sw.errors and len(calls) == (0 if batch_size else 1)
    if batch_size:  # held as arrays (set up once, by _stacked), built when read
        assert sw.stacked is not None and repr(sw.results) == "<2 results, 0 built>"
        cols, units = sw.columns()
        assert cols["F1"].shape == (2, len(TS)) and units["F1"] == sw[0].units()["F1"]
        for i in range(2):
            np.testing.assert_array_equal(cols["F1"][i], sw[i]["F1"])
    for i, m in enumerate(vary_models(paper, vary)):
        single = md.mixed(m, TS, **kw)
        assert np.max(np.abs(sw[i]["F1"] - single["F1"])) <= 1e-10 * 10.0
    assert np.max(np.abs(sw[0]["F1"] - 10.0 * np.sin(np.pi * TS / 2))) < 1e-5
    assert np.max(np.abs(sw[1]["F1"] - 10.0 * np.sin(np.pi * TS / 2))) > 1e-3


@pytest.mark.parametrize(
    "batch_size",
    [None, pytest.param(3, marks=pytest.mark.slow)],  # long: run by CI's slow set
    ids=["member-by-member", "vectorized"],
)
def test_a_failed_member_is_reported_and_the_others_kept(paper, batch_size):
    """A member whose run needs more steps than allowed fails by name; the others finish
    (held as arrays: the screen finishes the failed member at once, NaN in its rows)."""
    vary = {"T2.law.value": [500.0, 50_000.0, 520.0]}
    sw = md.sweep(paper, TS, vary=vary, max_steps=400, batch_size=batch_size, **OPTS)
    if batch_size:
        cols, _ = sw.columns()
        assert np.isnan(cols["slider.x"][1]).all() and np.isfinite(cols["slider.x"][[0, 2]]).all()
    assert set(sw.errors) == {1}
    assert isinstance(sw.errors[1], md.NumericalError)
    assert "step limit" in str(sw.errors[1])
    with pytest.raises(md.NumericalError):
        sw[1]
    assert sw.results[0] is not None and sw.results[2] is not None
    assert sorted(set(sw.table(["slider.x"])["member"])) == [0, 2]


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        ({"slider.mas": [1.0]}, "no field 'mas'"),
        ({"piston.mass": [1.0]}, "no body or element 'piston'"),
        ({"slider": [1.0]}, "'name.field'"),
        ({"EF.si": [[0.0, 0.0]]}, "geometry"),
        ({"EF.axis": [1.0]}, "structure"),
        ({"slider.mass": [1.0, 2.0], "crank.mass": [1.0]}, "1 values where"),
        ({"slider.mass": [1.0, np.nan]}, "member 1"),
        ({"slider.q0": [1.0, 2.0]}, "one row of shape (3,)"),
        ({}, "nothing to vary"),
    ],
)
def test_bad_variations_are_refused_by_name(paper, vary, words):
    with pytest.raises(md.ModelError, match=None) as err:
        md.sweep(paper, TS, vary=vary)
    assert words in str(err.value)


def test_a_member_of_another_structure_is_refused(paper):
    other = paper_mechanism(forces=[md.Torque("T2", "crank", law=md.Harmonic(1.0, 1.0))])
    with pytest.raises(md.ModelError, match="member 1 differs"):
        md.sweep(models=[paper, other], t=TS)


def test_a_members_input_error_names_the_member(paper):
    with pytest.raises(md.ModelError) as err:
        md.sweep(paper, TS, vary={"slider.mass": [0.01, 0.0]})
    assert "member 1 of the sweep" in "".join(getattr(err.value, "__notes__", []))


def test_members_varying_only_masses_and_forces_share_one_set_up(paper, monkeypatch):
    """Masses, inertias and forces do not enter a forward run's start: the sweep sets up the
    nominal model once (the members still equal their single runs:
    ``test_forward_members_equal_single_runs`` varies exactly these); a varied start is set
    up member by member."""
    sweep_module = importlib.import_module("mixdyn.analysis.sweep")

    assert sweep_module.shares_start(paper, {"slider.mass": [1], "F1.law.amplitude": [1]})
    assert sweep_module.shares_start(paper, {"crank.inertia": [1]})
    assert not sweep_module.shares_start(paper, {"crank.q0": [[0, 0, 0]]})
    assert not sweep_module.shares_start(paper, {})
    calls = _count_setups(monkeypatch, "forward")
    sw = md.sweep(paper, TS[:6], vary={"slider.mass": [0.01, 0.02, 0.03]}, **OPTS)
    assert len(calls) == 1 and not sw.errors and {"setup", "total"} <= set(sw.seconds)
    single = md.forward(vary_models(paper, {"slider.mass": [0.03]})[0], TS[:6], **OPTS)
    _same(sw[2], single)


@pytest.mark.slow  # starts two worker processes (20 s here); CI runs it
@pytest.mark.timeout(600)
def test_a_dask_cluster_sweep_equals_the_in_process_one(paper):
    """Two worker processes of a local Dask cluster: every member equals the in-process
    sweep's, its chunk's members sharing one start (a force varies) as there; a failed
    member's error crosses the process boundary whole (class, time); an input error names
    its member."""
    distributed = pytest.importorskip("distributed")
    vary = {"T2.law.value": [500.0, 50_000.0, 520.0, 480.0]}
    local = md.sweep(paper, TS, vary=vary, max_steps=400, **OPTS)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        seen = []
        sw = md.sweep(
            paper,
            TS,
            vary=vary,
            max_steps=400,
            client=client,
            chunk_size=2,
            on_member=seen.append,
            **OPTS,
        )
        with pytest.raises(md.ModelError) as err:
            md.sweep(paper, TS, vary={"slider.mass": [0.01, 0.0]}, client=client)
    assert sorted(seen) == [0, 1, 2, 3]  # progress from the cluster, a member each
    assert set(sw.errors) == set(local.errors) == {1}
    assert type(sw.errors[1]) is type(local.errors[1])
    assert sw.errors[1].time == local.errors[1].time
    for i in (0, 2, 3):
        np.testing.assert_array_equal(sw[i].q, local[i].q)
        np.testing.assert_array_equal(sw[i]["B.Fx"], local[i]["B.Fx"])
    assert "member 1 of the sweep" in "".join(getattr(err.value, "__notes__", []))


def test_kinematic_and_inverse_members_equal_single_runs():
    """Any analysis sweeps: a kinematic sweep over the crank's law (rows of coefficients) and
    an inverse sweep over the masses, each member equal to its single run; ``on_member``
    sees every member once."""
    model = slider_crank()
    t = np.linspace(0.0, 1.0, 21)
    laws = {"motor.law.coeffs": [[0.0, 2.0], [0.3, 5.0], [1.0, -3.0]]}
    seen = []
    kin = md.sweep(model, t, vary=laws, analysis="kinematic", on_member=seen.append)
    assert sorted(seen) == [0, 1, 2] and not kin.errors
    for i, m in enumerate(vary_models(model, laws)):
        single = md.kinematic(m, t)
        np.testing.assert_allclose(kin[i].q, single.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(kin[i].qdd, single.qdd, rtol=1e-10, atol=1e-12)
    masses = md.grid(**{"rod.mass": [0.5, 2.0], "slider.mass": [1.0, 4.0]})
    inv = md.sweep(model, t, vary=masses, analysis="inverse")
    efforts = []
    for i, m in enumerate(vary_models(model, masses)):
        single = md.inverse(m, t)
        for c in ("motor", "B.Fx", "slide.Fy"):
            scale = float(np.max(np.abs(single[c])))
            assert float(np.max(np.abs(inv[i][c] - single[c]))) <= 1e-10 * scale, c
        efforts.append(float(np.max(np.abs(single["motor"]))))
    assert len(set(efforts)) == 4  # the masses do change the motor torque
    with pytest.raises(md.ModelError, match="member by member"):
        md.sweep(model, t, vary=masses, analysis="inverse", batch_size=4)


def test_latin_hypercube_samples_each_stratum_once():
    """Each range cut into n strata gets exactly one sample per stratum; the seed fixes the
    members; the pairing of strata differs between paths."""
    n = 50
    a = md.latin_hypercube(n, seed=3, **{"slider.mass": (0.005, 0.02), "F1.law.amplitude": (5, 15)})
    for name, (lo, hi) in {"slider.mass": (0.005, 0.02), "F1.law.amplitude": (5, 15)}.items():
        v = a[name]
        assert v.shape == (n,) and np.all((v >= lo) & (v < hi))
        assert sorted(np.floor((v - lo) / (hi - lo) * n).astype(int)) == list(range(n))
    b = md.latin_hypercube(n, seed=3, **{"slider.mass": (0.005, 0.02), "F1.law.amplitude": (5, 15)})
    c = md.latin_hypercube(n, seed=4, **{"slider.mass": (0.005, 0.02), "F1.law.amplitude": (5, 15)})
    np.testing.assert_array_equal(a["slider.mass"], b["slider.mass"])
    assert not np.array_equal(a["slider.mass"], c["slider.mass"])
    rank = lambda x: np.argsort(np.argsort(x))  # noqa: E731
    assert not np.array_equal(rank(a["slider.mass"]), rank(a["F1.law.amplitude"]))
    with pytest.raises(md.ModelError, match="low < high"):
        md.latin_hypercube(4, **{"slider.mass": (1.0, 1.0)})
    with pytest.raises(md.ModelError, match="whole number"):
        md.latin_hypercube(0, **{"slider.mass": (1.0, 2.0)})


def test_a_sweep_as_a_labelled_array(tmp_path):
    """Sweep.dataset(): a variable per column on (member, t), the varied numbers and the
    members' status as coordinates, units in attrs; equal to the long table; written to
    NetCDF and read back equal."""
    xr = pytest.importorskip("xarray")
    from fixtures import slider_crank

    model = slider_crank()
    t = np.linspace(0, 1, 5)
    sw = md.sweep(model, t, vary={"slider.mass": [1.0, 2.0, 3.0]}, analysis="inverse")
    ds = sw.dataset(["motor", "slider.x"], output_units={"torque": "N*mm"})
    assert ds["motor"].dims == ("member", "t") and ds.sizes == {"member": 3, "t": 5}
    np.testing.assert_array_equal(ds["slider.mass"], [1.0, 2.0, 3.0])
    assert list(ds["status"].values) == ["ok"] * 3
    for i in range(3):
        np.testing.assert_allclose(ds["motor"][i], 1000 * sw[i]["motor"], rtol=1e-14)
    assert ds["motor"].attrs["units"] == "N*mm" and ds["slider.x"].attrs["units"] == "m"
    path = tmp_path / "sweep.nc"
    ds.to_netcdf(path, engine="scipy")
    back = xr.load_dataset(path, engine="scipy")
    np.testing.assert_array_equal(back["motor"].values, ds["motor"].values)


@pytest.mark.slow  # long: run by CI's slow set
def test_an_inverse_sweep_held_as_arrays():
    """64 inverse members over masses share the drivers' motion: member 0 is run, every
    member post-processed along its motion by one program, no result built before it is
    read; each member equals ``md.inverse`` of its model (efforts, reactions, motion), its
    columns those of the arrays, the Dataset's coordinates the varied masses."""
    model = slider_crank()
    t = np.linspace(0.0, 1.0, 5)
    vary = {"slider.mass": np.linspace(1.0, 4.0, 64), "rod.mass": np.linspace(2.0, 0.5, 64)}
    sw = md.sweep(model, t, vary=vary, analysis=md.analyses.Inverse())
    assert sw.stacked is not None and repr(sw.results) == "<64 results, 0 built>"
    cols, units = sw.columns()
    members = vary_models(model, vary)
    efforts = set()
    for i in (0, 17, 63):
        single = md.inverse(members[i], t)
        assert set(sw[i].columns()) == set(single.columns()) and units == single.units()
        for c in ("motor", "B.Fx", "slide.Fy", "slider.x"):
            scale = float(np.max(np.abs(single[c])))
            assert float(np.max(np.abs(sw[i][c] - single[c]))) <= 1e-12 * scale, c
            assert float(np.max(np.abs(cols[c][i] - single[c]))) <= 1e-12 * scale, c
        efforts.add(float(np.max(np.abs(single["motor"]))))
    assert len(efforts) == 3  # the masses reach the efforts
    if importlib.util.find_spec("xarray") is not None:
        ds = sw.dataset(["motor"])
        np.testing.assert_array_equal(ds["rod.mass"].values, vary["rod.mass"])
        assert ds["motor"].attrs["units"] == units["motor"] and ds.attrs["analysis"] == "inverse"
