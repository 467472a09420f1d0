"""Fixed-order mu-synthesis (piezolib.robust.fixed_order) on a textbook problem."""

import logging

import control as ct
import numpy as np
import pytest

from piezolib import robust
from piezolib.robust.fixed_order import (FixedOrderResult, ModalController, fixed_order_musyn,
                                         modal_controller)

# Robust performance of a lag plant with multiplicative input uncertainty, in the
# style of Skogestad & Postlethwaite: G = 200 / ((10 s + 1)(0.05 s + 1)^2),
# W_I = (s + 0.2) / (0.5 s + 1), W_P = (s / 2 + 0.5) / (s + 5e-3), W_u = 0.1.
BLK = [(1, 1), (1, 2)]
OMEGA = np.logspace(-3, 3, 60)


def textbook_problem():
    s = ct.tf("s")
    G = 200 / ((10 * s + 1) * (0.05 * s + 1) ** 2)
    parts = [ct.ss(G, inputs="u_p", outputs="y"),
             ct.ss((s + 0.2) / (0.5 * s + 1), inputs="u", outputs="y_Delta"),
             ct.ss((s / 2 + 0.5) / (s + 5e-3), inputs="e", outputs="z1"),
             ct.ss(ct.tf([0.1], [1]), inputs="u", outputs="z2"),
             ct.summing_junction(["u", "u_Delta"], "u_p"),
             ct.summing_junction(["w", "-y"], "e")]
    P = ct.interconnect(parts, inputs=["u_Delta", "w", "u"], outputs=["y_Delta", "z1", "z2", "e"])
    return G, ct.ss(P)


@pytest.fixture(scope="module")
def problem():
    G, P = textbook_problem()
    # a stabilising lag-lead start: stable, 3 states (odd order: one real pole)
    K0 = ct.ss(ct.tf([1.0, 0.1], [1.0, 1e-3]) * ct.tf([0.05, 1.0], [0.01, 1.0])
               * ct.tf([0.2], [0.002, 1.0]))
    return G, P, K0


@pytest.fixture(scope="module")
def result(problem):
    _, P, K0 = problem
    return fixed_order_musyn(P, BLK, K0, OMEGA)


def mu_peak(P, K, omega):
    return robust.mussv(robust.lft_response(P, K, omega), BLK, omega).upper.max()


def test_modal_form_reproduces_the_controller(problem):
    _, _, K0 = problem
    modal = modal_controller(K0)
    assert modal.order == 3 and modal.log_wr is not None
    w = np.logspace(-4, 4, 50)
    ref = np.ravel(K0(1j * w))
    np.testing.assert_allclose(modal.response(w), ref, rtol=1e-8)
    np.testing.assert_allclose(np.ravel(modal.state_space()(1j * w)), ref, rtol=1e-8)
    again = ModalController.from_theta(modal.theta, 3)
    np.testing.assert_array_equal(again.theta, modal.theta)
    # complex pole pair, even order
    K2 = ct.tf([3.0, 1.0, 50.0], [1.0, 0.4, 100.0])
    m2 = modal_controller(K2)
    assert m2.order == 2 and m2.log_wr is None
    np.testing.assert_allclose(np.exp(m2.log_w), [10.0], rtol=1e-10)
    np.testing.assert_allclose(np.ravel(m2.state_space()(1j * w)), np.ravel(K2(1j * w)),
                               rtol=1e-8)


def test_fixed_order_improves_on_its_start_and_is_verified(problem, result):
    G, P, K0 = problem
    assert isinstance(result, FixedOrderResult)
    assert result.K.nstates == 3 and result.K.input_labels == ["e"]
    assert result.K.output_labels == ["u"]
    start = mu_peak(P, K0, OMEGA)
    assert result.start_mu_peak == pytest.approx(start, rel=1e-6)
    assert result.mu_peak < 0.9 * start
    # verification independent of the optimiser: closed loops rebuilt by python-control
    assert np.all(ct.poles(ct.feedback(G * result.K, 1)).real < 0)
    assert np.all(ct.poles(robust.lower_lft(P, result.K)).real < 0)
    fine = np.logspace(-3, 3, 600)
    M = robust.lft_response(P, result.K, fine)
    bounds = robust.mussv(M, BLK, fine)
    assert bounds.upper.max() <= result.mu_peak * 1.01      # no peak hidden between points
    assert bounds.lower.max() <= bounds.upper.max() * (1 + 1e-9)
    assert bounds.lower.max() > 0.99 * bounds.upper.max()   # two full blocks: bounds meet
    hist = result.history
    assert hist.mu_upper.is_monotonic_decreasing and hist.accepted.any()
    assert np.all(np.abs(result.K.poles()).max() < 1e6)


def test_fixed_order_is_deterministic_and_logs(problem, result, caplog):
    _, P, K0 = problem
    with caplog.at_level(logging.INFO, logger="piezolib.robust.fixed_order"):
        again = fixed_order_musyn(P, BLK, K0, OMEGA)
    assert any("fixed-order" in r.getMessage() for r in caplog.records)
    np.testing.assert_array_equal(again.modal.theta, result.modal.theta)


