"""Upper bound of mu for mixed real/complex structures through SLICOT AB13MD.

Method notes (padding of non-square blocks, relaxation of repeated scalars)
in ``docs/robust.md``; :func:`piezolib.robust.mu.mussv` is the user-facing
entry point.
"""

import numpy as np

from piezolib.robust.blocks import Block, block_slices
from piezolib.robust.mu._common import (STEP_FRACTIONS, central_difference_hessian,
                                       certified_lmi_top, newton_direction)
from piezolib.robust.mu.upper_complex import balancing_logs, complex_upper_bound

__all__ = ["mixed_upper_bound"]

# continuation of the smoothing exponent of the D,G refinement (on eigenvalues / beta^2)
_DG_T_SCHEDULE = tuple(4.0 ** np.array([2, 4, 6, 8, 10, 11]))
_DG_NEWTON_ITERATIONS = 20
_DG_MAX_STEP = 2.0


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
        if b.is_full:
            m = max(b.rows, b.cols)
            rows.extend(n + np.arange(b.cols))
            cols.extend(n + np.arange(b.rows))
            nblock.append(m)
            itype.append(2)
            n += m
        else:
            for j in range(b.size):
                rows.append(n)
                cols.append(n)
                nblock.append(1)
                itype.append(1 if b.is_real else 2)
                n += 1
    Mp = np.zeros((nf, n, n), complex)
    rows, cols = np.asarray(rows), np.asarray(cols)
    Mp[:, rows[:, None], cols[None, :]] = M
    return Mp, np.array(nblock), np.array(itype), rows, cols


def mixed_upper_bound(M, blocks, newton=True):
    """D,G upper bound of mu (Fan, Tits and Doyle) by SLICOT AB13MD, one frequency at a time.

    Non-square full blocks are padded to square ones (this changes neither mu
    nor the bound); repeated scalars are relaxed to independent 1 x 1 ones
    (a valid, possibly conservative bound).  Every frequency starts cold,
    from an Osborne-balanced matrix (scaling ratios up to about 1e30); where
    the complex D-scaled bound (real blocks taken as complex, G = 0) is
    lower, or AB13MD fails, that bound and its scalings are returned.

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
    blocks : tuple of Block
        Structure fitting M (real and complex blocks).
    newton : bool, optional
        Refine the better of AB13MD's and the complex bound by Newton steps on
        (D, G) (default); without them the bound costs about half as much.

    Returns
    -------
    upper : ndarray, shape (nf,)
    d, g : ndarray, shape (nf, nblk)
        D-scale of each scalar-scaled block and G-scale of each 1 x 1 real
        block (NaN elsewhere), normalised so that the last complex full block
        has d = 1 (the LMI is homogeneous in (D^2, G)).
    Dl, Dr : ndarray, shapes (nf, p, p) and (nf, q, q)
        Diagonal scalings.
    G : ndarray, shape (nf, q, p)
        G-scalings: ``M^H Dl^2 M + 1j (G M - M^H G^T) - upper^2 Dr^2 <= 0``.
    """
    from slycot import ab13md

    nf, p, q = M.shape
    Mp, nblock, itype, rows, cols = _pad_square(M, blocks)
    n = Mp.shape[1]
    # Osborne pre-balancing on the padded structure (one unit per padded
    # block): AB13MD then starts from a well-scaled matrix, and the scalings
    # map back as D = D_ab D0, G = G_ab D0^2 (all diagonal)
    padded = tuple(Block.full(int(m), int(m)) if t == 2 else Block.scalar(1, real=True)
                   for m, t in zip(nblock, itype))
    x0 = balancing_logs(Mp, padded)[0]
    Mb = np.exp(x0)[:, :, None] * Mp * np.exp(-x0)[:, None, :]
    upper = np.zeros(nf)
    dpad = np.ones((nf, n))
    gpad = np.zeros((nf, n))
    for k in range(nf):
        if not np.any(Mb[k]):
            continue
        # always a cold start: warm starts (x from the previous frequency)
        # were seen to make AB13MD iterate without end
        try:
            upper[k], dpad[k], gpad[k], _ = ab13md(Mb[k], nblock, itype)
        except Exception:            # AB13MD's own failure: the complex bound below stands
            upper[k] = np.inf
    dpad, gpad = dpad * np.exp(x0), gpad * np.exp(2 * x0)
    # a complex D-scaled bound also bounds mu (real blocks are a subset of
    # complex ones, G = 0); it rescues frequencies where AB13MD stalls
    cplx = tuple(Block.full(1, 1) if t == 1 else b for b, t in zip(padded, itype))
    cu, _, cDl, _ = complex_upper_bound(Mp, cplx)
    use_c = cu < upper
    upper = np.where(use_c, cu, upper)
    dpad[use_c] = np.abs(np.diagonal(cDl[use_c], axis1=1, axis2=2))
    gpad[use_c] = 0.0
    # Newton refinement of the better of the two (AB13MD can be far above the optimum)
    if newton:
        upper, dpad, gpad = _refine_dg(Mp, nblock, itype, upper, dpad, gpad)
    if Mp.shape[1] == 1 and itype[0] == 1:
        # AB13MD returns 0 for a 1 x 1 real problem; mu is |m| if m is real
        m = Mp[:, 0, 0]
        upper = np.where(np.abs(m.imag) <= 1e-12 * np.abs(m), np.abs(m), 0.0)
        dpad[:], gpad[:] = 1.0, 0.0
    slots = block_slices(blocks)
    full = [out for b, (_, out) in zip(blocks, slots) if b.is_full]
    ref = rows[full[-1].start] if full else 0
    scale = dpad[:, ref:ref + 1]
    dpad, gpad = dpad / scale, gpad / scale ** 2
    d = np.full((nf, len(blocks)), np.nan)
    g = np.full((nf, len(blocks)), np.nan)
    for i, b in enumerate(blocks):
        start = slots[i][1].start
        if b.scalar_scaling:
            d[:, i] = dpad[:, rows[start]]
        if b.is_real and b.size == 1:
            g[:, i] = gpad[:, rows[start]]
    G = np.zeros((nf, q, p))
    same = rows[None, :] == cols[:, None]         # padded position shared by in and out
    qi, pi = np.nonzero(same)
    G[:, qi, pi] = gpad[:, cols[qi]]
    Dl = np.zeros((nf, p, p))
    Dr = np.zeros((nf, q, q))
    Dl[:, np.arange(p), np.arange(p)] = dpad[:, rows]
    Dr[:, np.arange(q), np.arange(q)] = dpad[:, cols]
    return upper, d, g, Dl, Dr, G


