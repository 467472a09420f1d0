"""The coefficient model set audited (notebook 02), on textbook third-order plants."""

import control as ct
import numpy as np
import pytest

from piezolib import uncertainty as unc
from piezolib.problem import coefficient_set as cs

#: s^3 + s^2 + 1.02 s + 1: stable (a2 a1 > a0) by 2 %, so +-5 % on the coefficients breaks it
MARGINAL = ct.tf([1.0], [1.0, 1.0, 1.02, 1.0])
#: 1/(s + 1)^3 with K = 1: a well-damped loop
CUBE, GAIN = ct.tf([1.0], [1.0, 3.0, 3.0, 1.0]), ct.tf([1.0], [1.0])
OMEGA = np.logspace(-2, 2, 64)
#: a coarse grid for the loop margins (small gain searches a spread on it)
COARSE = np.logspace(-1, 1, 24)


def test_survey_finds_the_members_hurwitz_says_are_unstable():
    survey = cs.survey_model_set(MARGINAL, 0.05, 3)
    assert survey.mset.size == 27 and all(survey.checks.values())
    # Hurwitz for a cubic: unstable exactly when a2 a1 <= a0
    a = np.array([1.0, 1.02, 1.0])[None, :] * (1 + 0.05 * survey.mset.offsets)
    assert survey.unstable.tolist() == np.flatnonzero(a[:, 2] * a[:, 1] <= a[:, 0]).tolist()
    table = survey.unstable_table()
    assert list(table.columns[:3]) == ["q0", "q1", "q2"] and len(table) == survey.unstable.size
    crossings = survey.crossings()
    assert crossings["unstable members"] == survey.unstable.size
    assert crossings["... up to [rad/s]"] == pytest.approx(1.0, abs=0.5)


def test_a_stable_set_has_no_crossings():
    crossings = cs.survey_model_set(CUBE, 0.05, 3).crossings()
    assert crossings["unstable members"] == 0
    assert "... up to [rad/s]" not in crossings


def test_envelope_peaks_lie_above_every_grid_maximum():
    survey = cs.survey_model_set(CUBE, 0.05, 3)
    peaks = cs.envelope_peaks(survey, OMEGA, grid_sizes=(50, 100))
    assert all(peaks.stable[0] >= value for value in peaks.grid_maxima.values())
    assert peaks.all[0] >= peaks.stable[0] and 0 < peaks.damping <= 1
    assert peaks.table()["refined peak at [rad/s]"] == peaks.stable[1]


def test_cover_and_spreads_with_a_first_order_weight():
    survey = cs.survey_model_set(CUBE, 0.05, 3)
    peaks = cs.envelope_peaks(survey, OMEGA, grid_sizes=(50,))
    H_m = ct.tf([0.5], [1.0])
    cover = cs.cover_envelope(survey, OMEGA, H_m, order=1)
    assert cover.order == 1 and all(cover.checks.values()) and cover.published.covers
    spreads = cs.compare_spreads(CUBE, H_m, OMEGA, (0.01,), survey, cover, peaks, order=1)
    assert list(spreads.table.index) == [1.0, 5.0] and all(spreads.checks.values())
    # the envelope grows with the spread: the constant weight's worst ratio falls
    assert spreads.table["H_m worst ratio"].is_monotonic_decreasing


def test_loop_margins_order_the_views_and_find_the_critical_member():
    survey = cs.survey_model_set(CUBE, 0.05, 3)
    margins = cs.loop_margins(CUBE, GAIN, ct.tf([0.05], [1.0]), survey, COARSE)
    checks = margins.checks
    assert checks["the critical member's closed loop has a pole pair at +-j omega*"]
    assert checks["H_m certifies at most small gain, small gain less than the exact margin"]
    # K = 1 narrows this plant's margin: the check that it widens it can fail, and does
    assert not checks["the exact margin is bounded and above the open-loop one"]
    assert margins.margin.spread < margins.open_loop.spread
    table = margins.spreads_table(cs.covered_spreads(ct.tf([0.05], [1.0]), CUBE, COARSE).set, 3)
    assert table.loc["exact margin delta* (real, zero exclusion)", "delta* / spread"] == 1.0
    lines = cs.findings(cs.envelope_peaks(survey, OMEGA, grid_sizes=(50,)),
                        cs.cover_envelope(survey, OMEGA, ct.tf([0.5], [1.0]), order=1),
                        margins, 0.48)
    assert len(lines) == 3 and "small gain" in lines[2]


def test_margin_gauges_have_their_minimum_at_the_margin():
    omega, gauge, gauge_open = cs.margin_gauges(CUBE, GAIN, np.logspace(-1, 1, 400))
    margin = unc.parametric_stability_margin(CUBE, GAIN)
    assert gauge.min() >= margin.spread * (1 - 1e-9)
    assert gauge.min() == pytest.approx(margin.spread, rel=1e-2)
    assert gauge_open.shape == omega.shape


def test_critical_offsets_kind():
    assert cs.critical_offsets_kind([-1, 1, 1, -1, -1, 1]) == "a Kharitonov polynomial"
    assert cs.critical_offsets_kind([1, 1, 1]) == "a corner of the box"
    assert cs.critical_offsets_kind([1, 0.2, -1]) == "not a corner"
    with pytest.raises(ValueError, match="offsets"):
        cs.critical_offsets_kind([np.nan])


def test_bad_input_names_the_argument():
    with pytest.raises(TypeError, match="survey"):
        cs.envelope_peaks("set", OMEGA)
    with pytest.raises(ValueError, match="omega"):
        cs.cover_envelope(cs.survey_model_set(CUBE, 0.05, 2), -OMEGA, CUBE)
