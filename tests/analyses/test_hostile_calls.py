"""Hostile calls of the Python API (issue 31): each one raises a named input error
(:class:`mixdyn.errors.ModelError`, naming the argument and what to give) before computing,
never a TypeError, an IndexError, a MemoryError or a numerical failure.

Each case fails while its arguments are checked, before any JAX program is compiled.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum
from mixdyn.errors import ModelError, NumericalError

T = np.linspace(0.0, 0.1, 3)


@pytest.fixture(scope="module")
def model():
    return pendulum()


@pytest.mark.parametrize(
    ("kwargs", "element", "words"),
    [
        ({"vary": {"bob.mass": [1, 2]}, "batch_size": 0}, "batch_size", ">= 1"),
        ({"vary": {"bob.mass": [1, 2]}, "threads": -1}, "threads", ">= 1"),
        ({"vary": {"bob.mass": [1, 2]}, "batch_size": 2.5}, "batch_size", "whole number"),
        ({"vary": "bob.mass"}, "vary", "mapping path -> values"),
        ({"vary": {"bob.mass": "heavy"}}, "vary 'bob.mass'", "give numbers"),
        ({"vary": {"bob.mass": [1, "x"]}}, "vary 'bob.mass'", "give numbers"),
        ({"vary": {"bob.mass": [1, 2]}, "client": 42}, "client", "distributed.Client"),
    ],
)
def test_bad_sweep_arguments_are_named_input_errors(model, kwargs, element, words):
    with pytest.raises(ModelError, match=words) as e:
        md.sweep(model, T, **kwargs)
    assert e.value.element == element


def test_an_unreachable_scheduler_fails_fast_and_by_name(model, monkeypatch):
    pytest.importorskip("distributed")
    cluster = importlib.import_module("mixdyn.analysis._cluster")
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 0.5)
    # port 9 (discard) has no Dask scheduler on the test machine
    with pytest.raises(ModelError, match=r"no Dask scheduler answers at 'tcp://127\.0\.0\.1:9'"):
        md.sweep(model, T, vary={"bob.mass": [1, 2]}, client="tcp://127.0.0.1:9")


def test_a_huge_latin_hypercube_is_refused_with_its_size():
    with pytest.raises(ModelError, match=r"7\.28 TiB") as e:
        md.latin_hypercube(10**12, **{"bob.mass": (1, 2)})
    assert e.value.element == "samples"
    # two ranges: twice the bytes (8 bytes a value), as the message says
    with pytest.raises(ModelError, match=r"14\.6 TiB"):
        md.latin_hypercube(10**12, **{"bob.mass": (1, 2), "bob.inertia": (0.1, 0.2)})
    with pytest.raises(ModelError, match="whole number"):
        md.latin_hypercube("many", **{"bob.mass": (1, 2)})


def test_a_latin_hypercube_below_the_limit_has_one_sample_per_stratum():
    n = 1000
    cols = md.latin_hypercube(n, seed=3, **{"bob.mass": (1.0, 2.0)})
    strata = np.floor((cols["bob.mass"] - 1.0) * n).astype(int)
    assert sorted(strata) == list(range(n))


def test_a_quasi_static_run_without_times_is_an_input_error(model):
    with pytest.raises(ModelError, match="at least 1") as e:
        md.quasi_static(model, [])
    assert e.value.element == "t"


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("run", [md.forward, md.kinematic, md.quasi_static])
def test_a_non_finite_start_pose_is_an_input_error(model, run, bad):
    q0 = [0.0, bad, 0.0]
    with pytest.raises(ModelError, match="starting pose holds") as e:
        run(model, T, q0=q0)
    assert not isinstance(e.value, NumericalError)
    assert e.value.element == "bob.y"
    with pytest.raises(ModelError, match="starting pose holds"):
        md.assemble(model, q0)


def test_a_rough_finite_start_pose_is_closed_onto_the_pin(model):
    """The other side of the check: a finite rough pose is assembled, the bob's point O
    ending on the ground pin (|c + R(phi) (0, 0.5)| = 0)."""
    q = np.asarray(md.assemble(model, [0.05, -0.4, 0.1]).q)
    x, y, phi = q
    ox, oy = x - 0.5 * math.sin(phi), y + 0.5 * math.cos(phi)
    assert math.hypot(ox, oy) < 1e-12


def test_a_noise_below_the_resolution_of_the_data_is_refused_before_fitting(model):
    ts = np.linspace(0.0, 0.2, 5)
    phi = 0.1 * np.cos(7.0 * ts)
    with pytest.raises(ModelError, match="finer than float64 resolves") as e:
        md.fit(model, ts, {"bob.phi": phi}, ["bob.mass"], noise=1e-300)
    assert e.value.element == "noise of 'bob.phi'"
    big = phi.copy()
    big[2] = 1e308
    with pytest.raises(ModelError, match=r"value 1e\+308 in row 2"):
        md.fit(model, ts, {"bob.phi": big}, ["bob.mass"], noise=1e-3)


def test_a_step_limit_beyond_the_loops_integers_is_an_input_error():
    with pytest.raises(ModelError, match="from 1 to 2,147,483,647") as e:
        md.Projection(max_steps=1e300)
    assert e.value.element == "max_steps"
    assert md.Projection(max_steps=2**31 - 1).max_steps == 2**31 - 1
