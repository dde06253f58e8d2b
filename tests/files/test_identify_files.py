"""Identification runs of model files (``kind: identify``): the example's recording gives the
numbers back within their noise-implied deviations, as the Python API does from the same data;
noise-free data gives a damper's coefficient back to the tolerances; a bad run, data file or
number is refused at its line (exit 2) before any computing."""

from __future__ import annotations

import importlib.util
import json
import sys

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from fixtures import EXAMPLES, IDENTIFY_RUNS
from mixdyn.cli import app

TEXT = (EXAMPLES / "identify_slider_crank.yaml").read_text()
MODEL = TEXT.split("\nruns:")[0]

IDENTIFY = IDENTIFY_RUNS


def _example():
    path = EXAMPLES / "identify_slider_crank.py"
    spec = importlib.util.spec_from_file_location("identify_slider_crank", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _write(tmp_path, runs=IDENTIFY, data=None):
    if data is None:
        t = np.linspace(0.0, 1.0, 41)
        true = mio.reads(
            MODEL.replace("damping: 1.2", "damping: 2.0") + runs.split("  - name: identify")[0]
        )
        res = mio.execute(true, ["forward"])["forward"]
        data = pd.DataFrame({"t": t, "v": res["slider.vx"]})
    data.to_csv(tmp_path / "rec.csv", index=False, float_format="%.17g")
    path = tmp_path / "fit.yaml"
    path.write_text(MODEL + runs)
    return path


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_noise_free_velocities_give_the_damper_back(tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(_write(tmp_path)), "--out", str(out)])
    assert res.exit_code == 0, res.output
    fit = pd.read_csv(out / "identify" / "fit.csv")
    assert list(fit["parameter"]) == ["damper.damping"] and fit["start"][0] == 1.2
    assert abs(fit["estimate"][0] - 2.0) <= 1e-6 * 2.0
    meta = json.loads((out / "identify" / "meta.json").read_text())
    assert meta["fit"]["chi2_reduced"] < 1e-8
    # results.csv: the run at the estimate, which reproduces the data
    run = mio.read_table(out / "identify")
    data = pd.read_csv(tmp_path / "rec.csv")
    np.testing.assert_allclose(run["slider.vx"], data["v"], rtol=0, atol=1e-6)
    assert (out / "identify" / "fit.png").stat().st_size > 10_000


@pytest.mark.slow  # four numbers fitted twice (40 s here); CI runs it
@pytest.mark.timeout(900)
def test_the_example_recovers_its_numbers_as_the_api_does(tmp_path):
    """examples/identify_slider_crank.yaml from its recording (seed 0): every estimate within
    4 deviations of the truth, the reduced chi-square near 1, and the same estimates as
    md.fit in Python from the same data and start."""
    ex = _example()
    out = tmp_path / "out"
    res = CliRunner().invoke(
        app, ["run", str(EXAMPLES / "identify_slider_crank.yaml"), "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    fit = pd.read_csv(out / "identify" / "fit.csv")
    est, sd = fit["estimate"].to_numpy(), fit["std_dev"].to_numpy()
    assert list(fit["parameter"]) == ex.PARAMS
    assert np.all(np.abs(est - ex.TRUE) <= 4 * sd), (est, sd)
    meta = json.loads((out / "identify" / "meta.json").read_text())
    assert 0.5 < meta["fit"]["chi2_reduced"] < 2.0
    api, api_sd, _, _ = ex.identify(0)
    np.testing.assert_allclose(est, api, rtol=1e-6)
    np.testing.assert_allclose(sd, api_sd, rtol=1e-4)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (("run: forward\n    data", "run: nope\n    data"), "unknown run 'nope'"),
        (("data: rec.csv", "data: missing.csv"), "no data file"),
        (("data: rec.csv", "data: ../rec.csv"), "relative to the model file"),
        (("data: v,", "data: w,"), "has no column 'w'"),
        (("column: slider.vx", "column: slider.q"), "not a body coordinate or velocity"),
        (("noise: 1 mm/s", "noise: 1 mm"), "expected a velocity"),
        (("noise: 1 mm/s", "noise: 0"), "noise must be > 0"),
        (("damper.damping:", "damper.stiffnes:"), "no field 'stiffnes'"),
        (("damper.damping:", "O.si:"), "geometry"),
        (("bounds: [0, 10]", "bounds: [3, 1]"), "are empty"),
    ],
)
def test_a_bad_identify_run_is_refused_before_computing(tmp_path, edit, words):
    old, new = edit
    assert old in IDENTIFY
    data = pd.DataFrame({"t": [0.0, 0.5, 1.0], "v": [0.0, 0.1, 0.2]})
    path = _write(tmp_path, IDENTIFY.replace(old, new, 1), data)
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert words in res.output and "fit.yaml" in res.output


def test_bad_data_is_refused_at_the_data_line(tmp_path):
    for frame, words in (
        (pd.DataFrame({"t": [0.0, 0.5, 0.5], "v": [0.0, 0.1, 0.2]}), "increasing"),
        (pd.DataFrame({"time": [0.0, 0.5], "v": [0.0, 0.1]}), "no column 't'"),
        (pd.DataFrame({"t": [0.0, 0.5], "v": ["a", 0.1]}), "not a finite number (row 2)"),
    ):
        res = CliRunner().invoke(app, ["check", str(_write(tmp_path, IDENTIFY, frame))])
        assert res.exit_code == 2 and words in res.output, res.output
    mixed = (
        IDENTIFY
        + """
  - name: back
    kind: mixed
    time: {span: [0, 1], n: 41}
    unknown: [motor]
    prescribed:
      - {coordinate: crank.phi, from_run: identify}
"""
    )
    data = pd.DataFrame({"t": [0.0, 0.5, 1.0], "v": [0.0, 0.1, 0.2]})
    res = CliRunner().invoke(app, ["check", str(_write(tmp_path, mixed, data))])
    assert res.exit_code == 2 and "is an identify run" in res.output, res.output


def test_a_recording_with_units_in_its_headers_is_read_in_them(tmp_path):
    """A recording with ``name [unit]`` headers (as results.csv writes them): times in ms and
    speeds in mm/s give the same measurements as the same data in the model's units (m, s);
    a unit of another kind than the measured column's is refused at the measurement's line."""
    from mixdyn.io import FileError
    from mixdyn.runs import Runner

    t = np.linspace(0.0, 1.0, 41)
    v = 0.3 * np.sin(2 * np.pi * t)  # m/s
    plans = []
    for header, scale in (("t,v", 1.0), ("t [ms],v [mm/s]", 1e3)):
        rows = "".join(f"{a * scale:.17g},{b * scale:.17g}\n" for a, b in zip(t, v, strict=True))
        (tmp_path / "rec.csv").write_text(f"{header}\n{rows}")
        path = tmp_path / "fit.yaml"
        path.write_text(MODEL + IDENTIFY)
        plans.append(Runner(mio.read(path)).plans["identify"])
    plain, with_units = plans
    np.testing.assert_allclose(with_units.times, plain.times, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(
        with_units.measured["slider.vx"], plain.measured["slider.vx"], rtol=1e-15, atol=1e-18
    )
    rows = "".join(f"{a},{b}\n" for a, b in zip(t, v, strict=True))
    (tmp_path / "rec.csv").write_text("t,v [deg]\n" + rows)
    with pytest.raises(FileError, match="angle") as err:
        Runner(mio.read(tmp_path / "fit.yaml"))
    assert "run 'identify', measured[0].data" in err.value.one_line()
