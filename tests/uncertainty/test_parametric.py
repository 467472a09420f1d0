"""Real parametric LFT of the denominator coefficients and the mu robust-stability margin."""

import control as ct
import numpy as np
import pytest

from piezolib import robust
from piezolib.uncertainty import (parametric_stability_margin, perturbed_plant,
                                  stability_gauge)
from piezolib.uncertainty.parametric import (mu_stability_margin, parametric_lft,
                                             parametric_loop_response, parametric_response)

# a lightly damped third-order plant with widely spread coefficients and a PI-like controller
G3 = ct.tf([2e3, 4e6], [1, 30, 4e4, 2e5], inputs="u", outputs="y")
K3 = ct.tf([0.05, 1], [1, 0.5], inputs="e", outputs="u")
W = np.logspace(-1, 4, 120)


def _upper_lft_response(P, q, omega):
    """F_u(P, diag(q)) on omega from P's own frequency response (no polynomial code)."""
    n = len(q)
    R = np.moveaxis(P(1j * omega, squeeze=False), -1, 0)
    M11, M12, M21, M22 = R[:, :n, :n], R[:, :n, n:], R[:, n:, :n], R[:, n:, n:]
    Q = np.diag(q)
    return (M22 + M21 @ Q @ np.linalg.solve(np.eye(n) - M11 @ Q, M12))[:, 0, 0]


@pytest.mark.parametrize("G", [G3, ct.tf([2.01e11, 4.74e15, 2.76e19, 1.84e23],
                                         [1, 1.08e4, 2.95e8, 1.98e12, 1.65e16, 5.79e19, 2.05e23]),
                               ct.tf([1, 2, 5], [1, 3, 7])], ids=["third", "sixth", "biproper"])
def test_lft_gives_every_perturbed_plant_exactly(G):
    spread = 0.05
    lft = parametric_lft(G, spread)
    n = len(lft.blk)
    assert lft.blk == ((-1, 0),) * n and lft.P.nstates == n
    assert lft.P.input_labels[:n] == [f"w_{i}" for i in range(n)]
    ws = lft.time_scale
    omega = ws * np.logspace(-2, 2, 80)
    rng = np.random.default_rng(3)
    for q in list(rng.uniform(-1, 1, (4, n))) + [np.ones(n), -np.ones(n)]:
        direct = np.ravel(perturbed_plant(G, spread, q)(1j * omega))
        np.testing.assert_allclose(_upper_lft_response(lft.P, q, omega), direct, rtol=1e-9)
    # the polynomial evaluation agrees with the realisation
    R = np.moveaxis(lft.P(1j * omega, squeeze=False), -1, 0)
    Rp = parametric_response(G, spread, omega)
    scale = np.abs(Rp).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(R - Rp) / scale) < 1e-10


def test_loop_matrix_is_the_closed_lft_and_has_rank_one():
    lft = parametric_lft(G3, 0.1, input_name="u", output_name="y")
    n = len(lft.blk)
    # close u = -K y with the toolkit's lower LFT: measurement e = -y
    flip = np.diag(np.r_[np.ones(n), -1.0])
    P = robust.with_signals(ct.ss([], [], [], flip) * lft.P, outputs=[f"z_{i}" for i in range(n)] + ["e"])
    M_lft = robust.lft_response(P, K3, W)
    M = parametric_loop_response(G3, K3, 0.1, W)
    np.testing.assert_allclose(M, M_lft, rtol=1e-8, atol=1e-12 * np.abs(M).max())
    assert np.all(np.linalg.svd(M, compute_uv=False)[:, 1] < 1e-12 * np.abs(M).max())


def test_mixed_mu_margin_matches_zero_exclusion():
    exact = parametric_stability_margin(G3, K3)
    real = mu_stability_margin(G3, K3, W, lower=True)
    # the certified spread cannot exceed the exact one (beyond the peak search)
    assert real.spread <= exact.spread * (1 + 1e-6)
    assert real.spread == pytest.approx(exact.spread, rel=1e-3)
    # the lower bound exhibits a destabilising member: its spread is not below the exact one
    assert real.spread_upper >= exact.spread * (1 - 1e-6)
    assert real.spread_upper == pytest.approx(exact.spread, rel=1e-3)
    mu = real.mu
    assert np.all(mu.lower <= mu.upper)
    # rank one, real blocks: mu = 1 / gauge (the lower bound reaches it on the grid)
    np.testing.assert_allclose(mu.lower, 1 / stability_gauge(G3, K3, W), rtol=1e-6)
    assert real.real and real.omega == pytest.approx(exact.omega, rel=1e-3)


def test_complex_blocks_give_the_disc_margin():
    cplx = mu_stability_margin(G3, K3, W, real=False, lower=True)
    # complex scalars on 1 m^T: mu = sum |m_i| exactly
    m = parametric_loop_response(G3, K3, 1.0, W)[:, 0, :]
    np.testing.assert_allclose(cplx.mu.upper, np.abs(m).sum(axis=1), rtol=1e-6)
    np.testing.assert_allclose(cplx.mu.lower, cplx.mu.upper, rtol=1e-6)
    # complex blocks are more conservative than the real ones
    assert cplx.spread < parametric_stability_margin(G3, K3).spread
    assert not cplx.real


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="spread"):
        parametric_lft(G3, 0.0)
    with pytest.raises(ValueError, match="spread"):
        parametric_lft(G3, np.nan)
    with pytest.raises(ValueError, match="G"):
        parametric_lft(ct.tf([1, 0, 0], [1, 1]), 0.1)            # improper
    with pytest.raises(ValueError, match="omega"):
        parametric_response(G3, 0.1, [-1.0, 2.0])
    with pytest.raises(ValueError, match="unstable"):
        mu_stability_margin(G3, -50 * K3, W)
    with pytest.raises(ValueError, match="omega"):
        mu_stability_margin(G3, K3, [10.0, 1.0, 100.0])
    with pytest.raises(TypeError, match="real"):
        mu_stability_margin(G3, K3, W, real=1)


def test_the_peak_only_margin_is_the_full_grid_margin():
    for real in (True, False):
        full = mu_stability_margin(G3, K3, W, real=real)
        fast = mu_stability_margin(G3, K3, W, real=real, peak=True)
        assert (fast.spread, fast.spread_upper, fast.omega) == (full.spread, full.spread_upper,
                                                                full.omega)
        assert np.all(fast.mu.upper >= full.mu.upper * (1 - 1e-9))     # still bounds
    with pytest.raises(ValueError, match="peak"):
        mu_stability_margin(G3, K3, W, peak=True, lower=True)
    with pytest.raises(TypeError, match="peak"):
        mu_stability_margin(G3, K3, W, peak="yes")
