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
