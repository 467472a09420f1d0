"""A tighter upper bound of mu for complex scalar blocks: the symmetric-lift certificate.

For n complex scalar blocks (each 1 x 1), mu(M) >= beta holds exactly when some
x != 0 has |(M x)_i| >= beta |x_i| for every i, i.e. q_i(x) = |(M x)_i|^2 - beta^2 |x_i|^2
>= 0 for all i.  The D-scaled bound certifies mu < beta with weights d_i >= 0 such
that sum_i d_i q_i(x) < 0 for every x != 0.  This module certifies it with
quadratic-form multipliers instead: positive semidefinite n x n matrices S_i with

    sum_i q_i(x) x^H S_i x < 0   for every x != 0,

which rules out x with all q_i(x) >= 0.  The left side is a Hermitian form in the
symmetric tensor z = x (x) x; demanding it negative on all symmetric tensors is the
linear matrix inequality

    F(S) = beta^2 P^T D P - N^H D N > 0,   D = blockdiag(S_1, ..., S_n),

with P an orthonormal basis of the symmetric tensors of C^n (x) C^n and
N = (M (x) I) P.  S_i = d_i I gives back the D-scaled bound, so the certificate is
never weaker; on random 8-scalar matrices it closes most of the D-scaled bound's gap
(``benchmarks/README.md``).  The smallest certified beta is the largest generalized
eigenvalue of (N^H D N, P^T D P), minimised over S by the method of centres: the
analytic centre of {S : F_tau(S) > 0, S_i > 0, sum_i tr S_i = 1} for a level tau that
moves down towards the eigenvalue at the previous centre.  Every returned bound is the
eigenvalue of the S it came from, recomputed from scratch, so it is a certificate
whatever the iteration did.  Derivation in ``docs/robust.md``.

It costs about n^3 unknowns (512 for n = 8) and about 10 ms per Newton step,
against about 1 ms per frequency for the D-scaled bound, so :func:`mussv` applies it
only where asked (``refine``) and only where the gap exceeds the requested tolerance.
"""

from functools import lru_cache

import numpy as np
import scipy.linalg as sla
from scipy import sparse

__all__ = ["lifted_scalar_upper_bound", "MAX_LIFTED_SCALARS"]

#: the Newton system has n^3 unknowns; beyond 10 scalars (1,000) a step costs seconds
MAX_LIFTED_SCALARS = 10


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
    """What the certificate needs for n scalars whatever M is (shared, not to be modified):
    the symmetric basis P, the Hermitian basis H, the sparse map from matrix entries to
    basis coefficients (one or two per basis matrix: turns a Hessian over entries into one
    over theta) and the trace of each unknown's basis matrix."""
    H = _hermitian_basis(n)
    return (_symmetric_basis(n), H, sparse.csr_matrix(H.reshape(n * n, n * n)),
            np.tile(np.einsum("kaa->k", H).real, n))


