"""The central H-infinity controller at one gamma, and the stabilising Riccati solutions it needs.

The formulas of Zhou, Doyle and Glover (1996, Ch. 17) on a plant that
:mod:`piezolib.robust.hinf` has scaled, balanced, regularised and normalised
(D12 = [0; I], D21 = [0, I]): the two Riccati equations, each solved from the
Hamiltonian pencil (or by scipy, then refined by Newton steps), their
positive-semidefiniteness and coupling conditions, and the controller.
:func:`~piezolib.robust.hinf.hinfsyn`'s gamma-iteration calls
:func:`_central` once or twice per trial.  Private to the H-infinity
synthesis: nothing here checks its arguments.
"""

import warnings

import numpy as np
import scipy.linalg as la

__all__ = []

_AXIS_REL_TOL = 1e-9  # Hamiltonian eigenvalue on the axis: |Re| <= tol |lambda| ...
_ERR_FACTOR = 10.0    # ... or |Re lambda| <= factor * eps * ||A||
_PSD_TOL = 1e-8       # relative tolerance of X >= 0, Y >= 0
_PENCIL_ZERO_TOL = 100 * np.finfo(float).eps  # Hamiltonian: error bound / ||pencil||
_RESIDUAL_TOL = 1e-5  # relative Riccati residual accepted


def _eig_errors(A):
    """Eigenvalues of A and the backward-error scale eps ||balance(A)||_1 of each.

    (First-order bounds with eigenvalue condition numbers were tried and
    found far too pessimistic on clustered closed-loop poles.)
    """
    if A.shape[0] == 0:
        return np.zeros(0, complex), np.zeros(0)
    balanced = la.matrix_balance(A, permute=False)[0]   # what LAPACK's eig works on
    lam = np.linalg.eigvals(A)
    return lam, np.full(lam.shape, np.finfo(float).eps * np.linalg.norm(balanced, 1))


def _marginal(lam, err):
    """True where eigenvalues ``lam`` are not clearly in the open left half-plane.

    Judged relative to each eigenvalue's own magnitude (Re >= -tol |lambda|)
    and to the rounding scale ``err`` (:func:`_eig_errors`) -- never relative to
    the largest eigenvalue, which flagged stable weight poles 1e10 below the
    fastest pole as marginal.
    """
    lam = np.atleast_1d(lam)
    return (lam.real >= -_AXIS_REL_TOL * np.abs(lam)) | (np.abs(lam.real) <= _ERR_FACTOR * err)


def _riccati(A, B, Q, R, S):
    """Stabilising X of A'X + XA - (XB + S) R^-1 (B'X + S') + Q = 0, R indefinite.

    Extended Hamiltonian pencil (van Dooren 1981), compressed by a QR step
    and ordered by QZ; raises ``LinAlgError`` when the pencil has eigenvalues
    on (or numerically at) the imaginary axis or the solution is not
    symmetric.  (scipy's ``solve_continuous_are`` does the same but spent
    10x longer here in multithreaded triangular solves.)
    """
    n, m = B.shape
    # symplectic diagonal scaling x = T x~ (powers of two), chosen by balancing
    # the pencil's magnitudes; X = T^-1 X~ T^-1
    H = np.block([[A, np.zeros((n, n)), B], [-Q, -A.T, -S], [S.T, B.T, R]])
    mag = np.abs(H) + np.abs(np.eye(2 * n + m))
    _, (sca, _) = la.matrix_balance(mag, permute=False, separate=True)
    t = np.exp2(np.round((np.log2(sca[:n]) - np.log2(sca[n:2 * n])) / 2))
    A, B, Q, S = A * t[None, :] / t[:, None], B / t[:, None], Q * t[:, None] * t[None, :], \
        S * t[:, None]
    H = np.block([[A, np.zeros((n, n)), B], [-Q, -A.T, -S], [S.T, B.T, R]])
    q, _ = la.qr(H[:, 2 * n:])
    Hc = (q.T @ H)[m:, :2 * n]
    Jc = q.T[m:, :2 * n]
    _, _, alpha, beta, _, Z = la.ordqz(Hc, Jc, sort="lhp", output="real")
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = alpha / beta
    finite = np.isfinite(lam)
    # On the axis: purely oscillatory relative to its own size, or within its
    # error bound of it.  (A threshold relative to the largest eigenvalue
    # flagged stable weight poles 1e10 below the fastest one.)
    lam = lam[finite]
    err = np.full(lam.shape, _PENCIL_ZERO_TOL * np.linalg.norm(Hc, 1))
    on_axis = _marginal(lam, err) & _marginal(-lam, err)
    if np.count_nonzero(lam.real < 0) != n or np.any(on_axis):
        raise la.LinAlgError("Hamiltonian pencil has eigenvalues on the imaginary axis")
    Z11, Z21 = Z[:n, :n], Z[n:, :n]
    if np.linalg.cond(Z11) > 1 / (100 * np.finfo(float).eps):
        raise la.LinAlgError("stable subspace is not a graph (Z11 singular)")
    X = np.linalg.solve(Z11.T, Z21.T).T
    # symmetrised, refined by Newton steps, then judged by the residual of the
    # (scaled) equation relative to the size of its terms (an absolute symmetry
    # test failed on X ~ 0; eigenvalues spread over 1e10 leave errors that made
    # X or Y spuriously indefinite before refinement)
    X = _newton_refine(A, B, Q, R, S, (X + X.T) / 2)
    res, size = _riccati_residual(A, B, Q, R, S, X)
    if res > _RESIDUAL_TOL * size:
        raise la.LinAlgError(f"Riccati residual {res / size:.2g} (relative)")
    return X / t[:, None] / t[None, :]


