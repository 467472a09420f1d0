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
        I.d2c(ct.tf([1.0], [1.0, -0.5], 0.1), method="bilinear")
    with pytest.raises(ValueError, match="z = -1"):
        I.d2c(ct.tf([1.0], [1.0, 1.0], 0.1), method="tustin")


def test_d2c_tustin_inverts_c2d_and_takes_negative_real_poles():
    # a model with a pole on the negative real axis has no ZOH inverse but a Tustin one
    sysd = ct.tf([1.0, 0.3], [1.0, -0.2, -0.63], 0.01)     # poles 0.9 and -0.7
    back = I.d2c(sysd, method="tustin")
    assert back.isctime(strict=True)
    z = np.exp(1j * np.linspace(0.01, 3.1, 50))
    again = ct.c2d(back, 0.01, "tustin")
    assert np.allclose(np.ravel(again(z)), np.ravel(sysd(z)), rtol=1e-10)
    # and the Hankel singular values are kept (balanced truncation commutes with the map)
    sys = realize(ct.tf([1.0, 0.5], [1.0, 0.2, 4.0]) * ct.tf([3.0], [1.0, 3.0]))
    hsv = ct.hankel_singular_values(I.d2c(ct.c2d(sys, 0.05, "tustin"), method="tustin"))
    assert np.allclose(hsv, ct.hankel_singular_values(sys), rtol=1e-8)


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


def test_user_chosen_delay_and_numerator_order_on_foreign_data():
    """nb != n_poles and nk = 2: the extra sample is reported as a delay, the
    model carries the user's names and units."""
    G = ct.tf([2e6], [1.0, 200.0, 1e6])                  # 2 poles, no zero
    fs = 5e3
    u = np.random.default_rng(5).standard_normal(3000)
    y = np.concatenate(([0.0], I.zoh_simulate(G, u, fs)[:-1]))   # one more sample of delay
    result = I.identify(u, y, fs, n_poles=2, n_zeros=0, nb=2, nk=2, input_name="v_in",
                        output_name="x", input_unit="V", output_unit="um")
    assert result.delay_samples == 1 and result.delay_s == pytest.approx(1 / fs)
    assert result.model.input_labels == ["v_in"] and result.model.output_labels == ["x"]
    assert (result.input_unit, result.output_unit) == ("V", "um")
    assert len(result.discrete.b) == 2 + 2            # nk leading zeros, nb terms
    assert np.allclose(np.sort_complex(result.model.poles()), np.sort_complex(G.poles()),
                       rtol=1e-6)
    assert float(result.model.dcgain()) == pytest.approx(2.0, rel=1e-6)
    # nb = 1 < n_poles = 2: a lower numerator order is accepted and keeps its structure
    short = I.identify(u, y, fs, n_poles=2, n_zeros=0, nb=1, nk=2)
    assert len(short.discrete.b) == 2 + 1 and short.discrete.b[:2].tolist() == [0.0, 0.0]
    assert float(short.model.dcgain()) == pytest.approx(2.0, rel=0.05)


def test_identify_rejects_orders_it_cannot_convert():
    u = np.random.default_rng(6).standard_normal(2000)
    y = I.zoh_simulate(ct.tf([1e6], [1.0, 200.0, 1e6]), u, 5e3)
    with pytest.raises(ValueError, match="nb"):
        I.identify(u, y, 5e3, n_poles=2, n_zeros=0, nb=3)
    with pytest.raises(ValueError, match="nk"):
        I.identify(u, y, 5e3, n_poles=2, n_zeros=0, nk=0)
    with pytest.raises(TypeError, match="input_name"):
        I.identify(u, y, 5e3, n_poles=2, n_zeros=0, input_name=3)


def test_identify_record_takes_rate_names_and_units_from_the_record():
    from piezolib.records import Record
    G = ct.tf([1e6], [1.0, 200.0, 1e6])
    u = np.random.default_rng(7).standard_normal(2000)
    rec = Record(u, I.zoh_simulate(G, u, 5e3), 5e3, input_unit="V", output_unit="um",
                 input_name="v", output_name="d")
    result = I.identify_record(rec, n_poles=2, n_zeros=0)
    assert result.model.input_labels == ["v"] and result.output_unit == "um"
    assert float(result.model.dcgain()) == pytest.approx(1.0, rel=1e-6)
    with pytest.raises(TypeError, match="record"):
        I.identify_record((u, u))


def test_refit_numerator_rejects_unpaired_complex_pole():
    # -1+1j used to be turned into -1 by taking the real part of the polynomial
    u = np.random.default_rng(0).standard_normal(500)
    with pytest.raises(ValueError, match="closed under complex conjugation"):
        I.refit_numerator([-1 + 1j, -5.0], u, u, 1e3, n_zeros=1)
    G = I.refit_numerator([-1 + 1j, -1 - 1j], u, u, 1e3, n_zeros=1)
    np.testing.assert_allclose(np.sort_complex(ct.poles(G)), [-1 - 1j, -1 + 1j], rtol=1e-9)
