"""The parametric model set: offsets, members, responses and poles."""

import itertools

import control as ct
import numpy as np
import pytest

from piezolib import paper
from piezolib import uncertainty as unc

OMEGA = np.logspace(0, 6, 60)
SPREAD = 0.05


def test_model_set_size_and_levels():
    mset = unc.model_set(paper.plant(), SPREAD, 3)
    assert mset.size == 3 ** 6 and mset.order == 6
    assert set(np.unique(mset.offsets)) == {-1.0, 0.0, 1.0}
    # the nominal member (all offsets 0) is the published plant
    nominal = np.flatnonzero(np.all(mset.offsets == 0, axis=1))[0]
    np.testing.assert_allclose(mset.denominators[nominal], paper.PLANT.den, rtol=1e-15)
    four = unc.model_set(paper.plant(), spread=0.02, levels=4)
    assert four.size == 4 ** 6
    np.testing.assert_allclose(np.unique(four.offsets), [-1, -1 / 3, 1 / 3, 1])


def test_default_levels_are_nominal_and_both_extremes():
    mset = unc.model_set(ct.tf([1], [1, 2, 1]), 0.1)
    assert mset.levels == 3 and mset.size == 9
    np.testing.assert_array_equal(mset.offsets[4], [0.0, 0.0])


def test_level_offsets_run_through_the_combinations_in_lexicographic_order():
    for levels, n in [(2, 3), (3, 4), (5, 2)]:
        values = np.linspace(-1.0, 1.0, levels)
        expected = np.array(list(itertools.product(values, repeat=n)))
        np.testing.assert_array_equal(unc.level_offsets(levels, n), expected)


def test_levels_cap_refuses_absurd_sets_quickly():
    # 100**6 = 1e12 models would hang or exhaust memory: refused up front, naming the argument
    with pytest.raises(ValueError, match=r"levels = 100 gives 100\*\*6 .* more than MAX_MEMBERS"):
        unc.model_set(paper.plant(), SPREAD, levels=100)
    with pytest.raises(ValueError, match="levels"):
        unc.level_offsets(10 ** 9, 6)
    # the largest allowed set still builds
    assert unc.level_offsets(10, 6).shape == (unc.MAX_MEMBERS, 6)


def test_set_response_equals_a_loop_over_members():
    mset = unc.model_set(paper.plant(), SPREAD)
    fast = unc.set_response(mset, OMEGA)
    for k in range(mset.size):
        direct = np.ravel(mset.member(k)(1j * OMEGA))
        np.testing.assert_allclose(fast[k], direct, rtol=1e-9)


def test_member_poles_and_unstable_members_match_np_roots():
    mset = unc.model_set(paper.plant(), SPREAD)
    poles = unc.member_poles(mset)
    for k in (0, 17, 364, 728):
        np.testing.assert_allclose(np.sort_complex(poles[k]),
                                   np.sort_complex(np.roots(mset.denominators[k])), rtol=1e-8)
    direct = [k for k in range(mset.size) if np.roots(mset.denominators[k]).real.max() >= 0]
    np.testing.assert_array_equal(unc.unstable_members(mset), direct)


def test_member_closed_loop_poles_match_characteristic_polynomial():
    mset = unc.model_set(paper.plant(), SPREAD)
    K = paper.controller()
    poles = unc.member_closed_loop_poles(mset, K)
    for k in (0, 200, 728):
        char = np.polyadd(np.polymul(mset.denominators[k], K.den[0][0]),
                          np.polymul(mset.plant.num[0][0], K.num[0][0]))
        expected = np.sort_complex(np.roots(char))
        np.testing.assert_allclose(np.sort(np.abs(poles[k])), np.sort(np.abs(expected)), rtol=1e-6)


def test_perturbed_plant_and_member():
    G = ct.tf([1, 2], [1, 3, 2])
    Gq = unc.perturbed_plant(G, 0.1, [1.0, -1.0], name="Gq")
    np.testing.assert_allclose(Gq.den[0][0], [1, 3 * 0.9, 2 * 1.1])
    np.testing.assert_allclose(Gq.num[0][0], [1, 2])
    mset = unc.model_set(G, 0.1, 2)
    assert mset.member(3).name == "G_3"
    np.testing.assert_allclose(mset.member(3).den[0][0], mset.denominators[3])
    with pytest.raises(ValueError, match="offsets must lie in"):
        unc.perturbed_plant(ct.tf([1], [1, 2, 2, 1]), 0.1, [0.0, 2.0, 0.0])
    with pytest.raises(ValueError, match="k must be < 4"):
        mset.member(4)


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(spread=0.0), ValueError, "spread must be positive"),
    (dict(spread=-0.05), ValueError, "spread must be positive"),
    (dict(spread=1.5), ValueError, "spread must be below 1"),
    (dict(levels=1), ValueError, "levels must be >= 2"),
    (dict(levels=2.5), TypeError, "levels must be an integer"),
    (dict(G=ct.tf([1, 0, 0], [1, 1])), ValueError, "G must be proper"),
    (dict(G="plant"), TypeError, "G must be a control"),
    (dict(G=ct.tf([1], [1])), ValueError, "at least one pole"),
])
def test_model_set_bad_input(kwargs, error, match):
    args = dict(G=paper.plant(), spread=SPREAD) | kwargs
    with pytest.raises(error, match=match):
        unc.model_set(**args)


def test_other_bad_inputs():
    mset = unc.model_set(paper.plant(), spread=0.01)
    with pytest.raises(ValueError, match="omega must be positive"):
        unc.set_response(mset, np.array([0.0, 1.0]))
    with pytest.raises(TypeError, match="mset must be a ModelSet"):
        unc.member_poles("set")
    with pytest.raises(TypeError, match="missing 1 required positional argument: 'spread'"):
        unc.model_set(paper.plant())
