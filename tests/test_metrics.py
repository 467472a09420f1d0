"""Tracking error % (Table 5) and improvement rows (Tables 4-5) on signals with known answers."""

import numpy as np
import pytest

from piezolib import metrics, signals

FS = 10_000.0


def triangle_um(frequency_Hz=10.0, periods=2, peak=12.0):
    return signals.triangle(peak, frequency_Hz, periods=periods, fs=FS)


def test_error_is_desired_minus_reached():
    x_r = np.array([0.0, 1.0, 2.0])
    x = np.array([0.5, 1.0, 1.0])
    assert np.array_equal(metrics.tracking_error(x_r, x), [-0.5, 0.0, 1.0])


@pytest.mark.parametrize("gain_error", [0.02, -0.05, 0.1])
def test_gain_error_gives_its_own_percentage(gain_error):
    # x = (1 - g) x_r: e = g x_r runs from 0 to 12 g -> both readings 100 |g| %
    t, x_r = triangle_um()
    x = (1 - gain_error) * x_r
    assert metrics.tracking_error_percent(x_r, x) == pytest.approx(100 * abs(gain_error))
    assert metrics.peak_to_peak_error_percent(x_r, x) == pytest.approx(100 * abs(gain_error))


@pytest.mark.parametrize("offset, amplitude", [(0.0, 0.06), (0.03, 0.06), (-0.1, 0.02)])
def test_offset_plus_ripple(offset, amplitude):
    # e = c + a cos(2 pi k / 100) reaches c + a and c - a exactly:
    # max|e| = |c| + a, max e - min e = 2a, both over R = 12 um
    t, x_r = triangle_um(periods=3)
    e = offset + amplitude * np.cos(2 * np.pi * np.arange(t.size) / 100)
    x = x_r - e
    assert metrics.tracking_error_percent(x_r, x) == pytest.approx(
        100 * (abs(offset) + amplitude) / 12.0, rel=1e-12)
    assert metrics.peak_to_peak_error_percent(x_r, x) == pytest.approx(
        100 * 2 * amplitude / 12.0, rel=1e-12)


@pytest.mark.parametrize("frequency_Hz, delay", [(1.0, 1), (10.0, 3), (50.0, 2)])
def test_pure_delay_of_a_triangle(frequency_Hz, delay):
    # x[k] = x_r[k - d]: on the ramps |e| = slope * d / fs with slope 2 R f,
    # so max|e| / R = 200 f d / fs percent (and the peak-to-peak is twice that)
    t, x_r = triangle_um(frequency_Hz, periods=3)
    x = np.r_[np.zeros(delay), x_r[:-delay]]
    s = slice(int(FS / frequency_Hz), None)          # whole periods after the first
    want = 200 * frequency_Hz * delay / FS
    assert metrics.tracking_error_percent(x_r[s], x[s], 12.0) == pytest.approx(want, rel=1e-9)
    assert metrics.peak_to_peak_error_percent(x_r[s], x[s], 12.0) == pytest.approx(2 * want,
                                                                                    rel=1e-9)


def test_default_range_is_that_of_the_reference():
    t, x_r = triangle_um(peak=6.0)
    x = x_r - 0.06
    assert metrics.tracking_error_percent(x_r, x) == pytest.approx(1.0)
    assert metrics.tracking_error_percent(x_r, x, 12.0) == pytest.approx(0.5)


def test_perfect_tracking_is_zero():
    t, x_r = triangle_um()
    assert metrics.tracking_error_percent(x_r, x_r.copy()) == 0.0


def test_improvement_formula():
    # Table 4 at 10 V: (6.19 - 0.45) / 6.19 = 92.73 %
    assert metrics.improvement_percent(6.19, 0.45) == pytest.approx(92.73, abs=5e-3)
    assert metrics.improvement_percent(2.0, 3.0) == pytest.approx(-50.0)
    out = metrics.improvement_percent([1.0, 4.0], [0.5, 1.0])
    assert np.allclose(out, [50.0, 75.0])


@pytest.mark.parametrize("before, after, error", [
    (0.0, 1.0, ValueError), (-1.0, 0.5, ValueError), (np.nan, 1.0, ValueError),
    (1.0, np.inf, ValueError), ([1.0, 2.0], [1.0, 2.0, 3.0], ValueError), ("a", 1.0, TypeError)])
