"""Raw records of foreign hysteresis (piezolib.problem.foreign_hysteresis), and the fits of the
hysteresis package judged on them: start states after a cut, dynamics learnt from the step."""

import warnings

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import records as R
from piezolib.problem import foreign_hysteresis as F

FS = 2000.0


@pytest.fixture(scope="module")
def bouc_wen():
    return F.foreign_raw_record("bouc_wen", FS, periods=3.7)


def test_records_have_the_raw_form_and_the_stated_noise(bouc_wen):
    rec = bouc_wen.record
    start = R.find_start_up(rec)
    assert start.step == int(0.5 * FS) and rec.input[start.step] == pytest.approx(-87.0)
    assert np.ptp(rec.input) == pytest.approx(300.0, rel=1e-3)
    assert np.std(rec.output - bouc_wen.x_true) == pytest.approx(bouc_wen.noise_rms, rel=0.05)
    assert np.allclose(bouc_wen.plant(rec.input), bouc_wen.x_true)


@pytest.mark.parametrize("family", F.FAMILIES)
def test_a_record_cut_at_a_maximum_fits_as_well_as_one_cut_at_a_minimum(family):
    # cut_at_turning_points(skip_transient=True) starts this record at its +150 V peak;
    # with the states "rest" and "virgin" only, PI fitted it 3 to 6 times worse
    raw = F.foreign_raw_record(family, FS, periods=3.7)
    rms = {}
    for first in (0, 1):
        cut = R.cut_at_turning_points(raw.record, skip_transient=True, first=first)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", hy.FitWarning)
            fit = hy.fit_pi([(cut.input, cut.output)])
        rms[cut.input[0] > 0] = fit.pooled_rms_percent
    assert rms[True] < 1.1 * rms[False]


def test_a_dahl_fit_of_a_record_cut_at_a_maximum_fits_as_well_as_one_cut_at_a_minimum():
    # with the starts "virgin" and "rest" only, the cut at the +150 V peak fitted 5 x worse
    raw = F.foreign_raw_record("bouc_wen", 200.0, periods=2.7)
    at_max, at_min = (R.cut_at_turning_points(raw.record, skip_transient=True, first=first)
                      for first in (0, 1))
    assert at_max.input[0] > 0 > at_min.input[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hy.FitWarning)
        auto = hy.fit_dahl([(at_max.input, at_max.output)], 30.0, offset=True, start="auto",
                           starts=1)
        rest = hy.fit_dahl([(at_min.input, at_min.output)], 30.0, offset=True, start="rest",
                           starts=1)
    assert auto.model.start == "maximum"
    assert auto.pooled_rms_percent < 1.1 * rest.pooled_rms_percent


def test_hammerstein_learns_the_resonance_from_a_raw_record(bouc_wen):
    # with the default order (4, 4) and a one-sample delay to start from, the fit kept the
    # delay (plain PI) at twice the error of a fit given the true dynamics
    v, x = bouc_wen.record.input, bouc_wen.record.output
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hy.FitWarning)
        fit = hy.fit_hammerstein([(v, x)], fs=FS)
        known = hy.fit_hammerstein([(v, x)], fs=FS, dynamics=hy.HammersteinModel(
            fit.model.hysteresis, tuple(bouc_wen.b), tuple(bouc_wen.a), FS).dynamics)
    assert len(fit.model.a) > 2 and set(fit.order_scores) == set(hy.AUTO_ORDERS)
    assert fit.rms_percent[0] < 1.1 * known.rms_percent[0]
    # the feedforward of a sine over the record's stroke tracks it on the generating stage
    stroke = np.percentile(x, [5, 95])
    t = np.arange(int(2 * FS)) / FS
    x_r = stroke.mean() + 0.5 * np.ptp(stroke) * np.sin(2 * np.pi * t - np.pi / 2)
    v_ff = fit.model.feedforward(x_r)
    assert np.ptp(v_ff) == pytest.approx(np.ptp(stroke) / 0.115, rel=0.2)   # about 0.115 um/V
    error = bouc_wen.plant(v_ff)[int(FS):] - x_r[int(FS):]          # after the first period
    assert 100 * np.sqrt(np.mean(error ** 2)) / np.ptp(x) < 1.0


def test_dynamics_that_hide_the_slope_get_a_warning():
    # a stage whose dynamics pass 1 Hz at a third of their DC gain: the record cannot tell
    # the DC gain (the slope) from the dynamics, and the fit says so
    import scipy.signal as sg
    t = np.arange(4000) / FS
    v = 150 * np.sin(2 * np.pi * t)
    p = hy.PIModel((0.0, 50.0), (0.1, 0.03)).simulate(v)
    x = sg.lfilter([0.0, 0.002], [1.0, -0.998], p)
    with pytest.warns(hy.FitWarning, match="dynamics are not identified|slope is not"):
        hy.fit_hammerstein([(v, x)], fs=FS, order=(1, 1), thresholds=(0.0, 50.0))


def test_best_achievable_lies_between_the_noise_floor_and_a_plain_pi_fit(bouc_wen):
    best = F.best_achievable(bouc_wen, levels=8, rows=3000)
    assert best.noise_floor_percent <= best.whole_percent < 0.3
    assert best.out_of_sample_percent < 0.3
    with pytest.raises(ValueError, match="family must be one of"):
        F.foreign_raw_record("dahl")
