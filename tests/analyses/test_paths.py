"""Parameter paths (``mixdyn.paths``): a model's numbers read, replaced, shaped and grouped
by their text paths; a bad path says what is wrong."""

from __future__ import annotations

import pytest

import mixdyn as md
from fixtures import paper_under_loads


@pytest.fixture(scope="module")
def paper():
    return paper_under_loads()


def test_parameter_paths(paper):
    """``mixdyn.paths``: read and replace a number by its path, its shape and group; a bad
    path names what is wrong."""
    assert float(md.paths.get(paper, "slider.mass")) == pytest.approx(0.00786)
    heavier = md.paths.replace(paper, "slider.mass", 0.02)
    assert float(md.paths.get(heavier, "slider.mass")) == 0.02
    assert float(md.paths.get(paper, "slider.mass")) != 0.02  # the model is unchanged
    assert md.paths.shape(paper, "crank.q0") == (3,)
    assert md.paths.shape(paper, "F1.law.amplitude") == ()
    assert md.paths.group(paper, "F1.law.amplitude") == "forces"
    assert md.paths.group(paper, "crank.mass") == "bodies"
    get, shape = md.paths.getter(paper, "T2.law.value")
    assert shape == () and float(get(heavier)) == float(get(paper))
    for path, words in [
        ("slider.mas", "no field 'mas'"),
        ("piston.mass", "no body or element 'piston'"),
        ("slider", "'name.field'"),
    ]:
        with pytest.raises(md.ModelError, match=words):
            md.paths.get(paper, path)
    with pytest.raises(md.ModelError, match="shape"):
        md.paths.replace(paper, "crank.q0", 1.0)
