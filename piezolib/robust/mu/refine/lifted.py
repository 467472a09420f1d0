"""A tighter upper bound of mu for complex structures: the symmetric-lift certificate.

With M p x q and x = Delta y, y = M x, mu(M) >= beta holds exactly when some x != 0
satisfies the constraints of every block b at level beta: for a full block (or a 1 x 1
scalar) q_b(x) = ||y_b||^2 - beta^2 ||x_b||^2 >= 0; for a repeated scalar delta I_r the same
inequality and, in addition, x_b parallel to y_b (x_b = delta y_b).  The D-scaled bound
certifies mu < beta with constant weights, sum_b d_b q_b(x) < 0 for every x != 0 (on the
D-balanced matrix).  This module weights each q_b by a positive semidefinite quadratic form
instead, with S_b Hermitian q x q:

    sum_b q_b(x) x^H S_b x < 0   for every x != 0 whose repeated-scalar parts are parallel,

which rules out every such x.  A repeated scalar also gives y_b y_b^H - beta^2 x_b x_b^H >= 0
(x_b = delta y_b), so its r x r multiplier T_b >= 0 adds (y_b^H T_b y_b - beta^2 x_b^H T_b x_b)
||x||^2 to the left side.  The left side is a Hermitian form in the symmetric tensor
z = x (x) x, and parallelism is linear in z: x_i y_j - x_j y_i = 0 for each pair i < j inside a
repeated scalar (y = M x, so each such product is a fixed combination of the entries of z).
Demanding the form negative on the symmetric tensors that meet those linear equations (an
orthonormal basis V) is the linear matrix inequality

    F(S) = beta^2 V^H D_x V - N^H D_y N > 0,   N = (M (x) I_q) V,

with D_x = sum_b E_b^H E_b (x) S_b + sum_b E_b^H T_b E_b (x) I and D_y likewise with F_b
(E_b, F_b select the block's entries of x and y; T_b only for repeated scalars).  S_b = I
gives back the D-scaled bound on the D-balanced matrix (for n scalars exactly; the
parallelism can only lower it), so the certificate is never weaker.  The smallest
certified beta is the square root of the largest generalized eigenvalue of
(N^H D_y N, V^H D_x V), minimised over S (and T) by the method of centres: the analytic
centre of {S : F_tau(S) > 0, S_b > 0, sum_b tr S_b = 1} for a level tau that moves down
towards the eigenvalue at the previous centre, each centre followed by a long step along the
line through it and the one before (the centres drift slowly along a smooth path, and on
q = 15 that step cut the centres needed several-fold).  Where S and T stall on a repeated
scalar, a few directions of its full (r q) x (r q) weight are added as cuts (W Sigma W^H,
k^2 unknowns each, W from the current centre; :meth:`_LiftedCertificate.add_cuts`), which
closed the gaps S and T leave on the benchmark's q = 15 case.  Every returned bound is the
eigenvalue of the multipliers it came from, recomputed from scratch, so it is a certificate
whatever the iteration did.  Derivation in ``docs/robust.md``.

It costs nb q^2 unknowns (512 for 8 scalars, 1,575 for seven blocks on q = 15) and a
Newton step about 9 ms for 8 scalars, 70 ms on q = 15 and 170 ms for eight blocks on q = 17
(2,312 unknowns; from about 1,500 unknowns on, the dense Cholesky factor is most of it),
against about 1 ms per frequency for the D-scaled bound, so :func:`mussv` applies it only
where asked (``refine``) and only where the gap exceeds the requested tolerance.
"""

from functools import lru_cache

import numpy as np
import scipy.linalg as sla

from piezolib.robust.blocks import block_slices
from piezolib.robust.mu._common import scaled_matrix

__all__ = ["lifted_upper_bound", "lifted_unknowns", "MAX_LIFTED_UNKNOWNS"]

#: the Newton system has nb q^2 unknowns; its dense Cholesky factor dominates a step from
#: about 1,500 on, and a step costs about 0.26 s at 2,900 unknowns and 0.8 s at 3,550
MAX_LIFTED_UNKNOWNS = 3000

#: cuts of the full repeated-scalar weight (see :meth:`_LiftedCertificate.add_cuts`): the
#: directions per repeated scalar and cut, the centres before a cut, and the rounds of cuts per
#: point (each round adds at most CUT_DIRECTIONS^2 unknowns per repeated scalar)
CUT_DIRECTIONS, CENTRES_BEFORE_CUT, MAX_CUTS = 4, 12, 4
#: a point also cuts once a centre closes less than this fraction of its distance to target
STALL = 0.02


