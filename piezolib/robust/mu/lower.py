"""Lower bounds of mu by power iteration, with a perturbation Delta attaining them.

Complex structures: the power iteration of Packard and Doyle (1993), batched
over frequency.  Structures with real scalars: the real loops are closed at
trial real values and the complex blocks get the power iteration.  Method
notes in ``docs/robust.md``; :func:`piezolib.robust.mu.mussv` is the
user-facing entry point.
"""

from typing import NamedTuple

import numpy as np

from piezolib.robust.blocks import block_slices
from piezolib.robust.mu._common import scaled_matrix

__all__ = ["complex_lower_bound", "mixed_lower_bound"]


def _over(x, n):
    """x / n (n >= 0, broadcast against x), 0 where n = 0."""
    return x * np.divide(1.0, n, out=np.zeros_like(n), where=n > 0)


def _row_norms(x):
    """Euclidean norms of the rows (last axis) of a complex x."""
    return np.sqrt((x.real ** 2 + x.imag ** 2).sum(-1))


def _unit(x):
    """Rows of x scaled to unit norm (zero rows stay zero)."""
    return _over(x, _row_norms(x)[..., None])


class _Layout(NamedTuple):
    """Where the blocks sit: 1 x 1 full blocks as index arrays (handled all at once in the
    power iteration), the others as (block, inputs slice, outputs slice)."""
    unit_in: np.ndarray
    unit_out: np.ndarray
    others: list


def _layout(blocks):
    """The :class:`_Layout` of a structure."""
    unit = [b.is_full and b.rows == b.cols == 1 for b in blocks]
    slices = block_slices(blocks)
    ui, uo = (np.array([s[k].start for u, s in zip(unit, slices) if u], int) for k in (0, 1))
    return _Layout(ui, uo, [(b, bi, bo) for b, u, (bi, bo) in zip(blocks, unit, slices)
                            if not u])


def _phase(x):
    """x / |x| elementwise, 0 where x = 0."""
    return _over(x, np.abs(x))


def _structured_q(layout, a, w, q_dim, p_dim):
    """Structured Q (N, q, p), ||Q_i|| <= 1, aligned with a (p-space) and w (q-space)."""
    N = a.shape[0]
    Q = np.zeros((N, q_dim, p_dim), complex)
    ui, uo = layout.unit_in, layout.unit_out
    Q[:, ui, uo] = _phase(w[:, ui]) * _phase(a[:, uo]).conj()
    for b, bi, bo in layout.others:
        ab, wb = a[:, bo], w[:, bi]
        if b.is_full:
            Q[:, bi, bo] = np.einsum("ni,nj->nij", _unit(wb), _unit(ab).conj())
        else:
            qs = _scalar_phase(np.einsum("ni,ni->n", ab.conj(), wb), b.kind)
            idx = np.arange(b.size)
            Q[:, bi.start + idx, bo.start + idx] = qs[:, None]
    return Q


def _power_iteration(M, layout, b, w, iterations, real_only):
    """Packard-Doyle power iteration from starts b, w (rows of a batch).

    A row stops once its gain |M b| repeats to 1e-13 from one sweep to the next (a
    fixed point, up to the eigenvalue's phase), or after ``iterations`` sweeps, at its
    structured Q.  Returns (value, Q, lambda) per row: value = |lambda|, the largest
    |eigenvalue| of Q M (real ones only if real_only), which certifies the lower bound.
    """
    N, p, q = M.shape
    MH = np.swapaxes(M, 1, 2).conj()
    Q = np.zeros((N, q, p), complex)
    b, w = _unit(b), _unit(w)
    active = np.arange(N)
    Ma, MHa = M, MH
    gain = np.full(N, np.inf)
    for it in range(iterations):
        a, w, b, new_gain = _power_sweep(Ma, MHa, layout, b, w)
        done = np.abs(new_gain - gain) <= 1e-13 * new_gain
        if it == iterations - 1:
            done[:] = True
        if done.any():
            Q[active[done]] = _structured_q(layout, a[done], w[done], q, p)
            keep = ~done
            active, w, b, new_gain = active[keep], w[keep], b[keep], new_gain[keep]
            if active.size == 0:
                break
            Ma, MHa = M[active], MH[active]
        gain = new_gain
    # the eigenvalue is the certificate, and it costs more than a sweep: once, at the end
    value, lam = _eigen_gain(Q, M, real_only)
    return value, Q, lam


