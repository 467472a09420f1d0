"""Structured singular value (mu) bounds of frequency-response arrays.

``mussv`` computes an upper and a lower bound of the structured singular
value mu_Delta(M) at every frequency of a frequency-response array, for a
block structure written in MATLAB's ``mussv`` convention (paper Sec. IV-B/C,
eq. 21-23 and Table 3).

Block-structure convention (``blk``)
------------------------------------
``M`` is p x q (p outputs, q inputs).  The perturbation Delta closes the loop
from M's outputs back to M's inputs, so Delta is q x p and
Delta = blockdiag(Delta_1, ..., Delta_n).  Row i of ``blk`` describes Delta_i:

============  ================================  ==========  ==========
row (r, c)    Delta_i                           M inputs    M outputs
============  ================================  ==========  ==========
(r, c), r,c>0 complex full block in C^{r x c}   r           c
(k, 0), k>0   complex repeated scalar d I_k     k           k
(-k, 0), k>0  real repeated scalar d I_k        k           k
============  ================================  ==========  ==========

The blocks take M's inputs and outputs in order, so sum(r_i) = q and
sum(c_i) = p.  The paper's M (eq. 18) is 3 x 2 with outputs
[y_Delta, y1, y2] and inputs [u_Delta, v_r]; its structure (eq. 21) is
``blk = [(1, 1), (1, 2)]``: Delta_r (1 x 1) from y_Delta to u_Delta, then the
1 x 2 performance block Delta_f from [y1, y2] to v_r.

Bounds
------
* Upper bound, complex structures: min over D of sigma_max(D_l M D_r^-1)
  (eq. 22) with D_l = blockdiag(d_i I_{c_i}), D_r = blockdiag(d_i I_{r_i})
  for full blocks and D_l = D_r = L_i (any invertible k x k matrix, here
  lower triangular) for repeated complex scalars.  For full blocks the
  function is convex in log d (Sezginer and Overton 1990).  It is minimised
  by Newton steps on a smooth convex surrogate, the log-Schatten-t norm
  (1/t) log sum_k sigma_k^t, for t = 2 (Frobenius, the Osborne scaling)
  up to t = 1.3e5, batched over all frequencies; the surrogate exceeds
  log sigma_max by at most log(min(p, q))/t, so the returned bound, which is
  sigma_max at the best D found, is within about 1e-5 of the optimum.
* Upper bound, with real scalar blocks: the mixed D,G bound of Fan, Tits and
  Doyle (1991) computed by SLICOT AB13MD (through slycot) one frequency at a
  time (always from a cold start: warm starts were seen not to terminate).
  AB13MD needs square blocks; non-square full blocks are padded with zero
  rows/columns (see ``_pad_square``: this changes neither mu nor the
  D-scaled bound), and repeated scalars (real or complex) are relaxed to
  independent 1 x 1 scalars, which gives a valid, possibly conservative,
  bound.
* Lower bound, complex structures: the power iteration of Packard and Doyle
  (1993), batched over frequency, from the singular vectors of the optimally
  scaled matrix and of M itself, plus seeded random starts where the bounds
  still differ.  Each run yields a structured Q with ||Q|| = 1; the bound is
  the largest |eigenvalue| lambda of Q M, so it is always a valid lower
  bound, attained by the returned Delta = Q / lambda:
  det(I - M Delta) = 0 and ||Delta|| = 1 / lower.
* Lower bound with real scalars (``_mixed_lower``): the real loops are
  closed at trial real values and the remaining complex blocks get the power
  iteration; the real values are searched along a set of directions with a
  fixed-point iteration that balances the real and complex parts, then
  refined coordinate-wise.  The returned Delta again attains the bound
  exactly, with real entries in the real blocks.  Purely real structures are
  exact only for a single 1 x 1 block; otherwise their lower bound may be 0.

For at most three complex full blocks (2 S + F <= 3) the D-scaled bound
equals mu, so the two bounds meet up to the optimiser's tolerance.
"""

from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib._checks import check_finite_array, check_integer

__all__ = ["MuResult", "mussv", "parse_blk"]

# continuation of the smoothing exponent t of the log-Schatten-t surrogate
_T_SCHEDULE = (2.0, 8.0, 32.0, 128.0, 512.0, 2048.0, 8192.0, 32768.0, 131072.0)
_NEWTON_ITERATIONS = 12           # per smoothing level (most stop after 2-4)
_STEP_FRACTIONS = np.array([1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 64, 1 / 256])
_MAX_STEP = 4.0                   # [log units] per Newton step
_MAX_LOG_SCALE = 40.0             # |log d| bound: d ratios up to e^40 ~ 2e17


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
        ``upper == sigma_max(Dl @ M @ inv(Dr))``.  For full block i,
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
        The block structure, as given.
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


class _Block:
    """One block of the structure, with its slices of M's outputs and inputs."""

    def __init__(self, kind, n_in, n_out, inputs, outputs):
        self.kind = kind          # "full", "complex" (repeated scalar) or "real"
        self.n_in = n_in          # rows of Delta_i = number of M inputs it drives
        self.n_out = n_out        # columns of Delta_i = number of M outputs it reads
        self.inputs = inputs      # slice of M's columns (q-space)
        self.outputs = outputs    # slice of M's rows (p-space)

    @property
    def k(self):
        return self.n_in

    @property
    def scalar_scaling(self):
        """True when the block's D-scale is a scalar times identity."""
        return self.kind == "full" or self.n_in == 1

    def __repr__(self):
        return f"_Block({self.kind}, {self.n_in}x{self.n_out})"


