"""A synthesis run's Grashof type and ground-pivot regions in model files (``grashof:``,
``pivots:``): read with their units into SI (by hand), described by ``mixdyn check``, and
every fault an input error at its line before any search."""

import numpy as np
import pytest

import mixdyn.io as mio
from mixdyn.io import FileError
from mixdyn.runs import Runner
from mixdyn.runs.report import report

FUNCTION = "    function: {pairs: [[0 deg, 240 deg], [30 deg, 220 deg], [60 deg, 200 deg]]}"
HEAD = "mixdyn: 1\nunits: {length: mm, mass: kg, time: s}\nruns:\n  - name: path\n"


def _text(*lines: str, points: str = "    points: [[0, 0], [100, 50], [150, 120]]") -> str:
    return HEAD + "\n".join(["    kind: synthesis", points, *lines]) + "\n"


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


def test_grashof_and_pivots_are_read_in_si_and_described(tmp_path):
    """``x: [10 cm, 200]`` in a file in mm is 0.1 m to 0.2 m; ``y: [-0.1 m, 0]`` -0.1 m to 0;
    the crank pivot's region is the bounds of x0 and y0; ``mixdyn check`` names both."""
    text = _text(
        "    grashof: crank_rocker",
        "    pivots:",
        "      O4: {x: [10 cm, 200], y: [-0.1 m, 0]}",
        "      O2: {x: [-50, 50], y: [-5 cm, 50 mm]}",
    )
    task = Runner(mio.reads(text, "limits.yaml")).plans["path"].task
    assert task.grashof == "crank_rocker"
    np.testing.assert_allclose(task.pivots["O4"], [[0.1, 0.2], [-0.1, 0.0]], rtol=1e-15)
    np.testing.assert_allclose(task.pivots["O2"], [[-0.05, 0.05], [-0.05, 0.05]], rtol=1e-15)
    np.testing.assert_allclose(task.box()[6:8], [[-0.05, 0.05], [-0.05, 0.05]], rtol=1e-15)
    path = tmp_path / "limits.yaml"
    path.write_text(text)
    line = next(x for x in report(path) if "synthesis" in x)
    assert "crank-rocker" in line and "O4 in x [0.1, 0.2] m, y [-0.1, 0] m" in line


def test_a_motion_and_a_function_take_the_grashof_type():
    """A motion's poses take both keys as a path's; a function's task its Grashof type."""
    motion = _text(
        "    grashof: double_crank",
        "    pivots: {O4: {x: [0, 300], y: [-200, 0]}}",
        points="    motion: {poses: [[0, 0, 0 deg], [100, 50, 20 deg], [150, 120, 45 deg]]}",
    )
    task = Runner(mio.reads(motion, "motion.yaml")).plans["path"].task
    assert task.grashof == "double_crank"
    np.testing.assert_allclose(task.pivots["O4"], [[0.0, 0.3], [-0.2, 0.0]], rtol=1e-15)
    function = _text("    grashof: crank_rocker", points=FUNCTION)
    assert Runner(mio.reads(function, "f.yaml")).plans["path"].task.grashof == "crank_rocker"
    plain = _text("    linkage: slider_crank", "    grashof: grashof")
    assert Runner(mio.reads(plain, "p.yaml")).plans["path"].task.grashof == "grashof"


@pytest.mark.parametrize(
    "extra, marker, words",
    [
        (["    grashof: triple_rocker"], "grashof", "crank_rocker"),
        (["    linkage: slider_crank", "    grashof: double_crank"], "grashof", "no double crank"),
        (["    linkage: slider_crank", "    pivots:", "      O4: {x: [0, 1], y: [0, 1]}"],
         "O4:", "no ground pivot 'O4'"),
        (["    pivots:", "      O4: {x: [200, 100], y: [0, 1]}"], "O4:", "low < high"),
        (["    pivots:", "      O4: {x: [1 kg, 2 kg], y: [0, 1]}"], "O4:", "kg"),
        (["    pivots:", "      O4: {x: [0, 1]}"], "O4:", "y"),
        (["    bounds: {x0: [0, 10]}", "    pivots:", "      O2: {x: [0, 1], y: [0, 1]}"],
         "O2:", "bounded twice"),
    ],
)  # fmt: skip
def test_bad_input_is_refused_at_its_line(extra, marker, words):
    """Each fault an input error (exit 2) at the line that holds it, before any search."""
    text = _text(*extra)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


def test_a_function_refuses_pivots_at_their_line():
    text = _text("    pivots: {O4: {x: [0, 1], y: [0, 1]}}", points=FUNCTION)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, "pivots"), str(e.value)
    assert "not for a function" in str(e.value)
