"""Speed of the uncertainty analysis (prints numbers; no asserts).

Goals: the 729-model responses on 2000 frequencies several times faster than
a loop over the members (python-control evaluates one member quickly; the
gain is in avoiding 729 Python calls); each library step of notebook 02
around a second at most on the 2-core machine.

    python benchmarks/bench_uncertainty.py
"""

import time

import numpy as np

from piezolib import paper, robust
from piezolib import uncertainty as unc

from bench_stage import best_of      # scripts run from benchmarks/ see each other


def main():
    omega = robust.frequency_grid(1.0, 1e6, 2000)
    G, K, H_m = paper.plant(), paper.controller(), paper.uncertainty_weight()
    mset = unc.model_set(G, paper.UNCERTAINTY_SPREAD, paper.UNCERTAINTY_LEVELS)

    fast = best_of(lambda: unc.set_response(mset, omega))
    s = 1j * omega
    start = time.perf_counter()
    for k in range(mset.size):
        np.ravel(mset.member(k)(s))
    loop = time.perf_counter() - start
    print(f"729 responses x {omega.size} frequencies: vectorised {fast * 1e3:7.1f} ms, "
          f"loop over members {loop * 1e3:7.0f} ms ({loop / fast:.0f}x)")

    E = unc.relative_error_envelope(mset, omega)
    steps = {
        "relative_errors (729 x 2000)": lambda: unc.relative_errors(mset, omega),
        "member_poles (729 batched)": lambda: unc.member_poles(mset),
        "member_closed_loop_poles with K": lambda: unc.member_closed_loop_poles(mset, K),
        "envelope_peak (refined)": lambda: unc.envelope_peak(mset, omega),
        "relative_error_bound (box)": lambda: unc.relative_error_bound(G, 0.05, omega),
        "largest_covered_spread(H_m)": lambda: unc.largest_covered_spread(H_m, G, omega),
        "fit_covering_weight, order 5": lambda: unc.fit_covering_weight(omega, E, 5),
        "parametric_stability_margin(G, K)": lambda: unc.parametric_stability_margin(G, K),
        "small_gain_spread(G, K)": lambda: unc.small_gain_spread(G, K, omega),
    }
    for name, func in steps.items():
        print(f"{name:36s} {best_of(func, repeat=2) * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