def parse_blk(blk, p=None, q=None):
    """Validate a MATLAB-style block structure and return its blocks.

    Parameters
    ----------
    blk : sequence of (int, int)
        Block structure (see the module docstring).
    p, q : int, optional
        Numbers of outputs and inputs of M; when given, the structure must
        use them exactly (sum of c_i = p, sum of r_i = q).

    Returns
    -------
    list of _Block
    """
    try:
        arr = np.asarray(blk)
    except Exception as exc:  # ragged input
        raise TypeError(f"blk must be a sequence of (r, c) integer pairs: {exc}") from None
    if arr.ndim == 1 and arr.size == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0:
        raise ValueError(f"blk must be a sequence of (r, c) pairs, got shape {arr.shape}")
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.integer)
                                   or (np.issubdtype(arr.dtype, np.floating)
                                       and np.all(arr == np.round(arr)))):
        raise TypeError(f"blk must hold integers, got {arr.tolist()}")
    arr = arr.astype(int)
    blocks, n_in, n_out = [], 0, 0
    for i, (r, c) in enumerate(arr):
        if r > 0 and c > 0:
            kind, bi, bo = "full", r, c
        elif r > 0 and c == 0:
            kind, bi, bo = "complex", r, r
        elif r < 0 and c == 0:
            kind, bi, bo = "real", -r, -r
        else:
            raise ValueError(
                f"blk row {i} = ({r}, {c}) is not a supported block: use (r, c) with "
                "r, c > 0 (complex full), (k, 0) (complex repeated scalar) or "
                "(-k, 0) (real repeated scalar)")
        blocks.append(_Block(kind, bi, bo, slice(n_in, n_in + bi), slice(n_out, n_out + bo)))
        n_in, n_out = n_in + bi, n_out + bo
    if p is not None and (n_out != p or n_in != q):
        raise ValueError(
            f"blk does not fit M: M is {p} x {q} (outputs x inputs), so the blocks' "
            f"column counts c_i must sum to {p} and row counts r_i to {q}; blk "
            f"{arr.tolist()} gives sum c_i = {n_out}, sum r_i = {n_in}")
    return blocks


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
        omega = check_finite_array("omega", omega, ndim=1)
        if omega.shape[0] != arr.shape[0]:
            raise ValueError(f"omega has {omega.shape[0]} frequencies but M has "
                             f"{arr.shape[0]}")
    return arr.astype(complex), omega


# ---------------------------------------------------------------------------
# upper bound for complex structures: smooth convex surrogate, batched Newton
# ---------------------------------------------------------------------------

