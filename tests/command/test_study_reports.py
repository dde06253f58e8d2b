"""The one-page report (``report.html``) of a sweep, a fit, an optimization and a failed run
(issue 32): each page's numbers are those of the run's own files, read here independently
(``members.csv``'s minimum and maximum, ``fit.csv``'s estimates, ``optimum.csv``'s optimum,
``results.csv`` against the recording for the residual), shown with their units; a failed
run's page names the failure (the error's class, time and message) and what was computed
before it.

A page shows a number with 6 significant digits: it is compared within 5e-6, relative.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from fixtures import CRANK_FILE, EXAMPLES, IDENTIFY_MODEL, IDENTIFY_RUNS
from mixdyn.cli import app
from mixdyn.runs import execute

#: A number as a page shows it (6 significant digits), against the file's.
RTOL = 5e-6

CRANK = CRANK_FILE

SWEEP = """\
  - name: masses
    kind: sweep
    run: turn
    vary:
      crank.mass: {values: [1 kg, 2.5 kg, 4 kg]}
    summaries:
      - {name: torque_max, column: motor, reduce: max}
      - {name: force_min, column: O.Fy, reduce: min}
"""

OPTIMIZE = """\
  - name: lighter
    kind: optimize
    run: turn
    objective: {column: motor, reduce: rms}
    vary:
      crank.mass: {bounds: [0.5 kg, 3 kg], start: 2 kg}
