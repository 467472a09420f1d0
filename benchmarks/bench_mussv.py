"""Benchmark: piezolib.robust.mu.mussv against dkpy's LMI upper bound on this problem's M.

M is eq. 18 for the published G, K and weights (inputs u_Delta, v_r; outputs
y_Delta, y1, y2), the structure eq. 21 (``blk = [(1, 1), (1, 2)]``), on a
logarithmic grid of 1000 frequencies.  Prints, in one run:

* mussv: wall time (best of several runs), largest relative gap between its
  upper and lower bounds, the mu_RS and mu_RP peaks;
* dkpy (``SsvLmiBisection``, the LMI upper bound by bisection, solved with
  cvxpy/Clarabel): wall time and values; then the ratio of times and the
  largest relative difference of the upper bounds.

dkpy is not a project dependency: run this in the benchmark environment
(``sh benchmarks/setup_dkpy.sh``, see benchmarks/README.md).  Without dkpy the comparison is skipped with a
message.

Usage::

    benchmarks/.dkpy-venv/bin/python benchmarks/bench_mussv.py [--n 1000] [--dkpy-jobs 1]
"""

import argparse
import os
from importlib.metadata import version
import time
import warnings

import numpy as np

from piezolib.problem import genplant
from piezolib import paper, robust
from piezolib.robust.mu import mussv

BLK = [(1, 1), (1, 2)]


def problem_response(n):
    """Frequency grid [rad/s] and M(j omega), shape (n, 3, 2)."""
    omega = np.logspace(0, 6, n)
    G, H_m, H_e, H_y, K = paper.problem()
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    return omega, robust.lft_response(P, K, omega)


def best_time(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, help="number of frequencies")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs of mussv (best kept)")
    ap.add_argument("--dkpy-jobs", type=int, default=1,
                    help="joblib processes for dkpy (1 = single process, -1 = all cores)")
    args = ap.parse_args()

    omega, M = problem_response(args.n)
    print(f"M: {M.shape[1]}x{M.shape[2]} on {args.n} frequencies "
          f"{omega[0]:.3g}...{omega[-1]:.3g} rad/s, blk = {BLK}; {os.cpu_count()} CPU(s)")

    t_ours, res = best_time(lambda: mussv(M, BLK, omega), args.repeats)
    t_upper, _ = best_time(lambda: mussv(M, BLK, omega, lower=False), args.repeats)
    rs = mussv(M[:, :1, :1], [(1, 1)], omega)
    print("\npiezolib.robust.mu.mussv")
    print(f"  time, upper + lower bound + Delta : {t_ours:8.3f} s  (best of {args.repeats})")
    print(f"  time, upper bound only            : {t_upper:8.3f} s")
    print(f"  max relative gap (upper-lower)/upper over all frequencies: {res.gap.max():.2e}")
    for name, r in (("mu_RS (M11, 1x1 block)", rs), ("mu_RP (M, eq. 21)", res)):
        up, w_up, _ = r.peak("upper")
        lo, w_lo, _ = r.peak("lower")
        print(f"  {name:24s} peak upper {up:.5f} at {w_up:9.1f} rad/s, "
              f"lower {lo:.5f} at {w_lo:9.1f} rad/s")

    try:
        import dkpy
    except ImportError as exc:
        print(f"\ndkpy comparison skipped: dkpy is not importable here ({exc}).\n"
              "Run in the benchmark environment: see benchmarks/README.md.")
        return

    jobs = None if args.dkpy_jobs == 1 else args.dkpy_jobs
    ssv = dkpy.SsvLmiBisection(n_jobs=jobs)
    N = np.moveaxis(M, 0, -1)          # dkpy wants (p, q, nf)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        mu_dk, _, _, info = ssv.compute_ssv(N, [list(b) for b in BLK])
        t_dk = time.perf_counter() - t0
    print(f"\ndkpy {version('dkpy')} SsvLmiBisection "
          f"(cvxpy/{info['solver_params'].get('solver', '?')}, bisection rtol "
          f"{ssv.bisection_rtol:g}, n_jobs={jobs})")
    if mu_dk is None or np.any([m is None for m in np.atleast_1d(mu_dk)]):
        print("  dkpy failed at some frequencies; statuses:", set(info["status"]))
        return
    mu_dk = np.asarray(mu_dk, float)
    k = int(np.argmax(mu_dk))
    rel = mu_dk / res.upper - 1
    print(f"  time                              : {t_dk:8.3f} s")
    print(f"  mu_RP peak {mu_dk[k]:.5f} at {omega[k]:9.1f} rad/s")
    print("\ncomparison (same M, same grid, same machine)")
    print(f"  time ratio dkpy / mussv (upper + lower): {t_dk / t_ours:8.1f} x")
    print(f"  time ratio dkpy / mussv (upper only)   : {t_dk / t_upper:8.1f} x")
    print(f"  upper bounds, dkpy / mussv - 1: max |.| {np.abs(rel).max():.2e}, "
          f"min {rel.min():+.2e}, max {rel.max():+.2e}")
    print(f"  peak ratio dkpy / mussv: {mu_dk.max() / res.upper.max():.6f}")
    goals = (np.abs(rel).max() <= 0.01, t_dk / t_ours >= 50)
    print(f"  goals: values within 1 %: {'met' if goals[0] else 'NOT met'}; "
          f">= 50x faster: {'met' if goals[1] else 'NOT met'}")


if __name__ == "__main__":
    main()
