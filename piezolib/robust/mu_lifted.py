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
towards the eigenvalue at the previous centre.  Every returned bound is the eigenvalue of
the S it came from, recomputed from scratch, so it is a certificate whatever the iteration
did.  Derivation in ``docs/robust.md``.

It costs nb q^2 unknowns (512 for 8 scalars, 726 for six blocks on q = 11) and 15-40 ms
per Newton step, against about 1 ms per frequency for the D-scaled bound, so :func:`mussv`
applies it only where asked (``refine``) and only where the gap exceeds the requested
tolerance.
"""

from functools import lru_cache

import numpy as np
import scipy.linalg as sla
from scipy import sparse

from piezolib.robust.blocks import block_slices
from piezolib.robust.mu_upper import scaled_matrix

__all__ = ["lifted_upper_bound", "lifted_unknowns", "MAX_LIFTED_UNKNOWNS"]

#: the Newton system has nb q^2 unknowns; beyond about 1,200 a step costs a tenth of a second
MAX_LIFTED_UNKNOWNS = 1200


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


@lru_cache(maxsize=None)
def _lift_constants(n):
    """What the certificate needs for q = n whatever M is (shared, not to be modified): the
    symmetric basis P, the Hermitian basis H, the sparse map from matrix entries to basis
    coefficients (one or two per basis matrix: turns a Hessian over entries into one over
    theta) and the trace of each basis matrix."""
    H = _hermitian_basis(n)
    return (_symmetric_basis(n), H, sparse.csr_matrix(H.reshape(n * n, n * n)),
            np.einsum("kaa->k", H).real)


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


class _LiftedCertificate:
    """The matrices of the certificate for one M (p x q) and its Newton derivatives.

    The unknowns theta hold S_b = sum_k theta[b, k] H_k (nb q^2 reals), then the entries of
    each repeated scalar's T_b in the r x r Hermitian basis (r^2 reals each).
    """

    def __init__(self, M, blocks):
        p, q = M.shape
        self.p, self.q, self.nb = p, q, len(blocks)
        self.V, self.H, self.to_basis, trace = _lift_constants(q)
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
        for b, (xs, ys) in zip(blocks, block_slices(blocks)):
            if b.repeated:
                H = _lift_constants(b.rows)[1]
                self.tensors.append((xs.start, H))
                forms_y.append(np.einsum("jam,kjl,lan->kmn", N4[ys].conj(), H, N4[ys],
                                         optimize=True))
                forms_x.append(np.einsum("jam,kjl,lan->kmn", V4[xs].conj(), H, V4[xs],
                                         optimize=True))
        self.tensor_forms = (np.concatenate(forms_y) if forms_y else np.zeros((0, m, m)),
                             np.concatenate(forms_x) if forms_x else np.zeros((0, m, m)))
        self.n_s = self.nb * q * q
        self.trace = np.concatenate([np.tile(trace, self.nb)]
                                    + [q * np.einsum("kaa->k", H).real for _, H in self.tensors])

    def start(self):
        """theta of S_b = I / (nb q) (unit total trace): the D-scaled bound on a balanced M.

        A repeated scalar's share is split between S_b and T_b = I / (10 nb q) (T_b = t I
        weighs its constraint as S_b = t I does), which leaves the bound as it is.
        """
        q, nb = self.q, self.nb
        theta = np.zeros((nb, q * q))
        theta[:, :q] = 1.0 / (nb * q)
        parts = [theta]
        for x0, H in self.tensors:
            theta[self.bx[x0], :q] *= 0.9
            t = np.zeros(len(H))
            t[:H.shape[1]] = 0.1 / (nb * q)
            parts.append(t)
        return np.concatenate([p.ravel() for p in parts])

    def multipliers(self, theta):
        """S_b, shape (nb, q, q)."""
        return np.einsum("ik,kab->iab", theta[:self.n_s].reshape(self.nb, -1), self.H)

    def tensor_multipliers(self, theta):
        """T_b (r_b x r_b) of the repeated scalars, in the order of the structure."""
        out, k = [], self.n_s
        for _, H in self.tensors:
            out.append(np.einsum("k,kab->ab", theta[k:k + len(H)], H))
            k += len(H)
        return out

    def _all_forms(self, theta):
        """(S, T, N^H D_y N, V^H D_x V) for the multipliers theta holds."""
        q, m = self.q, self.V.shape[1]
        S = self.multipliers(theta)
        N4 = self.N.reshape(self.p, q, m)
        V4 = self.V.reshape(q, q, m)
        A = np.einsum("iam,iab,ibk->mk", N4.conj(), S[self.by], N4, optimize=True)
        B = np.einsum("iam,iab,ibk->mk", V4.conj(), S[self.bx], V4, optimize=True)
        # (y_b^H T_b y_b - beta^2 x_b^H T_b x_b) ||x||^2, linear in T's coefficients
        t = theta[self.n_s:]
        A = A + np.tensordot(t, self.tensor_forms[0], 1)
        B = B + np.tensordot(t, self.tensor_forms[1], 1)
        return (S, self.tensor_multipliers(theta), (A + A.conj().T) / 2,
                (B + B.conj().T) / 2)

    def bound_squared(self, theta):
        """Largest generalized eigenvalue of (N^H D_y N, V^H D_x V): the certified beta^2."""
        _, _, A, B = self._all_forms(theta)
        m = A.shape[0]
        return sla.eigh(A, B, eigvals_only=True, subset_by_index=[m - 1, m - 1])[0]

    def barrier(self, theta, tau):
        """log det F_tau + sum_b log det S_b + sum_b log det T_b, or None outside the domain."""
        S, T, A, B = self._all_forms(theta)
        try:
            return sum(2 * np.log(np.linalg.cholesky(X).diagonal().real).sum()
                       for X in [tau * B - A, *S, *T])
        except np.linalg.LinAlgError:
            return None

    def _pair_form(self, X, Y, rows1, rows2):
        """tr(X dD1 Y dD2) as coefficients K[b1, (j, k), b2, (l, i)] of dS_b1[j, k] dS_b2[l, i].

        dD1 = sum_a e_a e_a^H (x) dS_rows1[a] (likewise dD2), so the coefficient sums
        X[c, i, a, j] Y[a, k, c, l] over the entries a of block b1 and c of block b2.
        """
        q, nb = self.q, self.nb
        X4 = X.reshape(len(rows2), q, len(rows1), q)
        Y4 = Y.reshape(len(rows1), q, len(rows2), q)
        K = np.empty((nb, q * q, nb, q * q), complex)
        for b1 in range(nb):
            a = rows1 == b1
            for b2 in range(nb):
                c = rows2 == b2
                Xr = X4[c][:, :, a].transpose(2, 0, 3, 1).reshape(-1, q * q)   # [ac, ji]
                Yr = Y4[a][:, :, c].transpose(0, 2, 1, 3).reshape(-1, q * q)   # [ac, kl]
                E = (Xr.T @ Yr).reshape(q, q, q, q).transpose(0, 2, 3, 1)
                K[b1, :, b2, :] = E.reshape(q * q, q * q)
        return K

    def _s_gradient(self, U, Y, tau):
        """tr(X dF) per S unknown, from U = V X V^H and Y = N X N^H (dF as in newton_step)."""
        p, q = self.p, self.q
        G = np.zeros((self.nb, q, q), complex)
        np.add.at(G, self.bx, tau * U.reshape(q, q, q, q)[np.arange(q), :, np.arange(q), :])
        np.add.at(G, self.by, -Y.reshape(p, q, p, q)[np.arange(p), :, np.arange(p), :])
        return np.einsum("iab,kba->ik", G, self.H).real.ravel()

    def newton_step(self, theta, tau):
        """Gradient of the barrier at theta and its Hessian's negative (positive definite)."""
        q, nb, T = self.q, self.nb, self.to_basis
        S, Ts, A, B = self._all_forms(theta)
        R = np.linalg.inv(tau * B - A)
        U = self.V @ R @ self.V.conj().T
        V = self.N @ R @ self.N.conj().T
        W = self.N @ R @ self.V.conj().T
        Si = np.linalg.inv(S)
        grad = self._s_gradient(U, V, tau) + np.einsum("iab,kba->ik", Si, self.H).real.ravel()
        # d^2 log det F = -tr(R dF R dF) with dF = tau V^H dD_x V - N^H dD_y N, i.e.
        # -(tau^2 tr(U dD_x U dD_x) - 2 tau tr(W dD_x W^H dD_y) + tr(V dD_y V dD_y))
        K = (tau ** 2 * self._pair_form(U, U, self.bx, self.bx)
             - 2 * tau * self._pair_form(W, W.conj().T, self.bx, self.by)
             + self._pair_form(V, V, self.by, self.by))
        # and -tr(S_b^-1 dS_b S_b^-1 dS_b) from the log det S_b
        for b in range(nb):
            K[b, :, b, :] += np.einsum("ij,kl->jkli", Si[b], Si[b]).reshape(q * q, q * q)
        # entries to theta on both sides: T[k, (j, k')] = H_k[j, k']
        K = np.stack([T @ K[b].reshape(q * q, -1) for b in range(nb)])
        K = K.reshape(nb * q * q, nb, q * q)
        K = np.stack([(T @ K[:, b].T).T for b in range(nb)], axis=1)
        H = K.reshape(nb * q * q, nb * q * q).real
        if self.tensors:
            grad, H = self._with_tensor_terms(grad, H, R, Ts, tau)
        return grad, (H + H.T) / 2

    def _with_tensor_terms(self, grad, H, R, Ts, tau):
        """Gradient and curvature extended by the T_b unknowns (few: r_b^2 per scalar)."""
        # dF = tau V^H dD_x V - N^H dD_y N for each basis matrix of every T_b
        F = tau * self.tensor_forms[1] - self.tensor_forms[0]
        G = R @ F
        n = len(F)
        g_t = np.einsum("kaa->k", G).real
        h_tt = (G.reshape(n, -1) @ np.swapaxes(G, 1, 2).reshape(n, -1).T).real
        k = 0
        for (_, Hb), Tb in zip(self.tensors, Ts):
            Ti = np.linalg.inv(Tb)
            TH = Ti @ Hb
            sl = slice(k, k + len(Hb))
            g_t[sl] += np.einsum("kaa->k", TH).real
            h_tt[sl, sl] += np.einsum("kab,lba->kl", TH, TH).real
            k += len(Hb)
        # tr(R dF_S R F_k): the S gradient with R replaced by R F_k R
        X = G @ R
        h_st = np.array([self._s_gradient(self.V @ x @ self.V.conj().T,
                                          self.N @ x @ self.N.conj().T, tau) for x in X]).T
        return (np.concatenate([grad, g_t]),
                np.block([[H, h_st], [h_st.T, h_tt]]))

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
            a, b = sla.cho_solve(factor, np.column_stack([grad, self.trace])).T
            step = a - b * (self.trace @ a) / (self.trace @ b)
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


