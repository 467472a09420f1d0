"""Uncertainty blocks and the MATLAB blk parser."""

import numpy as np
import pytest

from piezolib.robust.blocks import Block, block_slices, parse_blk


def test_blk_rows_become_blocks():
    blocks = parse_blk([(2, 3), (4, 0), (-2, 0)], p=9, q=8)
    full, cplx, real = blocks
    assert full == Block(2, 3) == Block.full(2, 3)
    assert full.is_full and not full.is_real and full.kind == "complex"
    assert (full.rows, full.cols) == (2, 3)
    assert cplx == Block.scalar(4) and not cplx.is_full and not cplx.is_real
    assert cplx.rows == cplx.cols == cplx.size == 4
    assert real == Block.scalar(2, real=True) and real.is_real and real.repeated
    assert [b.blk_row for b in blocks] == [(2, 3), (4, 0), (-2, 0)]
    # only full blocks and 1 x 1 scalars have a scalar D-scaling
    assert [b.scalar_scaling for b in blocks] == [True, False, False]
    assert Block.scalar(1).scalar_scaling


def test_blocks_are_frozen_and_hashable():
    b = Block.full(1, 2)
    with pytest.raises(AttributeError):
        b.rows = 3
    assert {b, Block.full(1, 2)} == {b}


def test_parse_accepts_blocks_a_single_row_and_integral_floats():
    blocks = (Block.full(1, 1), Block.full(1, 2))
    assert parse_blk(blocks, 3, 2) == blocks
    assert parse_blk([(1, 1), (1, 2)]) == blocks
    assert parse_blk((1, 2)) == (Block.full(1, 2),)
    assert parse_blk(np.array([[1.0, 1.0], [1.0, 2.0]])) == blocks


def test_block_slices_follow_the_order_of_the_blocks():
    slots = block_slices(parse_blk([(2, 1), (1, 0), (1, 3)]))
    assert slots == ((slice(0, 2), slice(0, 1)), (slice(2, 3), slice(1, 2)),
                     (slice(3, 4), slice(2, 5)))


@pytest.mark.parametrize("blk, error, match", [
    ([(1, 1), (0, 2)], ValueError, "blk row 1 = .* not a supported block"),
    ([(-1, 1)], ValueError, "not a supported block"),
    ([(0, 0)], ValueError, "not a supported block"),
    ([(1, 1), (1.5, 2)], TypeError, "blk must hold integers"),
    ([(1, 2, 3)], ValueError, "sequence of \\(r, c\\) pairs"),
    ([], ValueError, "non-empty"),
    ([(1, 1), (1,)], TypeError, "blk must be a sequence"),
    (3, TypeError, "blk must be a sequence"),
    ([Block.full(1, 1), (1, 2)], TypeError, "not both"),
])
def test_bad_structures_are_rejected(blk, error, match):
    with pytest.raises(error, match=match):
        parse_blk(blk)


def test_sizes_must_match_the_matrix():
    with pytest.raises(ValueError, match="blk does not fit M: M is p x q = 3 x 2"):
        parse_blk([(1, 1), (2, 1)], p=3, q=2)        # transposed performance block
    with pytest.raises(ValueError, match="give both p and q"):
        parse_blk([(1, 1)], p=1)


@pytest.mark.parametrize("args, error, match", [
    ((0, 1), ValueError, "rows must be positive"),
    ((1, -2), ValueError, "cols must be positive"),
    ((1.0, 1), TypeError, "rows must be an integer"),
    ((1, 1, "quaternion"), ValueError, "kind must be one of"),
    ((2, 3, "complex", True), ValueError, "repeated scalar block is square"),
    ((1, 1, "real", False), ValueError, "real full blocks are not supported"),
])
def test_bad_blocks_are_rejected(args, error, match):
    with pytest.raises(error, match=match):
        Block(*args)
