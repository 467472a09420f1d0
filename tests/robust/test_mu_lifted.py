"""The symmetric-lift upper bound of mu for complex scalar blocks (mussv(..., refine=...))."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from piezolib.robust.mu import mussv
from piezolib.robust.mu_lifted import _LiftedCertificate, _refine_point

EIGHT = [(1, 1)] * 8


def wide_gap_matrix(seed):
    """A seeded random 8 x 8 matrix (wide D-scaled gaps at seeds 9, 59, 195, 210)."""
    g = np.random.default_rng(seed)
    M = g.standard_normal((8, 8)) + 1j * g.standard_normal((8, 8))
    return np.diag(np.exp(g.standard_normal(8))) @ M


def balanced(M, res):
    """diag(d) M diag(d)^-1 with mussv's scalings (the same mu for scalar blocks)."""
    d = np.abs(np.diagonal(res.Dl[0]))
    return d[:, None] * M / d[None, :]


def certificate_holds(M, S, beta):
    """Check mu(M) < beta from multipliers S, built here from the definition.

    For every x: sum_i (|(M x)_i|^2 - beta^2 |x_i|^2) x^H S_i x < 0 must hold on all
    symmetric tensors z = x (x) x; the form is z^H (K^H D K - beta^2 D) z with
    D = blockdiag(S_i) (index i * n + k) and K = M (x) I.
    """
    n = M.shape[0]
    D = np.zeros((n * n, n * n), complex)
    for i in range(n):
        D[i * n:(i + 1) * n, i * n:(i + 1) * n] = S[i]
    K = np.kron(M, np.eye(n))
    form = K.conj().T @ D @ K - beta ** 2 * D
    swap = np.zeros((n * n, n * n))
    for a in range(n):
        for b in range(n):
            swap[a * n + b, b * n + a] = 1
    # orthonormal basis of the symmetric tensors: the +1 eigenvectors of the swap
    w, V = np.linalg.eigh(swap)
    sym = V[:, w > 0]
    psd = all(np.linalg.eigvalsh(s).min() > 0 for s in S)
    return psd and np.linalg.eigvalsh(sym.conj().T @ form @ sym).max() < 0


@pytest.mark.parametrize("seed", [195, 210, 9])
def test_refined_bound_is_certified_and_closes_the_gap(seed):
    M = wide_gap_matrix(seed)
    plain = mussv(M, EIGHT)
    assert plain.gap[0] > 0.012
    refined = mussv(M, EIGHT, refine=0.01)
    assert refined.lower[0] == plain.lower[0]
    assert refined.upper[0] < plain.upper[0]
    assert refined.gap[0] <= 0.005
    # the multipliers behind the bound certify it, checked from the definition
    Mb = balanced(M, plain)
    bound, theta = _refine_point(Mb, None, 0.0, 0.0, 60)
    S = _LiftedCertificate(Mb).multipliers(theta)
    assert certificate_holds(Mb, S, bound * (1 + 1e-9))
    assert not certificate_holds(Mb, S, bound * (1 - 1e-3))
    # and no perturbation found by brute force beats it: max over random phases of rho(Q M)
    g = np.random.default_rng(0)
    Q = np.exp(2j * np.pi * g.random((20000, 8)))
    rho = np.abs(np.linalg.eigvals(Q[:, :, None] * M[None])).max(axis=1)
    assert rho.max() <= bound


def test_identity_multipliers_on_the_balanced_matrix_give_the_d_scaled_bound():
    M = wide_gap_matrix(59)
    res = mussv(M, EIGHT)
    cert = _LiftedCertificate(balanced(M, res))
    assert np.sqrt(cert.bound_squared(cert.start())) == pytest.approx(res.upper[0], rel=1e-9)