def _refine_point(M, blocks, theta0, accept, target, max_centres):
    """Method of centres on a D-balanced M, from the better of S_b = I and theta0.

    Returns (certified bound, theta).  A start whose bound is <= accept is kept as it
    is; otherwise the centres go on until the bound is <= target (< accept, so that
    the next frequency's start has room).
    """
    cert = _LiftedCertificate(M, blocks)
    starts = [cert.start()] + ([theta0] if theta0 is not None else [])
    values = [cert.bound_squared(t) for t in starts]
    k = int(np.argmin(values))
    theta, lam = starts[k], values[k]
    best, best_theta = lam, theta
    if best <= accept ** 2:
        return np.sqrt(best), best_theta
    tau = lam * 1.01
    for _ in range(max_centres):
        if best <= target ** 2:
            break
        tau = lam + 0.5 * (tau - lam)            # halve the distance to the last eigenvalue
        theta = cert.centre(theta, tau)
        lam = cert.bound_squared(theta)
        if lam < best:
            best, best_theta = lam, theta
        if not tau - lam > 1e-9 * lam:          # the level has met the eigenvalue: converged
            break
    return np.sqrt(best), best_theta


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
        ``gap``; otherwise the method of centres runs until the gap is at most gap / 2
        or it has converged.
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
    theta = None
    previous = -2
    wide = np.nonzero(upper - lower > gap * upper)[0]
    # on the D-balanced matrix (same mu) the certificate starts at the D-scaled bound
    # and its eigenproblem stays well conditioned however M is scaled
    for k, balanced in zip(wide, scaled_matrix(M[wide], Dl[wide], Dr[wide])):
        bound, th = _refine_point(balanced, blocks, theta if previous == k - 1 else None,
                                  lower[k] / (1 - gap), lower[k] / (1 - gap / 2), max_centres)
        if bound < upper[k]:
            upper[k] = bound
        theta, previous = th, k
    return upper
