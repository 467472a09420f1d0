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
