"""expm_stack: scipy's expm on every matrix of a stack, computed at once."""

import numpy as np
import pytest
import scipy.linalg as la

from piezolib.robust.matrix_exponential import expm_stack


@pytest.mark.parametrize("scale", [1e-6, 1.0, 30.0])
def test_every_matrix_is_scipys_expm_to_rounding(scale):
    A = scale * np.random.default_rng(1).standard_normal((40, 7, 7))
    E = expm_stack(A)
    for Ak, Ek in zip(A, E):
        ref = la.expm(Ak)
        # relative to the conditioning of exp at A (the norm of A bounds it)
        assert np.linalg.norm(Ek - ref) <= 1e-13 * (1 + np.linalg.norm(Ak, 1)) ** 2 \
            * np.linalg.norm(ref)


def test_exact_cases_and_shapes():
    N = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    assert np.allclose(expm_stack(N), np.eye(3) + N + N @ N / 2, rtol=0, atol=1e-15)
    rotation = expm_stack(np.array([[0.0, -np.pi], [np.pi, 0.0]]))
    assert np.allclose(rotation, -np.eye(2), atol=1e-14)
    stack = np.zeros((2, 3, 4, 4))
    assert expm_stack(stack).shape == (2, 3, 4, 4)
    assert np.allclose(expm_stack(stack)[1, 2], np.eye(4), rtol=0, atol=1e-15)
    complex_ = expm_stack(np.array([[1j]]))
    assert np.isclose(complex_[0, 0], np.exp(1j))


@pytest.mark.parametrize("A, match", [(np.ones((2, 3)), "square"), (np.ones(3), "square"),
                                      (np.full((2, 2), np.nan), "A")])
def test_bad_input_names_the_argument(A, match):
    with pytest.raises(ValueError, match=match):
        expm_stack(A)
