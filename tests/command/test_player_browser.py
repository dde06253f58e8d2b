"""The HTML player in headless Chromium: the page opened at two times shows the mechanism where
the result says it is (each bar's pixels at the bar's position from the result's coordinates,
through the page's stated view), the force arrows along the result's reactions, every frame of
the result, a time readout equal to the result's time, a canvas at the screen's pixel
density, and two different pictures.

Skipped where no Chromium is installed, unless ``MIXDYN_REQUIRE_BROWSER`` is set (CI sets it
and installs Debian's chromium: a missing browser then fails the test).
"""

import html as htmllib
import json
import math
import os
import re
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

import mixdyn as md
from fixtures import slider_crank
from mixdyn.viz import Scene, html

CHROMIUM = next(
    (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None
)
REQUIRED = bool(os.environ.get("MIXDYN_REQUIRE_BROWSER"))
pytestmark = pytest.mark.skipif(
    CHROMIUM is None and not REQUIRED, reason="no Chromium here (CI installs it)"
)
DPR = 2
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--window-size=1000,800",
    f"--force-device-scale-factor={DPR}",
    "--virtual-time-budget=1500",
]


def chromium(tmp_path, url: str, what: str, height: int = 800) -> str | None:
    assert CHROMIUM is not None, "MIXDYN_REQUIRE_BROWSER is set but no Chromium is installed"
    profile = tmp_path / f"profile-{len(list(tmp_path.iterdir()))}"
    flags = [
        f if not f.startswith("--window-size") else f"--window-size=1000,{height}" for f in FLAGS
    ]
    args = [CHROMIUM, *flags, f"--user-data-dir={profile}"]
    if what == "dom":
        out = subprocess.run(
            [*args, "--dump-dom", url], capture_output=True, text=True, timeout=120, check=True
        )
        return out.stdout
    subprocess.run(
        [*args, f"--screenshot={what}", url], capture_output=True, timeout=120, check=True
    )
    return None


def rgb(color: str) -> np.ndarray:
    return np.array([int(color[k : k + 2], 16) for k in (1, 3, 5)], dtype=float)


def near(image: np.ndarray, xy, color, radius=2, tol=40.0) -> bool:
    """Whether a pixel within ``radius`` of ``xy`` (device px) has ``color`` (RGB, ±tol)."""
    x, y = round(xy[0]), round(xy[1])
    patch = image[y - radius : y + radius + 1, x - radius : x + radius + 1].astype(float)
    return bool(np.any(np.max(np.abs(patch - color), axis=-1) <= tol))


@pytest.fixture(scope="module")
def motion():
    return md.inverse(slider_crank(), np.linspace(0, math.pi, 101))


def test_player_shows_the_result_at_two_times(motion, tmp_path):
    page = html(motion, tmp_path / "player.html", trace=["crank.A"], forces=["O"])
    colors = [rgb(c) for c in ("#1f77b4", "#ff7f0e")]  # crank, rod (the first two bodies)
    shots, states = [], []
    for t in (0.5, 2.0):
        url = f"{page.as_uri()}#t={t}"
        dom = chromium(tmp_path, url, "dom")
        png = tmp_path / f"t{t}.png"
        chromium(tmp_path, url, str(png))
        body = re.search(r"<body([^>]*)>", dom).group(1)
        attrs = {k: htmllib.unescape(v) for k, v in re.findall(r'data-(\w+)="([^"]*)"', body)}
        view = json.loads(attrs["view"])
        i = int(np.argmin(np.abs(motion.t - t)))
        assert int(attrs["frame"]) == i and attrs["playing"] == "false"
        assert float(attrs["t"]) == pytest.approx(motion.t[i], rel=1e-9)
        readout = re.search(r'id="time">([^<]*)<', dom).group(1)
        assert f"frame {i + 1} / {len(motion.t)}" in readout  # every output time is a frame
        assert f"t = {motion.t[i]:.3f} s" in readout
        assert view["dpr"] == DPR and view["width"] == round(view["cssWidth"] * DPR)
        image = np.asarray(Image.open(png).convert("RGB"))

        def pixel(x, y, view=view):
            return (DPR * (view["ox"] + view["k"] * x), DPR * (view["oy"] - view["k"] * y))

        # Each bar's midpoint, from the result's coordinates and the body's own points.
        for b, body_ in enumerate(motion.model.bodies[:2]):
            local = np.mean([np.asarray(p) for p in body_.points.values()], axis=0)
            x, y, phi = motion.q[i, 3 * b : 3 * b + 3]
            c, s = math.cos(phi), math.sin(phi)
            mid = (x + c * local[0] - s * local[1], y + s * local[0] + c * local[1])
            assert near(image, pixel(*mid), colors[b]), f"{body_.name} not drawn at t={t}"
        # The reaction at O (on the crank, at the ground's origin) along the result's force.
        F = np.array([motion["O.Fx"][i], motion["O.Fy"][i]])
        note = re.search(r'id="note">arrows: ([0-9.e+-]+) N = ([0-9.e+-]+) m<', dom)
        length_px = np.hypot(*F) * float(note.group(2)) / float(note.group(1)) * view["k"]
        assert length_px > 25
        along = F / np.hypot(*F) * 15 / view["k"]  # 15 CSS px along the arrow
        assert near(image, pixel(*along), rgb("#d62728")), f"arrow O not along F at t={t}"
        assert not near(image, pixel(*-along), rgb("#d62728"), tol=25)
        shots.append(image)
        states.append((view, i))
    assert shots[0].shape == shots[1].shape
    assert np.mean(np.any(shots[0] != shots[1], axis=-1)) > 0.003
    # The crank moved: at the second time its first place shows no crank.
    (_, i0), (view1, _) = states
    x0 = motion.q[i0, :2]
    p0 = (DPR * (view1["ox"] + view1["k"] * x0[0]), DPR * (view1["oy"] - view1["k"] * x0[1]))
    assert not near(shots[1], p0, colors[0], tol=25)


