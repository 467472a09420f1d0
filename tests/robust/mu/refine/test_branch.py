"""Branch and bound over real parameters (mussv(..., refine=...) with real blocks)."""

from pathlib import Path

import numpy as np
import pytest

from piezolib.robust.blocks import parse_blk
from piezolib.robust.mu import mussv
from piezolib.robust.mu.refine.branch import branch_and_bound_upper, certifies_below

DATA = Path(__file__).parent / "data"
THREE_REAL = [(-1, 0)] * 3


def real_point():
    """A 3 x 3 matrix (one frequency of the benchmark's first purely real case) whose
    D,G bound is 14 % above the lower bound; a dense search of the parameter box's
    surface found no destabilising member beyond that lower bound."""
    return np.load(DATA / "real_scalars_point.npz")["M"]


def test_splitting_closes_the_real_gap_and_stays_above_the_lower_bound():
    M = real_point()
    plain = mussv(M, THREE_REAL)
    assert plain.gap[0] > 0.12
    refined = mussv(M, THREE_REAL, refine=0.05)
    assert refined.lower[0] == plain.lower[0]
    assert refined.gap[0] <= 0.05
    assert plain.lower[0] <= refined.upper[0] < plain.upper[0]
    # the lower bound's Delta is real, attains it and destabilises
    D = refined.Delta[0]
    assert np.allclose(D, np.diag(np.diag(D).real))
    assert np.isclose(np.linalg.norm(D, 2), 1 / refined.lower[0], rtol=1e-9)
    assert abs(np.linalg.det(np.eye(3) - M @ D)) < 1e-12


def test_no_certificate_below_a_destabilising_member():
    """The proof must fail where a real Delta of smaller norm makes I - M Delta singular."""
    M = real_point()
    lower = mussv(M, THREE_REAL).lower[0]
    blocks = parse_blk(THREE_REAL, 3, 3)
    assert not certifies_below(M[None], blocks, 0.99 * lower)[0]
    assert certifies_below(M[None], blocks, lower / (1 - 0.045))[0]


def test_mixed_structure_with_a_wide_block_before_the_real_one():
    """A 1 x 2 complex block ahead of a real scalar puts the real parameter at different
    positions of M's input and output spaces; the bounds must still bracket."""
    rng = np.random.default_rng(4)
    blk = [(1, 2), (-1, 0), (-1, 0)]
    M = rng.standard_normal((20, 4, 3)) + 1j * rng.standard_normal((20, 4, 3))
    plain = mussv(M, blk)
    refined = mussv(M, blk, refine=0.02)
    assert np.all(refined.upper <= plain.upper)
    assert np.all(refined.lower <= refined.upper * (1 + 1e-9))
    blocks = parse_blk(blk, 4, 3)
    assert not np.any(certifies_below(M, blocks, 0.99 * plain.lower))


def test_frequencies_start_from_their_neighbours_boxes():
    """On a grid the warm-started frequencies give the same certificates as cold ones."""
    M0 = real_point()
    t = np.linspace(0, 1, 24)[:, None, None]
    M = M0 * (1 + 0.05 * t) + 0.02 * t * M0.T
    plain = mussv(M, THREE_REAL)
    blocks = parse_blk(THREE_REAL, 3, 3)
    refined = branch_and_bound_upper(M, blocks, plain.upper, plain.lower, 0.05)
    assert np.all(refined <= plain.upper)
    improved = refined < plain.upper
    assert improved.sum() >= 20
    target = refined[improved]
    assert np.all(certifies_below(M[improved], blocks, target * (1 + 1e-9)))


@pytest.mark.parametrize("blk, p, q", [(THREE_REAL, 3, 3), ([(1, 2), (-1, 0), (-1, 0)], 4, 3)])
def test_inherited_scalings_are_checked_by_the_d_g_inequality(blk, p, q):
    """The cheap test of a parent's (Dl, Dr, G) on a sub-box is the D,G inequality itself:
    at the scalings of a D,G bound it returns that bound squared (plus its rounding; at most
    0 where the bound is 0, as real parameters can leave a complex M without any real
    destabilising member)."""
    from piezolib.robust.mu.refine import branch
    from piezolib.robust.mu.upper_mixed import mixed_upper_bound

    rng = np.random.default_rng(5)
    M = rng.standard_normal((6, p, q)) + 1j * rng.standard_normal((6, p, q))
    bound, _, _, Dl, Dr, G = mixed_upper_bound(M, parse_blk(blk, p, q))
    value = branch._certificate_value(M, Dl, Dr, G)
    positive = bound > 0
    assert positive.sum() >= 3
    np.testing.assert_allclose(value[positive], bound[positive] ** 2, rtol=1e-6)
    assert np.all(value[~positive] <= 1e-9)


def with_nan():
    M = real_point()[None].copy()
    M[0, 1, 1] = np.nan
    return M


@pytest.mark.parametrize("make_M, blk, beta, match", [
    (lambda: real_point()[None], THREE_REAL, 0.0, "beta must be"),
    (lambda: real_point()[None], THREE_REAL, np.nan, "beta must be"),
    (lambda: real_point()[None], THREE_REAL, [1.0, 2.0], "beta must be one level or one per"),
    (real_point, THREE_REAL, 1.0, "M must be 3-dimensional"),
    (with_nan, THREE_REAL, 1.0, "M contains 1 non-finite"),
    (lambda: real_point()[None], [(-1, 0)] * 2, 1.0, "blk"),
])
def test_certifies_below_rejects_bad_input(make_M, blk, beta, match):
    with pytest.raises(ValueError, match=match):
        certifies_below(make_M(), blk, beta)


def test_certifies_below_needs_a_positive_budget():
    with pytest.raises(ValueError, match="max_boxes"):
        certifies_below(real_point()[None], THREE_REAL, 1.0, max_boxes=0)


def test_certifies_below_needs_a_real_block():
    with pytest.raises(ValueError, match="real blocks"):
        certifies_below(real_point()[None], parse_blk([(1, 1)] * 3, 3, 3), 1.0)


def test_refine_rejects_repeated_real_scalars():
    with pytest.raises(ValueError, match="1 x 1 real scalars"):
        mussv(np.eye(3), [(-2, 0), (-1, 0)], refine=0.05)
