"""Lower LFT F_l(P, K) and its frequency response."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem import genplant

OMEGA = np.logspace(0, 6, 300)


def response(sys, omega=OMEGA):
    return np.moveaxis(sys(1j * omega, squeeze=False), -1, 0)


def test_lower_lft_is_the_closed_loop_formula():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((4, 4)) - 4 * np.eye(4)
    P = ct.ss(A, rng.standard_normal((4, 3)), rng.standard_normal((3, 4)),
              rng.standard_normal((3, 3)), inputs=["w1", "w2", "u"], outputs=["z1", "z2", "y"])
    K = ct.ss(ct.tf([2.0, 1.0], [1.0, 5.0]), inputs="y", outputs="u")
    w = np.logspace(-2, 2, 40)
    R, k = response(P, w), np.ravel(K(1j * w))
    expected = R[:, :2, :2] + (R[:, :2, 2:] * (k / (1 - R[:, 2, 2] * k))[:, None, None]
                               * R[:, 2:, :2])
    for omega_s in (None, 1.0, 37.0):
        M = robust.lower_lft(P, K, omega_s)
        assert M.input_labels == ["w1", "w2"] and M.output_labels == ["z1", "z2"]
        assert M.name == "M"
        np.testing.assert_allclose(response(M, w), expected, rtol=1e-9)
        np.testing.assert_allclose(robust.lft_response(P, K, w, omega_s), expected, rtol=1e-9)


def test_lower_lft_is_eq18():
    G, H_m, H_e, H_y, K = paper.problem()
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    M = robust.lower_lft(P, K)
    assert M.input_labels == ["u_Delta", "v_r"]
    assert M.output_labels == ["y_Delta", "y1", "y2"]
    s = 1j * OMEGA
    S, T, KS, GS = (np.ravel(f(s)) for f in robust.loop_functions(G, K))
    hm, he, hy = (np.ravel(h(s)) for h in (H_m, H_e, H_y))
    expected = np.stack([np.stack([-hm * T, hm * KS], -1),
                         np.stack([-he * GS, he * S], -1),
                         np.stack([hy * GS, hy * T], -1)], 1)
    for got in (response(M), robust.lft_response(P, K, OMEGA)):
        np.testing.assert_allclose(got, expected, rtol=1e-7, atol=1e-12)


def test_lower_lft_rejects_mismatched_sizes():
    G, K = paper.plant(), paper.controller()
    with pytest.raises(ValueError, match="too small"):
        robust.lower_lft(G, K)
    with pytest.raises(ValueError, match="too small"):
        robust.lft_response(G, K, OMEGA)
    with pytest.raises(ValueError, match="omega_s must be positive"):
        robust.lower_lft(ct.rss(2, 2, 2), ct.ss([], [], [], [[1.0]]), omega_s=-1.0)


def test_discrete_or_nan_models_are_rejected():
    # a discrete K used to come back as a continuous-time loop (dt lost)
    P = ct.ss([[-1.0]], [[1.0, 1.0]], [[1.0], [1.0]], np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"K must be continuous-time.*dt=0\.1"):
        robust.lower_lft(P, ct.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1))
    with pytest.raises(ValueError, match="K has a NaN coefficient"):
        robust.lower_lft(P, ct.tf([np.nan], [1.0, 1.0]))


def test_lft_response_at_an_open_loop_pole_on_the_axis():
    # P has an undamped pair at 10 rad/s and the grid hits it exactly: P(j10) does not
    # exist, the closed loop does; that point comes from the closed-loop realisation
    G = ct.ss(ct.tf([1.0], [1.0, 0.0, 100.0]))
    P = ct.ss(G.A, np.c_[G.B, G.B], np.r_[G.C, -G.C], [[0.0, 0.0], [0.0, 0.0]])
    K = ct.ss(ct.tf([30.0, 300.0], [1.0, 40.0]))
    w = np.array([1.0, 10.0, 100.0])
    M = robust.lft_response(P, K, w)
    expected = response(robust.lower_lft(P, K), w)
    np.testing.assert_allclose(M, expected, rtol=1e-9)
    assert np.all(np.isfinite(M))


def test_lft_response_names_a_closed_loop_pole_on_the_axis():
    # 1 - P22 K = (s^2 + 1)/(s^2 + 2) with P22 = 1/(s^2 + 2), K = 1: zero at s = j
    P22 = ct.ss(ct.tf([1.0], [1.0, 0.0, 2.0]))
    P = ct.ss(P22.A, np.c_[P22.B, P22.B], np.r_[P22.C, P22.C], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="singular at omega = 1 rad/s"):
        robust.lft_response(P, ct.ss([], [], [], [[1.0]]), [1.0])


def test_lft_hinf_norm_agrees_with_the_realisation_on_a_well_conditioned_loop():
    G, H_m, H_e, H_y, K = paper.problem()
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    grid = np.logspace(0, 7, 2000)
    peak, w_peak = robust.lft_hinf_norm(P, K, grid)
    ref, w_ref = robust.hinf_norm(robust.lower_lft(P, K), grid)
    assert peak == pytest.approx(ref, rel=1e-7) and w_peak == pytest.approx(w_ref, rel=1e-3)


def test_resolvent_condition_decides_as_the_exact_condition_number():
    # the cheap bound is exact wherever the threshold decision needs it
    from piezolib.robust.lft import _POLE_CONDITION, _resolvent_condition
    rng = np.random.default_rng(4)
    A = rng.standard_normal((12, 12)) @ np.diag(10 ** rng.uniform(-3, 3, 12))
    poles = np.linalg.eigvals(A)
    s = np.r_[1j * np.logspace(-3, 3, 300), poles[:4] * (1 + 10.0 ** -np.arange(4, 12, 2))]
    resolvent = s[:, None, None] * np.eye(12) - A
    exact, ours = np.linalg.cond(resolvent), _resolvent_condition(resolvent)
    assert np.any(exact > _POLE_CONDITION) and np.any(exact <= _POLE_CONDITION)
    assert np.array_equal(exact > _POLE_CONDITION, ours > _POLE_CONDITION)
    assert np.all(ours >= exact * (1 - 1e-9))
    assert np.allclose(ours[exact > _POLE_CONDITION], exact[exact > _POLE_CONDITION], rtol=1e-12)
    singular = np.stack([np.eye(3), np.diag([1.0, 1.0, 0.0])]).astype(complex)
    assert np.isinf(_resolvent_condition(singular)[1])
