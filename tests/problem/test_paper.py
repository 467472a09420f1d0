"""The published objects carry the documented poles, gains and orders."""

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib import paper


def test_plant_order_dc_gain_and_names():
    G = paper.plant()
    assert len(ct.poles(G)) == 6 and len(ct.zeros(G)) == 3
    assert ct.dcgain(G) == pytest.approx(1.84e23 / 2.05e23, rel=1e-12)
    assert ct.dcgain(G) == pytest.approx(0.8976, abs=1e-4)
    assert G.input_labels == ["u_c"] and G.output_labels == ["v_y"]


def test_plant_poles_are_three_lightly_damped_pairs():
    p = ct.poles(paper.plant())
    assert np.all(p.real < 0)
    wn = np.sort(np.unique(np.round(np.abs(p), 3)))
    # natural frequencies of the three pairs, rad/s (from the roots of a(s))
    np.testing.assert_allclose(wn, [5125.97, 6313.04, 13991.44], rtol=1e-4)
    # the fastest pair sits near Table 1's 2100 Hz resonance
    assert wn[-1] / (2 * np.pi) == pytest.approx(paper.RESONANT_FREQUENCY_HZ, rel=0.07)


def test_uncertainty_weight_shape():
    Hm = paper.uncertainty_weight()
    assert len(ct.poles(Hm)) == 5 and np.all(ct.poles(Hm).real < 0)
    assert ct.dcgain(Hm) == pytest.approx(0.02, rel=1e-9)
    w = np.logspace(2, 6, 4000)
    mag = np.abs(Hm(1j * w))
    # notch ratio zeta1/zeta2 = 70 around omega1 lifts 0.02 to about 1.4-1.5
    assert 1.3 < mag.max() < 1.6
    assert w[mag.argmax()] == pytest.approx(6.3e3, rel=0.05)


def test_performance_weights_limits():
    He, Hy = paper.error_weight(), paper.output_weight()
    assert ct.dcgain(He) == pytest.approx(1 / 0.003)
    assert abs(He(1j * 1e9)) == pytest.approx(1 / 2, rel=1e-5)
    assert ct.dcgain(Hy) == pytest.approx((1 / 1.5) ** 2)
    assert abs(Hy(1j * 1e12)) == pytest.approx(1e8, rel=1e-3)
    assert len(ct.poles(Hy)) == 2 and np.allclose(ct.poles(Hy), -7.5e7)


def test_controller_resolution_of_repeated_d3():
    K = paper.controller()
    assert len(ct.poles(K)) == 6 and np.all(ct.poles(K).real < 0)
    assert paper.CONTROLLER.d[3:] == (7.86e14, 3.21e10, 4.69e5)
    assert ct.dcgain(K) == pytest.approx(4.73e22 / 7.79e19)
    assert "d3" in paper.CONTROLLER_NOTE


def test_builders_accept_overrides():
    assert ct.dcgain(paper.error_weight(eps_e=0.01)) == pytest.approx(100)
    assert ct.dcgain(paper.uncertainty_weight(g=0.05)) == pytest.approx(0.05)


@pytest.mark.parametrize("builder, kwargs, match", [
    (paper.error_weight, {"M_e": 0}, "M_e must be positive"),
    (paper.error_weight, {"omega_e": -1.0}, "omega_e must be positive"),
    (paper.error_weight, {"eps_e": float("nan")}, "eps_e must be finite"),
    (paper.output_weight, {"eps_y": 0.0}, "eps_y must be positive"),
    (paper.output_weight, {"M_y": "big"}, "M_y must be a real number"),
    (paper.uncertainty_weight, {"zeta2": 0.0}, "zeta2 must be positive"),
    (paper.uncertainty_weight, {"g": -0.02}, "g must be positive"),
    (paper.uncertainty_weight, {"gain": 1.0}, "unknown parameter"),
])
def test_builders_reject_bad_arguments(builder, kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        builder(**kwargs)


def test_plant_rejects_wrong_coefficients():
    with pytest.raises(ValueError, match="6 denominator"):
        paper.plant(paper.PlantCoefficients(a=(1.0, 2.0)))
    with pytest.raises(ValueError, match="finite"):
        paper.plant(paper.PlantCoefficients(a=(np.nan,) * 6))
    with pytest.raises(TypeError, match="PlantCoefficients"):
        paper.plant([1, 2, 3])


def test_tables_are_consistent_frames():
    t4, t5 = paper.table4(), paper.table5()
    assert t4.shape == (6, 4) and t5.shape == (6, 6)
    assert list(t4.columns) == [10.0, 20.0, 30.0, 40.0]
    assert isinstance(paper.table1(), pd.DataFrame) and len(paper.table2()) == 10
    # improvement rows follow from the case rows to within the printed rounding
    for t in (t4, t5):
        implied = 100 * (t.loc["case_I"] - t.loc["case_II"]) / t.loc["case_I"]
        np.testing.assert_allclose(implied, t.loc["improvement_II_vs_I"], atol=0.1)


def test_problem_returns_the_five_published_models_with_named_signals():
    problem = paper.problem()
    assert isinstance(problem, paper.DesignProblem)
    G, H_m, H_e, H_y, K = problem
    assert (problem.G, problem.H_m, problem.H_e, problem.H_y, problem.K) == (G, H_m, H_e, H_y, K)
    signals = {"G": (["u_c"], ["v_y"]), "H_m": (["u_c"], ["y_Delta"]),
               "H_e": (["v_e"], ["y1"]), "H_y": (["v_y"], ["y2"]), "K": (["v_e"], ["u_b"])}
    for name, sys in zip(signals, problem):
        assert isinstance(sys, ct.TransferFunction) and sys.name == name
        assert (sys.input_labels, sys.output_labels) == signals[name]
    # the same models as the single builders
    s = 1j * np.logspace(0, 6, 50)
    for sys, builder in ((G, paper.plant), (H_m, paper.uncertainty_weight),
                         (H_e, paper.error_weight), (H_y, paper.output_weight),
                         (K, paper.controller)):
        np.testing.assert_array_equal(sys(s), builder()(s))
    # the published controller is stable (d3, d4, d5 reading)
    assert np.all(ct.poles(K).real < 0)
