"""ARX models by recursive least squares (eq. 1-3)."""

import numpy as np
import pytest

from piezolib import identification as I
from piezolib import paper

FS = paper.SAMPLING_FREQUENCY_HZ


def test_rls_recovers_exact_arx_coefficients(arx_system):
    u, y = arx_system.data()
    model = I.fit_arx(u, y, FS, na=3, nb=2, nk=1)
    assert np.allclose(model.a, arx_system.a, atol=1e-8, rtol=0)
    assert np.allclose(model.b, arx_system.b, atol=1e-8, rtol=0)
    hist = model.rls.history
    assert hist.shape == (len(y) - 3, 5)
    assert np.allclose(hist[-1], model.rls.parameters)
    # a priori errors vanish once the parameters are known
    assert np.max(np.abs(model.rls.a_priori_errors[-100:])) < 1e-8


@pytest.mark.parametrize("gain", [1e4, 1e8, 1e12])
def test_rls_equations_on_a_generic_regressor(gain):
    rng = np.random.default_rng(1)
    phi = rng.standard_normal((50, 3))
    psi = np.array([2.0, -1.0, 0.5])
    result = I.rls(phi, phi @ psi, initial_gain=gain)
    # in exact arithmetic eqs. 1-3 from Psi(0) = 0 give the regularised least-squares
    # estimate (W(0)^-1 + Phi' Phi)^-1 Phi' y, whose bias vanishes as the gain grows
    n = len(phi)
    W0_inv = np.diag(np.mean(phi ** 2, axis=0) / gain)
    regularised = np.linalg.solve(W0_inv + phi.T @ phi, phi.T @ (phi @ psi))
    bias = np.abs(np.linalg.solve(W0_inv + phi.T @ phi, W0_inv @ psi)).max()
    assert np.abs(regularised - psi).max() <= bias * (1 + 1e-6)
    # the covariance form cancels W(0) ~ gain down to ~1/N: each of the N updates leaves
    # a rounding error of order eps * gain in W, so Psi carries at most about
    # N eps gain |psi| (whichever BLAS kernel does the arithmetic)
    rounding = n * np.finfo(float).eps * gain * np.abs(psi).max()
    np.testing.assert_allclose(result.parameters, regularised, rtol=0, atol=rounding)
    np.testing.assert_allclose(result.parameters, psi, rtol=0, atol=bias + rounding)
    # one step by hand: eq. 1, 3, 2 with W(0) = g diag(1/theta^2) (the data
    # power of a one-sample record) and Psi(0) = 0
    g, theta, y0 = 10.0, phi[0], float(phi[0] @ psi)
    one = I.rls(phi[:1], [y0], initial_gain=g)
    W0 = np.diag(g / theta ** 2)
    w = W0 @ theta
    W = W0 - np.outer(w, w) / (1 + theta @ w)
    assert one.a_priori_errors[0] == y0
    assert np.allclose(one.history[0], W @ theta * y0)
    assert np.allclose(one.gain_matrix, W)


@pytest.mark.parametrize("u, y, match", [
    (np.r_[np.nan, np.ones(999)], np.ones(1000), "u contains 1 non-finite"),
    (np.ones(1000), np.ones(1000), "constant"),
    (np.arange(1000.0), np.ones(999), "equal lengths"),
    (np.random.default_rng(0).standard_normal(60), np.ones(60), "too short"),
    (np.sin(np.arange(2000) / 5.0), np.sin(np.arange(2000) / 5.0), "persistently exciting"),
])
def test_bad_data_raise(u, y, match):
    with pytest.raises(ValueError, match=match):
        I.fit_arx(u, y, FS)
    with pytest.raises(ValueError, match=match):
        I.identify(u, y, FS)


@pytest.mark.parametrize("scale_u, scale_y", [(1e4, 1.0), (1e-4, 1.0), (1.0, 1e5), (1e6, 1e-3)])
def test_fit_arx_is_invariant_to_units(arx_system, scale_u, scale_y):
    # regression: with W(0) = 1e10 I, u scaled by 1e4 turned a1 = 0.171 into -1929
    u, y = arx_system.data(n=3000, seed=4)
    y = y + 1e-3 * np.random.default_rng(5).standard_normal(len(y))   # not exactly ARX
    ref = I.fit_arx(u, y, FS, na=3, nb=2)
    scaled = I.fit_arx(u * scale_u, y * scale_y, FS, na=3, nb=2)
    np.testing.assert_allclose(scaled.a, ref.a, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(scaled.b * scale_u / scale_y, ref.b, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("gain", [1e300, 1e14, 0.0, -1.0, np.nan, np.inf])
def test_absurd_initial_gain_is_rejected(arx_system, gain):
    u, y = arx_system.data(n=500)
    with pytest.raises(ValueError, match="initial_gain"):
        I.fit_arx(u, y, FS, na=3, nb=2, initial_gain=gain)


@pytest.mark.parametrize("n, word", [(0, "empty"), (1, "too short")])
def test_empty_record_says_so(n, word):
    with pytest.raises(ValueError, match=f"u and y are {word}"):
        I.fit_arx(np.ones(n), np.ones(n), FS)
