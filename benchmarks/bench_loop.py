"""Speed of the 10 kHz loop of Fig. 1, the Sec. V experiments and notebook 06 (prints numbers).

Goals: a 1 s closed-loop run at 10 kHz (10 001 samples) well under a second
with any of the three controllers; open-loop runs (Cases I, II) in a few
milliseconds; both experiments of Sec. V (Tables 4-5) for one controller
well under a second; notebook 06 in about 10 s.

    python benchmarks/bench_loop.py [--skip-notebook]
"""

import argparse
import subprocess
import sys
import time
from pathlib import Path

from piezolib import paper
from piezolib.problem import stage as vstage
from piezolib.problem.design import design_controller
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.robust.discrete import discretize
from piezolib.robust.export import controller_sos
from piezolib.workbook import experiments

from bench_stage import best_of      # scripts run from benchmarks/ see each other


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-notebook", action="store_true")
    args = parser.parse_args()

    stage = vstage.VirtualStage(seed=0)
    dahl = workbook_dahl_fit().model                         # the notebooks' feedforward model
    G, H_m, H_e, H_y, K_pub = paper.problem()
    design = design_controller(G, H_m, H_e, H_y)
    fs = paper.SAMPLING_FREQUENCY_HZ
    controllers = {"ours, 6th order": design.K_deployed_discrete,
                   f"ours, full order ({design.K_full.nstates})": discretize(design.K_full, fs).K,
                   "published K (eq. 24)": discretize(K_pub, fs).K}
    t, v_r = experiments.tracking_reference(10.0, 10)        # 1 s of a 10 Hz, 12 um triangle
    n = v_r.size

    t_open = best_of(lambda: experiments.run_case("I", stage, v_r, dahl))
    t_ff = best_of(lambda: experiments.run_case("II", stage, v_r, dahl))
    print(f"1 s run ({n} samples), Case I (open loop, vectorised):   {t_open * 1e3:7.1f} ms")
    print(f"1 s run ({n} samples), Case II (Dahl feedforward):       {t_ff * 1e3:7.1f} ms")

    def stage_alone():
        sim = stage.start()
        for u in ((v_r - dahl.x0) / dahl.g_a).tolist():
            sim.step(u)

    t_stage = best_of(stage_alone)
    print(f"stage stepping alone, 1 s:                               {t_stage * 1e3:7.1f} ms "
          f"({t_stage / n * 1e6:.1f} us/sample)")
    for name, K in controllers.items():
        t_c = best_of(lambda: experiments.run_case("III", stage, v_r, dahl, K))
        print(f"1 s run, Case III with {name:28s}     {t_c * 1e3:7.1f} ms "
              f"({t_c / n * 1e6:.1f} us/sample, goal < 1000 ms)")
    for name, K in controllers.items():
        sos = controller_sos(K)
        t_c = best_of(lambda: experiments.run_case("III", stage, v_r, dahl, sos))
        print(f"1 s run, Case III, float32 sections of {name:16s}   {t_c * 1e3:7.1f} ms "
              f"({t_c / n * 1e6:.1f} us/sample, delay 1 sample)")
    K = controllers["ours, 6th order"]
    t_exp = best_of(lambda: (experiments.hysteresis_test(stage, dahl, K),
                             experiments.tracking_test(stage, dahl, K)), repeat=1)
    print(f"Tables 4 and 5 (all cases), one controller:              {t_exp * 1e3:7.1f} ms")

    if not args.skip_notebook:
        root = Path(__file__).resolve().parents[1]
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pytest", "-q",
                        str(root / "notebooks" / "06_tracking_experiments.ipynb")],
                       cwd=root, check=True, capture_output=True)
        print(f"notebook 06 under pytest/nbval (kernel start included):  "
              f"{time.perf_counter() - start:7.1f} s")


if __name__ == "__main__":
    main()
