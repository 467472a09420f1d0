"""Upper bound of mu for complex block structures by optimal D-scaling (eq. 22).

min over D of sigma_max(D_l M D_r^-1), batched over frequency, by Newton steps
on a smooth convex surrogate (the log-Schatten-t norm).  The method and its
accuracy are described in ``docs/robust.md``; :func:`piezolib.robust.mu.mussv`
is the user-facing entry point.
"""

import numpy as np

from piezolib.robust.blocks import block_slices
from piezolib.robust.mu._common import (STEP_FRACTIONS, absolute_hessian,
                                       central_difference_hessian, newton_direction, scaled_matrix)

__all__ = ["complex_upper_bound", "balancing_logs"]

# continuation of the smoothing exponent t of the log-Schatten-t surrogate: large steps
# while most matrices are still moving, x4 near the non-smooth optimum
_T_SCHEDULE = tuple(2.0 ** np.array([1, 4, 7, 10, 12, 14, 16, 18, 20, 22]))
_NEWTON_ITERATIONS = 40           # per smoothing level (most stop after 2-4)
_SHORT_FRACTIONS = 2.0 ** -np.array([10, 13, 16, 19])   # where all STEP_FRACTIONS fail
_WARM_STRIDE = 4                  # every 4th frequency of a grid starts cold
_WARM_LEVEL = 1024.0              # the others start at this smoothing level
_MAX_STEP = 4.0                   # [log units] per Newton step
_MAX_LOG_SCALE = 200.0            # |log d| bound relative to the balanced start
_MATRIX_SCALING_CHUNK = 100       # frequencies per batch where D has matrix blocks
_OSBORNE_SWEEPS = 60
_OSBORNE_REG = 2 * np.log(1e-30)  # log of the relative floor on block norms (ratios to 1e30)
# a repeated scalar's scale more skewed than this (condition number once its diagonal is
# normalised; at most about 9 on the benchmark's random cases) is optimised again from the
# balanced matrix: the triangular parametrisation travels slowly towards far, rotated optima
_SKEWED_SCALE = 30.0
_RECENTRE_ROUNDS = 3
# eigenvalue ratios mu with mu^(m-1) below this drop out of the diagonal Newton model
_NEGLIGIBLE_WEIGHT = 1e-16



def _units(blocks, elementwise):
    """Balancing units: (outputs, inputs) index arrays that share one scale.

    A full block (or 1 x 1 scalar) is one unit; with ``elementwise`` every
    element of a repeated scalar is its own unit (its D-scale may be any
    invertible matrix, so in particular any diagonal one).
    """
    out, n_in, n_out = [], 0, 0
    for b in blocks:
        if b.repeated and b.size > 1 and elementwise:
            for j in range(b.size):
                out.append((np.array([n_out + j]), np.array([n_in + j])))
        else:
            out.append((np.arange(n_out, n_out + b.cols), np.arange(n_in, n_in + b.rows)))
        n_in, n_out = n_in + b.rows, n_out + b.cols
    return out


def balancing_logs(M, blocks, elementwise=True):
    """Osborne balancing of the block norms of M: a start for the D-scaling.

    Minimises the Frobenius norm of D_l M D_r^-1 over scalings that are
    constant on each balancing unit (a full block; each element of a
    repeated scalar when ``elementwise``), by Osborne's sweeps on the matrix
    of squared block norms, in logarithms, batched over frequency.  Block
    norms below 1e-30 times the largest are floored there, so scaling ratios
    up to about 1e30 are reached and reducible matrices stay finite.

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
    blocks : tuple of Block
        Structure fitting M.
    elementwise : bool, optional
        Scale the elements of repeated scalars independently.

    Returns
    -------
    xl : ndarray, shape (nf, p)
        log of the scale of each output (row of M).
    xr : ndarray, shape (nf, q)
        log of the scale of each input (column of M).
    """
    nf, p, q = M.shape
    units = _units(blocks, elementwise)
    nu = len(units)
    Pout = np.zeros((p, nu))
    Pin = np.zeros((q, nu))
    for u, (o, i) in enumerate(units):
        Pout[o, u] = 1.0
        Pin[i, u] = 1.0
    if nu < 2:
        return np.zeros((nf, p)), np.zeros((nf, q))
    B2 = np.einsum("pu,npq,qv->nuv", Pout, np.abs(M) ** 2, Pin)
    B2[:, np.arange(nu), np.arange(nu)] = 0.0
    total = B2.sum(axis=(1, 2))
    with np.errstate(divide="ignore"):
        logB = np.log(B2)                              # -inf for zero blocks
        floor = np.where(total > 0, np.log(np.where(total > 0, total, 1)), 0.0) + _OSBORNE_REG
    x = np.zeros((nf, nu))
    for _ in range(_OSBORNE_SWEEPS):
        largest = np.zeros(nf)
        for u in range(nu):
            # log of row and column sums of the scaled squared norms (u's own entry excluded)
            row = np.logaddexp(_logsumexp(logB[:, u, :] - 2 * x, u), floor - 2 * x[:, u]) + 2 * x[:, u]
            col = np.logaddexp(_logsumexp(logB[:, :, u] + 2 * x, u), floor + 2 * x[:, u]) - 2 * x[:, u]
            step = (col - row) / 4
            x[:, u] += step
            largest = np.maximum(largest, np.abs(step))
        if largest.max() < 1e-4:
            break
    x -= x[:, -1:]
    xl, xr = np.zeros((nf, p)), np.zeros((nf, q))
    for u, (o, i) in enumerate(units):
        xl[:, o] = x[:, u:u + 1]
        xr[:, i] = x[:, u:u + 1]
    return xl, xr