def lifted_unknowns(blocks):
    """Real unknowns of the certificate for a structure: one q x q Hermitian S_b per block
    (each repeated scalar adds r^2 for its T_b, which the cap leaves out: few, and cheap)."""
    q = sum(b.rows for b in blocks)
    return len(blocks) * q * q


def _symmetric_basis(n):
    """Real orthonormal basis (n^2, n(n+1)/2) of the symmetric tensors of C^n (x) C^n."""
    i, k = np.triu_indices(n)
    P = np.zeros((n * n, len(i)))
    cols = np.arange(len(i))
    w = np.where(i == k, 1.0, np.sqrt(0.5))
    P[i * n + k, cols] = w
    P[k * n + i, cols] = w
    return P


def _hermitian_basis(n):
    """Real basis (n^2, n, n) of the Hermitian n x n matrices: E_aa, E_ab + E_ba, j(E_ab - E_ba)."""
    H = [np.diag(np.eye(n)[a]).astype(complex) for a in range(n)]
    for a, b in zip(*np.triu_indices(n, 1)):
        E = np.zeros((n, n), complex)
        E[a, b] = E[b, a] = 1
        H.append(E)
        E = np.zeros((n, n), complex)
        E[a, b], E[b, a] = 1j, -1j
        H.append(E)
    return np.array(H)


def _basis_gather(n):
    """The map from n x n matrix entries to Hermitian basis coefficients as two gathers:
    coefficient k of X is c1[k] X.flat[i1[k]] + c2[k] X.flat[i2[k]] (one entry for E_aa,
    the pair (a, b), (b, a) for the others, in the order of :func:`_hermitian_basis`)."""
    a, b = np.triu_indices(n, 1)
    diag = np.arange(n) * (n + 1)
    i1 = np.concatenate([diag, np.column_stack([a * n + b] * 2).ravel()])
    i2 = np.concatenate([diag, np.column_stack([b * n + a] * 2).ravel()])
    c1 = np.concatenate([np.ones(n), np.tile([1, 1j], len(a))])
    c2 = np.concatenate([np.zeros(n), np.tile([1, -1j], len(a))])
    return i1, i2, c1, c2


@lru_cache(maxsize=None)
def _lift_constants(n):
    """What the certificate needs for q = n whatever M is (shared, not to be modified): the
    symmetric basis P, the Hermitian basis H, the gathers from matrix entries to basis
    coefficients (:func:`_basis_gather`) and the trace of each basis matrix."""
    H = _hermitian_basis(n)
    return _symmetric_basis(n), H, _basis_gather(n), np.einsum("kaa->k", H).real


def _entry_products(X4, Y4, a, c):
    """Sum over the entries a (slice) and c (slice) of X4[c, i, a, j] Y4[a, k, c, l], as a
    (q^2, q^2) matrix with rows (j, k) and columns (l, i)."""
    q = X4.shape[1]
    Xr = X4[c, :, a].transpose(2, 0, 3, 1).reshape(-1, q * q)   # [(a, c), (j, i)]
    Yr = Y4[a, :, c].transpose(0, 2, 1, 3).reshape(-1, q * q)   # [(a, c), (k, l)]
    return (Xr.T @ Yr).reshape(q, q, q, q).transpose(0, 2, 3, 1).reshape(q * q, q * q)


def _parallel_functionals(M, blocks):
    """Rows (w, q^2): x_i y_j - x_j y_i (y = M x) for each pair i < j inside a repeated
    scalar, as linear functionals of z = x (x) x (entry i q + k holds x_i x_k)."""
    p, q = M.shape
    rows = []
    for b, (xs, ys) in zip(blocks, block_slices(blocks)):
        if b.repeated:
            for i, j in zip(*np.triu_indices(b.rows, 1)):
                ell = np.zeros((q, q), complex)
                ell[xs.start + i] += M[ys.start + j]
                ell[xs.start + j] -= M[ys.start + i]
                rows.append(ell.ravel())
    return np.array(rows).reshape(-1, q * q)


def _log_det_sum(matrices):
    """Sum of log det over Hermitian matrices, or None if one is not positive definite."""
    try:
        return sum(2 * np.log(np.linalg.cholesky(X).diagonal().real).sum() for X in matrices)
    except np.linalg.LinAlgError:
        return None


