"""Plots and animations: files of the right kind, size and frame count, and not blank."""

import math
import re

import numpy as np
import pytest
from PIL import Image

import mixdyn as md
from fixtures import four_bar, slider_crank
from mixdyn.viz import Scene, animate, html, plot_columns, result_columns


@pytest.fixture(scope="module")
def motion():
    model = slider_crank()
    return md.kinematic(model, np.linspace(0, math.pi, 61))


def test_png_plot(motion, tmp_path):
    cols, units = result_columns(motion, ["slider.x", "crank.A.y", "rod.B.vx"])
    assert units["crank.A.y"] == "m" and units["rod.B.vx"] == "m/s"
    np.testing.assert_allclose(cols["crank.A.y"], 0.1 * np.sin(2 * motion.t), atol=1e-12)
    path = plot_columns(
        cols,
        ["slider.x", "crank.A.y"],
        tmp_path / "p.png",
        units=units,
        title="slider",
        reference=(motion.t, 0.1 * np.sin(2 * motion.t), "exact"),
        size=(6, 4),
        dpi=100,
    )
    with Image.open(path) as im:
        assert im.size == (600, 400)
        assert len(im.convert("RGB").getcolors(maxcolors=100_000)) > 50


def test_svg_and_bad_suffix(motion, tmp_path):
    cols, units = result_columns(motion, ["slider.x"])
    text = plot_columns(cols, ["slider.x"], tmp_path / "p.svg", units=units).read_text()
    assert text.lstrip().startswith("<?xml") and "<svg" in text and len(text) > 5000
    with pytest.raises(ValueError, match=r"use \.png"):
        plot_columns(cols, ["slider.x"], tmp_path / "p.txt")
    with pytest.raises(KeyError, match="no column"):
        result_columns(motion, ["slider.nope"])
    with pytest.raises(KeyError, match=r"did you mean 'slider\.x'") as info:
        result_columns(motion, ["Slider.X"])  # case and a typo: close matches only
    assert "crank.omega" not in str(info.value)


def test_a_panel_per_unit_and_any_x_column(motion, tmp_path):
    """An angle, a speed and an acceleration get a panel each (one axis would flatten two of
    them); columns of one unit share a panel; the x axis may be any column."""
    names = ["crank.phi", "crank.omega", "slider.ax", "rod.ax"]
    cols, units = result_columns(motion, [*names, "slider.x"])
    svg = plot_columns(cols, names, tmp_path / "p.svg", units=units).read_text()
    assert svg.count('<g id="axes_') == 3  # rad, rad/s, m/s**2
    one = plot_columns(cols, ["slider.ax", "rod.ax"], tmp_path / "q.svg", units=units)
    assert one.read_text().count('<g id="axes_') == 1
    against = plot_columns(cols, ["slider.ax"], tmp_path / "r.png", units=units, x="crank.phi")
    with Image.open(against) as im:
        assert len(im.convert("RGB").getcolors(maxcolors=100_000)) > 50
    with pytest.raises(KeyError):
        plot_columns(cols, ["slider.ax"], tmp_path / "s.png", x="crank.nope")


def test_gif_frames_and_motion(motion, tmp_path):
    path = animate(motion, tmp_path / "a.gif", frames=25, fps=10, trace=["crank.A"], dpi=60)
    with Image.open(path) as gif:
        assert gif.n_frames == 25
        assert gif.size[0] >= 300 and gif.size[1] >= 150
        assert gif.info["duration"] == 100
        frames = []
        for k in (0, 12):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB")))
    assert np.mean(frames[0] != frames[1]) > 0.001


def test_gif_shows_every_frame_as_drawn(motion, tmp_path, monkeypatch):
    """Each frame of the GIF, decoded, is the frame drawn (on the one palette): the frames
    written as differences (unchanged pixels transparent), without Pillow's per-frame
    palette remapping, still add up to the drawing."""
    from mixdyn.viz import _draw

    writers = []
    make = _draw._gif_writer

    def keep(fps):
        writers.append(make(fps))
        return writers[-1]

    monkeypatch.setattr(_draw, "_gif_writer", keep)
    path = animate(motion, tmp_path / "a.gif", frames=12, trace=["crank.A"], dpi=50)
    drawn = [np.asarray(f.convert("RGB")) for f in writers[0]._frames]
    with Image.open(path) as gif:
        assert gif.n_frames == len(drawn) == 12
        for k, want in enumerate(drawn):
            gif.seek(k)
            np.testing.assert_array_equal(np.asarray(gif.convert("RGB")), want)


def test_no_more_frames_than_outputs(tmp_path):
    model = four_bar()
    res = md.kinematic(model, np.linspace(0, 1, 7))
    path = animate(None, tmp_path / "a.gif", model=model, t=res.t, q=res.q, frames=50)
    with Image.open(path) as gif:
        assert gif.n_frames == 7


def test_html_is_self_contained(motion, tmp_path):
    page = html(motion, tmp_path / "a.html", frames=30, trace=["crank.A"]).read_text()
    assert page.startswith("<!DOCTYPE html>") and "<canvas" in page and "<script>" in page
    assert "src=" not in page and "http" not in page.split("<script>")[1]
    assert '"crank"' in page and '"slider"' in page
    assert page.count('"t":[') == 1


