"""Multi-loop and loop-at-a-time disk margins on textbook MIMO loops with known answers.

The spinning satellite (Doyle 1986; Skogestad and Postlethwaite, Example 3.12; MATLAB's
"MIMO Stability Margins for Spinning Satellite"): P = 1/(s^2 + a^2) [[s - a^2, a (s + 1)],
[-a (s + 1), s - a^2]].  With K = I, S = (I + P)^-1 = 1/(s + 1) [[s, -a], [a, s]], so
M = S - I/2 = 1/(2 (s + 1)) [[s - 1, -2a], [2a, s - 1]], a normal matrix (D = I is
optimal by its symmetry) whose largest singular value sqrt(1 + (w + 2a)^2) / (2 sqrt(1 + w^2))
peaks where w^2 + 2a w - 1 = 0, i.e. at w = sqrt(a^2 + 1) - a, at mu = (a + sqrt(a^2 + 1)) / 2:
alpha = 2 (sqrt(a^2 + 1) - a), 0.0998 for a = 10.
"""

import math

import control as ct
import numpy as np
import pytest

from piezolib.robust.margins import loop_margins
from piezolib.robust.mimo_margins import (disk_margin_mimo, loop_at_a_time_disk_margins,
                                          loop_margins_mimo)

s = ct.tf("s")


def satellite(a=10.0):
    return ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))


def static(D):
    return ct.ss([], [], [], np.asarray(D, float))


@pytest.mark.parametrize("a", [10.0, 5.0, 2.0])
def test_satellite_multiloop_margin_closed_form(a):
    m = disk_margin_mimo(satellite(a))
    assert m.alpha == pytest.approx(2 * (math.sqrt(a ** 2 + 1) - a), rel=1e-6)
    assert m.alpha_upper == pytest.approx(m.alpha, rel=1e-5)        # two scalars: mu = D bound
    assert m.frequency == pytest.approx(-a + math.sqrt(a ** 2 + 1), rel=1e-4)
    gmin, gmax = m.gain_margin
    assert gmin == pytest.approx((2 - m.alpha) / (2 + m.alpha), rel=1e-12)
    assert gmax == pytest.approx((2 + m.alpha) / (2 - m.alpha), rel=1e-12)
    assert m.phase_margin_deg == pytest.approx(math.degrees(2 * math.atan(m.alpha / 2)))


def test_satellite_loop_at_a_time_margins_are_large():
    # each loop alone (the other closed) sees L_i = 1/s: |S_i - 1/2| = 1/2, alpha = 2, 90 deg
    for m in loop_at_a_time_disk_margins(satellite()):
        assert m.alpha == pytest.approx(2.0, rel=1e-9)
        assert m.gain_margin[0] == pytest.approx(0.0, abs=1e-9) and m.gain_margin[1] > 1e12
        assert m.phase_margin_deg == pytest.approx(90.0, abs=1e-6)
    assert disk_margin_mimo(satellite()).alpha < 0.1              # together: a 10 % change


def test_satellite_loop_at_a_time_matches_siso_margins_of_the_broken_loop():
    # L_1: loop 1 broken, loop 2 closed, from the interconnection, through the SISO module
    L = satellite()
    for i in range(2):
        closed = np.diag([0.0 if j == i else 1.0 for j in range(2)])
        Li = ct.feedback(L, static(closed))[i, i]
        siso = loop_margins(ct.minreal(ct.tf(Li), verbose=False), ct.tf([1], [1]))
        assert loop_at_a_time_disk_margins(L)[i].alpha == pytest.approx(siso.disk_margin,
                                                                         rel=1e-6)


def brute_force_mu_2x2(M, n_radius=1500, n_phase=721):
    """1 / min max(|d1|, |d2|) over det(I - M diag(d1, d2)) = 0, scanning d1 = r e^{j phi}."""
    best = math.inf
    phi = np.exp(1j * np.linspace(0, 2 * np.pi, n_phase))
    for r in np.linspace(1e-3, 1.0, n_radius) * 0.2:
        d1 = r * phi
        d2 = (1 - M[0, 0] * d1) / (M[1, 1] - np.linalg.det(M) * d1)
        best = min(best, float(np.min(np.maximum(np.abs(d1), np.abs(d2)))))
    return 1.0 / best


