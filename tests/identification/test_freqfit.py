"""Frequency-domain subspace fits on synthetic systems of known order."""

import control as ct
import numpy as np
import pytest

from piezolib.identification import (FitQualityWarning, fit_frf, frf_error, select_order,
                                     simulate_discrete)

FS = 2000.0


def resonant_system(order_pairs=3, seed=0):
    """A stable 2 x 3 discrete system of 2 * order_pairs states (lightly damped modes)."""
    rng = np.random.default_rng(seed)
    blocks = []
    for k in range(order_pairs):
        r, theta = 0.97 - 0.02 * k, 0.3 + 0.6 * k
        blocks.append(r * np.array([[np.cos(theta), np.sin(theta)],
                                    [-np.sin(theta), np.cos(theta)]]))
    A = np.block([[blocks[i] if i == j else np.zeros((2, 2)) for j in range(order_pairs)]
                  for i in range(order_pairs)])
    n = A.shape[0]
    return ct.ss(A, rng.standard_normal((n, 3)), rng.standard_normal((2, n)),
                 0.1 * rng.standard_normal((2, 3)), 1 / FS)


def response(sys, f):
    return sys(np.exp(2j * np.pi * f / FS))


F = np.linspace(5.0, 950.0, 300)


def test_exact_data_give_the_system_back():
    true = resonant_system()
    G = response(true, F)
    model = fit_frf(G, F, FS, true.nstates, input_labels=["a", "b", "c"],
                    output_labels=["p", "q"])
    assert model.nstates == 6 and model.dt == pytest.approx(1 / FS)
    assert model.input_labels == ["a", "b", "c"] and model.output_labels == ["p", "q"]
    assert frf_error(model, G, F) < 1e-8
    np.testing.assert_allclose(np.sort_complex(model.poles()), np.sort_complex(true.poles()),
                               atol=1e-8)


def test_noisy_data_error_at_the_noise_level_and_weights_matter():
    rng = np.random.default_rng(1)
    true = resonant_system()
    G0 = response(true, F)
    # noise 100 times larger on the upper half of the band: weighting by 1/variance helps
    std = np.where(F > 500, 0.3, 0.003)[None, None, :] * np.ones(G0.shape)
    G = G0 + std / np.sqrt(2) * (rng.standard_normal(G0.shape)
                                  + 1j * rng.standard_normal(G0.shape))
    unweighted = fit_frf(G, F, FS, 6)
    weighted = fit_frf(G, F, FS, 6, weight=1 / std ** 2)
    assert np.all(np.abs(weighted.poles()) < 1)
    assert frf_error(weighted, G0, F) < 0.7 * frf_error(unweighted, G0, F)   # poles unweighted
    # the weighted fit's error to the truth is below the noise on the data (not far below:
    # the poles come from the unweighted subspace step)
    assert frf_error(weighted, G0, F, 1 / std ** 2) < frf_error(weighted, G, F, 1 / std ** 2)


def test_unstable_poles_are_reflected_into_the_unit_disc():
    unstable = ct.ss(ct.tf([1.0, 0.3], [1.0, -2.2, 1.3], 1 / FS))   # poles at |z| = 1.14
    model = fit_frf(response(unstable, F), F, FS, 2)
    assert np.all(np.abs(model.poles()) < 1)


def test_order_selection_finds_the_true_order():
    rng = np.random.default_rng(2)
    true = resonant_system(order_pairs=4, seed=3)
    G0 = response(true, F)
    noisy = [G0 + 1e-3 * (rng.standard_normal(G0.shape) + 1j * rng.standard_normal(G0.shape))
             for _ in range(2)]
    sel = select_order(noisy[0], noisy[1], F, FS, [4, 6, 8, 10, 12])
    assert sel.order in (8, 10)           # the true 8, or one spare state fitted to noise
    assert sel.validation_error[list(sel.orders).index(6)] > 5 * sel.validation_error.min()
    assert np.all(np.diff(sel.fit_error[:3]) < 0)
    assert sel.model.nstates == sel.order