def _logsumexp(a, skip):
    """log sum exp over the last axis, leaving out entry ``skip``."""
    a = np.delete(a, skip, axis=-1)
    m = np.max(a, axis=-1)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        return m + np.log(np.sum(np.exp(a - m[:, None]), axis=-1))


class _Scaling:
    """Parametrisation theta -> (D_l, D_r) of the complex D-scalings.

    Scalar-scaled blocks get one log-scale each (the reference block's is
    fixed at 0); repeated complex scalars with k > 1 get a lower-triangular
    L_i = exp(diag(y)) + strictly-lower complex part.
    """

    def __init__(self, blocks, p, q):
        self.blocks, self.p, self.q = blocks, p, q
        self.slots = block_slices(blocks)     # (inputs, outputs) slice of each block
        scalar = [i for i, b in enumerate(blocks) if b.scalar_scaling]
        full = [i for i in scalar if blocks[i].is_full]
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
                rows, cols = np.tril_indices(b.size, -1)
                size = b.size + 2 * rows.size
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
            inputs, outputs = self.slots[i]
            self.out_map[outputs] = j + 1       # 0 is the fixed zero column
            self.in_map[inputs] = j + 1
        # (n, p) and (n, q): 1 where an output / input belongs to scalar-scaled parameter j
        parameters = np.arange(1, n + 1)[:, None]
        self.out_indicator = (self.out_map == parameters).astype(float)
        self.in_indicator = (self.in_map == parameters).astype(float)

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
        """D_l (N, p, p) and D_r (N, q, q)."""
        N = theta.shape[0]
        xl, xr = self.diag_logs(theta)
        Dl = np.zeros((N, self.p, self.p), complex)
        Dr = np.zeros((N, self.q, self.q), complex)
        Dl[:, np.arange(self.p), np.arange(self.p)] = np.exp(xl)
        Dr[:, np.arange(self.q), np.arange(self.q)] = np.exp(xr)
        for (bi, bo), L, _ in self._triangles(theta):
            Dl[:, bo, bo] = L
            Dr[:, bi, bi] = L
        return Dl, Dr

    def _triangles(self, theta):
        """((inputs, outputs) slices, L_i, L_i^-1) of every repeated scalar's triangular scale."""
        out = []
        for i, sl, rows, cols in self.tri:
            L = self._triangle(theta[:, sl], self.blocks[i].size, rows, cols)
            out.append((self.slots[i], L, np.linalg.inv(L)))
        return out

    @staticmethod
    def _triangle(par, k, rows, cols):
        L = np.zeros((par.shape[0], k, k), complex)
        idx = np.arange(k)
        L[:, idx, idx] = np.exp(par[:, :k])
        m = rows.size
        L[:, rows, cols] = par[:, k:k + m] + 1j * par[:, k + m:k + 2 * m]
        return L

    def scaled(self, M, theta):
        """Dl M Dr^-1 (N, p, q), and each repeated scalar's L_i^-1 (None if there are none)."""
        xl, xr = self.diag_logs(theta)
        A = np.exp(xl)[:, :, None] * M * np.exp(-xr)[:, None, :]
        if self.diagonal:
            return A, None
        # block by block: D is diagonal apart from the repeated scalars' k x k L_i
        inverses = []
        for (bi, bo), L, Li in self._triangles(theta):
            A[:, bo, :] = L @ A[:, bo, :]
            A[:, :, bi] = A[:, :, bi] @ Li
            inverses.append(Li)
        return A, inverses

    def gradient(self, theta, U, V, w, inverses):
        """Gradient of sum_k w_k log sigma_k with respect to theta (``inverses`` from :meth:`scaled`)."""
        N = theta.shape[0]
        grad = np.zeros((N, self.n))
        # diagonal of W_U = U diag(w) U^H and W_V
        wu = np.einsum("npk,nk->np", np.abs(U) ** 2, w)
        wv = np.einsum("nqk,nk->nq", np.abs(V) ** 2, w)
        for i, j in self.scalar_index.items():
            if j >= 0:
                bi, bo = self.slots[i]
                grad[:, j] = wu[:, bo].sum(1) - wv[:, bi].sum(1)
        if self.tri:
            Uw, Vw = U * w[:, None, :], V * w[:, None, :]
            for (i, sl, rows, cols), Li in zip(self.tri, inverses):
                bi, bo = self.slots[i]
                # block (bo, bo) of L^-1 U diag(w) U^H, minus block (bi, bi) of the V analogue
                diff = Li @ (Uw[:, bo] @ np.swapaxes(U[:, bo], 1, 2).conj()
                             - Vw[:, bi] @ np.swapaxes(V[:, bi], 1, 2).conj())
                k, m = self.blocks[i].size, rows.size
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
    A, inverses = scaling.scaled(M, theta)
    if not need_grad:
        s = _svd(A, compute_uv=False)
        return _log_schatten(s, t)[0], None, s[:, 0]
    U, s, V = _svd(A)
    F, w = _log_schatten(s, t)
    grad = scaling.gradient(theta, U, V, w, inverses)
    return F, grad, s[:, 0]


