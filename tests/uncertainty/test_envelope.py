"""Relative errors, their envelope and refined peak, the exact box bound and coverage."""

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib import uncertainty as unc

OMEGA = np.logspace(0, 6, 60)


@pytest.fixture(scope="module")
def paper_set():
    return unc.model_set(paper.plant(), 0.05, 3)


def test_vectorised_relative_errors_equal_a_loop_over_members(paper_set):
    mset = paper_set
    errors = unc.relative_errors(mset, OMEGA)
    g0 = np.ravel(mset.plant(1j * OMEGA))
    for k in range(mset.size):
        direct = np.ravel(mset.member(k)(1j * OMEGA))
        np.testing.assert_allclose(errors[k], np.abs(direct / g0 - 1), rtol=1e-6, atol=1e-12)


def test_envelope_stable_versus_all(paper_set):
    mset = paper_set
    errors = unc.relative_errors(mset, OMEGA)
    bad = unc.unstable_members(mset)
    stable = np.setdiff1d(np.arange(mset.size), bad)
    np.testing.assert_array_equal(unc.relative_error_envelope(mset, OMEGA, "all"), errors.max(0))
    np.testing.assert_array_equal(unc.relative_error_envelope(mset, OMEGA, "stable"),
                                  errors[stable].max(0))


def test_envelope_of_first_order_plant_is_known():
    # G = 1/(s + 1), a0 -> 1 +- delta: E(w) = delta / |j w + 1 - delta|
    G = ct.tf([1], [1, 1])
    delta = 0.1
    mset = unc.model_set(G, spread=delta, levels=2)
    w = np.logspace(-2, 2, 30)
    expected = delta / np.abs(1j * w + 1 - delta)
    np.testing.assert_allclose(unc.relative_error_envelope(mset, w), expected, rtol=1e-12)
    np.testing.assert_allclose(unc.relative_error_bound(G, delta, w), expected, rtol=1e-12)


def test_envelope_peak_is_refined_above_the_grid_value(paper_set):
    mset = paper_set
    peak, w_peak, member = unc.envelope_peak(mset, OMEGA)
    assert peak >= unc.relative_error_envelope(mset, OMEGA).max()
    assert member not in unc.unstable_members(mset)
    value = unc.relative_errors(mset, np.array([w_peak]))[member, 0]
    assert value == pytest.approx(peak, rel=1e-9)


def test_box_bound_dominates_dense_samples_and_is_attained():
    G = ct.tf([1, 2], [1, 1.2, 3, 1.5])
    delta = 0.2
    w = np.logspace(-1, 1.5, 80)
    bound = unc.relative_error_bound(G, delta, w)
    rng = np.random.default_rng(1)
    q = np.r_[unc.level_offsets(2, 3), rng.uniform(-1, 1, (3000, 3)),
              # points on the box edges, where the maximum may sit
              np.clip(rng.choice([-1.0, 1.0], (3000, 3)) + rng.uniform(-2, 0, (3000, 1))
                      * np.eye(3)[rng.integers(0, 3, 3000)], -1, 1)]
    sampled = unc.relative_errors(unc.ModelSet(G, delta, 2, q), w).max(axis=0)
    assert np.all(bound >= sampled * (1 - 1e-12))
    np.testing.assert_allclose(bound, sampled, rtol=2e-2)


# --- coverage ----------------------------------------------------------------------
def test_coverage_on_hand_made_cases():
    w = np.array([1.0, 10.0, 100.0])
    result = unc.coverage(ct.tf([2], [1]), w, np.array([1.0, 1.5, 2.5]))
    assert not result.covers
    assert result.worst_ratio == pytest.approx(0.8)
    assert result.omega_worst == 100.0
    assert result.max_excess_dB == pytest.approx(20 * np.log10(2))
    ok = unc.coverage(ct.tf([2], [1]), w, np.array([1.0, 1.5, 2.0]))
    assert ok.covers and ok.worst_ratio == pytest.approx(1.0)
    # |10/(s+10)| = 10/sqrt(w^2 + 100): exactly on the envelope
    lowpass = ct.tf([10], [1, 10])
    env = 10 / np.sqrt(w ** 2 + 100)
    res = unc.coverage(lowpass, w, env)
    assert res.worst_ratio == pytest.approx(1.0, rel=1e-12)
    assert abs(res.max_excess_dB) < 1e-9


def test_largest_covered_spread_first_order_known_value():
    # levels 2, G = 1/(s+1): sup_w E = delta/(1 - delta) at w -> 0, so the
    # constant weight c covers the set exactly up to delta = c/(1 + c)
    G = ct.tf([1], [1, 1])
    c = 0.25
    w = np.logspace(-6, 3, 400)
    res = unc.largest_covered_spread(ct.tf([c], [1]), G, w, levels=2, rtol=1e-6)
    assert res.bounded and res.lower <= c / (1 + c) <= res.upper
    assert res.spread == pytest.approx(c / (1 + c), rel=1e-5)
    box = unc.largest_covered_spread(ct.tf([c], [1]), G, w, levels=None, rtol=1e-6)
    assert box.spread == pytest.approx(c / (1 + c), rel=1e-5)


def test_largest_covered_spread_unbounded_is_reported():
    G = ct.tf([1], [1, 1])
    res = unc.largest_covered_spread(ct.tf([100], [1]), G, OMEGA, levels=2, spread_max=0.5)
    assert not res.bounded and res.spread == 0.5


def test_bad_inputs():
    mset = unc.model_set(paper.plant(), spread=0.01)
    with pytest.raises(ValueError, match="members must be one of"):
        unc.relative_error_envelope(mset, OMEGA, members="some")
    with pytest.raises(TypeError, match="mset must be a ModelSet"):
        unc.relative_errors("set", OMEGA)
    with pytest.raises(ValueError, match="omega must be positive"):
        unc.relative_errors(mset, np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match="weight must be proper"):
        unc.coverage(ct.tf([1, 0], [1]), OMEGA, np.ones_like(OMEGA))
    with pytest.raises(ValueError, match="envelope must have the shape"):
        unc.coverage(ct.tf([1], [1]), OMEGA, np.ones(3))
    with pytest.raises(ValueError, match="spread_max must be positive"):
        unc.largest_covered_spread(ct.tf([1], [1]), ct.tf([1], [1, 1]), OMEGA, spread_max=-1)
    with pytest.raises(ValueError, match="spread must be below 1"):
        unc.relative_error_bound(ct.tf([1], [1, 1]), 1.0, OMEGA)
