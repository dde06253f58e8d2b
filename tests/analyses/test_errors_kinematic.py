"""Errors of model building and kinematic analysis: each is a mixdyn error naming the
element at fault, and numerical failures carry the time at which they happened."""

import numpy as np
import pytest

import mixdyn as md
from fixtures import paper_mechanism, slider_crank

T = np.linspace(0.0, 1.0, 5)


# ------------------------------------------------------------------------ bad names
def test_unknown_body_is_named():
    with pytest.raises(md.ModelError, match="nobody") as err:
        md.Model([md.Body("crank")], joints=[md.Revolute("pin", "ground", "nobody.O")])
    assert err.value.element == "pin"
    assert "pin" in str(err.value)


def test_unknown_point_is_named():
    with pytest.raises(md.ModelError, match="'Q'") as err:
        md.Model(
            [md.Body("crank", points={"O": (0, 0)})],
            joints=[md.Revolute("pin", "ground", "crank.Q")],
        )
    assert err.value.element == "pin"
    assert "crank" in str(err.value) and "O" in str(err.value)  # says what there is


def test_unknown_ground_point_is_named():
    with pytest.raises(md.ModelError, match="'Z'") as err:
        md.Model([md.Body("crank")], joints=[md.Revolute("pin", "ground.Z", "crank")])
    assert err.value.element == "pin"


def test_unknown_names_in_drivers():
    with pytest.raises(md.ModelError, match="nobody") as err:
        md.Model([md.Body("crank")], drivers=[md.CoordinateDriver("m", "nobody", "phi", law=0)])
    assert err.value.element == "m"
    with pytest.raises(md.ModelError, match="psi") as err:
        md.Model([md.Body("crank")], drivers=[md.CoordinateDriver("m", "crank", "psi", law=0)])
    assert err.value.element == "m"
    with pytest.raises(md.ModelError, match="'Z'") as err:
        md.Model([md.Body("crank")], drivers=[md.PointDriver("m", "crank.Z", "x", law=0)])
    assert err.value.element == "m"
    # drivers handed to the analysis are checked the same way
    with pytest.raises(md.ModelError, match="nobody") as err:
        md.kinematic(slider_crank(), T, drivers=[md.CoordinateDriver("m2", "nobody", "x", law=0)])
    assert err.value.element == "m2"


def test_duplicate_names():
    with pytest.raises(md.ModelError, match="duplicate") as err:
        md.Model([md.Body("crank"), md.Body("crank")])
    assert err.value.element == "crank"
    with pytest.raises(md.ModelError, match="duplicate") as err:
        md.Model(
            [md.Body("crank")],
            joints=[md.Revolute("pin", "ground", "crank"), md.Revolute("pin", "ground", "crank")],
        )
    assert err.value.element == "pin"
    # a joint and a driver may not share a name either
    with pytest.raises(md.ModelError, match="duplicate") as err:
        md.Model(
            [md.Body("crank")],
            joints=[md.Revolute("pin", "ground", "crank")],
            drivers=[md.CoordinateDriver("pin", "crank", "phi", law=0.0)],
        )
    assert err.value.element == "pin"


def test_joint_on_one_body():
    with pytest.raises(md.ModelError, match="two different bodies") as err:
        md.Model(
            [md.Body("crank", points={"O": (0, 0)})], joints=[md.Revolute("r", "crank", "crank.O")]
        )
    assert err.value.element == "r"


def test_bad_numbers_are_model_errors():
    with pytest.raises(md.ModelError, match="mass") as err:
        md.Body("crank", mass=-1.0)
    assert err.value.element == "crank"
    with pytest.raises(md.ModelError, match="'P'") as err:
        md.Body("crank", points={"P": (0.0, np.nan)})
    assert err.value.element == "crank"
    with pytest.raises(md.ModelError, match="zero length") as err:
        md.Model(
            [md.Body("c"), md.Body("d")], joints=[md.Translational("s", "c", "d", axis=(0, 0))]
        )
    assert err.value.element == "s"
    with pytest.raises(md.ModelError, match="reserved"):
        md.Body("ground")


def test_bad_output_times_are_model_errors():
    with pytest.raises(md.ModelError, match="increasing"):
        md.kinematic(slider_crank(), [0.0, 0.5, 0.5, 1.0])


# ------------------------------------------------------------------ driver balance
def test_too_few_drivers():
    model = paper_mechanism(
        drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0, 1))]
    )
    with pytest.raises(md.DegreesOfFreedomError, match=r"2 degrees of freedom but 1 driver") as err:
        md.kinematic(model, T)
    assert "add 1" in str(err.value)
    with pytest.raises(md.DegreesOfFreedomError, match="0 driver"):
        md.kinematic(slider_crank(drivers=()), T)