def test_player_plays_on_opening_and_refuses_forces_without_them(motion, tmp_path):
    page = html(motion, tmp_path / "p.html")
    dom = chromium(tmp_path, page.as_uri(), "dom")
    assert 'data-playing="true"' in dom
    assert "Uncaught" not in dom
    with pytest.raises(ValueError, match="neither a joint, a point force"):
        html(motion, tmp_path / "q.html", forces=["crank"])
    kinematic = md.kinematic(slider_crank(), np.linspace(0, 1, 5))
    with pytest.raises(ValueError, match="no forces"):
        html(kinematic, tmp_path / "r.html", forces=True)


@pytest.mark.parametrize("unit", ["s", "ms", "min", "h", "us"])
def test_real_time_playback_knows_the_time_unit(unit):
    """The player's real-time clock: seconds per model time unit, the fast table against
    pint."""
    from mixdyn.io.quantities import factor
    from mixdyn.viz.player import seconds_per_time_unit

    model = slider_crank()
    model = md.Model(
        bodies=model.bodies,
        joints=model.joints,
        drivers=model.drivers,
        units=md.UnitSystem("m", "kg", unit),
    )
    assert seconds_per_time_unit(model) == pytest.approx(
        1.0 / factor("s", "time", model.units), rel=1e-15
    )


def _attrs(dom: str) -> dict:
    body = re.search(r"<body([^>]*)>", dom).group(1)
    return {k: htmllib.unescape(v) for k, v in re.findall(r'data-(\w+)="([^"]*)"', body)}


@pytest.mark.slow  # long: run by CI's slow set
def test_plot_cursor_follows_the_frame_and_a_click_moves_the_animation(motion, tmp_path):
    """The plot's cursor sits at the frame's time on the plot's time axis (and is drawn
    there), its readout is the result's value; a click at 3/4 of the plot's width shows the
    frame nearest 3/4 of the time span; another column is chosen by the page."""
    page = html(motion, tmp_path / "plot.html", columns=["motor", "crank.phi"])
    t0, t1 = motion.t[0], motion.t[-1]
    xs = []
    for i in (10, 60):
        url = f"{page.as_uri()}#frame={i}"
        dom = chromium(tmp_path, url, "dom", height=1200)
        attrs = _attrs(dom)
        plot, m = json.loads(attrs["plot"]), json.loads(attrs["plot"])["margins"]
        inner = plot["width"] - m["l"] - m["r"]
        assert int(attrs["frame"]) == i and plot["column"] == "motor"
        assert plot["x"] == pytest.approx(m["l"] + inner * (motion.t[i] - t0) / (t1 - t0))
        value = re.search(r'id="plotval">motor = ([-0-9.e+]+) N·m', dom).group(1)
        assert float(value) == pytest.approx(motion["motor"][i], rel=1e-5)
        png = tmp_path / f"plot{i}.png"
        chromium(tmp_path, url, str(png), height=1200)
        image = np.asarray(Image.open(png).convert("RGB"))
        foot = (DPR * (plot["left"] + plot["x"]), DPR * (plot["top"] + plot["height"] - m["b"] - 4))
        assert near(image, foot, rgb("#d62728")), f"no cursor at frame {i}"
        xs.append(plot["x"])
        # The motor's torque drawn in the view: its arc's middle, where the scene puts it.
        view = json.loads(attrs["view"])
        (arc,) = Scene(motion.model, motion.q, (), {"motor": motion["motor"]}).symbols
        mid = arc["path"][i, 18]
        at = (DPR * (view["ox"] + view["k"] * mid[0]), DPR * (view["oy"] - view["k"] * mid[1]))
        assert near(image, at, rgb(arc["color"])), f"no motor torque drawn at frame {i}"
    assert xs[1] - xs[0] == pytest.approx(inner * (motion.t[60] - motion.t[10]) / (t1 - t0))
    attrs = _attrs(chromium(tmp_path, f"{page.as_uri()}#plotclick=0.75", "dom"))
    assert int(attrs["frame"]) == int(np.argmin(np.abs(motion.t - (t0 + 0.75 * (t1 - t0)))))
    assert attrs["playing"] == "false"
    dom = chromium(tmp_path, f"{page.as_uri()}#frame=20&plotcol=1", "dom")
    assert json.loads(_attrs(dom)["plot"])["column"] == "crank.phi"
    value = re.search(r'id="plotval">crank.phi = ([-0-9.e+]+) rad', dom).group(1)
    assert float(value) == pytest.approx(motion["crank.phi"][20], rel=1e-5)


