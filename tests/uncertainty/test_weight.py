"""Fit of a stable minimum-phase weight covering a relative-error envelope."""

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