def test_improvement_bad_input(before, after, error):
    with pytest.raises(error):
        metrics.improvement_percent(before, after)


def test_tracking_error_bad_input():
    x_r = np.linspace(0, 12, 100)
    with pytest.raises(ValueError, match="equal lengths"):
        metrics.tracking_error_percent(x_r, x_r[:-1])
    with pytest.raises(ValueError, match="x contains"):
        metrics.tracking_error_percent(x_r, np.r_[x_r[:-1], np.nan])
    with pytest.raises(ValueError, match="x_r must be 1-dimensional"):
        metrics.tracking_error_percent(x_r.reshape(10, 10), x_r.reshape(10, 10))
    with pytest.raises(ValueError, match="constant"):
        metrics.tracking_error_percent(np.ones(10), np.zeros(10))
    with pytest.raises(ValueError, match="range_ must be positive"):
        metrics.tracking_error_percent(x_r, x_r, range_=0.0)
    with pytest.raises(ValueError, match="at least 2 samples"):
        metrics.peak_to_peak_error_percent([1.0], [1.0], 12.0)


# --- mean over noise seeds and its Student-t interval ---------------------------------
def test_mean_interval_of_three_draws_uses_t_with_two_dof():
    mean, low, high = metrics.mean_interval([1.0, 2.0, 3.0])
    t = 4.30265273                          # t_{0.975} with 2 degrees of freedom (tables)
    assert mean == 2.0
    assert (low, high) == pytest.approx((2.0 - t / np.sqrt(3), 2.0 + t / np.sqrt(3)), rel=1e-8)
    # 90 %: t_{0.95, 2 dof} = 2.919986; equal draws: no width at all
    assert metrics.mean_interval([1.0, 2.0, 3.0], confidence=0.9)[2] == pytest.approx(
        2.0 + 2.91998558 / np.sqrt(3), rel=1e-8)
    assert metrics.mean_interval([5.0, 5.0]) == (5.0, 5.0, 5.0)


def test_mean_interval_along_an_axis_and_its_coverage():
    rng = np.random.default_rng(4)
    draws = rng.normal(3.0, 2.0, size=(8, 4000))        # 4000 experiments of 8 draws
    mean, low, high = metrics.mean_interval(draws, axis=0)
    assert mean.shape == low.shape == (4000,)
    np.testing.assert_allclose(mean, draws.mean(axis=0))
    coverage = np.mean((low <= 3.0) & (3.0 <= high))
    assert abs(coverage - 0.95) < 3 * np.sqrt(0.95 * 0.05 / 4000)     # 3 sigma of the rate
    # the same along the last axis
    again = metrics.mean_interval(draws.T, axis=-1)
    np.testing.assert_array_equal(again[1], low)


@pytest.mark.parametrize("values, kwargs, match", [
    ([1.0], {}, "N >= 2 draws"),
    (np.ones((1, 3)), {}, "N >= 2 draws along axis 0"),
    ([1.0, 2.0], dict(confidence=1.0), "confidence must be below 1"),
    ([1.0, 2.0], dict(axis=1), "axis must be an integer"),
])
def test_mean_interval_bad_input(values, kwargs, match):
    with pytest.raises(ValueError, match=match):
        metrics.mean_interval(values, **kwargs)


def test_tracking_errors_percent_is_tracking_error_percent_per_column():
    rng = np.random.default_rng(3)
    x_r = np.sin(np.linspace(0, 7, 300)) * 6
    X = x_r[:, None] + rng.normal(0, 0.2, (300, 5))
    for range_ in (None, 12.0):
        many = metrics.tracking_errors_percent(x_r, X, range_)
        assert many.tolist() == [metrics.tracking_error_percent(x_r, X[:, j], range_)
                                 for j in range(5)]
    with pytest.raises(ValueError, match="one row per sample"):
        metrics.tracking_errors_percent(x_r, X[:-1])
    with pytest.raises(ValueError, match="X"):
        metrics.tracking_errors_percent(x_r, X[:, 0])
    with pytest.raises(ValueError, match="X"):
        metrics.tracking_errors_percent(x_r, np.where(X > 5, np.nan, X))
