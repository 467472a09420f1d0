"""Lower bounds on achievable mu / H-infinity norm: textbook values, validity against achieved designs."""

import control as ct
import pytest

from piezolib.robust.achievable import (LowerBound, achievable_range, performance_lower_bound,
                                        pointwise_lower_bound, structured_lower_bound)
from piezolib.robust.hinf import hinfsyn
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import hinf_norm

s = ct.tf("s")


def sensitivity_plant(W, G):
    """z = W (r - G u), y = r - G u: F_l(P, K) = W S."""
    Wss, Gss = ct.ss(W), ct.ss(G)
    Wss.name, Gss.name = "W", "G"
    W_ = ct.ss(Wss.A, Wss.B, Wss.C, Wss.D, inputs="e", outputs="z")
    G_ = ct.ss(Gss.A, Gss.B, Gss.C, Gss.D, inputs="u", outputs="yg")
    e = ct.summing_junction(["r", "-yg"], "e")
    return ct.interconnect([W_, G_, e], inputs=["r", "u"], outputs=["z", "e"])


def test_relative_degree_bound():
    # S(inf) = 1 for a strictly proper loop: inf_K ||W S|| = |W(inf)| = 0.5 (minimum-phase G)
    P = sensitivity_plant(0.5 * (s + 10) / (s + 0.01), 1 / (s + 1))
    lb = performance_lower_bound(P, 1, 1, ["z"], ["r"])
    assert lb.method == "hinf"
    assert lb.value == pytest.approx(0.5, rel=2e-3) and lb.value <= 0.5 * (1 + 1e-6)
    assert lb.hinf_lower <= lb.hinf_upper


def test_rhp_zero_interpolation_bound():
    # S(z) = 1 at the RHP zero z = 3: inf_K ||W S|| = |W(3)| (> |W(inf)| = 0.5)
    W = 0.5 * (s + 1) / (s + 0.01)
    P = sensitivity_plant(W, (1 - s / 3) / (s + 1) ** 2)
    lb = performance_lower_bound(P, 1, 1, [0], [0])
    exact = abs(complex(W(3.0)))
    assert lb.value <= exact * (1 + 1e-6) and lb.value == pytest.approx(exact, rel=2e-3)
    # its controller is close to optimal on the plant as given
    assert lb.hinf_upper == pytest.approx(exact, rel=2e-2)


def test_bound_below_every_controller():
    P = sensitivity_plant(0.5 * (s + 1) / (s + 0.01), (1 - s / 3) / (s + 1) ** 2)
    lb = performance_lower_bound(P, 1, 1, [0], [0])
    for rho in (1e-2, 1e-1, 1.0):   # H-inf controllers of more and more penalised problems
        res = hinfsyn(P, 1, 1, effort_weight=rho, noise_weight=rho, rtol=0.5)
        achieved = hinf_norm(lower_lft(P, res.K))[0]
        assert achieved >= lb.value
    # any stabilising K: a plain integral controller
    K = ct.tf([0.2], [1, 0])
    achieved = hinf_norm(lower_lft(P, K))[0]
    assert achieved >= lb.value


def test_pointwise_bound_is_parrott():
    # one measurement, one control, two exogenous outputs: min_x ||[a + b x; c]|| = |c| when b != 0
    P = ct.ss([], [], [], [[1.0, 2.0], [3.0, 0.0], [1.0, 0.0]], inputs=["w", "u"],
              outputs=["z1", "z2", "y"])
    assert pointwise_lower_bound(P, 1, 1, [1.0, 10.0]) == pytest.approx([3.0, 3.0])


def test_structured_bound_picks_largest_full_block():
    P = sensitivity_plant(0.5 * (s + 10) / (s + 0.01), 1 / (s + 1))
    best, per = structured_lower_bound(P, [(1, 1)], 1, 1)
    assert isinstance(best, LowerBound) and len(per) == 1 and best is per[0][1]
    text = achievable_range(best, 0.6)
    assert text.startswith("achievable mu_RP in [0.500, 0.600]")
    text = achievable_range(1.0, 0.5)                  # no bracket: never print [1.000, 0.500]
    assert "[" not in text and "below that bound" in text


def test_bad_input_named():
    P = sensitivity_plant(0.5 / (s + 1), 1 / (s + 1))
    with pytest.raises(ValueError, match="perf_outputs"):
        performance_lower_bound(P, 1, 1, ["nope"], ["r"])
    with pytest.raises(ValueError, match="perf_inputs"):
        performance_lower_bound(P, 1, 1, ["z"], [3])
    with pytest.raises(ValueError, match="omega"):
        pointwise_lower_bound(P, 1, 1, [-1.0])
    with pytest.raises(ValueError, match="nmeas"):
        performance_lower_bound(P, 2, 1, ["z"], ["r"])


def test_gamma_trial_limit_is_a_validated_count():
    W = 0.5 * (s + 1) / (s + 0.01)
    P = sensitivity_plant(W, (1 - s / 3) / (s + 1) ** 2)
    exact = abs(complex(W(3.0)))                  # inf_K ||W S||, as in the RHP-zero test
    full = performance_lower_bound(P, 1, 1, [0], [0])
    few = performance_lower_bound(P, 1, 1, [0], [0], max_iter=3)
    assert full.hinf.converged and full.hinf.iterations > 3
    assert few.hinf.iterations == 3 and not few.hinf.converged
    # fewer gamma trials: a wider bracket, but still a valid (lower) bound
    assert few.value < full.value <= exact * (1 + 1e-6)
    best, _ = structured_lower_bound(P, [(1, 1)], 1, 1, max_iter=3)
    assert best.value == few.value
    with pytest.raises(ValueError, match="max_iter must be >= 2"):
        performance_lower_bound(P, 1, 1, ["z"], ["r"], max_iter=1)
    with pytest.raises(TypeError, match="max_iter must be an integer"):
        performance_lower_bound(P, 1, 1, ["z"], ["r"], max_iter=60.0)
    with pytest.raises(TypeError, match="time_budget"):
        structured_lower_bound(P, [(1, 1)], 1, 1, time_budget=60.0)
