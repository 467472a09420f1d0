"""Speed of the virtual stage and of the identification (prints numbers; no asserts).

Goals: one closed-loop step in a few tens of microseconds at most; a 2 s
chirp run well under a second; identification of the chirp in about a
second; notebook 01 in about 10 s.

    python benchmarks/bench_stage.py
"""

import time
import warnings

from piezolib import identification as ident
from piezolib.problem import stage as vstage
from piezolib.problem import stage_calibration, stage_data


def best_of(func, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    stage = vstage.VirtualStage(seed=0)
    u, _ = stage_data.chirp_input(stage_data.IDENTIFICATION_CHIRP, stage.fs)
    t = best_of(lambda: stage.run(u))
    print(f"run(), 2.25 s chirp ({len(u)} samples):      {t * 1e3:7.1f} ms")

    triangles = [stage_calibration.case_I_input(A) for A in (10.0, 20.0, 30.0, 40.0)]
    t = best_of(lambda: [stage.run(x) for x in triangles])
    print(f"run(), four Case I triangles:              {t * 1e3:7.1f} ms")

    def stepping():
        sim = stage.start()
        for u_k in u.tolist():
            sim.step(u_k)
    t = best_of(stepping)
    print(f"step(), per sample:                        {t / len(u) * 1e6:7.1f} us")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = best_of(stage_calibration.calibrate_hysteresis, repeat=1)
    print(f"calibrate_hysteresis():                    {t:7.2f} s")

    ex = stage_data.load_chirp("identification")
    du, dy, _ = ex.deviations()
    t = best_of(lambda: ident.identify(du, dy, stage.fs), 1)
    print(f"identify(), {len(du)} samples:              {t:7.2f} s")
    phi, target, _ = ident.arx_regressors(du, dy, 6, 6, 1)
    t = best_of(lambda: ident.rls(phi, target, initial_gain=1e10), 1)
    print(f"rls(), per sample (12 parameters):         {t / len(target) * 1e6:7.1f} us")


if __name__ == "__main__":
    main()
