"""Tustin discretisation with pre-warping, response and sampled-loop checks."""

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib.robust.discrete import discretize, least_damped_frequency

FS = 10e3       # [Hz]


def test_tustin_matches_below_1khz_and_is_exact_at_the_prewarp_frequency():
    K = ct.tf([1, 2 * 0.05 * 3000, 3000 ** 2], [1, 2 * 0.7 * 3000, 3000 ** 2])  # notch
    assert least_damped_frequency(K, 1e4) == pytest.approx(3000, rel=1e-9)
    d = discretize(K, FS, prewarp="auto")
    assert d.prewarp_frequency == pytest.approx(3000, rel=1e-9)
    w0 = 3000.0
    kd = np.ravel(d.K(np.exp(1j * w0 / d.fs)))
    assert kd[0] == pytest.approx(np.ravel(K(1j * w0))[0], rel=1e-9)
    assert d.matches and d.max_relative_error < 0.1
    plain = discretize(K, FS, prewarp=None)
    assert plain.max_relative_error > d.max_relative_error


def test_discretised_design_loop(paper_design):
    d = paper_design.discrete
    assert d.fs == paper.SAMPLING_FREQUENCY_HZ and d.K.dt == pytest.approx(1e-4)
    assert d.matches and d.loop_stable


def test_sampling_rate_is_required_and_used():
    K = ct.tf([1, 2 * 0.05 * 3000, 3000 ** 2], [1, 2 * 0.7 * 3000, 3000 ** 2])
    with pytest.raises(TypeError, match="fs"):
        discretize(K)
    slow = discretize(K, 4e3, check_Hz=500.0)
    assert slow.fs == 4e3 and slow.K.dt == pytest.approx(2.5e-4)
    # a slower rate warps more: the same check band matches less well
    assert slow.max_relative_error > discretize(K, FS, check_Hz=500.0).max_relative_error


def test_sampled_loop_check():
    G = ct.tf([1e3], [1, 1e3])
    K = ct.tf([5e3], [1, 1e3])                           # DC loop gain 5
    ok = discretize(K, FS, G=G)
    assert ok.loop_stable and ok.loop_spectral_radius < 1
    bad = discretize(-K, FS, G=G)                         # positive feedback, unstable
    assert bad.loop_stable is False and bad.loop_spectral_radius > 1
    assert discretize(K, FS).loop_stable is None


def test_discretize_rejects_bad_input():
    with pytest.raises(ValueError, match="Nyquist"):
        discretize(ct.tf([1], [1, 1]), FS, check_Hz=6000)
    with pytest.raises(ValueError, match="continuous-time"):
        discretize(ct.tf([1], [1, 1], 1e-3), FS)
    with pytest.raises(ValueError, match="fs must be positive"):
        discretize(ct.tf([1], [1, 1]), -1.0)
