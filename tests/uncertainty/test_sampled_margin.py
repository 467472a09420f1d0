"""The sampled loop's parametric margin: what it claims, checked with the public API."""

import control as ct
import numpy as np
import pytest

from piezolib.uncertainty import (ModelSet, model_set, parametric_stability_margin,
                                  random_model_set, sampled_loop_poles, sampled_loop_unstable,
                                  sampled_parametric_margin)

G = ct.tf([1], [1, 3, 3, 1])            # 1/(s+1)^3
DT = 0.05
KD = ct.tf([2.0], [1], DT)


@pytest.fixture(scope="module")
def margin():
    return sampled_parametric_margin(G, KD, 1, samples=200)


def test_the_member_it_names_is_unstable_and_the_box_below_is_stable(margin):
    assert margin.bounded and margin.nominal_stable
    assert margin.spread < margin.spread_unstable <= margin.spread * (1 + 2e-3)
    member = ModelSet(G, margin.spread_unstable, 0, margin.offsets[None])
    assert np.abs(sampled_loop_poles(member, KD, DT, 1)).max() >= 1
    # every vertex and 3000 fresh random members at the returned spread are stable
    assert sampled_loop_unstable(model_set(G, margin.spread, levels=2), KD, DT, 1).size == 0
    draw = random_model_set(G, margin.spread, 3000, seed=7)
    assert sampled_loop_unstable(draw, KD, DT, 1).size == 0


def test_fast_sampling_approaches_the_continuous_exact_margin():
    # at 1 ms the ZOH is a half-sample delay: the continuous exact margin with 0.5 ms
    dt = 1e-3
    sampled = sampled_parametric_margin(G, ct.tf([2.0], [1], dt), 0, samples=0)
    exact = parametric_stability_margin(G, ct.tf([2.0], [1]), delay=dt / 2).spread
    assert sampled.spread == pytest.approx(exact, rel=2e-3)


def test_more_delay_less_margin_and_float32_changes_little(margin):
    more = sampled_parametric_margin(G, KD, 3, samples=0)
    assert more.spread < margin.spread
    single = sampled_parametric_margin(G, KD, 1, samples=200, float32=True)
    assert single.spread == pytest.approx(margin.spread, rel=2e-3)


def test_an_unstable_nominal_loop_has_no_margin():
    m = sampled_parametric_margin(G, ct.tf([20.0], [1], DT), 1)
    assert m.spread == 0.0 and not m.nominal_stable


@pytest.mark.parametrize("kwargs, error, word", [
    (dict(Kd=ct.tf([2.0], [1])), ValueError, "Kd"),
    (dict(Kd="2"), TypeError, "Kd"),
    (dict(samples=10 ** 6), ValueError, "samples"),
    (dict(delay_samples=10 ** 6), ValueError, "delay_samples"),
    (dict(delay_samples=-1), ValueError, "delay_samples"),
    (dict(spread_max=1.5), ValueError, "spread_max"),
    (dict(G=ct.tf([1], [1] * 14)), ValueError, "coefficients"),
])
def test_bad_input_is_refused_by_name(kwargs, error, word):
    args = dict(G=G, Kd=KD) | kwargs
    with pytest.raises(error, match=word):
        sampled_parametric_margin(args.pop("G"), args.pop("Kd"), **args)


def _same(a, b):
    return all(np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)
               for f in a.__dataclass_fields__)


def test_a_known_bracket_is_verified_and_gives_the_search_result(margin):
    known = (margin.spread, margin.spread_unstable, margin.offsets)
    assert _same(sampled_parametric_margin(G, KD, 1, samples=200, known=known), margin)


@pytest.mark.parametrize("shift", ["too high", "too low", "too wide", "stable member"])
def test_a_wrong_known_bracket_falls_back_to_the_search(margin, shift):
    low, high, q = margin.spread, margin.spread_unstable, margin.offsets
    known = {"too high": (1.05 * low, 1.06 * low, q),          # members unstable at its low end
             "too low": (0.9 * low, 0.9 * high, q),            # its member is stable at high
             "too wide": (0.5 * low, high, q),                 # wider than rtol
             "stable member": (low, high, np.zeros_like(q))}[shift]
    assert _same(sampled_parametric_margin(G, KD, 1, samples=200, known=known), margin)


@pytest.mark.parametrize("known, error", [
    ((0.1, 0.2), TypeError), ((0.2, 0.1, np.zeros(3)), ValueError),
    ((0.1, 0.6, np.zeros(3)), ValueError), ((0.1, 0.2, np.zeros(2)), ValueError),
    ((0.1, 0.2, np.full(3, 2.0)), ValueError), ((np.nan, 0.2, np.zeros(3)), ValueError)])
def test_bad_known_bracket_names_it(known, error):
    with pytest.raises(error, match="known"):
        sampled_parametric_margin(G, KD, 1, samples=0, known=known)
