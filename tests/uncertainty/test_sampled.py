"""Model sets at a sampling rate: ZOH members, sampled loops, random draws, the grid spread."""

import control as ct
import numpy as np
import pytest

from piezolib.identification import zoh_coefficients
from piezolib.uncertainty import (member_zoh_coefficients, model_set, random_model_set,
                                  sampled_loop_poles, sampled_loop_spread, sampled_loop_unstable)

# a lightly damped plant with two zeros and coefficients far from one (scaled inside)
PLANT = ct.tf([2e6, 3e9, 4e12], np.poly([-300 + 4000j, -300 - 4000j, -2000, -8000]).real)
DT = 1e-4


@pytest.mark.parametrize("plant, dt", [(PLANT, DT), (ct.tf([2.0, 3.0, 5.0], [1.0, 4.0, 6.0]), 0.01),
                                       (ct.tf([1.0], [1.0, -1.0, 4.0]), 0.05)])
def test_every_member_is_the_exact_zoh_model(plant, dt):
    """The batched ZOH equals the scaled single-model ZOH of each member (biproper and
    unstable plants included).  Both are computed as differences of polynomials whose
    coefficients are of the size of a's (binomial near z = 1), so agreement is measured
    against max |a|."""
    mset = random_model_set(plant, 0.2, 12, seed=3)
    b, a = member_zoh_coefficients(mset, dt)
    for k in range(mset.size):
        bk, ak = zoh_coefficients(mset.member(k), dt)
        scale = np.abs(ak).max()
        np.testing.assert_allclose(a[k], ak, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(b[k], bk, rtol=0, atol=1e-12 * scale)


def test_a_strictly_proper_member_has_no_feedthrough():
    b, _ = member_zoh_coefficients(model_set(PLANT, 0.05), DT)
    assert np.all(b[:, 0] == 0.0)


@pytest.mark.parametrize("delay", [0, 1, 3])
def test_sampled_loop_poles_match_python_controls_feedback(delay):
    """Independent recomputation: each member's ZOH model, z^-d and the controller closed
    by control.feedback; the spectral radii agree."""
    K = ct.c2d(ct.tf([0.4, 400.0], [1.0, 10.0]) * ct.tf([1.0], [1e-4, 1.0]), DT, "tustin")
    mset = random_model_set(PLANT, 0.3, 8, seed=5)
    radius = np.abs(sampled_loop_poles(mset, K, DT, delay)).max(axis=1)
    for k in range(mset.size):
        Gd = ct.c2d(mset.member(k), DT, "zoh") * ct.tf([1.0], np.r_[1.0, np.zeros(delay)], DT)
        expected = np.abs(ct.poles(ct.feedback(ct.ss(Gd) * ct.ss(K), 1))).max()
        assert radius[k] == pytest.approx(expected, abs=1e-7)


def test_unstable_members_are_those_with_a_pole_on_or_outside_the_circle():
    K = ct.c2d(ct.tf([3.0, 3000.0], [1.0, 1.0]), DT, "tustin")
    mset = model_set(PLANT, 0.3)
    radius = np.abs(sampled_loop_poles(mset, K, DT, 2)).max(axis=1)
    bad = sampled_loop_unstable(mset, K, DT, 2)
    np.testing.assert_array_equal(bad, np.flatnonzero(radius >= 1))
    assert 0 < bad.size < mset.size          # the example has both kinds


def test_more_delay_loses_members():
    K = ct.c2d(ct.tf([3.0, 3000.0], [1.0, 1.0]), DT, "tustin")
    mset = model_set(PLANT, 0.3)
    counts = [sampled_loop_unstable(mset, K, DT, d).size for d in range(4)]
    assert counts == sorted(counts) and counts[-1] > counts[0]


def test_the_grid_spread_brackets_the_first_unstable_grid():
    K = ct.c2d(ct.tf([3.0, 3000.0], [1.0, 1.0]), DT, "tustin")
    spread = sampled_loop_spread(PLANT, K, DT, 1, rtol=1e-4)
    assert 0 < spread < 0.5
    assert sampled_loop_unstable(model_set(PLANT, spread), K, DT, 1).size == 0
    assert sampled_loop_unstable(model_set(PLANT, spread * 1.001), K, DT, 1).size > 0


def test_the_grid_spread_is_zero_for_an_unstable_nominal_loop():
    K = ct.c2d(ct.tf([300.0], [1.0]), DT, "tustin")          # far too much gain
    assert sampled_loop_spread(PLANT, K, DT, 1) == 0.0


def test_random_draws_fill_the_box_and_repeat_with_their_seed():
    first, again = (random_model_set(PLANT, 0.05, 500, seed=2) for _ in range(2))
    np.testing.assert_array_equal(first.offsets, again.offsets)
    assert first.offsets.shape == (500, 4) and first.levels == 0
    assert np.abs(first.offsets).max() <= 1 and np.abs(first.offsets).max() > 0.99
    assert not np.array_equal(first.offsets, random_model_set(PLANT, 0.05, 500, seed=3).offsets)


def test_a_controller_at_another_sample_time_is_refused():
    K = ct.c2d(ct.tf([1.0], [1.0, 1.0]), 2 * DT, "tustin")
    with pytest.raises(ValueError, match="Kd must be a discrete model with sample time"):
        sampled_loop_poles(model_set(PLANT, 0.05), K, DT)
