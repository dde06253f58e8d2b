"""A model file's sweep held as arrays (:func:`mixdyn.runs.sweep._as_arrays`): where the
varied numbers reach only forces and bodies' masses and inertias and the members run as one
vectorized program, the members are one stacked problem, and the member table, the long
table (a point's columns and the file's ``output_units`` included) and the summaries are read
from the arrays, no member's result built. Truth: each member's single run of the file with
its numbers written in (a second method, member by member), and the same sweep run member by
member (:func:`~mixdyn.analysis._members.run_members`)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import mixdyn.io as mio
from fixtures import EXAMPLES, FORWARD_RUN, SWEEP_MODEL
from mixdyn.runs import Runner, execute, setup, sweep_members
from mixdyn.runs import sweep as file_sweep

MODEL = SWEEP_MODEL

BASE = FORWARD_RUN

#: Three values of F1's amplitude (a parameter in its law) by two slider masses (a
#: parameter in the body's mass), two members vectorized at a time.
SWEEP = """
  - name: sweep
    kind: sweep
    run: forward
    batch_size: 2
    vary:
      F0: {values: [6, 9, 14]}
      m5: {values: [0.006, 0.01]}
    summaries:
      - {name: x_max, column: slider.x, reduce: max}
      - {name: turn, column: crank.phi, reduce: last}
      - {name: d_rms, column: D.Fx, reduce: rms}
      - {name: f_range, column: slider.F.vx, reduce: range}
      - {name: d_mean, column: D.Fx, reduce: mean}
    outputs: [slider.x, crank.phi, D.Fx, slider.F.vx]
"""

SWEEP_OUTPUTS = ["slider.x", "crank.phi", "D.Fx", "slider.F.vx"]

OUTPUT_UNITS = {"angle": "deg", "force": "N"}
UNITS = "output_units: {angle: deg, force: N}\n"

#: The reductions of a member's column, written out (the truth of the summaries).
REDUCE = {
    "x_max": ("slider.x", np.max),
    "turn": ("crank.phi", lambda y: y[-1]),
    "d_rms": ("D.Fx", lambda y: np.sqrt(np.mean(y**2))),
    "f_range": ("slider.F.vx", lambda y: np.max(y) - np.min(y)),
    "d_mean": ("D.Fx", np.mean),
}


def _single(f0: float, m5: float):
    """The member's truth: the file's nominal run with ``F0`` and ``m5`` written in."""
    text = MODEL.replace("  F0: 10 ", f"  F0: {float(f0)!r} ")
    text = text.replace("  m5: 0.00786", f"  m5: {float(m5)!r}")
    return execute(mio.reads(text + BASE))["forward"]


@pytest.fixture(scope="module")
def swept():
    return execute(mio.reads(UNITS + MODEL + BASE + SWEEP), ["sweep"])["sweep"]


def _close(a, b, rtol: float, what) -> None:
    """``a`` equals ``b`` to ``rtol`` of ``b``'s largest magnitude (NaN where ``b`` is)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert np.array_equal(np.isnan(a), np.isnan(b)), what
    a, b = a[~np.isnan(b)], b[~np.isnan(b)]
    scale = max(float(np.max(np.abs(b), initial=0.0)), 1e-300)
    assert float(np.max(np.abs(a - b), initial=0.0)) <= rtol * scale, what


@pytest.mark.slow  # long: run by CI's slow set
def test_the_sweep_is_held_as_arrays_and_no_member_result_is_built(swept):
    assert swept.sweep.stacked is not None and swept.sweep.stacked.count == 6
    swept.members(), swept.table()
    assert len(swept.sweep.results._built) <= 1  # the first member's, for the names


