"""A model file's results from Python and on disk, the same numbers in every view (issue 32):
``mixdyn.load`` / ``mixdyn.run_file``, ``Result.table`` in the file's ``output_units`` with
``t`` a column as in ``results.csv``, ``name [unit]`` headers read back by
``mixdyn.read_table``, units in Parquet, figures returned, engineering unit labels, the
``SI`` and ``mm-N-s`` presets, plurals, help text and the first compile said off a terminal.

The truth is a uniform crank (mass m, length L, pinned at one end, in mm, kg, s) turned at a
constant rate w under gravity: its motor torque is m g L/2 cos(phi), its kinetic energy
m L^2 w^2 / 6, its power the torque times w, its centre at L/2 (cos phi, sin phi).
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from fixtures import CRANK_FILE
from mixdyn.cli import app
from mixdyn.units import engineering, factor, plain

M, L, W, G = 2.0, 0.25, 0.5, 9.81  # kg, m, rad/s, m/s^2

CRANK = CRANK_FILE


@pytest.fixture(scope="module")
def crank(tmp_path_factory):
    folder = tmp_path_factory.mktemp("crank")
    path = folder / "crank.yaml"
    path.write_text(CRANK)
    parquet = importlib.util.find_spec("pyarrow") is not None
    results = md.run_file(path, folder / "out", parquet=parquet)
    return path, folder / "out", results, parquet


def _truth(t):
    phi = W * t
    torque = M * G * L / 2 * np.cos(phi)  # N*m
    return {
        "crank.phi": np.degrees(phi),
        "crank.x": L / 2 * np.cos(phi),  # m
        "motor": torque,
        "motor.power": torque * W,  # W
        "energy.kinetic": np.full_like(t, M * L**2 * W**2 / 6),  # J
    }


def test_load_gives_the_model_its_runs_and_units(crank):
    path, _, _, _ = crank
    f = md.load(path)
    assert f.units == md.UnitSystem("mm", "kg", "s")
    assert list(f.runs) == ["turn"] and f.runs["turn"].kind == "inverse"
    assert [b.name for b in f.model.bodies] == ["crank"]
    assert f.output_units["angle"] == "deg" and f.output_units["power"] == "W"
    assert f.output_units["energy"] == "J" and f.output_units["torque"] == "N*m"
    # counted nouns take their number
    assert "1 body (3 coordinates), 1 joint (2 equations), 1 driver, 0 forces" in (
        f.model.summary()
    )


def test_the_table_is_in_the_files_units_with_t_a_column(crank):
    _, _, results, _ = crank
    r = results["turn"]
    df = r.table()
    assert list(df.columns[:2]) == ["t", "crank.x"]
    t = df["t"].to_numpy()
    np.testing.assert_allclose(t, np.linspace(0, 2, 11), rtol=0, atol=1e-15)
    for col, want in _truth(t).items():
        np.testing.assert_allclose(df[col], want, rtol=1e-9, atol=1e-12, err_msg=col)
    units = df.attrs["units"]
    assert (units["t"], units["crank.phi"], units["crank.x"]) == ("s", "deg", "m")
    assert (units["motor"], units["motor.power"], units["energy.kinetic"]) == ("N·m", "W", "J")
    assert units["crank.ax"] == "m/s²" and units["crank.alpha"] == "rad/s²"
    df[["t", "motor"]]  # no KeyError: t is a column
    np.testing.assert_array_equal(df.index, t)  # and the index: a column's plot is against t
    # the other preset: energy in mJ, torque in N*mm, lengths in mm
    mm = r.table(output_units="mm-N-s")
    truth = _truth(t)
    np.testing.assert_allclose(mm["energy.kinetic"], 1e3 * truth["energy.kinetic"], rtol=1e-9)
    np.testing.assert_allclose(mm["motor.power"], 1e3 * truth["motor.power"], rtol=1e-9)
    np.testing.assert_allclose(mm["motor"], 1e3 * truth["motor"], rtol=1e-9)
    assert mm.attrs["units"]["motor"] == "N·mm" and mm.attrs["units"]["motor.power"] == "mW"


def test_the_written_files_say_their_units_and_read_back(crank):
    _, out, results, parquet = crank
    r = results["turn"]
    head = (out / "turn" / "results.csv").read_text().partition("\n")[0].split(",")
    assert head[:4] == ["t [s]", "crank.x [m]", "crank.y [m]", "crank.phi [deg]"]
    assert "motor [N·m]" in head and "energy.kinetic [J]" in head
    back = md.read_table(out / "turn")
    api = r.table()
    assert list(back.columns) == list(api.columns)
    np.testing.assert_array_equal(back.index, api.index)
    np.testing.assert_allclose(back.to_numpy(), api.to_numpy(), rtol=1e-15, atol=0)
    assert back.attrs["units"] == {c: u for c, u in api.attrs["units"].items() if u}
    if parquet:
        pq = md.read_table(out / "turn" / "results.parquet")
        np.testing.assert_array_equal(pq[list(api.columns)].to_numpy(), api.to_numpy())
        from mixdyn.io.results import parquet_units

        assert parquet_units(out / "turn" / "results.parquet")["motor"] == "N·m"
    # a table of plain headers (an old-style file): names as they are, units from meta.json
    old = out / "old"
    old.mkdir()
    (old / "results.csv").write_text("t,slider.x\n0,0.5\n1,0.25\n")
    (old / "meta.json").write_text('{"units": {"t": "s", "slider.x": "m"}}')
    table = md.read_table(old)
    assert list(table.columns) == ["t", "slider.x"] and table.attrs["units"]["slider.x"] == "m"
    # mixdyn plot reads both, a unit changed on the way
    for folder in (out / "turn", old):
        col = "motor" if folder.name == "turn" else "slider.x"
        target = "N*mm" if col == "motor" else "mm"
        png = folder / "p.png"
        res = CliRunner().invoke(
            app, ["plot", str(folder), "-c", col, "-u", f"{col}={target}", "-o", str(png)]
        )
        assert res.exit_code == 0 and png.stat().st_size > 5_000, res.output


def test_plots_are_figures_of_the_tables_numbers(crank):
    from matplotlib.figure import Figure

    _, out, results, _ = crank
    r = results["turn"]
    fig = r.plot("motor", x="crank.phi")
    assert isinstance(fig, Figure)
    (line,) = fig.axes[0].get_lines()
    t = r.t
    np.testing.assert_allclose(line.get_xdata(), np.degrees(W * t), rtol=1e-12)
    np.testing.assert_allclose(line.get_ydata(), _truth(t)["motor"], rtol=1e-9)
    assert fig.axes[0].get_ylabel() == "motor [N·m]"
    assert fig.axes[0].get_xlabel() == "crank.phi [deg]"
    fig = md.viz.plot_columns(r.table(), ["motor", "crank.x"])
    assert isinstance(fig, Figure) and len(fig.axes) == 2  # a panel per unit
    path = md.viz.plot_columns(md.read_table(out / "turn"), ["motor"], out / "m.svg")
    assert path == out / "m.svg" and "N·m" in path.read_text()
    with pytest.raises(KeyError, match="motr"):
        r.plot(["motr"])


@pytest.mark.parametrize(
    "unit", ["mN*mm", "mm/s**2", "kg*mm**2", "N*m/rad", "rad/s**2", "µW", "um", "N*mm*s/rad"]
)
def test_engineering_labels_are_the_same_units(unit):
    """A label names the unit it was made from: pint's factor of each spelling into SI."""
    label = engineering(unit)
    assert "*" not in label and "**" not in label
    assert factor(label, None, md.SI) == pytest.approx(factor(unit, None, md.SI), rel=1e-15)
    assert plain(label) == unit.replace("um", "µm")


