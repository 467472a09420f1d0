"""Can branch and bound close the 8-scalar gaps of bench_mu_structures.py? (a measurement)

At the points of the ``8 scalars`` family (seed 0) where ``mussv``'s gap exceeds 1 %, this
tries to certify mu <= beta = 1.0099 * lower, i.e. a gap within 1 %, by a branch and bound
over the perturbation set: det(I - M Delta / beta) != 0 must hold on the unit polydisc of
the eight complex scalars.  A node is a product of disks |delta_i - c_i| <= r_i; with
Delta = C + R Delta', the node is cleared when I - M C / beta is invertible and the
D-scaled upper bound of (I - M C / beta)^-1 M R / beta is below 1.  A node that is not
cleared is split on its widest disk into the 7 disks of radius r/2 that cover it (one at
the centre, six at distance r sqrt(3)/2).  All nodes of a level are bounded in one
vectorised ``mussv`` call.

Prints per sampled point the gap, the nodes bounded per level and the fraction cleared,
and whether the point was certified within ``--max-nodes``.  Measured 2026-11-26: none of
11 points (gaps 1.0-1.9 %) was certified within 5,100-24,900 nodes (1.9-15.6 s per point,
against about 1 ms per point for the D-scaled bound itself).

Usage::

    python benchmarks/bench_mu_branch_and_bound.py [--points 11] [--max-nodes 5000]
"""

import argparse
import time
import warnings

import numpy as np

from bench_mu_structures import blk_dims, families, random_response
from piezolib.robust.mu import mussv

#: centres of the 7 disks of radius 1/2 that cover the unit disk
COVER = np.concatenate([[0], np.sqrt(3) / 2 * np.exp(1j * np.pi / 3 * np.arange(6))])


def gap_points(cases, n):
    """(M, lower, gap) at every point of the 8-scalar family where the gap exceeds 1 %."""
    rng = np.random.default_rng(0)
    points = []
    for name, blks, _ in families(rng, cases):
        for blk in blks:
            p, q = blk_dims(blk)
            _, M = random_response(rng, p, q, n)    # drawn for every family: same cases
            if name != "8 scalars":
                continue
            res = mussv(M, blk)
            points += [(M[k], res.lower[k], res.gap[k]) for k in np.nonzero(res.gap > 0.01)[0]]
    return points


def certify(M, beta, max_nodes):
    """Branch and bound on det(I - M Delta / beta) != 0; (certified, levels) with
    levels a list of (nodes bounded, fraction cleared)."""
    k = M.shape[0]
    Mb = M / beta
    centres, radii = np.zeros((1, k), complex), np.ones((1, k))
    levels, total = [], 0
    while True:                 # every level either clears all nodes or splits some
        loop = np.eye(k) - Mb[None] * centres[:, None, :]
        sub = np.linalg.solve(loop, Mb[None] * radii[:, None, :])
        upper = mussv(sub, [(1, 1)] * k, lower=False).upper
        open_ = upper >= 1
        total += len(upper)
        levels.append((len(upper), 1 - open_.mean()))
        if not open_.any():
            return True, levels
        if total >= max_nodes:
            return False, levels
        centres, radii = centres[open_], radii[open_]
        widest = np.repeat(np.argmax(radii, axis=1), len(COVER))
        centres = np.repeat(centres, len(COVER), axis=0)
        radii = np.repeat(radii, len(COVER), axis=0)
        child = np.arange(len(widest))
        centres[child, widest] += radii[child, widest] * np.tile(COVER, open_.sum())
        radii[child, widest] /= 2


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20,
                    help="cases per family (as bench_mu_structures)")
    ap.add_argument("--n", type=int, default=1000, help="frequencies per case")
    ap.add_argument("--points", type=int, default=11, help="gap points sampled evenly")
    ap.add_argument("--max-nodes", type=int, default=5000, help="nodes per point before giving up")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    points = gap_points(args.cases, args.n)
    pick = np.unique(np.linspace(0, len(points) - 1, args.points).astype(int))
    print(f"{len(points)} points with a gap above 1 %; branch and bound on {pick.size} of them")
    certified = 0
    for i in pick:
        M, lower, gap = points[i]
        t = time.perf_counter()
        ok, levels = certify(M, 1.0099 * lower, args.max_nodes)
        certified += ok
        trail = ", ".join(f"{n} ({c:.0%})" for n, c in levels)
        print(f"point {i:4d}: gap {gap:.2%}  {'certified' if ok else 'not certified'} after "
              f"{sum(n for n, _ in levels)} nodes, {time.perf_counter() - t:.1f} s; "
              f"nodes (cleared) per level: {trail}", flush=True)
    print(f"certified: {certified} of {pick.size}")


if __name__ == "__main__":
    main()
