"""Fits of raw foreign-hysteresis records (rest, a step that rings, a +-150 V 1 Hz sine) per
family and rate: the Hammerstein fit against the best achievable error, fit CPU time per 50 k
samples, and its feedforward of a sine of the record's stroke on the generating stage.

Each record is fitted with the default (operator="auto": PI plays or a Preisach grid, chosen by
the held-out and extrapolation scores; the op column names the one kept) and, for comparison,
with PI plays alone (operator="pi").  The CPU seconds are one thread's: OpenBLAS threads spin
while they wait, and on a shared machine that doubles or triples process time without making
the fit faster (set OPENBLAS_NUM_THREADS to measure otherwise).

    nice -n 10 python benchmarks/bench_raw_record.py
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")     # before numpy loads OpenBLAS

import time
import warnings

import control as ct
import numpy as np

from piezolib import hysteresis as hy
from piezolib.problem import foreign_hysteresis as F


def main():
    warnings.simplefilter("ignore", hy.FitWarning)
    print("family    fs_Hz  samples  noise%  best whole/out%  known-G whole%  fit whole/out%  "
          "ratio whole/out  CPU s/50k  tracking%  op")
    for family in F.FAMILIES:
        for fs in (5000.0, 20000.0):
            raw = F.foreign_raw_record(family, fs)
            best = F.best_achievable(raw, rows=6000)
            for operator in (None, "pi"):
                row(family, fs, raw, best, operator)


def row(family, fs, raw, best, operator):
    """One line of the table: the fit with ``operator`` (None: the default) of one record."""
    v, x = raw.record.input, raw.record.output
    chosen = {} if operator is None else {"operator": operator}
    t0 = time.process_time()
    fit = hy.fit_hammerstein([(v, x)], fs=fs, **chosen)
    cpu = (time.process_time() - t0) * 50000 / v.size
    known = hy.fit_hammerstein([(v, x)], fs=fs, dynamics=ct.tf(raw.b, raw.a, 1 / fs), **chosen)
    (fv, fx), (_, _, first) = hy.split_record(v, x, 0.5)
    part = hy.fit_hammerstein([(fv, fx)], fs=fs, **chosen)
    r = part.model.simulate(v)[first:] - x[first:]
    out = 100 * np.sqrt(np.mean(r ** 2)) / np.ptp(x)
    ref = min(best.whole_percent, known.rms_percent[0])
    t = np.arange(int(3 * fs)) / fs
    lo, hi = np.percentile(x, [2, 98])
    x_r = (lo + hi) / 2 + (hi - lo) / 2 * np.sin(2 * np.pi * t - np.pi / 2)
    e = raw.plant(fit.model.feedforward(x_r))[int(fs):] - x_r[int(fs):]
    track = 100 * np.sqrt(np.mean(e ** 2)) / np.ptp(x)
    print(f"{family:9s} {fs:6.0f} {v.size:8d}  {best.noise_floor_percent:5.3f}  "
          f"{best.whole_percent:6.3f}/{best.out_of_sample_percent:5.3f}    "
          f"{known.rms_percent[0]:6.3f}        {fit.rms_percent[0]:6.3f}/{out:5.3f}   "
          f"{fit.rms_percent[0] / ref:5.2f}/{out / best.out_of_sample_percent:5.2f}"
          f"       {cpu:5.2f}     {track:5.3f}   "
          f"{'pi only' if operator else 'default: ' + fit.operator}", flush=True)


if __name__ == "__main__":
    main()
