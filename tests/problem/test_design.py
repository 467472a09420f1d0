"""The one-call mu design (piezolib.problem.design): delay-aware plant, DK, fixed order."""

import logging

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem import analysis, design, genplant

FS = paper.SAMPLING_FREQUENCY_HZ
FINE = np.logspace(-2, 7, 2000)


@pytest.fixture(scope="module")
def result(models):
    G, H_m, H_e, H_y, _ = models
    return design.design_controller(G, H_m, H_e, H_y)


@pytest.fixture(scope="module")
def quick(models):
    """A cheaper design of another problem: 5 states, 5 kHz, two DK iterations."""
    G, H_m, H_e, _, _ = models
    return design.design_controller(G, H_m, H_e, paper.output_weight(M_y=1.2), order=5,
                                    max_iter=2, fs=5000.0)


def mu_peak(P, K, omega=FINE):
    M = robust.lft_response(P, K, omega)
    return robust.mussv(M, genplant.DESIGN_BLOCK_STRUCTURE, omega).upper.max()


def sampled_radius(G, Kd, delay_samples):
    """Spectral radius of the loop ZOH(G) z^-d Kd, built with python-control only."""
    Ts = Kd.dt
    Gd = ct.c2d(ct.ss(robust.realize(G)), Ts, method="zoh")
    delay = ct.tf([1.0], [1.0] + [0.0] * delay_samples, Ts)
    return np.max(np.abs(ct.poles(ct.feedback(Gd * delay * Kd, 1))))


def test_design_gives_full_reduced_fixed_and_discrete_controllers(result):
    assert isinstance(result, design.ControllerDesign)
    P = result.plant
    assert P.name == "P_delay" and result.delay_samples == 1 and result.fs == FS
    assert P.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"]
    assert result.K_full.nstates == P.nstates + 2 * design.DESIGN_D_ORDER
    assert result.K_reduced.nstates == 6 == result.K_fixed.nstates
    for K in (result.K_full, result.K_reduced, result.K_discrete, result.K_fixed,
              result.K_fixed_discrete):
        assert K.input_labels == ["v_e"] and K.output_labels == ["u_b"]
    assert result.K_reduced.name == "K_mu6" and result.K_fixed.name == "K_fixed6"
    assert result.K_full.name == f"K_mu{result.K_full.nstates}"
    assert result.K_fixed_discrete.dt == pytest.approx(1 / FS)
    assert result.K_deployed is result.K_fixed
    assert result.K_deployed_discrete is result.K_fixed_discrete
    assert result.discrete.matches and result.fixed_discrete.matches


def test_fixed_order_is_no_worse_than_full_order_dk(result):
    P = result.plant
    full, reduced, fixed = (mu_peak(P, K) for K in (result.K_full, result.K_reduced,
                                                    result.K_fixed))
    start = mu_peak(P, result.K_reduced, design.DESIGN_GRID)
    assert result.fixed_order.start_mu_peak == pytest.approx(start, rel=1e-6)
    assert fixed < reduced - 0.02                    # the fixed-order step pays off
    # the goal: 6 states, delay modelled, mu_RP not above the full-order DK design (the
    # 1e-3 allows for the 2000-point grid missing a sharp peak of either controller)
    assert fixed <= full + 1e-3
    assert abs(fixed - result.fixed_order.mu_peak) < 2e-3
    assert np.all(ct.poles(robust.lower_lft(P, result.K_fixed)).real < 0)


def test_deployed_controller_tolerates_sampling_and_two_samples_of_delay(models, result):
    G = models[0]
    radii = [sampled_radius(G, result.K_fixed_discrete, d) for d in range(3)]
    assert max(radii) < 1, radii
    # the roll-off requirement: |K| stays below K_hf far above the bandwidth
    high = np.abs(np.ravel(result.K_fixed(1j * np.logspace(5, 8, 50))))
    assert high.max() < genplant.DESIGN_ROLLOFF.hf_gain


def test_paper_problem_design_is_kept_without_delay(models):
    # one DK step: the path of the design without delay (the paper's plant P, no fixed-order
    # K); the full design's mu (below 0.85) and that one sample of delay destabilises it are
    # checked on the committed controllers (notebook 05, tests/workbook/test_pipeline.py)
    G, H_m, H_e, H_y, _ = models
    old = design.design_controller(G, H_m, H_e, H_y, delay_samples=None, fixed_order=False,
                                   max_iter=1)
    assert old.plant.name == "P" and old.K_fixed is None and old.K_deployed is old.K_reduced
    assert old.K_discrete.dt == pytest.approx(1e-4) and old.musyn.history.shape[0] == 1
    assert sampled_radius(G, old.K_discrete, 0) < 1