def test_satellite_margin_against_brute_force_over_diagonal_perturbations():
    L = satellite()
    m = disk_margin_mimo(L)
    omega = np.r_[0.0, np.linspace(0.01, 0.2, 20)]
    mus = []
    for w in omega:
        S = np.linalg.inv(np.eye(2) + L(1j * w))
        mus.append(brute_force_mu_2x2(S - 0.5 * np.eye(2)))
    brute_alpha = 1.0 / max(mus)
    # the scan finds destabilising sizes >= the true one (grid of radii 1.3e-4 wide)
    assert m.alpha <= brute_alpha * (1 + 1e-9)
    assert brute_alpha == pytest.approx(m.alpha, rel=3e-3)


def test_worst_factors_destabilise_at_their_frequency():
    L = satellite()
    m = disk_margin_mimo(L)
    F = np.diag(m.worst_factors)
    smallest = np.linalg.svd(np.eye(2) + L(1j * m.worst_frequency) @ F, compute_uv=False)[-1]
    assert smallest < 1e-6
    delta = 2 * (m.worst_factors - 1) / (m.worst_factors + 1)      # back into the disk (skew 0)
    assert np.max(np.abs(delta)) == pytest.approx(m.alpha_upper, rel=1e-6)


def test_satellite_ten_percent_real_gain_change_destabilises():
    # the textbook statement: input gains (1 + e, 1 - e) destabilise for e > 1/sqrt(a^2 + 1)
    P = satellite()
    e = 1 / math.sqrt(101)
    for k, stable in ((0.98, True), (1.02, False)):
        F = static(np.diag([1 + k * e, 1 - k * e]))
        poles = ct.poles(ct.feedback(P * F, static(np.eye(2))))
        assert bool(np.all(poles.real < 0)) is stable
    # every gain pair inside the disk-based gain margin keeps it stable (corners tried)
    gmin, gmax = disk_margin_mimo(P).gain_margin
    for g1 in (gmin * 1.001, gmax * 0.999):
        for g2 in (gmin * 1.001, gmax * 0.999):
            poles = ct.poles(ct.feedback(P * static(np.diag([g1, g2])), static(np.eye(2))))
            assert np.all(poles.real < 0)


def test_matlab_diskmargin_example():
    # MATLAB's diskmargin(P, C) example, C = [1 -2; 0 1]: DiskMargin 0.3754 at w = 0 (documented,
    # a guaranteed lower bound).  At w = 0 M is real and mu exact: the worst factors are real
    # gains that put a closed-loop pole at s = 0, so the true margin is ours, 0.2 % above.
    P, C = satellite(), static([[1.0, -2.0], [0.0, 1.0]])
    m = loop_margins_mimo(P, C)
    for mm, L in ((m.input, C * P), (m.output, P * C)):
        assert mm.frequency == 0.0
        assert 0.3754 <= mm.alpha <= 0.3754 * 1.005
        assert mm.alpha_upper == pytest.approx(mm.alpha, rel=1e-6)
        assert np.allclose(mm.worst_factors.imag, 0, atol=1e-9)
        F = static(np.diag(mm.worst_factors.real))
        poles = ct.poles(ct.feedback(L * F, static(np.eye(2))))
        assert np.min(np.abs(poles)) < 1e-6
    # python-control's disk_margins (SLICOT AB13MD upper bound) on a grid that starts at 1e-4
    dm, _, _ = ct.disk_margins(C * P, np.logspace(-4, 3, 2001))
    assert dm == pytest.approx(m.input.alpha, rel=1e-3)


