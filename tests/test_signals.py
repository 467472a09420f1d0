"""Reference and excitation signals: sampling, shape, argument checks."""

import numpy as np
import pytest

from piezolib import signals

FS = 10e3


def test_time_vector_covers_the_duration_at_fs():
    t = signals.time_vector(0.25, FS)
    assert len(t) == 2500 and t[0] == 0.0 and t[-1] == pytest.approx(0.25 - 1 / FS)
    assert np.allclose(np.diff(t), 1 / FS)
    with pytest.raises(ValueError, match="fewer than 2 samples"):
        signals.time_vector(1e-4, FS)


def test_triangle_rises_to_its_peak_and_closes_each_period():
    t, y = signals.triangle(4.0, 10.0, FS, periods=2)
    assert len(t) == 2001 and y[0] == 0.0 and y[-1] == 0.0
    assert y.max() == 4.0 and y[500] == 4.0 and y[1000] == 0.0
    _, shifted = signals.triangle(4.0, 10.0, 1000.0, minimum=1.0)
    assert shifted.min() == 1.0 and shifted.max() == 4.0 and len(shifted) == 101
    with pytest.raises(ValueError, match="exceed minimum"):
        signals.triangle(0.0, 10.0, FS)
    with pytest.raises(ValueError, match="at least 4"):
        signals.triangle(1.0, 10.0, 30.0)


def test_chirp_starts_at_its_crest_and_checks_its_band():
    t, y = signals.chirp(0.5, 10.0, 1000.0, 0.5, FS)
    assert len(t) == 5000 and y[0] == 0.5 and np.max(np.abs(y)) <= 0.5
    with pytest.raises(ValueError, match="f1_Hz"):
        signals.chirp(0.5, 10.0, 6000.0, 0.5, FS)
    with pytest.raises(ValueError, match="method"):
        signals.chirp(0.5, 10.0, 100.0, 0.5, FS, method="quadratic")


@pytest.mark.parametrize("call", [
    lambda: signals.time_vector(1.0),
    lambda: signals.triangle(1.0, 10.0, periods=2),
    lambda: signals.chirp(0.5, 10.0, 1000.0, 0.5),
], ids=["time_vector", "triangle", "chirp"])
def test_sampling_frequency_is_required(call):
    with pytest.raises(TypeError, match="fs"):
        call()
