"""Hammerstein models: play operators and least-squares weights on synthetic truth."""

import control as ct
import numpy as np
import pytest

from piezolib.identification import MIMOHammerstein, fit_play_weights, play_operators

FS = 1000.0


def _multisine(rng, N, n_u, R, P, rms):
    X = np.zeros((N // 2 + 1, n_u, R), complex)
    X[1:N // 4] = np.exp(2j * np.pi * rng.random((N // 4 - 1, n_u, R)))
    x = np.fft.irfft(X, n=N, axis=0)
    x *= rms / x.std(axis=0)
    return np.repeat(x[..., None], P, axis=3)


def test_play_operator_is_a_backlash():
    u = np.r_[np.linspace(0, 1, 11), np.linspace(0.9, -1, 20), np.linspace(-0.9, 1, 20)]
    p = play_operators(u[:, None, None], [0.0, 0.3])[:, 0, :, 0]
    assert np.array_equal(p[:, 0], u)                        # r = 0: the identity
    assert np.all(np.abs(p[:, 1] - u) <= 0.3 + 1e-12)        # never further than r from u
    assert np.isclose(p[10, 1], 0.7) and np.isclose(p[30, 1], -0.7)   # lags by r on strokes
    # rate independent: the same path sampled twice as densely gives the same values
    u2 = np.interp(np.arange(0, u.size - 0.5, 0.5), np.arange(u.size), u)
    p2 = play_operators(u2[:, None], [0.3])[::2, 0, 0]
    assert np.allclose(p2, p[:, 1])


def test_fit_recovers_known_weights_exactly():
    rng = np.random.default_rng(3)
    linear = ct.ss(ct.tf([[[0.3, 0.1], [0.1]], [[0.2], [0.4, -0.1]]],
                         [[[1, -1.2, 0.6], [1, -0.5]], [[1, -0.3], [1, -1.2, 0.6]]], 1 / FS))
    truth = MIMOHammerstein(linear, np.array([0.0, 0.2, 0.5]),
                             np.array([[1.0, -0.3, 0.1], [0.8, 0.2, -0.15]]))
    us, ys = [], []
    for rms in (0.3, 0.9):                   # two levels, as in a benchmark
        u = _multisine(rng, 256, 2, 3, 2, rms)
        # steady state: simulate three copies, keep the last two periods
        long = np.concatenate([u[..., 0]] * 4, axis=0)
        y = truth.simulate(long)[2 * 256:]
        ys.append(np.stack([y[:256], y[256:]], axis=-1))
        us.append(u)
    fit = fit_play_weights(linear, us, ys, truth.thresholds, np.arange(1, 64))
    assert np.allclose(fit.weights, truth.weights, atol=1e-6)
    assert fit.linear is linear


def test_one_level_and_noise():
    rng = np.random.default_rng(4)
    linear = ct.ss(ct.tf([0.5], [1, -0.5], 1 / FS))
    truth = MIMOHammerstein(linear, np.array([0.0, 0.4]), np.array([[1.0, 0.5]]))
    u = _multisine(rng, 512, 1, 4, 2, 0.5)
    long = np.concatenate([u[..., 0]] * 4, axis=0)
    y = truth.simulate(long)[2 * 512:]
    y = np.stack([y[:512], y[512:]], axis=-1) + 1e-3 * rng.standard_normal((512, 1, 4, 2))
    fit = fit_play_weights(linear, u, y, truth.thresholds, np.arange(1, 128))
    assert np.allclose(fit.weights, truth.weights, atol=0.05)


def test_simulate_checks_channels():
    m = MIMOHammerstein(ct.ss(ct.tf([0.5], [1, -0.5], 1 / FS)), np.array([0.0]),
                         np.array([[1.0]]))
    with pytest.raises(ValueError, match="u must have 1 channels"):
        m.simulate(np.zeros((10, 2)))
