"""LTI helpers: time scaling, realisation, closed-loop functions and norms."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust


@pytest.fixture(scope="module")
def loop():
    return paper.plant(), paper.controller()


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


def test_scale_time_preserves_response(loop):
    G, _ = loop
    Gs = robust.scale_time(G, 1e4)
    w = np.logspace(2, 5, 50)
    np.testing.assert_allclose(Gs(1j * w / 1e4), G(1j * w), rtol=1e-10)
    np.testing.assert_allclose(np.sort_complex(ct.poles(Gs) * 1e4),
                               np.sort_complex(ct.poles(G)), rtol=1e-9)


def test_time_scale_is_geometric_mean_of_extreme_pole_magnitudes():
    sys = ct.ss(ct.tf([1], [1, 101, 100]))                # poles -1, -100
    assert robust.time_scale_of(sys) == pytest.approx(10.0)
    # over several models, zero poles ignored, 1 for static models
    assert robust.time_scale_of(ct.tf([1], [1, 4]), ct.tf([1], [1, 0, 0]),
                                ct.tf([1], [1, 25])) == pytest.approx(10.0)
    assert robust.time_scale_of(ct.ss([], [], [], [[2.0]])) == 1.0
    with pytest.raises(TypeError):
        robust.time_scale_of("G")


def test_scaled_round_trip_keeps_response_and_names():
    sys = ct.ss(ct.tf([1e8, 1e12], [1, 2e3, 1e8]) * ct.tf([1], [1, 3.0]),
                inputs="u", outputs="y")
    ws = robust.time_scale_of(sys)
    scaled = robust.to_scaled(sys, ws)
    w = np.logspace(-1, 6, 60)
    np.testing.assert_allclose(scaled(1j * w / ws), sys(1j * w), rtol=1e-10)
    back = robust.from_scaled(scaled, ws, ["v"], ["z"], name="H")
    np.testing.assert_allclose(back(1j * w), sys(1j * w), rtol=1e-10)
    assert back.input_labels == ["v"] and back.output_labels == ["z"] and back.name == "H"
    renamed = robust.with_signals(sys, outputs=["w"])
    assert renamed.input_labels == ["u"] and renamed.output_labels == ["w"]
    np.testing.assert_array_equal(renamed.A, ct.ss(sys).A)


def test_realize_gives_the_same_model_in_ordinary_time(loop):
    _, K = loop                          # coefficients up to 1e23
    w = np.logspace(0, 6, 80)
    for omega_s in (None, 1e4):
        Kr = robust.realize(K, omega_s)
        assert isinstance(Kr, ct.StateSpace) and Kr.name == K.name
        assert Kr.input_labels == K.input_labels
        np.testing.assert_allclose(Kr(1j * w), K(1j * w), rtol=1e-9)


def test_loop_functions_identities(loop):
    G, K = loop
    w = np.logspace(0, 6, 200)
    s = 1j * w
    L = np.ravel(G(s)) * np.ravel(K(s))
    for omega_s in (None, 1e4):
        lf = robust.loop_functions(G, K, omega_s)
        S, T, KS, GS = (np.ravel(f(s)) for f in lf)
        np.testing.assert_allclose(S + T, 1, atol=1e-9)
        np.testing.assert_allclose(S, 1 / (1 + L), rtol=1e-7)
        np.testing.assert_allclose(KS, np.ravel(K(s)) / (1 + L), rtol=1e-7)
        np.testing.assert_allclose(GS, np.ravel(G(s)) / (1 + L), rtol=1e-7)
    assert lf.S.input_labels == ["v_r"] and lf.GS.input_labels == ["d"]
    assert lf.KS.output_labels == ["u_b"] and lf.T.name == "T"


def test_closed_loop_poles_match_characteristic_polynomial(loop):
    G, K = loop
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


def test_loop_functions_reject_mimo(loop):
    with pytest.raises(ValueError, match="G must be SISO"):
        robust.loop_functions(ct.rss(2, 2, 1), loop[1])


def test_scaled_coefficients_and_max_singular_value():
    # H(s) = 1e8 / (s^2 + 1e3 s + 1e8), so H(1e4 p) = 1 / (p^2 + 0.1 p + 1)
    num, den = robust.scaled_coefficients([1e8], [1, 1e3, 1e8], 1e4)
    np.testing.assert_allclose(num, [1.0], rtol=1e-15)
    np.testing.assert_allclose(den, [1.0, 0.1, 1.0], rtol=1e-15)
    # a static 1 x 2 gain [3, 4] has singular value 5 at every frequency
    static = ct.ss([], [], [], [[3.0, 4.0]])
    np.testing.assert_allclose(robust.max_singular_value(static, [0.0, 1.0, 1e3]), 5.0)


def test_frequency_grid():
    w = robust.frequency_grid(1.0, 1e3, 4)
    np.testing.assert_allclose(w, [1.0, 10.0, 100.0, 1000.0])
    with pytest.raises(ValueError, match="must exceed"):
        robust.frequency_grid(10.0, 1.0)


@pytest.mark.parametrize("sys, match", [
    (ct.tf([1, 2, 1], [1, 2]), "sys must be proper"),          # used to return 1e9
    (ct.tf([1], [1, 0.5], 0.01), "sys must be continuous-time"),
    (ct.tf([1], [1, np.nan]), "sys has a NaN coefficient"),
])
def test_hinf_norm_rejects_improper_discrete_and_nan(sys, match):
    with pytest.raises(ValueError, match=match):
        robust.hinf_norm(sys)