class _DGProblem:
    """beta^2(theta, g) = lambda_max(A^H A + j (G A - A^H G)), A = D M D^-1.

    The mixed bound's LMI M^H D^2 M + j (Gt M - M^H Gt) - beta^2 D^2 <= 0
    (D diagonal, constant on each padded block; Gt real diagonal on the 1 x 1
    real blocks), after the congruence with D^-1: G = D^-1 Gt D^-1.  The
    parameters are theta = log d of every block but the last (d = 1 there,
    the LMI is homogeneous) and y = asinh g of each real block (the optimal
    g can be unbounded, as for rank-one M: steps in y reach it geometrically).
    """

    def __init__(self, nblock, itype):
        self.starts = np.concatenate([[0], np.cumsum(nblock)[:-1]])   # first row of each block
        self.n = int(np.sum(nblock))
        self.E = np.zeros((len(nblock), self.n))    # block indicators
        for i, (s0, m) in enumerate(zip(self.starts, nblock)):
            self.E[i, s0:s0 + m] = 1.0
        self.real_rows = self.starts[np.asarray(itype) == 1]
        self.n_theta = len(nblock) - 1
        self.size = self.n_theta + len(self.real_rows)

    def split(self, x):
        """(log d per row, g per row) of parameters x = (theta, asinh g)."""
        logd = np.concatenate([x[:, :self.n_theta], np.zeros((len(x), 1))], axis=1) @ self.E
        g = np.zeros((len(x), self.n))
        g[:, self.real_rows] = np.sinh(x[:, self.n_theta:])
        return logd, g

    def hermitian(self, M, x):
        """H (N, n, n) and A = D M D^-1 at parameters x (N, size)."""
        logd, g = self.split(x)
        A = np.exp(logd)[:, :, None] * M * np.exp(-logd)[:, None, :]
        AH = np.swapaxes(A, 1, 2).conj()
        GA = g[:, :, None] * A
        H = AH @ A + 1j * (GA - np.swapaxes(GA, 1, 2).conj())
        return 0.5 * (H + np.swapaxes(H, 1, 2).conj()), A, g

    def surrogate(self, M, x, scale, t, need_grad=True):
        """(1/t) log sum exp(t lambda_k / scale), its gradient and lambda_max / scale."""
        H, A, g = self.hermitian(M, x)
        if not need_grad:
            lam = np.linalg.eigvalsh(H) / scale[:, None]
            top = lam[:, -1]
            return top + np.log(np.sum(np.exp(t * (lam - top[:, None])), axis=1)) / t, None, top
        lam, V = np.linalg.eigh(H)
        lam = lam / scale[:, None]
        top = lam[:, -1]
        e = np.exp(t * (lam - top[:, None]))
        F = top + np.log(e.sum(1)) / t
        w = e / e.sum(1, keepdims=True)
        # W = V diag(w) V^H; dF/dx_j = Re tr(dH_j W) / scale
        W = np.einsum("nak,nk,nbk->nab", V, w, V.conj())
        AW = A @ W
        AWAH = AW @ np.swapaxes(A, 1, 2).conj()
        grad = np.empty((len(x), self.size))
        # theta_j: dA = E_j A - A E_j,  dH = dA^H A + A^H dA + j (G dA - dA^H G)
        AHA_W = np.swapaxes(A, 1, 2).conj() @ AW          # A^H A W
        GAW = g[:, :, None] * AW                          # G A W
        WG = W * g[:, None, :]                            # W G
        for j in range(self.n_theta):
            e_j = self.E[j]
            t1 = 2 * np.einsum("na,a->n", np.diagonal(AWAH, axis1=1, axis2=2), e_j).real
            t2 = 2 * np.einsum("na,a->n", np.diagonal(AHA_W, axis1=1, axis2=2), e_j).real
            # Re tr(j (G dA - dA^H G) W) = -2 Im tr(G dA W), tr(G dA W) = tr(G E A W) - tr(G A E W)
            c1 = np.einsum("na,a->n", np.diagonal(GAW, axis1=1, axis2=2), e_j)
            c2 = np.einsum("nab,nba->n", A * e_j[None, None, :], WG)
            grad[:, j] = t1 - t2 - 2 * (c1 - c2).imag
        for i, r in enumerate(self.real_rows):
            # dH = j (E_r A - A^H E_r) dg/dy: Re tr(dH W) = -2 Im (A W)_rr cosh y
            grad[:, self.n_theta + i] = -2 * AW[:, r, r].imag * np.cosh(x[:, self.n_theta + i])
        return F, grad / scale[:, None], top