class _Scaling:
    """Parametrisation theta -> (D_l, D_r) of the complex D-scalings.

    Scalar-scaled blocks get one log-scale each (the reference block's is
    fixed at 0); repeated complex scalars with k > 1 get a lower-triangular
    L_i = exp(diag(y)) + strictly-lower complex part.
    """

    def __init__(self, blocks, p, q):
        self.blocks, self.p, self.q = blocks, p, q
        scalar = [i for i, b in enumerate(blocks) if b.scalar_scaling]
        full = [i for i in scalar if blocks[i].kind == "full"]
        self.reference = (full or scalar or [None])[-1]
        self.out_map = np.zeros(p, int)      # p-row -> column of the padded log-scale
        self.in_map = np.zeros(q, int)
        self.scalar_index = {}               # block -> theta index (or -1 for reference)
        self.tri = []                        # (block, theta slice, row idx, col idx)
        n = 0
        for i in scalar:
            if i == self.reference:
                self.scalar_index[i] = -1
            else:
                self.scalar_index[i] = n
                n += 1
        self.n_scalar = n
        for i, b in enumerate(blocks):
            if not b.scalar_scaling:
                rows, cols = np.tril_indices(b.k, -1)
                size = b.k + 2 * rows.size
                self.tri.append((i, slice(n, n + size), rows, cols))
                n += size
        self.n = n
        self.diagonal = not self.tri
        if self.reference is None:
            # only matrix-scaled blocks: fix the first log-diagonal of the last
            self.fixed = self.tri[-1][1].start
        else:
            self.fixed = None
        for i, j in self.scalar_index.items():
            b = blocks[i]
            self.out_map[b.outputs] = j + 1     # 0 is the fixed zero column
            self.in_map[b.inputs] = j + 1

    def free(self):
        mask = np.ones(self.n, bool)
        if self.fixed is not None:
            mask[self.fixed] = False
        return mask

    def diag_logs(self, theta):
        padded = np.concatenate([np.zeros(theta.shape[:-1] + (1,)),
                                 theta[..., :self.n_scalar]], axis=-1)
        return padded[..., self.out_map], padded[..., self.in_map]

    def matrices(self, theta):
        """D_l (N, p, p), D_r (N, q, q) and their inverses."""
        N = theta.shape[0]
        xl, xr = self.diag_logs(theta)
        Dl = np.zeros((N, self.p, self.p), complex)
        Dr = np.zeros((N, self.q, self.q), complex)
        il, ir = np.arange(self.p), np.arange(self.q)
        Dl[:, il, il] = np.exp(xl)
        Dr[:, ir, ir] = np.exp(xr)
        Dli = np.zeros_like(Dl)
        Dri = np.zeros_like(Dr)
        Dli[:, il, il] = np.exp(-xl)
        Dri[:, ir, ir] = np.exp(-xr)
        for i, sl, rows, cols in self.tri:
            b = self.blocks[i]
            L = self._triangle(theta[:, sl], b.k, rows, cols)
            Li = np.linalg.inv(L)
            Dl[:, b.outputs, b.outputs] = L
            Dr[:, b.inputs, b.inputs] = L
            Dli[:, b.outputs, b.outputs] = Li
            Dri[:, b.inputs, b.inputs] = Li
        return Dl, Dr, Dli, Dri

    @staticmethod
    def _triangle(par, k, rows, cols):
        L = np.zeros((par.shape[0], k, k), complex)
        idx = np.arange(k)
        L[:, idx, idx] = np.exp(par[:, :k])
        m = rows.size
        L[:, rows, cols] = par[:, k:k + m] + 1j * par[:, k + m:k + 2 * m]
        return L

    def scaled(self, M, theta):
        if self.diagonal:
            xl, xr = self.diag_logs(theta)
            return np.exp(xl)[:, :, None] * M * np.exp(-xr)[:, None, :], None
        Dl, Dr, Dli, Dri = self.matrices(theta)
        return Dl @ M @ Dri, (Dl, Dr, Dli, Dri)

    def gradient(self, theta, U, V, w, mats):
        """Gradient of sum_k w_k log sigma_k with respect to theta."""
        N = theta.shape[0]
        grad = np.zeros((N, self.n))
        # diagonal of W_U = U diag(w) U^H and W_V
        wu = np.einsum("npk,nk->np", np.abs(U) ** 2, w)
        wv = np.einsum("nqk,nk->nq", np.abs(V) ** 2, w)
        for i, j in self.scalar_index.items():
            if j >= 0:
                b = self.blocks[i]
                grad[:, j] = wu[:, b.outputs].sum(1) - wv[:, b.inputs].sum(1)
        if self.tri:
            Dl, Dr, Dli, Dri = mats
            GL = Dli @ np.einsum("npk,nk,nrk->npr", U, w, U.conj())
            GR = Dri @ np.einsum("nqk,nk,nrk->nqr", V, w, V.conj())
            for i, sl, rows, cols in self.tri:
                b = self.blocks[i]
                gl = GL[:, b.outputs, b.outputs]
                gr = GR[:, b.inputs, b.inputs]
                diff = gl - gr
                k, m = b.k, rows.size
                idx = np.arange(k)
                par = theta[:, sl]
                # d/dy_a with L_aa = exp(y_a); d/dRe L_ab, d/dIm L_ab (a > b)
                g = np.empty((N, k + 2 * m))
                g[:, :k] = np.exp(par[:, :k]) * diff[:, idx, idx].real
                g[:, k:k + m] = diff[:, cols, rows].real
                g[:, k + m:] = -diff[:, cols, rows].imag
                grad[:, sl] = g
        if self.fixed is not None:
            grad[:, self.fixed] = 0.0
        return grad


def _surrogate(M, theta, scaling, t, need_grad=True):
    """Smooth surrogate F_t = (1/t) log sum sigma_k^t of the scaled matrix.

    Returns F (N,), gradient (N, n) or None, sigma_max (N,).
    """
    A, mats = scaling.scaled(M, theta)
    if not need_grad:
        s = _svd(A, compute_uv=False)
        return _log_schatten(s, t)[0], None, s[:, 0]
    U, s, V = _svd(A)
    F, w = _log_schatten(s, t)
    grad = scaling.gradient(theta, U, V, w, mats)
    return F, grad, s[:, 0]


def _svd(A, compute_uv=True):
    """Thin SVD of a stack of matrices: U (N, p, k), s (N, k), V (N, q, k).

    Closed form when min(p, q) <= 2 (the paper's M is 3 x 2), where LAPACK's
    per-matrix overhead dominates; LAPACK otherwise.  The closed form goes
    through the k x k Gram matrix, so sigma_max has full relative accuracy
    and the smaller singular value absolute accuracy ~ eps sigma_max, which
    is all the surrogate needs (its weight on small sigma_k vanishes).
    """
    N, p, q = A.shape
    if min(p, q) > 2:
        if not compute_uv:
            return np.linalg.svd(A, compute_uv=False)
        U, s, Vh = np.linalg.svd(A, full_matrices=False)
        return U, s, np.swapaxes(Vh, 1, 2).conj()
    if p < q:   # work on A^H: swap the roles of U and V
        out = _svd(np.swapaxes(A, 1, 2).conj(), compute_uv)
        return out if not compute_uv else (out[2], out[1], out[0])
    if q == 1:
        s = np.linalg.norm(A[:, :, 0], axis=1)[:, None]
        if not compute_uv:
            return s
        U = A / np.where(s > 0, s, 1)[:, None, :]
        U[s[:, 0] == 0, 0, 0] = 1.0
        return U, s, np.ones((N, 1, 1), complex)
    # q == 2: eigen-decomposition of the 2 x 2 Hermitian Gram matrix A^H A
    a = np.einsum("npi,npi->n", A[:, :, :1].conj(), A[:, :, :1]).real
    c = np.einsum("npi,npi->n", A[:, :, 1:].conj(), A[:, :, 1:]).real
    b = np.einsum("np,np->n", A[:, :, 0].conj(), A[:, :, 1])
    half = 0.5 * (a - c)
    root = np.hypot(half, np.abs(b))
    lam1 = 0.5 * (a + c) + root
    lam2 = np.maximum(0.5 * (a + c) - root, 0.0)
    s = np.sqrt(np.stack([lam1, lam2], axis=1))
    if not compute_uv:
        return s
    # eigenvector of lam1: (b, lam1 - a) or (lam1 - c, conj b), the larger one
    v_a = np.stack([b, lam1 - a], axis=1)
    v_b = np.stack([lam1 - c + 0j, b.conj()], axis=1)
    use_a = np.linalg.norm(v_a, axis=1) >= np.linalg.norm(v_b, axis=1)
    v1 = np.where(use_a[:, None], v_a, v_b)
    n1 = np.linalg.norm(v1, axis=1, keepdims=True)
    v1 = np.where(n1 > 0, v1 / np.where(n1 > 0, n1, 1), np.array([1.0, 0.0]))
    v2 = np.stack([-v1[:, 1].conj(), v1[:, 0].conj()], axis=1)
    V = np.stack([v1, v2], axis=2)
    AV = A @ V
    U = AV / np.where(s > 0, s, 1)[:, None, :]
    # zero singular values: any orthonormal completion
    U[s[:, 0] == 0, :, 0] = np.eye(p)[0]
    zero = s[:, 1] == 0
    if np.any(zero):
        U[zero, :, 1] = _orthogonal_unit(U[zero, :, 0])
    return U, s, V