class _LiftedCertificate:
    """The matrices of the certificate for one M (p x q) and its Newton derivatives.

    The unknowns theta hold S_b = sum_k theta[b, k] H_k (nb q^2 reals), then the entries of
    each repeated scalar's T_b in the r x r Hermitian basis (r^2 reals each), then those of
    each cut's Sigma (k^2 reals; :meth:`add_cuts`), in the order the cuts were added.
    """

    def __init__(self, M, blocks):
        p, q = M.shape
        self.p, self.q, self.nb = p, q, len(blocks)
        self.V, self.H, self.gather, trace = _lift_constants(q)
        self.slices = block_slices(blocks)
        # block index of each entry of x (Delta's output) and of y (its input)
        self.bx = np.repeat(np.arange(self.nb), [b.rows for b in blocks])
        self.by = np.repeat(np.arange(self.nb), [b.cols for b in blocks])
        L = _parallel_functionals(M, blocks)
        if len(L):
            # the symmetric tensors on which every repeated scalar's parts are parallel
            _, _, vh = np.linalg.svd(L @ self.V)
            self.V = self.V @ vh[len(L):].conj().T
        self.N = np.kron(M, np.eye(q)) @ self.V
        # each repeated scalar's r x r multiplier T_b: its Hermitian basis, and the forms
        # N^H (T (x) I) N and V^H (T (x) I) V of each basis matrix T on the block's entries
        m = self.V.shape[1]
        N4, V4 = self.N.reshape(p, q, m), self.V.reshape(q, q, m)
        self.tensors, forms_y, forms_x = [], [], []
        for k, (b, (xs, ys)) in enumerate(zip(blocks, self.slices)):
            if b.repeated:
                H = _lift_constants(b.rows)[1]
                self.tensors.append((k, H))
                forms_y.append(np.einsum("jam,kjl,lan->kmn", N4[ys].conj(), H, N4[ys],
                                         optimize=True))
                forms_x.append(np.einsum("jam,kjl,lan->kmn", V4[xs].conj(), H, V4[xs],
                                         optimize=True))
        # the forms of every unknown beyond the S_b: the T_b, then those of the cuts
        self.extra_forms = (np.concatenate(forms_y) if forms_y else np.zeros((0, m, m)),
                            np.concatenate(forms_x) if forms_x else np.zeros((0, m, m)))
        self.n_s = self.nb * q * q
        self.n_base = self.n_s + len(self.extra_forms[0])
        self.trace = np.concatenate([np.tile(trace, self.nb)]
                                    + [q * np.einsum("kaa->k", H).real for _, H in self.tensors])
        # each cut: (block, Hermitian basis of Sigma, W^H V_b, W^H N_b, W)
        self.cuts = []

    def start(self):
        """theta of S_b = I / (nb q) (unit total trace): the D-scaled bound on a balanced M.

        A repeated scalar's share is split between S_b and T_b = I / (10 nb q) (T_b = t I
        weighs its constraint as S_b = t I does), which leaves the bound as it is.
        """
        q, nb = self.q, self.nb
        theta = np.tile(_identity_coefficients(q), (nb, 1)) / (nb * q)
        parts = [theta]
        for b, H in self.tensors:
            theta[b] *= 0.9
            parts.append(_identity_coefficients(H.shape[1]) * 0.1 / (nb * q))
        return np.concatenate([p.ravel() for p in parts])

    def multipliers(self, theta):
        """S_b, shape (nb, q, q)."""
        return np.einsum("ik,kab->iab", theta[:self.n_s].reshape(self.nb, -1), self.H)

    def cut_multipliers(self, theta):
        """Sigma (k x k) of each cut theta holds coefficients for, in the order of the cuts."""
        return self._extra_multipliers(theta)[len(self.tensors):]

    def _extra_multipliers(self, theta):
        """The T_b, then the Sigma of the first cuts (as many as theta has room for)."""
        out, k = [], self.n_s
        for H in [H for _, H in self.tensors] + [cut[1] for cut in self.cuts]:
            if k + len(H) > len(theta):
                break
            out.append(np.einsum("k,kab->ab", theta[k:k + len(H)], H))
            k += len(H)
        return out

    def repeated_weights(self, theta):
        """The whole weight of each repeated scalar b on its (r q) x (r q) entries (row i of
        the block, any k; index i q + k): T_b (x) I_q plus W Sigma W^H of its cuts, by b."""
        extra = self._extra_multipliers(theta)
        out = {b: np.kron(T, np.eye(self.q)) for (b, _), T in zip(self.tensors, extra)}
        for (b, _, _, _, W), Sigma in zip(self.cuts, extra[len(self.tensors):]):
            out[b] = out[b] + W @ Sigma @ W.conj().T
        return out

    def _all_forms(self, theta):
        """(S, [T_b..., Sigma...], N^H D_y N, V^H D_x V) for the multipliers theta holds."""
        q, m = self.q, self.V.shape[1]
        S = self.multipliers(theta)
        N4 = self.N.reshape(self.p, q, m)
        V4 = self.V.reshape(q, q, m)
        A = np.einsum("iam,iab,ibk->mk", N4.conj(), S[self.by], N4, optimize=True)
        B = np.einsum("iam,iab,ibk->mk", V4.conj(), S[self.bx], V4, optimize=True)
        # (y_b^H T_b y_b - beta^2 x_b^H T_b x_b) ||x||^2 and the cuts' terms, linear in
        # their coefficients
        t = theta[self.n_s:]
        A = A + np.tensordot(t, self.extra_forms[0][:len(t)], 1)
        B = B + np.tensordot(t, self.extra_forms[1][:len(t)], 1)
        return (S, self._extra_multipliers(theta), (A + A.conj().T) / 2,
                (B + B.conj().T) / 2)

    def bound_squared(self, theta):
        """Largest generalized eigenvalue of (N^H D_y N, V^H D_x V): the certified beta^2."""
        _, _, A, B = self._all_forms(theta)
        m = A.shape[0]
        return sla.eigh(A, B, eigvals_only=True, subset_by_index=[m - 1, m - 1])[0]

    def barrier(self, theta, tau):
        """log det F_tau + sum_b log det S_b + sum_b log det T_b (and the cuts' log det
        Sigma), or None outside the domain."""
        S, T, A, B = self._all_forms(theta)
        return _log_det_sum([tau * B - A, *S, *T])

    def _s_gradient(self, Ud, Yd, tau):
        """tr(X dF) per S unknown, from the diagonal q x q blocks of V X V^H and N X N^H
        (shapes (..., q, q, q), (..., p, q, q); dF as in :meth:`newton_step`); shape
        (..., nb q^2)."""
        lead = Ud.shape[:-3]
        G = np.stack([tau * Ud[..., xs, :, :].sum(-3) - Yd[..., ys, :, :].sum(-3)
                      for xs, ys in self.slices], axis=-3)
        # tr(G E_k) = sum_ab E_k[a, b] G[b, a]: two gathers from G^T (:func:`_basis_gather`)
        i1, i2, c1, c2 = self.gather
        Gt = np.swapaxes(G, -1, -2).reshape(G.shape[:-2] + (-1,))
        return (c1 * Gt[..., i1] + c2 * Gt[..., i2]).real.reshape(lead + (-1,))

    def _to_basis(self, E):
        """Re(T E T^T) for the map T from entries to basis coefficients (real (q^2, q^2))."""
        i1, i2, c1, c2 = self.gather
        E = c1[:, None] * E[i1] + c2[:, None] * E[i2]
        return (E[:, i1] * c1 + E[:, i2] * c2).real

    def _s_curvature(self, views, Si, tau):
        """Negative Hessian of the barrier over the S unknowns, (nb q^2, nb q^2).

        d^2 log det F = -tr(R dF R dF) with dF = tau V^H dD_x V - N^H dD_y N, i.e.
        -(tau^2 tr(U dD_x U dD_x) - 2 tau tr(W dD_x W^H dD_y) + tr(Y dD_y Y dD_y)), for
        U = V R V^H, Y = N R N^H, W = N R V^H (``views``, :meth:`_product_views`); and
        -tr(S_b^-1 dS_b S_b^-1 dS_b) from log det S_b.  Blocks b1 <= b2 are computed, the
        others mirrored.
        """
        nb, n = self.nb, self.q * self.q
        U4, Y4, Wx, Wy = views
        H = np.empty((nb * n, nb * n))
        for b1, (x1, y1) in enumerate(self.slices):
            for b2, (x2, y2) in enumerate(self.slices[b1:], b1):
                # dS_b1 in D_x with dS_b2 in D_y, and the other way round (transposed)
                E = (tau ** 2 * _entry_products(U4, U4, x1, x2)
                     + _entry_products(Y4, Y4, y1, y2)
                     - tau * (_entry_products(Wx, Wy, x1, y2)
                              + _entry_products(Wx, Wy, x2, y1).T))
                if b1 == b2:
                    E += np.einsum("ij,kl->jkli", Si[b1], Si[b1]).reshape(n, n)
                H[b1 * n:(b1 + 1) * n, b2 * n:(b2 + 1) * n] = block = self._to_basis(E)
                H[b2 * n:(b2 + 1) * n, b1 * n:(b1 + 1) * n] = block.T
        return H

    def _product_views(self, R):
        """U = V R V^H, Y = N R N^H, W = N R V^H and W^H, each with its two entry indices
        split: shapes (q, q, q, q), (p, q, p, q), (p, q, q, q), (q, q, p, q)."""
        p, q, Vh = self.p, self.q, self.V.conj().T
        VR, NR = self.V @ R, self.N @ R
        W = NR @ Vh
        return ((VR @ Vh).reshape(q, q, q, q), (NR @ self.N.conj().T).reshape(p, q, p, q),
                W.reshape(p, q, q, q), W.conj().T.reshape(q, q, p, q))

    def newton_step(self, theta, tau):
        """Gradient of the barrier at theta and its Hessian's negative (positive definite)."""
        S, extra, A, B = self._all_forms(theta)
        R = np.linalg.inv(tau * B - A)
        views = self._product_views(R)
        U4, Y4 = views[:2]
        Si = np.linalg.inv(S)
        x, y = np.arange(self.q), np.arange(self.p)
        grad = (self._s_gradient(U4[x, :, x], Y4[y, :, y], tau)
                + np.einsum("iab,kba->ik", Si, self.H).real.ravel())
        H = self._s_curvature(views, Si, tau)
        if len(theta) > self.n_s:
            grad, H = self._with_extra_terms(grad, H, R, extra, tau, views)
        return grad, (H + H.T) / 2

    def _tensor_sandwiches(self, views, tau):
        """Diagonal q x q blocks of V X_k V^H and N X_k N^H for X_k = R F_k R, each T basis
        matrix k (F_k = tau V_b^H (T_k (x) I) V_b - N_b^H (T_k (x) I) N_b on the block's
        entries), from U = V R V^H, Y = N R N^H, W = N R V^H (``views``): V R F_k R V^H is
        tau U[:, x_b] (T_k (x) I) U[x_b, :] - W^H[:, y_b] (T_k (x) I) W[y_b, :], and so on."""
        q = self.q
        U4, Y4, W4, Wh4 = views

        def sandwich(L4, R4, s):
            # sum_w L4[c, u, s_i, w] R4[s_j, w, c, v] as (c, i j, u, v)
            left = L4[:, :, s].transpose(0, 2, 1, 3)[:, :, None]
            Z = left @ R4[s].transpose(2, 0, 1, 3)[:, None]
            return Z.reshape(len(Z), -1, q, q)

        Ud, Yd = [], []
        for b, Hb in self.tensors:
            xs, ys = self.slices[b]
            Hf = Hb.reshape(len(Hb), -1)
            Ud.append(np.tensordot(Hf, tau * sandwich(U4, U4, xs) - sandwich(Wh4, W4, ys),
                                   ([1], [1])))
            Yd.append(np.tensordot(Hf, tau * sandwich(W4, Wh4, xs) - sandwich(Y4, Y4, ys),
                                   ([1], [1])))
        return np.concatenate(Ud), np.concatenate(Yd)

    def _cut_sandwiches(self, R, tau, n):
        """Diagonal q x q blocks of V X_k V^H and N X_k N^H for X_k = R F_k R, each basis
        matrix k of the first n cuts' Sigma.  F_k = tau P^H E_k P - Q^H E_k Q (P = W^H V_b,
        Q = W^H N_b) has rank 2 k at most, so V X_k V^H = tau (V R P^H) E_k (P R V^H) -
        (V R Q^H) E_k (Q R V^H): a few columns per cut instead of q^2 x q^2 products."""
        q, p = self.q, self.p
        Ud, Yd = [], []
        for _, H, P, Q, _ in self.cuts[:n]:
            k = len(P)
            halves = []
            for L in (self.V, self.N):
                a = (L @ (R @ P.conj().T)).reshape(-1, q, k)     # (c, i, a)
                b = (L @ (R @ Q.conj().T)).reshape(-1, q, k)
                # sum_ab E[a, b] a[c, i, a] conj(a[c, j, b]) for each basis matrix E
                halves.append(tau * np.einsum("cia,kab,cjb->kcij", a, H, a.conj(), optimize=True)
                              - np.einsum("cia,kab,cjb->kcij", b, H, b.conj(), optimize=True))
            Ud.append(halves[0])
            Yd.append(halves[1].reshape(len(H), p, q, q))
        return np.concatenate(Ud), np.concatenate(Yd)

    def _with_extra_terms(self, grad, H, R, extra, tau, views):
        """Gradient and curvature extended by the T_b and the cuts' unknowns (few: r_b^2 per
        repeated scalar, k^2 per cut)."""
        # dF = tau V^H dD_x V - N^H dD_y N for each basis matrix of every T_b
        n_t = self.n_base - self.n_s
        F = tau * self.extra_forms[1][:n_t] - self.extra_forms[0][:n_t]
        G = R @ F
        g_t = [np.einsum("kaa->k", G).real]
        h_tt = (G.reshape(n_t, -1) @ np.swapaxes(G, 1, 2).reshape(n_t, -1).T).real
        cuts = self.cuts[:len(extra) - len(self.tensors)]
        if cuts:
            g_c, h_tc, h_cc = self._cut_terms(cuts, R, G, tau)
            g_t.append(g_c)
            h_tt = np.block([[h_tt, h_tc], [h_tc.T, h_cc]])
        g_t = np.concatenate(g_t)
        # log det of each T_b and Sigma
        k = 0
        bases = [Hb for _, Hb in self.tensors] + [cut[1] for cut in cuts]
        for Hb, X in zip(bases, extra):
            XH = np.linalg.inv(X) @ Hb
            sl = slice(k, k + len(Hb))
            g_t[sl] += np.einsum("kaa->k", XH).real
            h_tt[sl, sl] += np.einsum("kab,lba->kl", XH, XH).real
            k += len(Hb)
        # tr(R dF_S R F_k): the S gradient with R replaced by R F_k R
        h_st = []
        if self.tensors:
            h_st.append(self._s_gradient(*self._tensor_sandwiches(views, tau), tau))
        if cuts:
            h_st.append(self._s_gradient(*self._cut_sandwiches(R, tau, len(cuts)), tau))
        h_st = np.concatenate(h_st).T
        return (np.concatenate([grad, g_t]),
                np.block([[H, h_st], [h_st.T, h_tt]]))

    def _cut_terms(self, cuts, R, G, tau):
        """tr(R F_a), tr(R F_T R F_a) and tr(R F_a R F_b) for the cuts' basis matrices a, b
        (F_a = tau P^H E_a P - Q^H E_a Q) and the T_b's (G = R F_T), from the small
        matrices X R X^H and X R F_T R X^H, X stacking every cut's P and Q."""
        X = np.concatenate([np.concatenate([P, Q]) for _, _, P, Q, _ in cuts])
        RX = R @ X.conj().T
        Z = X @ RX
        ZT = (X @ G) @ RX
        rows, k0 = [], 0
        for _, H, P, _, _ in cuts:
            k = len(P)
            rows.append((H, ((slice(k0, k0 + k), tau), (slice(k0 + k, k0 + 2 * k), -1.0))))
            k0 += 2 * k

        def traces(Y, H, parts):
            # tau tr(E Y[P, P]) - tr(E Y[Q, Q]) for each basis matrix E
            return sum(w * np.einsum("kab,...ba->...k", H, Y[..., sl, sl]) for sl, w in parts)

        g = np.concatenate([traces(Z, H, parts).real for H, parts in rows])
        h_tc = np.concatenate([traces(ZT, H, parts).real for H, parts in rows], axis=-1)

        def pair(Ha, Y1, Hb, Y2):
            # tr(E_a Y1 E_b Y2) for every pair of basis matrices
            A, B = Ha @ Y1, Hb @ Y2
            return A.reshape(len(Ha), -1) @ np.swapaxes(B, 1, 2).reshape(len(Hb), -1).T

        h_cc = np.block([[sum(wa * wb * pair(Ha, Z[sa, sb], Hb, Z[sb, sa])
                              for sa, wa in pa for sb, wb in pb).real
                          for Hb, pb in rows] for Ha, pa in rows])
        return g, h_tc, h_cc

    def add_cuts(self, theta, tau, directions=CUT_DIRECTIONS):
        """Add to every repeated scalar a weight W Sigma W^H that the current one lacks.

        The full weight of a repeated scalar b is any Hermitian Shat >= 0 on its (r q) x (r q)
        entries (row i of the block, any k): sum Shat (y_b (x) x)(y_b (x) x)^H - beta^2 (the
        same with x_b) is >= 0 whenever x_b = delta y_b with |delta| <= 1/beta.  The library's
        T_b (x) I and I (x) S_b are special cases; the whole Shat costs (r q)^2 unknowns.  At
        a centre, R = F_tau^-1 estimates the relaxed tensor, and a direction w with
        w^H (Y_b - tau U_b) w < 0 (Y = N R N^H, U = V R V^H on the block's entries) is one
        along which adding to Shat relaxes F_tau: the ``directions`` most negative such
        eigenvectors form W, and Sigma (k x k, k^2 unknowns) starts small.

        Returns theta extended by the cuts' Sigma (theta itself if no block has such a
        direction).  F_tau may lose its definiteness; a level above the new eigenvalue
        restores it.
        """
        S, extra, A, B = self._all_forms(theta)
        R = np.linalg.inv(tau * B - A)
        q, m = self.q, self.V.shape[1]
        V4, N4 = self.V.reshape(q, q, m), self.N.reshape(self.p, q, m)
        eps = 1e-3 * np.trace(S, axis1=1, axis2=2).real.mean() / q   # Sigma's start, eps I
        identities = []
        for b, _ in self.tensors:
            xs, ys = self.slices[b]
            Vb, Nb = V4[xs].reshape(-1, m), N4[ys].reshape(-1, m)
            L = Nb @ R @ Nb.conj().T - tau * (Vb @ R @ Vb.conj().T)
            w, v = np.linalg.eigh((L + L.conj().T) / 2)
            W = v[:, :directions][:, w[:directions] < -1e-9 * np.abs(w).max()]
            if W.shape[1]:
                self._append_cut(b, W)
                identities.append(_identity_coefficients(W.shape[1]))
        return np.concatenate([theta] + [eps * t for t in identities])

    def _append_cut(self, b, W):
        """Record a cut W Sigma W^H on repeated scalar b and the forms of its Sigma's basis
        matrices."""
        q, m = self.q, self.V.shape[1]
        xs, ys = self.slices[b]
        P = W.conj().T @ self.V.reshape(q, q, m)[xs].reshape(-1, m)
        Q = W.conj().T @ self.N.reshape(self.p, q, m)[ys].reshape(-1, m)
        H = _lift_constants(W.shape[1])[1]
        self.cuts.append((b, H, P, Q, W))
        fy = np.einsum("am,kab,bn->kmn", Q.conj(), H, Q, optimize=True)
        fx = np.einsum("am,kab,bn->kmn", P.conj(), H, P, optimize=True)
        self.extra_forms = (np.concatenate([self.extra_forms[0], fy]),
                            np.concatenate([self.extra_forms[1], fx]))
        self.trace = np.concatenate([self.trace, np.einsum("kaa->k", H).real])

    def positive(self, theta):
        """Whether every S_b, T_b and cut's Sigma theta holds is positive definite."""
        return _log_det_sum([*self.multipliers(theta), *self._extra_multipliers(theta)]) \
            is not None

    def extrapolate(self, previous, centre, lam, steps=(16, 8, 4, 2, 1)):
        """A point beyond ``centre`` on the line from the previous centre, and its bound.

        Consecutive centres lie on a smooth path towards the optimum, so a long step along
        their difference often lowers the bound far more than one more centre would; the
        longest of ``steps`` (multiples of the difference) that keeps the multipliers
        positive and lowers the bound below ``lam`` (the centre's) is taken, else the centre.
        """
        for k in steps:
            theta = centre + k * (centre - previous)
            if self.positive(theta):
                value = self.bound_squared(theta)
                if value < lam:
                    return theta, value
        return centre, lam

    def centre(self, theta, tau, steps=30):
        """Analytic centre of the level set tau (damped Newton, sum of traces fixed)."""
        value = self.barrier(theta, tau)
        for _ in range(steps):
            grad, curvature = self.newton_step(theta, tau)
            try:
                factor = sla.cho_factor(curvature)
            except np.linalg.LinAlgError:
                break
            # Newton step on the plane trace . step = 0
            trace = self.trace[:len(theta)]
            a, b = sla.cho_solve(factor, np.column_stack([grad, trace])).T
            step = a - b * (trace @ a) / (trace @ b)
            decrement = grad @ step
            if not decrement > 0.1:             # an approximate centre is enough
                break
            t = 1.0
            while t > 1e-10:
                trial = self.barrier(theta + t * step, tau)
                if trial is not None and trial >= value + 0.25 * t * decrement:
                    break
                t /= 2
            else:
                break
            theta, value = theta + t * step, trial
        return theta


