"""Parametric model set, envelopes, covering weights and exact margins."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, uncertainty as unc

OMEGA = np.logspace(0, 6, 60)


# --- the model set ---------------------------------------------------------------
def test_model_set_size_and_levels():
    mset = unc.model_set()
    assert mset.size == 3 ** 6 and mset.order == 6
    assert set(np.unique(mset.offsets)) == {-1.0, 0.0, 1.0}
    # the nominal member (all offsets 0) is the published plant
    nominal = np.flatnonzero(np.all(mset.offsets == 0, axis=1))[0]
    np.testing.assert_allclose(mset.denominators[nominal], paper.PLANT.den, rtol=1e-15)
    four = unc.model_set(spread=0.02, levels=4)
    assert four.size == 4 ** 6
    np.testing.assert_allclose(np.unique(four.offsets), [-1, -1 / 3, 1 / 3, 1])


def test_vectorised_responses_equal_a_loop_over_members():
    mset = unc.model_set(spread=0.05)
    G = mset.plant
    fast = unc.set_response(mset, OMEGA)
    errors = unc.relative_errors(mset, OMEGA)
    g0 = np.ravel(G(1j * OMEGA))
    for k in range(mset.size):
        direct = np.ravel(mset.member(k)(1j * OMEGA))
        np.testing.assert_allclose(fast[k], direct, rtol=1e-9)
        np.testing.assert_allclose(errors[k], np.abs(direct / g0 - 1), rtol=1e-6, atol=1e-12)


def test_member_poles_and_unstable_members_match_np_roots():
    mset = unc.model_set(spread=0.05)
    poles = unc.member_poles(mset)
    for k in (0, 17, 364, 728):
        np.testing.assert_allclose(np.sort_complex(poles[k]),
                                   np.sort_complex(np.roots(mset.denominators[k])), rtol=1e-8)
    direct = [k for k in range(mset.size) if np.roots(mset.denominators[k]).real.max() >= 0]
    np.testing.assert_array_equal(unc.unstable_members(mset), direct)


def test_member_closed_loop_poles_match_characteristic_polynomial():
    mset = unc.model_set(spread=0.05)
    K = paper.controller()
    poles = unc.member_closed_loop_poles(mset, K)
    for k in (0, 200, 728):
        char = np.polyadd(np.polymul(mset.denominators[k], K.den[0][0]),
                          np.polymul(mset.plant.num[0][0], K.num[0][0]))
        expected = np.sort_complex(np.roots(char))
        np.testing.assert_allclose(np.sort(np.abs(poles[k])), np.sort(np.abs(expected)), rtol=1e-6)


def test_envelope_stable_versus_all():
    mset = unc.model_set(spread=0.05)
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


def test_envelope_peak_is_refined_above_the_grid_value():
    mset = unc.model_set(spread=0.05)
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


# --- covering-weight fit -------------------------------------------------------------
def _stable_min_phase(W):
    return np.all(ct.poles(W).real < 0) and np.all(ct.zeros(W).real < 0)


def test_fit_recovers_a_rational_envelope():
    # the envelope is itself the magnitude of a 2nd-order weight: excess ~ 0
    true = 0.02 * ct.tf(np.array([1, 2 * 0.8 * 30, 900]) / 900,
                        np.array([1, 2 * 0.1 * 40, 1600]) / 1600)
    w = np.logspace(0, 3, 300)
    env = np.abs(np.ravel(true(1j * w)))
    W = unc.fit_covering_weight(w, env, 2)
    res = unc.coverage(W, w, env)
    assert res.covers and _stable_min_phase(W)
    assert res.max_excess_dB < 0.05
    assert W.input_labels == ["u_c"] and W.output_labels == ["y_Delta"]


@pytest.mark.parametrize("order", [1, 4, 5])
def test_fitted_weight_covers_paper_envelope(order):
    w = np.logspace(1, 6, 300)
    env = unc.relative_error_envelope(unc.model_set(spread=0.01), w)
    W = unc.fit_covering_weight(w, env, order)
    res = unc.coverage(W, w, env)
    assert res.covers and _stable_min_phase(W)
    assert len(ct.poles(W)) == order
    # a weight shaped like the envelope is tighter than the constant max(E)
    assert res.max_excess_dB < 20 * np.log10(env.max() / env.min())


# --- exact parametric margin ---------------------------------------------------------
def _third_order():
    return ct.tf([1], [1, 2, 2, 1])      # a2 = a1 = 2, a0 = 1


def test_open_loop_margin_third_order_hurwitz():
    # s^3 + a2 s^2 + a1 s + a0 is stable iff a2 a1 > a0; the worst member has
    # a2, a1 at -delta and a0 at +delta: 4 (1 - d)^2 = 1 + d
    res = unc.parametric_stability_margin(_third_order())
    assert res.bounded and res.nominal_stable
    assert res.spread == pytest.approx((9 - np.sqrt(33)) / 8, rel=1e-8)
    # the critical crossing of s^3 + a2 s^2 + a1 s + a0 is at w^2 = a1
    assert res.omega == pytest.approx(np.sqrt(2 * (1 - res.spread)), rel=1e-6)
    np.testing.assert_allclose(res.offsets, [1, -1, -1])


def test_critical_member_has_its_poles_on_the_axis():
    res = unc.parametric_stability_margin(_third_order())
    critical = unc.perturbed_plant(_third_order(), res.spread, res.offsets)
    poles = ct.poles(critical)
    assert np.min(np.abs(poles - 1j * res.omega)) < 1e-8 * res.omega
    np.testing.assert_allclose(critical.den[0][0],
                               [1, 2 * (1 - res.spread), 2 * (1 - res.spread), 1 + res.spread])
    with pytest.raises(ValueError, match="offsets must lie in"):
        unc.perturbed_plant(_third_order(), 0.1, [0.0, 2.0, 0.0])


def test_closed_loop_margin_with_gain_hurwitz():
    # with K = 1 the characteristic polynomial is s^3 + 2 s^2 + 2 s + 2:
    # 4 (1 - d)^2 = 1 + d + 1  ->  d = 1/4
    res = unc.parametric_stability_margin(_third_order(), ct.tf([1], [1]))
    assert res.spread == pytest.approx(0.25, rel=1e-8)


def test_unbounded_and_unstable_nominal_cases():
    second = ct.tf([1], [1, 1, 1])
    res = unc.parametric_stability_margin(second, spread_max=0.9)
    assert not res.bounded and res.spread == 0.9
    res = unc.parametric_stability_margin(_third_order(), ct.tf([10], [1]))
    assert not res.nominal_stable and res.spread == 0.0


def _closed_loop_unstable(G, K, q, spread):
    a = np.asarray(G.den[0][0], dtype=float)[::-1].copy()
    a[:-1] *= 1 + spread * q
    char = np.polyadd(np.polymul(a[::-1], K.den[0][0]), np.polymul(G.num[0][0], K.num[0][0]))
    return np.roots(char).real.max() >= 0


FAMILY_G = ct.tf([1, 3], [1, 1.5, 4, 2.5, 1.2])
FAMILY_K = ct.tf([0.3, 0.5], [0.05, 1.0])


def test_exact_margin_agrees_with_brute_force_sampling():
    G, K = FAMILY_G, FAMILY_K
    res = unc.parametric_stability_margin(G, K)
    assert res.bounded and res.nominal_stable
    rng = np.random.default_rng(7)
    samples = np.r_[unc.level_offsets(2, 4), unc.level_offsets(3, 4),
                    rng.uniform(-1, 1, (400, 4))]
    spreads = res.spread * np.linspace(0.9, 1.2, 31)
    destabilising = [d for d in spreads
                     if any(_closed_loop_unstable(G, K, q, d) for q in samples)]
    assert destabilising, "sampling found no unstable member up to 1.2 delta*"
    smallest = min(destabilising)
    # the exact margin is never larger than a destabilising sample ...
    assert res.spread <= smallest
    # ... and sampling reaches it (the critical member is on the box boundary)
    assert smallest <= res.spread * 1.011
    # just below delta* every sample is stable, the critical member crosses at j w*
    assert not any(_closed_loop_unstable(G, K, q, res.spread * 0.999) for q in samples)
    a = np.asarray(G.den[0][0], dtype=float)[::-1].copy()
    a[:-1] *= 1 + res.spread * res.offsets
    char = np.polyadd(np.polymul(a[::-1], K.den[0][0]), np.polymul(G.num[0][0], K.num[0][0]))
    roots = np.roots(char)
    k = np.argmin(np.abs(roots - 1j * res.omega))
    assert abs(roots[k] - 1j * res.omega) < 1e-6 * res.omega


def _kharitonov_pattern(n, which):
    # offsets of the four Kharitonov polynomials, lowest power first
    base = {1: [-1, -1, 1, 1], 2: [1, 1, -1, -1], 3: [1, -1, -1, 1], 4: [-1, 1, 1, -1]}[which]
    return np.resize(np.array(base, dtype=float), n)


def test_exact_margin_matches_kharitonov_segments():
    # the box is an interval polynomial; by the generalised Kharitonov theorem
    # the closed loops of the four Kharitonov segments decide its stability
    G, K = FAMILY_G, FAMILY_K
    res = unc.parametric_stability_margin(G, K)
    segments = [(1, 3), (1, 4), (2, 3), (2, 4)]
    lam = np.linspace(0, 1, 201)

    def any_unstable(spread):
        for i, j in segments:
            qi, qj = _kharitonov_pattern(4, i), _kharitonov_pattern(4, j)
            if any(_closed_loop_unstable(G, K, (1 - t) * qi + t * qj, spread) for t in lam):
                return True
        return False

    assert not any_unstable(res.spread * (1 - 1e-4))
    assert any_unstable(res.spread * (1 + 1e-3))


def test_gauge_on_grid_bounds_the_margin():
    G, K = paper.plant(), paper.controller()
    res = unc.parametric_stability_margin(G, K)
    gauge = unc.stability_gauge(G, K, np.logspace(2, 6, 3000))
    assert gauge.min() >= res.spread * (1 - 1e-9)
    assert unc.stability_gauge(G, K, np.array([res.omega]))[0] == pytest.approx(res.spread, rel=1e-8)


def test_small_gain_certificate_is_conservative():
    G, K = FAMILY_G, FAMILY_K
    exact = unc.parametric_stability_margin(G, K)
    open_loop = unc.parametric_stability_margin(G)
    sg = unc.small_gain_spread(G, K, np.logspace(-2, 3, 800))
    assert sg.bounded and sg.lower < sg.upper
    assert 0 < sg.spread <= min(exact.spread, open_loop.spread)


def test_weight_certified_spread_needs_small_gain():
    G, K = FAMILY_G, FAMILY_K
    norm, bracket = unc.weight_certified_spread(ct.tf([100], [1]), G, K, np.logspace(-2, 3, 200))
    assert norm > 1 and bracket.spread == 0.0
    norm, bracket = unc.weight_certified_spread(ct.tf([0.05], [1]), G, K, np.logspace(-2, 3, 200))
    assert norm < 1 and bracket.spread > 0


# --- bad input -------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, error, match", [
    (dict(spread=0.0), ValueError, "spread must be positive"),
    (dict(spread=-0.05), ValueError, "spread must be positive"),
    (dict(spread=1.5), ValueError, "spread must be below 1"),
    (dict(levels=1), ValueError, "levels must be >= 2"),
    (dict(levels=2.5), TypeError, "levels must be an integer"),
    (dict(G=ct.tf([1, 0, 0], [1, 1])), ValueError, "G must be proper"),
    (dict(G="plant"), TypeError, "G must be a control"),
    (dict(G=ct.tf([1], [1])), ValueError, "at least one pole"),
])
def test_model_set_bad_input(kwargs, error, match):
    with pytest.raises(error, match=match):
        unc.model_set(**kwargs)


def test_other_bad_inputs():
    mset = unc.model_set(spread=0.01)
    with pytest.raises(ValueError, match="omega must be positive"):
        unc.set_response(mset, np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match="members must be one of"):
        unc.relative_error_envelope(mset, OMEGA, members="some")
    with pytest.raises(TypeError, match="mset must be a ModelSet"):
        unc.relative_errors("set", OMEGA)
    with pytest.raises(ValueError, match="weight must be proper"):
        unc.coverage(ct.tf([1, 0], [1]), OMEGA, np.ones_like(OMEGA))
    with pytest.raises(ValueError, match="envelope must have the shape"):
        unc.coverage(ct.tf([1], [1]), OMEGA, np.ones(3))
    with pytest.raises(ValueError, match="envelope must be positive"):
        unc.fit_covering_weight(OMEGA, np.zeros_like(OMEGA), 2)
    with pytest.raises(ValueError, match="order must be >= 1"):
        unc.fit_covering_weight(OMEGA, np.ones_like(OMEGA), 0)
    with pytest.raises(ValueError, match="K must be proper"):
        unc.parametric_stability_margin(K=ct.tf([1, 0, 0], [1, 1]))
    with pytest.raises(TypeError, match="K must be a control"):
        unc.parametric_stability_margin(K=np.ones(3))
    with pytest.raises(TypeError, match="K is required"):
        unc.small_gain_spread()
    with pytest.raises(ValueError, match="spread_max must be positive"):
        unc.largest_covered_spread(ct.tf([1], [1]), spread_max=-1)