def _orthogonal_unit(u):
    """A unit vector orthogonal to each (unit) row of u."""
    e = np.zeros_like(u)
    e[np.arange(len(u)), np.argmin(np.abs(u), axis=1)] = 1.0
    e = e - np.einsum("ni,ni->n", u.conj(), e)[:, None] * u
    return e / np.linalg.norm(e, axis=1, keepdims=True)


def _log_schatten(s, t):
    s1 = np.maximum(s[:, :1], np.finfo(float).tiny)
    r = (s / s1) ** t
    total = r.sum(1)
    return np.log(s1[:, 0]) + np.log(total) / t, r / total[:, None]


def _newton_direction(H, g, free):
    """Regularised Newton direction -H^-1 g on the free parameters."""
    Hf = H[:, free][:, :, free]
    Hf = 0.5 * (Hf + np.swapaxes(Hf, 1, 2))
    lam, Q = np.linalg.eigh(Hf)
    floor = 1e-9 * np.maximum(np.abs(lam).max(1, keepdims=True), 1.0)
    lam = np.maximum(lam, floor)
    gf = g[:, free]
    step = np.zeros_like(g)
    step[:, free] = -np.einsum("nij,nj,nkj,nk->ni", Q, 1 / lam, Q, gf)
    norm = np.linalg.norm(step, axis=1, keepdims=True)
    step *= np.minimum(1.0, _MAX_STEP / np.maximum(norm, 1e-300))
    decrement = -np.einsum("ni,ni->n", step, g)
    return step, decrement


def _complex_upper(M, blocks, tol):
    """D-scaled upper bound for complex structures; returns (upper, theta, scaling)."""
    nf, p, q = M.shape
    scaling = _Scaling(blocks, p, q)
    n = scaling.n
    theta = np.zeros((nf, n))
    best = np.linalg.svd(M, compute_uv=False)[:, 0]
    best_theta = theta.copy()
    if n == 0 or (scaling.fixed is not None and n == 1):
        return best, best_theta, scaling
    free = scaling.free()
    active_all = best > 0            # mu = 0 where M = 0: nothing to optimise
    nfree = int(free.sum())
    for t in _T_SCHEDULE:
        active = np.nonzero(active_all)[0]
        h = 1e-4 / np.sqrt(t)
        for _ in range(_NEWTON_ITERATIONS):
            if active.size == 0:
                break
            Ma, th = M[active], theta[active]
            na = active.size
            # value and gradient at theta and at theta +- h e_j (Hessian by differences)
            shifts = np.zeros((1 + 2 * nfree, n))
            for j, col in enumerate(np.nonzero(free)[0]):
                shifts[1 + 2 * j, col] = h
                shifts[2 + 2 * j, col] = -h
            pts = (th[None] + shifts[:, None]).reshape(-1, n)
            F, g, _ = _surrogate(np.tile(Ma, (len(shifts), 1, 1)), pts, scaling, t)
            F0, g = F[:na], g.reshape(len(shifts), na, n)
            H = np.zeros((na, n, n))
            for j, col in enumerate(np.nonzero(free)[0]):
                H[:, :, col] = (g[1 + 2 * j] - g[2 + 2 * j]) / (2 * h)
            step, dec = _newton_direction(H, g[0], free)
            # line search over a fixed set of step fractions, all in one batch
            cand = th[None] + _STEP_FRACTIONS[:, None, None] * step[None]
            cand = np.clip(cand, -_MAX_LOG_SCALE, _MAX_LOG_SCALE)
            Fc, _, sc = _surrogate(np.tile(Ma, (len(_STEP_FRACTIONS), 1, 1)),
                                   cand.reshape(-1, n), scaling, t, need_grad=False)
            Fc, sc = Fc.reshape(len(_STEP_FRACTIONS), na), sc.reshape(len(_STEP_FRACTIONS), na)
            k = np.argmin(Fc, axis=0)
            Fnew = Fc[k, np.arange(na)]
            improved = Fnew < F0
            theta[active[improved]] = cand[k[improved], np.nonzero(improved)[0]]
            # keep the D with the smallest sigma_max seen (that is the bound)
            kbest = np.argmin(sc, axis=0)
            sbest = sc[kbest, np.arange(na)]
            better = sbest < best[active]
            best[active[better]] = sbest[better]
            best_theta[active[better]] = cand[kbest[better], np.nonzero(better)[0]]
            done = (~improved) | (dec < tol) | (F0 - Fnew < tol)
            active = active[~done]
    return best, best_theta, scaling


