"""Benchmark: mussv bounds on random structures (blocks x time x gap x dkpy ratio).

Random cases, each a 1,000-frequency response M(j omega) = C (j omega I - A)^-1 B + D of a
seeded random stable system, for several families of block structures:

* ``k scalars``: k complex 1 x 1 blocks (k = 3, 5, 8);
* ``exact``: random complex structures with 2 S + F <= 3 (S repeated scalars with k > 1,
  F other blocks), where the D-scaled bound equals mu: the gap must be <= 1e-6;
* ``complex <= 8``: random complex structures of up to 8 blocks (scalars, repeated, full);
* ``mixed``: random structures with real and complex blocks; ``real``: purely real ones.

The ``5 scalars, refine``, ``8 scalars, refine`` and ``complex <= 8, refine`` rows run
those cases again with ``mussv(..., refine=0.01)``: the symmetric-lift certificate at the
frequencies whose D-scaled gap exceeds 1 %.  Structures beyond its size cap
(``MAX_LIFTED_UNKNOWNS``) keep the D-scaled bound there; the row says how many cases were
refined.  The ``mixed real/cplx, refine`` and ``real, refine`` rows run with
``refine=0.05``: branch and bound over the real parameters where the D,G gap exceeds 5 %
(structures with repeated real scalars are not refined).

For every family it prints the time per case, the fraction of cases whose gap
(upper - lower) / upper is <= 1 % (<= 1e-6 for ``exact``) at every frequency, the fraction of
all frequency points meeting it, the median and worst gap, and for real structures the fraction
of points with upper > 0 where the lower bound is nonzero.  With dkpy importable (see
benchmarks/README.md, ``benchmarks/setup_dkpy.sh``) it times dkpy's LMI upper bound on the
first ``--dkpy-cases`` cases of each family (on ``--dkpy-n`` frequencies, scaled to 1,000) and
prints the ratio of dkpy's total time to ours on those cases.

Usage::

    python benchmarks/bench_mu_structures.py [--cases 20] [--n 1000] [--only scalars]
    benchmarks/.dkpy-venv/bin/python benchmarks/bench_mu_structures.py --dkpy-n 50
"""

import argparse
import os
import time
import warnings

import numpy as np

from piezolib.robust.blocks import parse_blk
from piezolib.robust.mu import mussv
from piezolib.robust.mu.ssv import _check_refine


def random_response(rng, p, q, n, order=4):
    """(omega, M) of a random stable system with p outputs and q inputs on n frequencies."""
    poles = -10 ** rng.uniform(-1, 2, order) + 1j * 0
    A = np.diag(poles) + 0.3 * np.triu(rng.standard_normal((order, order)), 1)
    B = rng.standard_normal((order, q))
    C = rng.standard_normal((p, order))
    D = 0.3 * (rng.standard_normal((p, q)))
    omega = np.logspace(-2, 3, n)
    eye = np.eye(order)
    X = np.linalg.solve(1j * omega[:, None, None] * eye - A, np.broadcast_to(B, (n, order, q)))
    return omega, C @ X + D


def blk_dims(blk):
    p = sum(c if c else abs(r) for r, c in blk)
    q = sum(abs(r) for r, c in blk)
    return p, q


def random_complex_blk(rng, nb, exact):
    while True:
        blk = []
        for _ in range(nb):
            kind = rng.integers(3)
            if kind == 0:
                blk.append((1, 1))
            elif kind == 1:
                blk.append((int(rng.integers(2, 4)), 0))
            else:
                blk.append((int(rng.integers(1, 4)), int(rng.integers(1, 4))))
        s = sum(1 for r, c in blk if c == 0 and r > 1)
        if not exact or 2 * s + len(blk) - s <= 3:
            return blk


def random_mixed_blk(rng, real_only):
    nb = int(rng.integers(2, 6))
    while True:
        blk = []
        for _ in range(nb):
            if real_only or rng.uniform() < 0.5:
                blk.append((-int(rng.integers(1, 3)) if rng.uniform() < 0.25 else -1, 0))
            else:
                blk.append((1, 1) if rng.uniform() < 0.5 else (int(rng.integers(1, 3)),
                                                                int(rng.integers(1, 3))))
        kinds = {r < 0 for r, _ in blk}
        if real_only or kinds == {True, False}:
            return blk


def families(rng, cases):
    fam = [(f"{k} scalars", [[(1, 1)] * k for _ in range(cases)], 0.01) for k in (3, 5, 8)]
    fam.append(("exact (2S+F<=3)", [random_complex_blk(rng, int(rng.integers(1, 4)), True)
                                    for _ in range(cases)], 1e-6))
    fam.append(("complex <= 8", [random_complex_blk(rng, int(rng.integers(1, 9)), False)
                                 for _ in range(cases)], 0.01))
    fam.append(("mixed real/cplx", [random_mixed_blk(rng, False) for _ in range(cases)], 0.05))
    fam.append(("real", [random_mixed_blk(rng, True) for _ in range(cases)], 0.05))
    return fam


