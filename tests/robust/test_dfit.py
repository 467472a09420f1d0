"""Stable minimum-phase fits of magnitude data (D-scalings)."""

import control as ct
import numpy as np
import pytest

from piezolib.robust import sos
from piezolib.robust.dfit import fit_magnitude

W = np.logspace(-2, 3, 300)


def minphase(order):
    """Known stable minimum-phase biproper functions of order 2 and 4."""
    sec = ct.tf([1 / 5 ** 2, 2 * 0.3 / 5, 1], [1 / 50 ** 2, 2 * 0.1 / 50, 1])
    if order == 2:
        return 2 * sec
    return 2 * sec * ct.tf([1 / 0.1 ** 2, 2 * 1.5 / 0.1, 1], [1, 2 * 0.8, 1])


@pytest.mark.parametrize("order", [2, 4])
def test_fit_recovers_known_magnitude(order):
    true = minphase(order)
    fit = fit_magnitude(W, np.abs(np.ravel(true(1j * W))), order)
    assert fit.max_log_error < 1e-6
    assert np.all(ct.poles(fit.tf).real < 0) and np.all(ct.zeros(fit.tf).real < 0)
    w = np.logspace(-3, 4, 50)
    np.testing.assert_allclose(np.abs(np.ravel(fit.tf(1j * w))), np.abs(np.ravel(true(1j * w))),
                               rtol=1e-5)


def test_fit_of_order_zero_is_weighted_geometric_mean():
    mag = np.exp(np.linspace(0, 2, W.size))
    weight = np.linspace(1, 3, W.size)
    fit = fit_magnitude(W, mag, 0, weight)
    expected = np.exp(np.sum(weight * np.log(mag)) / weight.sum())
    assert ct.dcgain(fit.tf) == pytest.approx(expected)


def test_fit_is_always_stable_minimum_phase_on_rough_data():
    rng = np.random.default_rng(3)
    mag = np.exp(rng.standard_normal(W.size))
    for order in (1, 3, 5):
        fit = fit_magnitude(W, mag, order)
        assert fit.order == order and ct.poles(fit.tf).size == order
        assert np.all(ct.poles(fit.tf).real < 0) and np.all(ct.zeros(fit.tf).real < 0)


def test_parameters_are_the_shared_model_and_warm_start_the_next_fit():
    true = minphase(4)
    mag = np.abs(np.ravel(true(1j * W)))
    fit = fit_magnitude(W, mag, 4)
    assert fit.parameters.shape == (sos.n_parameters(4),)
    np.testing.assert_allclose(np.abs(np.ravel(fit.tf(1j * W))),
                               np.exp(sos.log_magnitude(fit.parameters, np.log(W), 4)), rtol=1e-9)
    again = fit_magnitude(W, mag, 4, n_starts=1, initial=fit)
    assert again.rms_log_error <= fit.rms_log_error * (1 + 1e-9)


def test_fit_rejects_bad_data():
    with pytest.raises(ValueError, match="magnitude must be positive"):
        fit_magnitude(W, -np.ones_like(W), 2)
    with pytest.raises(ValueError, match="equal lengths"):
        fit_magnitude(W, np.ones(3), 2)
    with pytest.raises(ValueError, match="non-finite"):
        fit_magnitude(W, np.full_like(W, np.nan), 2)
    with pytest.raises(ValueError, match="at least"):
        fit_magnitude(W[:5], np.ones(5), 4)
