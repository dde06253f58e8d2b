"""Inverse and mixed dynamics: the paper's round trip, inverse <-> forward, a non-collocated
case against closed-form kinetostatics, the energy balance, and unsolvable problems."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import paper_loads, paper_mechanism, slider_crank

T_END = 2.0
TS = np.linspace(0.0, T_END, 1001)  # 2 ms samples of the forward run
TIGHT = dict(rtol=1e-12, atol=1e-12)


def F1_exact(t):
    return 10.0 * np.sin(np.pi * t / 2)


@pytest.fixture(scope="module")
def model():
    return paper_mechanism(forces=paper_loads())


@pytest.fixture(scope="module")
def forward_run(model):
    return md.forward(model, TS, hold=("crank.phi", "coupler.phi"), **TIGHT)


def _mixed(model, fw, **kw):
    return md.mixed(
        model,
        TS,
        prescribed=[md.prescribe(fw, "slider.x")],
        unknown=["F1"],
        q0=fw.q[0],
        qd0=fw.qd[0],
        **TIGHT,
        **kw,
    )


@pytest.fixture(scope="module")
def mixed_runs(model, forward_run):
    return {
        "partition, i = coupler.phi (the paper)": _mixed(
            model, forward_run, solver="partition", independent=["coupler.phi"]
        ),
        "partition, automatic": _mixed(model, forward_run, solver="partition"),
        "augmented": _mixed(model, forward_run, solver="augmented"),
    }


def test_forward_run_moves_and_closes(forward_run):
    """The forward run is not trivial and keeps the joints closed."""
    assert np.ptp(forward_run["slider.x"]) > 10.0  # mm
    assert forward_run.stats["max_violation"] < 1e-9


@pytest.mark.parametrize(
    "which", ["partition, i = coupler.phi (the paper)", "partition, automatic", "augmented"]
)
def test_round_trip_recovers_F1(mixed_runs, forward_run, which):
    """The paper's proof of method: the recovered force is 10 sin(pi t/2) (<= 1e-6 absolute)
    and the free motion equals the forward run's (crank and coupler angles <= 1e-7 rad)."""
    mx = mixed_runs[which]
    assert np.max(np.abs(mx["F1"] - F1_exact(TS))) <= 1e-6
    for col in ("crank.phi", "coupler.phi"):
        assert np.max(np.abs(mx[col] - forward_run[col])) <= 1e-7
    assert mx.units()["F1"] == "mN"  # kg*mm/s**2, named plainly


def test_solvers_agree(mixed_runs):
    """The partition and augmented solvers are two routes to one answer: <= 1e-9."""
    ref = mixed_runs["augmented"]
    for name, mx in mixed_runs.items():
        for col in ("F1", "crank.phi", "coupler.phi", "link.phi"):
            assert np.max(np.abs(mx[col] - ref[col])) <= 1e-9, (name, col)


def test_generalized_alpha_recovers_F1(model, forward_run):
    """Mixed dynamics integrated by generalized-alpha (augmented solver, ``G != C^T``: the
    unknown force's direction enters the Newton matrix): over the first 0.25 s at dt = 1e-4
    the recovered force is 10 sin(pi t/2) to 1e-6 (second order: measured 2.2e-7) and the
    free motion the forward run's (crank angle <= 1e-8 rad, measured 1.1e-9)."""
    k = int(np.searchsorted(TS, 0.25)) + 1
    ts = TS[:k]
    mx = md.mixed(
        model,
        ts,
        prescribed=[md.prescribe(forward_run, "slider.x")],
        unknown=["F1"],
        q0=forward_run.q[0],
        qd0=forward_run.qd[0],
        solver="augmented",
        method="generalized-alpha",
        dt=1e-4,
    )
    assert np.max(np.abs(mx["F1"] - F1_exact(ts))) <= 1e-6
    assert np.max(np.abs(mx["crank.phi"] - forward_run["crank.phi"][:k])) <= 1e-8