def test_barrier_derivatives_match_finite_differences():
    g = np.random.default_rng(1)
    n = 3
    M = g.standard_normal((n, n)) + 1j * g.standard_normal((n, n))
    cert = _LiftedCertificate(M)
    theta = cert.start() + 0.01 * g.standard_normal(n ** 3)
    tau = 1.2 * cert.bound_squared(theta)
    grad, curvature = cert.newton_step(theta, tau)
    hess = -curvature
    h, eye = 1e-5, np.eye(n ** 3)
    fd_grad = [(cert.barrier(theta + h * e, tau) - cert.barrier(theta - h * e, tau)) / (2 * h)
               for e in eye]
    fd_hess = [(cert.newton_step(theta + h * e, tau)[0] - cert.newton_step(theta - h * e, tau)[0])
               / (2 * h) for e in eye]
    np.testing.assert_allclose(grad, fd_grad, atol=1e-6 * np.abs(grad).max())
    np.testing.assert_allclose(hess, np.array(fd_hess), atol=1e-5 * np.abs(hess).max())


def test_refine_on_a_frequency_response_keeps_every_bound_valid():
    g = np.random.default_rng(3)
    M = np.array([wide_gap_matrix(210) * (1 + 0.02 * k) + 0.05 * k * np.diag(g.standard_normal(8))
                  for k in range(6)])
    plain = mussv(M, EIGHT)
    refined = mussv(M, EIGHT, refine=0.01)
    np.testing.assert_array_equal(refined.lower, plain.lower)
    assert np.all(refined.upper <= plain.upper)
    assert np.all(refined.upper >= refined.lower)
    assert np.all(refined.gap <= 0.01)
    untouched = plain.gap <= 0.01
    np.testing.assert_array_equal(refined.upper[untouched], plain.upper[untouched])


@settings(max_examples=15, deadline=None)
@given(base=st.sampled_from([9, 59, 195, 210]), seed=st.integers(0, 2 ** 32 - 1),
       size=st.floats(0, 0.03), spread=st.floats(0, 3))
def test_refined_bounds_stay_ordered_and_certified_near_wide_gaps(base, seed, size, spread):
    # a perturbed wide-gap matrix under a diagonal similarity (which leaves mu unchanged)
    g = np.random.default_rng(seed)
    scale = 10 ** g.uniform(-spread, spread, 8)
    M = (scale[:, None] / scale[None, :]) * (
        wide_gap_matrix(base) + size * (g.standard_normal((8, 8)) + 1j * g.standard_normal((8, 8))))
    plain = mussv(M, EIGHT)
    refined = mussv(M, EIGHT, refine=0.002)
    assert refined.lower[0] == plain.lower[0]
    assert refined.lower[0] <= refined.upper[0] <= plain.upper[0]
    if plain.gap[0] > 0.002:
        assert refined.upper[0] < plain.upper[0]
        Mb = balanced(M, plain)
        bound, theta = _refine_point(Mb, None, 0.0, 0.0, 60)
        S = _LiftedCertificate(Mb).multipliers(theta)
        assert certificate_holds(Mb, S, bound * (1 + 1e-9))


@pytest.mark.parametrize("refine, blk, lower, match", [
    (0, EIGHT, True, "refine must be"),
    (1.0, EIGHT, True, "refine must be"),
    (True, EIGHT, True, "refine must be"),
    ("0.01", EIGHT, True, "refine must be"),
    (0.01, [(1, 1)] * 6 + [(2, 2)], True, "complex scalar blocks"),
    (0.01, [(1, 1)] * 6 + [(2, 0)], True, "complex scalar blocks"),
    (0.01, [(-1, 0)] + [(1, 1)] * 7, True, "complex scalar blocks"),
    (0.01, EIGHT, False, "lower bound"),
])
def test_refine_rejects_what_it_cannot_do(refine, blk, lower, match):
    with pytest.raises(ValueError, match=match):
        mussv(np.eye(8), blk, refine=refine, lower=lower)


def test_refine_rejects_more_scalars_than_it_handles():
    with pytest.raises(ValueError, match="at most 10 scalar blocks"):
        mussv(np.eye(11), [(1, 1)] * 11, refine=0.01)