class _LiftedCertificate:
    """The matrices of the certificate for one M (n x n) and its Newton derivatives.

    The unknowns theta (n^3 reals) hold S_i = sum_k theta[i, k] H_k.
    """

    def __init__(self, M):
        n = self.n = M.shape[0]
        self.P, self.H, self.to_basis, self.trace = _lift_constants(n)
        self.N = np.kron(M, np.eye(n)) @ self.P

    def start(self):
        """theta of S_i = I / n^2 (unit total trace): the bound is sigma_max(M)."""
        n = self.n
        theta = np.zeros((n, n * n))
        theta[:, :n] = 1.0 / n ** 2
        return theta.ravel()

    def multipliers(self, theta):
        return np.einsum("ik,kab->iab", theta.reshape(self.n, -1), self.H)

    def _forms(self, S):
        """(N^H D N, P^T D P) for D = blockdiag(S)."""
        n, m = self.n, self.P.shape[1]
        N4 = self.N.reshape(n, n, m)
        P4 = self.P.reshape(n, n, m)
        A = np.einsum("iam,iab,ibk->mk", N4.conj(), S, N4, optimize=True)
        B = np.einsum("iam,iab,ibk->mk", P4, S, P4, optimize=True)
        return A, B

    def bound_squared(self, theta):
        """Largest generalized eigenvalue of (N^H D N, P^T D P): the certified beta^2."""
        A, B = self._forms(self.multipliers(theta))
        m = A.shape[0]
        return sla.eigh(A, B, eigvals_only=True, subset_by_index=[m - 1, m - 1])[0]

    def barrier(self, theta, tau):
        """log det F_tau(S) + sum_i log det S_i, or None outside the domain."""
        S = self.multipliers(theta)
        A, B = self._forms(S)
        try:
            return sum(2 * np.log(np.linalg.cholesky(X).diagonal().real).sum()
                       for X in [tau * B - A, *S])
        except np.linalg.LinAlgError:
            return None

    def _pair_trace(self, E):
        """Hessian over theta from E[(d, a), i, j, (b, c)] = coefficient of
        Delta_i[d, a] Delta_j[b, c] in a quadratic form of the block-diagonal Delta."""
        n, T = self.n, self.to_basis
        n2 = n * n
        E = (T @ E.reshape(n2, -1)).reshape(-1, n2)
        E = (T @ E.T).T.reshape(n2, n, n, n2)       # [k, i, j, l]
        H = E.real.transpose(1, 0, 2, 3).reshape(n ** 3, n ** 3)
        return (H + H.T) / 2

    def newton_step(self, theta, tau):
        """Gradient of the barrier at theta and its Hessian's negative (positive definite)."""
        n = self.n
        S = self.multipliers(theta)
        A, B = self._forms(S)
        R = np.linalg.inv(tau * B - A)
        U = self.P @ R @ self.P.T
        V = self.N @ R @ self.N.conj().T
        W = self.N @ R @ self.P.T
        Si = np.linalg.inv(S)
        G = (tau * U - V).reshape(n, n, n, n)[np.arange(n), :, np.arange(n), :] + Si
        grad = np.einsum("iab,kba->ik", G, self.H).real.ravel()
        # d^2 log det F = -tr(R dF R dF) with dF = tau P^T dD P - N^H dD N, i.e.
        # -tr(tau^2 U dD U dD - 2 tau W dD W^H dD + V dD V dD); each tr(X dD Y dD) has the
        # coefficient X_ij[a, b] Y_ji[c, d] on dS_i[d, a] dS_j[b, c]
        X = np.stack([tau ** 2 * U, -2 * tau * W, V]).reshape(3, n, n, n, n)
        Y = np.stack([U, W.conj().T, V]).reshape(3, n, n, n, n)
        E = np.einsum("tiajb,tjcid->daijbc", X, Y, optimize=True)
        # and -tr(S_i^-1 dS_i S_i^-1 dS_i) from the log det S_i, on the diagonal blocks only
        i = np.arange(n)
        E[:, :, i, i] += np.einsum("iab,icd->daibc", Si, Si)
        return grad, self._pair_trace(E)

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


def _refine_point(M, theta0, accept, target, max_centres):
    """Method of centres on a D-balanced M, from the better of S_i = I and theta0.

    Returns (certified bound, theta).  A start whose bound is <= accept is kept as it
    is; otherwise the centres go on until the bound is <= target (< accept, so that
    the next frequency's start has room).
    """
    cert = _LiftedCertificate(M)
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


def lifted_scalar_upper_bound(M, upper, lower, d, gap, *, max_centres=60):
    """Tighten the D-scaled upper bound of mu for complex scalar blocks where its gap is wide.

    Parameters
    ----------
    M : ndarray, shape (nf, n, n)
        Matrices, one per frequency, with n <= :data:`MAX_LIFTED_SCALARS` scalar blocks.
    upper, lower : ndarray, shape (nf,)
        D-scaled upper bound and a lower bound of mu at every frequency.
    d : ndarray, shape (nf, n)
        The D-scaled bound's scalings (upper = sigma_max(diag(d) M diag(d)^-1)).
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
    The certificate is computed for diag(d) M diag(d)^-1, whose mu is M's.  Neighbouring
    frequencies usually share a certificate: each refined point starts from the previous
    refined point's multipliers where they certify a smaller bound than S_i = I.
    """
    upper = np.array(upper, float)
    theta = None
    previous = -2
    for k in np.nonzero(upper - lower > gap * upper)[0]:
        # on the D-balanced matrix (same mu) the certificate starts at the D-scaled bound
        # and its eigenproblem stays well conditioned however M is scaled
        balanced = d[k][:, None] * M[k] / d[k][None, :]
        bound, th = _refine_point(balanced, theta if previous == k - 1 else None,
                                  lower[k] / (1 - gap), lower[k] / (1 - gap / 2), max_centres)
        if bound < upper[k]:
            upper[k] = bound
        theta, previous = th, k
    return upper