def _identity_coefficients(k):
    """Coefficients of I_k in the Hermitian basis of :func:`_hermitian_basis`."""
    return np.r_[np.ones(k), np.zeros(k * k - k)]


def _refine_point(M, blocks, start, accept, target, max_centres):
    """Method of centres on a D-balanced M, with an extrapolation after each centre
    (:meth:`_LiftedCertificate.extrapolate`) and, for repeated scalars, cuts of their full
    weight (:meth:`_LiftedCertificate.add_cuts`) after :data:`CENTRES_BEFORE_CUT` centres,
    when a centre closes less than :data:`STALL` of the distance still to the target, or at
    convergence, :data:`MAX_CUTS` rounds at most.

    ``start`` is None or (theta, cuts) of a neighbouring point, cuts a list of (block, W)
    that theta weighs: with those cuts it is kept if its bound is <= accept; otherwise the
    centres start, without those cuts, from the better of its S_b and T_b and S_b = I.
    Returns (certified bound, theta, certificate); theta may hold
    fewer cuts than the certificate has (those added after it).  A start whose bound is
    <= accept is kept as it is; otherwise the centres go on until the bound is <= target
    (< accept, so that the next frequency's start has room).
    """
    cert = _LiftedCertificate(M, blocks)
    if start is not None and start[1]:
        # the neighbour's multipliers with its cuts, kept if they are good enough here
        theta0, cuts = start
        for b, W in cuts:                   # any W gives a valid weight at this matrix too
            cert._append_cut(b, W)
        value = cert.bound_squared(theta0)
        if value <= accept ** 2:
            return np.sqrt(value), theta0, cert
        # otherwise centre without them: stale cuts slow the centres down several-fold
        cert = _LiftedCertificate(M, blocks)
        start = (theta0[:cert.n_base], [])
    starts = [cert.start()] + ([start[0]] if start is not None else [])
    values = [cert.bound_squared(t) for t in starts]
    k = int(np.argmin(values))
    theta, lam = starts[k], values[k]
    best, best_theta = lam, theta
    if best <= accept ** 2:
        return np.sqrt(best), best_theta, cert
    tau = lam * 1.01
    last_centre = last_lam = None
    since_cut = rounds = 0
    for _ in range(max_centres):
        if best <= target ** 2:
            break
        tau = lam + 0.5 * (tau - lam)            # halve the distance to the last eigenvalue
        centre = cert.centre(theta, tau)
        theta, lam = centre, cert.bound_squared(centre)
        converged = not tau - lam > 1e-9 * lam   # the level has met the eigenvalue
        if last_centre is not None and not converged:
            theta, beyond = cert.extrapolate(last_centre, centre, lam)
            tau, lam = tau + beyond - lam, beyond   # the same margin above the new eigenvalue
        # stalled: the last centre closed little of the distance still to go
        stalled = last_lam is not None and last_lam - lam < STALL * (lam - target ** 2)
        last_centre, last_lam = centre, lam
        if lam < best:
            best, best_theta = lam, theta
        since_cut += 1
        if (best > target ** 2 and rounds < MAX_CUTS and cert.tensors
                and (converged or stalled or since_cut >= CENTRES_BEFORE_CUT)):
            rounds += 1
            grown = cert.add_cuts(theta, tau)
            if len(grown) > len(theta):
                # a new, larger problem: restart the level a little above its eigenvalue
                theta, lam = grown, cert.bound_squared(grown)
                tau, last_centre, last_lam, since_cut = lam * 1.01, None, None, 0
                continue
        if converged:
            break
    return np.sqrt(best), best_theta, cert


