"""Exact parametric stability margin (zero exclusion) and small-gain certificates."""

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib import uncertainty as unc

FAMILY_G = ct.tf([1, 3], [1, 1.5, 4, 2.5, 1.2])
FAMILY_K = ct.tf([0.3, 0.5], [0.05, 1.0])


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
    at_critical = unc.stability_gauge(G, K, np.array([res.omega]))[0]
    assert at_critical == pytest.approx(res.spread, rel=1e-8)


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


def test_bad_inputs():
    G, w = _third_order(), np.logspace(-2, 3, 50)
    with pytest.raises(ValueError, match="K must be proper"):
        unc.parametric_stability_margin(G, K=ct.tf([1, 0, 0], [1, 1]))
    with pytest.raises(TypeError, match="K must be a control"):
        unc.parametric_stability_margin(G, K=np.ones(3))
    with pytest.raises(TypeError, match="K is required"):
        unc.small_gain_spread(G, None, w)
    with pytest.raises(TypeError, match="K is required"):
        unc.weight_certified_spread(ct.tf([0.05], [1]), G, None, w)
    with pytest.raises(TypeError, match="G must be a control"):
        unc.parametric_stability_margin(None)
    with pytest.raises(ValueError, match="omega must be non-negative"):
        unc.stability_gauge(G, None, np.array([-1.0]))


# --- with a loop delay ------------------------------------------------------------

def _delayed_characteristic(G, K, spread, offsets, s, tau):
    """a_q(s) d(s) + b(s) n(s) e^{-s tau} of the member with ``offsets`` (numpy only)."""
    a, b = np.asarray(G.den[0][0], float), np.asarray(G.num[0][0], float)
    n_k, d_k = np.asarray(K.num[0][0], float), np.asarray(K.den[0][0], float)
    a = a / a[0]
    b = b / G.den[0][0][0]
    low = a[::-1].copy()                         # lowest power first
    low[:-1] = low[:-1] * (1 + spread * np.asarray(offsets))
    aq = np.polyval(low[::-1], s)
    return aq * np.polyval(d_k, s) + np.polyval(b, s) * np.polyval(n_k, s) * np.exp(-s * tau)


def test_delay_margin_tends_to_the_delay_free_one_and_its_critical_member_is_on_the_axis():
    G = paper.plant()
    K = ct.tf(paper.controller())
    free = unc.parametric_stability_margin(G, K)
    tiny = unc.parametric_stability_margin(G, K, delay=1e-12)
    assert tiny.spread == pytest.approx(free.spread, rel=1e-6)
    tau = 1.5e-4                                  # 1.5 samples at 10 kHz
    m = unc.parametric_stability_margin(G, K, delay=tau)
    assert m.nominal_stable and m.bounded and 0 < m.spread < free.spread
    # the critical member of the delayed loop has a root at j omega*: the characteristic
    # function vanishes there relative to its terms
    s = 1j * m.omega
    value = _delayed_characteristic(ct.tf(G), K, m.spread, m.offsets, s, tau)
    scale = abs(_delayed_characteristic(ct.tf(G), K, 0.0, m.offsets, s, 0.0))
    assert abs(value) < 1e-6 * scale
    with pytest.raises(ValueError, match="delay"):
        unc.parametric_stability_margin(G, K, delay=-1.0)
    with pytest.raises(ValueError, match="delay"):
        unc.parametric_stability_margin(G, None, delay=1e-4)


@pytest.mark.parametrize("delay", [1e-300, 1e-14, 1e-12, 1e-11])
def test_a_negligible_delay_gives_the_delay_free_margin(delay):
    # the 12th-order Pade polynomial of such a delay spans hundreds of decades: its roots
    # are lost to rounding (spread 0 and "nominally unstable" before, or a LinAlgError)
    G, K = ct.tf([1], [1, 3, 3, 1]), ct.tf([0.5], [1])
    free = unc.parametric_stability_margin(G, K)
    tiny = unc.parametric_stability_margin(G, K, delay=delay)
    assert tiny.nominal_stable and tiny.spread == pytest.approx(free.spread, rel=1e-6)


def test_any_delay_destabilises_a_loop_whose_gain_at_infinity_exceeds_one():
    # L = -2 (s + 2)/(s + 1): stable without delay (pole at -3), |L(j inf)| = 2
    G, K = ct.tf([1, 2], [1, 1]), ct.tf([-2.0], [1])
    assert unc.parametric_stability_margin(G, K).nominal_stable
    assert not unc.parametric_stability_margin(G, K, delay=1e-12).nominal_stable
