"""D-scaling fits and DK-iteration."""

import control as ct
import numpy as np
import pytest

from piezolib.problem import genplant
from piezolib import paper, robust
from piezolib.problem.design import design_controller
from piezolib.robust.dfit import fit_magnitude
from piezolib.robust.dk import _full_blocks, musyn, scaled_plant
from piezolib.robust import lft_response
from piezolib.robust.mu import mussv

W = np.logspace(-2, 3, 300)


def minphase(order):
    """Known stable minimum-phase biproper functions of order 2 and 4."""
    sec = ct.tf([1 / 5 ** 2, 2 * 0.3 / 5, 1], [1 / 50 ** 2, 2 * 0.1 / 50, 1])
    if order == 2:
        return 2 * sec
    return 2 * sec * ct.tf([1 / 0.1 ** 2, 2 * 1.5 / 0.1, 1], [1, 2 * 0.8, 1])


@pytest.mark.parametrize("order", [2, 4])
def test_fit_recovers_known_magnitude(order):
    true = minphase(order)
    fit = fit_magnitude(W, np.abs(np.ravel(true(1j * W))), order)
    assert fit.max_log_error < 1e-6
    assert np.all(ct.poles(fit.tf).real < 0) and np.all(ct.zeros(fit.tf).real < 0)
    w = np.logspace(-3, 4, 50)
    np.testing.assert_allclose(np.abs(np.ravel(fit.tf(1j * w))), np.abs(np.ravel(true(1j * w))),
                               rtol=1e-5)


def test_fit_of_order_zero_is_weighted_geometric_mean():
    mag = np.exp(np.linspace(0, 2, W.size))
    weight = np.linspace(1, 3, W.size)
    fit = fit_magnitude(W, mag, 0, weight)
    expected = np.exp(np.sum(weight * np.log(mag)) / weight.sum())
    assert ct.dcgain(fit.tf) == pytest.approx(expected)


def test_fit_is_always_stable_minimum_phase_on_rough_data():
    rng = np.random.default_rng(3)
    mag = np.exp(rng.standard_normal(W.size))
    for order in (1, 3, 5):
        fit = fit_magnitude(W, mag, order)
        assert fit.order == order and ct.poles(fit.tf).size == order
        assert np.all(ct.poles(fit.tf).real < 0) and np.all(ct.zeros(fit.tf).real < 0)


def test_fit_rejects_bad_data():
    with pytest.raises(ValueError, match="magnitude must be positive"):
        fit_magnitude(W, -np.ones_like(W), 2)
    with pytest.raises(ValueError, match="equal lengths"):
        fit_magnitude(W, np.ones(3), 2)
    with pytest.raises(ValueError, match="non-finite"):
        fit_magnitude(W, np.full_like(W, np.nan), 2)
    with pytest.raises(ValueError, match="at least"):
        fit_magnitude(W[:5], np.ones(5), 4)


def test_scaled_plant_multiplies_the_right_channels():
    P = genplant.design_plant()
    d = ct.tf([1, 2], [1, 20])
    blocks = _full_blocks(genplant.DESIGN_BLOCK_STRUCTURE, 4, 2)
    PD = scaled_plant(P, blocks, [d], 1, 1)
    w = np.logspace(0, 5, 40)
    R, RD = (np.moveaxis(x(1j * w, squeeze=False), -1, 0) for x in (P, PD))
    dv = np.ravel(d(1j * w))
    expected = R.copy()
    expected[:, 0, :] *= dv[:, None]                  # y_Delta scaled by d
    expected[:, :, 0] /= dv[:, None]                  # u_Delta scaled by 1/d
    np.testing.assert_allclose(RD, expected, rtol=1e-7, atol=1e-12)


@pytest.fixture(scope="module")
def design():
    return design_controller()


def test_dk_iteration_history_and_bounds(design):
    mu = design.musyn
    hist = mu.history
    assert list(hist.columns) == ["iteration", "d_order", "gamma", "mu_upper", "mu_lower",
                                  "omega_peak", "K_order", "seconds"]
    # the first K-step has no scaling, so D-scaling must help: mu drops well below it
    assert mu.mu_peak < 0.7 * hist.mu_upper.iloc[0]
    assert mu.mu_peak == hist.mu_upper.min()
    # mu <= sigma(D M D^-1) <= gamma for the scalings of the K-step that gave K
    assert np.all(hist.mu_upper <= hist.gamma * (1 + 2e-3))
    assert np.all(hist.mu_lower <= hist.mu_upper * (1 + 1e-9))
    # two complex full blocks: the bounds meet
    assert mu.mu_lower_peak > 0.999 * mu.mu_peak
    assert "no improvement" in mu.stop_reason or "max_iter" in mu.stop_reason
    assert robust.is_stable(paper.plant(), design.K_full)


def test_dk_mu_of_exact_M_not_above_design_value(design):
    # the design plant adds the effort output to the performance block: the
    # exact M (eq. 18) can only have a lower mu
    omega = design.musyn.omega
    M = lft_response(genplant.generalized_plant(), design.K_full, omega)
    exact = mussv(M, genplant.BLOCK_STRUCTURE, lower=False).upper
    assert np.all(exact <= design.musyn.mu_upper * (1 + 1e-6))


def test_musyn_rejects_real_blocks_and_bad_grid():
    P = genplant.design_plant()
    with pytest.raises(ValueError, match="complex full blocks"):
        musyn(P, [(-1, 0), (1, 3)], verbose=False, max_iter=1)
    with pytest.raises(ValueError, match="increasing"):
        musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, omega=np.logspace(3, 1, 50), verbose=False)
    with pytest.raises(TypeError, match="d_order"):
        musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, d_order="high", verbose=False)


def test_musyn_progress_display(capsys):
    P = genplant.design_plant()
    musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, max_iter=2, d_order=2, verbose=True)
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2 and lines[0].startswith("DK  0")
    musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, max_iter=1, verbose=False)
    assert capsys.readouterr().out == ""