def test_design_follows_the_models_given_and_is_deterministic(models, result, quick, caplog):
    G, H_m, H_e, _, _ = models
    assert quick.K_reduced.nstates == 5 == quick.K_fixed.nstates
    assert quick.K_fixed_discrete.dt == pytest.approx(2e-4)
    assert not np.allclose(quick.musyn.history.gamma.iloc[0],
                           result.musyn.history.gamma.iloc[0])
    with caplog.at_level(logging.INFO, logger="piezolib"):
        again = design.design_controller(G, H_m, H_e, paper.output_weight(M_y=1.2), order=5,
                                         max_iter=2, fs=5000.0)
    messages = [r.getMessage() for r in caplog.records]
    assert any("delay-aware" in m for m in messages)
    assert any(m.startswith("fixed-order") for m in messages)
    np.testing.assert_array_equal(again.K_fixed.A, quick.K_fixed.A)
    np.testing.assert_array_equal(again.K_fixed.C, quick.K_fixed.C)


@pytest.mark.parametrize("change, error, match", [
    (dict(order=0), ValueError, "order"),
    (dict(max_iter=0), ValueError, "max_iter"),
    (dict(delay_samples=None, effort_weight=0.0), ValueError, "effort_weight"),
    (dict(delay_samples=-1), ValueError, "delay_samples"),
    (dict(fs=-1.0), ValueError, "fs"),
    (dict(fixed_order="yes"), TypeError, "fixed_order"),
    (dict(rolloff=genplant.RolloffWeight(hf_gain=-1.0)), ValueError, "hf_gain"),
    (dict(G=ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]])), ValueError, "G"),
])
def test_design_rejects_bad_arguments(models, change, error, match):
    G, H_m, H_e, H_y, _ = models
    args = dict(G=G, H_m=H_m, H_e=H_e, H_y=H_y)
    args.update(change)
    with pytest.raises(error, match=match):
        design.design_controller(**args)


def test_design_constants():
    assert design.DESIGN_D_ORDER == 4 and design.DESIGN_GRID.size == 300
    assert genplant.DESIGN_EFFORT_WEIGHT == 1e-3 and genplant.DESIGN_DELAY_SAMPLES == 1


# --- mixed mu ----------------------------------------------------------------------

def _fake(scale, margins):
    return design.MixedDesign(K=ct.ss(ct.tf([1.0], [1.0, 1.0])), performance_scale=scale,
                              spread=0.05, mu_peak=1.0, mu_lower_peak=1.0, start_mu_peak=2.0,
                              margins=margins, steps=None)


def test_the_chosen_mixed_design_is_the_best_performance_certified_for_the_box():
    ok = {0: 0.04, 1: 0.06, 2: 0.05, 3: 0.02}
    designs = [_fake(0.1, ok), _fake(0.3, {**ok, 1: 0.051}), _fake(0.5, {**ok, 1: 0.049}),
               _fake(1.0, {**ok, 3: 0.0})]
    # 0.5 misses the box at the design delay, 1.0 is unstable with 3 samples of delay
    assert design.choose_mixed_design(designs).performance_scale == 0.3
    assert design.choose_mixed_design(designs, spread=0.07) is None


def test_a_short_mixed_design_keeps_the_order_and_reports_exact_margins(models):
    G, _, H_e, H_y, K_pub = models
    K0 = ct.ss(K_pub)
    res = design.design_mixed_controller(G, H_e, H_y, K0, performance_scale=0.2,
                                         omega=np.logspace(2, 6, 40), dg_steps=2)
    assert res.K.nstates == K0.nstates and res.K.input_labels == ["v_e"]
    assert res.mu_peak <= res.start_mu_peak and res.mu_lower_peak <= res.mu_peak * (1 + 1e-9)
    assert set(res.margins) == set(analysis.MARGIN_DELAYS)
    margins = analysis.exact_margins_with_delay(G, res.K, FS, delays=(1,))
    assert margins[1] == res.margins[1]
