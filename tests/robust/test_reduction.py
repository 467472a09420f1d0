"""Controller reduction by (weighted) balanced truncation and residualisation."""

import control as ct
import numpy as np
import pytest

from piezolib import robust
from piezolib.problem.analysis import analyze
from piezolib.robust.reduction import hankel_singular_values, reduce_controller


def known_system():
    """Stable 6th-order SISO system with well separated Hankel singular values."""
    sys = ct.tf([1], [1, 1]) * ct.tf([2, 10], [1, 10]) * ct.tf([1, 0.5, 100], [1, 4, 100]) \
        * ct.tf([50], [1, 50])
    return ct.ss(sys, inputs="v_e", outputs="u_b")


def test_balanced_truncation_error_bound():
    K = known_system()
    hsv = hankel_singular_values(K, omega_s=1.0)
    for order in (2, 3, 4):
        red = reduce_controller(K, order, omega_s=1.0)
        bound = 2 * hsv[order:].sum()          # Glover's bound for balanced truncation
        assert red.error <= bound * (1 + 1e-6)
        assert red.error >= hsv[order] * (1 - 1e-6)   # no order-k model beats sigma_{k+1}
        assert np.all(ct.poles(red.K).real < 0)
        assert red.K.input_labels == ["v_e"] and red.order == order


def test_hankel_singular_values_match_python_control():
    K = known_system()
    np.testing.assert_allclose(hankel_singular_values(K, omega_s=1.0),
                               np.sort(ct.hankel_singular_values(K))[::-1], rtol=1e-8)


def test_residualisation_keeps_dc_gain():
    K = known_system()
    red = reduce_controller(K, 3, method="residualize", omega_s=1.0)
    assert ct.dcgain(red.K) == pytest.approx(ct.dcgain(K), rel=1e-9)


def test_unstable_part_is_kept():
    K = ct.ss(ct.tf([1, 2], [1, -1]) * ct.tf([1], [1, 3, 2]) * ct.tf([5], [1, 5]))
    red = reduce_controller(K, 2, omega_s=1.0)
    assert red.n_unstable == 1
    assert np.any(np.isclose(ct.poles(red.K), 1.0))
    with pytest.raises(ValueError, match="unstable"):
        reduce_controller(K, 0, omega_s=1.0)


def test_bad_arguments():
    K = known_system()
    with pytest.raises(ValueError, match="exceeds"):
        reduce_controller(K, 9)
    with pytest.raises(ValueError, match="method"):
        reduce_controller(K, 2, method="chop")
    with pytest.raises(ValueError, match="weight must be stable"):
        reduce_controller(K, 2, ct.tf([1], [1, -1]))


def test_default_time_scale_comes_from_the_model():
    # Hankel singular values do not depend on the time unit; the default
    # scale (time_scale_of K and W) gives those of the unscaled model
    K = known_system()
    W = ct.tf([1], [1, 20])
    np.testing.assert_allclose(hankel_singular_values(K), hankel_singular_values(K, omega_s=1.0),
                               rtol=1e-8)
    np.testing.assert_allclose(hankel_singular_values(K, W),
                               hankel_singular_values(K, W, omega_s=1.0), rtol=1e-8)
    red, ref = reduce_controller(K, 3, W), reduce_controller(K, 3, W, omega_s=1.0)
    w = np.logspace(-2, 3, 50)
    np.testing.assert_allclose(red.K(1j * w), ref.K(1j * w), rtol=1e-6)
    assert red.weighted_error == pytest.approx(ref.weighted_error, rel=1e-6)
    with pytest.raises(ValueError, match="omega_s must be positive"):
        reduce_controller(K, 3, omega_s=0.0)


def test_design_reduction_keeps_stability_and_reports_degradation(paper_design, paper_models):
    design = paper_design
    red = design.reduction
    assert red.order == 6 == design.K_reduced.nstates
    # small-gain certificate of the weighted reduction: ||(K - K6) G S|| < 1
    assert red.weighted_error < 1
    assert robust.is_stable(paper_models[0], design.K_reduced)
    full = analyze(design.K_full, *paper_models)
    reduced = analyze(design.K_reduced, *paper_models)
    # reduction can only cost mu here, and the cost is reported, not hidden
    assert reduced.mu_RP >= full.mu_RP * (1 - 1e-3)
    assert reduced.mu_RP - full.mu_RP < 0.1
