"""The one-call mu design (piezolib.problem.design) on the paper's problem."""

import logging

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib.problem import analysis, design, genplant


@pytest.fixture(scope="module")
def result(models):
    G, H_m, H_e, H_y, _ = models
    return design.design_controller(G, H_m, H_e, H_y)


def test_design_gives_full_reduced_and_discrete_controllers(result):
    assert isinstance(result, design.ControllerDesign)
    assert result.K_full.nstates == 22 and result.K_reduced.nstates == 6
    for K in (result.K_full, result.K_reduced, result.K_discrete):
        assert K.input_labels == ["v_e"] and K.output_labels == ["u_b"]
    assert result.K_reduced.name == "K_mu6" and result.K_full.name == "K_mu22"
    assert result.K_discrete.dt == pytest.approx(1 / paper.SAMPLING_FREQUENCY_HZ)
    assert result.discrete.matches and result.discrete.loop_stable
    assert result.plant.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"]
    assert result.reduction.order == 6


def test_design_meets_robust_performance(models, result):
    G, H_m, H_e, H_y, _ = models
    mu = result.musyn
    assert mu.history.mu_upper.iloc[0] > 1.2 and mu.mu_peak < 0.85
    reduced = analysis.robust_performance_peak(result.K_reduced, G, H_m, H_e, H_y,
                                               omega=np.logspace(-2, 8, 400))[0]
    assert reduced < 0.85 and reduced - mu.mu_peak < 0.03


def test_design_is_deterministic_and_logs(models, result, caplog):
    G, H_m, H_e, H_y, _ = models
    with caplog.at_level(logging.INFO, logger="piezolib.problem.design"):
        again = design.design_controller(G, H_m, H_e, H_y)
    assert any("DK-iteration" in r.getMessage() for r in caplog.records)
    np.testing.assert_array_equal(again.K_reduced.A, result.K_reduced.A)
    np.testing.assert_array_equal(again.K_reduced.D, result.K_reduced.D)


def test_design_follows_the_models_given(models, result):
    G, H_m, H_e, _, _ = models
    other = design.design_controller(G, H_m, H_e, paper.output_weight(M_y=1.2), order=5,
                                     max_iter=2, fs=5000.0)
    assert other.K_reduced.nstates == 5 and other.K_discrete.dt == pytest.approx(2e-4)
    assert not np.allclose(other.musyn.history.gamma.iloc[0],
                           result.musyn.history.gamma.iloc[0])


@pytest.mark.parametrize("change, error, match", [
    (dict(order=0), ValueError, "order"),
    (dict(max_iter=0), ValueError, "max_iter"),
    (dict(effort_weight=0.0), ValueError, "effort_weight"),
    (dict(fs=-1.0), ValueError, "fs"),
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
    assert genplant.DESIGN_EFFORT_WEIGHT == 1e-3
