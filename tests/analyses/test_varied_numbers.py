"""A number varied by a study is a number of a model like any other: a sweep's member, a
fit's or optimization's candidate and a model built with that number give the same
mechanism (the constants derived from the number follow it), and a value the model's
constructors refuse is refused as a member or a bound too, before any computing."""

import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.errors import ModelError
from mixdyn.runs import Runner

T = np.linspace(0.0, 1.0, 11)


def _gears(radius_1=0.03, phi=(0.4, -0.3)):
    """Two gears on ground pins 0.09 apart (radii ``radius_1`` and 0.06), started at the
    angles ``phi`` (their teeth mesh there), gear 1 turned at 2 rad/s; a rack on gear 2."""
    x2 = 0.09
    return md.Model(
        bodies=[
            md.Body("g1", 0.1, 2e-4, q0=(0.0, 0.0, phi[0])),
            md.Body("g2", 0.2, 4e-4, q0=(x2, 0.0, phi[1])),
            md.Body("rack", 0.3, 1e-3, q0=(x2 + 0.06 + 0.02, 0.01, 0.0)),
        ],
        ground={"O1": (0.0, 0.0), "O2": (x2, 0.0), "G": (x2 + 0.08, 0.0)},
        joints=[
            md.Revolute("O1", "ground.O1", "g1"),
            md.Revolute("O2", "ground.O2", "g2"),
            md.Translational("guide", "ground.G", "rack", axis=(0.0, 1.0)),
            md.GearPair("mesh", "g1", "g2", radius_1, 0.06),
            md.RackPinion("rack_mesh", "g2", "rack", radius=0.05, axis=(0.0, 1.0)),
        ],
        drivers=[md.CoordinateDriver("motor", "g1", "phi", law=md.Ramp(0.4, 2.0))],
        units=md.SI,
    )


def test_a_swept_gear_radius_gives_the_mechanism_built_with_it():
    """No slip from the start angles: ``R1 (phi1 - phi1_0) = -R2 (phi2 - phi2_0)`` and the
    rack moves up ``R (phi2 - phi2_0)``: the closed form, and single runs of models built with
    each radius, agree with the sweep's members (and with a model whose number is replaced
    by its path) to 1e-12."""
    radii = [0.02, 0.03, 0.045]
    nominal = _gears()
    sweep = md.sweep(
        nominal,
        T,
        vary={"mesh.radius_i": radii, "rack_mesh.radius": [0.05, 0.04, 0.03]},
        analysis=md.analyses.Kinematic(),
    )
    assert not sweep.errors
    for i, (r1, rr) in enumerate(zip(radii, [0.05, 0.04, 0.03], strict=True)):
        member = sweep[i]
        phi2 = -0.3 - r1 / 0.06 * 2.0 * T
        np.testing.assert_allclose(member["g2.phi"], phi2, rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            member["rack.y"] - member["rack.y"][0], rr * (phi2 + 0.3), rtol=0, atol=1e-12
        )
        built = _gears(radius_1=r1)
        built = md.Model(
            bodies=built.bodies,
            ground={"O1": (0.0, 0.0), "O2": (0.09, 0.0), "G": (0.17, 0.0)},
            joints=[
                *built.joints[:4],
                md.RackPinion("rack_mesh", "g2", "rack", radius=rr, axis=(0.0, 1.0)),
            ],
            drivers=built.drivers,
            units=md.SI,
        )
        single = md.kinematic(built, T)
        replaced = md.paths.replace(
            md.paths.replace(nominal, "mesh.radius_i", r1), "rack_mesh.radius", rr
        )
        for other in (single, md.kinematic(replaced, T)):
            for col in ("g2.phi", "g2.omega", "rack.y", "rack.vy"):
                np.testing.assert_allclose(member[col], other[col], rtol=0, atol=1e-12)


def _friction_slider(v_stick=1e-3):
    """A slider on a guide with joint friction, pushed by a force."""
    return md.Model(
        bodies=[md.Body("slider", 1.0, 0.1)],
        ground={"G": (0.0, 0.0)},
        joints=[md.Translational("guide", "ground.G", "slider", axis=(1.0, 0.0))],
        forces=[
            md.PointForce("push", "slider", law=2.0, along=(1.0, 0.0)),
            md.JointFriction("fr", "guide", mu=0.1, v_stick=v_stick),
        ],
        units=md.SI,
    )