def test_energy_and_power_follow_the_torque_and_force_units_given_by_hand(crank, tmp_path):
    """Units given by hand without a preset: the energy and the power follow them (a motor's
    power in W, not in the model's mm-based unit) unless given themselves; the numbers are the
    closed form's in those units."""
    _, _, results, _ = crank
    r = results["turn"]
    df = r.table(output_units={"torque": "N*m"})  # the model in mm, kg, s
    truth = _truth(df["t"].to_numpy())
    units = df.attrs["units"]
    assert (units["motor"], units["energy.kinetic"], units["motor.power"]) == ("N·m", "J", "W")
    for col in ("motor", "energy.kinetic", "motor.power"):
        np.testing.assert_allclose(df[col], truth[col], rtol=1e-9, err_msg=col)
    df = r.table(output_units={"force": "kN", "length": "m", "time": "ms"})
    assert (df.attrs["units"]["energy.kinetic"], df.attrs["units"]["motor.power"]) == ("kJ", "MW")
    np.testing.assert_allclose(df["motor.power"], 1e-6 * truth["motor.power"], rtol=1e-9)
    df = r.table(output_units={"torque": "N*m", "power": "kW"})  # given: kept
    np.testing.assert_allclose(df["motor.power"], 1e-3 * truth["motor.power"], rtol=1e-9)
    path = tmp_path / "c.yaml"  # a file's output_units say the same
    path.write_text(CRANK.replace("{preset: SI, angle: deg}", "{torque: N*m}"))
    f = md.load(path)
    assert (f.output_units["energy"], f.output_units["power"]) == ("J", "W")


