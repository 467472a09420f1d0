"""Upper bound of mu for mixed real/complex structures through SLICOT AB13MD.

Method notes (padding of non-square blocks, relaxation of repeated scalars)
in ``docs/robust.md``; :func:`piezolib.robust.mu.mussv` is the user-facing
entry point.
"""

import numpy as np

from piezolib.robust.blocks import Block, block_slices
from piezolib.robust.mu_upper import balancing_logs, complex_upper_bound

__all__ = ["mixed_upper_bound"]


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


def mixed_upper_bound(M, blocks):
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
