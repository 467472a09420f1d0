"""Table 3 for any controller: NS, NP, RS and RP (piezolib.problem.analysis)."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem import analysis


@pytest.fixture(scope="module")
def published(models):
    G, H_m, H_e, H_y, K = models
    return analysis.analyze(K, G, H_m, H_e, H_y)


def test_analysis_of_published_controller(models, published):
    G, H_m, _, _, K = models
    a = published
    assert a.nominal_stability and a.name == "K"
    # values recomputed from the printed models (as notebook 00 does); paper prints 0.81 / 0.92 / 0.48
    assert a.norm_He_S == pytest.approx(0.808, abs=0.002)
    assert a.norm_Hy_T == pytest.approx(0.982, abs=0.002)
    assert a.mu_RS == pytest.approx(0.819, abs=0.002)
    assert a.mu_RP == pytest.approx(1.448, abs=0.005)
    assert 6.0e3 < a.omega_RP < 7.0e3
    assert a.mu_RP_lower <= a.mu_RP * (1 + 1e-9) and a.mu_RP_lower > 0.999 * a.mu_RP
    # mu of a 1x1 complex block is |M11| = |H_m T|; the refined peak tops the grid
    s = 1j * a.omega
    HmT = np.ravel(H_m(s)) * np.ravel(robust.loop_functions(G, K).T(s))
    np.testing.assert_allclose(a.mu_RS_curve, np.abs(HmT), rtol=1e-7)
    assert a.mu_RS_curve.max() <= a.mu_RS <= a.mu_RS_curve.max() * 1.005
    assert a.mu_RP_upper.max() <= a.mu_RP
    assert np.all(a.closed_loop_poles.real < 0)
    frame = a.frame()
    assert list(frame.condition) == ["NS", "NP", "NP", "RS", "RP", "RP"]
    assert frame.met.tolist() == [True, True, True, True, False, False]


def test_analysis_of_destabilising_controller(models):
    G, H_m, H_e, H_y, K = models
    a = analysis.analyze(-K, G, H_m, H_e, H_y, name="minus K")
    assert not a.nominal_stability
    assert a.mu_RP == np.inf and a.norm_He_S == np.inf and np.isnan(a.omega_RP)
    assert np.all(np.isnan(a.mu_RP_upper)) and a.omega.shape == a.mu_RP_upper.shape
    table = analysis.table3(a, paper_values=paper.FIGURES_OF_MERIT)
    assert list(table.columns) == ["paper", "minus K"]
    assert not table.loc["NS: S, T, KS, GS stable", "minus K"]
    assert analysis.robust_performance_peak(-K, G, H_m, H_e, H_y)[0] == np.inf


def test_robust_performance_peak_is_the_analysis_peak(models, published):
    G, H_m, H_e, H_y, K = models
    peak, omega_peak = analysis.robust_performance_peak(K, G, H_m, H_e, H_y)
    assert peak == pytest.approx(published.mu_RP, rel=1e-3)
    assert omega_peak == pytest.approx(published.omega_RP, rel=1e-2)


def test_table3_side_by_side(models, published):
    G, H_m, H_e, H_y, _ = models
    other = analysis.analyze(ct.tf([0.5], [1e-4, 1.0]), G, H_m, H_e, H_y, name="lag",
                             omega=np.logspace(-2, 8, 200))
    table = analysis.table3(published, other)
    assert list(table.columns) == ["K", "lag"]
    assert table.loc["RP: peak mu(M)", "K"] == published.mu_RP
    with pytest.raises(TypeError, match="RobustnessAnalysis"):
        analysis.table3(published, "K")
    peaks = analysis.table3_peaks(published, other)
    assert list(peaks.columns) == ["K", "lag"]
    assert peaks.loc["omega of mu_RP peak [rad/s]", "K"] == published.omega_RP
    assert peaks.loc["mu_RP lower bound", "lag"] == other.mu_RP_lower
    assert peaks.loc["omega of ||H_y T|| [rad/s]", "lag"] == other.omega_Hy_T
    with pytest.raises(TypeError, match="table3_peaks: analyses must be RobustnessAnalysis"):
        analysis.table3_peaks(published, "K")


@pytest.mark.parametrize("change, error, match", [
    (dict(K=ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]])), ValueError, "K"),
    (dict(H_m="H_m"), TypeError, "H_m"),
    (dict(omega=np.logspace(0, 1, 5)), ValueError, "omega"),
])
def test_analyze_rejects_bad_arguments(models, change, error, match):
    G, H_m, H_e, H_y, K = models
    args = dict(K=K, G=G, H_m=H_m, H_e=H_e, H_y=H_y)
    args.update(change)
    with pytest.raises(error, match=match):
        analysis.analyze(**args)


def test_margins_table_published_controller(models):
    G, _, _, _, K = models
    # a more aggressive controller: the published K with twice the gain
    table = analysis.margins_table({"published": K, "2 K": 2 * K}, G, paper.SAMPLING_FREQUENCY_HZ)
    pub, hot = table["published"], table["2 K"]
    assert pub["closed loop stable"] and pub["phase margin [deg]"] > 60
    # the delay margin in samples of the sampled loop is the continuous one minus about the
    # half sample of the zero-order hold (Tustin's warping aside)
    cont = pub["delay margin [us]"] * 1e-6 * paper.SAMPLING_FREQUENCY_HZ
    assert 0.3 < cont - pub["sampled loop delay margin [samples]"] < 1.0
    assert all(pub[f"stable, delay {d}"] for d in analysis.MARGIN_DELAYS)
    # the whole-sample delays tolerated agree with the sampled loop's delay margin
    stable = [hot[f"stable, delay {d}"] for d in analysis.MARGIN_DELAYS]
    first_bad = stable.index(False) if False in stable else len(stable)
    assert hot["stable, delay 0"] and first_bad < len(stable)
    assert first_bad == int(np.floor(hot["sampled loop delay margin [samples]"])) + 1
    with pytest.raises(TypeError, match="controllers"):
        analysis.margins_table([K], G, 1e4)


def test_achievable_mu_lower_bound_below_published_mu(models, published):
    G, H_m, H_e, H_y, _ = models
    lb = analysis.achievable_mu_lower_bound(G, H_m, H_e, H_y)
    # a lower bound of every controller's mu_RP, the published K's included
    assert lb.value <= published.mu_RP
    # and of its nominal-performance part, sqrt(|H_e S|^2 + |H_y T|^2) >= each alone
    assert lb.value <= lb.hinf_upper
    assert lb.hinf_upper >= lb.value and lb.method == "hinf"


def test_box_stability_table_of_the_published_controller(models):
    from piezolib import uncertainty as unc

    G, published = models[0], models[4]
    Kd = robust.discretize(published, paper.SAMPLING_FREQUENCY_HZ).K
    table = analysis.box_stability_table({"published": (published, Kd)}, G, 0.05,
                                         paper.SAMPLING_FREQUENCY_HZ, delays=(0, 1))
    col = table["published"]
    # four of the 729 continuous loops are unstable (notebook 02), and the exact margins
    # are those of the margin function with the effective delays 0.5 and 1.5 samples
    assert col["unstable of 729, continuous, no delay"] == 4
    for d in (0, 1):
        exact = unc.parametric_stability_margin(G, published, delay=(d + 0.5) / 1e4).spread
        assert col[f"exact margin, delay {d} [%]"] == pytest.approx(100 * exact, rel=1e-12)
    assert col["exact margin, delay 1 [%]"] < col["exact margin, delay 0 [%]"] < 5
    assert col["unstable of 729, sampled, delay 1"] >= col["unstable of 729, sampled, delay 0"]
    assert 0 < col["grid spread, sampled, delay 1 [%]"] < 5