@pytest.mark.slow  # long: run by CI's slow set
def test_tables_equal_the_single_runs_of_the_edited_file(swept):
    """Each member's rows of the long table and its summaries equal its single run's
    columns (in degrees and newtons) and their reductions."""
    members, table = swept.members(), swept.table()
    assert list(members.columns) == [
        "member", "F0", "m5", "status", "error", "t_error", *REDUCE
    ]  # fmt: skip
    assert list(table.columns) == ["member", "F0", "m5", "t", *SWEEP_OUTPUTS]
    for i, (f0, m5) in enumerate(zip(members["F0"], members["m5"], strict=True)):
        single = _single(f0, m5)
        cols = single.table(points=["slider.F"], output_units=OUTPUT_UNITS)
        rows = table[table["member"] == i]
        assert (rows["F0"] == f0).all() and (rows["m5"] == m5).all()
        np.testing.assert_array_equal(rows["t"], cols["t"])
        for c in SWEEP_OUTPUTS:
            _close(rows[c], cols[c], 1e-10, (i, c))
        for name, (column, reduce) in REDUCE.items():
            _close(members[name][i], reduce(np.asarray(cols[column])), 1e-10, (i, name))
    assert swept.units["turn"] == "deg" and swept.units["d_rms"] == "N"
    assert len(set(members["x_max"].round(9))) == 6  # the numbers did change the motion


@pytest.mark.slow  # long: run by CI's slow set
def test_tables_equal_the_sweep_run_member_by_member(swept, monkeypatch):
    monkeypatch.setattr(file_sweep, "_as_arrays", lambda *a, **k: None)
    one_by_one = execute(mio.reads(UNITS + MODEL + BASE + SWEEP), ["sweep"])["sweep"]
    assert one_by_one.sweep.stacked is None
    for a, b in ((swept.members(), one_by_one.members()), (swept.table(), one_by_one.table())):
        assert list(a.columns) == list(b.columns) and len(a) == len(b)
        for c in a.columns:
            if a[c].dtype.kind == "f":
                _close(a[c], b[c], 1e-12, c)
            else:
                assert list(a[c]) == list(b[c]), c
    assert swept.units == one_by_one.units