# ---------------------------------------------------------------------------
# lower bound: power iteration
# ---------------------------------------------------------------------------

def _unit(x):
    n = np.linalg.norm(x, axis=-1, keepdims=True)
    return np.where(n > 0, x / np.where(n > 0, n, 1), 0)


def _structured_q(blocks, a, w, q_dim, p_dim):
    """Structured Q (N, q, p), ||Q_i|| <= 1, aligned with a (p-space) and w (q-space)."""
    N = a.shape[0]
    Q = np.zeros((N, q_dim, p_dim), complex)
    for b in blocks:
        ab, wb = a[:, b.outputs], w[:, b.inputs]
        if b.kind == "full":
            Q[:, b.inputs, b.outputs] = np.einsum("ni,nj->nij", _unit(wb), _unit(ab).conj())
        else:
            qs = _scalar_phase(np.einsum("ni,ni->n", ab.conj(), wb), b.kind)
            idx = np.arange(b.k)
            Q[:, b.inputs.start + idx, b.outputs.start + idx] = qs[:, None]
    return Q


def _power_iteration(M, blocks, b, w, iterations, real_only):
    """Packard-Doyle power iteration from starts b, w (rows of a batch).

    Returns the best (value, Q, lambda) seen at the checkpoints; rows whose
    value has settled stop iterating.
    """
    N, p, q = M.shape
    MH = np.swapaxes(M, 1, 2).conj()
    best_val = np.zeros(N)
    best_Q = np.zeros((N, q, p), complex)
    best_lam = np.ones(N, complex)
    b, w = _unit(b), _unit(w)
    active = np.arange(N)
    Ma, MHa = M, MH
    check = 5
    for it in range(iterations):
        a, w, b = _power_sweep(Ma, MHa, blocks, b, w)
        if (it + 1) % check and it != iterations - 1:
            continue
        Q = _structured_q(blocks, a, w, q, p)
        val, lam = _eigen_gain(Q, Ma, real_only)
        old = best_val[active]
        better = val > old
        rows = active[better]
        best_val[rows], best_Q[rows], best_lam[rows] = val[better], Q[better], lam[better]
        keep = np.abs(val - old) > 1e-13 * np.maximum(val, 1e-300)
        active, b, w = active[keep], b[keep], w[keep]
        if active.size == 0:
            break
        Ma, MHa = M[active], MH[active]
    return best_val, best_Q, best_lam


def _power_sweep(M, MH, blocks, b, w):
    """One sweep b -> a = M b -> z -> w = M^H z -> b, block by block."""
    a = _unit(np.einsum("npq,nq->np", M, b))
    w_new = _unit(np.einsum("nqp,np->nq", MH, _align(blocks, a, w, "z")))
    w = np.where(np.linalg.norm(w_new, axis=1, keepdims=True) > 0, w_new, w)
    bn = _unit(_align(blocks, a, w, "b"))
    b = np.where(np.linalg.norm(bn, axis=1, keepdims=True) > 0, bn, b)
    return a, w, b


def _align(blocks, a, w, side):
    """Block-wise alignment of the power iteration.

    ``side="z"`` gives z (M's output space): |w_i| a_i / |a_i| for a full
    block, conj(q_i) w_i for a scalar block; ``side="b"`` gives b (M's input
    space): |a_i| w_i / |w_i|, or q_i a_i, with q_i the scalar's phase (or
    sign) that aligns a_i with w_i.
    """
    to_z = side == "z"
    out = np.zeros_like(a if to_z else w)
    for blk in blocks:
        ab, wb = a[:, blk.outputs], w[:, blk.inputs]
        dest = blk.outputs if to_z else blk.inputs
        if blk.kind == "full":
            direction, size = (ab, wb) if to_z else (wb, ab)
            out[:, dest] = np.linalg.norm(size, axis=1, keepdims=True) * _unit(direction)
        else:
            qs = _scalar_phase(np.einsum("ni,ni->n", ab.conj(), wb), blk.kind)
            out[:, dest] = np.conj(qs)[:, None] * wb if to_z else qs[:, None] * ab
    return out


def _scalar_phase(s, kind):
    mag = np.abs(s)
    if kind == "complex":
        return np.where(mag > 0, s / np.where(mag > 0, mag, 1), 1.0)
    return np.where(s.real >= 0, 1.0, -1.0)


def _eigen_gain(Q, M, real_only):
    """Largest |lambda| of Q M (real lambda only if real_only), with lambda."""
    lam = np.linalg.eigvals(Q @ M)
    mag = np.abs(lam)
    if real_only:
        mag = np.where(np.abs(lam.imag) <= 1e-9 * np.maximum(mag, 1e-300), mag, 0.0)
    k = np.argmax(mag, axis=1)
    idx = np.arange(len(k))
    val = mag[idx, k]
    out = lam[idx, k]
    if real_only:
        out = out.real + 0j
    return val, np.where(val > 0, out, 1.0)


