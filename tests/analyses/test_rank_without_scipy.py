"""The rank checks and the null space of a small mechanism are computed with NumPy alone
(SciPy's sparse module is imported only for a sparse matrix): each agrees with the SciPy
path it stands beside, on independent, dependent and nearly dependent rows."""

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from mixdyn.analysis._structure import _full_row_rank
from mixdyn.analysis.mixed import _null_space

RNG = np.random.default_rng(7)


def _cases():
    A = RNG.standard_normal((6, 9))
    yield "independent", A, True
    B = A.copy()
    B[5] = 2.0 * B[1] - B[3]  # a dependent row
    yield "dependent", B, False
    C = A.copy()
    C[5] = C[1] + 1e-9 * RNG.standard_normal(9)  # nearly dependent: not certain
    yield "nearly dependent", C, False
    D = A.copy()
    D[2] = 0.0
    yield "zero row", D, False
    yield "no rows", np.zeros((0, 9)), True


@pytest.mark.parametrize(("name", "A", "full"), list(_cases()), ids=[c[0] for c in _cases()])
def test_dense_full_rank_agrees_with_the_sparse_path(name, A, full):
    assert _full_row_rank(A) is full
    assert _full_row_rank(sp.csr_matrix(A)) is full


@pytest.mark.parametrize("rank", [0, 2, 5])
def test_the_null_space_is_scipys(rank):
    A = (
        RNG.standard_normal((5, rank)) @ RNG.standard_normal((rank, 8))
        if rank
        else np.zeros((5, 8))
    )
    N = _null_space(A)
    ref = scipy.linalg.null_space(A)
    assert N.shape == ref.shape == (8, 8 - rank)
    np.testing.assert_allclose(N.T @ N, np.eye(8 - rank), atol=1e-12)  # orthonormal
    np.testing.assert_allclose(A @ N, 0.0, atol=1e-12)
    np.testing.assert_allclose(N @ N.T, ref @ ref.T, atol=1e-12)  # the same subspace