def test_decoupled_loops_multiloop_margin_is_the_smallest_siso_margin():
    loops = [4 / ((s + 1) * (0.1 * s + 1) * (0.01 * s + 1)), 2 * (s + 3) / (s * (s + 1)),
             10 / (s + 1) ** 2]
    L = ct.append(*[ct.ss(x) for x in loops])
    siso = [loop_margins(x, ct.tf([1], [1])).disk_margin for x in loops]
    m = disk_margin_mimo(L)
    assert m.alpha == pytest.approx(min(siso), rel=1e-6)
    assert m.alpha_upper == pytest.approx(min(siso), rel=1e-6)
    per_loop = [x.alpha for x in loop_at_a_time_disk_margins(L)]
    assert per_loop == pytest.approx(siso, rel=1e-6)


@pytest.mark.parametrize("skew", [1.0, -1.0, 0.5])
def test_skewed_siso_margin_against_python_control(skew):
    L = ct.tf(25, [1, 10, 10, 10])
    dm, _, _ = ct.disk_margins(L, np.logspace(-2, 3, 20001), skew=skew)
    m = disk_margin_mimo(ct.ss(L), skew=skew)
    assert m.alpha == pytest.approx(dm, rel=1e-5)
    if skew == 1.0:                              # sigma = 1: alpha = 1 / ||S||_inf
        assert m.alpha == pytest.approx(loop_margins(L, ct.tf([1], [1])).modulus_margin,
                                        rel=1e-6)


def test_discrete_loop():
    # the sampled satellite with unit feedback: a diagonal check first (decoupled ZOH loops)
    Ts = 0.01
    G1, G2 = ct.c2d(ct.tf([1], [1, 1]), Ts), ct.c2d(ct.tf([5], [1, 2, 5]), Ts)
    Ld = ct.append(ct.ss(G1), ct.ss(G2))
    theta = np.linspace(0, np.pi, 200001)
    z = np.exp(1j * theta)
    alphas = [1 / np.max(np.abs(1 / (1 + np.ravel(G(z))) - 0.5)) for G in (G1, G2)]
    m = disk_margin_mimo(Ld)
    assert m.alpha == pytest.approx(min(alphas), rel=1e-6)
    assert 0 <= m.frequency <= np.pi / Ts
    # the sampled satellite's margin stays near the continuous one (ZOH at 100 Hz, a = 10)
    Pd = ct.c2d(satellite(), Ts, "zoh")
    assert disk_margin_mimo(Pd).alpha == pytest.approx(disk_margin_mimo(satellite()).alpha,
                                                       rel=0.1)
    with pytest.raises(ValueError, match="Nyquist"):
        disk_margin_mimo(Ld, omega=np.linspace(1.0, 1.1 * np.pi / Ts, 50))


def test_three_channels_bounds_meet_and_beat_loop_at_a_time():
    rng = np.random.default_rng(3)
    G = ct.ss(-np.diag([1.0, 2.0, 5.0, 10.0]), rng.standard_normal((4, 3)),
              rng.standard_normal((3, 4)), np.zeros((3, 3)))
    K = static(0.5 * np.eye(3))
    L = G * K
    if not np.all(ct.poles(ct.feedback(L, static(np.eye(3)))).real < 0):
        pytest.skip("this random loop is unstable")
    m = disk_margin_mimo(L)
    assert m.alpha_upper == pytest.approx(m.alpha, rel=1e-3)   # 3 scalars: mu = D bound
    assert m.alpha <= min(x.alpha for x in loop_at_a_time_disk_margins(L)) * (1 + 1e-9)


def test_unstable_closed_loop_is_refused():
    with pytest.raises(ValueError, match="unstable"):
        disk_margin_mimo(ct.ss(ct.append(ct.ss(ct.tf([20], [1, 3, 3, 1])), ct.ss(ct.tf([1], [1, 1])))))
    with pytest.raises(ValueError, match="square"):
        disk_margin_mimo(ct.ss(-np.eye(2), np.eye(2), np.ones((3, 2)), np.zeros((3, 2))))


