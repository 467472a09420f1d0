"""Records made ready for fitting (piezolib.records.preparation): turning points and cuts,
decimation, split and detrend, the start-up of raw records that start at rest."""

import numpy as np
import pytest

from piezolib import records as R

FS = 5000.0


def loop_record(periods=4, fs=FS, f=10.0, rest=250, noise=0.0):
    n = int(periods * fs / f)
    u = np.r_[np.zeros(rest), 2.0 + 1.5 * np.sin(2 * np.pi * f * np.arange(n) / fs)]
    y = 3 * u + noise * np.random.default_rng(0).standard_normal(len(u))
    return R.Record(u, y, fs, output_unit="um")


def test_turning_points_and_cut_ignore_noise_and_the_start():
    rec = loop_record()
    points = R.turning_points(rec.input)
    quarter = FS / 10 / 4
    expected = 250 + quarter + 2 * quarter * np.arange(8)
    assert len(points) == 8 and np.all(np.abs(points - expected) <= 1)
    noisy = rec.input + 0.003 * np.random.default_rng(1).standard_normal(len(rec))
    assert len(R.turning_points(noisy)) == 8                       # noise makes no extra points
    cut = R.cut_at_turning_points(rec)
    assert cut.metadata["cut"] == (points[0], points[-1] + 1)
    assert cut.input[0] == rec.input[points[0]] and cut.t0 == pytest.approx(points[0] / FS)
    with pytest.raises(R.RecordError, match="turning point"):
        R.cut_at_turning_points(R.Record(np.arange(100.0), np.arange(100.0), FS))


def test_decimate_filters_before_keeping_samples():
    fs, n = 10e3, 20000
    t = np.arange(n) / fs
    slow, fast = np.sin(2 * np.pi * 20 * t), 0.5 * np.sin(2 * np.pi * 3900 * t)
    rec = R.Record(slow + fast, slow, fs)
    dec = R.decimate(rec, 5)
    assert dec.fs == 2000.0 and len(dec) == n // 5
    inner = slice(100, -100)
    # 3.9 kHz would alias to 100 Hz at 2 kHz: the filter removes it instead
    assert np.max(np.abs(dec.input[inner] - slow[::5][inner])) < 0.01
    assert R.decimate(rec, 1) is rec
    with pytest.raises(R.RecordError, match="too short"):
        R.decimate(R.Record(np.arange(50.0), np.arange(50.0), fs), 5)


@pytest.mark.parametrize("factor", [2, 5, 8])
def test_decimate_keeps_a_sines_amplitude_to_the_first_and_last_sample(factor):
    # a raw record's +-150 V, 1 Hz sine over 6.7 periods at 5 kHz: zero padding made it
    # swing +-162.7 V and start at -90 V
    t = np.arange(int(6.7 * FS)) / FS
    u = -150.0 * np.cos(2 * np.pi * t + 0.3)
    dec = R.decimate(R.Record(u, 0.25 * u, FS), factor)
    error = np.abs(dec.input - u[::factor])
    assert len(dec) == len(u[::factor])
    assert error[0] < 0.15 and error[-1] < 0.15 and error.max() < 0.15     # 0.1 % of 150 V
    assert np.max(np.abs(dec.output - 0.25 * u[::factor])) < 0.25 * 0.15


def test_split_and_detrend():
    rec = loop_record()
    first, second = R.split(rec, 0.25)
    assert len(first) + len(second) == len(rec)
    assert len(first) == round(0.25 * len(rec))
    assert second.t0 == pytest.approx(len(first) / FS)
    with pytest.raises(ValueError, match="fraction"):
        R.split(rec, 1.0)
    flat = R.detrend(rec.with_signals(output=rec.output + 2.0 + np.arange(len(rec)) * 1e-3),
                     kind="linear")
    assert abs(np.polyfit(np.arange(len(rec)), flat.output, 1)[0]) < 1e-12
    assert np.array_equal(flat.input, rec.input)
    with pytest.raises(ValueError, match="which"):
        R.detrend(rec, which="time")


