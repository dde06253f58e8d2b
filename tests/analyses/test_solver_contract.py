"""The linear-solver contract, for every operator class of ``Phi_q``.

:class:`DenseJacobian` and :class:`BandedJacobian` (``Constraints.jacobian``) factorize once and
return a ``Factor`` (``solve``, pivot ratio). Each is checked against NumPy's dense linear
algebra (an independent implementation) on random well-conditioned systems on a real sparsity
pattern, on a rank-deficient system (a parallelogram with a redundant link), on a
near-singular one (two nearly dependent rows: the damped SVD solve, to 1e-8 of a NumPy/SciPy
computation of its definition by another route), and for gradients against central finite
differences.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sla

from fixtures import parallelogram_with_extra_link, pendulum_chain, slider_crank
from mixdyn.equations import Constraints
from mixdyn.equations._jacobian import BandedJacobian, DenseJacobian
from mixdyn.linalg._dense import SINGULAR_DAMPING, SINGULAR_DAMPING_FORMED, SINGULAR_RATIO

PATHS = ("dense", "banded")


def _operator(path, c, v):
    """The operator of ``path`` for the matrix with values ``v`` on ``c``'s pattern."""
    op = BandedJacobian(c, v)
    return op if path == "banded" else DenseJacobian(op.dense(), c.rank)


@pytest.fixture(scope="module")
def chain():
    """A 12-link chain's constraint pattern (24 rows, 36 columns) with random values."""
    c = Constraints.of(pendulum_chain(12)).with_linear_solver("sparse")
    rows, _ = c.coo()
    rng = np.random.default_rng(7)
    v = rng.normal(size=rows.size)
    return c, jnp.asarray(v)


def _dense_np(c, v):
    rows, cols = c.coo()
    J = np.zeros((c.m, c.nq))
    np.add.at(J, (rows, cols), np.asarray(v))
    return J


