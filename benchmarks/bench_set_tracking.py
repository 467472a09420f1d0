"""Case III over the paper's 729-model set: the six Table 5 trajectories (prints numbers).

Every member of the ±5 % set on a0...a5 (3 levels per coefficient) runs Case III
of the tracking test at 1, 10, 20, 30, 40 and 50 Hz on the batched loop
(``workbook.set_tracking.tracking_over_set``: the workbook's Dahl feedforward,
the deployed controller as float32 sections from data/controllers/, one sample
of computation delay, members in batches of MEMBERS_PER_BATCH).  The members
whose sampled loop is unstable are not run (their count is printed); the time
covers the stability analysis, building the members and running the rest.

Goal (issue "Tracking over the whole uncertainty set"): 729 plants x the six
trajectories in at most 60 s on a 2-core machine.

    python benchmarks/bench_set_tracking.py [--controller K_ours|K_published] [--repeat 1]
"""

import argparse
import time
import warnings

from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.robust.export import read_json
from piezolib.uncertainty import model_set
from piezolib.workbook import outputs, set_tracking


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controller", default="K_ours", choices=("K_ours", "K_published"))
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()
    K = read_json(outputs.study_controllers_dir("reference") / f"{args.controller}.json",
                  "float32")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # the fit's FitWarning: notebook 03's subject
        dahl = workbook_dahl_fit().model
    stage = VirtualStage(seed=0)
    mset = model_set(stage.settings.plant, 0.05, 3)
    best = None
    for _ in range(args.repeat):
        start = time.perf_counter()
        res = set_tracking.tracking_over_set(stage, mset, dahl, K)
        seconds = time.perf_counter() - start
        best = seconds if best is None else min(best, seconds)
    run = mset.size - res.unstable.size
    print(f"Case III, {args.controller}, {mset.size} members x {res.errors.shape[1]} trajectories "
          f"(1-50 Hz), delay {res.delay_samples}: {res.unstable.size} unstable (not run), "
          f"{run} run")
    print(f"  {best:.1f} s (best of {args.repeat}), {res.samples / 1e6:.1f} million member-samples, "
          f"{1e9 * best / res.samples:.0f} ns per member-sample; goal <= 60 s: "
          f"{'met' if best <= 60 else 'missed'}")
    print(res.summary().round(3).to_string())


if __name__ == "__main__":
    main()
