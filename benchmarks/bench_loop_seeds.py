"""Case III over N noise seeds at once: the batched loop against the single run (prints numbers).

One Case III run of the tracking test at 1 Hz (3 periods at 10 kHz, 30 001
samples; the workbook's Dahl feedforward, the deployed controller as float32
sections from data/controllers/, one sample of computation delay): the
single-seed loop (``run_loop``) and the batched loop (``run_loop(...,
seeds=range(N))``) for N = 1, 8, 32, 64, with the cost per sample and per
sample and seed.  Every batch member equals the single run with its seed
(checked here for the first and last seed; the tests check it for every
controller form and delay).

Goal: 32 seeds in at most about 3x the time of one single-seed run.

    python benchmarks/bench_loop_seeds.py [--repeat 3]
"""

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.robust.export import read_json
from piezolib.workbook import experiments, loop

SEED_COUNTS = (1, 8, 32, 64)


def best_of(func, repeat):
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = func()
        times.append(time.perf_counter() - start)
    return min(times), out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    args = parser.parse_args()

    root = Path(__file__).resolve().parents[1]
    sections = read_json(root / "data" / "controllers" / "K_ours.json", "float32")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # the fit's identifiability notes
        dahl = workbook_dahl_fit().model
    stage = VirtualStage(seed=0)
    f = 1.0
    v_r = experiments.tracking_reference(f, experiments.tracking_periods(f))[1]
    n = v_r.size

    def case_III(**kw):
        return loop.run_loop(stage, v_r, feedforward=dahl, controller=sections, **kw)

    t1, single = best_of(case_III, args.repeat)
    print(f"Case III, tracking test at {f:g} Hz: {n} samples, controller {sections.name} "
          f"({len(sections.sos)} float32 sections), delay {loop.COMPUTATION_DELAY_SAMPLES}")
    print(f"{'path':24s} {'seeds':>5s} {'time [s]':>9s} {'x single':>9s} "
          f"{'us/sample':>10s} {'us/sample/seed':>15s}")
    print(f"{'single (scalar)':24s} {1:5d} {t1:9.3f} {1.0:9.2f} {t1 / n * 1e6:10.1f} "
          f"{t1 / n * 1e6:15.2f}")
    for N in SEED_COUNTS:
        tN, runs = best_of(lambda: case_III(seeds=range(N)), args.repeat)
        print(f"{'batched':24s} {N:5d} {tN:9.3f} {tN / t1:9.2f} {tN / n * 1e6:10.1f} "
              f"{tN / n / N * 1e6:15.2f}")
        for i in {0, N - 1}:
            one = single if i == 0 else loop.run_loop(stage.replace(seed=i), v_r,
                                                      feedforward=dahl, controller=sections)
            assert np.array_equal(runs[i].v_y_V, one.v_y_V), (N, i)
    print("goal: 32 seeds within about 3x the single run")


if __name__ == "__main__":
    main()