"""


class _Page(HTMLParser):
    """A report's tables by their class (rows of cell texts, the head row first), its
    headings and the failure line."""

    def __init__(self, text: str):
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self.headings: list[str] = []
        self.failure = ""
        self._table = self._cell = self._row = None
        self._text = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table":
            self._table = self.tables.setdefault(attrs.get("class") or "", [])
        elif tag == "tr" and self._table is not None:
            self._row = []
            self._table.append(self._row)
        elif tag in ("td", "th") and self._row is not None:
            self._cell = []
        elif tag in ("h2", "h1") or (tag == "p" and "failure" in (attrs.get("class") or "")):
            self._text = []

    def handle_endtag(self, tag):
        if tag == "table":
            self._table = self._row = None
        elif tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell))
            self._cell = None
        elif tag in ("h1", "h2") and self._text is not None:
            self.headings.append("".join(self._text))
            self._text = None
        elif tag == "p" and self._text is not None:
            self.failure = "".join(self._text)
            self._text = None

    def handle_data(self, data):
        for sink in (self._cell, self._text):
            if sink is not None:
                sink.append(data)

    def rows(self, cls: str) -> dict[str, dict[str, str]]:
        """Table ``cls`` as first cell -> {head: cell}."""
        head, *body = self.tables[cls]
        return {r[0]: dict(zip(head, r, strict=True)) for r in body}

    def facts(self) -> dict[str, str]:
        return {r[0]: r[1] for r in self.tables["facts"]}


def _run(tmp_path, text: str, *args: str):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--no-figures", *args])
    return res, out


def test_a_sweeps_report_holds_its_members_ranges_with_units(tmp_path):
    res, out = _run(tmp_path, CRANK + SWEEP, "--run", "masses", "--excel")
    assert res.exit_code == 0, res.output
    folder = out / "masses"
    members = mio.read_table(folder / "members.csv")
    # --excel: sweep.xlsx holds members.csv and table.csv, the same headers and numbers
    pytest.importorskip("openpyxl")
    book = pd.read_excel(folder / "sweep.xlsx", sheet_name=None)
    assert list(book) == ["members", "table", "meta"]
    for sheet, name in (("members", "members.csv"), ("table", "table.csv")):
        csv = pd.read_csv(folder / name).select_dtypes("number")
        assert list(book[sheet].columns) == list(pd.read_csv(folder / name).columns)
        np.testing.assert_allclose(book[sheet][csv.columns], csv, rtol=6.2e-16, atol=0)
    units = members.attrs["units"]
    page = _Page((folder / "report.html").read_text(encoding="utf-8"))
    facts = page.facts()
    assert facts["status"] == "ok" and facts["members"].startswith("3 (grid): 3 ok, 0 failed")
    varied = page.rows("varied")["crank.mass"]
    assert varied["unit"] == units["crank.mass"] == "kg" and varied["values"] == "3"
    assert float(varied["min"]) == members["crank.mass"].min() == 1.0
    assert float(varied["max"]) == members["crank.mass"].max() == 4.0
    summaries = page.rows("summaries")
    for name in ("torque_max", "force_min"):
        row, column = summaries[name], members[name]
        assert row["unit"] == units[name] and row["unit"] in ("N·m", "N")
        np.testing.assert_allclose(float(row["min"]), column.min(), rtol=RTOL)
        np.testing.assert_allclose(float(row["max"]), column.max(), rtol=RTOL)
        assert members["member"][column.idxmin()] == int(row["member at min"])
        assert members["member"][column.idxmax()] == int(row["member at max"])
    # the truth behind the file: the crank's largest motor torque m g L/2 (at phi = 0)
    np.testing.assert_allclose(members["torque_max"], members["crank.mass"] * 9.81 * 0.125)


def test_a_failed_runs_report_names_the_failure_and_what_came_before(tmp_path):
    """The slider of the example's slider-crank driven beyond the reach of crank + rod
    (as tests/command/test_failed_runs.py): the page states the error's class, its time and
    message as meta.json has them, and the rows computed before it as results.csv has them."""
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    text = text.replace(
        "{type: coordinate, name: motor, coordinate: crank.phi, law: omega*t}",
        "{type: coordinate, name: motor, coordinate: slider.x, law: 0.35 + 0.2*t}",
    ).replace("    kind: kinematic\n", "    kind: kinematic\n    initial: {crank.phi: 1.0}\n")
    res, out = _run(tmp_path, text, "--run", "kinematics")
    assert res.exit_code == 1, res.output
    folder = out / "kinematics"
    failure = json.loads((folder / "meta.json").read_text())["failure"]
    page = _Page((folder / "report.html").read_text(encoding="utf-8"))
    assert page.facts()["status"] == "failed"
    assert failure["error"] == "ConvergenceError"
    assert page.failure.startswith("The run failed at t = ")
    assert f"ConvergenceError: {failure['cause']}" in page.failure
    said = {r[0]: r[1] for r in page.tables["failure"]}
    assert said["error"] == failure["error"] and said["message"] == failure["cause"]
    t, unit = said["time"].split()
    assert unit == failure["time_unit"] == "s"
    np.testing.assert_allclose(float(t), failure["time"], rtol=RTOL)
    part = mio.read_table(folder)
    assert said["computed before it"].startswith(f"{len(part)} rows")
    ranges = page.rows("ranges")
    np.testing.assert_allclose(float(ranges["slider.x"]["max"]), part["slider.x"].max(), RTOL)
    assert ranges["slider.x"]["unit"] == part.attrs["units"]["slider.x"]


@pytest.mark.slow  # long: run by CI's slow set (its gradients compiled, 3 s here)
def test_an_optimizations_report_holds_its_optimum_and_constraints(tmp_path):
    res, out = _run(tmp_path, CRANK + OPTIMIZE, "--run", "lighter")
    assert res.exit_code == 0, res.output
    folder = out / "lighter"
    optimum = pd.read_csv(folder / "optimum.csv").set_index("parameter")
    meta = json.loads((folder / "meta.json").read_text())["optimize"]
    page = _Page((folder / "report.html").read_text(encoding="utf-8"))
    row = page.rows("optimum")["crank.mass"]
    assert row["unit"] == "kg"
    assert "The mechanism at the start" in page.headings  # of the run at the optimum
    for head in ("low", "high", "start", "optimum", "gradient"):
        np.testing.assert_allclose(float(row[head]), optimum.loc["crank.mass", head], RTOL)
    # the rms torque grows with the mass: the optimum is the low bound, which is active
    assert optimum.loc["crank.mass", "optimum"] == pytest.approx(0.5, rel=1e-9)
    assert row["bound active"] == "low"
    facts = page.facts()
    value, unit = facts["objective at the optimum"].split()[:2]
    assert unit == "N·m"  # the column's output unit, as results.csv has motor
    np.testing.assert_allclose(float(value) * 1e6, meta["objective_optimum"], RTOL)  # mN·mm
    run = mio.read_table(folder)
    np.testing.assert_allclose(float(value), np.sqrt(np.mean(run["motor"] ** 2)), RTOL)


@pytest.mark.slow  # long: run by CI's slow set (a fit's forward runs, 17 s here)
def test_a_fits_report_holds_its_estimate_and_residual(tmp_path):
    text, runs = IDENTIFY_MODEL, IDENTIFY_RUNS
    true = mio.reads(text.replace("damping: 1.2", "damping: 2.0") + runs.split("  - name: id")[0])
    v = execute(true, ["forward"])["forward"]["slider.vx"]
    rng = np.random.default_rng(0)
    data = pd.DataFrame({"t": np.linspace(0.0, 1.0, 41), "v": v + 1e-3 * rng.standard_normal(41)})
    data.to_csv(tmp_path / "rec.csv", index=False, float_format="%.17g")
    res, out = _run(tmp_path, text + runs, "--run", "identify")
    assert res.exit_code == 0, res.output
    folder = out / "identify"
    fit = pd.read_csv(folder / "fit.csv").set_index("parameter")
    page = _Page((folder / "report.html").read_text(encoding="utf-8"))
    row = page.rows("fitted")["damper.damping"]
    assert row["unit"] == "N·s/m"
    for head, col in (("start", "start"), ("estimate", "estimate"), ("std. deviation", "std_dev")):
        np.testing.assert_allclose(float(row[head]), fit.loc["damper.damping", col], RTOL)
    # the residual: the recording against the run at the estimate (results.csv)
    run = mio.read_table(folder)
    rms = np.sqrt(np.mean((data["v"].to_numpy() - run["slider.vx"].to_numpy()) ** 2))
    residual = page.rows("residuals")["slider.vx"]
    assert residual["unit"] == "m/s" and float(residual["noise"]) == pytest.approx(1e-3)
    np.testing.assert_allclose(float(residual["rms"]), rms, RTOL)
    assert 0.5 < float(residual["rms / noise"]) < 1.5  # the noise the data was given


CHROMIUM = next(
    (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None
)


@pytest.mark.slow  # long: run by CI's slow set (figures drawn, a browser started)
@pytest.mark.skipif(
    CHROMIUM is None and not os.environ.get("MIXDYN_REQUIRE_BROWSER"),
    reason="no Chromium here (CI installs it)",
)
def test_a_sweeps_report_opens_in_the_browser_with_its_figures(tmp_path):
    """The sweep's page in headless Chromium: its tables as written, its two figures shown
    as inline images that decode (each its natural size > 0), nothing fetched."""
    assert CHROMIUM is not None, "MIXDYN_REQUIRE_BROWSER is set but no Chromium is installed"
    plots = """\
    plots:
      - {file: torque.png, x: crank.mass, y: torque_max}
      - {file: band.png, band: motor}