def test_mp4_needs_ffmpeg(motion, tmp_path, monkeypatch):
    import shutil

    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(ValueError, match="ffmpeg"):
        animate(motion, tmp_path / "a.mp4")
    with pytest.raises(ValueError, match=r"use \.gif"):
        animate(motion, tmp_path / "a.avi")


def test_scene_outlines(motion):
    scene = Scene(motion.model, motion.q[:3], trace=["rod.B"])
    # the crank and rod are bars (their points are in a line); the slider, with none, a block
    assert [o.shape[1] for o in scene.outlines] == [2, 2, 4]
    np.testing.assert_allclose(scene.traces[0], motion.q[:3, 6:8], atol=1e-12)
    x0, x1, y0, y1 = scene.bounds
    assert x0 < 0 < 0.4 < x1 and y0 < 0 < y1
    assert scene.guides.shape == (1, 2, 2)


def test_report_page_is_self_contained_with_ranges_units_and_figures(motion, tmp_path):
    """The page holds every column's range (its min and max from the result) with its unit,
    the drawing and the figures inline (data URIs), and nothing fetched."""
    from mixdyn.viz.report import Report, scene_svg

    figure = plot_columns(
        *result_columns(motion, ["crank.phi"])[:1], ["crank.phi"], tmp_path / "a.png"
    )
    cols = motion.columns()
    units = motion.units()
    page = Report(
        path=tmp_path / "report.html",
        title="slider-crank: run turn",
        facts=[("run", "turn (kinematic)")],
        drawing=scene_svg(Scene(motion.model, motion.q[:1])),
        figures=[figure, tmp_path / "not-drawn.png"],
        columns=cols,
        units=units,
        settings={"kind": "kinematic", "time": {"span": [0, 3.14]}},
    ).write()
    text = page.read_text()
    assert "http" not in text and "<script" not in text and 'src="file' not in text
    assert text.count('src="data:image/png;base64,') == 1 and "<svg" in text
    ranges = re.search(r'<table class="ranges">(.*?)</table>', text).group(1)
    rows = re.findall(r"<tr><td>([^<]*)</td><td>([^<]*)</td><td class=n>([^<]*)</td>"
                      r"<td class=n>([^<]*)</td></tr>", ranges)  # fmt: skip
    assert [r[0] for r in rows] == list(cols)
    for name, unit, lo, hi in rows:
        assert unit == units.get(name, "")
        assert float(lo) == pytest.approx(np.min(cols[name]), rel=1e-5, abs=1e-12)
        assert float(hi) == pytest.approx(np.max(cols[name]), rel=1e-5, abs=1e-12)
    assert "<td>time.span</td><td>[0, 3.14]</td>" in text
    assert "Energy balance" not in text  # a kinematic run has no energies


def test_report_energy_balance_against_hand_made_energies():
    """A falling mass (T = t^2/2, V = -t^2/2) balances; a drag's work Wn = -t^3/3 must be
    counted; an error put in by hand is the error reported."""
    from mixdyn.viz.report import energy_balance

    t = np.linspace(0.0, 2.0, 21)
    T, V, Wn = 0.5 * t**2 - t**3 / 3, -0.5 * t**2, -(t**3) / 3
    cols = {"energy.kinetic": T, "energy.potential": V, "work.nonconservative": Wn}
    rows = {w: v for w, v, _ in energy_balance(cols, {"energy.kinetic": "J"})}
    assert rows["largest balance error |T + V - (T0 + V0) - Wn - Wc|"] == pytest.approx(
        0, abs=1e-14
    )
    assert rows["change of T + V"] == pytest.approx(-8 / 3)
    cols["energy.kinetic"] = T + 0.01 * t
    rows = {w: v for w, v, _ in energy_balance(cols, {})}
    assert rows["largest balance error |T + V - (T0 + V0) - Wn - Wc|"] == pytest.approx(0.02)
    assert energy_balance({"t": t}, {}) is None
    # without work columns (an inverse run's) the energies are shown, no balance claimed
    rows = energy_balance({"energy.kinetic": T, "energy.potential": V}, {})
    assert not any("balance" in w or "work" in w for w, _, _ in rows)
    assert {w: v for w, v, _ in rows}["change of T + V"] == pytest.approx(T[-1] + V[-1])


def test_the_players_numbers_are_rounded_as_python_formats_them():
    """The player's numbers, rounded to 9 significant digits at once, equal Python's own
    ``float(f"{v:.9g}")`` number by number, across magnitudes (tiny, subnormal, huge, zero)
    and for the NaN rows that lift a symbol's pen (``null`` in the page)."""
    from mixdyn.viz.player import nine_digits

    rng = np.random.default_rng(7)
    a = rng.normal(size=20_000) * 10.0 ** rng.integers(-40, 40, 20_000)
    a[:6] = [0.0, -0.0, 1e-300, 5e-324, 1.7e308, 123456789.5]
    want = [float(f"{v:.9g}") for v in a.tolist()]
    assert nine_digits(a).tolist() == want
