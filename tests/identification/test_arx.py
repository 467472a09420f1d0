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


def test_rls_equations_on_a_generic_regressor():
    rng = np.random.default_rng(1)
    phi = rng.standard_normal((50, 3))
    psi = np.array([2.0, -1.0, 0.5])
    result = I.rls(phi, phi @ psi, initial_gain=1e12)
    assert np.allclose(result.parameters, psi, atol=1e-8)
    # one step by hand: eq. 1, 3, 2 with W(0) = g I and Psi(0) = 0
    g, theta, y0 = 10.0, phi[0], float(phi[0] @ psi)
    one = I.rls(phi[:1], [y0], initial_gain=g)
    W = g * np.eye(3) - g * g * np.outer(theta, theta) / (1 + g * theta @ theta)
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
