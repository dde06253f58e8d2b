"""The cam follower in a model file, made from its class's declaration: each check lives in
the class and a file meets it at the field's line with the same words as Python; its law is
a law of the cam angle ``theta`` (knots in degrees converted to radians, ``t`` refused); a
model built in Python writes to a file that builds the same equations back. ``mixdyn check``
refuses a cam's or a driver's law that jumps at the law's line (exit 2) and passes the
shipped cam examples."""

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.cli import app
from mixdyn.equations import Constraints

FILE = """\
mixdyn: 1
units: {length: mm, mass: kg, time: s}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: cam, mass: 1, inertia: 100}
  - {name: follower, mass: 0.3, inertia: 20, q0: [0, 50, 0]}
joints:
  - {type: revolute, name: O, point_i: ground.O, point_j: cam}
  - {type: translational, name: guide, point_i: ground.O, point_j: follower, axis: [0, 1]}
  - type: cam_follower
    name: cam_pair
    cam: cam
    follower: follower
    law: 10*(1 - cos(theta))
    base: 50 mm
    follower_type: roller
    roller: 10 mm
drivers:
  - {type: coordinate, name: motor, coordinate: cam.phi, law: 2*pi*t}
"""


def sub(old: str, new: str, text: str = FILE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def line_of(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if fragment in line)


def refused(text: str) -> mio.FileError:
    with pytest.raises(mio.FileError) as e:
        mio.build(mio.reads(text))
    return e.value


def test_the_roller_against_the_base_is_one_check():
    """A roller as large as the base distance: the class refuses it, and a file reports the
    class's own words at the roller's line."""
    text = sub("roller: 10 mm", "roller: 50 mm")
    e = refused(text)
    assert e.line == line_of(text, "roller: 50 mm")
    with pytest.raises(md.ModelError) as py:
        md.CamFollower(
            "cam_pair", "cam", "follower", law=1.0, base=50.0, follower_type="roller", roller=50.0
        )
    assert py.value.field == "roller"
    assert py.value.message in str(e)


def test_a_translating_follower_needs_its_base():
    e = refused(sub("    base: 50 mm\n", ""))
    assert "base" in str(e) and e.line == line_of(FILE, "type: cam_follower")
    with pytest.warns(DeprecationWarning, match="give base"):
        pair = md.CamFollower("c", "cam", "follower", law=1.0)
    assert float(pair.base) == 1.0


def test_a_cam_law_of_time_is_refused():
    text = sub("10*(1 - cos(theta))", "10*(1 - cos(t))")
    e = refused(text)
    assert "not of time t" in str(e) and e.line == line_of(text, "cos(t)")


def test_spline_knots_are_angles():
    """A spline through 73 samples of ``10 (1 - cos theta)`` [mm], knots in degrees: the law
    at 90 and 180 degrees is the harmonic's there."""
    deg = np.arange(0, 361, 5)
    y = 10 * (1 - np.cos(np.radians(deg)))
    spline = (
        "{spline: {t: ["
        + ", ".join(f"{d} deg" for d in deg)
        + "], y: ["
        + ", ".join(f"{v:.12g}" for v in y)
        + "]}}"
    )
    model = mio.build(mio.reads(sub("10*(1 - cos(theta))", spline)))
    law = model.element("cam_pair").law
    np.testing.assert_allclose(
        [float(law(math.pi / 2)), float(law(math.pi))], [10.0, 20.0], atol=1e-4
    )


def test_a_cam_built_in_python_writes_back():
    """An oscillating flat-faced follower (which a file may hold: the class draws and runs
    it) with an expression law: written with ``theta``, read back to the same residual."""
    law = mio.expressions.ExpressionLaw("0.1/2*(1 - cos(t))", {})
    model = md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3),
            md.Body("arm", 0.2, 2e-3, q0=(0.1, 0.06, 0.0), points={"face": (-0.1, -0.02)}),
        ],
        ground={"O": (0.0, 0.0), "P": (0.1, 0.06)},
        joints=[
            md.Revolute("O", "ground.O", "cam"),
            md.Revolute("P", "ground.P", "arm"),
            md.CamFollower(
                "pair",
                "cam",
                "arm",
                law=law,
                motion="oscillating",
                pivot="ground.P",
                sense=-1.0,
                point="arm.face",
                follower_type="flat",
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.0, 1.0))],
        units=md.SI,
    )
    text = mio.dumps(model)
    assert "0.1/2*(1 - cos(theta))" in text and "sense: -1" in text and "base" not in text
    back = mio.build(mio.reads(text))
    assert mio.dumps(back) == text
    q = np.random.default_rng(3).uniform(-1, 1, model.nq)
    c, c_back = Constraints.of(model), Constraints.of(back)
    np.testing.assert_allclose(c.full(q, 0.3), c_back.full(q, 0.3), rtol=0, atol=1e-15)


