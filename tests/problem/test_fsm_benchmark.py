"""The FSM benchmark's files, metric and noise floor."""

import control as ct
import numpy as np
import pytest

from piezolib import robust
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


def test_axis_design_plant_closes_the_loop_of_its_docstring():
    # G (1 + W Delta) at the output: y_Delta = -W T u_Delta + W T v_r, y1 = W_S S (v_r - u_Delta),
    # y2 = W_T (S u_Delta + T v_r), y_u = W_u K S (v_r - u_Delta); a negligible delay (fs = 1e9)
    G = ct.tf([2.0], [1.0, 0.4, 4.0])
    W, W_S, W_T, W_u = (ct.tf([1.0, 2.0], [1.0, 20.0]), ct.tf([0.5, 1.0], [1.0, 0.01]),
                        ct.tf([1.0, 1.0], [0.1, 10.0]), ct.tf([0.01], [1.0]))
    K = ct.tf([1.0, 1.0], [1.0, 0.0])
    omega = np.logspace(-1, 2, 40)
    s = 1j * omega
    g, k = np.ravel(G(s)), np.ravel(K(s))
    S = 1 / (1 + g * k)
    T = 1 - S
    w, ws, wt, wu = (np.ravel(x(s)) for x in (W, W_S, W_T, W_u))
    expected = np.stack([np.stack([-w * T, w * T], -1), np.stack([-ws * S, ws * S], -1),
                         np.stack([wt * S, wt * T], -1), np.stack([-wu * k * S, wu * k * S], -1)],
                        axis=1)
    P = fsm.axis_design_plant(G, W, W_S, W_T, W_u, fs=1e9, delay_samples=None)
    assert P.input_labels == ["u_Delta", "v_r", "u_b"]
    assert P.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"]
    assert np.allclose(robust.lft_response(P, K, omega), expected, rtol=1e-6, atol=1e-9)
