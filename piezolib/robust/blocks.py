"""Uncertainty blocks of a structured perturbation Delta (MATLAB ``blk`` convention).

``M`` is p x q (p outputs, q inputs) and Delta = blockdiag(Delta_1, ...,
Delta_n) is q x p: each block reads some of M's outputs and drives some of
M's inputs, in order.  :func:`parse_blk` turns MATLAB's ``blk`` rows into
:class:`Block` objects; ``docs/robust.md`` has the full convention.
"""

from dataclasses import dataclass

import numpy as np

from piezolib._checks import check_integer

__all__ = ["Block", "parse_blk", "block_slices"]

_KINDS = ("complex", "real")


@dataclass(frozen=True)
class Block:
    """One block Delta_i of a structured perturbation.

    Parameters
    ----------
    rows : int
        Rows of Delta_i, i.e. the number of M's inputs it drives (> 0).
    cols : int
        Columns of Delta_i, i.e. the number of M's outputs it reads (> 0).
    kind : {'complex', 'real'}
        Field of the block's entries.
    repeated : bool
        True for a repeated scalar delta I_k (then rows == cols == k), False
        for a full block (complex only).

    Raises
    ------
    ValueError
        Non-positive sizes, an unknown kind, a non-square repeated scalar or
        a real full block.

    Examples
    --------
    >>> Block.from_blk_row(1, 2)
    Block(rows=1, cols=2, kind='complex', repeated=False)
    >>> Block.scalar(3, real=True).blk_row
    (-3, 0)
    """

    rows: int
    cols: int
    kind: str = "complex"
    repeated: bool = False

    def __post_init__(self):
        for name in ("rows", "cols"):
            value = getattr(self, name)
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                raise TypeError(f"Block {name} must be an integer, got {value!r}")
            if value <= 0:
                raise ValueError(f"Block {name} must be positive, got {value}")
            object.__setattr__(self, name, int(value))
        if self.kind not in _KINDS:
            raise ValueError(f"Block kind must be one of {_KINDS}, got {self.kind!r}")
        object.__setattr__(self, "repeated", bool(self.repeated))
        if self.repeated and self.rows != self.cols:
            raise ValueError(f"a repeated scalar block is square, got {self.rows} x {self.cols}")
        if self.kind == "real" and not self.repeated:
            raise ValueError("real full blocks are not supported; use a real repeated scalar")

    @classmethod
    def full(cls, rows, cols):
        """Complex full block in C^{rows x cols}."""
        return cls(rows, cols, "complex", False)

    @classmethod
    def scalar(cls, k, real=False):
        """Repeated scalar delta I_k, complex or real."""
        return cls(k, k, "real" if real else "complex", True)

    @classmethod
    def from_blk_row(cls, r, c):
        """Block of one MATLAB ``blk`` row: (r, c) full, (k, 0) complex or (-k, 0) real scalar."""
        if r > 0 and c > 0:
            return cls.full(r, c)
        if r > 0 and c == 0:
            return cls.scalar(r)
        if r < 0 and c == 0:
            return cls.scalar(-r, real=True)
        raise ValueError(
            f"({r}, {c}) is not a supported block: use (r, c) with r, c > 0 (complex "
            "full), (k, 0) (complex repeated scalar) or (-k, 0) (real repeated scalar)")

    @property
    def is_full(self):
        """True for a complex full block."""
        return not self.repeated

    @property
    def is_real(self):
        """True for a real (repeated) scalar block."""
        return self.kind == "real"

    @property
    def size(self):
        """k of a repeated scalar delta I_k (rows for a full block)."""
        return self.rows

    @property
    def scalar_scaling(self):
        """True when the block's D-scale is a scalar times identity (full or 1 x 1)."""
        return self.is_full or self.rows == 1

    @property
    def blk_row(self):
        """The MATLAB ``blk`` row (r, c) of this block."""
        if self.is_full:
            return (self.rows, self.cols)
        return (-self.rows if self.is_real else self.rows, 0)