RUN = """\
runs:
  - {name: kin, kind: kinematic, time: {span: [0, 1], n: 5}}
"""

#: A parabolic rise and return of 20 mm (constant accelerations +-80/pi**2 mm/rad**2): its
#: second derivative jumps by -8*20/pi**2 = -16.2114 at pi/2 and back at 3 pi/2.
CONSTANT_ACCELERATION = (
    "'where(theta < pi/2, 40*(theta/pi)**2, where(theta < pi, 20 - 40*((pi - theta)/pi)**2, "
    "where(theta < 3*pi/2, 20 - 40*((theta - pi)/pi)**2, 40*((2*pi - theta)/pi)**2)))'"
)
#: A trapezoidal speed: 16 pi rad/s**2 to t = 0.25, then 4 pi rad/s (a jump of -16 pi).
TRAPEZOID = "where(t < 0.25, 8*pi*t**2, pi/2 + 4*pi*(t - 0.25))"


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        (
            "10*(1 - cos(theta))",
            "where(theta < pi, 0, 20)",
            "jumps by +20 (model units) in its value at theta = 3.14159 rad (180 deg)",
        ),
        (
            "10*(1 - cos(theta))",
            "20*theta/(2*pi)",
            "where the turn wraps around to theta = 0",
        ),
        (
            "law: 2*pi*t}",
            "law: 'where(t < 0.5, 2*pi*t, 4*pi*t - pi)'}",
            "driver 'motor', law: the law 'where(t < 0.5, 2*pi*t, 4*pi*t - pi)' jumps by "
            "+6.28319 (model units) in its slope at t = 0.5",
        ),
        (
            "10*(1 - cos(theta))",
            CONSTANT_ACCELERATION,
            "jumps by -16.2114 (model units) in its second derivative at theta = 1.5708 rad "
            "(90 deg)",
        ),
        (
            "law: 2*pi*t}",
            f"law: '{TRAPEZOID}'}}",
            "jumps by -50.2655 (model units) in its second derivative at t = 0.25",
        ),
    ],
    ids=["cam-step", "cam-sawtooth", "driver-kink", "cam-acceleration", "driver-acceleration"],
)
def test_mixdyn_check_refuses_a_law_that_jumps_at_its_line(tmp_path, old, new, expected):
    text = sub(old, new, FILE + RUN)
    path = tmp_path / "jump.yaml"
    path.write_text(text, encoding="utf-8")
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2 and "Traceback" not in res.output, res.output
    assert f"{path}:{line_of(text, new)}:" in res.stderr and expected in res.stderr, res.stderr


def test_continuity_c1_accepts_finite_acceleration_jumps():
    """The constant-acceleration cam and the trapezoidal speed above, declared ``continuity:
    C1`` (on the cam, the driver, a prescribed motion), are accepted; the prescribed motion
    without it is refused at its law's line."""
    cam = sub("10*(1 - cos(theta))", CONSTANT_ACCELERATION + "\n    continuity: C1", FILE + RUN)
    text = sub("law: 2*pi*t}", f"law: '{TRAPEZOID}', continuity: C1}}", cam)
    model = mio.build(mio.reads(text))
    assert model.element("cam_pair").continuity == model.drivers[0].continuity == "C1"
    from mixdyn.runs import Runner

    Runner(mio.reads(text))  # the run's checks
    prescribed = (
        "  - name: kin2\n    kind: kinematic\n    time: {span: [0, 1], n: 5}\n"
        "    drivers: []\n    prescribed:\n"
        f"      - {{coordinate: cam.phi, law: '{TRAPEZOID}'CONTINUITY}}\n"
    )
    with pytest.raises(mio.FileError, match=r"second derivative at t = 0\.25") as e:
        Runner(mio.reads(cam + prescribed.replace("CONTINUITY", "")))
    assert e.value.line == len((cam + prescribed).splitlines())
    Runner(mio.reads(cam + prescribed.replace("CONTINUITY", ", continuity: C1")))


@pytest.mark.parametrize("name", ["cam_follower", "cam_rocker"])
def test_the_cam_examples_pass_mixdyn_check(name):
    res = CliRunner().invoke(app, ["check", str(EXAMPLES / f"{name}.yaml")])
    assert res.exit_code == 0, res.output
