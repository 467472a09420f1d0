"""Output-error models (Steiglitz-McBride passes over RLS)."""

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib import identification as I
from piezolib import paper

FS = paper.SAMPLING_FREQUENCY_HZ


def test_output_error_removes_the_arx_bias_of_white_output_noise(arx_system):
    u, y = arx_system.data(20000)
    noisy = y + np.random.default_rng(2).normal(0, 0.3, len(y))
    arx = I.fit_arx(u, noisy, FS, na=3, nb=2)
    oe = I.fit_output_error(u, noisy, FS, na=3, nb=2)
    assert oe.converged
    err_arx = np.max(np.abs(arx.a - arx_system.a))
    err_oe = np.max(np.abs(oe.a - arx_system.a))
    assert err_oe < 0.01 < err_arx


def test_discrete_systems_keep_the_estimated_delay(arx_system):
    # na + 1 > nk + nb: the numerator must be padded, not shifted by a sample
    u, y = arx_system.data(500)
    t = np.arange(len(u)) / FS
    for model in (I.fit_arx(u, y, FS, na=3, nb=2), I.fit_output_error(u, y, FS, na=3, nb=2)):
        _, y_sys = ct.forced_response(model.system, t, u)
        assert np.allclose(y_sys, y, atol=1e-7)


def test_estimated_models_have_neutral_signal_names(arx_system):
    u, y = arx_system.data(500)
    models = [I.fit_arx(u, y, FS, na=3, nb=2).system,
              I.fit_output_error(u, y, FS, na=3, nb=2).system]
    u_g = np.random.default_rng(7).standard_normal(3000) * 0.1
    result = I.identify(u_g, I.zoh_simulate(paper.plant(), u_g, FS), FS)
    models += [result.discrete.system, result.continuous_full, result.model]
    for model in models:
        assert (model.input_labels, model.output_labels) == (["u"], ["y"]), model.name


def test_output_error_with_nb_below_na_and_two_sample_delay():
    a = np.array([1.0, -1.5, 0.7, -0.1])
    b = np.array([0.0, 0.0, 0.5, 0.25])                  # nk = 2, nb = 2
    u = np.random.default_rng(8).standard_normal(2000)
    y = sg.lfilter(b, a, u)
    model = I.fit_output_error(u, y, FS, na=3, nb=2, nk=2)
    assert np.allclose(model.a, a, atol=1e-8) and np.allclose(model.b, b, atol=1e-8)