@pytest.mark.parametrize("change, match", [
    (dict(K0=ct.tf([1.0], [1.0, -1.0])), "stable"),
    (dict(K0=ct.tf([-50.0], [1.0, 1.0])), "does not stabilise"),
    (dict(K0=ct.ss(ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]]))), "SISO"),
    (dict(omega=np.logspace(2, -2, 40)), "omega"),
    (dict(trust_radius=0.0), "trust_radius"),
    (dict(max_iter=0), "max_iter must be >= 1"),
    (dict(k_step_iterations=0), "k_step_iterations must be >= 1"),
    (dict(refinements=-1), "refinements must be >= 0"),
])
def test_fixed_order_rejects_bad_arguments(problem, change, match):
    _, P, K0 = problem
    args = dict(P=P, blk=BLK, K0=K0, omega=OMEGA)
    args.update(change)
    with pytest.raises(ValueError, match=match):
        fixed_order_musyn(**args)


def test_fixed_order_result_does_not_depend_on_the_clock_or_the_bar(problem, result,
                                                                   monkeypatch, capsys, slow_clock):
    """Steps that seem to take 1000 s each, with the bar shown: the same controller."""
    _, P, K0 = problem
    monkeypatch.setattr(robust.fixed_order, "time", slow_clock)
    monkeypatch.setenv("PIEZOLIB_PROGRESS", "1")
    slow = fixed_order_musyn(P, BLK, K0, OMEGA)
    np.testing.assert_array_equal(slow.modal.theta, result.modal.theta)
    assert slow.mu_peak == result.mu_peak and slow.stop_reason == result.stop_reason
    assert len(slow.records) == len(result.records) and slow.elapsed >= 1000.0
    err = capsys.readouterr().err
    assert "fixed-order 3" in err and "/60" in err     # max_iter 20 x (refinements 2 + 1)


@pytest.mark.parametrize("change, exc, match", [
    (dict(max_iter=2.5), TypeError, "max_iter must be an integer"),
    (dict(k_step_iterations="60"), TypeError, "k_step_iterations must be an integer"),
    (dict(time_budget=60.0), TypeError, "time_budget"),
])
def test_fixed_order_limits_are_integer_counts(problem, change, exc, match):
    _, P, K0 = problem
    with pytest.raises(exc, match=match):
        fixed_order_musyn(P, BLK, K0, OMEGA, **change)


# --- real blocks: the D,G-scaled bound -------------------------------------------

# the same loop with the input gain error real (a real scalar in [-1, 1] times W_I)
BLK_REAL = [(-1, 0), (1, 2)]


def test_dg_scaled_bound_is_the_mixed_bound_and_its_gradient_is_exact(problem):
    from piezolib.robust import fixed_order as fo

    _, P, K0 = problem
    modal = modal_controller(K0, OMEGA)
    loop = fo._Loop(P, OMEGA, robust.time_scale_of(P, K0))
    mu = robust.mussv(loop.M(modal.response(OMEGA)), BLK_REAL, OMEGA, lower=False)
    assert mu.G is not None and np.any(np.abs(mu.g[:, 0]) > 1e-3)     # G-scalings are used
    scale = np.ones(modal.theta.size)
    sigma = fo._scaled_bound(loop, modal, OMEGA, fo._scalings(mu), scale)
    value, grad = sigma(np.zeros(modal.theta.size), True)
    # at the current controller the scaled bound is the mixed upper bound itself
    np.testing.assert_allclose(value, mu.upper, rtol=1e-6)
    # central differences (step 1e-6 of parameters of order one: error ~1e-12 relative)
    rng = np.random.default_rng(3)
    for _ in range(3):
        d = 1e-6 * rng.standard_normal(modal.theta.size)
        fd = (sigma(d, False) - sigma(-d, False)) / 2
        np.testing.assert_allclose(fd, grad @ d, rtol=1e-4, atol=1e-6 * np.abs(grad @ d).max())


def test_fixed_order_with_a_real_block_lowers_mixed_mu_below_the_complex_design(problem,
                                                                                  result):
    _, P, K0 = problem
    mixed = fixed_order_musyn(P, BLK_REAL, K0, OMEGA)

    def real_peak(K, omega):
        return robust.mussv(robust.lft_response(P, K, omega), BLK_REAL, omega).upper.max()

    fine = np.logspace(-3, 3, 400)
    # verified independently of the search's own grid
    assert real_peak(mixed.K, fine) < real_peak(K0, fine)
    # the complex design is certified for discs; the mixed one does better on the interval
    assert real_peak(mixed.K, fine) < real_peak(result.K, fine)
    assert np.all(ct.poles(robust.lower_lft(P, mixed.K)).real < 0)
    assert mixed.mu.g is not None                                  # mixed bounds reported
    # each step reports both bounds of the best controller so far
    hist = mixed.history
    assert np.all(hist["mu_lower"] > 0) and np.all(hist["mu_lower"] <= hist["mu_upper"] * (1 + 1e-9))
    assert np.all(mixed.mu.lower <= mixed.mu.upper * (1 + 1e-9))

