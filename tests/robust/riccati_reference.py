"""An independent optimal H-infinity level by the two-Riccati test (test data, not library code).

Shared by ``tests/robust/test_hinf_random.py`` and ``benchmarks/bench_hinf_random.py``;
nothing in ``piezolib`` imports it, and it uses only numpy and scipy, so it shares no code
with :func:`piezolib.robust.hinf.hinfsyn` (which solves its Riccati equations from a
generalized eigenvalue pencil, with scipy's ``solve_continuous_are`` as a second opinion).

The test is the classical one for a plant with D11 = 0, D22 = 0, D12^T D12 = I and
D21 D21^T = I (K. Zhou, J. C. Doyle and K. Glover, *Robust and Optimal Control*, 1996,
Sec. 17.1, the case with cross terms D12^T C1 and B1 D21^T): a controller with
||F_l(P, K)||_inf < gamma exists iff

* the Hamiltonian H = [A - B2 D12^T C1, B1 B1^T / gamma^2 - B2 B2^T;
  -C1^T (I - D12 D12^T) C1, -(A - B2 D12^T C1)^T] has no imaginary-axis eigenvalue and its
  stable invariant subspace gives X = X2 X1^-1 >= 0,
* the dual J = [(A - B1 D21^T C2)^T, C1^T C1 / gamma^2 - C2^T C2;
  -B1 (I - D21^T D21) B1^T, -(A - B1 D21^T C2)] likewise gives Y >= 0,
* and rho(X Y) < gamma^2.

Here each stable subspace comes from scipy's ordered real Schur form of the Hamiltonian
itself, and the optimum from a bisection on gamma in log scale.
"""

import numpy as np
import scipy.linalg as la

__all__ = ["riccati_gamma_feasible", "riccati_optimal_gamma"]


def _normalized_parts(P, nmeas, ncon):
    A, B, C, D = (np.asarray(x, float) for x in (P.A, P.B, P.C, P.D))
    nw, nz = B.shape[1] - ncon, C.shape[0] - nmeas
    B1, B2, C1, C2 = B[:, :nw], B[:, nw:], C[:nz], C[nz:]
    D11, D12, D21, D22 = D[:nz, :nw], D[:nz, nw:], D[nz:, :nw], D[nz:, nw:]
    if (np.any(D11) or np.any(D22) or not np.allclose(D12.T @ D12, np.eye(ncon))
            or not np.allclose(D21 @ D21.T, np.eye(nmeas))):
        raise ValueError("the reference test needs D11 = D22 = 0, D12^T D12 = I, D21 D21^T = I")
    return A, B1, B2, C1, C2, D12, D21


def _stabilizing_solution(H, n):
    """X of the Riccati equation with Hamiltonian H, or None where none stabilises."""
    scale = max(np.abs(H).max(), 1.0)
    eig = la.eigvals(H)
    if np.min(np.abs(eig.real)) <= 1e-9 * scale:     # imaginary-axis eigenvalue
        return None
    T, U, sdim = la.schur(H, output="real", sort="lhp")
    if sdim != n:
        return None
    U1, U2 = U[:n, :n], U[n:, :n]
    if np.linalg.cond(U1) > 1e12:
        return None
    X = np.linalg.solve(U1.T, U2.T).T
    return (X + X.T) / 2


def riccati_gamma_feasible(P, gamma, nmeas=1, ncon=1):
    """True where a controller with ||F_l(P, K)||_inf < gamma exists (two-Riccati test)."""
    A, B1, B2, C1, C2, D12, D21 = _normalized_parts(P, nmeas, ncon)
    n = A.shape[0]
    Ax = A - B2 @ D12.T @ C1
    C1p = C1 - D12 @ (D12.T @ C1)                       # (I - D12 D12^T) C1
    H = np.block([[Ax, B1 @ B1.T / gamma**2 - B2 @ B2.T], [-C1p.T @ C1p, -Ax.T]])
    X = _stabilizing_solution(H, n)
    if X is None:
        return False
    Ay = A - B1 @ D21.T @ C2
    B1p = B1 - (B1 @ D21.T) @ D21                       # B1 (I - D21^T D21)
    J = np.block([[Ay.T, C1.T @ C1 / gamma**2 - C2.T @ C2], [-B1p @ B1p.T, -Ay]])
    Y = _stabilizing_solution(J, n)
    if Y is None:
        return False
    tol = 1e-9 * max(1.0, np.abs(X).max(), np.abs(Y).max())
    if np.linalg.eigvalsh(X).min() < -tol or np.linalg.eigvalsh(Y).min() < -tol:
        return False
    return np.abs(np.linalg.eigvals(X @ Y)).max() < gamma**2


def riccati_optimal_gamma(P, nmeas=1, ncon=1, *, gamma_max=1e9, rtol=1e-7):
    """Optimal H-infinity level of P by bisection on :func:`riccati_gamma_feasible`.

    The bisection runs in log scale between 1e-12 and ``gamma_max`` until the
    bracket is ``rtol`` wide and returns its feasible end; inf when
    ``gamma_max`` itself fails.
    """
    if not riccati_gamma_feasible(P, gamma_max, nmeas, ncon):
        return np.inf
    lo, hi = 1e-12, gamma_max
    while hi / lo - 1 > rtol:
        mid = np.sqrt(lo * hi)
        if riccati_gamma_feasible(P, mid, nmeas, ncon):
            hi = mid
        else:
            lo = mid
    return hi
