"""Performance weights on S and T: their templates' levels, poles and orders."""

import control as ct
import numpy as np
import pytest

from piezolib import robust


@pytest.mark.parametrize("order", [1, 2, 3])
def test_sensitivity_template_levels(order):
    W = robust.sensitivity_weight(1e-2, 2.0, 50.0, order=order)
    # 1/|W_S| is the template on |S|: A^n at DC, M^n at high frequency
    assert 1 / ct.dcgain(W) == pytest.approx(1e-2 ** order, rel=1e-12)
    assert 1 / abs(W(1e9j)) == pytest.approx(2.0 ** order, rel=1e-6)
    np.testing.assert_allclose(ct.poles(W), -50.0 * 1e-2, rtol=1e-4)   # n-fold at -omega_b A
    assert np.all(ct.zeros(W).real < 0)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_complementary_template_levels(order):
    W = robust.complementary_sensitivity_weight(1.5, 1e-3, 400.0, order=order)
    # 1/|W_T| is the template on |T|: M^n at DC, eps^n at high frequency
    assert 1 / ct.dcgain(W) == pytest.approx(1.5 ** order, rel=1e-12)
    assert 1 / abs(W(1e12j)) == pytest.approx(1e-3 ** order, rel=1e-6)
    np.testing.assert_allclose(ct.poles(W), -400.0 / 1e-3, rtol=1e-4)  # n-fold at -omega_b/eps
    assert np.all(ct.zeros(W).real < 0)


def test_an_order_n_weight_is_the_n_th_power_of_the_first_order_one():
    omega = np.logspace(-2, 6, 50)
    for build in (robust.sensitivity_weight, robust.complementary_sensitivity_weight):
        one, three = build(0.2, 3.0, 10.0), build(0.2, 3.0, 10.0, order=3)
        np.testing.assert_allclose(three(1j * omega), one(1j * omega) ** 3, rtol=1e-12)


def test_signal_names_default_to_neutral_ones_and_can_be_set():
    W_S = robust.sensitivity_weight(0.1, 2.0, 1.0)
    W_T = robust.complementary_sensitivity_weight(1.5, 0.1, 1.0, inputs="v_y", outputs="z2",
                                                  name="H_y")
    assert (W_S.input_labels, W_S.output_labels, W_S.name) == (["e"], ["z_e"], "W_S")
    assert (W_T.input_labels, W_T.output_labels, W_T.name) == (["v_y"], ["z2"], "H_y")


@pytest.mark.parametrize("build", [robust.sensitivity_weight,
                                   robust.complementary_sensitivity_weight])
def test_order_must_be_a_positive_integer(build):
    with pytest.raises(ValueError, match="order must be >= 1"):
        build(0.1, 2.0, 1.0, order=0)
    with pytest.raises(TypeError, match="order must be an integer"):
        build(0.1, 2.0, 1.0, order=1.5)
