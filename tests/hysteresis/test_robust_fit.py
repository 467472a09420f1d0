"""fit_dahl and fit_pi on raw, noisy, full-rate records: no numerical error, honest reports."""

import warnings

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib.problem.stage import VirtualStage

SENSOR_NOISE_V = 0.5e-3          # the virtual stage's sensor noise on v_y [V rms]


def stage_record(fs, noise_factor, start, seconds=0.25, f=8.0):
    """u_c [V] and v_y [V] of the virtual stage: from rest, at a step, or cut mid-stroke."""
    stage = VirtualStage(seed=2, sample_rate_Hz=fs, noise_rms_V=noise_factor * SENSOR_NOISE_V)
    t = np.arange(int(seconds * fs)) / fs
    if start == "rest":
        u = 1.5 - 1.5 * np.cos(2 * np.pi * f * t)
    elif start == "step":
        u = 1.5 + 1.5 * np.sin(2 * np.pi * f * t)       # jumps to 1.5 V at t = 0
    else:
        u = 1.5 + 1.5 * np.sin(2 * np.pi * f * t + 1.0)
    rec = stage.run(u)
    k = int(0.3 * fs / f) if start == "mid" else 0     # starts mid-stroke, stage moving
    return rec.u_c_V[k:], rec.v_y_V[k:]


@pytest.mark.parametrize("fs, noise, start", [
    (1_000.0, 20, "rest"), (5_000.0, 5, "step"), (5_000.0, 20, "mid"),
    (20_000.0, 20, "step"), (20_000.0, 5, "mid")])
def test_no_numerical_error_on_raw_noisy_records(fs, noise, start):
    v, x = stage_record(fs, noise, start)
    v, x = 10 * v, 3 * x                                   # actuator volts and um: any units
    period = int(fs / 8.0)                                 # scored after the first period
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)     # overflow, invalid value ...
        warnings.simplefilter("ignore", hy.FitWarning)
        dahl = hy.fit_dahl([(v, x)], gamma_a=30.0, offset=True, start="rest", starts=1,
                           discard=period)
        pi = hy.fit_pi([(v, x)], n_plays=8, discard=period)
    for fit in (dahl, pi):
        assert np.all(np.isfinite(fit.x_model[0]))
        table = fit.parameter_table()
        assert np.isfinite(table["value"]).all()
    # a fit close to the loops despite noise up to 20x the stage's (stroke 9 um)
    assert dahl.rms_percent[0] < 3.0 and pi.rms_percent[0] < 2.0
    assert pi.rms_percent[0] < dahl.rms_percent[0]


def test_starting_values_do_not_depend_on_the_first_sample():
    v, x = stage_record(5_000.0, 5, "rest")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hy.FitWarning)
        base = hy.fit_dahl([(v, x)], gamma_a=30.0, offset=True, starts=1)
        x_bad = x.copy()
        x_bad[0] += 0.5                                     # a wild first sample
        moved = hy.fit_dahl([(v, x_bad)], gamma_a=30.0, offset=True, starts=1, discard=1)
    assert moved.model.g_a == pytest.approx(base.model.g_a, rel=0.05)


def test_first_order_limit_reports_unidentifiable_parameters():
    """alpha1, alpha2 and beta2 are not separately identifiable in the first-order limit;
    their combinations H_ss and alpha2/alpha1 are."""
    true = hy.DahlModel(1e4, 1.4e4, 0.0, 0.25 * 1.4e4 / 30.0, 30.0, 1.25,
                        form="bliman_sorine", x0=-0.15, start="rest")
    t = np.arange(2000) / 10_000.0
    v = 2.0 - 2.0 * np.cos(2 * np.pi * 10 * t)
    x = true.simulate(v) + np.random.default_rng(0).normal(0, 2.5e-3, v.size)
    with pytest.warns(hy.FitWarning, match="not identifiable"):
        fit = hy.fit_dahl([(v, x)], gamma_a=30.0, offset=True, start="rest", starts=1)
    table = fit.parameter_table()
    assert not table.loc["alpha1", "identifiable"]
    assert table.loc["H_ss = beta2 gamma_a / alpha2", "identifiable"]
    assert table.loc["H_ss = beta2 gamma_a / alpha2", "95% CI low"] < 0.25 < \
        table.loc["H_ss = beta2 gamma_a / alpha2", "95% CI high"]
    assert table.loc["x0", "95% CI low"] < -0.15 < table.loc["x0", "95% CI high"]


def test_bound_limited_parameter_is_reported():
    """Straight data (no hysteresis): the Dahl fit runs to a bound, and says so."""
    t = np.arange(3000) / 10_000.0
    v = 2.0 - 2.0 * np.cos(2 * np.pi * 10 * t)
    x = 0.9 * v + np.random.default_rng(1).normal(0, 1e-3, v.size)
    with pytest.warns(hy.FitWarning) as record:
        fit = hy.fit_dahl([(v, x)], gamma_a=30.0, starts=1)
    table = fit.parameter_table()
    assert (table["at_bound"] | ~table["identifiable"]).any()
    assert any("on a bound" in str(w.message) or "not identifiable" in str(w.message)
               for w in record)


def test_data_that_cannot_support_the_model_raise_clearly():
    t = np.arange(2000) / 10_000.0
    v = 2.0 - 2.0 * np.cos(2 * np.pi * 10 * t)
    with pytest.raises(ValueError, match="x increasing with v"):
        hy.fit_dahl([(v, -v)], gamma_a=30.0)
    with pytest.raises(ValueError, match="x increasing with v"):
        hy.fit_pi([(v, -v)])
    with pytest.raises(ValueError, match="no full cycle"):
        hy.fit_pi([(t, t)])
    with pytest.raises(TypeError, match="must be real"):
        hy.fit_pi([(v + 0j, v)])


def test_monotone_path_follows_the_input_strokes():
    v = np.r_[np.linspace(0, 1, 50), np.linspace(1, 0, 50)[1:]]
    x = v + np.random.default_rng(4).normal(0, 0.05, v.size)
    path = hy.monotone_path(v, x)
    assert np.all(np.diff(path[:50]) >= 0) and np.all(np.diff(path[49:]) <= 0)
    assert np.sqrt(np.mean((path - v) ** 2)) < np.sqrt(np.mean((x - v) ** 2))
