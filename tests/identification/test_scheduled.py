"""Amplitude-scheduled models: the schedule from the input, blending between levels."""

import control as ct
import numpy as np
import pytest

from piezolib.identification import ScheduledModel, input_rms, simulate_discrete

DT = 1e-3
M1 = ct.ss(ct.tf([0.2], [1, -0.8], DT))
M2 = ct.ss(ct.tf([0.5, 0.1], [1, -0.3], DT))


def test_input_rms_per_record():
    u = np.zeros((4, 2, 3))
    u[:, :, 1] = 2.0
    u[:, 0, 2] = 1.0
    assert np.allclose(input_rms(u), [0.0, 2.0, np.sqrt(0.5)])


@pytest.mark.parametrize("scale, expected", [(1.0, (1.0, 0.0)), (3.0, (0.0, 1.0)),
                                             (2.0, (0.5, 0.5)), (0.2, (1.0, 0.0)),
                                             (10.0, (0.0, 1.0))])
def test_blend_is_linear_between_levels_and_clamped(scale, expected):
    u = np.random.default_rng(0).standard_normal((300, 1, 1))
    u *= scale / input_rms(u)
    m = ScheduledModel((M1, M2), (1.0, 3.0))
    assert np.allclose(m.blend_weights(u)[:, 0], expected)
    y = m.simulate(u)
    want = expected[0] * simulate_discrete(M1, u) + expected[1] * simulate_discrete(M2, u)
    assert np.allclose(y, want)


def test_not_linear_in_amplitude():
    u = np.random.default_rng(1).standard_normal((200, 1))
    m = ScheduledModel((M1, M2), (0.5, 2.0))
    assert not np.allclose(m.simulate(2 * u), 2 * m.simulate(u))


@pytest.mark.parametrize("models, levels, match", [
    ((M1, M2), (2.0, 1.0), "levels"),
    ((M1,), (1.0, 2.0), "levels"),
    ((), (), "models"),
    ((M1, ct.ss(ct.tf([1], [1, 1]))), (1.0, 2.0), "models\\[1\\]"),
    ((M1, np.ones(2)), (1.0, 2.0), "models\\[1\\]"),
])
def test_bad_construction(models, levels, match):
    with pytest.raises((ValueError, TypeError), match=match):
        ScheduledModel(models, levels)
