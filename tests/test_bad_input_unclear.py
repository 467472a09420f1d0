"""Bad input that once gave an unclear error or a silent answer: each now a clear error.

The cases of the third bad-input campaign that the sweeps (``tests/test_bad_input*.py``) do
not reach: a value of the right type that is still wrong (a significance level of 2, a
controller coefficient past float32's range), sizes past what the machine can do, and
errors that blamed the wrong argument.
"""

import json

import control as ct
import numpy as np
import pytest

from piezolib import identification as ident
from piezolib import robust
from piezolib import uncertainty as unc
from piezolib.hysteresis import DahlFeedforward, DahlModel
from piezolib.problem import stage_calibration
from piezolib.robust.dgk import mixed_musyn

DAHL = DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0, g_a=1.28,
                 form="bliman_sorine", x0=-0.15, start="rest")
KD = ct.tf([1.0, -0.5], [1.0, -0.2], 1e-4)
G3 = ct.tf([1.0], [1.0, 3.0, 3.0, 1.0])


def test_whiteness_refuses_a_significance_level_above_one():
    with pytest.raises(ValueError, match=r"alpha must be a significance level in \(0, 1\)"):
        ident.whiteness(np.random.default_rng(0).standard_normal(200), alpha=2)


def test_the_feedforward_step_refuses_text():
    with pytest.raises(TypeError, match="x_r must be a real number"):
        DahlFeedforward(DAHL).step("1")


def test_case_I_input_refuses_a_voltage_the_stage_cannot_drive():
    with pytest.raises(ValueError, match=r"amplitude_V must be at most 120 V"):
        stage_calibration.case_I_input(1e6)
    assert stage_calibration.case_I_input(40.0).max() == pytest.approx(4.0)


def test_export_refuses_a_non_finite_meta_value_before_writing(tmp_path):
    with pytest.raises(ValueError, match=r"meta\['x'\]\['y'\] = nan"):
        robust.export_controller(KD, tmp_path, "K", meta={"x": {"y": float("nan")}})
    assert not list(tmp_path.iterdir())


def test_export_names_the_float32_range_before_writing(tmp_path):
    with pytest.raises(ValueError, match="outside the float32 range"):
        robust.export_controller(ct.tf([1e39, -0.5], [1.0, -0.2], 1e-4), tmp_path, "K")
    assert not list(tmp_path.iterdir())


def test_export_names_the_float32_normal_range_before_writing(tmp_path):
    """1e-46 rounds to zero in float32 (the first-order bound, relative, does not see it)."""
    with pytest.raises(ValueError, match="below the float32 normal range"):
        robust.export_controller(ct.tf([1e-46], [1.0, -0.5], 1e-4), tmp_path, "K")
    assert not list(tmp_path.iterdir())
    with pytest.warns(robust.ExportWarning, match="below the float32 normal range"):
        robust.export_controller(ct.tf([1e-46], [1.0, -0.5], 1e-4), tmp_path, "K",
                                 dtype="float64")          # float32 only written alongside


def _twentieth_order(gain):
    poles = 0.5 * np.exp(1j * np.linspace(0.1, 3.0, 10))
    zeros = 0.7 * np.exp(1j * np.linspace(0.2, 2.9, 10))
    return ct.tf(gain * np.real(np.poly(np.r_[zeros, zeros.conj()])),
                 np.real(np.poly(np.r_[poles, poles.conj()])), 1e-4)


@pytest.mark.parametrize("K", [ct.tf([1e-46], [1.0, -0.5], 1e-4), _twentieth_order(4e-10)],
                         ids=["1e-46 / (z - 0.5)", "20th order, gain 4e-10"])
def test_a_tiny_gain_is_not_identically_zero(K):
    """Zero is judged relative to the controller, not against an absolute tolerance: the
    sections reproduce the tiny controller's response."""
    sos = robust.controller_sos(K)
    w = 2 * np.pi * np.array([100.0, 1000.0])
    ref = np.ravel(K(np.exp(1j * w * 1e-4)))
    assert np.allclose(sos.frequency_response(w, "float64"), ref, rtol=1e-6, atol=0)


def test_frf_error_blames_the_models_sample_time():
    fs, f = 1000.0, np.linspace(10.0, 400.0, 20)
    G = np.ravel(ct.c2d(ct.tf([1.0], [1e-2, 1.0]), 1 / fs)(np.exp(2j * np.pi * f / fs)))
    with pytest.raises(ValueError, match=r"model is sampled at 500 Hz.*Nyquist"):
        ident.frf_error(ct.c2d(ct.tf([1.0], [1e-2, 1.0]), 1 / 500), G, f)


@pytest.mark.parametrize("call, limit", [
    (lambda: ident.fit_frf(np.ones(20), np.linspace(1, 100, 20), 1000.0, 2, n_rows=10 ** 6),
     "n_rows must be at most 168"),
    (lambda: unc.random_model_set(G3, 0.05, 10 ** 10), "count must be at most 1,000,000"),
    (lambda: unc.sampled_loop_poles(unc.random_model_set(G3, 0.05, 2), ct.tf([1.0], [1.0], 1e-3),
                                    1e-3, delay_samples=10 ** 6),
     "delay_samples must be at most 100 "),
])
def test_sizes_past_the_limit_are_refused_before_any_work(call, limit):
    with pytest.raises(ValueError, match=limit):
        call()


