"""A cam and its translating follower: the follower's displacement, velocity and acceleration
against the closed forms of a harmonic and a cycloidal cam, the equations against finite
differences, the contact force of a spring-loaded follower against Newton's law, and the
separation speed ``sqrt(2 (F0 + k h) / (m h))`` of a harmonic cam: below it the follower stays
on the cam, above it the run fails naming the time it leaves."""

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES, evaluate, fd_gamma, fd_jacobian
from mixdyn.equations import Constraints
from mixdyn.runs import execute

H, BASE, M, K, F0 = 0.02, 0.05, 0.5, 200.0, 5.0


def cam_model(law, omega, *, spring=True, follower_type="knife", roller=0.0):
    """A cam pinned at the origin turning at ``omega``, a follower on a vertical guide above
    it, pressed onto the cam by a spring of rate K with preload F0 (at zero lift)."""
    y_anchor = -1.0
    L0 = BASE - y_anchor - F0 / K
    forces = (
        [md.SpringDamper("spring", "ground.A", "follower", stiffness=K, free_length=L0)]
        if spring
        else []
    )
    return md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3, q0=(0, 0, 0)),
            md.Body("follower", M, 1e-4, q0=(0, BASE, 0)),
        ],
        ground={"O": (0.0, 0.0), "A": (0.0, y_anchor)},
        joints=[
            md.Revolute("O", "ground.O", "cam"),
            md.Translational("guide", "ground.O", "follower", axis=(0, 1)),
            md.CamFollower(
                "cam_pair",
                "cam",
                "follower",
                law=law,
                base=BASE,
                follower_type=follower_type,
                roller=roller,
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.0, omega))],
        forces=forces,
        units=md.SI,
    )


def harmonic(theta):
    import jax.numpy as jnp

    return H / 2 * (1 - jnp.cos(theta))