def _lower_bound(M, blocks, starts, iterations, rng, n_random, upper):
    """Best power-iteration lower bound over several starts.

    The deterministic starts run everywhere; the ``n_random`` seeded random
    starts run only where the bounds still differ by more than 1e-6.
    """
    nf, p, q = M.shape
    real_only = any(b.kind == "real" for b in blocks)
    lower = np.zeros(nf)
    Delta = np.zeros((nf, q, p), complex)

    def run(rows, start_list):
        R = len(start_list)
        b0 = np.concatenate([s[0] for s in start_list])
        w0 = np.concatenate([s[1] for s in start_list])
        val, Q, lam = _power_iteration(np.tile(M[rows], (R, 1, 1)), blocks, b0, w0,
                                       iterations, real_only)
        n = len(rows)
        val = val.reshape(R, n)
        k = np.argmax(val, axis=0)
        pick = k * n + np.arange(n)
        best = val[k, np.arange(n)]
        better = best > lower[rows]
        sel = rows[better]
        lower[sel] = best[better]
        Delta[sel] = Q[pick[better]] / lam[pick[better]][:, None, None]

    run(np.arange(nf), starts)
    todo = np.nonzero(lower < upper * (1 - 1e-6))[0]
    if todo.size and n_random:
        shape = (todo.size, q)
        run(todo, [(rng.standard_normal(shape) + 1j * rng.standard_normal(shape),
                    rng.standard_normal(shape) + 1j * rng.standard_normal(shape))
                   for _ in range(n_random)])
    return lower, Delta


# ---------------------------------------------------------------------------
# mixed (real + complex) upper bound through SLICOT AB13MD
# ---------------------------------------------------------------------------

def _pad_square(M, blocks):
    """Pad non-square full blocks with zero rows/columns for AB13MD.

    Full block i (r_i x c_i) becomes m_i x m_i with m_i = max(r_i, c_i): M
    gets m_i - c_i zero rows after its c_i rows and m_i - r_i zero columns
    after its r_i columns.  This leaves mu unchanged: if E_o (n x p) and
    E_i (n x q) are the zero-inserting isometries, M_pad = E_o M E_i^T and
    det(I - M_pad Dp) = det(I - M E_i^T Dp E_o), where E_i^T Dp E_o keeps the
    top-left r_i x c_i corner of each padded block Dp_i (no larger in norm);
    conversely every Delta embeds, zero-padded, with the same norm.  The
    D-scaled bound is unchanged too, as the zero rows and columns add nothing
    to sigma_max(D M D^-1).  Real scalars are split into 1 x 1 real blocks.

    Returns the padded matrices, AB13MD's nblock/itype, and the row/column
    positions of M's outputs/inputs in the padded matrix.
    """
    nf, p, q = M.shape
    nblock, itype, rows, cols = [], [], [], []
    n = 0
    for b in blocks:
        if b.kind == "full":
            m = max(b.n_in, b.n_out)
            rows.extend(n + np.arange(b.n_out))
            cols.extend(n + np.arange(b.n_in))
            nblock.append(m)
            itype.append(2)
            n += m
        else:
            for j in range(b.k):
                rows.append(n)
                cols.append(n)
                nblock.append(1)
                itype.append(1 if b.kind == "real" else 2)
                n += 1
    Mp = np.zeros((nf, n, n), complex)
    rows, cols = np.asarray(rows), np.asarray(cols)
    Mp[:, rows[:, None], cols[None, :]] = M
    return Mp, np.array(nblock), np.array(itype), rows, cols


def _mixed_upper(M, blocks):
    """AB13MD D,G upper bound, one frequency at a time.

    Returns upper (nf,), d (nf, nblk), g (nf, nblk), the diagonals of Dl
    (nf, p) and Dr (nf, q) and G (nf, q, p), normalised so that the last
    complex full block has d = 1 (the LMI is homogeneous in (D^2, G)).
    """
    from slycot import ab13md

    nf, p, q = M.shape
    Mp, nblock, itype, rows, cols = _pad_square(M, blocks)
    upper = np.zeros(nf)
    dpad = np.ones((nf, Mp.shape[1]))
    gpad = np.zeros((nf, Mp.shape[1]))
    for k in range(nf):
        if not np.any(Mp[k]):
            continue
        # always a cold start: warm starts (x from the previous frequency)
        # were seen to make AB13MD iterate without end
        upper[k], dpad[k], gpad[k], _ = ab13md(Mp[k], nblock, itype)
    if Mp.shape[1] == 1 and itype[0] == 1:
        # AB13MD returns 0 for a 1 x 1 real problem; mu is |m| if m is real
        m = Mp[:, 0, 0]
        upper = np.where(np.abs(m.imag) <= 1e-12 * np.abs(m), np.abs(m), 0.0)
        dpad[:], gpad[:] = 1.0, 0.0
    full = [b for b in blocks if b.kind == "full"]
    ref = rows[full[-1].outputs.start] if full else 0
    scale = dpad[:, ref:ref + 1]
    dpad, gpad = dpad / scale, gpad / scale ** 2
    d = np.full((nf, len(blocks)), np.nan)
    g = np.full((nf, len(blocks)), np.nan)
    for i, b in enumerate(blocks):
        if b.kind == "full" or b.k == 1:
            d[:, i] = dpad[:, rows[b.outputs.start]]
        if b.kind == "real" and b.k == 1:
            g[:, i] = gpad[:, rows[b.outputs.start]]
    G = np.zeros((nf, q, p))
    same = rows[None, :] == cols[:, None]         # padded position shared by in and out
    qi, pi = np.nonzero(same)
    G[:, qi, pi] = gpad[:, cols[qi]]
    return upper, d, g, dpad[:, rows], dpad[:, cols], G


