"""Result units named plainly (issue 14): forces in N, torques in N*m, energies in J, powers in
W, with the SI prefix that makes them exactly the model's units (mN and mN*mm in mm, kg, s);
pint, reading both spellings, is the truth that they are the same unit."""

from __future__ import annotations

import pytest

import mixdyn as md
from fixtures import EXAMPLES
from mixdyn.io.quantities import factor
from mixdyn.units import DIMENSIONS

SYSTEMS = [
    md.SI,
    md.UnitSystem("mm", "kg", "s"),
    md.UnitSystem("mm", "g", "ms"),
    md.UnitSystem("cm", "g", "s"),
    md.UnitSystem("in", "lb", "s"),
    md.UnitSystem("km", "t", "s"),
]


@pytest.mark.parametrize("units", SYSTEMS, ids=lambda u: u.describe())
def test_every_label_is_exactly_the_models_unit(units):
    for kind in DIMENSIONS:
        label, base = units.label(kind), units.unit(kind)
        if not base:
            assert label == ""
            continue
        # pint's factor of each spelling into the model's unit of the kind: both exactly 1
        assert factor(label, kind, units) == pytest.approx(1.0, rel=1e-12), (kind, label)
        assert factor(base, kind, units) == pytest.approx(1.0, rel=1e-12), (kind, base)


def test_the_plain_names():
    si, mm = md.SI, md.UnitSystem("mm", "kg", "s")
    assert [si.label(k) for k in ("force", "torque", "energy", "power")] == ["N", "N*m", "J", "W"]
    assert [mm.label(k) for k in ("force", "torque", "energy", "power", "stiffness")] == [
        "mN",
        "mN*mm",
        "µJ",
        "µW",
        "mN/mm",
    ]
    assert md.UnitSystem("mm", "g", "ms").label("torque") == "N*mm"
    # no SI prefix is exact in inches and pounds: the base spelling
    assert md.UnitSystem("in", "lb", "s").label("force") == "lb*in/s**2"


