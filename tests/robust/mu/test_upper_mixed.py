"""Mixed real/complex upper bound (D,G scalings)."""

import numpy as np

from piezolib.robust.blocks import parse_blk
from piezolib.robust.mu import mussv
from piezolib.robust.mu.upper_mixed import mixed_upper_bound


def crandn(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


def lmi_max_eig(M, beta, Dl, Dr, G):
    """Largest eigenvalue of M^H Dl^2 M + j (G M - M^H G^T) - beta^2 Dr^2 (<= 0 certifies beta)."""
    MH = np.swapaxes(M, 1, 2).conj()
    lmi = (MH @ Dl ** 2 @ M + 1j * (G @ M - MH @ np.swapaxes(G, 1, 2))
           - beta[:, None, None] ** 2 * Dr ** 2)
    return np.linalg.eigvalsh(lmi).max(axis=1)


def test_badly_scaled_mixed_matrix_keeps_a_tight_bound():
    # scaling M by a structured similarity changes neither mu nor the bound
    rng = np.random.default_rng(1)
    blk = [(-1, 0), (1, 1), (-1, 0), (2, 2)]
    N = crandn(rng, 10, 5, 5)
    s = np.array([1e-8, 1.0, 1e8, 1e4, 1e4])
    M = s[:, None] * N / s[None, :]
    scaled, plain = mussv(M, blk), mussv(N, blk)
    np.testing.assert_allclose(scaled.upper, plain.upper, rtol=1e-3)
    assert np.all(scaled.gap <= plain.gap + 1e-3)


def test_certificate_holds_after_rescaling():
    rng = np.random.default_rng(2)
    blocks = parse_blk([(-1, 0), (1, 2), (-1, 0), (2, 1)], 5, 5)
    M = crandn(rng, 8, 5, 5) * 10 ** rng.uniform(-3, 3, (8, 5, 1))
    upper, d, g, Dl, Dr, G = mixed_upper_bound(M, blocks)
    # the certificate holds up to rounding relative to the size of its terms
    size = (np.linalg.norm(M, 2, axis=(1, 2)) ** 2 * np.abs(Dl).max(axis=(1, 2)) ** 2
            + 2 * np.abs(G).max(axis=(1, 2)) * np.linalg.norm(M, 2, axis=(1, 2))
            + upper ** 2 * np.abs(Dr).max(axis=(1, 2)) ** 2)
    assert np.all(lmi_max_eig(M, upper, Dl, Dr, G) <= 1e-7 * size)
    assert np.all(upper <= np.linalg.svd(M, compute_uv=False)[:, 0] * (1 + 1e-9))
    np.testing.assert_allclose(d[:, 3], 1.0)


def test_mixed_structures_have_nonzero_lower_bounds():
    rng = np.random.default_rng(3)
    for blk in ([(-1, 0), (1, 1), (-1, 0)], [(-1, 0), (2, 2), (-2, 0), (1, 1)]):
        p = sum(c if c else abs(r) for r, c in blk)
        M = crandn(rng, 30, p, p)
        res = mussv(M, blk)
        assert np.mean(res.lower > 0) >= 0.95
        assert np.median(res.gap) <= 0.05