def _svd(A, compute_uv=True):
    """Thin SVD of a stack of matrices: U (N, p, k), s (N, k), V (N, q, k).

    Closed form when min(p, q) <= 2 (the paper's M is 3 x 2), where LAPACK's
    per-matrix overhead dominates; otherwise from the eigen-decomposition of
    the smaller Gram matrix (cheaper than LAPACK's SVD), U = A V / sigma.
    Through the Gram matrix sigma_max has full relative accuracy and a small
    sigma_k absolute accuracy ~ sqrt(eps) sigma_max, which is all the
    surrogate needs (its weight (sigma_k / sigma_max)^t on small sigma_k
    vanishes); a zero sigma_k gets a zero column of U.
    """
    N, p, q = A.shape
    if min(p, q) > 2:
        if not compute_uv:
            G = A @ np.swapaxes(A, 1, 2).conj() if p <= q else np.swapaxes(A, 1, 2).conj() @ A
            return np.sqrt(np.maximum(np.linalg.eigvalsh(G)[:, ::-1], 0.0))
        if p < q:
            V, s, U = _svd(np.swapaxes(A, 1, 2).conj())
            return U, s, V
        lam, V = np.linalg.eigh(np.swapaxes(A, 1, 2).conj() @ A)
        s = np.sqrt(np.maximum(lam[:, ::-1], 0.0))
        V = V[:, :, ::-1]
        U = (A @ V) / np.where(s > 0, s, 1)[:, None, :]
        return U, s, V
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


