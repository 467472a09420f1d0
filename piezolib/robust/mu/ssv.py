"""The structured singular value's entry point: :func:`mussv` and its result :class:`MuResult`.

Upper and lower bounds of mu_Delta(M) at every frequency, for a block
structure in MATLAB's ``mussv`` convention (:mod:`piezolib.robust.blocks`).
It chooses the algorithms of the wing (:mod:`piezolib.robust.mu`):
:mod:`~piezolib.robust.mu.upper_complex` (D-scaling),
:mod:`~piezolib.robust.mu.upper_mixed` (real blocks, AB13MD),
:mod:`~piezolib.robust.mu.lower` (power iteration) and, on request
(``refine``), :mod:`~piezolib.robust.mu.refine`; their derivations are in
``docs/robust.md``.
"""

from dataclasses import dataclass, field

import control as ct
import numpy as np
from threadpoolctl import ThreadpoolController

from piezolib._checks import check_finite_array, check_integer, check_positive
from piezolib.robust.blocks import Block, block_slices, parse_blk
from piezolib.robust.mu.lower import complex_lower_bound, mixed_lower_bound
from piezolib.robust.mu.refine.branch import branch_and_bound_upper
from piezolib.robust.mu.refine.lifted import (MAX_LIFTED_UNKNOWNS, lifted_unknowns,
                                              lifted_upper_bound)
from piezolib.robust.mu.upper_complex import complex_upper_bound
from piezolib.robust.mu.upper_mixed import mixed_upper_bound

__all__ = ["MuResult", "mussv"]

#: the BLAS libraries numpy and scipy loaded, to run mussv single-threaded
_BLAS = ThreadpoolController()