@pytest.mark.parametrize(
    ("model", "vary", "member", "words", "built"),
    [
        (
            _gears,
            {"mesh.radius_i": [0.03, 0.02, 0.0, -1.0]},
            2,
            "mesh.radius_i = 0 ",
            lambda: _gears(radius_1=0.0),
        ),
        (_gears, {"g2.mass": [0.1, -0.2]}, 1, "g2.mass = -0.2 ", lambda: md.Body("g2", -0.2)),
        (
            _friction_slider,
            {"fr.v_stick": [1e-3, 1e-4, 0.0]},
            2,
            "fr.v_stick = 0 ",
            lambda: _friction_slider(v_stick=0.0),
        ),
        (
            _friction_slider,
            {"fr.mu": [0.1, -0.1, 0.2]},
            1,
            "fr.mu = -0.1 ",
            lambda: md.JointFriction("fr", "guide", mu=-0.1),
        ),
    ],
)
def test_a_member_with_a_number_its_model_refuses_is_refused_before_computing(
    model, vary, member, words, built
):
    """The value a model's constructor refuses (the one a model file refuses at its line)
    is refused as a member, naming the member, the path and the value, with the
    constructor's reason, before any run (a stick band of 0 ran for minutes)."""
    with pytest.raises(ModelError) as truth:
        built()
    with pytest.raises(ModelError, match=f"member {member}: {words}") as err:
        md.sweep(model(), T, vary=vary)
    assert truth.value.message in str(err.value)


def _no_search(*args, **kwargs):
    raise AssertionError("the search started")


@pytest.mark.parametrize(
    ("params", "bounds", "words", "built"),
    [
        (
            ["rod.mass"],
            {"rod.mass": (-10.0, 10.0)},
            "the low bound: rod.mass = -10 is refused",
            lambda: md.Body("rod", -10.0),
        ),
        (
            ["spring.stiffness", "spring.free_length"],
            {"spring.stiffness": (0.0, 10.0), "spring.free_length": (-5.0, 1000.0)},
            "the low bound: spring.free_length = -5 is refused",
            lambda: md.SpringDamper("spring", "ground.O", "slider", free_length=-5.0),
        ),
    ],
)
def test_optimization_bounds_a_model_refuses_are_refused_before_searching(
    monkeypatch, params, bounds, words, built
):
    """Bounds whose end a model built with it refuses (the truth: that constructor) are an
    input error naming the bounds, not an optimum at a negative mass."""
    import scipy.optimize

    spec = mio.read(EXAMPLES / "slider_crank_spring.yaml")
    model, t = mio.build(spec), Runner(spec).plans["revolution"].times
    monkeypatch.setattr(scipy.optimize, "minimize", _no_search)
    with pytest.raises(ModelError) as truth:
        built()
    path = next(p for p in params if bounds[p][0] < 0)
    with pytest.raises(ModelError, match=words) as err:
        md.optimize(
            model,
            t,
            lambda o: o["motor"][0] ** 2,
            params,
            bounds,
            analysis=md.analyses.Inverse(),
        )
    assert err.value.element == f"bounds of {path!r}"
    assert truth.value.message in str(err.value)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        (dict(bounds={"rod.mass": (-10.0, 10.0)}), "the low bound: rod.mass = -10 is refused"),
        (dict(bounds={"rod.mass": (-np.inf, -1.0)}, start=[-2.0]), "the high bound: rod.mass"),
        (dict(start=[-2.0]), "the start: rod.mass = -2 is refused"),
    ],
)
def test_fit_bounds_and_starts_a_model_refuses_are_refused_before_fitting(
    monkeypatch, kwargs, words
):
    import scipy.optimize

    monkeypatch.setattr(scipy.optimize, "least_squares", _no_search)
    model = mio.build(mio.read(EXAMPLES / "identify_slider_crank.yaml"))
    with pytest.raises(ModelError, match=words) as err:
        md.fit(model, T, {"slider.x": np.full(len(T), 0.3)}, ["rod.mass"], **kwargs)
    assert "mass must be a finite number >= 0" in str(err.value)


