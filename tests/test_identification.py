"""Identification: RLS (eq. 1-3), ARX/OE, d2c, 3-zero refit, validation tools."""

import control as ct
import numpy as np
import pytest
import scipy.signal as sg

from piezolib import identification as I
from piezolib import paper
from piezolib.robust import realize

FS = paper.SAMPLING_FREQUENCY_HZ

# a stable ARX system y[k] = -a1 y[k-1] - a2 y[k-2] - a3 y[k-3] + b1 u[k-1] + b2 u[k-2]
A_TRUE = np.array([1.0, -1.5, 0.7, -0.1])
B_TRUE = np.array([0.0, 0.5, 0.25])


def arx_data(n=2000, seed=0):
    u = np.random.default_rng(seed).standard_normal(n)
    return u, sg.lfilter(B_TRUE, A_TRUE, u)


def test_rls_recovers_exact_arx_coefficients():
    u, y = arx_data()
    model = I.fit_arx(u, y, FS, na=3, nb=2, nk=1)
    assert np.allclose(model.a, A_TRUE, atol=1e-8, rtol=0)
    assert np.allclose(model.b, B_TRUE, atol=1e-8, rtol=0)
    hist = model.rls.history
    assert hist.shape == (len(y) - 3, 5)
    assert np.allclose(hist[-1], model.rls.parameters)
    # a priori errors vanish once the parameters are known
    assert np.max(np.abs(model.rls.a_priori_errors[-100:])) < 1e-8


def test_rls_equations_on_a_generic_regressor():
    rng = np.random.default_rng(1)
    phi = rng.standard_normal((50, 3))
    psi = np.array([2.0, -1.0, 0.5])
    result = I.rls(phi, phi @ psi, initial_gain=1e12)
    assert np.allclose(result.parameters, psi, atol=1e-8)
    # one step by hand: eq. 1, 3, 2 with W(0) = g I and Psi(0) = 0
    g, theta, y0 = 10.0, phi[0], float(phi[0] @ psi)
    one = I.rls(phi[:1], [y0], initial_gain=g)
    W = g * np.eye(3) - g * g * np.outer(theta, theta) / (1 + g * theta @ theta)
    assert one.a_priori_errors[0] == y0
    assert np.allclose(one.history[0], W @ theta * y0)
    assert np.allclose(one.gain_matrix, W)


def test_output_error_removes_the_arx_bias_of_white_output_noise():
    u, y = arx_data(20000)
    noisy = y + np.random.default_rng(2).normal(0, 0.3, len(y))
    arx = I.fit_arx(u, noisy, FS, na=3, nb=2)
    oe = I.fit_output_error(u, noisy, FS, na=3, nb=2)
    assert oe.converged
    err_arx = np.max(np.abs(arx.a - A_TRUE))
    err_oe = np.max(np.abs(oe.a - A_TRUE))
    assert err_oe < 0.01 < err_arx


def test_discrete_systems_keep_the_estimated_delay():
    # na + 1 > nk + nb: the numerator must be padded, not shifted by a sample
    u, y = arx_data(500)
    t = np.arange(len(u)) / FS
    for model in (I.fit_arx(u, y, FS, na=3, nb=2), I.fit_output_error(u, y, FS, na=3, nb=2)):
        _, y_sys = ct.forced_response(model.system, t, u)
        assert np.allclose(y_sys, y, atol=1e-7)


def test_prediction_error_structure_is_exact_for_the_zoh_model():
    """Noise-free ZOH data of G: OE -> d2c -> refit gives back eq. 4."""
    u = np.random.default_rng(3).standard_normal(6000) * 0.1
    y = I.zoh_simulate(paper.plant(), u, FS)
    result = I.identify(u, y, FS)
    a, b = I.monic_coefficients(result.model)
    assert np.allclose(a, paper.PLANT.a, rtol=1e-6)
    assert np.allclose(b, paper.PLANT.b, rtol=1e-6)
    assert result.dropped_share < 1e-6


def test_refit_numerator_with_true_poles():
    u = np.random.default_rng(4).standard_normal(3000)
    y = I.zoh_simulate(paper.plant(), u, FS)
    model = I.refit_numerator(ct.poles(paper.plant()), u, y, FS)
    assert np.allclose(I.monic_coefficients(model)[1], paper.PLANT.b, rtol=1e-7)


@pytest.mark.parametrize("sys, dt", [
    (paper.plant(), 1e-4),
    (ct.tf([1.0], [1.0, 2.0, 100.0]), 1e-4),
    (ct.tf([1.0], [1.0, 2.0, 100.0]), 1e-2),
    (ct.tf([2.0, 3.0], [1.0, 5.0, 6.0]), 1e-2),
    (ct.tf([1.0, 0.5], [1.0, 0.2, 4.0]) * ct.tf([3.0], [1.0, 3.0]), 1e-2),
], ids=["eq4", "resonant_fast", "resonant_slow", "real_poles", "third_order"])
def test_d2c_inverts_c2d(sys, dt):
    sysd = ct.c2d(realize(sys), dt, "zoh")
    back = I.d2c(sysd)
    w = np.logspace(-1, np.log10(np.pi / dt) - 0.2, 60)
    ref = np.asarray(sys(1j * w)).ravel()
    got = np.asarray(back(1j * w)).ravel()
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-8
    assert np.allclose(np.sort_complex(ct.poles(back)), np.sort_complex(ct.poles(sys)),
                       rtol=1e-8)