def _riccati_residual(A, B, Q, R, S, X):
    """(||residual||_1, size of the largest term) of the Riccati equation at X."""
    XBS = X @ B + S
    quad = XBS @ np.linalg.solve(R, XBS.T)
    res = A.T @ X + X @ A + Q - quad
    size = max(np.linalg.norm(A.T @ X, 1), np.linalg.norm(Q, 1), np.linalg.norm(quad, 1),
               np.finfo(float).tiny)
    return float(np.linalg.norm(res, 1)), float(size)


def _newton_refine(A, B, Q, R, S, X, steps=3):
    """Kleinman-Newton steps from X: with F = R^-1 (B'X + S') and A_F = A - B F,
    X+ solves A_F' X+ + X+ A_F + Q + F'RF - SF - F'S' = 0.  A step is kept only
    while A_F is stable and the residual decreases."""
    best, (res, _) = X, _riccati_residual(A, B, Q, R, S, X)
    for _ in range(steps):
        F = np.linalg.solve(R, B.T @ best + S.T)
        AF = A - B @ F
        if np.linalg.eigvals(AF).real.max() >= 0:
            break
        rhs = Q + F.T @ R @ F - S @ F - F.T @ S.T
        try:
            # near-axis modes (slow weight poles) make scipy warn that it perturbs the
            # equation; the step is judged by its residual below, so the warning is noise
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                Xn = la.solve_continuous_lyapunov(AF.T, -(rhs + rhs.T) / 2)
        except (la.LinAlgError, ValueError):
            break
        Xn = (Xn + Xn.T) / 2
        res_n, _ = _riccati_residual(A, B, Q, R, S, Xn)
        if not np.isfinite(res_n) or res_n >= res:
            break
        best, res = Xn, res_n
    return best


def _stabilising_riccati(A, B, Q, R, S, scipy_first=False):
    """(X, '') with X the stabilising solution of :func:`_riccati`'s equation, or (None, reason).

    Where the pencil solution fails or A - B R^-1 (B'X + S') is not stable,
    scipy's balanced ``solve_continuous_are`` gives a second opinion: on the
    Lundstrom-scaled distillation K-step (a weight pole 1e9 below the fastest
    pole) the pencil route called gamma = 2.0 unstabilising and gamma = 1.0
    "on the axis" where the optimum is 0.973, and scipy's solutions stabilise.
    ``scipy_first`` asks scipy first and the pencil second.
    """
    def stabilising(X):
        K = np.linalg.solve(R, B.T @ X + S.T)
        return A.shape[0] == 0 or np.linalg.eigvals(A - B @ K).real.max() < 0

    def pencil():
        try:
            X = _riccati(A, B, Q, R, S)
        except (la.LinAlgError, ValueError):
            return None, "no stabilising Riccati solution"
        return (X, "") if stabilising(X) else (None, "Riccati solution not stabilising")

    def scipy():
        try:
            X = la.solve_continuous_are(A, B, Q, R, s=S, balanced=True)
        except (la.LinAlgError, ValueError):
            return None, "no stabilising Riccati solution"
        X = (X + X.T) / 2
        res, size = _riccati_residual(A, B, Q, R, S, X)
        if np.all(np.isfinite(X)) and res <= _RESIDUAL_TOL * size and stabilising(X):
            return X, ""
        return None, "no stabilising Riccati solution"

    first, second = (scipy, pencil) if scipy_first else (pencil, scipy)
    X, reason = first()
    if X is None:
        X, other = second()
        # where both fail, the pencil's reason is the more specific one
        reason = "" if X is not None else (other if scipy_first else reason)
    return X, reason


