"""One linear-solver layer for every analysis (issue 7): with ``linear_solver="sparse"`` the
equations of every fixture and example the sparse path applies to equal the dense path's
(``Phi``, ``Phi_q``, ``Phi_t``, ``gamma``, the products with ``Phi_q``, the Schur solve and the
joint reactions, at random states), and each analysis path (kinematic, inverse, forward with
each integrator, collocated and non-collocated mixed) agrees with ``linear_solver="dense"`` to
<= 1e-12 (relative to each quantity's scale) on one fixture; a dead point is still detected on
the sparse path; the problems the sparse path cannot solve are refused with clear errors.

(The analyses run the same code on every model once the equations are evaluated: the
equations are compared fixture by fixture, the time integrations once per path.)"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import (
    EXAMPLES,
    andrews_mechanism,
    double_four_bar,
    four_bar,
    paper_loads,
    paper_mechanism,
    parallelogram_with_extra_link,
    pendulum,
    pendulum_chain,
    slider_crank,
    spring_slider,
)
from mixdyn.analysis._problem import Problem
from mixdyn.analysis._reactions import joint_reactions
from mixdyn.equations import Constraints
from mixdyn.model._element import Resolver
from mixdyn.runs import execute

TOL = 1e-12


def _coordinate(name, body, coord, value, rate):
    return md.CoordinateDriver(name, body, coord, law=md.Ramp(value, rate))


def _paper_driven():
    drivers = [
        _coordinate("m_crank", "crank", "phi", 0.0, 0.5),
        _coordinate("m_coupler", "coupler", "phi", 0.0, -0.3),
    ]
    return paper_mechanism(drivers=drivers), ("crank.phi", "coupler.phi")


def _chain_driven(n=6):
    model = pendulum_chain(n)
    drivers = [
        _coordinate(f"d{k}", f"link{k}", "phi", 0.5 - math.pi / 2, 0.2 * (k + 1)) for k in range(n)
    ]
    return model.replace(drivers=drivers), ()


def _double_four_bar_driven():
    model, _ = double_four_bar(2)
    return model.replace(drivers=[_coordinate("motor", "crank0", "phi", math.pi / 2, -1.0)]), ()


def _andrews_driven():
    model = andrews_mechanism()
    beta = float(model.q0[2])
    return model.replace(drivers=[_coordinate("drive", "crank", "phi", beta, 10.0)]), ()


def _example(name):
    model = mio.load(EXAMPLES / f"{name}.yaml")
    spec = mio.read(EXAMPLES / f"{name}.yaml")
    hold = tuple(spec.assembly.hold or ()) if spec.assembly is not None else ()
    return model, hold


#: Fully driven models (kinematic analysis, inverse dynamics): builder -> (model, hold).
DRIVEN = {
    "slider_crank": lambda: (slider_crank(), ()),
    "four_bar": lambda: (four_bar(), ()),
    "paper_mechanism": _paper_driven,
    "pendulum": lambda: (
        pendulum().replace(drivers=[md.CoordinateDriver("swing", "bob", "phi", law=0.2)]),
        (),
    ),
    "spring_slider": lambda: (
        spring_slider().replace(drivers=[_coordinate("push", "slider", "x", 0.6, 0.1)]),
        (),
    ),
    "pendulum_chain": _chain_driven,
    "double_four_bar": _double_four_bar_driven,
    "andrews_mechanism": _andrews_driven,
    "example_four_bar": lambda: _example("four_bar"),
    "example_slider_crank": lambda: _example("slider_crank"),
}


def _loads():
    return paper_loads()


#: Models under their forces (forward dynamics): builder -> (model, hold, qd0).
FREE = {
    "slider_crank": lambda: (slider_crank(drivers=()), (), None),
    "paper_mechanism": lambda: (
        paper_mechanism(forces=_loads()),
        ("crank.phi", "coupler.phi"),
        None,
    ),
    "pendulum": lambda: (pendulum(theta0=0.4), (), None),
    "spring_slider": lambda: (spring_slider(), (), None),
    "pendulum_chain": lambda: (pendulum_chain(6), (), None),
    "double_four_bar": lambda: (*double_four_bar(2)[:1], (), double_four_bar(2)[1]),
    "andrews_mechanism": lambda: (andrews_mechanism(), (), None),
    "example_pendulum": lambda: (*_example("pendulum"), None),
    "example_antonya": lambda: (*_example("antonya"), None),
}


def _agree(a, b, what, tol=TOL, scale=None):
    """``a`` and ``b`` (arrays of one kind of quantity) agree to ``tol`` relative to the
    largest magnitude of ``b`` (or to ``scale``)."""
    a, b = np.asarray(a), np.asarray(b)
    if scale is None:
        scale = float(np.max(np.abs(b), initial=0.0))
    scale = max(scale, 1e-300)
    err = float(np.max(np.abs(a - b), initial=0.0)) / scale
    assert err <= tol, f"{what}: relative difference {err:.2e}"


def _agree_columns(s, d, kinds=("force", "torque")):
    """Every extra column of the results, grouped by kind (the reactions' forces against the
    largest force, and so on)."""
    groups: dict = {}
    for name, kind in d.kinds.items():
        groups.setdefault(kind, []).append(name)
    for kind in kinds:
        names = groups.get(kind, [])
        if names:
            _agree(np.stack([s[n] for n in names]), np.stack([d[n] for n in names]), kind)


#: The fixtures whose equations are compared: every model of ``DRIVEN`` (the joints of the
#: ``FREE`` model of the same name with drivers added) and the ``FREE`` examples.
EQUATIONS = {
    **{name: (lambda name=name: DRIVEN[name]()[0]) for name in DRIVEN},
    **{name: (lambda name=name: FREE[name]()[0]) for name in FREE if name.startswith("example_")},
}


@eqx.filter_jit
def _equations(c, Minv, q, qd, t, x, y, b, lam):
    """Everything the analyses evaluate of the constraints on ``c``'s path, at one state:
    through the public methods of :class:`Constraints` (and the joint reactions); on the
    sparse path also the products with ``Phi_q`` and the Schur solve from its values."""
    out = dict(
        full=c.full(q, t),
        phi=c(q, t),
        phi_q=c.phi_q(q, t),
        phi_t=c.phi_t(q, t),
        gamma=c.gamma(q, qd, t),
        reactions=joint_reactions(c, q, t, lam),
    )
    if c.banded:
        v = c.jacobian_values(q, t)
        out["matvec"], out["rmatvec"] = c.matvec(v, x), c.rmatvec(v, y)
        out["schur"], out["ratio"] = c.schur_solve(v, Minv, b)
    return out


@pytest.mark.parametrize("name", list(EQUATIONS))
def test_sparse_equations_equal_the_dense_ones(name):
    """At three random states near the fixture's start: ``Phi`` (all rows and the rows kept;
    relative to the coordinates' size), ``Phi_t`` and ``gamma`` of the sparse path (per element,
    vectorized per kind) equal the dense path's to 1e-14; ``Phi_q`` scattered from the
    per-element Jacobians equals ``jax.jacfwd`` of the dense ``Phi`` to 1e-15; ``Phi_q x`` and
    ``Phi_q^T y`` from the sparse values equal the dense products; the banded Cholesky solve of
    ``Phi_q M^-1 Phi_q^T y = b`` equals NumPy's dense solve to 1e-10; the joint reactions from
    the multipliers equal the dense path's to 1e-12. (These are all the analyses take from the
    constraints: what each analysis does with them is compared once per path below.)"""
    model = EQUATIONS[name]()
    cd = Constraints.of(model).with_linear_solver("dense")
    cs = cd.with_linear_solver("sparse")
    assert (cd.linear_solver.name, cs.linear_solver.name) == ("dense", "sparse")
    Minv = 1.0 / np.asarray(model.mass_diagonal)
    rng = np.random.default_rng(sum(map(ord, name)))
    for _ in range(3):
        state = (
            np.asarray(model.q0) + 1e-2 * rng.normal(size=model.nq),  # q
            rng.normal(size=model.nq),  # qd
            rng.uniform(0.0, 1.0),  # t
            rng.normal(size=model.nq),  # x
            rng.normal(size=cd.m),  # y
            rng.normal(size=cd.m),  # b
            rng.normal(size=cd.m),  # multipliers
        )
        args = [jnp.asarray(a) for a in (Minv, *state)]
        d, s = _equations(cd, *args), _equations(cs, *args)
        # Phi near an assembled state is a small difference of terms as large as the
        # mechanism (the rotations written element by element on the dense path, as a batched
        # product on the sparse one): its rounding is relative to the coordinates' size.
        size = float(np.max(np.abs(state[0])))
        for key in ("full", "phi"):
            _agree(s[key], d[key], key, 1e-14, scale=max(size, float(np.max(np.abs(d[key])))))
        for key in ("phi_t", "gamma"):
            _agree(s[key], d[key], key, 1e-14)
        C = np.asarray(d["phi_q"])
        _agree(s["phi_q"], C, "Phi_q", 1e-15)
        x, y, b = state[3], state[4], state[5]
        _agree(s["matvec"], C @ x, "Phi_q x", 1e-14)
        _agree(s["rmatvec"], C.T @ y, "Phi_q^T y", 1e-14)
        S = C @ (Minv[:, None] * C.T)
        _agree(s["schur"], np.linalg.solve(S, b), "Schur solve", 1e-10)
        assert 0.0 < float(s["ratio"]) <= 1.0
        _agree(s["reactions"], d["reactions"], "joint reactions")


def test_elements_with_laws_of_different_shapes_group_apart():
    """Two coordinate drivers with polynomial laws of different degrees cannot share one
    vectorized evaluation: the sparse form still works."""
    model, _ = _chain_driven(3)
    drivers = [
        md.CoordinateDriver("d0", "link0", "phi", law=md.Polynomial([-1.0, 0.1, 0.2])),
        _coordinate("d1", "link1", "phi", -1.0, 0.1),
        md.CoordinateDriver("d2", "link2", "phi", law=-1.0),
    ]
    c = Constraints.of(model.replace(drivers=drivers)).with_linear_solver("sparse")
    q = jnp.asarray(np.asarray(model.q0))
    J = jax.jacfwd(c, argnums=0)(q, 0.5)
    assert float(jnp.max(jnp.abs(c.phi_q(q, 0.5) - J))) <= 1e-15


def test_rank_analysis_fast_path_agrees_with_the_qr(monkeypatch):
    """The O(m) certificate of independent rows gives the report the rank-revealing QR gives
    (and declines where a row is redundant)."""
    from mixdyn.analysis import _structure

    models = [DRIVEN[name]()[0] for name in DRIVEN]
    models.append(parallelogram_with_extra_link())
    models.append(slider_crank(drivers=[md.CoordinateDriver("lift", "slider", "y", law=0.0)]))
    fast = [_structure.analyse(m) for m in models]
    assert _structure._full_row_rank(np.eye(3)[:2])
    assert not _structure._full_row_rank(np.ones((2, 3)))
    monkeypatch.setattr(_structure, "_full_row_rank", lambda A: False)
    for m, f in zip(models, fast, strict=True):
        assert _structure.analyse(m) == f, m.name


# ------------------------------------------------------------------ kinematics
@pytest.mark.slow  # long: run by CI's slow set
def test_inverse_agrees():
    """Inverse dynamics (and the kinematic analysis under it: assembly with held coordinates,
    Newton's positions, velocities, accelerations) on the paper's mechanism driven by two
    motors: positions, velocities, accelerations, driver efforts, reactions and multipliers."""
    model, hold = DRIVEN["paper_mechanism"]()
    ts = np.linspace(0.0, 0.2, 4)
    d = md.inverse(model, ts, hold=hold, linear_solver="dense")
    s = md.inverse(model, ts, hold=hold, linear_solver="sparse")
    assert d.stats["linear_solver"] == "dense" and s.stats["linear_solver"] == "sparse"
    _agree(s.q, d.q, "positions")
    _agree(s.qd, d.qd, "velocities")
    _agree(s.qdd, d.qdd, "accelerations")
    _agree_columns(s, d)  # driver efforts, reactions, multipliers


@pytest.mark.slow  # default run: test_inverse_agrees (the kinematic analysis under it)
def test_kinematic_sparse_under_auto():
    model, _ = _chain_driven(24)  # 48 joint rows + 24 drivers >= 64 rows
    ts = np.linspace(0.0, 0.1, 3)
    a = md.kinematic(model, ts)
    d = md.kinematic(model, ts, linear_solver="dense")
    assert a.stats["linear_solver"] == "sparse"
    _agree(a.q, d.q, "positions")
    _agree(a.qd, d.qd, "velocities")
    _agree(a.qdd, d.qdd, "accelerations")


@pytest.mark.parametrize("name", ["paper_mechanism", "double_four_bar", "andrews_mechanism"])
def test_assembly_agrees(name):
    model, hold = DRIVEN[name]()
    rough = np.asarray(model.q0) + 1e-2
    d = md.assemble(model, rough, hold=hold, linear_solver="dense")
    s = md.assemble(model, rough, hold=hold, linear_solver="sparse")
    _agree(s.q, d.q, "assembled positions")


@pytest.mark.slow  # long: run by CI's slow set
def test_assembly_with_redundant_equations_falls_back():
    """A redundant joint equation makes ``J J^T`` singular once the damping fades: the sparse
    assembly takes the dense step there and closes the joints all the same; the kinematic
    analysis then runs on the sparse path (regularized Schur complement) as on the dense one."""
    model = parallelogram_with_extra_link()
    rough = np.asarray(model.q0) + 1e-3
    s = md.assemble(model, rough, linear_solver="sparse")
    d = md.assemble(model, rough, linear_solver="dense")
    assert s.residual <= 1e-12
    _agree(s.q, d.q, "assembled positions", 1e-9)
    ts = np.linspace(0.0, 0.1, 3)
    ks = md.kinematic(model, ts, linear_solver="sparse")
    kd = md.kinematic(model, ts, linear_solver="dense")
    assert ks.stats["linear_solver"] == "sparse"
    for a, b, what in ((ks.q, kd.q, "q"), (ks.qd, kd.qd, "qd"), (ks.qdd, kd.qdd, "qdd")):
        _agree(a, b, f"kinematic {what} with a redundant equation")


# ------------------------------------------------------------------ dead points
R, L, TH0 = 0.1, 0.3, 0.5
X0 = R * np.cos(TH0) + np.sqrt(L**2 - (R * np.sin(TH0)) ** 2)


@pytest.mark.slow  # long: run by CI's slow set
def test_dead_point_detected_on_the_sparse_path():
    """As in test_errors_kinematic: the slider driven to its dead point at t = 1 (an output
    time) and back; the sparse path reports the singularity there, naming the driver."""
    k = (R + L - X0) / 1.0
    law = md.Polynomial([R + L - k, 2 * k, -k])
    drivers = [md.CoordinateDriver("push", "slider", "x", law=law)]
    model = slider_crank(R, L, theta0=TH0)
    ts = np.linspace(0.0, 2.0, 101)
    with pytest.raises(md.SingularityError) as err:
        md.kinematic(model, ts, drivers=drivers, linear_solver="sparse")
    assert err.value.time == pytest.approx(1.0, abs=0.02)
    assert "push" in err.value.elements
    # output times that miss it: regular, and as on the dense path
    ts = np.linspace(0.0, 2.0, 40)
    s = md.kinematic(model, ts, drivers=drivers, linear_solver="sparse")
    d = md.kinematic(model, ts, drivers=drivers, linear_solver="dense")
    _agree(s.q, d.q, "positions", 1e-9)


# ------------------------------------------------------------------ forward dynamics
@pytest.mark.slow  # default run: the projection agreement below and the operator contract
def test_forward_baumgarte_agrees():
    """RK4 + Baumgarte on the paper's mechanism under its loads (two torques and a point force;
    the start assembled with two coordinates held): positions, velocities, accelerations,
    reactions, powers and energies."""
    model, hold, qd0 = FREE["paper_mechanism"]()
    ts = np.linspace(0.0, 0.004, 3)
    kw = dict(hold=hold, qd0=qd0, method="baumgarte", dt=1e-3)
    d = md.forward(model, ts, linear_solver="dense", **kw)
    s = md.forward(model, ts, linear_solver="sparse", **kw)
    assert d.stats["linear_solver"] == "dense" and s.stats["linear_solver"] == "sparse"
    _agree(s.q, d.q, "positions")
    _agree(s.qd, d.qd, "velocities")
    _agree(s.qdd, d.qdd, "accelerations")
    _agree_columns(s, d, ("force", "torque", "power", "energy"))


@pytest.mark.slow  # default run: JacobianOperator.partition in test_solver_contract.py
def test_partitioning_agrees():
    """Coordinate partitioning: on the sparse path the dependent coordinates are solved by the
    minimum-norm solve weighted to the dependent block (one banded Cholesky pattern whatever
    the partition); the same run as the dense LU of ``Phi_qD`` (measured 5e-14 m on a
    30-link chain, 3x faster), here on the slider-crank."""
    model, hold, qd0 = FREE["slider_crank"]()
    ts = np.linspace(0.0, 0.05, 3)
    kw = dict(hold=hold, qd0=qd0, method="partitioning", rtol=1e-10, atol=1e-10)
    d = md.forward(model, ts, linear_solver="dense", **kw)
    s = md.forward(model, ts, linear_solver="sparse", **kw)
    assert s.stats["linear_solver"] == "sparse"
    _agree(s.q, d.q, "positions", 1e-10)
    _agree(s.qd, d.qd, "velocities", 1e-10)


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_forward_projection_chain_agrees():
    """Adaptive Tsit5 with projection (the default) on an 8-link pendulum chain: positions,
    velocities, accelerations and reactions."""
    model = pendulum_chain(8)
    ts = np.linspace(0.0, 0.05, 3)
    kw = dict(rtol=1e-10, atol=1e-12)
    d = md.forward(model, ts, linear_solver="dense", **kw)
    s = md.forward(model, ts, linear_solver="sparse", **kw)
    assert s.stats["linear_solver"] == "sparse"
    _agree(s.q, d.q, "positions")
    _agree(s.qd, d.qd, "velocities")
    _agree(s.qdd, d.qdd, "accelerations")
    _agree_columns(s, d)


# ------------------------------------------------------------------ mixed dynamics
@pytest.fixture(scope="module")
def paper_forward():
    model = paper_mechanism(forces=_loads())
    ts = np.linspace(0.0, 0.2, 6)
    fw = md.forward(model, ts, hold=("crank.phi", "coupler.phi"), rtol=1e-12, atol=1e-12)
    return model, ts, fw


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_collocated_mixed_round_trip_agrees(paper_forward):
    """The paper's round trip (F1 unknown, the slider's x prescribed: a force along the
    coordinate it prescribes, so the system is symmetric) on the sparse path."""
    model, ts, fw = paper_forward
    kw = dict(
        prescribed=[md.prescribe(fw, "slider.x")],
        unknown=["F1"],
        q0=fw.q[0],
        qd0=fw.qd[0],
        rtol=1e-12,
        atol=1e-12,
    )
    d = md.mixed(model, ts, linear_solver="dense", **kw)
    s = md.mixed(model, ts, linear_solver="sparse", **kw)
    assert s.stats["collocated"] and s.stats["linear_solver"] == "sparse"
    assert d.stats["linear_solver"] == "dense"
    _agree(s.q, d.q, "positions")
    _agree(s["F1"], d["F1"], "F1")
    _agree_columns(s, d)
    np.testing.assert_allclose(s["F1"], 10 * np.sin(np.pi * ts / 2), atol=1e-6)


def _crank_torque_model():
    return slider_crank(0.1, 0.3, 1.0, theta0=0.9).replace(
        drivers=(), forces=[md.Torque("motor", "crank", law=0.0)]
    )


@pytest.mark.slow
def test_collocated_torque_with_either_sign():
    """A torque on the crank with the crank angle prescribed, ``B = Psi_q^T``, or the same
    motion prescribed as the ground's angle relative to the crank, ``B = -Psi_q^T``: the same
    torque either way, dense and sparse."""
    model = _crank_torque_model()
    ts = np.linspace(0.0, 0.1, 3)
    f = [0.9, 1.0, 0.5]
    motions = {
        "coordinate": md.CoordinateDriver("angle", "crank", "phi", law=md.Polynomial(f)),
        "relative": md.RelativeAngleDriver(
            "angle", "crank", "ground", law=md.Polynomial([-a for a in f])
        ),
    }
    runs = {}
    for how, motion in motions.items():
        for ls in ("dense", "sparse"):
            runs[how, ls] = md.mixed(
                model,
                ts,
                prescribed=[motion],
                unknown=["motor"],
                linear_solver=ls,
                rtol=1e-12,
                atol=1e-12,
            )
            assert runs[how, ls].stats["linear_solver"] == ls
    ref = runs["coordinate", "dense"]
    for key, res in runs.items():
        _agree(res["motor"], ref["motor"], f"torque {key}")
        _agree(res.q, ref.q, f"positions {key}")
    _agree_columns(runs["relative", "sparse"], runs["relative", "dense"])


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_non_collocated_mixed_on_the_sparse_path():
    """Slider prescribed, crank torque unknown: ``G != C^T``. The sparse path solves it by a
    rank-1 Woodbury update of the symmetric Schur complement: the torque, motion and reactions
    agree with the dense LU of ``C M^-1 G``; 'auto' takes the sparse path when asked for it by
    size; the partition solver asked on the sparse path is refused."""
    model = _crank_torque_model()
    ts = np.linspace(0.0, 0.1, 3)
    kw = dict(
        prescribed=[md.CoordinateDriver("x", "slider", "x", law=md.Ramp(0.37, -0.1))],
        unknown=["motor"],
        rtol=1e-12,
        atol=1e-12,
    )
    s = md.mixed(model, ts, linear_solver="sparse", **kw)
    d = md.mixed(model, ts, linear_solver="dense", **kw)
    assert s.stats["linear_solver"] == "sparse" and not s.stats["collocated"]
    assert d.stats["linear_solver"] == "dense"
    _agree(s["motor"], d["motor"], "unknown torque")
    _agree(s.q, d.q, "positions")
    _agree(s.qdd, d.qdd, "accelerations")
    _agree_columns(s, d)
    with pytest.raises(md.ModelError, match="partition"):
        md.mixed(model, ts, linear_solver="sparse", solver="partition", **kw)


def _chain_with_torques(n):
    model = pendulum_chain(n)
    return model.replace(forces=[md.Torque("T5", "link5"), md.Torque("T17", "link17")])


@eqx.filter_jit
def _acc(problem, q, qd, t):
    return problem.accelerations(q, qd, t)


@pytest.mark.slow  # default run: the mixed agreements above (the same Woodbury solve)
def test_generalized_alpha_mixed_agrees():
    """Generalized-alpha on a non-collocated mixed problem: on the sparse path its iteration
    matrix is the Woodbury-updated Schur complement; the same run as the dense LU (to the
    Newton tolerance, 1e-10 of the force scale)."""
    model = _crank_torque_model()
    ts = np.linspace(0.0, 0.05, 3)
    kw = dict(
        prescribed=[md.CoordinateDriver("x", "slider", "x", law=md.Ramp(0.37, -0.1))],
        unknown=["motor"],
        method="generalized-alpha",
        dt=1e-3,
    )
    s = md.mixed(model, ts, linear_solver="sparse", **kw)
    d = md.mixed(model, ts, linear_solver="dense", **kw)
    assert s.stats["linear_solver"] == "sparse"
    _agree(s["motor"], d["motor"], "unknown torque", 1e-9)
    _agree(s.q, d.q, "positions", 1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_woodbury_accelerations_match_the_dense_solve():
    """Unit check of the rank-p update at random states: a chain of 30 links (sparse path under
    'auto') with two unknown torques acting on other bodies than those whose angles are
    prescribed (``G != C^T``): accelerations and multipliers against the dense solve."""
    model = _chain_with_torques(30)
    drivers = (
        md.CoordinateDriver("a3", "link3", "phi", law=md.Polynomial([0.1, 0.2])),
        md.CoordinateDriver("a20", "link20", "phi", law=md.Polynomial([-0.2, 0.1])),
    )
    r = Resolver(model.ground, model.bodies)
    drivers = tuple(d.bind(r) for d in drivers)
    c = Constraints(model.joints, drivers, model.nq)
    unknown = ("T5", "T17")
    pd = Problem(model, c.with_linear_solver("dense"), unknown)
    ps = Problem(model, c.with_linear_solver("sparse"), unknown)
    assert ps.c.banded and ps.solver == "augmented" and not ps.collocated
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = jnp.asarray(np.asarray(model.q0) + 1e-2 * rng.normal(size=model.nq))
        qd = jnp.asarray(rng.normal(size=model.nq))
        t = jnp.asarray(0.3)
        qdd_s, mu_s, _ = _acc(ps, q, qd, t)
        qdd_d, mu_d, _ = _acc(pd, q, qd, t)
        _agree(qdd_s, qdd_d, "accelerations")
        _agree(mu_s, mu_d, "multipliers and unknown torques")


# ------------------------------------------------------------------ model files
def test_model_file_run_takes_the_linear_solver():
    text = (EXAMPLES / "four_bar.yaml").read_text()
    text = text.replace(
        "kind: kinematic\n", "kind: kinematic\n    linear_solver: sparse\n"
    ).replace("time: {span: [0, 2*pi], step: 0.05}", "time: {span: [0, 0.2], n: 3}")
    spec = mio.reads(text)
    res = execute(spec, ["kinematics"])["kinematics"]
    assert res.stats["linear_solver"] == "sparse"
    # the default normal form does not change: 'auto' is the default
    assert "linear_solver" not in mio.dumps(mio.read(EXAMPLES / "four_bar.yaml"))


@pytest.mark.parametrize("linear_solver", ["dense", "sparse", "auto"])
def test_free_body_without_constraints(linear_solver):
    """No constraint equation at all: nothing to solve on either path (it used to fail on an
    empty reduction)."""
    model = md.Model([md.Body("b", 1.0, 0.1)], gravity=(0.0, -9.81), units=md.SI)
    ts = np.linspace(0.0, 0.1, 3)
    res = md.forward(model, ts, linear_solver=linear_solver, method="baumgarte", dt=0.01)
    np.testing.assert_allclose(res["b.y"], -9.81 * ts**2 / 2, atol=1e-12)
