"""The player's plot carries every column of the result: each column the result has (the
chosen ones first), at the frames the page shows, in the result's output units, to 9
significant digits; a body's coordinate carried once (read from the body's coordinates, as
the page does). The browser's side is ``test_player_browser.py``."""

import dataclasses
import json
import math
import re

import numpy as np
import pytest

import mixdyn as md
from fixtures import slider_crank
from mixdyn.viz import html

#: Output units of the page and each column's factor from the model's unit (by its unit).
OUTPUT_UNITS = {"angle": "deg", "torque": "N*mm"}
#: A torque in N*mm gives energies in mJ and powers in mW (the time in s).
FACTORS = {
    "rad": (180 / math.pi, "deg"),
    "N*m": (1e3, "N·mm"),
    "J": (1e3, "mJ"),
    "W": (1e3, "mW"),
}


@pytest.fixture(scope="module")
def motion():
    return md.inverse(slider_crank(), np.linspace(0, math.pi, 41))


def page_data(path) -> dict:
    return json.loads(re.search(r"const D = (.*?);\n", path.read_text(encoding="utf-8")).group(1))


def carried(data: dict) -> dict[str, tuple[np.ndarray, str]]:
    """The page's columns as its script reads them: ``v``, or a body's coordinate ``q``."""
    out = {}
    for c in data["plots"]:
        if "q" in c:
            k, j = c["q"]
            v = [row[j] for row in data["bodies"][k]["q"]]
        else:
            v = c["v"]
        out[c["name"]] = (np.array(v, dtype=float), c["unit"])
    return out


def test_the_page_carries_every_column_at_its_frames(motion, tmp_path):
    shown = dataclasses.replace(motion, output_units=OUTPUT_UNITS)
    page = html(shown, tmp_path / "p.html", frames=15, columns=["motor"], plot_x="crank.phi")
    data = page_data(page)
    assert data["shown"] == ["motor"] and data["plotX"] == "crank.phi"
    # The page's frames are output times of the result.
    idx = np.array([int(np.argmin(np.abs(motion.t - t))) for t in data["t"]])
    assert len(set(idx)) == len(idx) == 15 and idx[0] == 0 and idx[-1] == len(motion.t) - 1
    np.testing.assert_allclose(data["t"], motion.t[idx], rtol=5e-9, atol=1e-300)
    columns = carried(data)
    assert data["plots"][0]["name"] == "motor"
    assert set(columns) == set(motion.columns()) - {"t"}
    units = motion.units()
    for name, values in motion.columns().items():
        if name == "t":
            continue
        factor, unit = FACTORS.get(units[name], (1.0, md.units.engineering(units[name])))
        want = np.asarray(values)[idx] * factor
        got, got_unit = columns[name]
        assert got_unit == unit, name
        # 9 significant digits: within half a unit of the 9th digit of each value.
        assert np.all(np.abs(got - want) <= 0.5e-8 * (1 + 1e-6) * np.abs(want)), name
    # The crank's x (in metres, as the body's coordinates) is carried once, its angle (in
    # degrees) apart.
    by_name = {c["name"]: c for c in data["plots"]}
    assert by_name["crank.x"].get("q") == [0, 0] and "v" not in by_name["crank.x"]
    assert "v" in by_name["crank.phi"]


def test_a_column_the_result_lacks_is_refused(motion, tmp_path):
    with pytest.raises(ValueError, match="cannot plot"):
        html(motion, tmp_path / "p.html", plot_x="crank.nope")
    with pytest.raises(ValueError, match="need a result"):
        html(None, tmp_path / "q.html", model=motion.model, t=motion.t, q=motion.q, plot_x="t1")
    data = page_data(html(motion, tmp_path / "r.html", columns=()))
    assert data["plots"] == [] and data["shown"] == []


def journal_motion(clearance=5e-4, radius=4e-4, n=33):
    """A journal (body ``pin``) whose centre goes once round a circle of ``radius`` [m] about
    its bearing's centre (at the origin, on the ground), as a forward result in metres with
    the bearing's eccentricity columns (the centre's offset), shown in millimetres."""
    pin = md.Body("pin", 0.1, 1e-6, q0=(radius, 0.0, 0.0))
    bearing = md.JournalBearing(
        "jb", "ground", "pin", clearance, 0.01, young_modulus=2e11, restitution=1.0
    )
    model = md.Model([pin], forces=[bearing])
    t = np.linspace(0.0, 1.0, n)
    a = 2 * math.pi * t
    q = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(n)], axis=1)
    extra = {"jb.ex": q[:, 0], "jb.ey": q[:, 1]}  # the bearing's frame is the ground's
    zeros = np.zeros_like(q)
    return md.Result(
        "forward", model, t, q, zeros, zeros, extra=extra,
        kinds={"jb.ex": "length", "jb.ey": "length"}, output_units={"length": "mm"},
    )  # fmt: skip


def test_a_journals_orbit_is_carried_with_its_clearance_in_the_plotted_unit(tmp_path):
    """A journal bearing's eccentricity columns are offered as an orbit whose circle is the
    radial clearance, in the unit the columns are plotted in (0.5 mm of a model in metres,
    shown in mm, is 0.5); the columns themselves are the journal's offset in mm."""
    result = journal_motion()
    page = html(result, tmp_path / "orbit.html", columns=["jb.ey"], plot_x="jb.ex")
    data = page_data(page)
    assert data["orbits"] == [{"x": "jb.ex", "y": "jb.ey", "r": 0.5}]
    columns = carried(data)
    a = 2 * np.pi * result.t
    np.testing.assert_allclose(columns["jb.ex"][0], 0.4 * np.cos(a), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(columns["jb.ey"][0], 0.4 * np.sin(a), rtol=1e-8, atol=1e-12)
    assert columns["jb.ex"][1] == columns["jb.ey"][1] == "mm"