def test_energy_balance_of_recovered_force(mixed_runs):
    """Work of the recovered force plus work of the known forces equals the change of the
    mechanism's energy; and the recovered force's power integrates to its work."""
    mx = mixed_runs["augmented"]
    E = mx["energy.total"]
    W = mx["work.nonconservative"] + mx["work.constraints"]
    assert np.max(np.abs(E - E[0] - W)) <= 1e-9 * np.max(np.abs(E - E[0]))
    # F1's power: u * (B . qd) = F1 * slider.vx; independent trapezoidal integration.
    P = mx["F1"] * mx["slider.vx"]
    np.testing.assert_allclose(mx["F1.power"], P, rtol=1e-10, atol=1e-12 * np.max(np.abs(P)))
    W_F1 = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(TS) * (P[1:] + P[:-1]))])
    np.testing.assert_allclose(W_F1, mx["work.constraints"], atol=1e-5 * np.max(np.abs(W_F1)))


# --------------------------------------------------------------------------------- inverse
@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_inverse_efforts_reproduce_motion_in_forward():
    """Efforts from an inverse run, applied as known forces in a forward run, reproduce the
    prescribed motion (crank angle) to <= 1e-7."""
    law = md.Polynomial([0.0, 1.0, 0.0, 0.5])  # phi = t + t^3 / 2
    driven = slider_crank(
        0.1, 0.3, 1.0, drivers=[md.CoordinateDriver("motor", "crank", "phi", law=law)]
    )
    driven = driven.replace(
        gravity=(0.0, -9.81),
        forces=[
            md.SpringDamper(
                "spring", "ground", "slider", stiffness=50.0, damping=0.5, free_length=0.3
            )
        ],
    )
    ts = np.linspace(0.0, 1.0, 1001)
    inv = md.inverse(driven, ts)
    assert inv.units()["motor"] == "N*m"
    torque = md.Spline(ts, inv["motor"], kind="quintic")
    free = driven.replace(
        drivers=(), forces=[*driven.forces, md.Torque("motor", "crank", law=torque)]
    )
    fw = md.forward(free, ts, q0=inv.q[0], qd0=inv.qd[0], **TIGHT)
    assert np.max(np.abs(fw["crank.phi"] - law(ts))) <= 1e-7
    assert np.max(np.abs(fw["slider.x"] - inv["slider.x"])) <= 1e-7


def test_inverse_power_balance():
    """The driver's power equals the rate of change of energy minus the known forces' power
    (an independent check of the effort through finite differences of the energy)."""
    law = md.Harmonic(1.0, 3.0)
    m = slider_crank(0.1, 0.3, 1.0, drivers=[md.CoordinateDriver("motor", "crank", "phi", law=law)])
    m = m.replace(gravity=(0.0, -9.81))
    ts = np.linspace(0.0, 1.0, 2001)
    inv = md.inverse(m, ts)
    E = inv["energy.total"]
    dE = np.gradient(E, ts, edge_order=2)
    P = inv["motor"] * inv["crank.omega"]
    np.testing.assert_allclose(inv["motor.power"], P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P[2:-2], dE[2:-2], atol=1e-5 * np.max(np.abs(P)))


# ----------------------------------------------------------------------- non-collocated
def _slider_crank_closed_form(r, l, masses, inertias, x_law):
    """Crank torque for a prescribed slider motion, by the power balance
    ``T omega_crank = d(KE)/dt`` on the closed-form kinematics (no gravity, no other force).

    The mechanism's positions are explicit functions of the slider position x:
    ``cos th = (x^2 + r^2 - l^2) / (2 r x)``, crank centre at ``r/2 (cos th, sin th)``, rod
    centre halfway between the crank pin and the slider, rod angle from the pin to the
    slider. Derivatives by JAX of these formulas — none of mixdyn's machinery is used.
    """

    def config(x):
        th = jnp.arccos((x**2 + r**2 - l**2) / (2 * r * x))
        pin = r * jnp.array([jnp.cos(th), jnp.sin(th)])
        rod_c = 0.5 * (pin + jnp.array([x, 0.0]))
        psi = jnp.arctan2(-pin[1], x - pin[0])
        return jnp.array([0.5 * pin[0], 0.5 * pin[1], th, rod_c[0], rod_c[1], psi, x, 0.0, 0.0])

    Mdiag = jnp.array(
        [
            masses[0],
            masses[0],
            inertias[0],
            masses[1],
            masses[1],
            inertias[1],
            masses[2],
            masses[2],
            inertias[2],
        ]
    )

    def kinetic(t):
        x, xd = jax.jvp(x_law, (t,), (1.0,))
        qd = jax.jvp(config, (x,), (xd,))[1]
        return 0.5 * jnp.sum(Mdiag * qd**2), qd[2]

    def torque(t):
        dKE = jax.grad(lambda s: kinetic(s)[0])(t)
        return dKE / kinetic(t)[1]

    return jax.vmap(torque)


