"""Large mechanisms on the sparse path (issue 31: an 11,000-body model's ``check`` ran past
60 s): the programs of a dynamic run's start do not grow with the number of joints, and the
guard at singular positions does not form the dense ``Phi_q`` of a large one.

* The consistent start's velocity fix takes the constraint set packed (a few stacked arrays):
  its compiled program has the same arguments for a chain of 10 and of 40 links (the set
  itself: one argument per joint's number, and XLA's compile time grew faster than the
  count: 9 s for 1,000 links, 155 s for 4,000), and its velocities equal those of the dense
  path (an LU of the dense ``Phi_q W Phi_q^T``) to rounding.
* Above :data:`~mixdyn.equations._jacobian.DENSE_GUARD_MAX_ENTRIES` (lowered here) the guard's
  damped solve runs on the banded factors: it equals its definition, ``S``'s eigenvalues
  ``s`` inverted as ``s / (s + mu)^2`` (``mu = SINGULAR_DAMPING max diag S``), computed by
  SciPy through an SVD of ``Phi_q W^(1/2)``, and agrees with the dense damped SVD solve on
  the components that are not near the singular direction.
"""

from __future__ import annotations

import importlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sla

from fixtures import pendulum_chain
from mixdyn.analysis import _start
from mixdyn.equations import Constraints
from mixdyn.equations._jacobian import BandedJacobian
from mixdyn.linalg._dense import SINGULAR_DAMPING, SINGULAR_RATIO

jacobian_module = importlib.import_module("mixdyn.equations._jacobian")


def _chain_set(n: int):
    model = pendulum_chain(n)
    return model, Constraints.of(model).with_linear_solver("sparse")


def _arguments(n: int) -> int:
    model, c = _chain_set(n)
    q = jnp.asarray(np.asarray(model.q0, dtype=float))
    args = (c.packed(), q, jnp.zeros(model.nq), jnp.asarray(0.0), jnp.ones(model.nq))
    return len(jax.tree_util.tree_leaves(args))


def test_the_packed_velocity_fix_has_the_same_arguments_for_any_chain():
    assert _arguments(10) == _arguments(40)


@pytest.mark.slow  # compiles the start's programs on both paths (10-20 s on a shared CPU)
def test_the_packed_velocity_fix_equals_the_dense_path():
    model, c = _chain_set(12)
    assert c.banded
    q = np.asarray(model.q0, dtype=float)
    rng = np.random.default_rng(4)
    qd = rng.normal(size=model.nq)
    W = np.ones(model.nq)
    W[[2, 5]] = 0.0  # two velocities kept (held)
    t = jnp.asarray(0.0)
    packed, r1 = _start.fix_velocities(c, jnp.asarray(q), jnp.asarray(qd), t, jnp.asarray(W))
    dense_set = c.with_linear_solver("dense")
    dense, r2 = _start.fix_velocities(dense_set, jnp.asarray(q), jnp.asarray(qd), t, jnp.asarray(W))
    np.testing.assert_allclose(np.asarray(packed), np.asarray(dense), rtol=0, atol=1e-12)
    assert float(r1) < 1e-12 and float(r2) < 1e-12
    np.testing.assert_array_equal(np.asarray(packed)[[2, 5]], qd[[2, 5]])
    # an independent check: the velocity constraints hold (Phi_q qd = 0 for a chain)
    J = np.asarray(BandedJacobian(c, c.jacobian_values(jnp.asarray(q), t)).dense())
    np.testing.assert_allclose(J @ np.asarray(packed), 0.0, atol=1e-12)


@pytest.fixture
def near_singular():
    """A 12-link chain's pattern with random values and two nearly dependent rows (as in
    test_solver_contract.py)."""
    c = Constraints.of(pendulum_chain(12)).with_linear_solver("sparse")
    rows, cols = c.coo()
    rng = np.random.default_rng(7)
    J = np.zeros((c.m, c.nq))
    np.add.at(J, (rows, cols), rng.normal(size=rows.size))
    J[0] = J[1] + 1e-9 * J[0]  # rows 0 and 1 share the pattern (the same joint)
    W = np.random.default_rng(3).uniform(0.5, 2.0, size=c.nq)
    b = np.random.default_rng(5).normal(size=c.m)
    return c, J, J[rows, cols], W, b


@pytest.mark.slow  # the solves run eagerly, each operation compiled (about 10 s)
def test_a_large_guard_damps_on_the_banded_factors(near_singular, monkeypatch):
    c, J, v, W, b = near_singular
    monkeypatch.setattr(jacobian_module, "DENSE_GUARD_MAX_ENTRIES", 0)
    op = BandedJacobian(c, jnp.asarray(v))

    def dense(self):
        raise AssertionError("the dense Phi_q was formed")

    monkeypatch.setattr(BandedJacobian, "dense", dense)
    f = op.schur(jnp.asarray(W), guard=True)
    assert float(f.ratio) < SINGULAR_RATIO
    y = np.asarray(f.solve(jnp.asarray(b)))
    # the definition, by SciPy: S = F F^T, F = J W^(1/2); s = sigma^2
    F = J * np.sqrt(W)
    U, sigma, _ = sla.svd(F, full_matrices=False, lapack_driver="gesvd")
    s = sigma**2
    mu = SINGULAR_DAMPING * np.max(np.sum(F * F, axis=1))
    ref = U @ (s / (s + mu) ** 2 * (U.T @ b))
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-7 * np.abs(ref).max())
    # where s >> mu both guards invert s: the dense damped SVD solve agrees there
    monkeypatch.undo()
    dense = np.asarray(BandedJacobian(c, jnp.asarray(v)).schur(jnp.asarray(W), guard=True).solve(b))
    far = s > 1e4 * mu
    np.testing.assert_allclose(U[:, far].T @ y, U[:, far].T @ dense, rtol=1e-3, atol=1e-12)