def _power_sweep(M, MH, layout, b, w):
    """One sweep b -> a = M b -> z -> w = M^H z -> b, block by block; also |M b|."""
    Mb = np.einsum("npq,nq->np", M, b)
    gain = _row_norms(Mb)
    a = _over(Mb, gain[:, None])
    w_new = _unit(np.einsum("nqp,np->nq", MH, _align(layout, a, w, "z")))
    w = np.where(np.any(w_new != 0, axis=1, keepdims=True), w_new, w)
    bn = _unit(_align(layout, a, w, "b"))
    b = np.where(np.any(bn != 0, axis=1, keepdims=True), bn, b)
    return a, w, b, gain


def _align(layout, a, w, side):
    """Block-wise alignment of the power iteration.

    ``side="z"`` gives z (M's output space): |w_i| a_i / |a_i| for a full
    block, conj(q_i) w_i for a scalar block; ``side="b"`` gives b (M's input
    space): |a_i| w_i / |w_i|, or q_i a_i, with q_i the scalar's phase (or
    sign) that aligns a_i with w_i.
    """
    to_z = side == "z"
    out = np.zeros_like(a if to_z else w)
    ui, uo = layout.unit_in, layout.unit_out
    if to_z:
        out[:, uo] = np.abs(w[:, ui]) * _phase(a[:, uo])
    else:
        out[:, ui] = np.abs(a[:, uo]) * _phase(w[:, ui])
    for blk, bi, bo in layout.others:
        ab, wb = a[:, bo], w[:, bi]
        dest = bo if to_z else bi
        if blk.is_full:
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
    real_only = any(b.is_real for b in blocks)
    layout = _layout(blocks)
    lower = np.zeros(nf)
    Delta = np.zeros((nf, q, p), complex)

    def run(rows, start_list):
        R = len(start_list)
        b0 = np.concatenate([s[0] for s in start_list])
        w0 = np.concatenate([s[1] for s in start_list])
        val, Q, lam = _power_iteration(np.tile(M[rows], (R, 1, 1)), layout, b0, w0,
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


def complex_lower_bound(M, blocks, Dl, Dr, upper, *, iterations=60, restarts=3, rng=None):
    """Lower bound of mu for a structure without real blocks, and a Delta attaining it.

    The power iteration starts from the top singular vectors of the scaled
    matrix Dl M Dr^-1 and of M itself, then from ``restarts`` seeded random
    vectors where the bounds still differ, and, for structures where the
    D-scaled bound is mu, where the scaled matrix's largest singular value is
    double, from 13 combinations of the two top singular vectors (with twice
    the sweeps).  On a frequency grid each point's Delta is finally tried at
    its neighbours (:func:`_continue_along_frequency`).

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
    blocks : tuple of Block
        Complex structure fitting M.
    Dl, Dr : ndarray, shapes (nf, p, p) and (nf, q, q)
        D-scalings of the upper bound (used for the first start).
    upper : ndarray, shape (nf,)
        The upper bound (random starts only where lower < upper).
    iterations, restarts : int
        Power-iteration sweeps per start; number of random starts.
    rng : numpy.random.Generator, optional
        Source of the random starts (default: seeded with 0).

    Returns
    -------
    lower : ndarray, shape (nf,)
    Delta : ndarray, shape (nf, q, p)
        Structured, ``det(I - M Delta) = 0``, ``norm(Delta, 2) = 1 / lower``.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    # start from the top singular vectors of the scaled and unscaled M:
    # with A = Dl M Dr^-1 = sigma u v^H + ..., b = Dr^-1 v and w = Dr^H v
    # satisfy the power iteration's alignment conditions when D is optimal
    _, s, Vh = np.linalg.svd(scaled_matrix(M, Dl, Dr))
    V = np.swapaxes(Vh, 1, 2).conj()
    v0 = np.linalg.svd(M)[2][:, 0, :].conj()
    starts = [_aligned_start(Dr, V[:, :, 0]), (v0, v0)]
    lower, Delta = _lower_bound(M, blocks, starts, iterations, rng, restarts, upper)
    # where the D-scaled bound equals mu (2 S + F <= 3), a gap beside a double
    # sigma_max at the optimal D is a stall: v may be anywhere in the top singular
    # plane, and the aligned combination need not be the first singular vector.
    # (Elsewhere a double sigma_max mostly marks the bound's own conservatism.)
    rows = np.zeros(0, int)
    if s.shape[1] > 1 and _d_scaled_bound_is_mu(blocks):
        rows = np.nonzero((s[:, 1] >= (1 - 1e-6) * s[:, 0]) & (lower < upper * (1 - 1e-6)))[0]
    if rows.size:
        plane = [_aligned_start(Dr[rows], np.cos(phi) * V[rows, :, 0]
                                + np.exp(1j * psi) * np.sin(phi) * V[rows, :, 1])
                 for phi in np.pi / 8 * np.arange(1, 5) for psi in np.pi / 2 * np.arange(4)
                 if phi < np.pi / 2 or psi == 0]
        # (the iteration converges slowly near a double sigma_max: twice the sweeps)
        low, D = _lower_bound(M[rows], blocks, plane, 2 * iterations, rng, 0, upper[rows])
        better = low > lower[rows]
        lower[rows[better]], Delta[rows[better]] = low[better], D[better]
    if M.shape[0] > 1:
        _continue_along_frequency(M, blocks, lower, Delta, upper, iterations)
    return lower, Delta


def _continue_along_frequency(M, blocks, lower, Delta, upper, iterations):
    """Carry each frequency's Delta to its neighbours, in place, where that is better.

    A start that finds a higher local maximum at one frequency says nothing at
    the next one; but the maximum moves continuously with frequency, so each
    point's Q (Delta scaled to norm 1) is tried at the neighbouring points,
    repeatedly until nothing improves, and the power iteration then climbs
    from wherever it did.  (On the benchmark's 8 scalar blocks it lifts some
    lower bounds by up to 1.6 %, on larger structures by up to 3.5 %, for a
    few percent of the run time.)
    """
    nf = M.shape[0]
    Q = Delta * lower[:, None, None]             # lambda's phase is immaterial for complex blocks
    value = lower.copy()
    gap = lower < upper * (1 - 1e-6)
    sources = np.nonzero(lower > 0)[0]
    for _ in range(nf):
        dst = np.concatenate([sources + 1, sources - 1])
        src = np.concatenate([sources, sources])
        ok = (dst >= 0) & (dst < nf)
        src, dst = src[ok], dst[ok]
        ok = gap[dst]
        src, dst = src[ok], dst[ok]
        if dst.size == 0:
            break
        val = np.abs(np.linalg.eigvals(Q[src] @ M[dst])).max(axis=1)
        order = np.argsort(val)                  # the best candidate per point written last
        src, dst, val = src[order], dst[order], val[order]
        better = val > value[dst] * (1 + 1e-9)
        src, dst, val = src[better], dst[better], val[better]
        value[dst] = val
        Q[dst] = Q[src]
        sources = np.unique(dst)
    rows = np.nonzero(value > lower)[0]
    if rows.size == 0:
        return
    # climb from the carried Q: the power iteration starts from its top eigenvector
    lam, X = np.linalg.eig(Q[rows] @ M[rows])
    top = np.argmax(np.abs(lam), axis=1)
    x = X[np.arange(rows.size), :, top]
    val, Qp, lamp = _power_iteration(M[rows], _layout(blocks), x, x, iterations, False)
    lam_top = lam[np.arange(rows.size), top]
    climbed = val > value[rows]
    lower[rows] = np.where(climbed, val, value[rows])
    Delta[rows] = np.where(climbed[:, None, None], Qp / lamp[:, None, None],
                           Q[rows] / lam_top[:, None, None])


def _d_scaled_bound_is_mu(blocks):
    """2 S + F <= 3 (S repeated complex scalars with k > 1, F other blocks): the bound is mu."""
    S = sum(1 for b in blocks if b.repeated and b.size > 1)
    return 2 * S + len(blocks) - S <= 3


def _aligned_start(Dr, v):
    """Power-iteration start (b, w) = (Dr^-1 v, Dr^H v) from a right singular vector v of Dl M Dr^-1."""
    return np.linalg.solve(Dr, v[..., None])[..., 0], np.einsum("nji,nj->ni", Dr.conj(), v)


def mixed_lower_bound(M, blocks, upper, *, iterations=60, restarts=3, rng=None):
    """Lower bound of mu for structures with real scalars, and a Delta attaining it.

    Closing the real loops at fixed real values delta_r leaves the complex
    blocks with M_c(delta_r) = M_cc + M_cr D_r (I - M_rr D_r)^-1 M_rc, and
    det(I - M Delta) = det(I - M_rr D_r) det(I - M_c Delta_c); so any
    delta_r and a complex Delta_c destabilising M_c give a structured Delta
    of norm max(|delta_r|, ||Delta_c||).  delta_r is searched on a grid
    (scaled by 1 / upper) and refined coordinate-wise; the complex part uses
    the power iteration.  Without complex blocks only a single 1 x 1 real
    scalar is handled exactly (mu = |m| for real m); other purely real
    structures use :func:`_real_lower_bound` (a vertex search with one free
    coordinate).

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
    blocks : tuple of Block
        Structure fitting M, with at least one real block.
    upper : ndarray, shape (nf,)
        An upper bound of mu (sets the scale of the search).
    iterations, restarts : int
        Power-iteration sweeps per start; random starts (pure real case).
    rng : numpy.random.Generator, optional
        Source of the random directions and starts (default: seeded with 0).

    Returns
    -------
    lower : ndarray, shape (nf,)
    Delta : ndarray, shape (nf, q, p)
        Structured, ``det(I - M Delta) = 0``, ``norm(Delta, 2) = 1 / lower``.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    nf, p, q = M.shape
    layout = list(zip(blocks, block_slices(blocks)))
    real = [(b, s) for b, s in layout if b.is_real]
    comp = [(b, s) for b, s in layout if not b.is_real]
    if not comp:
        if p == 1 and q == 1:
            m = M[:, 0, 0]
            ok = (np.abs(m.imag) <= 1e-12 * np.abs(m)) & (m != 0)
            lower = np.where(ok, np.abs(m), 0.0)
            Delta = np.where(ok, 1 / np.where(ok, m.real, 1), 0.0)[:, None, None] + 0j
            return lower, Delta
        return _real_lower_bound(M, blocks, upper, rng, iterations)
    IR = np.concatenate([np.arange(q)[bi] for _, (bi, _) in real])
    OR = np.concatenate([np.arange(p)[bo] for _, (_, bo) in real])
    IC = np.concatenate([np.arange(q)[bi] for _, (bi, _) in comp])
    OC = np.concatenate([np.arange(p)[bo] for _, (_, bo) in comp])
    sub = tuple(b for b, _ in comp)       # the complex blocks, in order on M_c
    owner = np.concatenate([np.full(b.size, j) for j, (b, _) in enumerate(real)])
    Mrr, Mrc = M[:, OR][:, :, IR], M[:, OR][:, :, IC]
    Mcr, Mcc = M[:, OC][:, :, IR], M[:, OC][:, :, IC]
    nr = len(real)

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


_BETA_GRID = 40              # log-spaced trial values of beta per search
_BETA_SPAN = 1e-4            # the grid covers [1e-4, 1] x upper
_BISECTIONS = 60


def _real_lower_bound(M, blocks, upper, rng, iterations):
    """Lower bound of mu for purely real (repeated) scalar structures.

    All blocks but one 1 x 1 block j sit at a vertex, delta_b = s_b / beta
    (s_b = +-1); closing them leaves the scalar loop
    n_j(beta) = M_jj + M_jo D_o (I - M_oo D_o)^-1 M_oj and
    det(I - M Delta) = det(I - M_oo D_o) (1 - delta_j n_j(beta)).  So
    delta_j = 1 / n_j(beta) destabilises with a real delta_j exactly where
    Im n_j(beta) = 0, and the whole Delta has norm 1 / beta when
    |n_j(beta)| >= beta.  The largest such beta in (0, upper] is found on a
    log grid and refined by bisection on the sign of Im n_j, for every free
    block j and a set of sign vectors s (all vertices for up to four blocks,
    else the signs of a complex-structure worst case and seeded random
    ones), followed by single sign flips of the best vertex.  The result is
    a valid lower bound (its Delta is returned) but not always mu: the
    worst real perturbation need not have this form, and a complex M may
    give mu = 0.
    """
    nf, p, q = M.shape
    layout = list(zip(blocks, block_slices(blocks)))
    nr = len(layout)
    owner = np.concatenate([np.full(b.size, j) for j, (b, _) in enumerate(layout)])
    free = [j for j, (b, _) in enumerate(layout) if b.size == 1]
    lower = np.zeros(nf)
    Delta = np.zeros((nf, q, p), complex)
    if p == 1:                         # one 1 x 1 real block: mu = |m| for real m
        m = M[:, 0, 0]
        ok = (np.abs(m.imag) <= 1e-12 * np.abs(m)) & (m != 0)
        lower = np.where(ok, np.abs(m), 0.0)
        Delta[:, 0, 0] = np.where(ok, 1 / np.where(ok, m.real, 1), 0.0)
        return lower, Delta
    scale = np.where(upper > 0, upper, 0.0)
    if not free or not np.any(scale > 0):
        return lower, Delta
    if nr <= 4:
        signs = np.array(np.meshgrid(*[[1.0, -1.0]] * nr)).reshape(nr, -1).T
        signs = np.repeat(signs[:, None, :], nf, axis=1)
    else:
        # signs of the worst complex-scalar perturbation, then random vertices
        cplx = tuple(type(b).scalar(b.size) for b, _ in layout)
        v = np.linalg.svd(M)[2][:, 0, :].conj()
        _, Dc = _lower_bound(M, cplx, [(v, v)], iterations, rng, 0, np.zeros(nf))
        first = np.array([Dc[:, sl[0].start, sl[1].start].real for _, sl in layout]).T
        first = np.where(first >= 0, 1.0, -1.0)
        rand = np.where(rng.standard_normal((11, nf, nr)) >= 0, 1.0, -1.0)
        signs = np.concatenate([first[None], -first[None], rand])
    best_s = np.ones((nf, nr))

    def search(sign_sets):
        """Try every sign vector of sign_sets (ns, nf, nr) with every free block."""
        for j in free:
            val, D = _free_coordinate(M, layout, owner, j, sign_sets, scale)
            k = np.argmax(val, axis=0)
            v = val[k, np.arange(nf)]
            better = v > lower
            lower[better] = v[better]
            Delta[better] = D[k[better], np.nonzero(better)[0]]
            best_s[better] = sign_sets[k[better], np.nonzero(better)[0]]

    search(signs)
    for _ in range(2):                 # single sign flips of the best vertex
        flips = np.repeat(best_s[None], nr, axis=0)
        flips[np.arange(nr), :, np.arange(nr)] *= -1
        search(flips)
    return lower, Delta


def _free_coordinate(M, layout, owner, j, signs, scale):
    """Largest beta in (0, scale] with a real destabilising delta_j (see _real_lower_bound).

    Returns the bound (ns, nf) (0 where none is found) and Delta (ns, nf, q, p).
    """
    ns, nf, nr = signs.shape
    p = M.shape[1]
    bj, (ij, oj) = layout[j]
    rows_j, cols_j = oj.start, ij.start               # M's output / input of block j
    others = np.nonzero(owner != j)[0]
    Mb = np.broadcast_to(M, (ns, nf, p, p))
    s_el = signs[..., owner[others]]                  # (ns, nf, n_o) sign per element
    Moo = Mb[..., others[:, None], others[None, :]]
    Moj = Mb[..., others, cols_j]
    Mjo = Mb[..., rows_j, others]
    mjj = Mb[..., rows_j, cols_j]
    eye = np.eye(len(others))

    def loop(beta):
        """n_j(beta), shape beta.shape; beta (ns, nf, ...) broadcast over trailing axes."""
        extra = beta.ndim - 2
        exp = (Ellipsis,) + (None,) * extra
        d = s_el[(slice(None), slice(None)) + (None,) * extra] / beta[..., None]
        X = eye - _expand(Moo, extra) * d[..., None, :]
        sol = np.linalg.solve(X, _expand(Moj, extra)[..., None])[..., 0]
        return mjj[exp] + np.einsum("...i,...i->...", _expand(Mjo, extra), d * sol)

    unit = np.where(scale > 0, scale, 1.0)          # rows with scale 0 are dropped below
    grid = unit[None, :, None] * np.logspace(np.log10(_BETA_SPAN), 0, _BETA_GRID)
    grid = np.broadcast_to(grid, (ns, nf, _BETA_GRID))
    with np.errstate(all="ignore"):
        n = loop(grid)
    # complex mode: bisect on the sign of Im n_j; real mode (n_j real on the
    # whole grid, e.g. a real M): bisect on the sign of |n_j| - beta
    real_mode = np.all(np.abs(n.imag) <= 1e-10 * np.abs(n), axis=-1)
    h = np.where(real_mode[..., None], np.sign(np.abs(n) - grid), np.sign(n.imag))
    feasible = np.abs(n) >= grid
    change = np.where(real_mode[..., None], (h[..., :-1] > 0) & (h[..., 1:] < 0),
                      (h[..., :-1] * h[..., 1:] < 0) & (feasible[..., :-1] | feasible[..., 1:]))
    # the highest sign change on the grid
    has = change.any(axis=-1) & (scale > 0)[None, :]
    top = _BETA_GRID - 2 - np.argmax(change[..., ::-1], axis=-1)
    lo = np.log(np.take_along_axis(grid, top[..., None], -1)[..., 0])
    hi = np.log(np.take_along_axis(grid, top[..., None] + 1, -1)[..., 0])
    at_top = real_mode & (h[..., -1] >= 0) & (scale > 0)[None, :]   # feasible at beta = upper
    lo = np.where(at_top, np.log(grid[..., -1]), lo)
    hi = np.where(at_top, lo, hi)
    has = has | at_top
    h_lo = np.where(at_top, 1.0, np.take_along_axis(h, top[..., None], -1)[..., 0])
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        with np.errstate(all="ignore"):
            nm = loop(np.exp(mid))
        hm = np.where(real_mode, np.sign(np.abs(nm) - np.exp(mid)), np.sign(nm.imag))
        same = hm == h_lo
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    beta = np.exp(np.where(np.abs(h_lo) > 0, lo, hi))
    with np.errstate(all="ignore"):
        n_root = loop(beta)
    dj = 1 / n_root.real
    ok = (has & np.isfinite(dj) & (np.abs(n_root.imag) <= 1e-9 * np.abs(n_root))
          & (np.abs(dj) * beta <= 1 + 1e-12))
    q = M.shape[2]
    D = np.zeros((ns, nf, q, p), complex)
    delta = signs[..., owner] / np.where(ok, beta, 1.0)[..., None]
    delta[..., cols_j] = np.where(ok, dj, 0.0)
    idx = np.arange(p)
    D[..., idx, idx] = np.where(ok[..., None], delta, 0.0)
    return np.where(ok, beta, 0.0), D


def _expand(a, extra):
    """Insert ``extra`` axes after the two leading (sign set, frequency) axes."""
    return a[(slice(None), slice(None)) + (None,) * extra]
