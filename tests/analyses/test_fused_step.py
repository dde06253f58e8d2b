"""The two forms of a body's rotation, and the generalized-alpha Newton loops.

A body point or vector is rotated by products written out element-wise where the elements are
evaluated one after the other (the dense path: XLA fuses them), by the 2 x 2 matrix product
where they are vectorized per kind (the sparse path's ``vmap``). Both equal the closed form
``r + A(phi) s`` (NumPy), and a chain's ``Phi_q`` and ``gamma`` on the two paths agree to
rounding. Generalized-alpha's ``newton="auto"`` runs its modified iterations in a loop of their
own: where they contract well (no switch to full Newton) its run is the modified one's, bit
for bit.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum_chain
from mixdyn.equations import Constraints
from mixdyn.model._geometry import point, vector, vectorized_elements


def _closed_form(q, b, s):
    x, y, phi = q[3 * b : 3 * b + 3]
    c, sn = np.cos(phi), np.sin(phi)
    return np.array([x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]])


def test_point_and_vector_in_both_forms_equal_the_closed_form():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(8, 6)) * np.array([1.0, 1.0, 3.0, 1.0, 1.0, 3.0])
    s = rng.normal(size=(8, 2))
    want = np.stack([_closed_form(qk, 1, sk) for qk, sk in zip(q, s, strict=True)])
    fused = jax.jit(jax.vmap(lambda q, s: point(q, 1, s)))
    with vectorized_elements():
        batched = jax.jit(jax.vmap(lambda q, s: point(q, 1, s)))(q, s)
    for got in (fused(q, s), batched):
        np.testing.assert_allclose(got, want, rtol=1e-15, atol=1e-15)
    u = np.array([0.6, -0.8])
    np.testing.assert_allclose(
        vector(jnp.asarray(q[0]), 1, u), _closed_form(q[0], 1, u) - [q[0, 3], q[0, 4]], atol=1e-15
    )


def test_chain_jacobian_and_gamma_agree_on_both_paths():
    model = pendulum_chain(4)
    rng = np.random.default_rng(7)
    q = jnp.asarray(np.asarray(model.q0) + 0.3 * rng.normal(size=model.nq))
    qd = jnp.asarray(rng.normal(size=model.nq))
    dense = Constraints.of(model).with_linear_solver("dense")
    banded = Constraints.of(model).with_linear_solver("sparse")
    assert not dense.banded and banded.banded

    @jax.jit
    def both(q, qd):
        return (
            dense.phi_q(q, 0.0),
            banded.jacobian(q, 0.0).dense(),
            dense.gamma(q, qd, 0.0),
            banded.gamma(q, qd, 0.0),
        )

    Jd, Jb, gd, gb = both(q, qd)
    np.testing.assert_allclose(Jd, Jb, rtol=0, atol=1e-15)
    np.testing.assert_allclose(gd, gb, rtol=1e-14, atol=1e-14)


@pytest.mark.slow  # long: run by CI's slow set
def test_auto_newton_without_a_switch_is_the_modified_iteration():
    model = pendulum_chain(2)
    t = np.linspace(0.0, 0.05, 3)
    kw = dict(method="generalized-alpha", dt=1e-3, energy_tol=None)
    auto = md.forward(model, t, newton="auto", **kw)
    modified = md.forward(model, t, newton="modified", **kw)
    assert auto.stats["newton_iterations"] == modified.stats["newton_iterations"]
    np.testing.assert_array_equal(np.asarray(auto.q), np.asarray(modified.q))
    np.testing.assert_array_equal(np.asarray(auto.qd), np.asarray(modified.qd))