def _power_divided_differences(mu, m, rows):
    """(mu_k^m - mu_l^m) / (mu_k - mu_l) for mu in [0, 1], m * mu^(m-1) where they are equal.

    For the first ``rows`` k and every l: shape (N, rows, len(mu)).  Written as
    hi^(m-1) (1 - rho^m) / (1 - rho), rho = lo / hi, with expm1 and log1p so
    that nearly equal eigenvalues do not cancel.
    """
    a, b = mu[:, :rows, None], mu[:, None, :]
    hi, lo = np.maximum(a, b), np.minimum(a, b)
    if m == 0:
        return np.zeros(hi.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(hi > 0, (hi - lo) / np.where(hi > 0, hi, 1.0), 0.0)
        ratio = np.where(delta > 0, -np.expm1(m * np.log1p(-delta)) / np.where(delta > 0, delta, 1),
                         m)
        dd = np.where(hi > 0, hi ** (m - 1) * ratio, 1.0 if m == 1 else 0.0)
    return dd


def _leading_count(mu, m):
    """How many of the descending eigenvalue ratios mu the Newton model keeps.

    Every term of the surrogate's gradient and Hessian carries a weight mu_k^m
    or a divided difference below m max(mu_k, mu_l)^(m-1); past the first
    eigenvalues with m mu^(m-1) > 1e-16 m they are negligible (at large t
    only the one to three eigenvalues near the top remain).
    """
    if m < 1:
        return mu.shape[1]
    keep = mu ** (m - 1) > _NEGLIGIBLE_WEIGHT
    return max(1, int(keep.sum(1).max()))


def _block_rows(X, indicator, r):
    """Rows 1 ... r of X_j^H X_j over the rows of X (N, p, k) in block j: (N, n, r, k).

    ``indicator`` (n, p) is 1 where row a of X belongs to block j.
    """
    N, p, k = X.shape
    T = X[:, :, :r].conj()[:, :, :, None] * X[:, :, None, :]
    T = np.ascontiguousarray(T).view(float).reshape(N, p, -1)
    return (indicator @ T).view(complex).reshape(N, len(indicator), r, k)


def _real_pairing(X, Y):
    """Re sum_kl X_i,kl conj(Y_j,kl) for stacks X, Y of shape (N, n, r, k): (N, n, n).

    As a real matrix product over the interleaved real and imaginary parts
    (Re(x conj y) = Re x Re y + Im x Im y), with no conjugated copies.
    """
    N, n = X.shape[:2]
    Xf = np.ascontiguousarray(X).view(float).reshape(N, n, -1)
    Yf = np.ascontiguousarray(Y).view(float).reshape(N, n, -1)
    return Xf @ np.swapaxes(Yf, 1, 2)


def _diagonal_newton_model(M, theta, scaling, t):
    """Surrogate F_t, its gradient and exact Hessian for diagonal scalings.

    With G = A^H A (A the scaled matrix) and Phi = sum_k (lambda_k /
    lambda_1)^(t/2) over G's eigenvalues, F_t = log sigma_1 + log(Phi) / t.
    dG/dtheta_j = 2 A^H E_j A - F_j G - G F_j (E_j, F_j: the block's output and
    input indicators); the Hessian of the spectral function Phi follows from
    first-order eigenvalue perturbation plus the divided differences of its
    derivative (the Daleckii-Krein formula).  One eigen-decomposition per
    matrix instead of 2n + 1 gradients for a Hessian by differences.  In G's
    eigenbasis only the rows of the leading eigenvalues carry weight
    (:func:`_leading_count`); the pairings run over those rows alone, with the
    mirrored entries (k leading, l not) counted twice.

    Returns F (N,), gradient (N, n), Hessian (N, n, n), sigma_max (N,).
    """
    N, p, q = M.shape
    n = scaling.n
    A, _ = scaling.scaled(M, theta)
    # eigenvectors of G = A^H A (cheaper than an SVD; small eigenvalues lose
    # relative accuracy, but their weights (lambda / lambda_1)^(t/2) vanish)
    lam, V = np.linalg.eigh(np.swapaxes(A, 1, 2).conj() @ A)
    lam, V = np.maximum(lam[:, ::-1], 0.0), V[:, :, ::-1]
    lam1 = np.maximum(lam[:, :1], np.finfo(float).tiny)
    mu = lam / lam1
    m = t / 2 - 1
    r = _leading_count(mu, m)
    W = (A @ V) / np.sqrt(lam1)[:, :, None]
    # rows 1 ... r of P_j = W_j^H W_j and Q_j = V_j^H V_j over block j's rows
    P = _block_rows(W, scaling.out_indicator, r)
    Q = _block_rows(V, scaling.in_indicator, r)
    dG = 2 * P - Q * mu[:, None, None, :] - mu[:, None, :r, None] * Q
    pw = mu[:, :r] ** m                            # f'(lambda) = (t/2) mu^m / lambda_1
    phi = np.sum(mu ** (t / 2), axis=1)
    g_phi = (t / 2) * np.einsum("nk,njkk->nj", pw, dG[..., :r]).real
    B = _real_pairing(Q * pw[:, None, :, None], P)
    C = _real_pairing(Q * (pw[:, :, None] * (mu[:, :r, None] + mu[:, None, :]))[:, None], Q)
    weights = _power_divided_differences(mu, m, r)
    weights[:, :, r:] *= 2
    D = _real_pairing(dG * weights[:, None], dG)
    Pdiag = np.einsum("nk,njkk->nj", pw, P[..., :r]).real
    H_phi = (t / 2) * (4 * (np.eye(n) * Pdiag[:, :, None]) - 4 * (B + np.swapaxes(B, 1, 2))
                       + 2 * C + D)
    grad = g_phi / (t * phi[:, None])
    hess = (H_phi / phi[:, None, None] - g_phi[:, :, None] * g_phi[:, None, :]
            / phi[:, None, None] ** 2) / t
    s = np.sqrt(lam[:, :min(p, q)])
    return _log_schatten(s, t)[0], grad, hess, s[:, 0]


def _hessian_by_differences(M, theta, scaling, t, free):
    """Surrogate, gradient and a Hessian from central differences of the gradient.

    (Forward differences, half the cost, left repeated-scalar structures whose
    bound is exact up to 1e-6 above mu.)
    """
    cols = np.nonzero(free)[0]
    copies = 2 * cols.size + 1
    return central_difference_hessian(
        lambda pts: _surrogate(np.tile(M, (copies, 1, 1)), pts, scaling, t)[:2],
        theta, 1e-4 / np.sqrt(t), cols)


def _line_search(M, theta, step, scaling, t, F0):
    """Full Newton step, then shorter fractions only where the longer ones did not decrease F.

    Where none of ``STEP_FRACTIONS`` decreases F either, fractions down to
    2^-19 are tried: close to a kink of sigma_max (two singular values a
    relative 1e-4 apart) the surrogate at large t hardly sees the second one,
    and even 1/256 of its Newton step can overshoot the kink (seen to leave
    8 scalars' bounds 8e-6 above the D-scaled optimum).

    Returns, per matrix, the lowest surrogate value found, the lowest sigma_max
    and the parameters of each.
    """
    cand = np.clip(theta + step, -_MAX_LOG_SCALE, _MAX_LOG_SCALE)
    F, _, s = _surrogate(M, cand, scaling, t, need_grad=False)
    cand_F, cand_s = cand.copy(), cand.copy()
    # halving first: where the full step fails, 1/2 or 1/4 of it mostly succeeds
    for fractions in (STEP_FRACTIONS[1:2], STEP_FRACTIONS[2:3], STEP_FRACTIONS[3:],
                      _SHORT_FRACTIONS):
        retry = np.nonzero(~(F < F0))[0]
        if retry.size:
            _shorter_steps(M, theta, step, scaling, t, fractions, retry, (F, s, cand_F, cand_s))
    return F, s, cand_s, cand_F


def _shorter_steps(M, theta, step, scaling, t, fractions, retry, found):
    """Try ``fractions`` of the step on the rows ``retry``; keep, in place, what beats ``found``.

    ``found`` = (F, sigma_max, parameters of F, parameters of sigma_max).
    """
    F, s, cand_F, cand_s = found
    n = theta.shape[1]
    short = theta[retry][None] + fractions[:, None, None] * step[retry][None]
    short = np.clip(short, -_MAX_LOG_SCALE, _MAX_LOG_SCALE)
    Fs, _, ss = _surrogate(np.tile(M[retry], (len(fractions), 1, 1)), short.reshape(-1, n),
                           scaling, t, need_grad=False)
    Fs, ss = Fs.reshape(len(fractions), -1), ss.reshape(len(fractions), -1)
    cols = np.arange(retry.size)
    kf, ks = np.argmin(Fs, axis=0), np.argmin(ss, axis=0)
    use_f = Fs[kf, cols] < F[retry]
    use_s = ss[ks, cols] < s[retry]
    cand_F[retry[use_f]] = short[kf[use_f], cols[use_f]]
    cand_s[retry[use_s]] = short[ks[use_s], cols[use_s]]
    F[retry[use_f]] = Fs[kf[use_f], cols[use_f]]
    s[retry[use_s]] = ss[ks[use_s], cols[use_s]]


def _complex_upper(M, blocks, tol, theta0=None, schedule=_T_SCHEDULE):
    """D-scaled upper bound for complex structures; returns (upper, theta, scaling).

    The Newton steps start from ``theta0`` (default 0: the balanced M) and
    run the smoothing levels ``schedule``.
    """
    nf, p, q = M.shape
    scaling = _Scaling(blocks, p, q)
    n = scaling.n
    theta = np.zeros((nf, n)) if theta0 is None else theta0.copy()
    best = np.linalg.svd(M, compute_uv=False)[:, 0]
    best_theta = np.zeros((nf, n))
    if n == 0 or (scaling.fixed is not None and n == 1):
        return best, best_theta, scaling
    free = scaling.free()
    active_all = best > 0            # mu = 0 where M = 0: nothing to optimise
    state = (theta, best, best_theta)
    # repeated scalars: Hessians carried from level to level (NaN: none yet)
    hessians = None if scaling.diagonal else np.full((nf, n, n), np.nan)
    for t in schedule:
        # a level before the last only sets the start of the next one: with
        # scalar scalings (a convex surrogate) its minimiser is needed to a fraction
        # of the smoothing's own offset ~ 1/t; repeated scalars' non-convex
        # parametrisation wants each level converged, but may stop there on an
        # updated Hessian (the last level stops on a recomputed one)
        last = t == schedule[-1]
        level_tol = max(tol, 1e-2 / t) if scaling.diagonal and not last else tol
        _newton_level(M, np.nonzero(active_all)[0], state, scaling, t, free, level_tol,
                      hessians, strict=last)
        settled = active_all & _settled(M, theta, scaling, t)
        if not last and np.any(settled):
            # leaving the continuation here: this level's minimiser is the answer
            _newton_level(M, np.nonzero(settled)[0], state, scaling, t, free, tol, hessians,
                          strict=True)
        active_all &= ~settled
    return best, best_theta, scaling


def _newton_level(M, active, state, scaling, t, free, tol, hessians=None, strict=True):
    """Newton steps on the level-t surrogate for the matrices ``active``.

    Updates ``state`` = (theta, best, best_theta) in place: the current
    parameters, and the smallest sigma_max seen (that is the bound) with its
    parameters.  A matrix stops when a step no longer lowers the surrogate
    by ``tol`` (or its Newton decrement is below it).

    Diagonal scalings have an exact Hessian at the cost of one eigen-
    decomposition.  Repeated scalars' Hessian takes 2 n + 1 gradients by
    differences: it is recomputed only after a step that failed (and, with
    ``strict``, before a matrix stops), and otherwise updated by BFGS from one
    gradient per step.  ``hessians`` (nf, n, n) carries those Hessians from
    level to level (NaN: none yet), and is updated in place.
    """
    theta, best, best_theta = state
    model = None                     # (F, g, H) at theta of the active rows
    if not scaling.diagonal and active.size:
        F, g, _ = _surrogate(M[active], theta[active], scaling, t)
        model = (F, g, hessians[active])
    for _ in range(_NEWTON_ITERATIONS):
        if active.size == 0:
            break
        Ma, th = M[active], theta[active]
        if scaling.diagonal:
            F0, g0, H, _ = _diagonal_newton_model(Ma, th, scaling, t)
            fresh = np.ones(active.size, bool)
        else:
            F0, g0, H, fresh = _refreshed_model(Ma, th, scaling, t, free, model)
        # updated Hessians are positive definite already (BFGS on a positive one)
        H = absolute_hessian(H, free, fresh)
        step, dec = newton_direction(H, g0, free, _MAX_STEP, positive=True)
        Fnew, sbest, cand_best, cand_new = _line_search(Ma, th, step, scaling, t, F0)
        improved = Fnew < F0
        theta[active[improved]] = cand_new[improved]
        better = sbest < best[active]
        best[active[better]] = sbest[better]
        best_theta[active[better]] = cand_best[better]
        converged = (dec < tol) | (F0 - Fnew < tol)
        done = (~improved | converged) & (fresh | (improved & converged & (not strict)))
        # a failed step on an updated Hessian (or, if strict, a converged one) recomputes it
        retry = ~fresh & ~done & (~improved | converged)
        if not scaling.diagonal:
            hessians[active[done]] = H[done]
            model = _updated_model(Ma, theta[active], scaling, t, (F0, g0, H), th,
                                   improved, retry, done)
            model = tuple(x[~done] for x in model)
        active = active[~done]
    if model is not None and active.size:
        hessians[active] = model[2]


def _refreshed_model(M, theta, scaling, t, free, model):
    """Surrogate, gradient and Hessian, recomputed by differences where ``model`` has none.

    ``model`` (F, g, H) carries rows whose H is NaN where a recomputation is
    due; returns F, g, H and which rows were recomputed.
    """
    if model is None:
        F, g, H = _hessian_by_differences(M, theta, scaling, t, free)
        return F, g, H, np.ones(len(M), bool)
    F, g, H = (x.copy() for x in model)
    fresh = np.isnan(H[:, 0, 0])
    if np.any(fresh):
        F[fresh], g[fresh], H[fresh] = _hessian_by_differences(M[fresh], theta[fresh], scaling,
                                                               t, free)
    return F, g, H, fresh


def _updated_model(M, theta, scaling, t, model, theta0, improved, retry, done):
    """The next step's model: BFGS-updated where a step was taken, NaN-marked to recompute.

    ``model`` = (F, g, H) at ``theta0``, H the positive definite Hessian the
    step was taken with (:func:`absolute_hessian`); the update keeps it
    positive definite, and is skipped where y^T s <= 0.
    """
    F0, g0, H = model
    N, n = g0.shape
    F, g = F0.copy(), g0.copy()
    Hn = np.full((N, n, n), np.nan)
    moved = improved & ~done & ~retry
    if np.any(moved):
        F[moved], g[moved], _ = _surrogate(M[moved], theta[moved], scaling, t)
        s = theta[moved] - theta0[moved]
        y = g[moved] - g0[moved]
        Hm = H[moved]
        Hs = np.einsum("nij,nj->ni", Hm, s)
        sHs = np.einsum("ni,ni->n", s, Hs)
        ys = np.einsum("ni,ni->n", y, s)
        ok = (ys > 1e-12 * np.linalg.norm(y, axis=1) * np.linalg.norm(s, axis=1)) & (sHs > 0)
        upd = (Hm - np.einsum("ni,nj->nij", Hs, Hs) / np.where(ok, sHs, 1)[:, None, None]
               + np.einsum("ni,nj->nij", y, y) / np.where(ok, ys, 1)[:, None, None])
        Hn[moved] = np.where(ok[:, None, None], upd, Hm)
    # improved and retried rows have a new theta: their F, g come with the recomputation
    return F, g, Hn


def _settled(M, theta, scaling, t):
    """Matrices whose surrogate at level ``t`` already equals log sigma_max.

    Where sum_k>1 (sigma_k / sigma_1)^t is below 1e-15 at the point a level
    converged to, that level minimised log sigma_max itself, and larger t
    cannot move the point: no further levels for those matrices.
    """
    s = _svd(scaling.scaled(M, theta)[0], compute_uv=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        rest = np.sum((s[:, 1:] / s[:, :1]) ** t, axis=1)
    return rest < 1e-15


def _warm_started_upper(M0, blocks, tol, xl0):
    """:func:`_complex_upper` on a frequency grid of balanced matrices M0, warm-started.

    Every ``_WARM_STRIDE``-th matrix runs all smoothing levels; the others
    start from the nearest of those's scalings (carried through the two
    balancings: only ratios of block scales matter) and run the levels from
    t = ``_WARM_LEVEL`` on, where that start is no worse than the balancing
    itself.  Only the path changes: the D-scaled bound has no local minima
    that are not global (its level sets are convex in D^H D).  Measured: 8
    scalar blocks 30-45 % less time, structures with repeated scalars about
    20 %, bounds within 5e-8 of the cold start's.
    """
    nf = M0.shape[0]
    cold = np.zeros(nf, bool)
    cold[::_WARM_STRIDE] = True
    cold[-1] = True
    rows = np.nonzero(cold)[0]
    up_c, th_c, scaling = _upper_in_chunks(M0[rows], blocks, tol)
    upper, theta = np.zeros(nf), np.zeros((nf, scaling.n))
    upper[rows], theta[rows] = up_c, th_c
    warm = np.nonzero(~cold)[0]
    nearest = rows[np.argmin(np.abs(warm[:, None] - rows[None, :]), axis=1)]
    theta0 = _carried_scalings(scaling, theta[nearest], xl0[nearest], xl0[warm])
    plain = _svd(M0[warm], compute_uv=False)[:, 0]
    started = _svd(scaling.scaled(M0[warm], theta0)[0], compute_uv=False)[:, 0]
    good = started <= plain
    schedule = tuple(t for t in _T_SCHEDULE if t >= _WARM_LEVEL)
    for use, th0, sched in ((good, theta0[good], schedule), (~good, None, _T_SCHEDULE)):
        if np.any(use):
            up_w, th_w, _ = _upper_in_chunks(M0[warm[use]], blocks, tol, th0, sched)
            upper[warm[use]], theta[warm[use]] = up_w, th_w
    return upper, theta, scaling


def _carried_scalings(scaling, theta, xl_from, xl_to):
    """Scaling parameters that give matrices balanced by ``xl_to`` the D of ``theta``.

    ``theta`` (N, n) parametrises D relative to the balancing ``xl_from`` (N, p).
    D matters only up to a positive factor c, which keeps the reference
    block's scale (or the fixed first diagonal of the last L_i) where it is:
    a scalar block's log-scale moves by its change of balancing relative to
    the reference's, and a repeated scalar's L_i becomes c L_i E_i, with E_i
    the ratio of the two balancings on its elements (still lower triangular).
    """
    first_row = {i: outputs.start for i, (_, outputs) in enumerate(scaling.slots)}
    dx = xl_from - xl_to
    if scaling.reference is not None:
        log_c = -dx[:, first_row[scaling.reference]]
    else:
        log_c = -dx[:, first_row[scaling.tri[-1][0]]]
    out = np.zeros_like(theta)
    for i, j in scaling.scalar_index.items():
        if j >= 0:
            out[:, j] = theta[:, j] + dx[:, first_row[i]] + log_c
    for i, sl, rows, cols in scaling.tri:
        k = scaling.blocks[i].size
        d = dx[:, first_row[i]:first_row[i] + k] + log_c[:, None]
        par = theta[:, sl]
        out[:, sl.start:sl.start + k] = par[:, :k] + d
        factor = np.exp(d[:, cols])                   # L_ab (a > b) scales with column b
        out[:, sl.start + k:sl.stop] = par[:, k:] * np.tile(factor, 2)
    return out


def _upper_in_chunks(M0, blocks, tol, theta0=None, schedule=_T_SCHEDULE):
    """:func:`_complex_upper` over chunks of frequencies where D has matrix blocks.

    The chunks' working arrays stay in cache: about 20 % faster on 1000
    frequencies than one batch.
    """
    nf = M0.shape[0]
    chunk = nf if all(b.scalar_scaling for b in blocks) else _MATRIX_SCALING_CHUNK
    parts = [_complex_upper(M0[k:k + chunk], blocks, tol,
                            None if theta0 is None else theta0[k:k + chunk], schedule)
             for k in range(0, nf, chunk)]
    upper, theta = (np.concatenate(x) for x in list(zip(*parts))[:2])
    return upper, theta, parts[0][2]


def _skewed(Dl, scaling):
    """Frequencies where a repeated scalar's block of Dl is far from diagonal (see
    ``_SKEWED_SCALE``)."""
    out = np.zeros(Dl.shape[0], bool)
    for i, *_ in scaling.tri:
        bo = scaling.slots[i][1]
        B = Dl[:, bo, bo]
        d = np.sqrt(np.abs(np.diagonal(B, axis1=1, axis2=2)))
        out |= np.linalg.cond(B / d[:, :, None] / d[:, None, :]) > _SKEWED_SCALE
    return out


def _optimised_scaling(M, blocks, tol):
    """(upper, Dl, Dr, scaling) from the Osborne start and the Newton steps, D not normalised."""
    xl0, xr0 = balancing_logs(M, blocks)
    M0 = np.exp(xl0)[:, :, None] * M * np.exp(-xr0)[:, None, :]
    if M.shape[0] >= 4 * _WARM_STRIDE:
        upper, theta, scaling = _warm_started_upper(M0, blocks, tol, xl0)
    else:
        upper, theta, scaling = _upper_in_chunks(M0, blocks, tol)
    Dl, Dr = scaling.matrices(theta)
    Dl = Dl * np.exp(xl0)[:, None, :]            # D = D_theta @ diag(exp(x0))
    Dr = Dr * np.exp(xr0)[:, None, :]
    return upper, Dl, Dr, scaling


def _recentred(M, blocks, tol, upper, Dl, Dr, scaling):
    """Optimise the D-scaling again from Dl M Dr^-1 where a repeated scalar's scale is skewed.

    The new scaling composes with the old one (D = D_new D_old) where it lowers the bound;
    the rounds stop once no new scale is skewed.  On a matrix under a random similarity
    in the structure's commutant (condition number 5e5) one round brought the bound from
    79.4 back to its value 4.87 on the original matrix.
    """
    sel = np.nonzero(_skewed(Dl, scaling))[0]
    for _ in range(_RECENTRE_ROUNDS):
        if not sel.size:
            break
        _, step_l, step_r, _ = _optimised_scaling(scaled_matrix(M[sel], Dl[sel], Dr[sel]),
                                                  blocks, tol)
        Dl1, Dr1 = step_l @ Dl[sel], step_r @ Dr[sel]
        # the bound of the composed scaling itself, so that upper = sigma_max(Dl M Dr^-1)
        up1 = _svd(scaled_matrix(M[sel], Dl1, Dr1), compute_uv=False)[:, 0]
        better = up1 < upper[sel]
        sel = sel[better]
        upper[sel], Dl[sel], Dr[sel] = up1[better], Dl1[better], Dr1[better]
        sel = sel[_skewed(step_l[better], scaling)]
    return upper, Dl, Dr


def complex_upper_bound(M, blocks, tol=1e-12):
    """D-scaled upper bound of mu for a structure without real blocks.

    The D-scaling starts from Osborne balancing (:func:`balancing_logs`,
    which reaches scaling ratios far beyond what the Newton steps could
    travel) and is refined by Newton steps on the smooth surrogate; where a
    repeated scalar's scale ends far from diagonal, again from the balanced
    matrix (:func:`_recentred`).

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
        Complex matrices, frequency axis first.
    blocks : tuple of Block
        Complex blocks (full or repeated scalar) fitting M
        (:func:`piezolib.robust.blocks.parse_blk`).
    tol : float, optional
        Newton steps stop when they lower the surrogate's logarithm by less.

    Returns
    -------
    upper : ndarray, shape (nf,)
        sigma_max(Dl M Dr^-1) at the best scaling found.
    d : ndarray, shape (nf, nblk)
        Scalar D-scale of each scalar-scaled block (NaN otherwise); the last
        full block (else the last scalar-scaled block) has d = 1.
    Dl, Dr : ndarray, shapes (nf, p, p) and (nf, q, q)
        The scalings (real when every block has a scalar scaling).
    """
    nf, p, q = M.shape
    upper, Dl, Dr, scaling = _optimised_scaling(M, blocks, tol)
    if not scaling.diagonal:
        upper, Dl, Dr = _recentred(M, blocks, tol, upper, Dl, Dr, scaling)
    # the unscaled matrix (D = I) is a candidate too
    plain = np.linalg.svd(M, compute_uv=False)[:, 0]
    use_plain = plain < upper
    upper = np.where(use_plain, plain, upper)
    Dl[use_plain] = np.eye(p)
    Dr[use_plain] = np.eye(q)
    d = np.full((nf, len(blocks)), np.nan)
    ref = scaling.reference
    if ref is not None:
        diag_l = np.abs(np.diagonal(Dl, axis1=1, axis2=2))
        ref_scale = diag_l[:, scaling.slots[ref][1].start]
        Dl, Dr = Dl / ref_scale[:, None, None], Dr / ref_scale[:, None, None]
        for i, b in enumerate(blocks):
            if b.scalar_scaling:
                d[:, i] = diag_l[:, scaling.slots[i][1].start] / ref_scale
    if scaling.diagonal:
        Dl, Dr = Dl.real, Dr.real
    return upper, d, Dl, Dr
