"""Notebook 09's analysis on a small third-order loop (not the paper's): the box as an exact
LFT, real mu equal to the exact margin (rank one), the relaxations below it, the checks and
claim rows of the chosen design."""

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib import robust
from piezolib.problem import coefficient_box as box
from piezolib.problem.analysis import exact_margins_with_delay
from piezolib.problem.design import MixedDesign

#: A lightly damped third-order plant near 1e3 rad/s, a lag controller, a 10 kHz loop.
G = ct.tf([1e9], [1.0, 800.0, 2e6, 1e9])
K = ct.tf([0.3, 300.0], [1.0, 2000.0])
H_M = ct.tf([0.5, 50.0], [1.0, 1e3])
H_E = ct.tf([0.5], [1e-3, 0.05])
H_Y = ct.tf([1e-4, 0.0], [1e-3, 10.0])
FS = 1e4
GRID = (1e2, 1e5, 25)
TRACKING = pd.DataFrame({1.0: [0.5, 0.4], 10.0: [0.9, 0.8], 50.0: [3.0, 2.5]},
                        index=["Case III, our deployed K", "Case III, mixed-mu K"])


@pytest.fixture(scope="module")
def lft():
    return box.lft_exactness(G, K)


@pytest.fixture(scope="module")
def margins(lft):
    return box.stability_margins(G, H_M, {"K": K}, GRID, (1e1, 1e6, 120), exact={"K": lft.critical})


@pytest.fixture(scope="module")
def chosen():
    Kss = ct.ss(K)
    design = MixedDesign(K=Kss, performance_scale=1.0, spread=0.05, mu_peak=1.0,
                         mu_lower_peak=0.9, start_mu_peak=1.1,
                         margins=exact_margins_with_delay(G, Kss, FS), steps=None)
    tradeoff = box.recomputed_tradeoff([design], G, H_E, H_Y, FS)
    assert all(tradeoff.checks.values()) and tradeoff.chosen is design
    sos = robust.controller_sos(robust.discretize(Kss, FS).K, name="K")
    return box.check_chosen_design(design, Kss, {box.DEPLOYED: sos, box.MIXED: sos},
                                        G, H_E, H_Y, FS, ((1e1, 1e5, 20),))


def test_the_lft_is_exact(lft):
    assert len(lft.blk) == 3 and lft.blk[0] == (-1, 0)
    assert lft.lft_error < 1e-12 and lft.member_error < 1e-9
    assert all(lft.checks.values()) and "3 real blocks" in str(lft)


def test_real_mu_is_the_exact_margin_and_the_relaxations_certify_less(margins):
    r = margins.controllers["K"]
    assert r.real.spread == pytest.approx(r.exact.spread, rel=1e-4)       # rank one: exact
    assert r.real.spread <= r.exact.spread * (1 + 1e-6) <= r.real.spread_upper * (1 + 2e-6)
    assert r.complex.spread < r.real.spread and r.hm.lower <= r.small_gain.lower
    assert all(margins.checks.values()) and all(k.startswith("K: ") for k in margins.checks)
    assert margins.table().loc["K", "exact [%]"] == pytest.approx(100 * r.exact.spread)
    assert margins.comparison().loc["real / complex blocks", "K"] > 1
    claims = margins.claims()
    assert [c["section"] for c in claims] == ["IV"] * 5 + ["III-B"]
    assert claims[2]["ours"] == r.exact.spread and all(c["paper"] is None for c in claims)


def test_a_check_fails_when_it_does_not_hold(margins):
    r = margins.controllers["K"]
    narrow = box.ControllerMargins(**{**r.__dict__, "omega": np.array([1e4, 1e5])})
    assert not narrow.checks["the critical frequency lies inside the mu grid"]


def test_bounds_at_one_spread_match_the_exact_values(lft):
    spread = 2 * lft.critical.spread                  # twice the margin: not robustly stable
    b = box.spread_bounds(G, K, spread, lft.critical, GRID, 5, name="K")
    assert b.omega.size == 30 and all(b.checks.values())
    np.testing.assert_allclose(b.real.lower, b.exact_real, rtol=1e-6)
    np.testing.assert_allclose(b.complex.upper, b.exact_complex, rtol=1e-6)
    table = b.table()
    assert table["exact real mu at the crossing (spread / delta*)"] == pytest.approx(2.0)
    assert [c["quantity"] for c in b.claims()][0].startswith("K: peak mu_RS at +-")
    safe = box.spread_bounds(G, K, 0.5 * lft.critical.spread, lft.critical, GRID, 5, name="K")
    assert not safe.checks[next(iter(safe.checks))]   # robustly stable: the first check fails


def test_the_chosen_design_is_checked_and_claimed(chosen):
    assert all(chosen.checks.values())
    assert chosen.unstable(1) == (27, 0) and chosen.margin(1) >= 0.05
    assert list(chosen.box.columns) == [box.DEPLOYED, box.MIXED]
    assert chosen.table()["mu_RS upper, exact delay"] <= 0.05 / chosen.margin(1) * (1 + 1e-3)
    claims = box.mixed_claims(chosen, TRACKING)
    assert len(claims) == 15
    # the sampled loop's margin leads, the continuous stand-in is named for what it is
    assert claims[0]["quantity"] == "mixed-mu K: sampled-loop parametric margin, delay 0"
    assert claims[0]["ours"] == chosen.sampled_margin(0) == chosen.sampled[box.MIXED][0].spread
    assert claims[1]["quantity"] == "mixed-mu K: continuous stand-in margin, delay 0"
    assert claims[2]["quantity"] == "mixed-mu K: unstable of 27, sampled loop, delay 0"
    assert chosen.box.loc["sampled-loop margin, delay 1 [%]", box.MIXED] == pytest.approx(
        100 * chosen.sampled_margin(1))
    assert claims[-2]["ours"] == 0.8 and claims[-1]["ours"] == 2.5     # the mixed-mu K row


def test_without_a_certified_design_the_check_fails_and_nothing_is_claimed(chosen):
    none = box.ChosenDesignCheck(**{**chosen.__dict__, "design": None})
    assert none.checks == {"a mixed-mu design is certified for the box": False}
    assert box.mixed_claims(none, TRACKING) == [] and none.table().empty


def test_summary_lines(lft, margins, chosen):
    b = box.spread_bounds(G, K, 0.05, lft.critical, GRID, 5)
    lines = box.summary_lines(lft, margins, b, chosen, TRACKING, published="K")
    assert len(lines) == 6 and lines[0].startswith("the LFT is exact")
    assert "unstable sampled loops of 27 with delay 1: 0" in lines[-1]


@pytest.mark.parametrize("call, word", [
    (lambda: box.stability_margins(G, H_M, {}, GRID), "controllers"),
    (lambda: box.stability_margins(G, H_M, {"K": K}, (1e2, 1e5)), "grid"),
    (lambda: box.spread_bounds(G, K, -0.1, None), "spread"),
    (lambda: box.recomputed_tradeoff(iter([]), G, H_E, H_Y, FS), "designs"),
    (lambda: box.mixed_claims("chosen", TRACKING), "chosen"),
])
def test_bad_input_names_the_argument(call, word):
    with pytest.raises((TypeError, ValueError), match=word):
        call()