@pytest.mark.slow  # long: run by CI's slow set
def test_non_collocated_slider_prescribed_crank_torque_unknown():
    """Prescribe the slider position, leave the crank torque unknown (not collocated):
    the recovered torque matches the closed-form kinetostatics."""
    r, l = 0.1, 0.3
    law = md.Harmonic(0.02, 2.0, phase=np.pi / 2, offset=0.33)  # x = 0.33 + 0.02 cos 2t
    m = slider_crank(r, l, 1.0, theta0=0.9)
    m = m.replace(drivers=(), forces=[md.Torque("motor", "crank", law=0.0)])
    ts = np.linspace(0.0, 1.0, 201)
    res = md.mixed(
        m,
        ts,
        prescribed=[md.CoordinateDriver("x", "slider", "x", law=law)],
        unknown=["motor"],
        solver="augmented",
        **TIGHT,
    )
    masses = [float(b.mass) for b in m.bodies]
    inertias = [float(b.inertia) for b in m.bodies]
    exact = _slider_crank_closed_form(r, l, masses, inertias, law)(jnp.asarray(ts))
    np.testing.assert_allclose(res["slider.x"], law(ts), atol=1e-10)
    np.testing.assert_allclose(
        res["motor"], np.asarray(exact), rtol=1e-7, atol=1e-9 * np.max(np.abs(exact))
    )


# ---------------------------------------------------------------------------- bad input
def test_more_unknowns_than_prescribed(model, forward_run):
    with pytest.raises(md.SolvabilityError, match="2 unknown force"):
        md.mixed(
            model, TS[:11], prescribed=[md.prescribe(forward_run, "slider.x")], unknown=["F1", "T2"]
        )


def test_unknown_force_cannot_affect_its_motion(forward_run):
    """A vertical force on the slider cannot move it along its guide: named, with a
    suggestion of forces that could."""
    m = paper_mechanism(forces=[*paper_loads(), md.PointForce("Fy", "slider", along=(0, 1))])
    with pytest.raises(md.SolvabilityError) as err:
        md.mixed(
            m,
            TS[:11],
            prescribed=[md.prescribe(forward_run, "slider.x")],
            unknown=["Fy"],
            q0=forward_run.q[0],
        )
    assert "Fy" in str(err.value)
    assert "F1" in str(err.value)  # suggested


def test_prescribed_motion_fixed_by_joints(model, forward_run):
    with pytest.raises(md.SolvabilityError, match=r"slider\.y"):
        md.mixed(
            model,
            TS[:11],
            prescribed=[
                md.CoordinateDriver(
                    "slider.y", "slider", "y", law=float(forward_run["slider.y"][0])
                )
            ],
            unknown=["F1"],
            q0=forward_run.q[0],
        )


def test_partition_with_singular_Phi_qk(model, forward_run):
    """Choosing a coordinate the joints fix (the slider's angle) as independent leaves a
    singular dependent block: a clear error naming it."""
    with pytest.raises(md.SolvabilityError, match=r"slider\.phi"):
        _mixed(model, forward_run, solver="partition", independent=["slider.phi"])


def test_partition_needs_collocated_forces():
    m = slider_crank(0.1, 0.3, 1.0, theta0=0.9).replace(
        drivers=(), forces=[md.Torque("motor", "crank", law=0.0)]
    )
    with pytest.raises(md.SolvabilityError, match="augmented"):
        md.mixed(
            m,
            np.linspace(0, 0.1, 3),
            prescribed=[md.CoordinateDriver("x", "slider", "x", law=md.Ramp(0.35, 0.0))],
            unknown=["motor"],
            solver="partition",
        )