@pytest.mark.parametrize("follower_type", ["knife", "roller", "flat"])
def test_harmonic_cam_follows_its_closed_form(follower_type):
    w = 5.0
    law = md.FunctionLaw(harmonic)
    model = cam_model(law, w, follower_type=follower_type, roller=0.01)
    t = np.linspace(0, 2 * math.pi / w, 73)
    res = md.inverse(model, t)
    th = w * t
    np.testing.assert_allclose(res["follower.y"], BASE + H / 2 * (1 - np.cos(th)), atol=1e-13)
    np.testing.assert_allclose(res["follower.vy"], H / 2 * w * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(res["follower.ay"], H / 2 * w**2 * np.cos(th), atol=1e-11)
    # Newton on the follower: the cam's push F = m a + spring force (F0 + K s)
    s = H / 2 * (1 - np.cos(th))
    np.testing.assert_allclose(res["cam_pair.F"], M * res["follower.ay"] + F0 + K * s, rtol=1e-10)
    if follower_type == "flat":
        np.testing.assert_allclose(res["cam_pair.alpha"], 0.0)
    else:  # tan(alpha) = s' / (base + s), no offset
        np.testing.assert_allclose(
            np.tan(res["cam_pair.alpha"]), H / 2 * np.sin(th) / (BASE + s), atol=1e-12
        )


def test_cycloidal_rise():
    w, beta = 4.0, math.pi
    import jax.numpy as jnp

    def rise(th):
        return H * (th / beta - jnp.sin(2 * jnp.pi * th / beta) / (2 * jnp.pi))

    def cycloidal(th):  # the rise over [0, beta], the same return over [beta, 2 beta]
        return jnp.where(th < beta, rise(th), rise(2 * beta - th))

    law = md.FunctionLaw(cycloidal)
    model = cam_model(law, w, spring=False)
    t = np.linspace(0, beta / w, 41)
    res = md.kinematic(model, t)
    x = w * t / beta
    np.testing.assert_allclose(
        res["follower.y"] - BASE, H * (x - np.sin(2 * np.pi * x) / (2 * np.pi)), atol=1e-13
    )
    np.testing.assert_allclose(
        res["follower.vy"], H * w / beta * (1 - np.cos(2 * np.pi * x)), atol=1e-12
    )
    np.testing.assert_allclose(
        res["follower.ay"], 2 * np.pi * H * w**2 / beta**2 * np.sin(2 * np.pi * x), atol=1e-10
    )


def test_cam_equations_against_finite_differences():
    model = md.Model(
        bodies=[
            md.Body("cam", 1.0, 0.1, q0=(0.1, 0.2, 0.3), points={"C": (0.02, -0.01)}),
            md.Body("fol", 1.0, 0.1, q0=(0.3, 0.6, 0.1), points={"P": (0.0, -0.05)}),
            md.Body("frame", 1.0, 0.1, q0=(0.0, 0.1, 0.4)),
        ],
        joints=[
            md.CamFollower(
                "c",
                "cam",
                "fol",
                law=md.Harmonic(0.05, 2.0, 0.2, 0.01),
                base=0.3,
                axis=(0.3, 1.0),
                frame="frame",
                center="cam.C",
                point="fol.P",
            )
        ],
        units=md.SI,
    )
    c = Constraints.of(model)
    rng = np.random.default_rng(5)
    q0 = np.array([0.1, 0.2, 0.3, 0.3, 0.6, 0.1, 0.0, 0.1, 0.4])
    for _ in range(3):
        q = q0 + rng.uniform(-0.3, 0.3, size=9)
        qd = rng.uniform(-2, 2, size=9)
        _, Phi_q, _, gamma = evaluate(c, q, qd, 0.0)
        np.testing.assert_allclose(Phi_q, fd_jacobian(c, q, 0.0), rtol=0, atol=1e-8)
        np.testing.assert_allclose(gamma, fd_gamma(c, q, qd, 0.0), rtol=1e-6, atol=1e-6)


@pytest.mark.slow  # long: run by CI's slow set
def test_separation_speed_of_a_spring_loaded_follower():
    w_sep = math.sqrt(2 * (F0 + K * H) / (M * H))
    law = md.FunctionLaw(harmonic)
    below = md.inverse(cam_model(law, 0.97 * w_sep), np.linspace(0, 2 * math.pi / w_sep, 401))
    assert below["cam_pair.F"].min() > 0
    w = 1.05 * w_sep
    with pytest.raises(md.ContactLostError, match="cam_pair") as info:
        md.inverse(cam_model(law, w), np.linspace(0, 2 * math.pi / w, 2001))
    # F = F0 + K h/2 (1 - cos th) + M w^2 h/2 cos th = 0
    th = math.acos(-(F0 + K * H / 2) / ((M * w**2 - K) * H / 2))
    assert info.value.time == pytest.approx(th / w, rel=1e-4)


def test_the_cam_example_file_and_its_separation_speed(tmp_path):
    """examples/cam_follower.yaml: the roller follower rises with the harmonic law written in
    theta; the file at 1250 rpm runs, at 1350 rpm it fails (exit 1) naming the contact and
    the time (the separation speed is sqrt(2 (F0 + k h) / (m h)) = 1293 rpm); a law of t is
    refused; the file writes back with its law in theta."""

    from typer.testing import CliRunner

    import mixdyn.io as mio
    from mixdyn.cli import app

    path = EXAMPLES / "cam_follower.yaml"
    text = path.read_text()
    res = execute(mio.read(path))["inverse"]
    th = res["cam.phi"]
    np.testing.assert_allclose(res["follower.y"], 50 + 10 * (1 - np.cos(th)), atol=1e-10)
    w_sep = math.sqrt(2 * (15 + 40) / (0.3 * 0.02)) * 30 / math.pi  # rpm
    assert 1290 < w_sep < 1296
    for rpm, code in ((1250, 0), (1350, 1)):
        f = tmp_path / f"c{rpm}.yaml"
        f.write_text(text.replace("rate: 300 rpm", f"rate: {rpm} rpm"))
        out = CliRunner().invoke(app, ["run", str(f), "--out", str(tmp_path / "o"), "--no-figures"])
        assert out.exit_code == code, out.output
        if code:
            assert "contact 'cam_pair' is lost" in out.output and "at t = " in out.output
    f = tmp_path / "t.yaml"
    f.write_text(text.replace("h/2*(1 - cos(theta))", "h/2*(1 - cos(t))"))
    out = CliRunner().invoke(app, ["check", str(f)])
    assert out.exit_code == 2 and "not of time t" in out.output
    assert "h/2*(1 - cos(theta))" in mio.dumps(mio.build(mio.read(path)))


@pytest.mark.parametrize("sense", [1.0, -1.0])
def test_oscillating_follower(sense):
    """A roller follower arm pivoted beside the cam swings by beta/2 (1 - cos theta): its
    angle, speed and acceleration follow the closed form, and the cam's moment on it is
    I psi'' plus the return spring's torque (Newton about the pivot)."""
    w, beta, I, kr = 3.0, 0.3, 2e-3, 4.0
    model = md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3, q0=(0, 0, 0)),
            md.Body("arm", 0.2, I, q0=(0.12, 0.07, 0.0), points={"roller": (-0.1, 0.0)}),
        ],
        ground={"O": (0.0, 0.0), "P": (0.12, 0.07)},
        joints=[
            md.Revolute("O", "ground.O", "cam"),
            md.Revolute("P", "ground.P", "arm"),
            md.CamFollower(
                "pair",
                "cam",
                "arm",
                law=md.FunctionLaw(lambda th: beta / 2 * (1 - jnp_cos(th))),
                motion="oscillating",
                pivot="ground.P",
                sense=sense,
                point="arm.roller",
                follower_type="roller",
                roller=0.01,
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.0, w))],
        forces=[
            md.RotarySpringDamper("ret", "ground", "arm", stiffness=kr, free_angle=-sense * 0.5)
        ],
        units=md.SI,
    )
    t = np.linspace(0, 2 * math.pi / w, 61)
    res = md.inverse(model, t)
    th = w * t
    psi = sense * beta / 2 * (1 - np.cos(th))
    np.testing.assert_allclose(res["arm.phi"], psi, atol=1e-13)
    np.testing.assert_allclose(res["arm.omega"], sense * beta / 2 * w * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(res["arm.alpha"], sense * beta / 2 * w**2 * np.cos(th), atol=1e-11)
    lift_moment = sense * (I * res["arm.alpha"] + kr * (psi + sense * 0.5))
    np.testing.assert_allclose(res["pair.M"], lift_moment, rtol=1e-10)
    assert np.all(res["pair.M"] > 0)
    assert "pair.F" not in res.columns()


def jnp_cos(x):
    import jax.numpy as jnp

    return jnp.cos(x)


def test_the_rocker_example_file():
    """examples/cam_rocker.yaml: the arm swings by the cycloidal rise and return written in
    theta (clockwise, sense -1), the cam pushes throughout, and the file writes back."""

    import mixdyn.io as mio

    path = EXAMPLES / "cam_rocker.yaml"
    spec = mio.read(path)
    # two and a half turns: the law, given over one turn, is read within each turn
    longer = path.read_text().replace("span: [0, 0.5], n: 181", "span: [0, 1.25], n: 451")
    res = execute(mio.reads(longer))["inverse"]
    th = np.mod(res["cam.phi"], 2 * np.pi)
    b = math.radians(15)
    rise = th / np.pi - np.sin(2 * th) / (2 * np.pi)
    s = np.where(th < np.pi, rise, 2 - th / np.pi + np.sin(2 * th) / (2 * np.pi))
    np.testing.assert_allclose(res["arm.phi"], -b * s, atol=1e-12)
    assert res["cam_pair.M"].min() > 0
    assert mio.reads(mio.dumps(spec)) == spec
    again = mio.build(mio.reads(mio.dumps(mio.build(spec))))
    assert again.joints[2].motion == "oscillating" and again.joints[2].sense == -1.0


def test_a_cam_given_by_samples():
    """A cam profile given by 73 samples of its displacement over a turn (a periodic cubic
    spline through them): the follower follows the harmonic law the samples came from, to the
    spline's accuracy (under 0.2 micrometres at 5 degree spacing), over two turns."""
    th = np.linspace(0, 2 * np.pi, 73)
    law = md.Spline(th, H / 2 * (1 - np.cos(th)), bc_type="periodic")
    w = 5.0
    t = np.linspace(0, 4 * math.pi / w, 97)
    res = md.kinematic(cam_model(law, w, spring=False), t)
    np.testing.assert_allclose(res["follower.y"], BASE + H / 2 * (1 - np.cos(w * t)), atol=2e-7)
    np.testing.assert_allclose(res["follower.vy"], H / 2 * w * np.sin(w * t), atol=2e-5)


def test_an_oscillating_flat_faced_follower_touches_its_cam_profile():
    """An arm pivoted at P whose flat underside (through the face point, normal up) rides on
    the cam, swinging by beta/2 (1 - cos theta): at every cam angle the face's line, placed
    by the arm's rotation about P (independent of the envelope the profile is drawn from),
    touches the drawn profile and has all of it on the cam's side."""
    beta, base = 0.1, 0.04
    model = md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3, q0=(0, 0, 0)),
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
                law=md.FunctionLaw(lambda th: beta / 2 * (1 - jnp_cos(th))),
                motion="oscillating",
                pivot="ground.P",
                sense=-1.0,  # lifting the face turns the arm clockwise
                point="arm.face",
                follower_type="flat",
                axis=(0.0, 1.0),
                base=base,
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.0, 1.0))],
        units=md.SI,
    )
    pair = model.joints[2]
    prof = pair.profile(720)
    P, F0, n0 = np.array([0.1, 0.06]), np.array([0.0, 0.04]), np.array([0.0, 1.0])
    worst_side, worst_touch = 0.0, 0.0
    for th in np.linspace(0.0, 2 * math.pi, 97):
        dpsi = -beta / 2 * (1 - math.cos(th))
        R = np.array([[math.cos(dpsi), -math.sin(dpsi)], [math.sin(dpsi), math.cos(dpsi)]])
        F, n = P + R @ (F0 - P), R @ n0
        back = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]])
        d = prof @ (back @ n) - (back @ F) @ (back @ n)  # signed distance to the face
        worst_side = max(worst_side, float(d.max()))
        worst_touch = max(worst_touch, float(np.abs(d).min()))
    assert worst_side < 2e-6 * base and worst_touch < 2e-5 * base
    # the swing lifts the face: the profile reaches beyond the base circle
    assert np.linalg.norm(prof, axis=1).max() > base * 1.05