@pytest.mark.parametrize("path", PATHS)
def test_products_agree_with_the_matrix(chain, path):
    c, v = chain
    J = _dense_np(c, v)
    op = _operator(path, c, v)
    rng = np.random.default_rng(1)
    x, y = rng.normal(size=c.nq), rng.normal(size=c.m)
    np.testing.assert_allclose(op.mv(jnp.asarray(x)), J @ x, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(op.rmv(jnp.asarray(y)), J.T @ y, rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(np.asarray(op.dense()), J)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("shift", [None, 0.3])
def test_schur_solve_well_conditioned(chain, path, shift):
    c, v = chain
    J = _dense_np(c, v)
    rng = np.random.default_rng(2)
    W = rng.uniform(0.5, 2.0, size=c.nq)
    S = J @ np.diag(W) @ J.T + (0.0 if shift is None else shift) * np.eye(c.m)
    assert np.linalg.cond(S) < 1e6  # the premise: a well-conditioned system
    B = rng.normal(size=(c.m, 3))
    f = _operator(path, c, v).schur(jnp.asarray(W), shift)
    X = np.asarray(f.solve(jnp.asarray(B)))
    np.testing.assert_allclose(X, np.linalg.solve(S, B), rtol=1e-9, atol=1e-11)
    x1 = np.asarray(f.solve(jnp.asarray(B[:, 0])))  # a vector right-hand side too
    np.testing.assert_allclose(x1, X[:, 0], rtol=1e-12, atol=1e-14)
    assert 1e-8 < float(f.ratio) <= 1.0


@pytest.mark.parametrize("path", PATHS)
def test_guard_leaves_regular_systems_alone(chain, path):
    c, v = chain
    op = _operator(path, c, v)
    W = jnp.ones(c.nq)
    b = jnp.arange(c.m, dtype=float)
    np.testing.assert_array_equal(
        np.asarray(op.schur(W, guard=True).solve(b)), np.asarray(op.schur(W).solve(b))
    )


@pytest.mark.parametrize("path", PATHS)
def test_min_norm_solution(chain, path):
    c, v = chain
    J = _dense_np(c, v)
    rng = np.random.default_rng(3)
    W = rng.uniform(0.5, 2.0, size=c.nq)
    b = rng.normal(size=c.m)
    f = _operator(path, c, v).min_norm(jnp.asarray(W), refine=1)
    x = np.asarray(f.solve(jnp.asarray(b)))
    # the least W^-1-norm solution of J x = b, from NumPy's dense solve
    ref = W * (J.T @ np.linalg.solve(J @ np.diag(W) @ J.T, b))
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(J @ x, b, rtol=1e-10, atol=1e-11)


@pytest.mark.parametrize("path", PATHS)
def test_partition_solves_the_dependent_block(chain, path):
    """``partition(D)``: ``x`` zero outside ``D`` with ``Phi_qD x_D = b`` (NumPy's solve of
    the block), and a ratio that sees the block's conditioning: a well-conditioned choice
    (column-pivoted QR) scores far above a block made nearly singular."""
    c, v = chain
    J = _dense_np(c, v)
    _, _, piv = sla.qr(J, pivoting=True)  # m well-conditioned columns (column pivoting)
    D = np.sort(piv[: c.m])
    assert np.linalg.cond(J[:, D]) < 1e6  # the premise
    rng = np.random.default_rng(4)
    b = rng.normal(size=c.m)
    f = _operator(path, c, v).partition(jnp.asarray(D))
    x = np.asarray(f.solve(jnp.asarray(b)))
    others = np.setdiff1d(np.arange(c.nq), D)
    assert np.max(np.abs(x[others])) < 1e-12
    np.testing.assert_allclose(x[D], np.linalg.solve(J[:, D], b), rtol=1e-8, atol=1e-10)
    # a block with one column nearly zero (on the same pattern): the ratio collapses
    _, cols = c.coo()
    vbad = np.asarray(v).copy()
    vbad[cols == D[1]] *= 1e-9
    bad = _operator(path, c, jnp.asarray(vbad)).partition(jnp.asarray(D))
    assert float(bad.ratio) < 1e-6 * float(f.ratio)


@pytest.mark.parametrize("path", PATHS)
def test_solver_square_system(path):
    model = slider_crank()
    base = Constraints.of(model)
    assert base.m == model.nq
    c = base.with_linear_solver("sparse")
    q = model.q0
    J = np.asarray(base.phi_q(q, 0.0))
    op = c.jacobian(q, 0.0) if path == "banded" else base.jacobian(q, 0.0)
    assert isinstance(op, BandedJacobian if path == "banded" else DenseJacobian)
    b = np.linspace(-1.0, 1.0, model.nq)
    f = op.solver(refine=1)
    np.testing.assert_allclose(
        np.asarray(f.solve(jnp.asarray(b))), np.linalg.solve(J, b), rtol=1e-9, atol=1e-12
    )
    # the pivot ratios of both paths measure Phi_q's conditioning on one scale
    s = np.linalg.svd(J, compute_uv=False)
    assert 1e-3 * s[-1] / s[0] < float(f.ratio) <= 1.0


@pytest.mark.parametrize("path", PATHS)
def test_rank_deficient_minimum_norm(path):
    """A parallelogram with an extra link: 13 rows of rank 12. Consistent right-hand sides
    are solved exactly and with the minimum-norm multipliers (NumPy's pseudo-inverse)."""
    model = parallelogram_with_extra_link()
    q = model.q0
    J = np.asarray(Constraints.of(model).phi_q(q, 0.0))
    rank = np.linalg.matrix_rank(J)
    assert rank == J.shape[0] - 1
    c = Constraints.of(model).with_rank(rank)
    c = c.with_linear_solver("sparse") if path == "banded" else c
    op = c.jacobian(q, 0.0)
    W = 1.0 / np.asarray(model.mass_diagonal)
    S = J @ np.diag(W) @ J.T
    rng = np.random.default_rng(4)
    b = S @ rng.normal(size=S.shape[0])  # in the range of S
    f = op.schur(jnp.asarray(W))
    y = np.asarray(f.solve(jnp.asarray(b)))
    np.testing.assert_allclose(S @ y, b, rtol=1e-8, atol=1e-10 * np.abs(b).max())
    np.testing.assert_allclose(y, np.linalg.pinv(S) @ b, rtol=1e-6, atol=1e-7 * np.abs(y).max())
    assert float(f.ratio) > 1e-8  # the redundancy is not a loss of rank
    # least-norm solutions of Phi_q x = r for r in the range of Phi_q
    r = J @ rng.normal(size=J.shape[1])
    x = np.asarray(op.min_norm(jnp.asarray(W)).solve(jnp.asarray(r)))
    np.testing.assert_allclose(J @ x, r, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(x, W * (J.T @ (np.linalg.pinv(S) @ r)), rtol=1e-6, atol=1e-9)


def _damped_gram(F, b):
    """The damped solve of ``S y = b``, ``S = F F^T``: ``S``'s singular values
    ``s = sigma^2`` inverted as ``s / (s^2 + (SINGULAR_DAMPING s_max)^2)``, by SciPy through
    another route than the solve's SVD of ``F``: a Householder QR ``F^T = Q R``
    (``S = R^T R``), then LAPACK's ``gesvd`` of ``R^T``. ``S`` itself is not formed: its
    small singular values would be rounding (``~eps s_max``)."""
    _, R = sla.qr(F.T, mode="economic")
    U, sigma, _ = sla.svd(R.T, lapack_driver="gesvd")
    s = sigma**2
    return U @ (s / (s**2 + (SINGULAR_DAMPING * s[0]) ** 2) * (U.T @ b))


@pytest.mark.parametrize(("path", "depth"), [("dense", 1e-9), ("banded", 1e-9), ("banded", 1e-5)])
def test_near_singular_reports_and_damps(chain, path, depth):
    """Two nearly dependent rows (``sigma_min / sigma_max`` of ``Phi_q`` 8e-12; 8e-8 on the
    banded path, whose Cholesky pivot ratio falls below SINGULAR_RATIO that far from the
    singular position, and where the filter's sensitivity to rounding peaks): the ratio falls
    below SINGULAR_RATIO, and the guarded solve is the damped solve of ``S = Phi_q W Phi_q^T``
    (Tikhonov filter factors of ``S``'s singular values), equal to SciPy's to 1e-8 of its
    largest component whatever LAPACK either runs on."""
    c, v = chain
    rows, cols = c.coo()
    J = _dense_np(c, v)
    J[0] = J[1] + depth * J[0]  # rows 0 and 1 share the pattern (the same joint)
    v2 = jnp.asarray(J[rows, cols])
    op = _operator(path, c, v2)
    W = np.random.default_rng(3).uniform(0.5, 2.0, size=c.nq)
    f = op.schur(jnp.asarray(W), guard=True)
    assert float(f.ratio) < SINGULAR_RATIO
    b = np.random.default_rng(5).normal(size=c.m)
    y = np.asarray(f.solve(jnp.asarray(b)))
    ref = _damped_gram(J * np.sqrt(W), b)
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-8 * np.abs(ref).max())


@pytest.mark.parametrize("path", PATHS)
def test_near_singular_mixed_problem_damps_its_own_schur_complement(chain, path):
    """A mixed problem with unknown forces of any direction (``B`` not along the prescribed
    motions' gradients): ``S = C W G`` is not symmetric, and near a singular position (two
    nearly dependent rows of ``C``, in ``G`` too) the guarded solve is the Tikhonov solution
    of ``S mu = b`` with ``lambda = SINGULAR_DAMPING_FORMED s_max``, computed here by SciPy as
    the least-squares solution of ``[S; lambda I] mu = [b; 0]``, to 1e-8 of its largest
    component; ``x`` follows from ``mu``."""
    c, v = chain
    rows, cols = c.coo()
    m, n, p = c.m, c.nq, 2
    C = _dense_np(c, v)
    C[0] = C[1] + 1e-9 * C[0]
    rng = np.random.default_rng(12)
    W = rng.uniform(0.5, 2.0, size=n)
    B = rng.normal(size=(n, p))
    r1, r2 = rng.normal(size=n), rng.normal(size=m)
    op = _operator(path, c, jnp.asarray(C[rows, cols]))
    kkt, ratio = op.kkt(jnp.asarray(W), jnp.asarray(B))
    assert float(ratio) < SINGULAR_RATIO
    x, mu = (np.asarray(a) for a in kkt(jnp.asarray(r1), jnp.asarray(r2)))
    G = np.concatenate([C[: m - p].T, -B], axis=1)
    S = C @ np.diag(W) @ G
    lam = SINGULAR_DAMPING_FORMED * np.linalg.norm(S, 2)
    rhs = np.concatenate([C @ (W * r1) - r2, np.zeros(m)])
    ref = sla.lstsq(np.vstack([S, lam * np.eye(m)]), rhs)[0]
    np.testing.assert_allclose(mu, ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    x_ref = W * r1 - W * (G @ ref)
    np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-8 * np.abs(x_ref).max())


def _batched_operator(path, c, v, batched):
    if path == "banded":
        return BandedJacobian(c.for_batch() if batched else c, v)
    return DenseJacobian(BandedJacobian(c, v).dense(), c.rank, batched)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("singular", [(), (1,), (0, 2)], ids=["none", "one", "two"])
def test_batched_guard_equals_the_member_by_member_guard(chain, path, singular):
    """A sweep's guard (decided once per batch, ``custom_vmap``) gives each member of a
    ``vmap`` what the member's own guard gives it alone: the LU solve where regular, the damped
    SVD solve where near-singular (checked against SciPy's there)."""
    c, v = chain
    rows, cols = c.coo()
    rng = np.random.default_rng(8)
    values, rhs = [], []
    for k in range(4):
        J = _dense_np(c, v * (1 + 0.1 * k))
        if k in singular:
            J[0] = J[1] + 1e-9 * J[0]
        values.append(J[rows, cols])
        rhs.append(rng.normal(size=c.m))
    V, B = jnp.asarray(np.array(values)), jnp.asarray(np.array(rhs))
    W = jnp.ones(c.nq)

    def solve(batched):
        return lambda v, b: _batched_operator(path, c, v, batched).schur(W, guard=True).solve(b)

    together = np.asarray(jax.jit(jax.vmap(solve(True)))(V, B))
    alone = np.array([np.asarray(solve(False)(V[k], B[k])) for k in range(4)])
    np.testing.assert_allclose(together, alone, rtol=1e-12, atol=1e-12 * np.abs(alone).max())
    for k in singular:
        ref = _damped_gram(_dense_np(c, V[k]), np.asarray(B[k]))
        np.testing.assert_allclose(together[k], ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    # unbatched (one member), the batched operator is the plain guard
    one = np.asarray(jax.jit(solve(True))(V[0], B[0]))
    np.testing.assert_allclose(one, alone[0], rtol=1e-12, atol=1e-12 * np.abs(alone[0]).max())


def _fd_grad(fun, x, h=1e-6):
    x = np.asarray(x, dtype=float)
    g = np.zeros_like(x)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        g[i] = (float(fun(jnp.asarray(x + e))) - float(fun(jnp.asarray(x - e)))) / (2 * h)
    return g


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("kind", ["schur", "min_norm"])
def test_gradients_match_finite_differences(chain, path, kind):
    c, v = chain
    rng = np.random.default_rng(6)
    W = jnp.asarray(rng.uniform(0.5, 2.0, size=c.nq))
    b = jnp.asarray(rng.normal(size=c.m))
    out = rng.normal(size=c.nq if kind == "min_norm" else c.m)

    def fun(vals):
        op = _operator(path, c, vals)
        f = op.schur(W) if kind == "schur" else op.min_norm(W, refine=1)
        return jnp.dot(jnp.asarray(out), f.solve(b))

    g = np.asarray(jax.jit(jax.grad(fun))(v))
    scale = np.abs(g).max()  # central differences: rounding ~ 1e-16 |f| / h
    np.testing.assert_allclose(g, _fd_grad(jax.jit(fun), v), rtol=1e-5, atol=1e-8 * scale)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("mixed", [False, True], ids=["forward", "mixed"])
def test_kkt_solution_and_gradients(chain, path, mixed):
    """The constrained-dynamics solve ``W^-1 x + G mu = r1``, ``C x = r2`` against NumPy's
    dense solve of the whole matrix, and its gradient with respect to every input (the
    matrix's values, the metric, the unknown forces' directions, both right-hand sides)
    along random directions against central differences: the dense path differentiates it
    implicitly (one more solve with the same factor), the banded path through its
    factorization."""
    c, v = chain
    rng = np.random.default_rng(11)
    n, m = c.nq, c.m
    p = 2 if mixed else 0
    W = rng.uniform(0.5, 2.0, size=n)
    B = rng.normal(size=(n, p))
    r1, r2 = rng.normal(size=n), rng.normal(size=m)
    wx, wmu = rng.normal(size=n), rng.normal(size=m)
    sizes = np.cumsum([v.size, n, n * p, n])

    def split(z):
        vals, W_, B_, r1_, r2_ = jnp.split(z, sizes)
        return vals, W_, B_.reshape(n, p), r1_, r2_

    def solve(z):
        vals, W_, B_, r1_, r2_ = split(z)
        kkt, _ = _operator(path, c, vals).kkt(W_, B_ if mixed else None)
        return kkt(r1_, r2_)

    z0 = jnp.concatenate([v, W, B.ravel(), r1, r2])
    x, mu = (np.asarray(a) for a in jax.jit(solve)(z0))
    C = _dense_np(c, v)
    G = C.T if not mixed else np.concatenate([C[: m - p].T, -B], axis=1)
    K = np.block([[np.diag(1.0 / W), G], [C, np.zeros((m, m))]])
    ref = np.linalg.solve(K, np.concatenate([r1, r2]))
    np.testing.assert_allclose(np.concatenate([x, mu]), ref, rtol=1e-9, atol=1e-10)

    def fun(z):
        x, mu = solve(z)
        return jnp.dot(wx, x) + jnp.dot(wmu, mu)

    # the gradient along random directions against central differences along them
    g = np.asarray(jax.jit(jax.grad(fun))(z0))
    run, h = jax.jit(fun), 1e-6
    for d in rng.normal(size=(4, z0.size)):
        fd = (float(run(z0 + h * d)) - float(run(z0 - h * d))) / (2 * h)
        assert abs(g @ d - fd) <= 1e-6 * np.abs(g).sum(), (g @ d, fd)
