"""Generalized plant (eq. 16), LFT and M (eq. 17-18), and the Table 3 analysis."""

import control as ct
import numpy as np
import pytest

from piezolib.problem import analysis, genplant
from piezolib import paper, robust

OMEGA = np.logspace(0, 6, 300)


@pytest.fixture(scope="module")
def models():
    return dict(G=paper.plant(), H_m=paper.uncertainty_weight(), H_e=paper.error_weight(),
                H_y=paper.output_weight(), K=paper.controller())


def response(sys, omega=OMEGA):
    return np.moveaxis(sys(1j * omega, squeeze=False), -1, 0)


def test_generalized_plant_entries_are_eq16(models):
    P = genplant.generalized_plant()
    assert P.input_labels == ["u_Delta", "v_r", "u_b"]
    assert P.output_labels == ["y_Delta", "y1", "y2", "v_e"]
    assert P.nstates == 14
    s = 1j * OMEGA
    g, hm, he, hy = (np.ravel(models[k](s)) for k in ("G", "H_m", "H_e", "H_y"))
    zero = np.zeros_like(g)
    expected = np.stack([np.stack([zero, zero, hm], -1),
                         np.stack([-he * g, he, -he * g], -1),
                         np.stack([hy * g, zero, hy * g], -1),
                         np.stack([-g, np.ones_like(g), -g], -1)], 1)
    got = response(P)
    scale = np.maximum(np.abs(expected), 1e-300)
    nonzero = np.abs(expected) > 0
    assert np.max(np.abs(got - expected)[nonzero] / scale[nonzero]) < 1e-8
    assert np.max(np.abs(got[~nonzero])) < 1e-9


def test_effort_output_and_design_plant():
    P = genplant.design_plant()
    assert P.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"]
    resp = response(P)
    np.testing.assert_allclose(resp[:, 3, 2], genplant.DESIGN_EFFORT_WEIGHT, rtol=1e-12)
    np.testing.assert_allclose(resp[:, 3, :2], 0, atol=1e-14)
    assert genplant.DESIGN_BLOCK_STRUCTURE == ((1, 1), (1, 3))


def test_dropping_fast_poles_of_H_y(models):
    H_y = models["H_y"]
    num, den, dropped = genplant.drop_fast_poles(H_y, 1e6)
    assert dropped.size == 2 and np.all(np.abs(dropped) > 7e7)
    assert np.polyval(num, 0) / np.polyval(den, 0) == pytest.approx(ct.dcgain(H_y), rel=1e-12)
    # dropping a real pole p changes the response by about 2 omega/|p| (two poles)
    err = genplant.weight_truncation_error(H_y, 1e6, np.array([1e2, 1e4]))
    np.testing.assert_allclose(err, 2 * np.array([1e2, 1e4]) / 7.5e7, rtol=1e-3)
    P = genplant.generalized_plant(weight_pole_limit=1e6)
    assert P.nstates == 12
    got = response(P)[:, 2, 0]
    s = 1j * OMEGA
    exact = np.ravel(H_y(s)) * np.ravel(models["G"](s))
    assert np.max(np.abs(got / exact - 1)) < 2 * OMEGA.max() / 7.5e7 * 1.01


def test_lower_lft_is_eq18(models):
    K = models["K"]
    M = genplant.closed_loop_matrix(K)
    assert M.input_labels == ["u_Delta", "v_r"]
    assert M.output_labels == ["y_Delta", "y1", "y2"]
    lf = robust.loop_functions(models["G"], K)
    s = 1j * OMEGA
    S, T, KS, GS = (np.ravel(f(s)) for f in lf)
    hm, he, hy = (np.ravel(models[k](s)) for k in ("H_m", "H_e", "H_y"))
    expected = np.stack([np.stack([-hm * T, hm * KS], -1),
                         np.stack([-he * GS, he * S], -1),
                         np.stack([hy * GS, hy * T], -1)], 1)
    for got in (response(M), robust.lft_response(genplant.generalized_plant(), K, OMEGA)):
        np.testing.assert_allclose(got, expected, rtol=1e-7, atol=1e-12)


def test_lower_lft_rejects_mismatched_sizes(models):
    with pytest.raises(ValueError, match="too small"):
        robust.lower_lft(models["G"], models["K"])


def test_analysis_of_published_controller(models):
    a = analysis.analyze(models["K"])
    assert a.nominal_stability
    # values recomputed from the printed models (DESIGN.md); paper prints 0.81 / 0.92 / 0.48
    assert a.norm_He_S == pytest.approx(0.808, abs=0.002)
    assert a.norm_Hy_T == pytest.approx(0.982, abs=0.002)
    assert a.mu_RS == pytest.approx(0.819, abs=0.002)
    assert a.mu_RP == pytest.approx(1.448, abs=0.005)
    assert 6.0e3 < a.omega_RP < 7.0e3
    assert a.mu_RP_lower <= a.mu_RP * (1 + 1e-9) and a.mu_RP_lower > 0.999 * a.mu_RP
    # mu of a 1x1 complex block is |M11| = |H_m T|; the refined peak tops the grid
    s = 1j * a.omega
    HmT = np.ravel(models["H_m"](s)) * np.ravel(robust.loop_functions(models["G"],
                                                                     models["K"]).T(s))
    np.testing.assert_allclose(a.mu_RS_curve, np.abs(HmT), rtol=1e-7)
    assert a.mu_RS_curve.max() <= a.mu_RS <= a.mu_RS_curve.max() * 1.005
    assert a.mu_RP_upper.max() <= a.mu_RP
    frame = a.frame()
    assert list(frame.condition) == ["NS", "NP", "NP", "RS", "RP", "RP"]
    assert frame.met.tolist() == [True, True, True, True, False, False]


def test_analysis_of_destabilising_controller(models):
    a = analysis.analyze(-models["K"], name="minus K")
    assert not a.nominal_stability
    assert a.mu_RP == np.inf and a.norm_He_S == np.inf and np.isnan(a.omega_RP)
    table = analysis.table3(a, paper_values=paper.FIGURES_OF_MERIT)
    assert list(table.columns) == ["paper", "minus K"]
    assert not table.loc["NS: S, T, KS, GS stable", "minus K"]