def test_d2c_refuses_impossible_models():
    with pytest.raises(ValueError, match="negative real axis"):
        I.d2c(ct.tf([1.0], [1.0, 0.5], 0.1))
    with pytest.raises(ValueError, match="numeric sample time"):
        I.d2c(ct.tf([1.0], [1.0, 1.0]))
    with pytest.raises(ValueError, match="method"):
        I.d2c(ct.tf([1.0], [1.0, -0.5], 0.1), method="tustin")


def test_zoh_simulate_matches_python_control():
    u = np.sin(np.arange(500) / 7.0)
    t = np.arange(500) / FS
    _, ref = ct.forced_response(ct.c2d(realize(paper.plant()), 1 / FS, "zoh"), t, u)
    assert np.allclose(I.zoh_simulate(paper.plant(), u, FS), ref, atol=1e-11)


def test_monic_coefficients_of_the_published_plant():
    a, b = I.monic_coefficients(paper.plant())
    assert np.allclose(a, paper.PLANT.a, rtol=1e-12)
    assert np.allclose(b, paper.PLANT.b, rtol=1e-12)
    table = I.coefficient_table(paper.plant(), paper.plant())
    assert list(table.index) == [f"a{i}" for i in range(6)] + [f"b{i}" for i in range(4)]
    assert np.allclose(table["relative error"], 0, atol=1e-12)


def test_pole_pairs_of_a_known_system():
    wn, zeta = I.pole_pairs(ct.tf([1.0], [1.0, 2 * 0.1 * 50.0, 2500.0])
                            * ct.tf([1.0], [1.0, 2 * 0.5 * 10.0, 100.0]))
    assert np.allclose(wn, [10.0, 50.0]) and np.allclose(zeta, [0.5, 0.1])


def test_fit_percent_and_whiteness():
    rng = np.random.default_rng(5)
    y = rng.standard_normal(4000)
    assert I.fit_percent(y, y) == 100.0
    assert I.fit_percent(y, np.full_like(y, y.mean())) == pytest.approx(0.0, abs=1e-12)
    assert I.whiteness(rng.standard_normal(20000)).passed
    coloured = sg.lfilter([1.0], [1.0, -0.5], rng.standard_normal(20000))
    result = I.whiteness(coloured)
    assert not result.passed and result.n_outside >= 4
    assert result.autocorrelation[0] == pytest.approx(0.5, abs=0.03)


def test_empirical_frequency_response_of_a_known_filter():
    u = np.random.default_rng(6).standard_normal(40000)
    y = I.zoh_simulate(paper.plant(), u, FS)
    w, h = I.empirical_frequency_response(u, y, FS)
    band = (w > 2e3) & (w < 2e4)
    ref = np.asarray(ct.c2d(realize(paper.plant()), 1 / FS, "zoh")(np.exp(1j * w[band] / FS)))
    assert np.max(np.abs(h[band] - ref.ravel()) / np.abs(ref.ravel())) < 0.05


@pytest.mark.parametrize("u, y, match", [
    (np.r_[np.nan, np.ones(999)], np.ones(1000), "u contains 1 non-finite"),
    (np.ones(1000), np.ones(1000), "constant"),
    (np.arange(1000.0), np.ones(999), "equal lengths"),
    (np.random.default_rng(0).standard_normal(60), np.ones(60), "too short"),
    (np.sin(np.arange(2000) / 5.0), np.sin(np.arange(2000) / 5.0), "persistently exciting"),
])
def test_bad_data_raise(u, y, match):
    with pytest.raises(ValueError, match=match):
        I.fit_arx(u, y, FS)
    with pytest.raises(ValueError, match=match):
        I.identify(u, y, FS)


def test_estimated_models_have_neutral_signal_names():
    u, y = arx_data(500)
    models = [I.fit_arx(u, y, FS, na=3, nb=2).system,
              I.fit_output_error(u, y, FS, na=3, nb=2).system]
    u_g = np.random.default_rng(7).standard_normal(3000) * 0.1
    result = I.identify(u_g, I.zoh_simulate(paper.plant(), u_g, FS), FS)
    models += [result.discrete.system, result.continuous_full, result.model]
    for model in models:
        assert (model.input_labels, model.output_labels) == (["u"], ["y"]), model.name


def test_time_scale_defaults_to_one_chosen_from_the_model():
    G = paper.plant()
    for time_scale in (1e3, 1e4, 1e5):
        for got, ref in zip(I.monic_coefficients(G, time_scale=time_scale),
                            I.monic_coefficients(G)):
            assert np.allclose(got, ref, rtol=1e-12, atol=0)
    u = np.random.default_rng(8).standard_normal(3000)
    y = I.zoh_simulate(G, u, FS)
    poles = ct.poles(G)
    explicit = I.monic_coefficients(I.refit_numerator(poles, u, y, FS, time_scale=1e4))[1]
    chosen = I.monic_coefficients(I.refit_numerator(poles, u, y, FS))[1]
    assert np.allclose(explicit, chosen, rtol=1e-8, atol=0)
    with pytest.raises(ValueError, match="time_scale"):
        I.monic_coefficients(G, time_scale=-1.0)