def dkpy_takes(blk):
    """dkpy's LMI bound takes full blocks only (here: no repeated scalars)."""
    return all(c != 0 for r, c in blk)


def dkpy_time(blk, M, n_dk):
    import dkpy
    ssv = dkpy.SsvLmiBisection()
    N = np.moveaxis(M[:: max(1, len(M) // n_dk)][:n_dk], 0, -1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        ssv.compute_ssv(N, [list(b) for b in blk])
    return (time.perf_counter() - t0) * len(M) / N.shape[-1]


#: families also run with ``mussv(..., refine=tol)`` (the symmetric-lift certificate for
#: complex structures, branch and bound over the real parameters with real blocks)
REFINED = {"5 scalars", "8 scalars", "complex <= 8", "mixed real/cplx", "real"}


def refinable(blk):
    """Whether ``mussv(..., refine=...)`` takes the structure (the lift's size cap; with
    real blocks, 1 x 1 real scalars only): mussv's own check."""
    try:
        _check_refine(0.01, parse_blk(blk, *blk_dims(blk)), True)
    except ValueError:
        return False
    return True


def print_row(name, tol, t_dk, times, case_ok, gaps, nonzero, t_ours, refined=None):
    """One table line: time per case, fractions within tol, gaps, dkpy's time over ours."""
    ratio = sum(t_dk) / sum(t_ours) if t_dk else None
    g = np.concatenate(gaps)
    nz = np.concatenate(nonzero)
    nz_txt = f"{nz.mean():8.3f}" if nz.size else f"{'-':>8s}"
    r_txt = f"{ratio:9.0f}" if ratio is not None else f"{'-':>9s}"
    print(f"{name:24s} {np.mean(times):8.2f}s {np.mean(case_ok):8.2f} "
          f"{np.mean(g <= tol):9.4f} {np.median(g):10.2e} {g.max():9.2e} {nz_txt} {r_txt}"
          f"   (tol {tol:g}"
          + (f"; refined {sum(refined)} of {len(refined)} cases)" if refined else ")"),
          flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20, help="random cases per family")
    ap.add_argument("--n", type=int, default=1000, help="frequencies per case")
    ap.add_argument("--dkpy-n", type=int, default=50,
                    help="frequencies dkpy is timed on (time scaled to --n)")
    ap.add_argument("--dkpy-cases", type=int, default=3,
                    help="cases per family dkpy is timed on (the ratio is over these)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", default="", help="run only families whose name contains this")
    args = ap.parse_args()
    os.environ.setdefault("PYTHONWARNINGS", "ignore")   # dkpy's worker processes warn a lot
    rng = np.random.default_rng(args.seed)
    try:
        import dkpy  # noqa: F401
        have_dkpy = True
    except ImportError:
        have_dkpy = False
    print(f"{args.cases} random cases per family, {args.n} frequencies each")
    head = (f"{'family':24s} {'time/case':>9s} {'cases ok':>8s} {'points ok':>9s} "
            f"{'median gap':>10s} {'worst gap':>9s} {'lower>0':>8s} {'dkpy/ours':>9s}")
    print(head)
    for name, blks, tol in families(rng, args.cases):
        if args.only not in name:
            continue
        # the refined rows run on the same cases as their family
        variants = {name: {}}
        if name in REFINED:
            variants[f"{name}, refine"] = {"refine": tol}
        stats = {v: dict(times=[], case_ok=[], gaps=[], nonzero=[], t_ours=[],
                         **({"refined": []} if opts else {})) for v, opts in variants.items()}
        t_dk = []
        for i, blk in enumerate(blks):
            p, q = blk_dims(blk)
            _, M = random_response(rng, p, q, args.n)
            timed = i < args.dkpy_cases and have_dkpy and dkpy_takes(blk)
            for v, opts in variants.items():
                st = stats[v]
                if opts:
                    st["refined"].append(refinable(blk))
                    opts = opts if st["refined"][-1] else {}
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    t0 = time.perf_counter()
                    res = mussv(M, blk, **opts)
                    st["times"].append(time.perf_counter() - t0)
                st["gaps"].append(res.gap)
                st["case_ok"].append(np.all(res.gap <= tol))
                pos = res.upper > 1e-12 * max(res.upper.max(), 1e-300)
                st["nonzero"].append(res.lower[pos] > 0)
                if timed:
                    st["t_ours"].append(st["times"][-1])
            if timed:
                t_dk.append(dkpy_time(blk, M, args.dkpy_n))
        for v in variants:
            print_row(v, tol, t_dk, **stats[v])
    if not have_dkpy:
        print("\ndkpy not importable: the dkpy/ours column is empty.  Create its venv with "
              "`sh benchmarks/setup_dkpy.sh` and run this script with "
              "`benchmarks/.dkpy-venv/bin/python`.")


if __name__ == "__main__":
    main()
