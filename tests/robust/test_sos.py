"""The gain-and-sections magnitude model shared by the D-fit and the covering-weight fit."""

import control as ct
import numpy as np
import pytest

from piezolib.robust import sos

LOG_OMEGA = np.log(np.logspace(-2, 3, 120))


def random_theta(order, seed):
    rng = np.random.default_rng(seed)
    theta = np.empty(sos.n_parameters(order))
    theta[0] = rng.normal()
    lower, upper = sos.parameter_bounds(order, (np.log(0.05), np.log(200.0)),
                                        (np.log(0.05), np.log(3.0)))
    theta[1:] = rng.uniform(lower[1:], upper[1:])
    return theta


def test_n_parameters_and_bounds_layout():
    assert [sos.n_parameters(n) for n in range(6)] == [1, 3, 5, 7, 9, 11]
    lower, upper = sos.parameter_bounds(3, (1.0, 2.0), (-3.0, 4.0), log_gain=(-5.0, 5.0))
    np.testing.assert_array_equal(lower, [-5, 1, -3, 1, -3, 1, 1])
    np.testing.assert_array_equal(upper, [5, 2, 4, 2, 4, 2, 2])
    lower, upper = sos.parameter_bounds(0, (1.0, 2.0), (-3.0, 4.0))
    assert lower.tolist() == [-np.inf] and upper.tolist() == [np.inf]
    with pytest.raises(ValueError, match="order must be >= 0"):
        sos.n_parameters(-1)


@pytest.mark.parametrize("order", [0, 1, 2, 3, 4, 5])
def test_jacobian_matches_finite_differences(order):
    theta = random_theta(order, order)
    value, J = sos.log_magnitude(theta, LOG_OMEGA, order, jacobian=True)
    np.testing.assert_array_equal(value, sos.log_magnitude(theta, LOG_OMEGA, order))
    assert J.shape == (LOG_OMEGA.size, theta.size)
    h = 1e-6
    for i in range(theta.size):
        step = np.zeros_like(theta)
        step[i] = h
        numeric = (sos.log_magnitude(theta + step, LOG_OMEGA, order)
                   - sos.log_magnitude(theta - step, LOG_OMEGA, order)) / (2 * h)
        np.testing.assert_allclose(J[:, i], numeric, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("order", [0, 1, 2, 3, 4, 5])
def test_transfer_function_magnitude_equals_the_model(order):
    theta = random_theta(order, 10 + order)
    H = sos.transfer_function(theta, order, inputs="u", outputs="y", name="H")
    omega = np.exp(LOG_OMEGA)
    np.testing.assert_allclose(np.log(np.abs(np.ravel(H(1j * omega)))),
                               sos.log_magnitude(theta, LOG_OMEGA, order), rtol=1e-9, atol=1e-9)
    # stable, minimum phase, biproper with |H(0)| = k
    assert len(ct.poles(H)) == order
    assert np.all(ct.poles(H).real < 0) and np.all(ct.zeros(H).real < 0)
    assert ct.dcgain(H) == pytest.approx(np.exp(theta[0]), rel=1e-12)
    assert H.input_labels == ["u"] and H.output_labels == ["y"] and H.name == "H"


def test_known_section():
    # k = 2, zero pair at 10 rad/s (zeta 0.5), pole pair at 100 rad/s (zeta 0.3)
    theta = np.log([2.0, 10.0, 0.5, 100.0, 0.3])
    H = 2 * ct.tf([1 / 100, 2 * 0.5 / 10, 1], [1 / 1e4, 2 * 0.3 / 100, 1])
    omega = np.array([1e-3, 10.0, 100.0, 1e4])
    np.testing.assert_allclose(np.exp(sos.log_magnitude(theta, np.log(omega), 2)),
                               np.abs(np.ravel(H(1j * omega))), rtol=1e-12)


def test_theta_of_the_wrong_length_is_refused():
    with pytest.raises(ValueError, match=r"theta must have shape \(5,\) for order 2"):
        sos.log_magnitude(np.zeros(4), LOG_OMEGA, 2)
    with pytest.raises(ValueError, match="theta must have shape"):
        sos.transfer_function(np.zeros(3), 2)
