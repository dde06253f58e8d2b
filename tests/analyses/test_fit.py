"""``md.fit``: numbers fitted to a measured motion. Noise-free velocities give the damper's
coefficient back to the tolerances; numbers the measurements cannot determine, bad columns,
bounds and starts are refused by name. (The noisy identification of four numbers within their
confidence: ``tests/analyses/test_gradients.py``, through ``examples/identify_slider_crank.py``.)"""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES

T = np.linspace(0.0, 1.0, 41)
OPTS = dict(rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def example():
    path = EXAMPLES / "identify_slider_crank.py"
    spec = importlib.util.spec_from_file_location("identify_slider_crank", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def recorded(example):
    model = example.build_model()
    return model, md.forward(model, T, **OPTS)


@pytest.mark.slow  # the file run of test_identify_files.py does the same through md.fit
def test_a_damper_is_recovered_from_noise_free_velocities(recorded):
    model, rec = recorded
    fit = md.fit(
        model,
        T,
        {"slider.vx": rec["slider.vx"], "crank.omega": rec["crank.omega"]},
        ["damper.damping"],
        start=[0.5],
        bounds={"damper.damping": (0.0, 10.0)},
        **OPTS,
    )
    assert abs(fit["damper.damping"] - 2.0) <= 1e-6 * 2.0
    assert fit.chi2 < 1e-10 and fit.evaluations < 30
    assert list(fit.table()["parameter"]) == ["damper.damping"]


@pytest.mark.slow  # a second Jacobian program to compile (11 s); CI runs it
def test_numbers_the_measurements_cannot_determine_are_named(recorded):
    """The slider cannot turn (translational joint): its inertia has no effect, the
    damper's has; the error names the one."""
    model, rec = recorded
    with pytest.raises(md.ConvergenceError, match=r"do not determine slider\.inertia \("):
        md.fit(
            model, T, {"slider.x": rec["slider.x"]}, ["damper.damping", "slider.inertia"], **OPTS
        )


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        (dict(measured={"slider.z": np.zeros(41)}), "unknown coordinate"),
        (dict(measured={"slider.x": np.zeros(5)}), "one per output time (41)"),
        (dict(measured={}), "nothing measured"),
        (dict(noise=0.0), "noise must be a number > 0"),
        (dict(bounds={"rod.mass": (0, 1)}), "'rod.mass' is not fitted"),
        (dict(bounds={"damper.damping": (3, 4)}), "outside its bounds"),
        (dict(start=[1.0, 2.0]), "start must be 1 finite numbers"),
        (dict(params=["A.si"]), "geometry"),
    ],
)
def test_bad_input_is_refused_before_fitting(example, kwargs, words):
    model = example.build_model()  # refused before any run: no recording needed
    args = dict(measured={"slider.x": np.full(len(T), 0.3)}, params=["damper.damping"])
    args.update(kwargs)
    with pytest.raises(md.ModelError) as err:
        md.fit(model, T, args.pop("measured"), args.pop("params"), **args, **OPTS)
    assert words in str(err.value)