def lifted_upper_bound(M, blocks, upper, lower, Dl, Dr, gap, *, max_centres=60):
    """Tighten the D-scaled upper bound of mu for a complex structure where its gap is wide.

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
        Matrices, one per frequency.
    blocks : tuple of Block
        Complex blocks (full or repeated scalar) fitting M, with at most
        :data:`MAX_LIFTED_UNKNOWNS` unknowns (:func:`lifted_unknowns`).
    upper, lower : ndarray, shape (nf,)
        D-scaled upper bound and a lower bound of mu at every frequency.
    Dl, Dr : ndarray, shapes (nf, p, p) and (nf, q, q)
        The D-scaled bound's scalings (upper = sigma_max(Dl M Dr^-1)).
    gap : float
        Points whose relative gap (upper - lower) / upper exceeds ``gap`` are refined:
        the previous frequency's certificate is kept where it brings the gap within
        ``gap``; otherwise the method of centres runs until the gap is at most
        0.9 gap (a little room for the next frequency's start) or it has converged.
    max_centres : int, optional
        Cap on the analytic centres per point.

    Returns
    -------
    ndarray, shape (nf,)
        Upper bounds, each the smaller of the given one and its certificate's.

    Notes
    -----
    The certificate is computed for Dl M Dr^-1, whose mu is M's.  Neighbouring
    frequencies usually share a certificate: each refined point starts from the previous
    refined point's multipliers where they certify a smaller bound than S_b = I.
    """
    upper = np.array(upper, float)
    start = None
    previous = -2
    wide = np.nonzero(upper - lower > gap * upper)[0]
    # on the D-balanced matrix (same mu) the certificate starts at the D-scaled bound
    # and its eigenproblem stays well conditioned however M is scaled
    for k, balanced in zip(wide, scaled_matrix(M[wide], Dl[wide], Dr[wide])):
        bound, th, cert = _refine_point(balanced, blocks, start if previous == k - 1 else None,
                                        lower[k] / (1 - gap), lower[k] / (1 - 0.9 * gap),
                                        max_centres)
        if bound < upper[k]:
            upper[k] = bound
        # the next frequency may reuse this one's multipliers and the cuts they weigh
        used = len(cert.cut_multipliers(th))
        start, previous = (th, [(cut[0], cut[4]) for cut in cert.cuts[:used]]), k
    return upper
