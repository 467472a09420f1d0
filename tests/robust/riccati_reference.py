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
itself, and the optimum from a bisection on gamma in log scale.  In double precision this
test is itself ill-conditioned on badly scaled plants (it was off by up to 45 % on some of
``benchmarks/bench_hinf_random.py``'s plants); :func:`riccati_margin_mp` repeats it in 60-digit arithmetic
(mpmath, which only the benchmark environment has) to settle such disagreements.
"""

import control as ct
import numpy as np
import scipy.linalg as la

__all__ = ["random_orthonormal_plant", "rescaled_controls_and_measurements",
           "riccati_gamma_feasible", "riccati_optimal_gamma", "riccati_margin_mp"]


def random_orthonormal_plant(rng):
    """(P, nmeas, ncon): a random plant the test applies to.

    1-3 controls and measurements, D12 and D21 with orthonormal columns and rows,
    D11 = D22 = 0, A scaled by 10^U(-3, 3), each of B1, B2, C1, C2 by 10^U(-2, 2).
    """
    n, nu, ny = int(rng.integers(1, 11)), int(rng.integers(1, 4)), int(rng.integers(1, 4))
    nz, nw = nu + int(rng.integers(0, 3)), ny + int(rng.integers(0, 3))
    A = rng.standard_normal((n, n)) * 10 ** rng.uniform(-3, 3)
    B1, B2 = (rng.standard_normal((n, k)) * 10 ** rng.uniform(-2, 2) for k in (nw, nu))
    C1, C2 = (rng.standard_normal((k, n)) * 10 ** rng.uniform(-2, 2) for k in (nz, ny))
    D12 = np.linalg.qr(rng.standard_normal((nz, nz)))[0][:, :nu]
    D21 = np.linalg.qr(rng.standard_normal((nw, nw)))[0][:, :ny].T
    D = np.block([[np.zeros((nz, nw)), D12], [D21, np.zeros((ny, nu))]])
    return ct.ss(A, np.hstack([B1, B2]), np.vstack([C1, C2]), D), ny, nu


def rescaled_controls_and_measurements(rng, P, nmeas, ncon):
    """P with u -> T u, y -> S y (random, condition numbers up to 1e3) and a random D22.

    Neither changes the optimal gamma (a controller for one is a controller for the
    other), so the reference test, which needs D12, D21 orthonormal and D22 = 0, still
    answers for the result through P.
    """
    A, B, C, D = (np.array(x, float) for x in (P.A, P.B, P.C, P.D))
    nz, nw = C.shape[0] - nmeas, B.shape[1] - ncon
    T = np.linalg.qr(rng.standard_normal((ncon, ncon)))[0] @ np.diag(
        10 ** rng.uniform(-1.5, 1.5, ncon))
    S = np.diag(10 ** rng.uniform(-1.5, 1.5, nmeas)) @ np.linalg.qr(
        rng.standard_normal((nmeas, nmeas)))[0]
    B[:, nw:], D[:nz, nw:] = B[:, nw:] @ T, D[:nz, nw:] @ T
    C[nz:], D[nz:, :nw] = S @ C[nz:], S @ D[nz:, :nw]
    D[nz:, nw:] = rng.standard_normal((nmeas, ncon)) * 10 ** rng.uniform(-2, 1)
    return ct.ss(A, B, C, D)


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


def _hamiltonian_blocks(parts, gamma, mul):
    """((A_x, R_x, Q_x), (A_y, R_y, Q_y)): the blocks of the two Hamiltonians
    [[A_x, R_x], [-Q_x, -A_x^T]] (for X) and [[A_y^T, R_y], [-Q_y, -A_y]] (for Y).
    ``mul`` is the matrix product (numpy arrays or mpmath matrices)."""
    A, B1, B2, C1, C2, D12, D21 = parts
    Ax = A - mul(mul(B2, D12.T), C1)
    C1p = C1 - mul(D12, mul(D12.T, C1))                 # (I - D12 D12^T) C1
    Ay = A - mul(mul(B1, D21.T), C2)
    B1p = B1 - mul(mul(B1, D21.T), D21)                 # B1 (I - D21^T D21)
    return ((Ax, mul(B1, B1.T) / gamma**2 - mul(B2, B2.T), mul(C1p.T, C1p)),
            (Ay, mul(C1.T, C1) / gamma**2 - mul(C2.T, C2), mul(B1p, B1p.T)))


def riccati_gamma_feasible(P, gamma, nmeas=1, ncon=1):
    """True where a controller with ||F_l(P, K)||_inf < gamma exists (two-Riccati test)."""
    (Ax, Rx, Qx), (Ay, Ry, Qy) = _hamiltonian_blocks(_normalized_parts(P, nmeas, ncon),
                                                     gamma, np.matmul)
    n = Ax.shape[0]
    X = _stabilizing_solution(np.block([[Ax, Rx], [-Qx, -Ax.T]]), n)
    Y = None if X is None else _stabilizing_solution(np.block([[Ay.T, Ry], [-Qy, -Ay]]), n)
    if Y is None:
        return False
    tol = 1e-9 * max(1.0, np.abs(X).max(), np.abs(Y).max())
    if np.linalg.eigvalsh(X).min() < -tol or np.linalg.eigvalsh(Y).min() < -tol:
        return False
    return np.abs(np.linalg.eigvals(X @ Y)).max() < gamma**2


def riccati_margin_mp(P, gamma, nmeas=1, ncon=1, dps=60):
    """rho(X Y) / gamma^2 of the two-Riccati test in ``dps``-digit arithmetic (mpmath).

    Below 1 where ``gamma`` is feasible; inf where a Hamiltonian has no n stable
    eigenvalues or X or Y is not positive semidefinite (to -1e-30 relative).  P's
    matrices are taken as exact; everything from the Hamiltonians on runs in ``dps``
    digits.
    """
    import mpmath as mp                  # benchmark environment only

    with mp.workdps(dps):
        parts = [mp.matrix(np.atleast_2d(x).tolist()) for x in _normalized_parts(P, nmeas, ncon)]
        (Ax, Rx, Qx), (Ay, Ry, Qy) = _hamiltonian_blocks(parts, mp.mpf(gamma),
                                                         lambda a, b: a * b)
        n = Ax.rows

        def block(a, b, c, d):
            out = mp.matrix(2 * n, 2 * n)
            for i in range(n):
                for j in range(n):
                    out[i, j], out[i, n + j] = a[i, j], b[i, j]
                    out[n + i, j], out[n + i, n + j] = c[i, j], d[i, j]
            return out

        def solution(Ham):
            E, V = mp.eig(Ham)
            stable = [i for i in range(2 * n) if mp.re(E[i]) < 0]
            if len(stable) != n:
                return None
            U1 = mp.matrix([[V[r, i] for i in stable] for r in range(n)])
            U2 = mp.matrix([[V[n + r, i] for i in stable] for r in range(n)])
            X = U2 * mp.inverse(U1)
            X = (X + X.H) / 2
            ev = [mp.re(e) for e in mp.eig(X)[0]]
            return X if min(ev) >= -mp.mpf(10) ** -30 * max(1, max(ev)) else None

        X = solution(block(Ax, Rx, -Qx, -Ax.T))
        Y = None if X is None else solution(block(Ay.T, Ry, -Qy, -Ay))
        if Y is None:
            return np.inf
        rho = max(abs(e) for e in mp.eig(X * Y)[0])
        return float(rho / mp.mpf(gamma) ** 2)


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