def _refine_dg(M, nblock, itype, upper, dpad, gpad):
    """Lower a D,G bound (AB13MD's, or the complex one) by Newton steps from its scalings.

    AB13MD's bound can sit well above the optimal D,G bound (on random
    rank-one matrices, where that optimum is mu, a median 0.7 % above it).
    From the given D, G the refinement minimises a smoothed lambda_max
    (log-sum-exp of the eigenvalues, exponent t from 16 to 4e6) of the
    congruence-transformed LMI (:class:`_DGProblem`), with Hessians from
    central differences of analytic gradients.  The returned bound is
    sqrt(lambda_max) at the best point found plus a bound on its rounding,
    and replaces the given one only where it is lower.
    """
    if not np.any(np.asarray(itype) == 1) or M.shape[1] == 1:
        return upper, dpad, gpad
    prob = _DGProblem(nblock, itype)
    ok = np.isfinite(upper) & (upper > 0) & np.all(dpad > 0, axis=1)
    rows = np.nonzero(ok)[0]
    if rows.size == 0 or prob.size == 0:
        return upper, dpad, gpad
    Mr = M[rows]
    d0 = dpad[rows][:, prob.starts]
    d0 = d0 / d0[:, -1:]
    # G = D^-1 Gt D^-1 does not change when (D^2, Gt) are scaled together
    x = np.concatenate([np.log(d0[:, :-1]), np.arcsinh(
        gpad[rows][:, prob.real_rows] / dpad[rows][:, prob.real_rows] ** 2)], axis=1)
    scale = upper[rows] ** 2
    # |g| <= 1e6 beta: beyond it the G term's rounding (~ eps |g| ||A||) outweighs any gain
    cap = np.full(x.shape, np.inf)
    cap[:, prob.n_theta:] = np.arcsinh(1e6 * upper[rows])[:, None]
    x = np.clip(x, -cap, cap)
    best_x = x.copy()
    best = _lambda_max(prob, Mr, x)
    todo = np.ones(rows.size, bool)
    for t in _DG_T_SCHEDULE:
        # levels before the last only supply the next one's start
        tol = 1e-12 if t == _DG_T_SCHEDULE[-1] else max(1e-12, 1e-3 / t)
        active = np.nonzero(todo)[0]
        for _ in range(_DG_NEWTON_ITERATIONS):
            if active.size == 0:
                break
            Ma, xa, sa = Mr[active], x[active], scale[active]
            F0, g0, H = _dg_newton_model(prob, Ma, xa, sa, t)
            step, _ = newton_direction(H, g0, np.ones(prob.size, bool), _DG_MAX_STEP)
            F, xn, lam = _dg_line_search(prob, Ma, xa, step, sa, t, cap[active])
            improved = F < F0
            x[active[improved]] = xn[improved]
            value = lam * sa
            better = improved & (value < best[active])
            best[active[better]] = value[better]
            best_x[active[better]] = xn[better]
            done = ~improved | (F0 - F < tol)
            active = active[~done]
        # where lambda_max stands alone at this level, larger t changes nothing
        todo &= ~_dg_settled(prob, Mr, x, scale, t)
    refined = np.sqrt(np.maximum(_certified_lambda_max(prob, Mr, best_x), 0.0))
    use = refined < upper[rows]
    sel = rows[use]
    upper = upper.copy()
    upper[sel] = refined[use]
    logd, g = prob.split(best_x[use])
    dpad, gpad = dpad.copy(), gpad.copy()
    dpad[sel] = np.exp(logd)
    gpad[sel] = g * np.exp(2 * logd)
    return upper, dpad, gpad


