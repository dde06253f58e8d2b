"""The straight-line linear-solver path (:class:`mixdyn.UnrolledSolver`) against NumPy/SciPy.

Its Cholesky and LU factorizations, written out at trace time, solve random well-conditioned
symmetric positive definite and general systems as ``numpy.linalg.solve`` does (to rounding),
with SciPy's LU factors and LAPACK's pivots; the constrained-dynamics (KKT) solve of the
operator equals the solve of the whole KKT matrix by NumPy, for forward and mixed problems;
the automatic choice takes the path for a few rows only; and a pendulum chain's accelerations
and runs equal the dense (LAPACK) path's to 1e-12.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sla

import mixdyn as md
from fixtures import pendulum_chain
from mixdyn.analysis._problem import Problem
from mixdyn.equations import Constraints
from mixdyn.equations._jacobian import DenseJacobian
from mixdyn.linalg import AutoSolver, DenseSolver, UnrolledSolver, as_linear_solver
from mixdyn.linalg._dense import SINGULAR_RATIO
from mixdyn.linalg._unrolled import cholesky_unrolled, lu_factor_unrolled, lu_unrolled

#: Sizes up to the automatic choice's; one by default, the others in CI's slow set.
SIZES = [pytest.param(m, marks=pytest.mark.slow) for m in (1, 2, 3, 6)] + [5]


@eqx.filter_jit
def _solve(factor, A, B):
    """``(X, x, ratio)``: ``factor(A)`` solving ``B`` (m, k) and its first column (m,)."""
    f = factor(A)
    return f.solve(B), f.solve(B[:, 0]), f.ratio


@pytest.mark.parametrize("m", SIZES)
def test_cholesky_solves_spd_systems_like_numpy(m):
    rng = np.random.default_rng(m)
    G = rng.normal(size=(m, m))
    S = G @ G.T + m * np.eye(m)
    B = rng.normal(size=(m, 3))
    X, x, ratio = _solve(cholesky_unrolled, jnp.asarray(S), jnp.asarray(B))
    np.testing.assert_allclose(X, np.linalg.solve(S, B), rtol=1e-12)
    np.testing.assert_allclose(x, np.linalg.solve(S, B[:, 0]), rtol=1e-12)
    d = np.diag(np.linalg.cholesky(S)) ** 2
    np.testing.assert_allclose(float(ratio), d.min() / d.max(), rtol=1e-12)


@pytest.mark.parametrize("m", SIZES)
def test_lu_has_lapack_pivots_and_solves_like_numpy(m):
    rng = np.random.default_rng(10 + m)
    A = rng.normal(size=(m, m)) + 0.5 * np.eye(m)  # pivoting needed: no dominant diagonal
    B = rng.normal(size=(m, 2))
    lu, perm = jax.jit(lu_unrolled)(jnp.asarray(A))
    lu_ref, piv = sla.lu_factor(A)
    perm_ref = np.arange(m)
    for k, p in enumerate(piv):  # LAPACK's row exchanges as a permutation
        perm_ref[[k, p]] = perm_ref[[p, k]]
    np.testing.assert_array_equal(np.asarray(perm), perm_ref)
    np.testing.assert_allclose(lu, lu_ref, rtol=1e-12, atol=1e-14)
    X, _, ratio = _solve(lu_factor_unrolled, jnp.asarray(A), jnp.asarray(B))
    np.testing.assert_allclose(X, np.linalg.solve(A, B), rtol=1e-11)
    d = np.abs(np.diag(lu_ref))
    np.testing.assert_allclose(float(ratio), d.min() / d.max(), rtol=1e-12)


@pytest.mark.parametrize(
    "mixed", [False, pytest.param(True, marks=pytest.mark.slow)], ids=["forward", "mixed"]
)
def test_kkt_equals_numpy_solve_of_the_whole_matrix(mixed):
    rng = np.random.default_rng(3)
    m, n, p = 5, 9, (1 if mixed else 0)
    C = rng.normal(size=(m, n))
    W = rng.uniform(0.5, 2.0, size=n)
    B = rng.normal(size=(n, p)) if mixed else None
    G = C.T if B is None else np.concatenate([C[: m - p].T, -B], axis=1)
    K = np.block([[np.diag(1.0 / W), G], [C, np.zeros((m, m))]])
    r1, r2 = rng.normal(size=n), rng.normal(size=m)
    ref = np.linalg.solve(K, np.concatenate([r1, r2]))

    @jax.jit
    def kkt(C, W, B, r1, r2):
        solve, ratio = DenseJacobian(C, path=UnrolledSolver()).kkt(W, B)
        return *solve(r1, r2), ratio

    x, mu, ratio = kkt(*(None if a is None else jnp.asarray(a) for a in (C, W, B, r1, r2)))
    np.testing.assert_allclose(np.concatenate([x, mu]), ref, rtol=1e-10, atol=1e-12)
    assert float(ratio) > SINGULAR_RATIO


def test_singular_schur_complement_takes_the_guard():
    """Two equal rows: the Cholesky pivot vanishes (or goes negative: NaN), the ratio says
    so and the guard's damped solve gives the dense path's finite answer."""
    rng = np.random.default_rng(4)
    C = rng.normal(size=(4, 6))
    C[3] = C[1]
    W = jnp.ones(6)
    b = jnp.asarray(rng.normal(size=4))

    @jax.jit
    def guarded(C, b):
        f = DenseJacobian(C, path=UnrolledSolver()).schur(W, guard=True)
        g = DenseJacobian(C).schur(W, guard=True)
        return f.solve(b), g.solve(b), f.ratio

    y, y_dense, ratio = guarded(jnp.asarray(C), b)
    assert not float(ratio) >= SINGULAR_RATIO
    assert np.all(np.isfinite(y))
    np.testing.assert_allclose(y, y_dense, rtol=1e-10, atol=1e-12)


def test_chosen_once_by_size():
    def never():
        raise AssertionError("the symbolic analysis is not needed here")

    auto = AutoSolver()
    assert isinstance(auto.resolve(auto.max_unrolled, True, never), UnrolledSolver)
    assert isinstance(auto.resolve(auto.max_unrolled + 2, True, never), DenseSolver)
    assert isinstance(as_linear_solver("unrolled"), UnrolledSolver)
    assert isinstance(UnrolledSolver(max_rows=4).resolve(6, True, never), DenseSolver)
    c = Constraints.of(pendulum_chain(2)).with_linear_solver("auto")
    assert isinstance(c.linear_solver, UnrolledSolver)


def test_a_vectorized_program_takes_the_straight_line_path_up_to_more_rows():
    """10 rows: LAPACK in a single run, straight-line code in a sweep's vectorized program
    (the choice made at resolve, carried by the dense path); an explicit "dense" stays
    dense in both, and the two paths' accelerations of a vectorized batch agree to
    rounding."""
    auto = AutoSolver()
    rows = auto.max_unrolled + 4
    dense = auto.resolve(rows, True, lambda: None)
    assert isinstance(dense, DenseSolver) and isinstance(dense.vectorized(), UnrolledSolver)
    big = auto.resolve(auto.max_unrolled_vectorized + 1, False, lambda: None)
    assert big.vectorized() is big
    assert DenseSolver().vectorized() == DenseSolver()

    model = pendulum_chain(5)  # 10 rows
    c = Constraints.of(model).with_linear_solver("auto")
    assert isinstance(c.linear_solver, DenseSolver) and c.m == 10
    assert isinstance(c.for_batch().linear_solver, UnrolledSolver)
    explicit = Constraints.of(model).with_linear_solver("dense").for_batch()
    assert isinstance(explicit.linear_solver, DenseSolver)

    rng = np.random.default_rng(7)
    q = jnp.asarray(model.q0) + 1e-3 * jnp.asarray(rng.normal(size=(4, model.nq)))
    qd = jnp.asarray(rng.normal(size=(4, model.nq)))

    def batch(cs):
        acc = jax.vmap(lambda q, qd: Problem(model, cs).accelerations(q, qd, 0.3)[:2])
        return eqx.filter_jit(acc)(q, qd)

    for a, b in zip(batch(c.for_batch()), batch(explicit), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11)


def test_chain_accelerations_equal_the_dense_path():
    model = pendulum_chain(3)
    q = jnp.asarray(model.q0)
    qd = jnp.asarray(np.random.default_rng(5).normal(size=model.nq))
    accelerations = eqx.filter_jit(lambda p, q, qd: p.accelerations(q, qd, 0.3))
    out = [
        accelerations(Problem(model, Constraints.of(model).with_linear_solver(s)), q, qd)
        for s in ("unrolled", "dense")
    ]
    for a, b in zip(out[0][:2], out[1][:2], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.parametrize("method", ["baumgarte", "generalized-alpha"])
def test_chain_runs_equal_the_dense_path(method):
    model = pendulum_chain(3)
    t = np.linspace(0.0, 0.5, 6)
    runs = [
        md.forward(model, t, method=method, dt=1e-3, energy_tol=None, linear_solver=s)
        for s in ("auto", "dense")
    ]
    assert runs[0].stats["linear_solver"] == "unrolled"
    for key in ("q", "qd"):
        a, b = (np.asarray(getattr(r, key)) for r in runs)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