def test_a_preset_is_checked_at_its_line(tmp_path):
    path = tmp_path / "c.yaml"
    for given, words in (("SI", None), ("{preset: SI, torque: N*mm}", None), ("SJ", "SI, mm-N-s")):
        path.write_text(CRANK.replace("{preset: SI, angle: deg}", given))
        res = CliRunner().invoke(app, ["check", str(path)])
        if words is None:
            assert res.exit_code == 0, res.output
        else:
            assert res.exit_code == 2 and "output_units" in res.stderr and words in res.stderr
    path.write_text(CRANK.replace("{preset: SI, angle: deg}", "{preset: SI, torque: N*mm}"))
    assert md.load(path).output_units["torque"] == "N*mm"  # a kind given beats the preset's


def test_help_is_wrapped_by_the_formatter(monkeypatch):
    """Each command's summary fills its lines (no break mid-sentence), and text in brackets
    (``[unit]``, ``[xarray]``) is shown, not taken for markup."""
    monkeypatch.setenv("COLUMNS", "100")
    text = CliRunner().invoke(app, ["--help"]).output
    rows = [line.strip("│ ") for line in text.splitlines() if line.startswith("│")]
    summary, current = {}, None
    for row in rows:
        first, _, rest = row.partition(" ")
        if first in ("show", "check", "run", "plot", "animate", "schema", "dump", "server"):
            current = first
            summary[current] = [rest.strip()]
        elif current is not None and row.strip():
            summary[current].append(row.strip())
    assert set(summary) >= {"check", "run", "dump"}
    for name, lines in summary.items():
        for line in lines[:-1]:  # every line but a paragraph's last is nearly full
            assert len(line) > 70, (name, line)
    assert 'each header "name [unit]"' in " ".join(summary["run"])
    run_help = " ".join(CliRunner().invoke(app, ["run", "--help"]).output.split())
    assert "mixdyn[xarray]" in run_help.replace("│ ", "").replace(" │", "")


def test_off_a_terminal_the_first_compile_is_said_once(crank, monkeypatch):
    """``mixdyn run`` off a terminal asks for one line at the first compile; the hook calls
    it once, at the first program compiled from scratch, and is cleared after the run."""
    import jax.numpy as jnp

    from mixdyn.runtime import _programs

    path, out, _, _ = crank
    seen = []
    real = _programs.on_first_compile
    monkeypatch.setattr(_programs, "on_first_compile", lambda fn: seen.append(fn) or real(fn))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out / "cli"), "--no-figures"])
    assert res.exit_code == 0, res.output
    assert callable(seen[0]) and seen[-1] is None  # set for the runs, cleared after
    said = []
    real(lambda: said.append(1))

    @_programs.cached_jit
    def fresh(x):
        return jnp.sin(x) * 3.0

    fresh(jnp.zeros(7))
    fresh(jnp.zeros(9))  # another program: said once only
    assert said == [1]
    real(None)
