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
from mixdyn.viz import html

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


def chromium(tmp_path, url: str, what: str) -> str | None:
    assert CHROMIUM is not None, "MIXDYN_REQUIRE_BROWSER is set but no Chromium is installed"
    profile = tmp_path / f"profile-{len(list(tmp_path.iterdir()))}"
    args = [CHROMIUM, *FLAGS, f"--user-data-dir={profile}"]
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