def test_input_output_margin_worst_factors_destabilise_and_it_is_the_smallest():
    P, C = satellite(), static([[1.0, -2.0], [0.0, 1.0]])
    m = loop_margins_mimo(P, C)
    io = m.input_output
    assert io.alpha <= min(m.input.alpha, m.output.alpha)
    assert io.alpha_upper == pytest.approx(io.alpha, rel=1e-3)
    # independent of the interconnection behind mu: I + K F_o P F_i singular at that frequency
    Fi, Fo = np.diag(io.worst_factors[:2]), np.diag(io.worst_factors[2:])
    L = C.D @ Fo @ P(1j * io.worst_frequency) @ Fi
    assert np.linalg.svd(np.eye(2) + L, compute_uv=False)[-1] < 1e-6
    delta = 2 * (io.worst_factors - 1) / (io.worst_factors + 1)
    assert np.max(np.abs(delta)) == pytest.approx(io.alpha_upper, rel=1e-6)


def test_input_output_margin_with_feedthrough_in_plant_and_controller():
    # D_P and D_K both nonzero: an algebraic loop that the interconnection solves in closed
    # form (ct.interconnect refused it with a RuntimeError)
    a = 10.0
    P = ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], [[0.2, 0.0], [0.05, 0.1]])
    C = ct.ss([[-50.0]], [[50.0, 0.0]], [[0.5], [0.0]], [[1.0, -2.0], [0.0, 1.0]])
    m = loop_margins_mimo(P, C)
    io = m.input_output
    assert io.alpha <= min(m.input.alpha, m.output.alpha) * (1 + 1e-9)
    Fi, Fo = np.diag(io.worst_factors[:2]), np.diag(io.worst_factors[2:])
    w = 1j * io.worst_frequency
    L = np.asarray(C(w)).reshape(2, 2) @ Fo @ np.asarray(P(w)).reshape(2, 2) @ Fi
    assert np.linalg.svd(np.eye(2) + L, compute_uv=False)[-1] < 1e-6


def test_siso_input_output_margin_against_brute_force():
    # one loop, a factor at the plant input and one at its output: 1 + L f1 f2 = 0
    G = ct.tf(25, [1, 10, 10, 10])
    io = loop_margins_mimo(ct.ss(G), static([[1.0]])).input_output
    phi = np.exp(1j * np.linspace(0, 2 * np.pi, 2001))
    best = math.inf
    for w in io.worst_frequency * np.linspace(0.9, 1.1, 21):
        g = np.ravel(G(1j * w))[0]
        for r in np.linspace(0.15, 0.35, 400):
            d1 = r * phi
            f1 = (1 + d1 / 2) / (1 - d1 / 2)
            f2 = -1 / (g * f1)
            d2 = 2 * (f2 - 1) / (f2 + 1)
            best = min(best, float(np.min(np.maximum(np.abs(d1), np.abs(d2)))))
    assert io.alpha <= best * (1 + 1e-9)
    assert best == pytest.approx(io.alpha, rel=2e-3)


def test_a_sharp_closed_loop_resonance_is_not_missed():
    # loop 2's closed-loop pole pair at sqrt(3000) rad/s is damped 1e-6 * 50 / 54.8: |S - 1/2|
    # peaks over a band 1e-6 wide, far narrower than the grid's spacing (2 %); the grid holds
    # the closed-loop poles' frequencies, so the peak is found to the SISO margin's precision
    # (a plain 600-point grid with its refinement is 6e-6 off)
    wn, zeta = 50.0, 1e-6
    L2 = ct.tf([500.0], [1.0, 2 * zeta * wn, wn ** 2])
    L = ct.append(ct.ss(ct.tf([1.0], [1.0, 1.0])), ct.ss(L2))
    wc = math.sqrt(3000.0)
    siso = loop_margins(L2, ct.tf([1], [1]),
                        omega=np.linspace(wc * (1 - 1e-3), wc * (1 + 1e-3), 400001)).disk_margin
    assert disk_margin_mimo(L).alpha == pytest.approx(siso, rel=1e-8)