def _central(pl, gamma, scipy_first=False):
    """Central controller of the normalised plant at ``gamma``, or a failure reason.

    ``scipy_first``: solve the Riccati equations with scipy first (see
    :func:`_stabilising_riccati`)."""
    A, B1, B2, C1, C2, D11 = pl.A, pl.B1, pl.B2, pl.C1, pl.C2, pl.D11
    n, m1, m2 = A.shape[0], B1.shape[1], B2.shape[1]
    p1, p2 = C1.shape[0], C2.shape[0]
    q1, r1 = p1 - m2, m1 - p2
    g2 = gamma * gamma
    B, C = np.hstack([B1, B2]), np.vstack([C1, C2])
    D1_ = np.hstack([D11, pl.D12])
    D_1 = np.vstack([D11, pl.D21])
    R = D1_.T @ D1_
    R[:m1, :m1] -= g2 * np.eye(m1)
    Rt = D_1 @ D_1.T
    Rt[:p1, :p1] -= g2 * np.eye(p1)
    X, failure = _stabilising_riccati(A, B, C1.T @ C1, R, C1.T @ D1_, scipy_first)
    if X is not None:
        Y, failure = _stabilising_riccati(A.T, C.T, B1 @ B1.T, Rt, B1 @ D_1.T, scipy_first)
    if failure:
        return None, failure
    F = -np.linalg.solve(R, D1_.T @ C1 + B.T @ X)
    L = -np.linalg.solve(Rt, D_1 @ B1.T + C @ Y).T
    for name, Z in (("X", X), ("Y", Y)):
        ev = np.linalg.eigvalsh(Z) if n else np.zeros(1)
        if ev.min() < -_PSD_TOL * max(1.0, ev.max()):
            return None, f"{name} not positive semidefinite"
    if n and np.abs(np.linalg.eigvals(X @ Y)).max() >= g2:
        return None, "rho(XY) >= gamma^2"
    D1111, D1112 = D11[:q1, :r1], D11[:q1, r1:]
    D1121, D1122 = D11[q1:, :r1], D11[q1:, r1:]
    Gq = np.linalg.inv(g2 * np.eye(q1) - D1111 @ D1111.T) if q1 else np.zeros((0, 0))
    Gr = np.linalg.inv(g2 * np.eye(r1) - D1111.T @ D1111) if r1 else np.zeros((0, 0))
    Dh11 = -D1121 @ D1111.T @ Gq @ D1112 - D1122
    try:
        Dh12 = la.cholesky(np.eye(m2) - D1121 @ Gr @ D1121.T, lower=True)
        Dh21 = la.cholesky(np.eye(p2) - D1112.T @ Gq @ D1112, lower=False)
    except la.LinAlgError:
        return None, "D11 condition violated"
    F12, F2 = F[r1:m1], F[m1:]
    L12, L2 = L[:, q1:p1], L[:, p1:]
    Zinv = np.eye(n) - Y @ X / g2
    Bh2 = np.linalg.solve(Zinv, (B2 + L12) @ Dh12)
    Ch2 = -Dh21 @ (C2 + F12)
    Bh1 = -np.linalg.solve(Zinv, L2) + Bh2 @ np.linalg.solve(Dh12, Dh11)
    Ch1 = F2 + Dh11 @ np.linalg.solve(Dh21, Ch2)
    Ah = A + B @ F + Bh1 @ np.linalg.solve(Dh21, Ch2)
    return (Ah, Bh1, Ch1, Dh11), "ok"
