"""Benchmark: the causal all-levels model of the fine steering mirror (notebook 10).

Refits the committed model's structure (``data/models/fsm_causal_model.npz``: branches, window,
per-level orders of the basis poles) on the six training realisations of every level and times
it; scores the refit and the committed model with the benchmark's official metric on the test
files; prints them beside the published neural LFR, the per-level linear models (orders as
committed, refitted here) and the metric's noise floor with and without the drift.
``--select`` re-runs the whole choice on held-out realisations too (minutes) and prints its
validation table.

Usage, from the repository root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fsm_causal.py [--select]
"""

import argparse
import time

import numpy as np

from piezolib import identification as ident
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_causal, fsm_models


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--select", action="store_true",
                        help="re-run the selection on held-out realisations (minutes)")
    args = parser.parse_args()
    committed = fsm_causal.read_causal_model()
    blas = fsm_models.level_blas()
    print(f"committed: {committed.description()}")
    if args.select:
        fit = fsm_causal.derive_causal_model(blas, committed.orders)
        print(f"re-derived: {fit.description()}")
        print(fit.validation_table().round(3).to_string())
        model, fit_s = fit.model, fit.fit_s
    else:
        model, fit_s = fsm_causal.fit_causal_model(blas, committed.orders,
                                                   committed.model.branches,
                                                   committed.model.window_samples)
    print(f"final fit (poles + one least-squares solve, 36 records, {model.n_regressors} "
          f"regressors per output): {fit_s:.1f} s wall")
    lfr = fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
    rows = {"causal (refit here)": {}, "causal (committed)": {}, "published neural LFR": lfr,
            "linear per level": {}, "noise floor": {}, "noise floor without drift": {}}
    t0 = time.perf_counter()
    for lv in fsm.LEVELS_MV:
        rows["causal (refit here)"][lv] = fsm.score_simulation(model.simulate, lv).nrmse_percent
        rows["causal (committed)"][lv] = fsm.score_simulation(committed.model.simulate,
                                                              lv).nrmse_percent
    score_s = time.perf_counter() - t0
    for lv in fsm.LEVELS_MV:
        bl = blas.blas[lv]
        linear = ident.fit_frf(bl.G, bl.frequency_Hz, fsm.SAMPLING_FREQUENCY_HZ,
                               committed.orders[lv])
        rows["linear per level"][lv] = fsm.score(linear, lv).nrmse_percent
        rows["noise floor"][lv] = fsm.noise_floor(lv).nrmse_percent
        rows["noise floor without drift"][lv] = fsm.noise_floor(lv, without_drift=True).nrmse_percent
    print(f"scoring both causal models on the 3 test sets: {score_s:.1f} s")
    print(f"{'test NRMSE [%]':32s}" + "".join(f"{lv:>9d} mV" for lv in fsm.LEVELS_MV))
    for name, per_level in rows.items():
        print(f"{name:32s}" + "".join(f"{per_level[lv]:12.3f}" for lv in fsm.LEVELS_MV))
    gap = np.array([lfr[lv] - rows["causal (committed)"][lv] for lv in fsm.LEVELS_MV])
    print("causal below the LFR by [points]: " + " / ".join(f"{g:.2f}" for g in gap))


if __name__ == "__main__":
    main()
