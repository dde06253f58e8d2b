"""The sparse linear-solver path (issue 7) against the dense one: Jacobian, accelerations,
projections and a generalized-alpha run agree to <= 1e-12 (the forward runs of the other
integrators: ``test_sparse_all.py``); gradients through the sparse solve match central finite
differences; redundant constraints are solved on the sparse path too (the dense path's motion,
the minimum-norm split of the multipliers)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import four_bar, paper_mechanism, parallelogram_with_extra_link, slider_crank
from fixtures import horizontal_chain as chain
from mixdyn.analysis._problem import Problem
from mixdyn.equations import Constraints
from mixdyn.linalg import schur_structure

MODELS = {
    "slider_crank": slider_crank,
    "four_bar": four_bar,
    "paper_mechanism": paper_mechanism,
    "chain40": lambda: chain(40),
}


def _state(model, seed=0):
    rng = np.random.default_rng(seed)
    q = jnp.asarray(np.asarray(model.q0)) + 1e-3 * rng.normal(size=model.nq)
    qd = jnp.asarray(rng.normal(size=model.nq))
    return q, qd


def _rel(a, b):
    return float(jnp.max(jnp.abs(a - b)) / jnp.maximum(jnp.max(jnp.abs(b)), 1e-300))


@eqx.filter_jit
def _evaluate(problem, q, qd, t):
    """What the analyses evaluate at one state on ``problem``'s path, in one compiled
    program (evaluated op by op, the same numbers took a minute)."""
    c = problem.c
    qdd, mu, ratio = problem.accelerations(q, qd, t)
    out = dict(
        phi=c(q, t),
        gamma=c.gamma(q, qd, t),
        phi_t=c.phi_t(q, t),
        qdd=qdd,
        mu=mu,
        ratio=ratio,
        velocities=problem.project_velocities(q, qd, t),
        positions=problem.project_positions(q, t, 1e-14)[0],
    )
    out["jacobian"] = c.jacobian_values(q, t) if c.banded else c.phi_q(q, t)
    return out


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n == "chain40" else n for n in MODELS],
)
def test_jacobian_gamma_and_accelerations_agree(name):
    model = MODELS[name]()
    c = Constraints.of(model)
    cs = c.with_linear_solver("sparse")
    assert cs.linear_solver == md.linalg.BandedSolver()
    q, qd = _state(model)
    t = jnp.asarray(0.3)
    d = _evaluate(Problem(model, c), q, qd, t)
    s = _evaluate(Problem(model, cs), q, qd, t)
    rows, cols = cs.coo()
    P = np.zeros((c.m, c.nq))
    np.add.at(P, (rows, cols), np.asarray(s["jacobian"]))
    # The dense path writes the rotations element by element (fused), the sparse path as a
    # batched product: the same entries to a few units of rounding.
    D = np.asarray(d["jacobian"])
    np.testing.assert_allclose(P, D, rtol=0, atol=4 * np.finfo(float).eps * np.max(np.abs(D)))
    assert _rel(s["phi"], d["phi"]) <= 1e-14
    assert _rel(s["gamma"], d["gamma"]) <= 1e-14
    assert _rel(s["phi_t"], d["phi_t"]) <= 1e-14
    assert _rel(s["qdd"], d["qdd"]) <= 1e-12
    assert _rel(s["mu"], d["mu"]) <= 1e-12
    assert 0 < float(s["ratio"]) <= 1
    assert _rel(s["velocities"], d["velocities"]) <= 1e-12
    assert _rel(s["positions"], d["positions"]) <= 1e-12


@pytest.mark.slow  # default run: test_sparse_all.py::test_generalized_alpha_mixed_agrees
def test_generalized_alpha_sparse_agrees():
    """Generalized-alpha on the sparse path (the modified Newton matrix through the banded
    Cholesky of its Schur complement, G mu by a reverse pass through Phi, no dense Phi_q)
    against the dense path on a 12-link chain (two Cholesky blocks) over 0.2 s at
    dt = 1e-3: coordinates, velocities and reactions agree to 1e-10 of their scale (measured
    4e-14, 6e-14 for the reactions), both with about two Newton iterations per step
    (measured 1.87)."""
    model = chain(12)
    ts = np.linspace(0.0, 0.2, 5)
    kw = dict(method="generalized-alpha", dt=1e-3, rho_inf=0.9)
    d = md.forward(model, ts, linear_solver="dense", **kw)
    s = md.forward(model, ts, linear_solver="sparse", **kw)
    for col in ("b11.x", "b11.y", "b5.phi", "b11.vx", "b8.omega", "J3.Fx", "J11.Fy"):
        scale = max(float(np.max(np.abs(d[col]))), 1.0)
        assert float(np.max(np.abs(s[col] - d[col]))) <= 1e-10 * scale, col
    for r in (d, s):
        assert r.stats["newton_iterations"] <= 2.5 * r.stats["steps"]


def _objective(problem, q, qd):
    qdd, mu, _ = problem.accelerations(q, qd, 0.0)
    return jnp.sum(qdd**2) + jnp.sum(jnp.sin(mu))


def _qdd_squared(problem, q, qd):
    return jnp.sum(problem.accelerations(q, qd, 0.0)[0] ** 2)


@pytest.mark.slow  # default run: test_solver_contract.py, gradients of both paths
def test_gradient_through_sparse_solve():
    model = chain(20)
    ps = Problem(model, Constraints.of(model).with_linear_solver("sparse"))
    q, qd = _state(model, 1)
    f = eqx.filter_jit(_objective)
    g = eqx.filter_jit(jax.grad(_objective, argnums=1))(ps, q, qd)
    rng = np.random.default_rng(2)
    for _ in range(3):
        d = jnp.asarray(rng.normal(size=model.nq))
        h = 1e-6
        fd = (f(ps, q + h * d, qd) - f(ps, q - h * d, qd)) / (2 * h)
        assert abs(float(g @ d) - float(fd)) <= 1e-6 * max(abs(float(fd)), 1.0)
    # the same gradient as the dense path
    pd = Problem(model, Constraints.of(model))
    grad = eqx.filter_jit(jax.grad(_qdd_squared, argnums=1))
    assert _rel(grad(ps, q, qd), grad(pd, q, qd)) <= 1e-10


def test_schur_solve_vmap_and_jacfwd():
    rng = np.random.default_rng(3)
    rows = np.repeat(np.arange(30), 6)
    cols = (np.arange(30)[:, None] // 2 * 3 + np.arange(6)[None, :]).ravel()
    st = schur_structure(30, 51, rows, cols)
    v = jnp.asarray(rng.normal(size=rows.size))
    Minv = jnp.asarray(rng.uniform(0.5, 2.0, 51))
    b = jnp.asarray(rng.normal(size=(4, 30)))
    C = np.zeros((30, 51))
    np.add.at(C, (rows, cols), np.asarray(v))
    S = C @ np.diag(Minv) @ C.T
    x = jax.jit(jax.vmap(lambda b: st.solve(v, Minv, b)[0]))(b)
    assert np.allclose(x, np.linalg.solve(S, b.T).T, rtol=1e-10, atol=1e-12)
    solve = jax.jit(lambda v: st.solve(v, Minv, b[0])[0])
    J = jax.jit(jax.jacfwd(solve))(v)
    h = 1e-6
    e = jnp.zeros_like(v).at[7].set(h)
    fd = (solve(v + e) - solve(v - e)) / (2 * h)
    assert np.allclose(J[:, 7], fd, rtol=1e-6, atol=1e-8)


@pytest.mark.slow  # default run: the rank-deficient operator contract (test_solver_contract.py)
def test_redundant_constraints_on_the_sparse_path():
    """Twelve joint equations of rank 11: the sparse path's regularized Schur complement gives
    the closed-form motion (the coupler translates on a circle), the dense path's constraint
    forces, and names the redundant equation."""
    model = parallelogram_with_extra_link()
    ts = np.linspace(0.0, 0.5, 6)
    s = md.forward(model, ts, linear_solver="sparse")
    d = md.forward(model, ts, linear_solver="dense")
    assert (s.stats["linear_solver"], d.stats["linear_solver"]) == ("sparse", "dense")
    assert len(s.stats["redundant_equations"]) == 1
    assert s.stats["redundant_equations"] == d.stats["redundant_equations"]
    th = np.pi / 6 + ts  # the fixture's motor: theta0 + omega t, omega = 1 rad/s
    cx, cy = s["coupler.x"], s["coupler.y"]
    assert np.max(np.abs(cx - (0.25 + 0.3 * np.cos(th)))) <= 1e-12
    assert np.max(np.abs(cy - 0.3 * np.sin(th))) <= 1e-12
    for a, b in ((s.q, d.q), (s.qd, d.qd), (s.qdd, d.qdd)):
        assert _rel(jnp.asarray(a), jnp.asarray(b)) <= 1e-12
    # The split of the reactions among the redundant equations is a convention (minimum
    # norm); the sparse solve reaches it to ~1e-8 relative (Constraints.schur_solver).
    for k in [c for c in d.table().columns if c.startswith("lambda.")]:
        assert np.max(np.abs(s[k] - d[k])) <= 1e-8 * max(np.max(np.abs(d[k])), 1.0), k


def test_regularized_schur_solve_is_the_minimum_norm_solution():
    """``S = C M^-1 C^T`` singular (one redundant row), ``b`` consistent: the sparse solve
    against the pseudo-inverse solution (NumPy SVD), and ``C^T y`` to rounding."""
    model = parallelogram_with_extra_link()
    c0 = Constraints.of(model)  # 12 joint equations and the motor, of rank 12
    c = c0.with_rank(c0.m - 1).with_linear_solver("sparse")
    q, t = model.q0, 0.0
    C = np.asarray(eqx.filter_jit(c.phi_q)(q, t))
    Minv = 1.0 / np.asarray(model.mass_diagonal)
    S = C @ (Minv[:, None] * C.T)
    assert np.linalg.matrix_rank(S) == c.m - 1
    b = S @ np.random.default_rng(1).normal(size=c.m)

    @eqx.filter_jit
    def schur_solve(c, q, t, Minv, b):
        return c.schur_solve(c.jacobian_values(q, t), Minv, b)

    y, ratio = schur_solve(c, q, t, jnp.asarray(Minv), jnp.asarray(b))
    y_ref = np.linalg.pinv(S, rcond=1e-10) @ b
    assert np.max(np.abs(C.T @ (np.asarray(y) - y_ref))) <= 1e-12 * np.max(np.abs(C.T @ y_ref))
    assert np.max(np.abs(np.asarray(y) - y_ref)) <= 1e-8 * np.max(np.abs(y_ref))
    assert 1e-6 < float(ratio) <= 1.0  # the redundancy is not a singular position


def test_auto_choice_and_bad_name():
    assert Constraints.of(slider_crank()).with_linear_solver("auto").linear_solver.name == "dense"
    assert Constraints.of(chain(64)).with_linear_solver("auto").linear_solver.name == "sparse"
    # the measured threshold: 32 rows (a 16-link chain) sparse, 30 dense
    assert Constraints.of(chain(16)).with_linear_solver("auto").linear_solver.name == "sparse"
    assert Constraints.of(chain(15)).with_linear_solver("auto").linear_solver.name == "dense"
    with pytest.raises(md.errors.ModelError, match="linear_solver"):
        Constraints.of(slider_crank()).with_linear_solver("klu")


def test_the_linear_solver_is_an_object_resolved_once():
    """A name and its object are one choice; the set carries the resolved path, never
    ``AutoSolver``; the automatic choice's thresholds are the object's own; a run's result is
    the same whichever spelling chose its path (bit for bit)."""
    c = Constraints.of(chain(16))
    assert c.with_linear_solver(md.AutoSolver()).linear_solver == md.BandedSolver()
    assert c.with_linear_solver(md.AutoSolver(min_rows=64)).linear_solver == md.DenseSolver()
    assert c.with_linear_solver(md.AutoSolver(max_block=1)).linear_solver == md.DenseSolver()
    assert c.with_linear_solver("sparse").banded and not c.with_linear_solver("dense").banded
    assert Constraints(c.joints, c.drivers, c.nq, linear_solver="auto").linear_solver.name == (
        "sparse"
    )
    model = slider_crank()
    t = np.linspace(0.0, 0.3, 4)
    for name, obj in (("dense", md.DenseSolver()), ("sparse", md.BandedSolver())):
        a = md.kinematic(model, t, linear_solver=name)
        b = md.kinematic(model, t, linear_solver=obj)
        assert a.stats["linear_solver"] == b.stats["linear_solver"] == name
        np.testing.assert_array_equal(np.asarray(a.q), np.asarray(b.q))
    with pytest.raises(md.errors.ModelError, match="linear_solver"):
        md.kinematic(model, t, linear_solver=object())


def test_singular_schur_reports_zero_ratio():
    # two identical rows: S is singular, the pivot ratio says so (0 or NaN results)
    rows = np.array([0, 0, 1, 1])
    cols = np.array([0, 1, 0, 1])
    st = schur_structure(2, 2, rows, cols)
    _, ratio = st.solve(jnp.ones(4), jnp.ones(2), jnp.ones(2))
    assert float(ratio) < 1e-12
