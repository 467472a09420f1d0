"""Controller reduction and Tustin discretisation."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem.analysis import analyze
from piezolib.problem.design import design_controller
from piezolib.robust.discrete import discretize, least_damped_frequency
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


@pytest.fixture(scope="module")
def design():
    return design_controller()


def test_design_reduction_keeps_stability_and_reports_degradation(design):
    red = design.reduction
    assert red.order == 6 == design.K_reduced.nstates
    # small-gain certificate of the weighted reduction: ||(K - K6) G S|| < 1
    assert red.weighted_error < 1
    assert robust.is_stable(paper.plant(), design.K_reduced)
    full, reduced = analyze(design.K_full), analyze(design.K_reduced)
    # reduction can only cost mu here, and the cost is reported, not hidden
    assert reduced.mu_RP >= full.mu_RP * (1 - 1e-3)
    assert reduced.mu_RP - full.mu_RP < 0.1


def test_tustin_matches_below_1khz_and_is_exact_at_the_prewarp_frequency():
    K = ct.tf([1, 2 * 0.05 * 3000, 3000 ** 2], [1, 2 * 0.7 * 3000, 3000 ** 2])  # notch
    assert least_damped_frequency(K, 1e4) == pytest.approx(3000, rel=1e-9)
    d = discretize(K, prewarp="auto")
    assert d.prewarp_frequency == pytest.approx(3000, rel=1e-9)
    w0 = 3000.0
    kd = np.ravel(d.K(np.exp(1j * w0 / d.fs)))
    assert kd[0] == pytest.approx(np.ravel(K(1j * w0))[0], rel=1e-9)
    assert d.matches and d.max_relative_error < 0.1
    plain = discretize(K, prewarp=None)
    assert plain.max_relative_error > d.max_relative_error


def test_discretised_design_loop(design):
    d = design.discrete
    assert d.fs == paper.SAMPLING_FREQUENCY_HZ and d.K.dt == pytest.approx(1e-4)
    assert d.matches and d.loop_stable


def test_discretize_rejects_bad_input():
    with pytest.raises(ValueError, match="Nyquist"):
        discretize(ct.tf([1], [1, 1]), check_hz=6000)
    with pytest.raises(ValueError, match="continuous-time"):
        discretize(ct.tf([1], [1, 1], 1e-3))