@dataclass(frozen=True)
class MuResult:
    """Bounds of mu at each frequency, with the scalings and a worst Delta.

    All arrays have the frequency axis first, also for a single matrix
    (then nf = 1).

    Attributes
    ----------
    upper : ndarray, shape (nf,)
        Upper bound of mu (D- or D,G-scaled bound).
    lower : ndarray, shape (nf,)
        Lower bound of mu, attained by ``Delta``.
    d : ndarray, shape (nf, nblk)
        Scalar D-scale d_i of each block whose scaling is a scalar (complex
        full blocks, 1 x 1 scalar blocks, real scalars), normalised so that
        the last complex full block has d = 1; NaN for repeated complex
        scalars with k > 1, whose scaling is a matrix (see ``Dl``, ``Dr``).
    Dl, Dr : ndarray, shapes (nf, p, p) and (nf, q, q)
        Left and right scaling matrices: for complex structures
        ``upper == sigma_max(Dl @ M @ inv(Dr))`` (except at the frequencies that
        ``mussv(..., refine=...)`` tightened, where upper is below it).  For full block i,
        Dl holds d_i I_{c_i} and Dr holds d_i I_{r_i}.
    g : ndarray, shape (nf, nblk), or None
        G-scale of each 1 x 1 real scalar block (NaN for other blocks);
        None when the structure has no real block.
    G : ndarray, shape (nf, q, p), or None
        G-scalings as q x p matrices (g at the real scalar positions); with
        them the mixed bound certifies
        ``M^H Dl^2 M + 1j (G M - M^H G^T) - upper^2 Dr^2 <= 0``.
    Delta : ndarray, shape (nf, q, p)
        Structured perturbation with ``det(I - M Delta) = 0`` and
        ``norm(Delta, 2) = 1 / lower``; zero where ``lower == 0``.
    omega : ndarray, shape (nf,), or None
        Frequencies [rad/s] if given (or taken from an FRD input).
    blk : tuple of (int, int)
        The block structure as MATLAB ``blk`` rows (:attr:`blocks` as
        :class:`~piezolib.robust.blocks.Block` objects).
    """

    upper: np.ndarray
    lower: np.ndarray
    d: np.ndarray
    Dl: np.ndarray
    Dr: np.ndarray
    g: np.ndarray | None
    G: np.ndarray | None
    Delta: np.ndarray
    omega: np.ndarray | None
    blk: tuple = field(default=())

    @property
    def blocks(self):
        """The block structure as a tuple of :class:`~piezolib.robust.blocks.Block`."""
        return parse_blk(self.blk)

    @property
    def gap(self):
        """Relative gap (upper - lower) / upper at each frequency (0 where upper = 0)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            gap = (self.upper - self.lower) / self.upper
        return np.where(self.upper > 0, gap, 0.0)

    def peak(self, bound="upper"):
        """Largest value of a bound and where it occurs.

        Parameters
        ----------
        bound : {"upper", "lower"}

        Returns
        -------
        value : float
        omega : float or None
            Frequency [rad/s] of the peak (None without frequencies).
        index : int
            Frequency index of the peak.
        """
        if bound not in ("upper", "lower"):
            raise ValueError(f"bound must be 'upper' or 'lower', got {bound!r}")
        values = getattr(self, bound)
        k = int(np.argmax(values))
        w = None if self.omega is None else float(self.omega[k])
        return float(values[k]), w, k


def _as_response(M, omega):
    """Return (array (nf, p, q), omega or None) from the accepted inputs."""
    if isinstance(M, ct.FrequencyResponseData):
        data = np.asarray(M.frdata if hasattr(M, "frdata") else M.fresp)
        if omega is not None:
            raise ValueError("omega must not be given with an FRD M (its own "
                             "frequencies are used)")
        omega = np.asarray(M.omega, float)
        arr = np.moveaxis(data.reshape(M.noutputs, M.ninputs, -1), -1, 0)
        arr = check_finite_array("M", arr)
        return arr.astype(complex), omega
    arr = check_finite_array("M", M)
    if arr.ndim not in (2, 3):
        raise ValueError("M must be a p x q matrix or an (nf, p, q) array with the "
                         f"frequency axis first, got shape {arr.shape}")
    arr = arr[None] if arr.ndim == 2 else arr
    if min(arr.shape) == 0:
        raise ValueError(f"M must not be empty, got shape {arr.shape}")
    if omega is not None:
        omega = check_finite_array("omega", omega, ndim=1, real=True)
        if np.any(omega < 0):
            raise ValueError(f"omega must be frequencies >= 0 [rad/s], got {omega.min():g}")
        if omega.shape[0] != arr.shape[0]:
            raise ValueError(f"omega has {omega.shape[0]} frequencies but M has "
                             f"{arr.shape[0]}")
    return arr.astype(complex), omega


def _check_refine(refine, blocks, lower):
    """Raise unless ``refine`` is None or a gap in (0, 1) on a structure it applies to."""
    if refine is None:
        return
    if isinstance(refine, bool) or not isinstance(refine, (int, float, np.floating)) \
            or not 0 < refine < 1:
        raise ValueError(f"refine must be None or a relative gap in (0, 1), got {refine!r}")
    if any(b.is_real and b.size > 1 for b in blocks):
        raise ValueError("refine with real blocks splits 1 x 1 real scalars only (the D,G "
                         "bound relaxes a repeated real scalar to independent ones, so "
                         "splitting could not approach mu), got blk "
                         f"{[b.blk_row for b in blocks]}")
    if not any(b.is_real for b in blocks) and lifted_unknowns(blocks) > MAX_LIFTED_UNKNOWNS:
        raise ValueError(f"refine handles structures of at most {MAX_LIFTED_UNKNOWNS} "
                         "unknowns (blocks x q^2, q = columns of M), got "
                         f"{len(blocks)} x {sum(b.rows for b in blocks)}^2 = "
                         f"{lifted_unknowns(blocks)}")
    if not lower:
        raise ValueError("refine needs the lower bound: it refines where the gap is wide; "
                         "pass lower=True")


#: frequencies bounded at a time by ``mussv(..., peak=True)``
PEAK_CHUNK = 8


def _descending_until(score, compute, scale, chunk=PEAK_CHUNK):
    """``[(indices, compute(indices)), ...]`` in descending order of ``scale * score`` until no
    frequency left can beat the largest ``scale * value`` found (``compute`` returns a tuple
    whose first entry is the value per index): ``score`` must bound that value from above, so
    the largest value over all frequencies is the one found (``scale``: mussv's
    per-frequency normalisation, undone to compare frequencies)."""
    score = score * scale
    order = np.argsort(-score, kind="stable")
    parts, best = [], -np.inf
    for start in range(0, order.size, chunk):
        if score[order[start]] <= best:
            break
        idx = order[start:start + chunk]
        parts.append((idx, compute(idx)))
        best = max(best, float(np.max(parts[-1][1][0] * scale[idx])))
    return parts


def _complex_relaxation(blocks):
    """The structure with every real scalar taken as independent 1 x 1 complex scalars: its
    D-scaled bound bounds the mixed D,G bound from above (that bound starts from it)."""
    out = []
    for b in blocks:
        out.extend([Block.scalar(1)] * b.rows if b.is_real else [b])
    return tuple(out)


def _peak_upper(arr, blocks, scale):
    """The mixed upper bound where it can set the peak, the complex relaxation's bound
    elsewhere (both bound mu; the peak is the one of the mixed bound at every frequency)."""
    nf, p, q = arr.shape
    cu, _, cDl, cDr = complex_upper_bound(arr, _complex_relaxation(blocks))
    d = np.full((nf, len(blocks)), np.nan)
    g = np.full((nf, len(blocks)), np.nan)
    for i, (b, (_, rows)) in enumerate(zip(blocks, block_slices(blocks))):
        if b.scalar_scaling:
            d[:, i] = cDl[:, rows.start, rows.start].real
        if b.is_real and b.size == 1:
            g[:, i] = 0.0
    upper, Dl, Dr, G = cu.copy(), cDl.real.copy(), cDr.real.copy(), np.zeros((nf, q, p))
    for idx, (u, di, gi, Dli, Dri, Gi) in _descending_until(
            cu, lambda k: mixed_upper_bound(arr[k], blocks), scale):
        if np.any(u > cu[idx] * (1 + 1e-9)):        # the pruning's premise failed: bound all
            return mixed_upper_bound(arr, blocks)
        upper[idx], d[idx], g[idx], Dl[idx], Dr[idx], G[idx] = u, di, gi, Dli, Dri, Gi
    return upper, d, g, Dl, Dr, G


def _peak_lower(arr, upper, scale, bound):
    """``bound(indices)`` -> (lower, Delta) where it can raise the largest lower bound (the
    upper bound is above it), zero (a valid lower bound) elsewhere."""
    nf, p, q = arr.shape
    low, Delta = np.zeros(nf), np.zeros((nf, q, p), complex)
    for idx, (lo, De) in _descending_until(upper, bound, scale):
        low[idx], Delta[idx] = lo, De
    return low, Delta


def mussv(M, blk, omega=None, *, lower=True, restarts=3, iterations=60, tol=1e-12, seed=0,
          refine=None, peak=False):
    """Upper and lower bounds of the structured singular value mu_Delta(M).

    Parameters
    ----------
    M : array_like or control.FrequencyResponseData
        Complex p x q matrix, or array of shape (nf, p, q) with the frequency
        axis first (e.g. a frequency response on nf frequencies), or an FRD
        (its frequencies become ``omega``).
    blk : sequence of (int, int) or of Block
        Block structure in MATLAB ``mussv`` convention
        (:func:`piezolib.robust.blocks.parse_blk`): (r, c) complex full r x c
        block, (k, 0) complex repeated scalar, (-k, 0) real repeated scalar;
        Delta is q x p, sum r_i = q, sum c_i = p.  E.g. ``[(1, 1), (1, 2)]``
        for a 1 x 1 uncertainty and a 1 x 2 performance block on a 3 x 2 M.
    omega : array_like, optional
        Frequencies [rad/s] of the nf matrices, stored in the result.
    lower : bool, optional
        Compute the lower bound and Delta (default).  With False, ``lower``
        is all zeros and ``Delta`` all zeros (faster, for D-steps).
    restarts : int, optional
        Random starts of the power iteration, in addition to the two
        deterministic ones (optimal-D and unscaled singular vectors).
    iterations : int, optional
        Power-iteration sweeps per start.
    tol : float, optional
        Newton steps on the smooth surrogate stop when they lower its
        logarithm by less than ``tol`` (complex structures).
    seed : int, optional
        Seed of the random starts (results are deterministic).
    refine : float, optional
        For complex structures (full blocks and complex scalars, at most
        :data:`~piezolib.robust.mu.refine.lifted.MAX_LIFTED_UNKNOWNS` unknowns, i.e. blocks x q^2
        <= 3000): at frequencies whose relative gap exceeds ``refine`` (e.g. 0.01),
        tighten the upper bound with the symmetric-lift certificate of
        :mod:`piezolib.robust.mu.refine.lifted`, each until its gap is at most ``0.9 refine`` or
        the certificate's optimum (or its cap of 60 centres) is reached.
        With real blocks (1 x 1 real scalars; repeated real scalars are
        rejected): branch and bound over the real parameters
        (:mod:`piezolib.robust.mu.refine.branch`) tries to certify lower / (1 - 0.9 refine)
        at each frequency whose gap exceeds ``refine``, with a budget of
        :data:`~piezolib.robust.mu.refine.branch.MAX_BOXES` D,G bounds there; where
        that runs out the D,G bound stays.
        Both cost far more than the plain bounds (milliseconds to seconds per refined
        frequency; measured in ``benchmarks/README.md``, "What mussv(refine=...) costs").
        Default None (the D-scaled or D,G bound only).
    peak : bool, optional
        Only the peaks over the grid are wanted (``upper.max()``, ``lower.max()``): the
        expensive bounds are computed in descending order of a cheaper bound above them
        until no frequency left can change the peak.  With real blocks, the D,G bound is
        computed where the complex relaxation's D-scaled bound (a bound above it) exceeds the
        largest D,G bound found, that relaxation's bound stands elsewhere (G = 0 there);
        the lower bound is computed where the upper bound exceeds the largest lower bound
        found, and is 0 elsewhere.  The peaks equal those of a full run's upper bound; the
        lower bound's peak can differ from a full run's by its random starts.  Both arrays
        stay valid bounds at every frequency.  Not with ``refine``.  Default False.

    Returns
    -------
    MuResult
        ``upper``, ``lower`` (nf,), scalings ``d``, ``Dl``, ``Dr`` (and ``g``
        with real blocks), the worst-case ``Delta`` (nf, q, p) and ``omega``.
        A single matrix gives nf = 1 (arrays of length 1).

    Raises
    ------
    ValueError, TypeError
        For non-finite or wrongly shaped ``M`` or ``omega``, a ``blk`` that
        does not fit M or holds an unsupported block row.

    Examples
    --------
    Two scalar blocks on a triangular matrix: mu is the largest diagonal
    entry, although sigma_max is 2.41.

    >>> import numpy as np
    >>> from piezolib.robust.mu import mussv
    >>> r = mussv(np.array([[1.0, 2.0], [0.0, 1.0]]), [(1, 1), (1, 1)])
    >>> round(float(r.upper[0]), 6), round(float(r.lower[0]), 6)
    (1.0, 1.0)
    """
    arr, omega = _as_response(M, omega)
    nf, p, q = arr.shape
    blocks = parse_blk(blk, p, q)
    restarts = check_integer("restarts", restarts, minimum=0)
    iterations = check_integer("iterations", iterations, minimum=1)
    tol = check_positive("tol", tol)
    if tol >= 1:
        raise ValueError(f"tol must be below 1 (a decrease of a logarithm), got {tol!r}")
    if not isinstance(lower, bool):
        raise TypeError(f"lower must be True or False, got {lower!r}")
    _check_refine(refine, blocks, lower)
    if not isinstance(peak, bool):
        raise TypeError(f"peak must be True or False, got {peak!r}")
    if peak and refine is not None:
        raise ValueError("peak=True does not combine with refine (refine tightens the bound "
                         "at every frequency whose gap is wide)")
    rng = np.random.default_rng(seed)
    blk_tuple = tuple(b.blk_row for b in blocks)
    has_real = any(b.is_real for b in blocks)
    # mu is homogeneous: work on M / c with c the largest |entry| at each
    # frequency (absurd scales such as 1e300 stay in range), scale back below
    c = np.abs(arr).max(axis=(1, 2))
    c = np.where(c > 0, c, 1.0)
    arr = arr / c[:, None, None]

    # the matrices are small (q is at most a few tens), so BLAS threads only add overhead:
    # on 2 cores they made refining 8 scalars 8x slower (docs/robust.md)
    with _BLAS.limit(limits=1, user_api="blas"):
        if has_real and peak:
            upper, d, g, Dl, Dr, G = _peak_upper(arr, blocks, c)
        elif has_real:
            upper, d, g, Dl, Dr, G = mixed_upper_bound(arr, blocks)
        else:
            upper, d, Dl, Dr = complex_upper_bound(arr, blocks, tol)
            g = G = None
        if not lower:
            low, Delta = np.zeros(nf), np.zeros((nf, q, p), complex)
        elif peak and has_real:
            low, Delta = _peak_lower(arr, upper, c, lambda k: mixed_lower_bound(
                arr[k], blocks, upper[k], iterations=iterations, rng=rng, restarts=restarts))
        elif peak:
            low, Delta = _peak_lower(arr, upper, c, lambda k: complex_lower_bound(
                arr[k], blocks, Dl[k], Dr[k], upper[k], iterations=iterations, rng=rng,
                restarts=restarts))
        elif has_real:
            low, Delta = mixed_lower_bound(arr, blocks, upper, iterations=iterations, rng=rng,
                                           restarts=restarts)
        else:
            low, Delta = complex_lower_bound(arr, blocks, Dl, Dr, upper, iterations=iterations,
                                             rng=rng, restarts=restarts)
        if refine is not None and has_real:
            upper = branch_and_bound_upper(arr, blocks, upper, low, refine)
        elif refine is not None:
            upper = lifted_upper_bound(arr, blocks, upper, low, Dl, Dr, refine)
    # both bounds are exact numbers for their D and Q; when they meet, the
    # lower one can exceed the upper one by rounding only (a larger excess
    # would be a bug, and is left visible)
    low = np.where(low <= upper * (1 + 1e-9), np.minimum(low, upper), low)
    upper, low, Delta = upper * c, low * c, Delta / c[:, None, None]
    if G is not None:
        G = G * c[:, None, None]
        g = g * c[:, None]
    return MuResult(upper=upper, lower=low, d=d, Dl=Dl, Dr=Dr, g=g, G=G, Delta=Delta,
                    omega=omega, blk=blk_tuple)