def _dg_settled(prob, M, x, scale, t):
    """sum_k exp(t (lambda_k - lambda_max) / scale) - 1 < 1e-15: the surrogate is lambda_max."""
    lam = np.linalg.eigvalsh(prob.hermitian(M, x)[0]) / scale[:, None]
    rest = np.sum(np.exp(t * (lam[:, :-1] - lam[:, -1:])), axis=1)
    return rest < 1e-15


def _lambda_max(prob, M, x):
    return np.linalg.eigvalsh(prob.hermitian(M, x)[0])[:, -1]


def _certified_lambda_max(prob, M, x):
    """lambda_max of the LMI matrix at parameters x plus a bound on its rounding errors."""
    _, A, g = prob.hermitian(M, x)
    return certified_lmi_top(A, g[:, :, None] * A)


def _dg_newton_model(prob, M, x, scale, t):
    """Surrogate, gradient and a Hessian by central differences of the gradient."""
    copies = 2 * x.shape[1] + 1
    return central_difference_hessian(
        lambda pts: prob.surrogate(np.tile(M, (copies, 1, 1)), pts, np.tile(scale, copies), t)[:2],
        x, 1e-4 / np.sqrt(t), np.arange(x.shape[1]))


def _dg_line_search(prob, M, x, step, scale, t, cap):
    """The fraction of the step with the lowest surrogate (all fractions at once)."""
    N, P = x.shape
    fr = STEP_FRACTIONS
    cand = np.clip(x[None] + fr[:, None, None] * step[None], -cap, cap)
    F, _, lam = prob.surrogate(np.tile(M, (len(fr), 1, 1)), cand.reshape(-1, P),
                               np.tile(scale, len(fr)), t, need_grad=False)
    F, lam = F.reshape(len(fr), N), lam.reshape(len(fr), N)
    k = np.argmin(F, axis=0)
    cols = np.arange(N)
    return F[k, cols], cand[k, cols], lam[k, cols]
