"""Fixed-order mu-synthesis against DK-iteration + reduction on the delay-aware problem.

Prints, for the workbook's delay-aware synthesis plant (one sample of delay at
10 kHz, roll-off weight), the wall time and the peak mu_RP (upper bound on a
3000-point grid, recomputed here) of: the full-order DK design, its 6th-order
G S-weighted reduction, and the 6th-order fixed-order design started from it,
plus the lower bound on what any controller can reach.

Run: ``python benchmarks/bench_fixed_order.py``
"""

import time

import numpy as np

from piezolib import paper, robust
from piezolib.problem import genplant
from piezolib.problem.design import DESIGN_GRID
from piezolib.robust import achievable
from piezolib.robust.fixed_order import fixed_order_musyn

FINE = np.logspace(-2, 7, 3000)


def peak(P, K):
    M = robust.lft_response(P, K, FINE)
    return robust.mussv(M, genplant.DESIGN_BLOCK_STRUCTURE, FINE, lower=False).upper.max()


def main():
    G, H_m, H_e, H_y, _ = paper.problem()
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=paper.SAMPLING_FREQUENCY_HZ)
    t0 = time.perf_counter()
    dk = robust.musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, 1, 1, DESIGN_GRID, d_order=4)
    t_dk = time.perf_counter() - t0
    t0 = time.perf_counter()
    red = robust.reduce_controller(dk.K, 6, robust.loop_functions(G, dk.K).GS,
                                   method="residualize")
    t_red = time.perf_counter() - t0
    t0 = time.perf_counter()
    fo = fixed_order_musyn(P, genplant.DESIGN_BLOCK_STRUCTURE, red.K, DESIGN_GRID)
    t_fo = time.perf_counter() - t0
    lb = achievable.structured_lower_bound(P, genplant.DESIGN_BLOCK_STRUCTURE, 1, 1)[0]
    print(f"delay-aware plant: {P.nstates} states; lower bound on mu_RP {lb.value:.4f}")
    print(f"{'design':32s} {'states':>6s} {'time [s]':>9s} {'mu_RP (3000 pts)':>17s}")
    rows = [("DK-iteration, full order", dk.K, t_dk),
            ("DK + G S-weighted reduction", red.K, t_dk + t_red),
            ("fixed-order mu (from reduced)", fo.K, t_dk + t_red + t_fo)]
    for name, K, t in rows:
        print(f"{name:32s} {K.nstates:6d} {t:9.2f} {peak(P, K):17.4f}")
    print(f"fixed-order step alone: {t_fo:.2f} s, {len(fo.records)} D-K steps, "
          f"{fo.stop_reason}")


if __name__ == "__main__":
    main()
