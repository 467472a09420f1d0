"""Hysteresis % (eq. 25-26) on loops of known width."""

import numpy as np
import pytest

from piezolib import signals
from piezolib.hysteresis import measure

FS = 10_000.0


def elliptic_loop(phase_lag, periods=3, n=4000, amplitude=4.0):
    """v = A(1 - cos th)/2, x = A(1 - cos(th - phi))/2: hysteresis % = 100 tan(phi)."""
    theta = np.linspace(0, 2 * np.pi * periods, n * periods + 1)
    return (amplitude * (1 - np.cos(theta)) / 2,
            amplitude * (1 - np.cos(theta - phase_lag)) / 2)


@pytest.mark.parametrize("phi", [0.02, 0.1, 0.3])
def test_ellipse_width_is_tan_phi(phi):
    v, x = elliptic_loop(phi)
    assert measure.hysteresis_percent(v, x) == pytest.approx(100 * np.tan(phi), rel=5e-3)


def test_offset_branches_on_triangle():
    t, v = signals.triangle(4.0, 10.0, fs=FS, periods=2)
    x = 3.0 * v - 0.2 * np.sign(np.gradient(v))   # branches 0.4 apart around the midpoint
    m = measure.hysteresis_measure(v, x)
    assert m.v_mid == pytest.approx(2.0)
    assert m.x_lo - m.x_up == pytest.approx(0.4, abs=1e-9)
    assert (m.n_up, m.n_down) == (2, 2)


def test_noise_and_several_periods_are_averaged():
    v, x = elliptic_loop(0.1, periods=8)
    rng = np.random.default_rng(1)
    noisy = measure.hysteresis_percent(v, x + rng.normal(0, 0.01, x.size))
    assert noisy == pytest.approx(100 * np.tan(0.1), abs=0.15)


def test_no_loop_gives_zero():
    t, v = signals.triangle(4.0, 10.0, fs=FS, periods=1)
    assert measure.hysteresis_percent(v, 2 * v) == pytest.approx(0.0, abs=1e-12)


def test_hysteresis_percent_when_input_jumps_across_the_window():
    """Coarse strokes with no sample near V_M: the two samples around V_M are used."""
    up = np.array([0.0, 0.7, 1.45, 2.2, 3.0])
    v = np.r_[up, up[::-1][1:], up[1:], up[::-1][1:]]
    descending = np.r_[False, np.diff(v) < 0]
    branch = np.where(descending, 0.1, -0.1)          # branches 0.2 apart ...
    branch[(v == 0) | (v == 3)] = 0.0                 # ... meeting at the turning points
    x = 2 * v + branch
    assert measure.hysteresis_percent(v, x) == pytest.approx(0.2 / 6.0 * 100, rel=1e-12)


@pytest.mark.parametrize("v, x, match", [
    (np.linspace(0, 1, 100), np.linspace(0, 1, 100), "no full cycle"),
    (np.ones(100), np.arange(100.0), "constant"),
    (np.r_[np.nan, np.ones(99)], np.ones(100), "v contains 1 non-finite"),
    (np.ones(100), np.ones(99), "equal lengths"),
])
def test_bad_records_raise(v, x, match):
    with pytest.raises(ValueError, match=match):
        measure.hysteresis_percent(v, x)