def _rows_of(blk):
    """Integer (n, 2) array of ``blk`` rows; Block items are converted."""
    if isinstance(blk, Block):
        blk = [blk]
    try:
        items = list(blk)
    except TypeError:
        raise TypeError(f"blk must be a sequence of (r, c) integer pairs, got {blk!r}") from None
    if items and all(isinstance(x, Block) for x in items):
        return None, tuple(items)
    if any(isinstance(x, Block) for x in items):
        raise TypeError("blk must hold either Block objects or (r, c) pairs, not both")
    try:
        arr = np.asarray(items)
    except Exception as exc:  # ragged input
        raise TypeError(f"blk must be a sequence of (r, c) integer pairs: {exc}") from None
    if arr.ndim == 1 and arr.size == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0:
        raise ValueError(f"blk must be a non-empty sequence of (r, c) pairs, got shape {arr.shape}")
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.integer)
                                   or (np.issubdtype(arr.dtype, np.floating)
                                       and np.all(arr == np.round(arr)))):
        raise TypeError(f"blk must hold integers, got {arr.tolist()}")
    return arr.astype(int), None


def parse_blk(blk, p=None, q=None):
    """Validate a block structure and return its blocks.

    Parameters
    ----------
    blk : sequence of (int, int) or of Block
        MATLAB ``mussv`` rows: (r, c) with r, c > 0 a complex full r x c
        block, (k, 0) a complex repeated scalar, (-k, 0) a real repeated
        scalar; or :class:`Block` objects.
    p, q : int, optional
        Numbers of outputs and inputs of M; when given, the structure must use
        them exactly (sum of the blocks' cols = p, of their rows = q).

    Returns
    -------
    tuple of Block

    Raises
    ------
    TypeError
        Non-integer entries or a ragged ``blk``.
    ValueError
        A ``blk`` that is not a list of pairs, an unsupported row (zero or
        negative sizes), or sizes that do not match M.

    Examples
    --------
    >>> [b.blk_row for b in parse_blk([(1, 1), (1, 2)], p=3, q=2)]
    [(1, 1), (1, 2)]
    """
    arr, blocks = _rows_of(blk)
    if blocks is None:
        out = []
        for i, (r, c) in enumerate(arr):
            try:
                out.append(Block.from_blk_row(int(r), int(c)))
            except ValueError as exc:
                raise ValueError(f"blk row {i} = {exc}") from None
        blocks = tuple(out)
    if (p is None) != (q is None):
        raise ValueError("give both p and q (M's outputs and inputs) or neither")
    if p is not None:
        p, q = check_integer("p", p, minimum=1), check_integer("q", q, minimum=1)
        n_in, n_out = sum(b.rows for b in blocks), sum(b.cols for b in blocks)
        if n_out != p or n_in != q:
            rows = [b.blk_row for b in blocks]
            raise ValueError(
                f"blk does not fit M: M is p x q = {p} x {q} (outputs x inputs), so the "
                f"blocks' column counts c_i must sum to {p} and row counts r_i to {q}; blk "
                f"{rows} gives sum c_i = {n_out}, sum r_i = {n_in}")
    return blocks


def block_slices(blocks):
    """Where each block sits in M: (inputs, outputs) slices, one pair per block.

    ``inputs`` indexes M's columns (the block's rows), ``outputs`` M's rows
    (the block's columns), in the order of ``blocks``.

    Examples
    --------
    >>> blocks = parse_blk([(1, 1), (2, 3)])          # a 1x1 and a 2x3 complex block
    >>> block_slices(blocks)
    ((slice(0, 1, None), slice(0, 1, None)), (slice(1, 3, None), slice(1, 4, None)))
    """
    blocks = tuple(blocks) if hasattr(blocks, "__iter__") and not isinstance(blocks, str) else ()
    if not blocks or not all(isinstance(b, Block) for b in blocks):
        raise TypeError("blocks must be a non-empty sequence of Block (parse a blk with "
                        "parse_blk)")
    out, n_in, n_out = [], 0, 0
    for b in blocks:
        out.append((slice(n_in, n_in + b.rows), slice(n_out, n_out + b.cols)))
        n_in, n_out = n_in + b.rows, n_out + b.cols
    return tuple(out)
