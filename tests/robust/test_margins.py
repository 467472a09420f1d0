"""Margins of textbook loops against known values and python-control; sampled-loop delay tolerance."""

import math

import control as ct
import numpy as np
import pytest

from piezolib.robust.margins import delay_tolerance, loop_margins, sampled_loop_radius

s = ct.tf("s")
ONE = ct.tf([1], [1])


def test_integrator_lag_loop():
    # L = 1/(s(s+1)): |L| = 1 at w^4 + w^2 = 1, PM = 180 - 90 - atan(w) = 51.83 deg, no GM
    m = loop_margins(1 / (s * (s + 1)), ONE)
    wc = math.sqrt((math.sqrt(5) - 1) / 2)
    assert m.omega_crossover == pytest.approx(wc, rel=1e-9)
    assert m.phase_margin_deg == pytest.approx(90 - math.degrees(math.atan(wc)), abs=1e-7)
    assert m.gain_margin == math.inf
    assert m.delay_margin_s == pytest.approx(math.radians(m.phase_margin_deg) / wc, rel=1e-9)
    assert m.closed_loop_stable


@pytest.mark.parametrize("k", [0.5, 2.0, 4.0])
def test_third_order_lag_gain_margin(k):
    # L = k/(s+1)^3: phase -180 deg at w = sqrt(3), |L| = k/8 there, so GM = 8/k
    m = loop_margins(k / (s + 1) ** 3, ONE)
    assert m.gain_margin == pytest.approx(8 / k, rel=1e-9)
    assert m.omega_gain_margin == pytest.approx(math.sqrt(3), rel=1e-9)


def test_agrees_with_python_control():
    G, K = 4 / ((s + 1) * (0.1 * s + 1) * (0.01 * s + 1)), (s + 2) / s
    m = loop_margins(G, K)
    gm, pm, sm, wpc, wgc, _ = ct.stability_margins(G * K)
    assert m.gain_margin == pytest.approx(gm, rel=1e-6)
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert m.omega_crossover == pytest.approx(wgc, rel=1e-6)
    assert m.modulus_margin == pytest.approx(sm, rel=1e-3)
    dm, dgm, dpm = ct.disk_margins(G * K, np.logspace(-3, 4, 20000))
    assert m.disk_margin == pytest.approx(dm, rel=1e-4)
    assert 20 * math.log10(m.disk_gain_margin) == pytest.approx(dgm, rel=1e-4)
    assert m.disk_phase_margin_deg == pytest.approx(dpm, rel=1e-4)


def test_delay_margin_is_exact():
    # closing the loop with a Pade model of the delay margin puts a pole on the axis
    G = 10 / ((s + 1) * (s + 5))
    m = loop_margins(G, ONE)
    num, den = ct.pade(0.99 * m.delay_margin_s, 12)
    stable = np.all(ct.poles(ct.feedback(G * ct.tf(num, den), 1)).real < 0)
    num, den = ct.pade(1.01 * m.delay_margin_s, 12)
    unstable = np.any(ct.poles(ct.feedback(G * ct.tf(num, den), 1)).real > 0)
    assert stable and unstable


def test_unstable_loop_reported():
    assert not loop_margins(20 / (s + 1) ** 3, ONE).closed_loop_stable


def test_sampled_loop_delay_tolerance_matches_python_control():
    fs = 1000.0
    G = 200 / (s + 50)
    Kd = ct.c2d(ct.tf([3.0, 30], [1, 0]), 1 / fs, "tustin")
    tol = delay_tolerance(G, Kd, delays=range(6))
    Gd = ct.c2d(G, 1 / fs, "zoh")
    zinv = ct.tf([1], [1, 0], 1 / fs)
    for d, r in zip(tol.delays, tol.spectral_radius):
        L = Gd * Kd
        for _ in range(d):
            L = L * zinv
        assert r == pytest.approx(max(abs(ct.poles(ct.feedback(L, 1)))), rel=1e-9)
    assert tol.stable[0] and not tol.stable[-1]
    # the whole-sample delay that destabilises is the first one above the delay margin
    assert tol.max_stable_delay == math.floor(tol.delay_margin_samples)
    assert sampled_loop_radius(G, Kd, 0) == tol.spectral_radius[0]


def test_bad_input_named():
    with pytest.raises(ValueError, match="Kd"):
        sampled_loop_radius(1 / (s + 1), 1 / (s + 1))
    with pytest.raises(ValueError, match="delays"):
        delay_tolerance(1 / (s + 1), ct.tf([1], [1, 0], 0.01), delays=(1, 2))
    with pytest.raises(ValueError, match="G"):
        loop_margins(ct.tf([1], [1, 0], 0.1), ONE)


