"""The members of a model file's sweep made from the swept run's model
(:mod:`mixdyn.runs.sweep_members`): where the varied numbers reach only forces and bodies'
masses and inertias, each member's model holds the numbers of the model built from the file
with the member's values written in (leaf for leaf), and its results equal that file's single
run; where a varied number reaches anything else, each member is built from its file and its
results equal the single run all the same; members sharing a start run in vectorized chunks
with the same results."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import mixdyn.io as mio
from fixtures import FORWARD_RUN, SWEEP_MODEL
from mixdyn.runs import Runner, execute, setup, sweep_members
from mixdyn.runs import sweep as file_sweep
from mixdyn.runs.sweep_members import quick_members

MODEL = SWEEP_MODEL

BASE = FORWARD_RUN

COLUMNS = ("slider.x", "crank.phi", "D.Fx", "work.nonconservative")


def _sweep(vary: str) -> str:
    return MODEL + BASE + (
        "  - name: sweep\n    kind: sweep\n    run: forward\n    vary:\n" + vary +
        "    summaries:\n      - {name: x_max, column: slider.x, reduce: max}\n"
    )  # fmt: skip


def _edited(text: str, values: dict[str, float]) -> str:
    """The file with the member's values written in place of the nominal ones."""
    for line, value in values.items():
        head = line.split(":")[0]
        assert line in text, line
        text = text.replace(line, f"{head}: {value!r}", 1)
    return text


#: The vary entries and, per member, file line -> its value: forces (T reaches two torques)
#: and a body's inertia by its path (the crank's is the file's first inertia line).
QUICK = (
    "      T: {values: [400, 650]}\n      crank.inertia: {values: [15, 25]}\n",
    [{"  T: 500": t, "    inertia: 20.2313": j} for t in (400.0, 650.0) for j in (15.0, 25.0)],
)


def _members(text: str):
    runner = Runner(mio.reads(text))
    plan = runner.plans["sweep"]
    _, model, _ = setup.call(runner, plan.base, {}, checked=False)
    return runner, plan, model


def test_the_members_models_are_the_models_built_from_the_edited_file():
    runner, plan, model = _members(_sweep(QUICK[0]))
    quick = quick_members(runner, plan, model)
    assert quick is not None and set(quick.reached) == {"M2", "M3", "crank.inertia"}
    for member, values in zip(quick.models, QUICK[1], strict=True):
        truth = Runner(mio.reads(_edited(MODEL, values) + BASE)).model
        assert jax.tree.structure(member) == jax.tree.structure(truth)
        for a, b in zip(jax.tree.leaves(member), jax.tree.leaves(truth), strict=True):
            assert np.array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize(
    ("vary", "members", "quick"),
    [
        (*QUICK, True),
        (
            "      y0: {values: [0.0, 1.5, 3.0]}\n",
            [{"    q0: [0, 25, 0]": "[y0, 25, 0]"} for _ in range(3)],
            False,
        ),
    ],
    ids=["forces-and-inertia", "start-guess"],
)
def test_members_equal_the_single_runs_of_the_edited_file(vary, members, quick):
    text = _sweep(vary)
    if not quick:  # a parameter y0 in the crank's start guess
        text = text.replace("  m5: 0.00786", "  m5: 0.00786\n  y0: 0").replace(
            "    q0: [0, 25, 0]", "    q0: [y0, 25, 0]"
        )
    runner, plan, model = _members(text)
    assert (quick_members(runner, plan, model) is not None) is quick
    swept = execute(mio.reads(text), ["sweep"])["sweep"]
    assert not swept.sweep.errors and len(swept.sweep) == len(members)
    for i, values in enumerate(members):
        if quick:
            single_text = _edited(MODEL, values) + BASE
        else:
            y0 = float(plan.values["y0"][i])
            single_text = MODEL.replace("    q0: [0, 25, 0]", f"    q0: [{y0!r}, 25, 0]") + BASE
        single = execute(mio.reads(single_text))["forward"]
        for c in COLUMNS:
            scale = float(np.max(np.abs(single[c])))
            assert float(np.max(np.abs(swept.sweep[i][c] - single[c]))) <= 1e-12 * scale, (i, c)
    ends = {round(float(r["crank.phi"][-1]), 9) for r in swept.sweep.results}
    assert len(ends) == (len(members) if quick else 1)  # the numbers did change the motion


@pytest.mark.slow
def test_members_in_chunks_equal_the_single_runs(monkeypatch):
    """Members sharing a start run in vectorized chunks (two members here; the last chunk
    filled up with a copy of its first member), each reported done once."""
    monkeypatch.setattr(sweep_members, "CHUNK", 2)
    text = _sweep("      T: {values: [400, 500, 650]}\n")
    runner, plan, _ = _members(text)
    assert sweep_members.chunk_size(None, plan.members) == 2
    done = []
    swept = file_sweep.execute(runner, plan, done.append)
    assert sorted(done) == [0, 1, 2] and not swept.sweep.errors
    for i, t in enumerate((400.0, 500.0, 650.0)):
        single = execute(mio.reads(_edited(MODEL, {"  T: 500": t}) + BASE))["forward"]
        for c in COLUMNS:
            scale = float(np.max(np.abs(single[c])))
            assert float(np.max(np.abs(swept.sweep[i][c] - single[c]))) <= 1e-12 * scale, (i, c)