def _mixed_lower(M, blocks, upper, iterations, rng, restarts):
    """Lower bound for structures with real scalars.

    Closing the real loops at fixed real values delta_r leaves the complex
    blocks with M_c(delta_r) = M_cc + M_cr D_r (I - M_rr D_r)^-1 M_rc, and
    det(I - M Delta) = det(I - M_rr D_r) det(I - M_c Delta_c); so any
    delta_r and a complex Delta_c destabilising M_c give a structured Delta
    of norm max(|delta_r|, ||Delta_c||).  delta_r is searched on a grid
    (scaled by 1 / upper) and refined coordinate-wise; the complex part uses
    the power iteration.  Without complex blocks only a single 1 x 1 real
    scalar is handled exactly (mu = |m| for real m); other purely real
    structures get the plain power-iteration bound (often 0).
    """
    nf, p, q = M.shape
    real = [b for b in blocks if b.kind == "real"]
    comp = [b for b in blocks if b.kind != "real"]
    if not comp:
        if p == 1 and q == 1:
            m = M[:, 0, 0]
            ok = (np.abs(m.imag) <= 1e-12 * np.abs(m)) & (m != 0)
            lower = np.where(ok, np.abs(m), 0.0)
            Delta = np.where(ok, 1 / np.where(ok, m.real, 1), 0.0)[:, None, None] + 0j
            return lower, Delta
        v = np.linalg.svd(M)[2][:, 0, :].conj()
        return _lower_bound(M, blocks, [(v, v)], iterations, rng, restarts, upper)
    IR = np.concatenate([np.arange(q)[b.inputs] for b in real])
    OR = np.concatenate([np.arange(p)[b.outputs] for b in real])
    IC = np.concatenate([np.arange(q)[b.inputs] for b in comp])
    OC = np.concatenate([np.arange(p)[b.outputs] for b in comp])
    sub, ni, no = [], 0, 0
    for b in comp:      # the complex blocks, re-based on M_c
        sub.append(_Block(b.kind, b.n_in, b.n_out, slice(ni, ni + b.n_in),
                          slice(no, no + b.n_out)))
        ni, no = ni + b.n_in, no + b.n_out
    owner = np.concatenate([np.full(b.k, j) for j, b in enumerate(real)])
    Mrr, Mrc = M[:, OR][:, :, IR], M[:, OR][:, :, IC]
    Mcr, Mcc = M[:, OC][:, :, IR], M[:, OC][:, :, IC]
    nr = len(real)
    scale = 1.0 / np.where(upper > 0, upper, 1.0)

    def evaluate(rows, delta):
        """Value and Delta for real values delta (len(rows), nr)."""
        n = len(rows)
        Dr = np.zeros((n, len(IR), len(OR)))
        Dr[:, np.arange(len(IR)), np.arange(len(OR))] = delta[:, owner]
        X = np.eye(len(OR)) - Mrr[rows] @ Dr
        det = np.abs(np.linalg.det(X))
        sing = det < 1e-12
        X[sing] = np.eye(len(OR))
        Mc = Mcc[rows] + Mcr[rows] @ Dr @ np.linalg.solve(X, Mrc[rows])
        v = np.linalg.svd(Mc)[2][:, 0, :].conj()
        low_c, Dc = _lower_bound(Mc, sub, [(v, v)], iterations, rng, 0, np.zeros(n))
        dmax = np.abs(delta).max(axis=1)
        with np.errstate(divide="ignore"):
            val = np.minimum(np.where(dmax > 0, 1 / np.where(dmax > 0, dmax, 1), np.inf),
                             np.where(low_c > 0, low_c, 0.0))
        val = np.where(sing, np.where(dmax > 0, 1 / np.where(dmax > 0, dmax, 1), 0), val)
        Delta = np.zeros((n, q, p), complex)
        Delta[:, IR[:, None], OR[None, :]] = Dr
        Delta[:, IC[:, None], OC[None, :]] = np.where(sing[:, None, None], 0, Dc)
        return np.where(np.isfinite(val), val, 0.0), Delta, low_c

    lower = np.zeros(nf)
    Delta = np.zeros((nf, q, p), complex)
    best_dir = np.zeros((nf, nr))

    def consider(dirs, beta):
        """Evaluate delta = dirs / beta for dirs (nc, nf, nr), beta (nc, nf)."""
        nc = len(dirs)
        rows = np.tile(np.arange(nf), nc)
        delta = (dirs / beta[:, :, None]).reshape(-1, nr)
        val, D, low_c = evaluate(rows, delta)
        val, low_c = val.reshape(nc, nf), low_c.reshape(nc, nf)
        k = np.argmax(val, axis=0)
        v = val[k, np.arange(nf)]
        better = v > lower
        lower[better] = v[better]
        Delta[better] = D[(k * nf + np.arange(nf))[better]]
        best_dir[better] = dirs[k[better], np.nonzero(better)[0]]
        return low_c

    # directions nu of the real part, delta_r = nu / beta with |nu_j| <= 1:
    # for each, iterate beta <- mu_c(M_c(nu / beta)) towards the balanced
    # point where the real and complex parts have the same norm 1 / beta
    if nr == 1:
        dirs = np.linspace(-1, 1, 21)[:, None]
    elif nr == 2:
        g1 = np.linspace(-1, 1, 5)
        dirs = np.stack(np.meshgrid(g1, g1), -1).reshape(-1, 2)
    else:   # vertices (up to 16) and seeded random directions
        vert = np.array(np.meshgrid(*[[-1.0, 1.0]] * min(nr, 4))).reshape(min(nr, 4), -1).T
        vert = np.concatenate([vert, np.ones((len(vert), nr - vert.shape[1]))], axis=1)
        dirs = np.concatenate([vert, rng.uniform(-1, 1, (16, nr))])
    dirs = np.repeat(dirs[:, None, :], nf, axis=1)
    beta = np.repeat(np.where(upper > 0, upper, 1.0)[None], len(dirs), axis=0)
    for _ in range(6):
        low_c = consider(dirs, beta)
        beta = np.clip(low_c, 1e-3 * upper, upper)
        beta = np.where(beta > 0, beta, 1.0)
    # coordinate refinement of the best direction, each trial direction
    # with its own short beta iteration
    step = 0.25
    for _ in range(8):
        trial = []
        for j in range(nr):
            for sign in (1, -1):
                c = best_dir.copy()
                c[:, j] = np.clip(c[:, j] + sign * step, -1, 1)
                trial.append(c)
        trial = np.array(trial)
        beta = np.repeat(np.where(lower > 0, lower, np.where(upper > 0, upper, 1.0))[None],
                         len(trial), axis=0)
        for _ in range(3):
            low_c = consider(trial, beta)
            beta = np.clip(low_c, 1e-3 * upper, upper)
            beta = np.where(beta > 0, beta, 1.0)
        step /= 2
    return lower, Delta