def test_a_swept_start_gives_the_mesh_phase_of_a_model_built_with_it():
    """A gear's start angle is where its teeth mesh: a member with gear 2 started at
    ``phi2_0`` turns as ``phi2_0 - R1 / R2 (phi1 - phi1_0)`` (the closed form), as a model
    built with that start does."""
    starts = [(0.09, 0.0, -0.3), (0.09, 0.0, 0.2), (0.09, 0.0, 1.0)]
    sweep = md.sweep(_gears(), T, vary={"g2.q0": starts}, analysis=md.analyses.Kinematic())
    for i, q0 in enumerate(starts):
        np.testing.assert_allclose(
            sweep[i]["g2.phi"], q0[2] - 0.03 / 0.06 * 2.0 * T, rtol=0, atol=1e-12
        )
        single = md.kinematic(_gears(phi=(0.4, q0[2])), T)
        for col in ("g2.phi", "rack.y"):
            np.testing.assert_allclose(sweep[i][col], single[col], rtol=0, atol=1e-12)


def test_a_number_replaced_by_path_is_the_model_built_with_it():
    """``md.paths.replace`` gives the model built with the number: a start's mesh phase
    follows it (the single run of the model built with it, to 1e-12), and a value the
    constructor refuses is refused with its reason."""
    replaced = md.paths.replace(_gears(), "g2.q0", (0.09, 0.0, 0.7))
    built = _gears(phi=(0.4, 0.7))
    for col in ("g2.phi", "rack.y"):
        np.testing.assert_allclose(
            md.kinematic(replaced, T)[col], md.kinematic(built, T)[col], rtol=0, atol=1e-12
        )
    with pytest.raises(ModelError, match=r"the value: mesh.radius_i = 0 is refused: .* > 0"):
        md.paths.replace(_gears(), "mesh.radius_i", 0.0)


def _rocker(amplitude=0.2):
    """A cam turned from 0.8 rad at 3 rad/s swinging a pivoted arm by ``a sin(theta)``."""
    return md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3, q0=(0, 0, 0.8)),
            md.Body("arm", 0.2, 2e-3, q0=(0.12, 0.07, 0.0), points={"roller": (-0.1, 0.0)}),
        ],
        ground={"O": (0.0, 0.0), "P": (0.12, 0.07)},
        joints=[
            md.Revolute("O", "ground.O", "cam"),
            md.Revolute("P", "ground.P", "arm"),
            md.CamFollower(
                "pair",
                "cam",
                "arm",
                law=md.Harmonic(amplitude, 1.0),
                motion="oscillating",
                pivot="ground.P",
                point="arm.roller",
                follower_type="roller",
                roller=0.01,
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.8, 3.0))],
        units=md.SI,
    )


def test_a_swept_cam_law_keeps_the_follower_where_it_starts():
    """An oscillating follower's angle is its start plus the law's change from the cam's
    start angle, ``a (sin(theta) - sin(0.8))`` (the closed form), for each swept amplitude,
    as a model built with it gives."""
    amplitudes = [0.1, 0.2, 0.3]
    sweep = md.sweep(
        _rocker(), T, vary={"pair.law.amplitude": amplitudes}, analysis=md.analyses.Kinematic()
    )
    for i, a in enumerate(amplitudes):
        theta = 0.8 + 3.0 * T
        np.testing.assert_allclose(
            sweep[i]["arm.phi"], a * (np.sin(theta) - np.sin(0.8)), rtol=0, atol=1e-12
        )
        single = md.kinematic(_rocker(a), T)
        np.testing.assert_allclose(sweep[i]["arm.phi"], single["arm.phi"], rtol=0, atol=1e-12)


def test_a_fit_without_bounds_searches_within_the_range_a_model_accepts(monkeypatch):
    """A fitted mass without bounds is searched above the least mass a body accepts (its
    constructor takes that value and refuses the next float below it); a damping, which
    has no least value, stays unbounded."""
    import scipy.optimize

    seen = {}

    def capture(fun, x0, **kwargs):
        seen.update(kwargs)
        raise RuntimeError("captured")

    monkeypatch.setattr(scipy.optimize, "least_squares", capture)
    model = mio.build(mio.read(EXAMPLES / "identify_slider_crank.yaml"))
    with pytest.raises(RuntimeError, match="captured"):
        md.fit(model, T, {"slider.x": np.full(len(T), 0.3)}, ["rod.mass", "damper.damping"])
    (low_mass, low_damping), high = seen["bounds"]
    md.Body("b", low_mass)
    with pytest.raises(ModelError):
        md.Body("b", np.nextafter(low_mass, -np.inf))
    assert low_damping == -np.inf and np.all(np.asarray(high) == np.inf)
