"""Continuous models: d2c, ZOH, 3-zero refit, identify, coefficients."""

import control as ct
import numpy as np
import pytest

from piezolib import identification as I
from piezolib import paper
from piezolib.robust import realize

FS = paper.SAMPLING_FREQUENCY_HZ


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


def test_pole_pairs_of_a_known_system():
    wn, zeta = I.pole_pairs(ct.tf([1.0], [1.0, 2 * 0.1 * 50.0, 2500.0])
                            * ct.tf([1.0], [1.0, 2 * 0.5 * 10.0, 100.0]))
    assert np.allclose(wn, [10.0, 50.0]) and np.allclose(zeta, [0.5, 0.1])


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