# --- raw records that start at rest ------------------------------------------------------
def raw_record(noise=2e-3, seed=0):
    """Rest, a step onto the input's top (the step is the first turning point), a lightly
    damped resonance ringing after it, then 2 Hz cosines dipping from the top."""
    import scipy.signal as sg
    n = int(FS / 2)
    phase = 2 * np.pi * np.arange(n) / n
    u = np.concatenate([np.zeros(500)] + [3 - a * (1 - np.cos(phase)) for a in (0.5, 1, 1.5)])
    w0, zeta = 2 * np.pi * 300, 0.03
    b, a = sg.cont2discrete(([w0 ** 2], [1, 2 * zeta * w0, w0 ** 2]), 1 / FS, method="zoh")[:2]
    y = sg.lfilter(np.ravel(b), a, u) + np.random.default_rng(seed).normal(0, noise, u.size)
    return R.Record(u, y, FS)


def test_the_default_cut_keeps_the_step_and_its_ringing():
    rec = raw_record()
    assert R.cut_at_turning_points(rec).metadata["cut"][0] == 500    # the step sample itself


def test_skip_transient_drops_rest_step_ringing_and_virgin_stroke(caplog):
    rec = raw_record()
    start_up = R.find_start_up(rec)
    assert start_up.rest_end == start_up.step == 500
    ringing_ms = 1e3 * (start_up.settled - start_up.step) / FS
    assert 20 < ringing_ms < 250       # 1/(zeta w0) = 18 ms: it decays into 2 mV noise
    first_minimum = 500 + int(FS / 4)  # the first cosine's bottom, a quarter second later
    assert abs(start_up.first_turning_point - first_minimum) <= 2
    with caplog.at_level("INFO", logger="piezolib.records"):
        cut = R.cut_at_turning_points(rec, skip_transient=True)
    assert cut.metadata["cut"][0] == start_up.first_turning_point
    assert cut.metadata["start_up"] == start_up
    assert "step" in cut.metadata["dropped"] and "ringing" in cut.metadata["dropped"]
    assert "dropped" in caplog.text and "ringing" in caplog.text
    # what is left has no ringing: the output's second difference is at the noise level
    assert np.abs(np.diff(cut.output, 2)).max() < 8 * np.sqrt(6) * 2e-3


def test_skip_transient_says_where_it_cut_and_from_which_extreme(caplog):
    # the cut of a raw record that lands on an input maximum (after which every start but
    # "maximum" fits badly) was said nowhere: only what the start-up held was logged
    t = np.arange(int(2.2 * FS)) / FS
    u = np.r_[np.zeros(500), 150 * np.sin(2 * np.pi * t + np.arcsin(-87 / 150))]
    rec = R.Record(u, 0.1 * u, FS)
    with caplog.at_level("INFO", logger="piezolib.records"):
        cut = R.cut_at_turning_points(rec, skip_transient=True)
    a, b = cut.metadata["cut"]
    assert cut.metadata["starts_at"] == "maximum" and u[a] == pytest.approx(150, abs=0.1)
    assert f"cut at samples {a} to {b - 1}" in caplog.text
    assert "a maximum of 150 V" in caplog.text and "after an ascending stroke" in caplog.text
    at_minimum = R.cut_at_turning_points(rec, skip_transient=True, first=1)
    assert at_minimum.metadata["starts_at"] == "minimum"
    assert "turning point 1 after the start-up" in at_minimum.metadata["cut_note"]


def test_a_record_without_start_up_loses_only_its_first_stroke():
    t = np.arange(2000) / FS
    u = np.sin(2 * np.pi * 5 * t)
    rec = R.Record(u, 2 * u, FS)
    start_up = R.find_start_up(rec)
    assert start_up.step is None and start_up.rest_end <= 1     # moves from its second sample
    assert start_up.first_turning_point == R.turning_points(u)[0]
    assert R.cut_at_turning_points(rec, skip_transient=True).metadata["cut"] == \
        R.cut_at_turning_points(rec).metadata["cut"]
    with pytest.raises(TypeError, match="skip_transient"):
        R.cut_at_turning_points(rec, skip_transient="yes")
    with pytest.raises(R.RecordError, match="constant"):
        R.find_start_up(R.Record(np.ones(10), t[:10], FS))


def test_find_start_up_refuses_bad_input():
    rec = raw_record()
    with pytest.raises(TypeError, match="record"):
        R.find_start_up(rec.input)
    for bad in (0.0, 1.0, -0.1):
        with pytest.raises(ValueError, match="threshold"):
            R.find_start_up(rec, threshold=bad)