def test_mixed_musyn_checks_dk_options():
    P = ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)))
    blk, omega = [(-1, 0), (1, 1)], np.logspace(0, 2, 20)
    with pytest.raises(TypeError, match="dk_options must be a dict"):
        mixed_musyn(P, blk, omega, dk_options=[1])
    with pytest.raises(ValueError, match=r"dk_options: \['nope'\] are not options of musyn"):
        mixed_musyn(P, blk, omega, dk_options={"nope": 1})


def test_export_meta_stays_strict_json(tmp_path):
    robust.export_controller(KD, tmp_path, "K", meta={"x": 1.5})
    json.loads((tmp_path / "K.json").read_text(), parse_constant=lambda c: pytest.fail(c))


def test_axis_design_plant_refuses_an_unstable_weight():
    from piezolib.problem import fsm_benchmark
    good = dict(G=ct.tf([2e7], [1.0, 400.0, 4e7]), W_m=ct.tf([0.1], [1.0]),
                W_S=ct.tf([1.0], [1.0, 1.0]), W_T=ct.tf([0.1], [1.0]), W_u=ct.tf([0.01], [1.0]),
                fs=6400.0)
    with pytest.raises(ValueError, match="W_S must be stable"):
        fsm_benchmark.axis_design_plant(**{**good, "W_S": ct.tf([1.0], [1.0, -1.0])})


@pytest.mark.parametrize("text", ["time,u,y\n0,1,2\n", '{"cells": [{"cell_type": "co'])
def test_build_names_an_executed_file_that_is_no_notebook(text, tmp_path):
    from piezolib.workbook import document
    path = tmp_path / "report.ipynb"
    path.write_text(text)
    with pytest.raises(ValueError, match=rf"{path} is not a readable Jupyter notebook"):
        document.build(executed=path, output=tmp_path / "out")


def _periodic_records():
    N, lines = 64, np.arange(1, 11)
    rng = np.random.default_rng(0)
    u = np.zeros((N, 1, 2, 2))
    for r in range(2):
        phases = rng.uniform(0, 2 * np.pi, lines.size)
        u[:, 0, r, :] = np.cos(2 * np.pi * np.outer(np.arange(N), lines) / N
                               + phases).sum(1)[:, None]
    return u, 0.5 * u + 0.5 * np.roll(u, 1, axis=0)


def test_bla_periodic_refuses_a_repeated_line():
    u, y = _periodic_records()
    with pytest.raises(ValueError, match=r"lines must name each DFT line once, got \[3\]"):
        ident.bla_periodic(u, y, 64.0, lines=[3, 3, 5])


def test_bla_labels_name_each_signal_once():
    bla = ident.bla_periodic(*_periodic_records(), 64.0)
    for labels in (["u", "u"], []):
        with pytest.raises(ValueError, match="input_labels must name each of the 1 signals once"):
            bla.frd(input_labels=labels)
    assert bla.frd(input_labels=["v_a"]).input_labels == ["v_a"]


def test_a_latin_1_study_file_is_named(tmp_path):
    from piezolib.workbook import study
    path = tmp_path / "x.toml"
    path.write_bytes('name = "x"\n# café\n'.encode("latin-1"))
    with pytest.raises(ValueError, match=rf"{path}: not UTF-8 text"):
        study.load(path)


def test_a_latin_1_sweep_file_is_named(tmp_path):
    from piezolib.workbook import sweep_spec
    path = tmp_path / "x.toml"
    path.write_bytes('[grid]\n# café\n"design.order" = [4]\n'.encode("latin-1"))
    with pytest.raises(ValueError, match=rf"{path}: not UTF-8 text"):
        sweep_spec.load_spec(path)


def test_fit_pi_bounds_the_plays_before_any_work():
    from piezolib.hysteresis import fit_pi
    v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20)]
    with pytest.raises(ValueError, match="n_plays must be at most 100 "):
        fit_pi((v, v), n_plays=10 ** 7)


def test_fit_hammerstein_bounds_the_plays_before_any_work():
    from piezolib.hysteresis import fit_hammerstein
    v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20)]
    with pytest.raises(ValueError, match="n_plays must be at most 100 "):
        fit_hammerstein((v, v), fs=100.0, order=(1, 1), n_plays=10 ** 6)
    with pytest.raises(ValueError, match="thresholds must hold at most 100 plays"):
        fit_hammerstein((v, v), fs=100.0, order=(1, 1), thresholds=np.arange(1000.0))


@pytest.mark.parametrize("loops", [lambda v: (v, np.full(v.size, 2.0)),
                                   lambda v: [(v, v), (v, np.zeros(v.size))]])
def test_fit_hammerstein_names_a_constant_output(loops):
    from piezolib.hysteresis import fit_hammerstein
    v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20)]
    with pytest.raises(ValueError, match=r"loops\[\d\] x is constant"):
        fit_hammerstein(loops(v), fs=100.0, order=(1, 1), n_plays=3)
