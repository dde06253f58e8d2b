"""Mixed runs from model files, on mechanisms other than the paper's: motions prescribed by a
law, by samples and replayed from another run, each checked against an independent truth (the
inverse analysis, a closed form, the force of a forward run); the pre-run check binds the
prescribed motions as the analysis does; a mixed run never holds a coordinate it prescribes."""

import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import DATA
from mixdyn.runs import Runner

ENGINE = DATA / "engine_mixed.yaml"
CART = DATA / "cart_pendulum.yaml"
PENDULUM = DATA / "pendulum_mixed.yaml"

OMEGA = 3000 * 2 * np.pi / 60  # the engine's crank speed [rad/s]


def _line(text: str, needle: str) -> int:
    """1-based line of the first line of ``text`` containing ``needle``."""
    return next(i for i, s in enumerate(text.splitlines(), 1) if needle in s)


@pytest.fixture(scope="module")
def engine():
    runner = Runner(mio.read(ENGINE))
    return runner, runner.execute()


@pytest.fixture(scope="module")
def cart():
    runner = Runner(mio.read(CART))
    return runner, runner.execute()


# ------------------------------------------------------------------ law: against md.inverse
def test_law_engine_load_torque_is_the_inverse_dynamics_motor_torque(engine):
    """A vertical engine at 3000 rpm (crank prescribed by a law), gravity and a gas force: the
    unknown load torque is the motor torque of the inverse analysis of the same model with the
    crank driven by a driver of the same law."""
    runner, res = engine
    mx = res["constant_speed"]
    np.testing.assert_allclose(mx["crank.phi"], np.pi / 2 + OMEGA * mx.t, atol=1e-9)
    np.testing.assert_allclose(mx["crank.omega"], OMEGA, rtol=1e-9)
    motor = md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(np.pi / 2, OMEGA))
    inv = md.inverse(runner.model.replace(drivers=[motor]), mx.t)
    scale = np.max(np.abs(inv["motor"]))
    assert scale > 10.0  # inertia, gravity and gas force all count: a torque of tens of N*m
    np.testing.assert_allclose(mx["load"], inv["motor"], atol=1e-7 * scale)
    np.testing.assert_allclose(mx.q, inv.q, atol=1e-9)


# ------------------------------------------------------------------ the check binds the motions
def test_the_check_tests_the_prescribed_coordinate():
    """The engine lists the piston before the rod: the check that did not bind the prescribed
    motion tested piston.phi (fixed by the cylinder) and refused crank.phi as redundant."""
    runner = Runner(mio.read(ENGINE))
    rep = runner.mobility(runner.plans["constant_speed"])
    assert (rep.dof, rep.n_drivers, rep.redundant_drivers) == (1, 1, ())


def test_the_check_refuses_a_coordinate_the_joints_fix():
    """With the bodies in the order crank, rod, piston, prescribing piston.x (fixed by the
    cylinder) passed the unbinding check (it tested rod.x): now the check itself refuses it."""
    text = ENGINE.read_text()
    head, rest = text.split("  - name: piston\n")
    piston, rest = rest.split("  - name: rod\n")
    rod, tail = rest.split("\njoints:")
    text = f"{head}  - name: rod\n{rod}\n  - name: piston\n{piston.rstrip()}\njoints:{tail}"
    text = text.replace(
        "{coordinate: crank.phi, law: pi/2 + omega*t}", "{coordinate: piston.x, law: 0}"
    )
    runner = Runner(mio.reads(text, "engine.yaml"))
    assert [b.name for b in runner.model.bodies] == ["crank", "rod", "piston"]
    with pytest.raises(mio.FileError, match=r"redundant: prescribed piston\.x"):
        runner.mobility(runner.plans["constant_speed"])


# ------------------------------------------------------------------ law, samples: closed forms
@pytest.mark.slow  # long: run by CI's slow set
def test_law_and_samples_pendulum_torque_in_closed_form():
    """A rod pendulum whose angle is prescribed, by a law (constant speed) and by samples (a
    cubic spline through samples of a quadratic, which it reproduces): the torque is
    M = J_O phi'' + m g (L/2) sin(phi) with J_O = m L^2 / 3."""
    runner = Runner(mio.read(PENDULUM))
    res = runner.execute()
    m, g, L = 1.0, 9.81, 1.0
    J_O = m * L**2 / 3
    law = res["constant_speed"]
    t = law.t
    np.testing.assert_allclose(law["rod.phi"], 2 * t, atol=1e-10)
    np.testing.assert_allclose(law["motor"], m * g * L / 2 * np.sin(2 * t), atol=1e-8)
    samples = res["samples"]
    phi = 0.5 + 2 * t - t**2 / 2
    np.testing.assert_allclose(samples["rod.phi"], phi, atol=1e-10)
    np.testing.assert_allclose(
        samples["motor"], J_O * -1.0 + m * g * L / 2 * np.sin(phi), atol=1e-8
    )


