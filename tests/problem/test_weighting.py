"""The weights of eq. 15, P against eq. 16, M against eq. 18, S and T under their templates."""

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib import paper
from piezolib.problem import genplant, weighting

OMEGA = np.logspace(0, 6, 25)


def test_templates_follow_eq15_for_other_weights():
    e = paper.ErrorWeightParameters(M_e=3.0, eps_e=0.01, omega_e=500.0)
    y = paper.OutputWeightParameters(M_y=1.2, eps_y=0.001, omega_y=2e4)
    t = weighting.template_asymptotes(e, y)
    np.testing.assert_allclose(t.table["computed"], t.table["from eq. 15"], rtol=2e-3)
    assert t.crossing_rad_s > e.omega_e
    with pytest.raises(TypeError, match="error_params"):
        weighting.template_asymptotes(y, y)


def test_P_matches_eq16_and_a_wrong_weight_is_seen(models):
    G, H_m, H_e, H_y, _ = models
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    entries = weighting.eq16_entries(P, G, H_m, H_e, H_y, omega=OMEGA)
    assert len(entries.table) == 12 and all(entries.checks.values())
    assert entries.omega.size == OMEGA.size
    wrong = weighting.eq16_entries(P, G, H_m, 2 * H_e, H_y, omega=OMEGA)
    assert wrong.worst == pytest.approx(0.5, rel=1e-6)
    assert not all(wrong.checks.values())
    with pytest.raises(TypeError, match="P"):
        weighting.eq16_entries(G.num, G, H_m, H_e, H_y)


def test_M_matches_eq18_only_for_its_own_controller(models):
    G, H_m, H_e, H_y, K = models
    M = genplant.closed_loop_matrix(K, G, H_m, H_e, H_y)
    assert weighting.eq18_error(M, K, G, H_m, H_e, H_y, omega=OMEGA) < 1e-6
    assert weighting.eq18_error(M, 1.1 * K, G, H_m, H_e, H_y, omega=OMEGA) > 1e-3
    with pytest.raises(TypeError, match="M"):
        weighting.eq18_error(None, K, G, H_m, H_e, H_y)


def _met(S_dB=0.97, bandwidth=372.0, stable=True):
    table = pd.DataFrame([("published K", True, True, 1.13, -0.02, 335.0),
                          ("our K", True, True, S_dB, -0.02, bandwidth)],
                         columns=["controller", "|S| < 1/|H_e|", "|T| < 1/|H_y|",
                                  "||S|| [dB]", "||T|| [dB]", "bandwidth of T [Hz]"])
    return weighting.TemplatesMet({"published K": None, "our K": None}, table,
                                  {"published K": True, "our K": stable}, ("published K",))


def test_claims_skip_the_peaks_of_the_published_controller():
    claims = _met().claims()
    assert [c["section"] for c in claims] == ["Fig. 11(a)", "Fig. 11(b)", "Fig. 11(a)",
                                              "Fig. 11(b)", "Sec. IV-B", "Sec. IV-B"]
    assert claims[-2]["quantity"] == "||S|| < 6 dB (our K)" and claims[-2]["note"] == "0.97 dB"
    assert claims[-1]["quantity"] == "||T|| < 3.5 dB (our K)"


def test_design_checks_hold_and_fail():
    assert all(_met().design_checks("our K").values())
    assert not all(_met(S_dB=6.5).design_checks("our K").values())
    assert not all(_met(bandwidth=500.0).design_checks("our K").values())
    assert not all(_met(stable=False).checks.values())
    with pytest.raises(ValueError, match="name"):
        _met().design_checks("nobody")


def test_templates_met_refuses_no_controllers(models):
    G, H_m, H_e, H_y, _ = models
    with pytest.raises(ValueError, match="controllers"):
        weighting.templates_met({}, G, H_m, H_e, H_y)
    with pytest.raises(TypeError, match="controllers"):
        weighting.templates_met([1.0], G, H_m, H_e, H_y)


@pytest.mark.slow
def test_templates_met_on_a_first_order_loop():
    """An integrator on a first-order plant: stable, with the bandwidth of its loop."""
    G = ct.tf([1e3], [1, 1e3])
    K = ct.tf([2e3], [1, 0])
    H_e, H_y = paper.error_weight(paper.ERROR_WEIGHT), paper.output_weight(paper.OUTPUT_WEIGHT)
    met = weighting.templates_met({"PI": K, "unstable": -K}, G, ct.tf([0.1], [1]), H_e, H_y,
                                  omega=np.logspace(1, 6, 16))
    assert met.checks == {"PI: the loop is stable": True, "unstable: the loop is stable": False}
    T = ct.feedback(G * K, 1)
    assert met.table.loc[0, "bandwidth of T [Hz]"] == pytest.approx(
        ct.bandwidth(T) / (2 * np.pi), rel=0.02)
