"""Uncertainty weights: the inverse-notch shape, and the fit covering a relative-error envelope."""

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib import uncertainty as unc

OMEGA = np.logspace(0, 6, 60)


def _stable_min_phase(W):
    return np.all(ct.poles(W).real < 0) and np.all(ct.zeros(W).real < 0)


def test_fit_recovers_a_rational_envelope():
    # the envelope is itself the magnitude of a 2nd-order weight: excess ~ 0
    true = 0.02 * ct.tf(np.array([1, 2 * 0.8 * 30, 900]) / 900,
                        np.array([1, 2 * 0.1 * 40, 1600]) / 1600)
    w = np.logspace(0, 3, 300)
    env = np.abs(np.ravel(true(1j * w)))
    W = unc.fit_covering_weight(w, env, 2, inputs="u_c", outputs="y_Delta")
    res = unc.coverage(W, w, env)
    assert res.covers and _stable_min_phase(W)
    assert res.max_excess_dB < 0.05
    assert W.input_labels == ["u_c"] and W.output_labels == ["y_Delta"]


def test_default_signal_names_are_neutral():
    w = np.logspace(0, 3, 50)
    W = unc.fit_covering_weight(w, 1 / np.sqrt(1 + (w / 100) ** 2), 1)
    assert W.input_labels == ["u"] and W.output_labels == ["y_Delta"] and W.name == "W_m"


@pytest.mark.parametrize("order", [1, 4, 5])
def test_fitted_weight_covers_paper_envelope(order):
    w = np.logspace(1, 6, 300)
    env = unc.relative_error_envelope(unc.model_set(paper.plant(), spread=0.01), w)
    W = unc.fit_covering_weight(w, env, order)
    res = unc.coverage(W, w, env)
    assert res.covers and _stable_min_phase(W)
    assert len(ct.poles(W)) == order
    # a weight shaped like the envelope is tighter than the constant max(E)
    assert res.max_excess_dB < 20 * np.log10(env.max() / env.min())


def test_bad_inputs():
    with pytest.raises(ValueError, match="envelope must be positive"):
        unc.fit_covering_weight(OMEGA, np.zeros_like(OMEGA), 2)
    with pytest.raises(ValueError, match="order must be >= 1"):
        unc.fit_covering_weight(OMEGA, np.ones_like(OMEGA), 0)
    with pytest.raises(ValueError, match="envelope must have the shape"):
        unc.fit_covering_weight(OMEGA, np.ones(3), 2)


# --- the inverse-notch shape --------------------------------------------------

def test_inverse_notch_lifts_the_gain_by_the_damping_ratio_at_its_frequency():
    # eps = M = 1 makes the low-pass exactly 1, so |W(j omega_i)| = g zeta_z / zeta_p
    W = unc.inverse_notch_weight(0.1, [(50.0, 0.6, 0.02)], 3.0, 1.0, 1.0)
    assert abs(W(50.0j)) == pytest.approx(0.1 * 0.6 / 0.02, rel=1e-12)
    assert ct.dcgain(W) == pytest.approx(0.1, rel=1e-12)
    assert abs(W(1e6j)) == pytest.approx(0.1, rel=1e-6)
    assert _stable_min_phase(W)


def test_inverse_notch_limits_are_those_of_the_low_pass():
    W = unc.inverse_notch_weight(0.5, [(10.0, 0.5, 0.1), (200.0, 2.0, 0.3)], 1e3,
                                 lowpass_dc_gain=4.0, lowpass_hf_gain=1e-3)
    assert ct.dcgain(W) == pytest.approx(0.5 * 4.0, rel=1e-12)
    assert abs(W(1e12j)) == pytest.approx(0.5 * 1e-3, rel=1e-6)
    poles = np.sort_complex(ct.poles(W))
    assert len(poles) == 5 and np.all(poles.real < 0)
    # the low-pass's pole at omega_c / M and the sections' poles at |p| = omega_i
    assert np.min(np.abs(poles + 1e3 / 4.0)) < 1e-6 * 1e3
    assert sorted(np.round(np.abs(poles[np.abs(poles.imag) > 0]), 6)) == [10.0, 10.0, 200.0, 200.0]


def test_inverse_notch_without_sections_is_the_low_pass():
    W = unc.inverse_notch_weight(2.0, [], 10.0, 3.0, 0.0)
    assert W.input_labels == ["u"] and W.output_labels == ["y_Delta"] and W.name == "W_m"
    np.testing.assert_allclose(W.num[0][0], [2.0 * 10.0])           # strictly proper: eps = 0
    np.testing.assert_allclose(W.den[0][0], [1.0, 10.0 / 3.0])


@pytest.mark.parametrize("notches, match", [
    ([(10.0, 0.5)], "notches must be rows"),
    ([(10.0, 0.5, 0.0)], r"notches\[0\] zeta_poles must be positive"),
    ([(1.0, 0.5, 0.1), (-10.0, 0.5, 0.1)], r"notches\[1\] omega_rad_s must be positive"),
    ([(10.0, -0.5, 0.1)], r"notches\[0\] zeta_zeros must be non-negative"),
])
def test_inverse_notch_names_the_bad_section(notches, match):
    with pytest.raises(ValueError, match=match):
        unc.inverse_notch_weight(1.0, notches, 10.0)