def test_output_units_convert_the_written_results(tmp_path):
    """``output_units: {angle: deg, torque: N*mm, angular_velocity: rpm}``: results.csv holds
    the crank angle in degrees, its speed in rpm and the motor torque in N*mm (the API's values
    converted by pint's factors), and says so in meta.json; a kind or unit that does not fit is
    refused at its line."""
    import json
    import math

    import numpy as np
    from typer.testing import CliRunner

    import mixdyn.io as mio
    from mixdyn.cli import app

    example = EXAMPLES / "slider_crank.yaml"
    text = example.read_text().replace("n: 181", "n: 7")
    head = "output_units: {angle: deg, angular_velocity: rpm, torque: N*mm}\n"
    path = tmp_path / "u.yaml"
    path.write_text(head + text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--no-figures"])
    assert res.exit_code == 0, res.output
    api = mio.execute(mio.reads(text))
    for name, result in api.items():
        table = md.read_table(out / name)
        np.testing.assert_allclose(table["crank.phi"], np.degrees(result["crank.phi"]), rtol=1e-14)
        np.testing.assert_allclose(
            table["crank.omega"], result["crank.omega"] * 30 / math.pi, rtol=1e-14
        )
        np.testing.assert_array_equal(table["slider.x"], result["slider.x"])  # not asked: m
        meta = json.loads((out / name / "meta.json").read_text())
        assert meta["units"]["crank.phi"] == "deg" and meta["units"]["slider.x"] == "m"
        if result.kind == "inverse":
            np.testing.assert_allclose(table["motor"], 1000 * result["motor"], rtol=1e-14)
            assert meta["units"]["motor"] == "N·mm" == table.attrs["units"]["motor"]
    for bad, words in (
        ("{angel: deg}", "no kind of quantity 'angel'"),
        ("{torque: N}", "expected a torque"),
    ):
        path.write_text(f"output_units: {bad}\n" + text)
        res = CliRunner().invoke(app, ["check", str(path)])
        assert res.exit_code == 2 and words in res.output, res.output


def test_plot_draws_a_column_in_another_unit(tmp_path):
    """``mixdyn plot --unit crank.phi=deg``: the written radians drawn in degrees (the
    conversion checked on the table handed to the plot); a unit of another dimension, an
    unknown column or a malformed option are refused, naming ``--unit``."""
    import math

    import numpy as np
    from typer.testing import CliRunner

    from mixdyn.cli import app
    from mixdyn.io.results import column_in_unit

    example = EXAMPLES / "slider_crank.yaml"
    path = tmp_path / "s.yaml"
    path.write_text(example.read_text().replace("n: 181", "n: 7"))
    out = tmp_path / "out"
    assert (
        CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--no-figures"]).exit_code
        == 0
    )
    folder = out / "inverse"
    table = md.read_table(folder)
    units = table.attrs["units"]
    assert units["crank.phi"] == "rad" and units["motor"] == "N·m"
    conv, new = column_in_unit(table, units, "crank.phi=deg", folder, 0)
    np.testing.assert_allclose(conv["crank.phi"], table["crank.phi"] * 180 / math.pi, rtol=1e-14)
    conv, new = column_in_unit(table, units, "motor = N*mm", folder, 0)
    np.testing.assert_allclose(conv["motor"], 1000 * table["motor"], rtol=1e-14)
    assert new["motor"] == "N*mm" and units["motor"] == "N·m"
    ok = CliRunner().invoke(
        app,
        [
            "plot",
            str(folder),
            "-c",
            "crank.phi",
            "-u",
            "crank.phi=deg",
            "-o",
            str(tmp_path / "p.png"),
        ],
    )
    assert ok.exit_code == 0 and (tmp_path / "p.png").stat().st_size > 10_000, ok.output
    for bad, words in (
        ("motor=mm", "not a unit of"),
        ("rod.q=deg", "no column"),
        ("deg", "not COLUMN=UNIT"),
    ):
        res = CliRunner().invoke(app, ["plot", str(folder), "-c", "motor", "-u", bad])
        assert res.exit_code == 2 and words in res.output and "--unit 1" in res.output, res.output


def test_points_listed_in_outputs_are_written_and_the_api_converts_too(tmp_path):
    """``outputs: [rod.B]`` writes the point's x, y, vx, vy, ax, ay to results.csv, equal to
    ``Result.point`` (and so to the slider's own columns: rod.B is the slider's pin);
    ``Result.table(output_units=...)`` and ``Sweep.table(output_units=...)`` convert as the
    file does; a point that does not exist is refused at its line."""

    import numpy as np
    from typer.testing import CliRunner

    from mixdyn.cli import app

    example = EXAMPLES / "slider_crank.yaml"
    text = example.read_text().replace("n: 181", "n: 7")
    text = text.replace("    kind: inverse\n", "    kind: inverse\n    outputs: [rod.B]\n", 1)
    path = tmp_path / "p.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--no-figures"])
    assert res.exit_code == 0, res.output
    table = md.read_table(out / "inverse")
    for a, b in (("x", "x"), ("vx", "vx"), ("ax", "ax")):
        np.testing.assert_allclose(table[f"rod.B.{a}"], table[f"slider.{b}"], atol=1e-12)
    np.testing.assert_allclose(table["rod.B.y"], 0.0, atol=1e-12)
    path.write_text(text.replace("outputs: [rod.B]", "outputs: [rod.Q]"))
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2 and "outputs[0]" in res.output and "'Q'" in res.output

    import mixdyn.io as mio

    result = mio.execute(mio.reads(text), ["inverse"])["inverse"]
    df = result.table(["rod.B"], output_units={"angle": "deg", "length": "mm", "time": "ms"})
    np.testing.assert_allclose(df["crank.phi"], np.degrees(result["crank.phi"]), rtol=1e-14)
    np.testing.assert_allclose(df["rod.B.x"], 1000 * result.point("rod.B")[0][:, 0], rtol=1e-14)
    np.testing.assert_allclose(df["t"], 1000 * result.t, rtol=1e-14)
    assert df.attrs["units"]["rod.B.vx"] == "m/s" and df.attrs["units"]["rod.B.x"] == "mm"
    sweep = md.Sweep([result, None], {}, [{}, {}], {})
    long = sweep.table(["crank.phi"], output_units={"angle": "deg"})
    np.testing.assert_allclose(long["crank.phi"], np.degrees(result["crank.phi"]), rtol=1e-14)
    assert long.attrs["units"]["crank.phi"] == "deg"