def test_a_part_is_built_once_for_each_value_of_its_parameters(monkeypatch):
    """The members' varied leaves are those of the model built from the file with the
    member's numbers written in, and each part (F1's law, the slider's mass) is built once
    for each value of the parameter it names: 3 + 2 builds for the 3 x 2 grid."""
    built = []
    leaves_of = sweep_members._leaves
    monkeypatch.setattr(sweep_members, "_leaves", lambda *a: built.append(a[0]) or leaves_of(*a))
    runner = Runner(mio.reads(MODEL + BASE + SWEEP))
    plan = runner.plans["sweep"]
    _, model, _ = setup.call(runner, plan.base, {}, checked=False)
    quick = sweep_members.quick_members(runner, plan, model)
    assert len(built) == 3 + 2 and quick.count == 6
    assert quick.names == ("slider.mass", "F1[0]")
    for i, (f0, m5) in enumerate(zip(plan.values["F0"], plan.values["m5"], strict=True)):
        text = MODEL.replace("  F0: 10 ", f"  F0: {float(f0)!r} ")
        truth = jax.tree.leaves(
            Runner(mio.reads(text.replace("  m5: 0.00786", f"  m5: {float(m5)!r}") + BASE)).model
        )
        for k, column in zip(quick.positions, quick.values, strict=True):
            np.testing.assert_array_equal(column[i], np.asarray(truth[k]))
        member = jax.tree.leaves(quick.models[i])
        for a, b in zip(member, truth, strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_the_summaries_reduce_every_member_at_once_as_one_by_one():
    """A summary's reduction of (M, N) columns gives, row by row, the reduction of each
    member's (N,) column, written out here."""
    y = np.random.default_rng(3).normal(size=(5, 17))
    truth = {
        "max": max, "min": min, "absmax": lambda r: max(abs(v) for v in r),
        "mean": lambda r: sum(r) / len(r), "rms": lambda r: (sum(v * v for v in r) / len(r)) ** 0.5,
        "first": lambda r: r[0], "last": lambda r: r[-1], "range": lambda r: max(r) - min(r),
    }  # fmt: skip
    assert set(truth) == set(file_sweep._REDUCE)
    for name, reduce in file_sweep._REDUCE.items():
        rows = reduce(y)
        assert rows.shape == (5,)
        for i in range(5):
            assert abs(rows[i] - truth[name](list(y[i]))) <= 1e-14, name
            assert rows[i] == reduce(y[i]), name


def _same_tables(ours, theirs):
    """The sweep's members and table equal another way's: the same columns and rows, numbers
    to 1e-12, the rest exactly."""
    for a, b in zip(ours, theirs, strict=True):
        assert list(a.columns) == list(b.columns) and len(a) == len(b)
        for c in a.columns:
            if a[c].dtype.kind == "f":
                _close(a[c], b[c], 1e-12, c)
            else:
                assert list(a[c]) == list(b[c]), c


INVERSE = (
    (EXAMPLES / "slider_crank.yaml").read_text().split("\nruns:")[0]
    + """
runs:
  - name: inverse
    kind: inverse
    time: {span: [0, 1], n: 11}
  - name: sweep
    kind: sweep
    run: inverse
    vary:
      slider.mass: {values: [0.5, 1.0, 2.5]}
      rod.inertia: {values: [0.01, 0.03]}
    summaries:
      - {name: peak, column: motor, reduce: absmax}
    outputs: [motor, B.Fx]
"""
)


@pytest.mark.slow  # long: run by CI's slow set
def test_an_inverse_file_sweep_shares_the_motion_and_equals_the_single_runs(monkeypatch):
    """An inverse sweep over masses and inertias (its members sharing the drivers' motion:
    the array path taken at 2 members here) writes the tables of each member's single run
    of the file with its numbers written in, and of the sweep run member by member."""
    monkeypatch.setattr(file_sweep, "CHUNK", 2)
    swept = execute(mio.reads(INVERSE), ["sweep"])["sweep"]
    assert swept.sweep.stacked is not None and not swept.sweep.errors
    members, table = swept.members(), swept.table()
    for i, (m, j) in enumerate(zip(members["slider.mass"], members["rod.inertia"], strict=True)):
        text = INVERSE.replace(
            "  - name: slider\n    mass: 1\n", f"  - name: slider\n    mass: {m!r}\n"
        )
        text = text.replace(
            "  - name: rod\n    mass: 1\n    inertia: 0.01\n",
            f"  - name: rod\n    mass: 1\n    inertia: {j!r}\n",
        )
        single = execute(mio.reads(text), ["inverse"])["inverse"]
        rows = table[table["member"] == i]
        for c in ("motor", "B.Fx"):
            _close(rows[c], single[c], 1e-12, (i, c))
        _close(members["peak"][i], np.max(np.abs(single["motor"])), 1e-12, i)
    assert len(set(members["peak"].round(9))) == 6  # the numbers did change the torque
    monkeypatch.setattr(file_sweep, "_as_arrays", lambda *a, **k: None)
    one_by_one = execute(mio.reads(INVERSE), ["sweep"])["sweep"]
    _same_tables((members, table), (one_by_one.members(), one_by_one.table()))


KINEMATIC = (
    (EXAMPLES / "slider_crank.yaml").read_text().split("\nruns:")[0]
    + """
runs:
  - name: kinematics
    kind: kinematic
    time: {span: [0, 1], n: 11}
  - name: sweep
    kind: sweep
    run: kinematics
    vary:
      l: {values: [250 mm, 300 mm, 420 mm]}
      omega: {values: [2 rad/s, 3.5 rad/s]}
    summaries:
      - {name: reach, column: slider.x, reduce: max}
      - {name: swing, column: rod.B.vx, reduce: absmax}
    outputs: [slider.x, rod.phi, rod.B.vx]
"""
)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_kinematic_file_sweep_held_as_arrays_equals_the_single_runs(monkeypatch):
    """A kinematic sweep over the rod's length (its points: each member built from its file,
    its own start) and the crank speed, held as arrays (two members a call here): its tables
    are those of each member's single run of the file with its numbers written in, and of
    the sweep run member by member."""
    from mixdyn.analysis import _kinematic_members

    monkeypatch.setattr(file_sweep, "CHUNK", 2)
    monkeypatch.setattr(_kinematic_members, "CHUNK", 2)
    swept = execute(mio.reads(KINEMATIC), ["sweep"])["sweep"]
    assert isinstance(swept.sweep.stacked, _kinematic_members.KinematicStack)
    assert not swept.sweep.errors
    members, table = swept.members(), swept.table()
    assert len(swept.sweep.results._built) <= 1  # the first member's, for the names
    for i, (l, w) in enumerate(zip(members["l"], members["omega"], strict=True)):
        text = KINEMATIC.replace("  l: 300 mm ", f"  l: {l!r} m ")
        text = text.replace("  omega: 2 rad/s ", f"  omega: {w!r} rad/s ")
        single = execute(mio.reads(text), ["kinematics"])["kinematics"]
        cols = single.table(points=["rod.B"])
        rows = table[table["member"] == i]
        for c in ("slider.x", "rod.phi", "rod.B.vx"):
            _close(rows[c], cols[c], 1e-12, (i, c))
        _close(members["reach"][i], np.max(cols["slider.x"]), 1e-12, i)
        _close(members["swing"][i], np.max(np.abs(cols["rod.B.vx"])), 1e-12, i)
    assert len(set(members["reach"].round(9))) == 3  # the rod's length did change the reach
    monkeypatch.setattr(file_sweep, "_prepared_arrays", lambda *a, **k: None)
    one_by_one = execute(mio.reads(KINEMATIC), ["sweep"])["sweep"]
    assert one_by_one.sweep.stacked is None
    _same_tables((members, table), (one_by_one.members(), one_by_one.table()))


#: The slider-crank's gas force as a parameter ``F`` (a force: each member shares the
#: start where only it varies), its statics swept over the rod's length and the force.
STATICS = (
    (EXAMPLES / "slider_crank.yaml")
    .read_text()
    .split("\nruns:")[0]
    .replace("law: 50 N}", "law: F}")
    .replace("  omega: 2 rad/s", "  F: 50 N\n  omega: 2 rad/s")
    + """
runs:
  - name: statics
    kind: statics
    time: {span: [0, 1], n: 6}
  - name: sweep
    kind: sweep
    run: statics
    vary:
      l: {values: [250 mm, 420 mm]}
      F: {values: [20 N, 50 N]}
    summaries:
      - {name: peak, column: motor, reduce: absmax}
    outputs: [motor, slider.x, B.Fx]
"""
)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_statics_file_sweep_held_as_arrays_equals_member_by_member_and_virtual_work(
    monkeypatch,
):
    """A quasi-static sweep over the rod's length (each member prepared from its file) and
    the gas force, held as arrays (two members a call here): its tables are those of the
    sweep run member by member, no member's result built but the first, and each member's
    motor torque is the static one by virtual work, ``F dx/dth`` with the slider's
    ``x = r cos th + sqrt(l^2 - r^2 sin^2 th)``, ``th = omega t`` (written out here)."""
    from mixdyn.analysis import _static_members

    monkeypatch.setattr(file_sweep, "CHUNK", 2)
    monkeypatch.setattr(_static_members, "CHUNK", 2)
    swept = execute(mio.reads(STATICS), ["sweep"])["sweep"]
    assert isinstance(swept.sweep.stacked, _static_members.StaticStack)
    assert not swept.sweep.errors
    members, table = swept.members(), swept.table()
    assert len(swept.sweep.results._built) <= 1  # the first member's, for the names
    r, omega = 0.1, 2.0
    for i, (l, f) in enumerate(zip(members["l"], members["F"], strict=True)):
        rows = table[table["member"] == i]
        th = omega * np.asarray(rows["t"])
        s = np.sin(th)
        root = np.sqrt(l**2 - r**2 * s**2)
        _close(rows["slider.x"], r * np.cos(th) + root, 1e-10, (i, "x"))
        _close(rows["motor"], f * (-r * s - r**2 * s * np.cos(th) / root), 1e-10, (i, "motor"))
        _close(rows["B.Fx"], np.full(len(th), f), 1e-10, (i, "B.Fx"))
    monkeypatch.setattr(file_sweep, "_prepared_arrays", lambda *a, **k: None)
    one_by_one = execute(mio.reads(STATICS), ["sweep"])["sweep"]
    assert one_by_one.sweep.stacked is None
    _same_tables((members, table), (one_by_one.members(), one_by_one.table()))
