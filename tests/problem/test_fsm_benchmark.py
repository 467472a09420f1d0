"""The FSM benchmark's files, metric and noise floor."""

import control as ct
import numpy as np
import pytest

from piezolib.problem import fsm_benchmark as fsm


def test_committed_files_are_intact_and_shaped():
    assert fsm.check_files() == {}
    u, y = fsm.load(200, "train")
    assert u.shape == y.shape == (8192, 3, 6, 2)


def test_zero_model_scores_one_and_the_floor_is_small():
    zero = ct.ss(np.zeros((1, 1)), np.zeros((1, 3)), np.zeros((3, 1)), np.zeros((3, 3)),
                 1 / fsm.SAMPLING_FREQUENCY_HZ)
    s = fsm.score(zero, 100)
    assert s.nrmse_percent == pytest.approx(100 * np.sqrt(1 + 0.0), rel=0.01)   # y has ~zero mean
    assert 0 < fsm.noise_floor(100).nrmse_percent < 5
