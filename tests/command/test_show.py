"""Seeing a model without running it (issue 14): ``mixdyn show`` draws the assembled start
with every body, joint and ground point named; ``Model.__repr__`` shows the numbers;
notebooks get a drawing and tables (``_repr_html_``), results a summary with units."""

from __future__ import annotations

import json

import numpy as np
from PIL import Image
from typer.testing import CliRunner

import mixdyn as md
from fixtures import EXAMPLES, paper_under_loads, slider_crank
from mixdyn.cli import app


def test_show_draws_the_assembled_start_with_its_names(tmp_path):
    svg = tmp_path / "m.svg"
    res = CliRunner().invoke(app, ["show", str(EXAMPLES / "antonya.yaml"), "-o", str(svg)])
    assert res.exit_code == 0, res.output
    text = svg.read_text()
    for name in ("crank", "coupler", "link", "slider", "EF", "ground.E", "assembled start"):
        assert f">{name}" in text or name in text, name
    png = tmp_path / "m.png"
    res = CliRunner().invoke(app, ["show", str(EXAMPLES / "four_bar.yaml"), "-o", str(png)])
    assert res.exit_code == 0, res.output
    with Image.open(png) as im:
        assert len(im.convert("RGB").getcolors(maxcolors=100_000)) > 50
    html = tmp_path / "m.html"
    res = CliRunner().invoke(app, ["show", str(EXAMPLES / "pendulum.yaml"), "-o", str(html)])
    assert res.exit_code == 0, res.output
    page = html.read_text()  # the player at the start: one frame, the model's bodies
    data = json.loads(page.split("const D = ", 1)[1].split(";\n", 1)[0])
    assert 'id="view"' in page and data["t"] == [0.0]
    assert [b["name"] for b in data["bodies"]] == ["rod"]
    res = CliRunner().invoke(app, ["show", str(EXAMPLES / "pendulum.yaml"), "-o", "m.gif"])
    assert res.exit_code == 2 and "cannot draw to 'm.gif'" in res.output


def test_a_model_shows_its_numbers():
    text = repr(paper_under_loads())
    assert "mass 0.00786 kg" in text and "inertia 50.63 kg*mm**2" in text
    assert "joint EF: Translational on ground - slider" in text
    assert "force T2: Torque on crank; law value 500" in text
    html = slider_crank()._repr_html_()
    assert "<svg" in html and "<td>rod</td>" in html and "CoordinateDriver" in html


def test_a_result_shows_its_columns_with_units():
    res = md.kinematic(slider_crank(), np.linspace(0.0, 1.0, 5))
    html = res._repr_html_()
    assert "<td>slider.x</td><td>m</td>" in html and "Result(kinematic" in html


def test_a_result_in_a_notebook_plots_its_headline_columns():
    """An inverse run shows its motor torque plotted (the curve's SVG) besides the table; a
    kinematic run its bodies' angles."""
    from mixdyn.viz.show import headline_columns

    inv = md.inverse(slider_crank(), np.linspace(0.0, 1.0, 9))
    assert headline_columns(inv) == ["motor"]
    html = inv._repr_html_()
    assert "<svg" in html and "motor" in html and "<td>motor</td><td>N·m</td>" in html
    kin = md.kinematic(slider_crank(), np.linspace(0.0, 1.0, 5))
    assert headline_columns(kin) == ["crank.phi", "rod.phi", "slider.phi"]
    assert "<svg" in kin._repr_html_()
