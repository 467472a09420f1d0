"""Closed-loop functions and norms on cases with known answers."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust


def test_hinf_norm_of_resonant_second_order():
    zeta, wn = 0.05, 1e4
    sys = ct.tf([wn ** 2], [1, 2 * zeta * wn, wn ** 2])
    peak, w_peak = robust.hinf_norm(sys)
    assert peak == pytest.approx(1 / (2 * zeta * np.sqrt(1 - zeta ** 2)), rel=1e-8)
    assert w_peak == pytest.approx(wn * np.sqrt(1 - 2 * zeta ** 2), rel=1e-4)


def test_hinf_norm_dc_peak_and_unstable_rejected():
    assert robust.hinf_norm(ct.tf([2], [1, 1])) == (pytest.approx(2.0), 0.0)
    with pytest.raises(ValueError, match="must be stable"):
        robust.hinf_norm(ct.tf([1], [1, -1]))


def test_scale_time_preserves_response():
    G = paper.plant()
    Gs = robust.scale_time(G, 1e4)
    w = np.logspace(2, 5, 50)
    np.testing.assert_allclose(Gs(1j * w / 1e4), G(1j * w), rtol=1e-10)
    np.testing.assert_allclose(np.sort_complex(ct.poles(Gs) * 1e4),
                               np.sort_complex(ct.poles(G)), rtol=1e-9)


def test_loop_functions_identities():
    G, K = paper.plant(), paper.controller()
    lf = robust.loop_functions(G, K)
    w = np.logspace(0, 6, 200)
    s = 1j * w
    S, T, KS, GS = (np.ravel(f(s)) for f in lf)
    np.testing.assert_allclose(S + T, 1, atol=1e-9)
    L = np.ravel(G(s)) * np.ravel(K(s))
    np.testing.assert_allclose(S, 1 / (1 + L), rtol=1e-7)
    np.testing.assert_allclose(KS, np.ravel(K(s)) / (1 + L), rtol=1e-7)
    np.testing.assert_allclose(GS, np.ravel(G(s)) / (1 + L), rtol=1e-7)


def test_closed_loop_poles_match_characteristic_polynomial():
    G, K = paper.plant(), paper.controller()
    char = np.polyadd(np.polymul(G.den[0][0], K.den[0][0]),
                      np.polymul(G.num[0][0], K.num[0][0]))
    expected = np.sort_complex(np.roots(char))
    got = robust.closed_loop_poles(G, K)
    np.testing.assert_allclose(np.sort(np.abs(got)), np.sort(np.abs(expected)), rtol=1e-6)
    assert robust.is_stable(G, K)
    assert robust.is_stable(G, -K) is False


def test_bandwidth_of_first_order():
    # |100/(jw + 100)| = -3 dB exactly at w = 100 sqrt(10**0.3 - 1)
    expected = 100 * np.sqrt(10 ** 0.3 - 1)
    assert robust.bandwidth(ct.tf([100], [1, 100])) == pytest.approx(expected, rel=1e-4)


def test_loop_functions_reject_mimo():
    with pytest.raises(ValueError, match="G must be SISO"):
        robust.loop_functions(ct.rss(2, 2, 1), paper.controller())


def test_scaled_coefficients_and_max_singular_value():
    # H(s) = 1e8 / (s^2 + 1e3 s + 1e8), so H(1e4 p) = 1 / (p^2 + 0.1 p + 1)
    num, den = robust.scaled_coefficients([1e8], [1, 1e3, 1e8], 1e4)
    np.testing.assert_allclose(num, [1.0], rtol=1e-15)
    np.testing.assert_allclose(den, [1.0, 0.1, 1.0], rtol=1e-15)
    # a static 1 x 2 gain [3, 4] has singular value 5 at every frequency
    static = ct.ss([], [], [], [[3.0, 4.0]])
    np.testing.assert_allclose(robust.max_singular_value(static, [0.0, 1.0, 1e3]), 5.0)