# ------------------------------------------------------------------ from_run, samples: round trip
def test_from_run_cart_pendulum_recovers_the_force(cart):
    """Forward run with F = 2 sin(pi t) on the cart, then the mixed run replaying the cart's x
    from it (partition solver, the pendulum free): F and the whole motion come back."""
    _, res = cart
    fw, mx = res["forward"], res["mixed"]
    np.testing.assert_allclose(mx["F"], 2 * np.sin(np.pi * mx.t), atol=1e-6)
    np.testing.assert_allclose(mx.q, fw.q, atol=1e-7)


def test_samples_cart_pendulum_recovers_the_force(cart):
    """The cart's motion of the forward run written into the file as samples (a quintic
    Hermite law: positions, speeds, accelerations at the output times) gives F back too
    (augmented solver)."""
    _, res = cart
    fw = res["forward"]
    k = fw.model.coordinate_index("cart.x")

    def flow(a):
        return "[" + ", ".join(repr(float(v)) for v in a) + "]"

    run = f"""
  - name: samples
    kind: mixed
    time: {{span: [0, 1], n: 21}}
    unknown: [F]
    prescribed:
      - coordinate: cart.x
        law:
          hermite:
            t: {flow(fw.t)}
            y: {flow(fw.q[:, k])}
            yd: {flow(fw.qd[:, k])}
            ydd: {flow(fw.qdd[:, k])}
    rtol: 1.0e-11
    atol: 1.0e-12
"""
    runner = Runner(mio.reads(CART.read_text() + run, "cart.yaml"))
    mx = runner.execute(["samples"])["samples"]
    np.testing.assert_allclose(mx["F"], 2 * np.sin(np.pi * mx.t), atol=1e-6)
    np.testing.assert_allclose(mx.q, fw.q, atol=1e-7)


# ------------------------------------------------------------------ holds
def test_a_mixed_run_does_not_inherit_a_hold_on_what_it_prescribes(engine, cart):
    """assembly.hold still applies to other runs and to the coordinates a mixed run leaves
    free; a hold on a prescribed coordinate is dropped (its speed would be held at 0 against
    a crank turning at 3000 rpm: the engine's run above would fail)."""
    runner, _ = engine
    assert runner.spec.assembly.hold == ["crank.phi"]
    assert runner.hold(runner.plans["constant_speed"]) == ()
    runner, _ = cart
    assert runner.hold(runner.plans["forward"]) == ("cart.x", "pole.phi")
    assert runner.hold(runner.plans["mixed"]) == ("pole.phi",)


def test_a_run_that_holds_what_it_prescribes_is_refused():
    text = ENGINE.read_text().replace(
        "    rtol: 1.0e-10\n", "    rtol: 1.0e-10\n    hold: [crank.phi]\n"
    )
    with pytest.raises(mio.FileError) as e:
        Runner(mio.reads(text, "engine.yaml"))
    assert e.value.line == _line(text, "    hold: [crank.phi]")
    assert "crank.phi is held, but the run prescribes it" in str(e.value)


def test_a_conflicting_inherited_hold_is_an_input_error_naming_assembly_hold():
    """assembly.hold on rod.phi holds the rod's speed at 0 while the crank turns: the error
    points at assembly.hold, not at the run."""
    text = ENGINE.read_text().replace("hold: [crank.phi]", "hold: [crank.phi, rod.phi]")
    runner = Runner(mio.reads(text, "engine.yaml"))
    assert runner.hold(runner.plans["constant_speed"]) == ("rod.phi",)
    with pytest.raises(mio.FileError) as e:
        runner.mobility(runner.plans["constant_speed"])
    msg = str(e.value)
    assert e.value.line == _line(text, "hold: [crank.phi, rod.phi]")
    assert "assembly, hold" in msg and "rod.phi (from assembly.hold)" in msg
    assert "prescribed crank.phi" in msg and "hold: []" in msg


def test_a_conflicting_hold_of_the_run_is_an_input_error_naming_the_run():
    """The run's own hold on piston.y keeps the piston at its top position while the crank
    starts 0.3 rad past it: the start cannot be assembled; the error points at the run's
    hold."""
    text = ENGINE.read_text().replace(
        "law: pi/2 + omega*t}", "law: pi/2 + 0.3 + omega*t}\n    hold: [piston.y]"
    )
    runner = Runner(mio.reads(text, "engine.yaml"))
    with pytest.raises(mio.FileError) as e:
        runner.check_solvable(runner.plans["constant_speed"])
    msg = str(e.value)
    assert e.value.line == _line(text, "hold: [piston.y]")
    assert "piston.y (from the run's hold)" in msg and "remove them" in msg