def test_simulation_matches_a_time_loop():
    rng = np.random.default_rng(4)
    true = resonant_system()
    u = rng.standard_normal((500, 3, 2))
    y = simulate_discrete(true, u)
    for r in range(2):
        ref = ct.forced_response(true, U=u[:, :, r].T).outputs.T
        np.testing.assert_allclose(y[:, :, r], ref, atol=1e-10)
    # and the steady-state response follows the frequency response
    f_line = 50 * FS / 500
    tone = np.cos(2 * np.pi * f_line * np.arange(5000) / FS)
    y_tone = simulate_discrete(true, np.c_[tone, 0 * tone, 0 * tone])
    g = response(true, np.array([f_line]))[:, 0, 0]
    expected = np.abs(g[0]) * np.cos(2 * np.pi * f_line * np.arange(5000) / FS + np.angle(g[0]))
    np.testing.assert_allclose(y_tone[-500:, 0], expected[-500:], atol=1e-6)


def _second_order_frf(fs=1000.0):
    G = ct.ss(ct.c2d(ct.tf([100.0], [1, 2, 100.0]), 1 / fs))
    f = np.linspace(1.0, 400.0, 200)
    return G, np.ravel(G(np.exp(2j * np.pi * f / fs)))[None, None, :], f, fs


@pytest.mark.parametrize("k", [1e-300, 1e-150, 1e150, 1e300])
def test_an_frf_at_either_end_of_the_float_range_fits_as_well_as_at_one(k):
    # |G|^2 underflowed (1e-300: a model of relative error 1.1, no warning) or overflowed
    # (1e300: a deep SVD error); the output scaling now works on G / max|G|
    _, H, f, fs = _second_order_frf()
    model = fit_frf(k * H, f, fs, 2)
    assert frf_error(model, k * H, f) < 1e-9


def test_a_stable_fit_of_an_unstable_frf_warns_with_its_error():
    fs = 1000.0
    f = np.linspace(1.0, 400.0, 200)
    U = ct.ss(ct.c2d(ct.tf([1.0], [1, -5.0]), 1 / fs))          # a pole at z = e^(5/fs) > 1
    H = np.ravel(U(np.exp(2j * np.pi * f / fs)))[None, None, :]
    with pytest.warns(FitQualityWarning, match="outside the unit circle"):
        fit_frf(H, f, fs, 1)


def test_the_block_row_limit_allows_order_max_rows_minus_8_and_refuses_one_row_more():
    """MAX_ROWS (168): order MAX_ROWS - 8 with the default n_rows = order + 8 fits (notebook
    10's order curve reaches 160); one row more is refused before any work, naming n_rows."""
    from piezolib.identification.freqfit import MAX_ROWS

    assert MAX_ROWS == 168
    f = np.linspace(1.0, 990.0, 200)
    G = response(resonant_system(), f)[:1, :1]                   # SISO, 200 lines
    model = fit_frf(G, f, FS, MAX_ROWS - 8, iterations=0)
    assert model.nstates == MAX_ROWS - 8
    with pytest.raises(ValueError, match="n_rows"):
        fit_frf(G, f, FS, MAX_ROWS - 7)                          # default n_rows = MAX_ROWS + 1
    with pytest.raises(ValueError, match="n_rows"):
        fit_frf(G, f, FS, 8, n_rows=MAX_ROWS + 1)


def test_simulate_discrete_with_real_and_complex_modes_on_records_of_any_shape():
    # one mode of each conjugate pair is run twice over (2 Re): real poles and a
    # 4-D input (time, inputs, realisations, periods) must still give the time loop
    true = ct.ss(ct.tf([[[1.0, 0.3]], [[0.5, -0.2, 0.1]]],
                       [[[1.0, -1.2, 0.72]], [[1.0, -0.5, 0.06]]], 1 / FS))
    u = np.random.default_rng(3).standard_normal((300, 1, 2, 2))
    y = simulate_discrete(true, u)
    assert y.shape == (300, 2, 2, 2)
    for r in range(2):
        for p in range(2):
            ref = ct.forced_response(true, U=u[:, :, r, p].T).outputs
            np.testing.assert_allclose(y[:, :, r, p], np.atleast_2d(ref).T, atol=1e-12)
