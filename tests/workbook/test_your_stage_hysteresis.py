"""Notebook 08's hysteresis stages (piezolib.workbook.your_stage_hysteresis) on loops of a
known Prandtl-Ishlinskii truth: the loops' cut, the choice by validation on records not
fitted or on held-out halves, the feedforward cross-check."""

import numpy as np
import pytest
import scipy.signal as sg

from piezolib import hysteresis as hy
from piezolib.records import Record
from piezolib.workbook import your_stage as own
from piezolib.workbook import your_stage_hysteresis as own_hysteresis

FS = 5000.0


def loop_pair(freq=1.0, amplitude=1.5, n=400):
    t = np.arange(n) / 100.0
    v = amplitude - amplitude * np.cos(2 * np.pi * freq * t)
    return v, PI_TRUTH.simulate(v)


PI_TRUTH = hy.PIModel((0.0, 0.3, 0.6, 0.9), (0.8, 0.2, 0.15, 0.1), x0=0.1)


def test_prepare_loops_starts_each_loop_at_a_minimum_and_scales_to_sensor_volts():
    v, x = loop_pair(n=600)
    rec = Record(v[50:], 3.0 * x[50:], FS)            # from a maximum: cut at the next minimum
    loops = own_hysteresis.prepare_loops(own.OwnRecords(None, {"a": rec}, FS), 3.0, 1,
                                         skip_transient=False)
    u, y = loops.data["a"]
    assert u[0] == pytest.approx(v.min(), abs=1e-3) and loops.dropped == {}
    assert loops.fs == FS
    assert y.max() == pytest.approx(x.max())


def quick_fits(monkeypatch):
    """fit_dahl replaced by a two-play PI fit: the choice logic without the slow Dahl fit."""
    monkeypatch.setattr(hy, "fit_dahl",
                        lambda data, gamma_a, **kw: hy.fit_pi(data, n_plays=2, offset=True))


def test_fit_hysteresis_holds_out_the_second_half_when_nothing_else_validates(monkeypatch):
    quick_fits(monkeypatch)
    loops = own_hysteresis.HysteresisLoops({"raw": loop_pair()}, {}, 100.0)
    choice = own_hysteresis.fit_hysteresis(loops, ["raw"], [], gamma_a=30.0, plays=4,
                                           ceiling_percent=5.0)
    assert choice.held_out_in_time and choice.validation_names == ["raw (second half)"]
    assert "validated on the second half (held out in time)" in str(choice)
    assert choice.chosen_name in ("PI", "Hammerstein")    # plays fit the four-play truth
    assert all(choice.checks.values())


def test_fit_hysteresis_has_the_hammerstein_model_among_its_candidates(monkeypatch):
    # a stage whose plays drive a first-order lag: only the Hammerstein model follows it
    quick_fits(monkeypatch)
    v, p = loop_pair(n=800)
    x = p[0] + sg.lfilter([0.0, 0.3], [1.0, -0.7], p - p[0])
    loops = own_hysteresis.HysteresisLoops({"a": (v[:400], x[:400]), "b": (v[400:], x[400:])},
                                           {}, 100.0)
    choice = own_hysteresis.fit_hysteresis(loops, ("a",), ("b",), gamma_a=30.0, plays=4,
                                           ceiling_percent=5.0)
    assert set(choice.fits) == {"Dahl", "PI", "Hammerstein"}
    assert choice.chosen_name == "Hammerstein"
    assert choice.validation_rms("Hammerstein") < 0.2 * choice.validation_rms("PI")
    assert "Hammerstein" in str(choice)
    # the Hammerstein fit's operator (PI plays or a Preisach grid) is said, with its scores
    hammerstein = choice.fits["Hammerstein"]
    assert f"Hammerstein operator: {hammerstein.operator} (" in str(choice)
    assert set(hammerstein.extrapolation_scores) == set(hy.OPERATORS)


def test_fit_hysteresis_validates_on_the_records_not_fitted(monkeypatch):
    quick_fits(monkeypatch)
    loops = own_hysteresis.HysteresisLoops({"a": loop_pair(), "b": loop_pair(1.3, 1.2)}, {},
                                            100.0)
    choice = own_hysteresis.fit_hysteresis(loops, ("a",), ("a", "b"), gamma_a=30.0,
                                           plays=4, ceiling_percent=5.0)
    assert not choice.held_out_in_time and choice.validation_names == ["b"]
    assert choice.validation_rms("PI") == choice.scores["pooled RMS %"].min()
    ff = own_hysteresis.feedforward_cross_check(choice)
    assert ff.checks == {"the chosen model's feedforward inverts it (RMS below 0.5 %)": True}
    with pytest.raises(ValueError, match="fit_loops"):
        own_hysteresis.fit_hysteresis(loops, ("c",), (), gamma_a=30.0, plays=4,
                                      ceiling_percent=5.0)