# --- phase crossovers at w = 0 and w = inf, which no grid reaches --------------------------
def test_downward_gain_margin_at_dc():
    # L = 2/(s - 1): L(j0) = -2 on the negative real axis; closed loop s - 1 + 2k stable
    # for k > 1/2, so the gain may drop by 0.5 (the pole crosses s = 0), never rise to a limit
    m = loop_margins(1 / (s - 1), ct.tf(2, 1))
    assert m.closed_loop_stable
    assert m.gain_margin_low == pytest.approx(0.5, abs=1e-9) and m.omega_gain_margin_low == 0
    assert m.gain_margin == math.inf and math.isnan(m.omega_gain_margin)
    gm, _, _, wpc, _, _ = ct.stability_margins(2 / (s - 1))     # right here, python-control
    assert m.gain_margin_low == pytest.approx(gm, rel=1e-12) and wpc == 0
    # S = (s - 1)/(s + 1): |S - 1/2| peaks at DC, 3/2, so alpha = 2/3 exactly
    assert m.disk_margin == pytest.approx(2 / 3, rel=1e-12) and m.omega_disk == 0
    assert m.modulus_margin == pytest.approx(1.0, rel=1e-12)


def test_upward_gain_margin_at_infinite_frequency():
    # L = -0.5 (s - 1)/(s + 1): |L| = 0.5 and Im L = -0.5 sin(2 atan w) < 0 for 0 < w < inf,
    # so no phase crossover in between; L(0) = +0.5, L(j inf) = -0.5.  The closed loop
    # (1 - k/2) s + (1 + k/2) = 0 has its pole at -(2 + k)/(2 - k): stable for 0 < k < 2,
    # the pole leaving through infinity at k = 2 -- an upward gain margin of 2 at w = inf
    G, K = (s - 1) / (s + 1), ct.tf(-0.5, 1)
    m = loop_margins(G, K)
    assert m.closed_loop_stable
    assert m.gain_margin == pytest.approx(2.0, rel=1e-12) and m.omega_gain_margin == math.inf
    assert m.gain_margin_low == 0 and math.isnan(m.omega_gain_margin_low)
    for k, stable in ((2 * (1 - 1e-6), True), (2 * (1 + 1e-6), False)):
        assert np.all(ct.poles(ct.feedback(G * K * k, 1)).real < 0) == stable
    # S(j inf) = 1/(1 - 0.5) = 2: the disk margin is set there too, and agrees: (2 + a)/(2 - a) = 2
    assert m.modulus_margin == pytest.approx(0.5, rel=1e-12) and m.omega_disk == math.inf
    assert m.disk_gain_margin == pytest.approx(2.0, rel=1e-12)


def test_integrator_loops_have_no_crossover_at_dc():
    # L(0) is infinite (a single or double integrator): never a downward margin from DC
    for G in (1 / (s * (s + 1)), (s + 3) / (s ** 2 * (s + 10)), ct.ss(1 / (s * (s + 1)))):
        m = loop_margins(G, ONE)
        assert m.gain_margin_low == 0 and math.isnan(m.omega_gain_margin_low)


def test_high_frequency_gain_above_one_leaves_no_delay_margin():
    # |L(j inf)| = 2: with any delay the loop gain circles -1 at high frequency
    G = 2 * (s + 3) / (s + 1)
    m = loop_margins(G, ONE)
    assert m.closed_loop_stable and m.crossovers.size == 0
    assert m.delay_margin_s == 0 and m.omega_delay_margin == math.inf
    num, den = ct.pade(1e-4, 12)
    assert np.any(ct.poles(ct.feedback(G * ct.tf(num, den), 1)).real > 0)


@pytest.mark.parametrize("L", [10 / ((s + 1) * (s + 2) * (s + 3)), 1 / (s * (s + 1) * (s + 2)),
                               5 * (s + 1) / (s * (s + 2) * (0.05 * s + 1) ** 2)])
def test_ordinary_loops_agree_with_python_control(L):
    m = loop_margins(L, ONE)
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(L)
    assert m.gain_margin == pytest.approx(gm, rel=1e-6)
    assert m.omega_gain_margin == pytest.approx(wpc, rel=1e-6)
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert m.omega_crossover == pytest.approx(wgc, rel=1e-6)
    assert m.gain_margin_low == 0


def test_modulus_margin_is_refined_between_grid_points():
    # on a 40-point grid the smallest |1 + L| on the grid is 0.5745; the refined minimum
    # matches a grid of 2 million points
    L = 2 / (s * (s + 1))
    omega = np.logspace(-2, 2, 40)
    dense = np.logspace(-2, 2, 2_000_001)
    reference = np.min(np.abs(1 + np.ravel(L(1j * dense))))
    m = loop_margins(L, ONE, omega=omega)
    assert m.modulus_margin == pytest.approx(reference, rel=1e-9)
    assert m.modulus_margin < np.min(np.abs(1 + np.ravel(L(1j * omega)))) - 1e-2