@pytest.mark.slow  # long: run by CI's slow set
def test_report_opens_with_every_column_its_unit_and_the_figures(tmp_path):
    """``mixdyn run``'s report.html in the browser: a row per column of results.csv with the
    unit of its header and its range, the figures the run lists in meta.json shown (inline
    images that decode), the energy balance, and nothing fetched."""
    from typer.testing import CliRunner

    from fixtures import EXAMPLES
    from mixdyn.cli import app

    out = tmp_path / "out"
    res = CliRunner().invoke(
        app, ["run", str(EXAMPLES / "pendulum.yaml"), "--run", "swing", "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    folder = out / "swing"
    meta = json.loads((folder / "meta.json").read_text())
    page = folder / meta["report"]
    dom = chromium(tmp_path, page.as_uri(), "dom")
    table = re.search(r'<table class="ranges">(.*?)</table>', dom, re.S).group(1)
    rows = re.findall(r"<tr><td>([^<]*)</td><td>([^<]*)</td><td class=\"n\">([^<]*)</td>", table)
    header = (folder / "results.csv").read_text().splitlines()[0].split(",")
    written = [re.fullmatch(r"(.*?)(?: \[(.*)\])?", h).groups() for h in header]
    assert [(n, u or "") for n, u, _ in rows] == [(n, u or "") for n, u in written]
    data = md.read_table(folder / "results.csv")
    for name, _, lo in rows:
        assert float(lo) == pytest.approx(data[name].min(), rel=1e-5, abs=1e-12)
    images = re.findall(r'<img src="data:image/(png|gif);base64,[^"]+" alt="([^"]+)"', dom)
    shown = [alt for _, alt in images]
    assert shown == [f for f in [*meta["figures"], *meta["animation"]] if not f.endswith(".html")]
    assert "Energy balance" in dom and "<svg" in dom
    assert not re.search(r'(src|href)="https?:', dom)
    png = tmp_path / "report.png"
    chromium(tmp_path, page.as_uri(), str(png))
    with Image.open(png) as im:
        assert len(im.convert("RGB").getcolors(maxcolors=1_000_000)) > 200  # drawn, not blank


def _screen(plot: dict, x, y):
    """A plot's data point -> CSS px in the plot canvas, through the page's stated ranges."""
    m, (x0, x1), (y0, y1) = plot["margins"], plot["xrange"], plot["yrange"]
    inner_w, inner_h = plot["width"] - m["l"] - m["r"], plot["height"] - m["t"] - m["b"]
    return (
        m["l"] + inner_w * (np.asarray(x) - x0) / (x1 - x0),
        m["t"] + inner_h * (y1 - np.asarray(y)) / (y1 - y0),
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_phase_plot_cursor_and_click_go_to_the_frame(motion, tmp_path):
    """Against another column: the slider's position against the crank angle opened at a
    frame by the address has its cursor at the result's (crank angle, slider position) of that
    frame, drawn there, on axes that span the columns' ranges (6 % margin) with their units;
    on the slider's phase portrait (velocity against position: x goes out and back), a click
    shows the frame whose point is nearest the click on the screen, not the one nearest in x
    alone."""
    page = html(motion, tmp_path / "phase.html")  # the default columns: any other chosen
    i = 37
    url = f"{page.as_uri()}#frame={i}&plotx=crank.phi&plotcol=slider.x"
    dom = chromium(tmp_path, url, "dom", height=1200)
    attrs = _attrs(dom)
    plot = json.loads(attrs["plot"])
    phi, x = motion["crank.phi"], motion["slider.x"]
    assert int(attrs["frame"]) == i
    assert (plot["xcolumn"], plot["column"]) == ("crank.phi", "slider.x")
    assert plot["xv"] == pytest.approx(phi[i], rel=5e-9)
    assert plot["yv"] == pytest.approx(x[i], rel=5e-9)
    for got, v in ((plot["xrange"], phi), (plot["yrange"], x)):
        span = v.max() - v.min()
        assert got == pytest.approx([v.min() - 0.06 * span, v.max() + 0.06 * span], rel=1e-7)
    assert (plot["x"], plot["y"]) == pytest.approx(_screen(plot, phi[i], x[i]), abs=1e-6)
    readout = re.search(r'id="plotval">([^<]*)<', dom).group(1)
    assert re.match(r"slider\.x = [-0-9.e]+ m,\s+crank\.phi = [-0-9.e]+ rad", readout), readout
    png = tmp_path / "phase.png"
    chromium(tmp_path, url, str(png), height=1200)
    image = np.asarray(Image.open(png).convert("RGB"))
    at = (DPR * (plot["left"] + plot["x"]), DPR * (plot["top"] + plot["y"]))
    assert near(image, at, rgb("#d62728")), "no cursor at the frame's point"
    # A click beside a point of the return stroke of the phase portrait.
    v = motion["slider.vx"]
    dom = chromium(tmp_path, f"{page.as_uri()}#frame=0&plotx=slider.x&plotcol=slider.vx", "dom")
    plot = json.loads(_attrs(dom)["plot"])
    sx, sy = _screen(plot, x, v)
    j = 80
    cx, cy = sx[j] + 4.0, sy[j] - 3.0
    nearest = int(np.argmin(np.hypot(sx - cx, sy - cy)))
    assert int(np.argmin(np.abs(sx - cx))) != nearest  # x alone would go elsewhere
    m = plot["margins"]
    f = (cx - m["l"]) / (plot["width"] - m["l"] - m["r"])
    g = (cy - m["t"]) / (plot["height"] - m["t"] - m["b"])
    url = f"{page.as_uri()}#plotx=slider.x&plotcol=slider.vx&plotclick={f:.9f},{g:.9f}"
    attrs = _attrs(chromium(tmp_path, url, "dom"))
    assert int(attrs["frame"]) == nearest and attrs["playing"] == "false"


@pytest.mark.slow  # long: run by CI's slow set
def test_a_journals_orbit_is_drawn_in_its_clearance_circle_with_equal_axes(tmp_path):
    """A journal bearing's ey against its ex: the axes are centred on the bearing, scaled
    alike (as many mm per pixel across as up), and hold the clearance circle, which is drawn
    (grey pixels on it); the cursor is at the frame's offset."""
    from test_player_plot import journal_motion

    result = journal_motion()
    page = html(result, tmp_path / "orbit.html", columns=["jb.ey"], plot_x="jb.ex")
    url = f"{page.as_uri()}#frame=5"
    dom = chromium(tmp_path, url, "dom", height=1700)
    plot = json.loads(_attrs(dom)["plot"])
    assert (plot["xcolumn"], plot["column"], plot["orbit"]) == ("jb.ex", "jb.ey", 0.5)
    (x0, x1), (y0, y1), m = plot["xrange"], plot["yrange"], plot["margins"]
    assert x0 == pytest.approx(-x1) and y0 == pytest.approx(-y1)
    per_x = (x1 - x0) / (plot["width"] - m["l"] - m["r"])
    per_y = (y1 - y0) / (plot["height"] - m["t"] - m["b"])
    assert per_x == pytest.approx(per_y, rel=1e-9)
    assert min(x1, y1) > 0.5
    a = 2 * np.pi * result.t[5]
    assert (plot["xv"], plot["yv"]) == pytest.approx((0.4 * np.cos(a), 0.4 * np.sin(a)), rel=1e-8)
    png = tmp_path / "orbit.png"
    chromium(tmp_path, url, str(png), height=1700)
    image = np.asarray(Image.open(png).convert("RGB"))
    angles = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    sx, sy = _screen(plot, 0.5 * np.cos(angles), 0.5 * np.sin(angles))
    grey = [
        near(image, (DPR * (plot["left"] + u), DPR * (plot["top"] + w)), rgb("#888888"))
        for u, w in zip(sx, sy, strict=True)
    ]
    assert sum(grey) >= 24, f"the clearance circle is drawn at {sum(grey)} of 48 places"
