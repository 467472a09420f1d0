"""hinfsyn on seeded random well-posed plants against two independent references.

* The two-Riccati test of Zhou, Doyle and Glover (``tests/robust/riccati_reference.py``:
  ordered Schur forms of the two Hamiltonians, bisection on gamma; numpy/scipy only, no
  code shared with hinfsyn): its optimum gamma_ric is the main reference.
* python-control's ``hinfsyn`` (SLICOT SB10AD), run in a child process with a timeout:
  its reported gamma and the recomputed norm of its controller (often the controller
  does not verify, so its gamma is shown, not trusted).

Prints, per plant, our gamma with the bracket's infeasible end, gamma_ric and the
relative difference, SB10AD's numbers and our time; then a summary: plants within
0.1 % of gamma_ric, infeasibility claims above gamma_ric (false ones), converged=True
with a recomputed norm above gamma.

Usage::

    python benchmarks/bench_hinf_random.py [--count 50] [--gamma-max 1e9] [--no-sb10ad]
"""

import argparse
import pathlib
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import TimeoutError as FuturesTimeout

import control as ct
import numpy as np

from piezolib.robust.hinf import HinfSynthesisError, hinfsyn
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import hinf_norm

ROOT = pathlib.Path(__file__).resolve().parents[1]


sys.path.insert(0, str(ROOT / "tests" / "robust"))      # its test-data modules
import riccati_reference  # noqa: E402


def random_well_posed_plant(rng, n):
    """Random P with D12 = [0; 1], D21 = [0, 1], D11 = D22 = 0 (2 w, 1 u, 2 z, 1 y)."""
    A = rng.standard_normal((n, n)) * 10 ** rng.uniform(-2, 2)
    B = rng.standard_normal((n, 3))
    C = rng.standard_normal((3, n))
    D = np.array([[0.0, 0, 0], [0, 0, 1], [0, 1, 0]])
    return ct.ss(A, B, C, D)


def _sb10ad(matrices):
    """(reported gamma, recomputed norm of its controller) of SLICOT SB10AD."""
    warnings.simplefilter("ignore")
    P = ct.ss(*matrices)
    try:
        K, _, gam, _ = ct.hinfsyn(P, 1, 1)
    except Exception:
        return np.nan, np.nan
    M = lower_lft(P, K)
    if not np.all(ct.poles(M).real < 0):
        return gam, np.inf
    return gam, hinf_norm(M, omega=np.logspace(-6, 6, 6000))[0]


def _sb10ad_in_child(pool, P, timeout):
    """(pool, gamma, norm) of SB10AD; a child that runs past ``timeout`` s is killed."""
    future = pool.submit(_sb10ad, (P.A, P.B, P.C, P.D))
    try:
        return (pool, *future.result(timeout=timeout))
    except FuturesTimeout:          # SB10AD is known to run for minutes
        for proc in list((pool._processes or {}).values()):
            proc.kill()
        pool.shutdown(wait=False, cancel_futures=True)
        return ProcessPoolExecutor(max_workers=1), np.nan, np.nan


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=50, help="random plants (seeds 5000, ...)")
    ap.add_argument("--gamma-max", type=float, default=1e9, help="hinfsyn's gamma_max")
    ap.add_argument("--timeout", type=float, default=20.0, help="SB10AD time limit [s]")
    ap.add_argument("--no-sb10ad", action="store_true", help="skip python-control's hinfsyn")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    rel, false_claims, overclaims, unconverged, times, failures = [], [], [], [], [], []
    print(f"{'seed':>4} {'n':>2} {'gamma':>12} {'infeasible':>12} {'gamma_ric':>12} "
          f"{'rel diff':>9} {'SB10AD':>11} {'SB10AD K':>11} {'time':>6}")
    pool = None if args.no_sb10ad else ProcessPoolExecutor(max_workers=1)
    for seed in range(args.count):
        rng = np.random.default_rng(5000 + seed)
        n = int(rng.integers(2, 9))
        P = random_well_posed_plant(rng, n)
        g_ric = riccati_reference.riccati_optimal_gamma(P, gamma_max=args.gamma_max)
        t = time.perf_counter()
        try:
            res = hinfsyn(P, 1, 1, rtol=1e-4, gamma_max=args.gamma_max)
        except HinfSynthesisError as exc:
            times.append(time.perf_counter() - t)
            failures.append(seed)
            print(f"{seed:4d} {n:2d} raised: {str(exc)[:70]} (gamma_ric {g_ric:.6g})", flush=True)
            continue
        times.append(time.perf_counter() - t)
        rel.append(res.gamma / g_ric - 1)
        if res.gamma_infeasible > g_ric * (1 + 1e-4):     # the bisection's own accuracy
            false_claims.append(seed)
        if res.converged and res.norm > res.gamma * (1 + 1e-3):
            overclaims.append(seed)
        if not res.converged:
            unconverged.append(seed)
        gam = ref = np.nan
        if pool is not None:
            pool, gam, ref = _sb10ad_in_child(pool, P, args.timeout)
        print(f"{seed:4d} {n:2d} {res.gamma:12.7g} {res.gamma_infeasible:12.7g} {g_ric:12.7g} "
              f"{rel[-1]:9.2e} {gam:11.6g} {ref:11.6g} {times[-1]:6.2f}"
              f"{'' if res.converged else '  (not converged)'}", flush=True)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)
    rel = np.abs(rel)
    print(f"\nplants: {args.count}; within 0.1 % of the two-Riccati optimum: "
          f"{np.count_nonzero(rel <= 1e-3)}; median |gamma/gamma_ric - 1| {np.median(rel):.1e}, "
          f"max {rel.max():.1e}; raised: {failures}; not converged: {unconverged}")
    print(f"infeasibility claimed above gamma_ric: {false_claims or 'none'}; converged=True with "
          f"norm > gamma: {overclaims or 'none'}; hinfsyn time median {np.median(times):.2f} s, "
          f"max {np.max(times):.2f} s")


if __name__ == "__main__":
    main()
