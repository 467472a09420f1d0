"""Hysteresis truth of the virtual stage: the play operator and the law it is chosen from."""

import numpy as np
import pytest

from piezolib import paper, signals
from piezolib.problem import stage_hysteresis as H

FS = paper.SAMPLING_FREQUENCY_HZ


def test_play_operator_matches_its_definition():
    h = H.CALIBRATED_HYSTERESIS.operator()
    rng = np.random.default_rng(3)
    v = np.cumsum(rng.normal(0, 2.0, 3000))
    v[100:120] = v[99]                                 # repeated samples
    out, state = h.apply(v)
    y = np.array(h.initial_state(0.0))
    r, w = np.array(h.thresholds_V), np.array(h.weights)
    ref = []
    for vk in v:
        y = np.minimum(np.maximum(y, vk - r), vk + r)
        ref.append(vk + w @ (y - r))
    assert np.allclose(out, ref, rtol=0, atol=1e-12)
    assert np.allclose(state, y)


def test_chord_gain_and_return_to_zero():
    h = H.CALIBRATED_HYSTERESIS.operator()
    _, v = signals.triangle(40.0, 10.0, FS, periods=2)
    out, _ = h.apply(v)
    assert out[0] == pytest.approx(0.0, abs=1e-12) and out[-1] == pytest.approx(0.0, abs=1e-12)
    assert out.max() / 40.0 == pytest.approx(h.chord_gain(40.0), rel=1e-12)
    assert h.chord_gain(0.5) == h.linear_weight == 1.0
