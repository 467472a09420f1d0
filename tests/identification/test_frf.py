"""The robust BLA estimate on synthetic 2 x 2 systems with known truth."""

import control as ct
import numpy as np
import pytest
import scipy.signal

from piezolib.identification import bla_periodic, excited_lines

FS = 1000.0
N = 256
LINES = np.arange(1, 100)                       # excited lines (up to 387 Hz)
TRUE = ct.ss(ct.tf([[[0.3, 0.1], [0.2]], [[0.1], [0.25, -0.05]]],
                   [[[1.0, -1.4, 0.74], [1.0, -0.6]], [[1.0, -0.8], [1.0, -1.4, 0.74]]], 1 / FS))


def orthogonal_multisines(rng, n_groups, n_periods):
    """Input (N, 2, 2 * n_groups, P): per group two random-phase multisines mixed by a
    2 x 2 orthogonal matrix (U(k) = diag(X(k)) T, optimally conditioned)."""
    T = np.array([[1.0, 1.0], [1.0, -1.0]])
    groups = []
    for _ in range(n_groups):
        X = np.zeros((N // 2 + 1, 2), complex)
        X[LINES] = np.exp(2j * np.pi * rng.random((LINES.size, 2)))
        x = np.fft.irfft(X, n=N, axis=0)
        x /= x.std()
        groups.append(np.einsum("nc,cr->ncr", x, T))
    u = np.concatenate(groups, axis=2)
    return np.repeat(u[..., None], n_periods, axis=3)


def steady_state(u, nonlinearity=None):
    """The system's periodic steady state: simulate three periods, keep the last."""
    n_y = TRUE.noutputs
    y = np.empty((N, n_y) + u.shape[2:])
    b, a = [], []
    for i in range(n_y):
        for j in range(TRUE.ninputs):
            num, den = ct.tfdata(ct.tf(TRUE[i, j]))
            num, den = np.ravel(num[0][0]), np.ravel(den[0][0])
            # polynomials in z -> in z^-1: pad the numerator to the denominator's length
            b.append((i, j, np.r_[np.zeros(den.size - num.size), num], den))
    for r in range(u.shape[2]):
        one = np.tile(u[:, :, r, 0], (3, 1))
        out = np.zeros((3 * N, n_y))
        for i, j, num, den in b:
            out[:, i] += scipy.signal.lfilter(num, den, one[:, j])
        if nonlinearity is not None:
            out = nonlinearity(out)
        y[:, :, r, :] = out[-N:, :, None]
    return y


def truth():
    return TRUE(np.exp(2j * np.pi * LINES / N))


def test_excited_lines_found_in_a_noisy_input():
    rng = np.random.default_rng(0)
    u = orthogonal_multisines(rng, 2, 2)
    noisy = u + 1e-3 * rng.standard_normal(u.shape)
    np.testing.assert_array_equal(excited_lines(noisy), LINES)


def test_linear_system_recovered_within_its_standard_deviation():
    rng = np.random.default_rng(1)
    u = orthogonal_multisines(rng, n_groups=4, n_periods=8)
    sigma = 0.02
    y = steady_state(u) + sigma * rng.standard_normal(u.shape)
    bla = bla_periodic(u, y, FS)
    np.testing.assert_array_equal(bla.lines, LINES)
    np.testing.assert_allclose(bla.frequency_Hz, LINES * FS / N)
    G0 = truth()
    z = np.abs(bla.G - G0) / bla.std_noise                  # about Rayleigh(1/sqrt(2))
    assert np.mean(z ** 2) == pytest.approx(1.0, rel=0.1)
    assert np.mean(z < 3) > 0.99
    # linear system: total and noise variances agree, no distortion to speak of
    ratio = np.mean(bla.var_total) / np.mean(bla.var_noise)
    assert ratio == pytest.approx(1.0, rel=0.15)


def test_noise_variance_matches_the_noise_that_was_added():
    """Var(G) from output noise: sum_j sigma^2 |U^-1|^2 / (P M); |U^-1|^2 known from the input."""
    rng = np.random.default_rng(2)
    n_groups, n_periods, sigma = 3, 6, 0.05
    u = orthogonal_multisines(rng, n_groups, n_periods)
    y = steady_state(u) + sigma * rng.standard_normal(u.shape)
    bla = bla_periodic(u, y, FS)
    U = np.fft.rfft(u[..., 0], axis=0)[LINES]               # (F, 2, R)
    expected = np.zeros(bla.G.shape[1:])
    for m in range(n_groups):
        Ui = np.linalg.inv(U[:, :, 2 * m:2 * m + 2])        # (F, 2, 2): rows realisations
        noise_dft = sigma ** 2 * N                            # variance of a DFT line of white noise
        expected += (noise_dft * np.sum(np.abs(Ui) ** 2, axis=1)).T
    expected /= n_groups ** 2 * n_periods
    measured = bla.var_noise.mean(axis=0)                   # both outputs see the same noise
    assert np.mean(measured) / np.mean(expected) == pytest.approx(1.0, rel=0.05)


def test_distortion_detected_only_with_the_nonlinearity():
    rng = np.random.default_rng(3)
    u = orthogonal_multisines(rng, n_groups=6, n_periods=4)
    noise = 0.01 * rng.standard_normal(u.shape)
    linear = bla_periodic(u, steady_state(u) + noise, FS)
    cubic = bla_periodic(u, steady_state(u, lambda y: y + 0.3 * y ** 3) + noise, FS)
    # linear: distortion within the estimation error of the variances
    assert np.mean(linear.var_total) / np.mean(linear.var_noise) < 1.3
    # static nonlinearity: the groups' spread far exceeds the noise
    assert np.mean(cubic.var_total) / np.mean(cubic.var_noise) > 10
    assert np.mean(cubic.std_distortion) > 3 * np.mean(linear.std_distortion)
    # noise variance is not changed by the nonlinearity
    assert np.mean(cubic.var_noise) / np.mean(linear.var_noise) == pytest.approx(1.0, rel=0.2)


def test_frd_carries_the_frequencies_in_rad_s():
    rng = np.random.default_rng(4)
    u = orthogonal_multisines(rng, 2, 2)
    bla = bla_periodic(u, steady_state(u), FS)
    frd = bla.frd(["a", "b"], ["p", "q"])
    np.testing.assert_allclose(frd.omega, 2 * np.pi * bla.frequency_Hz)
    assert frd.input_labels == ["a", "b"] and frd.output_labels == ["p", "q"]
    np.testing.assert_allclose(bla.G, truth(), rtol=1e-9, atol=1e-12)


def test_dependent_realisations_are_refused():
    rng = np.random.default_rng(5)
    u = orthogonal_multisines(rng, 2, 2)
    u[:, :, 1] = u[:, :, 0]                                  # group 0 singular
    with pytest.raises(ValueError, match="singular"):
        bla_periodic(u, steady_state(u), FS)


def test_one_period_or_one_group_is_refused():
    rng = np.random.default_rng(6)
    u = orthogonal_multisines(rng, 2, 2)
    y = steady_state(u)
    with pytest.raises(ValueError, match="2 periods"):
        bla_periodic(u[..., :1], y[..., :1], FS)
    with pytest.raises(ValueError, match="groups"):
        bla_periodic(u[:, :, :2], y[:, :, :2], FS)