"""
    path = tmp_path / "m.yaml"
    path.write_text(CRANK + SWEEP + plots)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--run", "masses"])
    assert res.exit_code == 0, res.output
    page = out / "masses" / "report.html"
    probe = (
        "<script>addEventListener('load', () => document.body.dataset.sizes = "
        "[...document.images].map(i => i.naturalWidth + 'x' + i.naturalHeight).join(' '))"
        "</script>"
    )
    probed = tmp_path / "probed.html"  # the page with a probe of its images' decoded sizes
    probed.write_text(page.read_text(encoding="utf-8").replace("</body>", probe + "</body>"))
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]
    dom = subprocess.run(
        [CHROMIUM, *flags, f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom",
         probed.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    shown = _Page(dom)
    assert shown.rows("summaries") == _Page(page.read_text(encoding="utf-8")).rows("summaries")
    alts = re.findall(r'<img src="data:image/png;base64,[^"]+" alt="([^"]+)"', dom)
    assert alts == ["torque.png", "band.png"]
    sizes = re.search(r'data-sizes="([^"]*)"', dom).group(1).split()
    assert len(sizes) == 2 and all(int(w) > 100 and int(h) > 100 for w, h in
                                   (s.split("x") for s in sizes))  # fmt: skip
    assert not re.search(r'(src|href)="https?:', dom)