# ---------------------------------------------------------------------------
# public entry point
# ---------------------------------------------------------------------------

def mussv(M, blk, omega=None, *, lower=True, restarts=3, iterations=60, tol=1e-12, seed=0):
    """Upper and lower bounds of the structured singular value mu_Delta(M).

    Parameters
    ----------
    M : array_like or control.FrequencyResponseData
        Complex p x q matrix, or array of shape (nf, p, q) with the frequency
        axis first (e.g. a frequency response on nf frequencies), or an FRD
        (its frequencies become ``omega``).
    blk : sequence of (int, int)
        Block structure in MATLAB ``mussv`` convention (module docstring):
        (r, c) complex full r x c block, (k, 0) complex repeated scalar,
        (-k, 0) real repeated scalar; Delta is q x p, sum r_i = q,
        sum c_i = p.  The paper's M of eq. 18 uses ``[(1, 1), (1, 2)]``.
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
    if not isinstance(lower, bool):
        raise TypeError(f"lower must be True or False, got {lower!r}")
    rng = np.random.default_rng(seed)
    blk_tuple = tuple((int(r), int(c)) for r, c in np.asarray(blk).reshape(-1, 2))
    has_real = any(b.kind == "real" for b in blocks)

    if has_real:
        upper, d, g, dl, dr, G = _mixed_upper(arr, blocks)
        Dl = np.zeros((nf, p, p))
        Dr = np.zeros((nf, q, q))
        Dl[:, np.arange(p), np.arange(p)] = dl
        Dr[:, np.arange(q), np.arange(q)] = dr
    else:
        upper, theta, scaling = _complex_upper(arr, blocks, tol)
        Dl, Dr, _, _ = scaling.matrices(theta)
        g = G = None
        d = np.full((nf, len(blocks)), np.nan)
        xl, _ = scaling.diag_logs(theta)
        for i, b in enumerate(blocks):
            if b.scalar_scaling:
                d[:, i] = np.exp(xl[:, b.outputs.start])
        if scaling.diagonal:
            Dl, Dr = Dl.real, Dr.real
    if not lower:
        low, Delta = np.zeros(nf), np.zeros((nf, q, p), complex)
    elif has_real:
        low, Delta = _mixed_lower(arr, blocks, upper, iterations, rng, restarts)
    else:
        # start from the top singular vectors of the scaled and unscaled M:
        # with A = Dl M Dr^-1 = sigma u v^H + ..., b = Dr^-1 v and w = Dr^H v
        # satisfy the power iteration's alignment conditions when D is optimal
        v = np.linalg.svd(Dl @ arr @ np.linalg.inv(Dr))[2][:, 0, :].conj()
        v0 = np.linalg.svd(arr)[2][:, 0, :].conj()
        starts = [(np.linalg.solve(Dr, v[..., None])[..., 0],
                   np.einsum("nji,nj->ni", Dr.conj(), v)), (v0, v0)]
        low, Delta = _lower_bound(arr, blocks, starts, iterations, rng, restarts, upper)
    # both bounds are exact numbers for their D and Q; when they meet, the
    # lower one can exceed the upper one by rounding only (a larger excess
    # would be a bug, and is left visible)
    low = np.where(low <= upper * (1 + 1e-9), np.minimum(low, upper), low)
    return MuResult(upper=upper, lower=low, d=d, Dl=Dl, Dr=Dr, g=g, G=G, Delta=Delta,
                    omega=omega, blk=blk_tuple)
