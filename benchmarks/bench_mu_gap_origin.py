"""Benchmark: where the mu bounds' remaining gap comes from, upper or lower bound.

For the random cases of ``bench_mu_structures.py`` (the same draws as its full run) this takes
each case's worst-gap frequency and checks both bounds independently there:

* the upper bound against the global optimum of the D-scaled bound, the convex LMI
  ``M^H P_l M <= beta^2 P_r`` over structured P >= I (Hermitian k x k blocks for repeated
  scalars), solved by cvxpy/Clarabel with bisection on beta^2 -- no code shared with mussv's
  Newton steps on the triangular parametrisation;
* the lower bound against the best of ``--starts`` random starts of the power iteration
  (``--sweeps`` sweeps each), a brute-force search for a higher local maximum of rho(Q M).

If the upper bound equals the LMI optimum and no start beats the lower bound, the gap is the
D-scaled bound's own conservatism (mu is then most likely the lower bound), not an optimiser's.

Needs cvxpy (in the dkpy venv, ``benchmarks/setup_dkpy.sh``)::

    benchmarks/.dkpy-venv/bin/python benchmarks/bench_mu_gap_origin.py [--cases 6] [--n 200]
"""

import argparse
import time
import warnings

import numpy as np

from bench_mu_structures import blk_dims, families, random_response
from piezolib.robust.blocks import block_slices, parse_blk
from piezolib.robust.mu import mussv
from piezolib.robust.mu.lower import _layout, _power_iteration

FAMILIES = ("5 scalars", "8 scalars", "complex <= 8")


def lmi_d_bound(M, blk, rtol=1e-9):
    """Global minimum over structured D of sigma_max(D M D^-1), by LMI feasibility and bisection."""
    import cvxpy as cp
    blocks = parse_blk(blk)
    left, right, cons = [], [], []
    for b, (inputs, outputs) in zip(blocks, block_slices(blocks)):
        if b.repeated and b.size > 1:
            X = cp.Variable((b.size, b.size), hermitian=True)
            cons.append(X >> np.eye(b.size))
            left.append(X)
            right.append(X)
        else:
            x = cp.Variable(nonneg=True)
            cons.append(x >= 1)
            left.append(x * np.eye(outputs.stop - outputs.start))
            right.append(x * np.eye(inputs.stop - inputs.start))

    def block_diagonal(parts):
        sizes = [P.shape[0] for P in parts]
        return cp.bmat([[P if i == j else np.zeros((sizes[i], sizes[j]))
                         for j, _ in enumerate(parts)] for i, P in enumerate(parts)])

    beta2 = cp.Parameter(nonneg=True)
    lhs = M.conj().T @ block_diagonal(left) @ M - beta2 * block_diagonal(right)
    problem = cp.Problem(cp.Minimize(0), cons + [0.5 * (lhs + lhs.H) << 0])
    lo, hi = 0.0, np.linalg.svd(M, compute_uv=False)[0] ** 2 * (1 + 1e-6)
    while hi - lo > rtol * hi:
        beta2.value = 0.5 * (lo + hi)
        try:
            problem.solve(solver="CLARABEL")
            feasible = problem.status == "optimal"
        except cp.error.SolverError:
            feasible = False
        lo, hi = (lo, beta2.value) if feasible else (beta2.value, hi)
    return np.sqrt(hi)


def best_of_random_starts(M, blk, starts, sweeps, seed=0):
    """Largest power-iteration value over ``starts`` random starts on one matrix M."""
    p, q = M.shape
    rng = np.random.default_rng(seed)
    shape = (starts, q)
    b = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    w = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    val, _, _ = _power_iteration(np.broadcast_to(M, (starts, p, q)).copy(),
                                 _layout(parse_blk(blk)), b, w, sweeps, False)
    return val.max()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=6, help="random cases per family")
    ap.add_argument("--n", type=int, default=200, help="frequencies per case (every 1000/n-th)")
    ap.add_argument("--starts", type=int, default=3000, help="random power-iteration starts")
    ap.add_argument("--sweeps", type=int, default=300, help="power-iteration sweeps per start")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"worst-gap point of each case ({args.n} of 1000 frequencies); upper vs the LMI "
          f"optimum, lower vs the best of {args.starts} random starts")
    print(f"{'family':14s} {'case':>4s} {'gap':>9s} {'upper-LMI':>10s} {'starts-lower':>12s} "
          f"{'time':>6s}")
    for name, blks, _ in families(rng, args.cases):
        for i, blk in enumerate(blks):
            p, q = blk_dims(blk)
            _, M = random_response(rng, p, q, 1000)   # drawn in every family, as in the full run
            if name not in FAMILIES:
                continue
            M = M[:: max(1, 1000 // args.n)]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = mussv(M, blk)
            k = int(np.argmax(res.gap))
            t0 = time.perf_counter()
            lmi = lmi_d_bound(M[k], blk)
            best = best_of_random_starts(M[k], blk, args.starts, args.sweeps)
            print(f"{name:14s} {i:4d} {res.gap[k]:9.2e} {(res.upper[k] - lmi) / lmi:+10.1e} "
                  f"{(best - res.lower[k]) / res.lower[k]:+12.1e} "
                  f"{time.perf_counter() - t0:5.1f}s", flush=True)
    print("upper-LMI: relative excess of mussv's upper bound over the global D-scaled optimum "
          "(solver accuracy ~1e-7);\nstarts-lower: relative excess of the best random start over "
          "mussv's lower bound (> 0: the lower bound missed a higher local maximum)")


if __name__ == "__main__":
    main()
