"""hinfsyn against an independent LMI solution on the 50 random plants of bench_hinf_random.

The optimal gamma of each plant is computed a second way, by the Gahinet-Apkarian
LMIs (projected bounded-real conditions on R, S with [R I; I S] >= 0, minimising
gamma), solved by cvxpy/Clarabel -- no Riccati equation and no code shared with
``hinfsyn``.  Needs cvxpy: run with the dkpy venv,
``benchmarks/.dkpy-venv/bin/python benchmarks/bench_hinf_lmi.py``.
"""

import warnings

import cvxpy as cp
import numpy as np
import scipy.linalg as la

from bench_hinf_random import random_well_posed_plant
from piezolib.robust.hinf import hinfsyn


def lmi_gamma(P, nmeas=1, ncon=1):
    """(optimal gamma, solver status) of P by the projected LMIs."""
    A, B, C, D = (np.asarray(x, float) for x in (P.A, P.B, P.C, P.D))
    n, m1, p1 = A.shape[0], B.shape[1] - ncon, C.shape[0] - nmeas
    B1, B2, C1, C2 = B[:, :m1], B[:, m1:], C[:p1], C[p1:]
    D11, D12, D21 = D[:p1, :m1], D[:p1, m1:], D[p1:, :m1]
    R = cp.Variable((n, n), symmetric=True)
    S = cp.Variable((n, n), symmetric=True)
    g = cp.Variable()

    def projected(core, right, basis, k):
        # [N 0; 0 I]' [core, right; right', -g I] [N 0; 0 I]
        big = cp.bmat([[core, right], [right.T, -g * np.eye(k)]])
        T = la.block_diag(basis, np.eye(k))
        out = T.T @ big @ T
        return (out + out.T) / 2

    core_r = cp.bmat([[A @ R + R @ A.T, R @ C1.T], [C1 @ R, -g * np.eye(p1)]])
    core_s = cp.bmat([[A.T @ S + S @ A, S @ B1], [B1.T @ S, -g * np.eye(m1)]])
    lmi_r = projected(core_r, np.vstack([B1, D11]), la.null_space(np.hstack([B2.T, D12.T])), m1)
    lmi_s = projected(core_s, np.vstack([C1.T, D11.T]), la.null_space(np.hstack([C2, D21])), p1)
    coupling = cp.bmat([[R, np.eye(n)], [np.eye(n), S]])
    cons = [lmi_r << -1e-9 * np.eye(lmi_r.shape[0]), lmi_s << -1e-9 * np.eye(lmi_s.shape[0]),
            (coupling + coupling.T) / 2 >> 0]
    prob = cp.Problem(cp.Minimize(g), cons)
    try:
        prob.solve(solver="CLARABEL")
    except cp.error.SolverError as exc:
        return np.nan, f"solver error: {str(exc)[:40]}"
    return float(g.value), prob.status


def main(count=50):
    warnings.simplefilter("ignore")
    print(f"{'seed':>4} {'n':>2} {'hinfsyn':>12} {'LMI':>12} {'LMI status':>18} {'rel diff':>9}")
    rows = []
    for seed in range(count):
        rng = np.random.default_rng(5000 + seed)    # the plants of bench_hinf_random
        n = int(rng.integers(2, 9))
        P = random_well_posed_plant(rng, n)
        ours = hinfsyn(P, 1, 1, rtol=1e-4, gamma_max=1e9).gamma
        ref, status = lmi_gamma(P)
        rel = ours / ref - 1
        rows.append((status, rel))
        print(f"{seed:4d} {n:2d} {ours:12.6g} {ref:12.6g} {status:>18s} {rel:9.2e}", flush=True)
    exact = [r for s, r in rows if s == "optimal"]
    loose = [r for s, r in rows if s == "optimal_inaccurate"]
    print(f"\nplants: {count}; LMI solved to 'optimal': {len(exact)}, of which within 0.1 %: "
          f"{sum(abs(r) <= 1e-3 for r in exact)} (rel diff {min(exact):.2e} ... {max(exact):.2e}); "
          f"'optimal_inaccurate': {len(loose)}, within 0.1 %: {sum(abs(r) <= 1e-3 for r in loose)}, "
          f"within 1 %: {sum(abs(r) <= 1e-2 for r in loose)}; other: {count - len(exact) - len(loose)}")


if __name__ == "__main__":
    main()