def test_too_many_drivers():
    """A driver beyond the degrees of freedom is refused, naming the extra driver."""
    drivers = [
        md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.0, 1.0)),
        md.CoordinateDriver("push", "slider", "x", law=0.4),
    ]
    with pytest.raises((md.DegreesOfFreedomError, md.RedundantConstraintError)) as err:
        md.kinematic(slider_crank(drivers=drivers), T)
    assert "push" in str(err.value)
    report = md.degrees_of_freedom(slider_crank(drivers=drivers))
    assert report.dof == 1 and report.n_drivers == 2 and not report.balanced
    assert "expected 1" in str(report)


def test_driver_repeating_a_joint_motion():
    """The slide joint fixes the slider's y and angle: driving either is redundant."""
    for coordinate in ("y", "phi"):
        drivers = [md.CoordinateDriver("lift", "slider", coordinate, law=0.0)]
        with pytest.raises(md.RedundantConstraintError, match="lift"):
            md.kinematic(slider_crank(drivers=drivers), T)
        report = md.degrees_of_freedom(slider_crank(drivers=drivers))
        assert report.redundant_drivers == ("lift",)


# -------------------------------------------------------------------------- assembly
def test_unreachable_assembly_names_the_joint():
    """A rod of length 5 from (3, 0) to the tip of a unit link turning about the origin can
    reach at most 4: the assembly fails and names the distance joint."""
    model = md.Model(
        [md.Body("link", q0=(0.5, 0.0, 0.0), points={"O": (-0.5, 0.0), "T": (0.5, 0.0)})],
        joints=[
            md.Revolute("pin", "ground", "link.O"),
            md.Distance("rope", "ground.P", "link.T", length=5.0),
        ],
        ground={"P": (3.0, 0.0)},
    )
    with pytest.raises(md.AssemblyError) as err:
        md.assemble(model)
    assert "rope.length" in err.value.elements
    assert "rope" in str(err.value)
    with pytest.raises(md.AssemblyError, match="rope"):
        md.kinematic(model.replace(drivers=[md.CoordinateDriver("m", "link", "phi", law=0.0)]), T)


# ------------------------------------------------------------------------ dead point
R, L = 0.1, 0.3
TH0 = 0.5
X0 = R * np.cos(TH0) + np.sqrt(L**2 - (R * np.sin(TH0)) ** 2)  # slider at crank angle TH0
X_DEAD = R + L  # slider at the outer dead point (crank and rod in line)


def test_slider_pushed_past_the_dead_point():
    """Driving the slider outwards at constant speed beyond ``r + l`` leaves the workspace at
    the dead point ``td``: the failure is reported at the first output time after ``td``,
    naming the driver."""
    v = 0.01
    td = (X_DEAD - X0) / v
    t = np.linspace(0.0, 2 * td, 101)
    dt = t[1] - t[0]
    drivers = [md.CoordinateDriver("push", "slider", "x", law=md.Ramp(X0, v))]
    with pytest.raises((md.SingularityError, md.ConvergenceError)) as err:
        md.kinematic(slider_crank(R, L, theta0=TH0), t, drivers=drivers)
    assert td < err.value.time <= td + dt
    assert "push" in err.value.elements
    assert f"{err.value.time:.6g}" in str(err.value)


def _through_dead_point(n):
    """Slider driven to the dead point and back, ``x = x_dead - k (t - td)^2``, ``td = 1``;
    ``n`` output times on [0, 2]."""
    td = 1.0
    k = (X_DEAD - X0) / td**2
    law = md.Polynomial([X_DEAD - k * td**2, 2 * k * td, -k])
    drivers = [md.CoordinateDriver("push", "slider", "x", law=law)]
    t = np.linspace(0.0, 2 * td, n)
    return md.kinematic(slider_crank(R, L, theta0=TH0), t, drivers=drivers), td, t[1] - t[0]


def test_slider_driven_near_the_dead_point_is_regular():
    """Output times that miss the dead point: the crank angle follows the closed form
    ``cos th = (x^2 + r^2 - l^2) / (2 r x)`` on either side of ``td`` (on one side or the
    other of the slider line after it: the drivers do not say which)."""
    res, td, _ = _through_dead_point(40)  # the times straddle td = 1
    before = res.t < td
    x = res["slider.x"]
    th = np.arccos((x**2 + R**2 - L**2) / (2 * R * x))
    np.testing.assert_allclose(res["crank.phi"][before], th[before], atol=1e-9)
    np.testing.assert_allclose(np.abs(res["crank.phi"][~before]), th[~before], atol=1e-9)


def test_slider_driven_through_the_dead_point_reports_a_singularity():
    with pytest.raises(md.SingularityError) as err:
        _through_dead_point(101)  # t = 1.0 is an output time
    assert err.value.time == pytest.approx(1.0, abs=0.02)
