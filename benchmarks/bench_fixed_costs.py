"""Fixed costs of the toolkit against its peers, side by side on the same problems.

* ``robust.hinfsyn`` (default options) against SLICOT's SB10AD called directly
  (``slycot.sb10ad``, gamma 1e100 as python-control passes it) and against
  ``control.hinfsyn`` (SB10AD behind python-control's wrapper);
* ``robust.loop_margins`` against ``control.stability_margins(G * K)``.

Problems: the textbook plants of ``benchmarks/bench_textbook.py`` (S&P's S/KS design,
the two-mass spring, S&P's distillation column) and the first ``--count`` random plants
of ``benchmarks/bench_hinf_random.py`` (family ``siso``), built by their own builders.
The loops of the margins are each plant's own: the textbook G with our H-infinity K,
and -P22 with our K for the random plants (hinfsyn's positive feedback as a negative
one), plus the paper's published loop.

Each time is the median of ``--repeats`` runs, the competitors interleaved run by run;
times are CPU seconds (SB10AD and ct.hinfsyn timed inside a child process, killed after
``--timeout`` s, shown as inf) with BLAS limited to one thread (on a shared
2-core machine multithreaded OpenBLAS made SB10AD 5-40x slower, and wall time follows
the other users' load).  Prints one table per tool and the ratios.

Usage, from the repository root::

    python benchmarks/bench_fixed_costs.py [--count 22] [--repeats 3]
"""

import argparse
import math
import pathlib
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import TimeoutError as FuturesTimeout

import control as ct
import numpy as np
from threadpoolctl import threadpool_limits

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_hinf_random  # noqa: E402  (puts tests/robust on the path for textbook_problems)
import bench_textbook  # noqa: E402

from piezolib.problem import paper  # noqa: E402
from piezolib.robust import hinfsyn, loop_margins  # noqa: E402

tp = bench_textbook.tp


def plants(count):
    """name -> (P, nmeas, ncon, G or None): textbook plants, then the random ones."""
    out = {"S&P 2.8.3 S/KS": (tp.disturbance_process().P, 1, 1, tp.disturbance_process().G),
           "two-mass spring": (tp.two_mass_spring().P, 1, 1, None),
           "S&P 8.12 distillation": (tp.distillation_column().P, 2, 2, None)}
    for seed in range(count):
        P, nmeas, ncon, _ = bench_hinf_random.siso_plant(seed)
        out[f"random siso {seed}"] = (P, nmeas, ncon, None)
    return out


def peer_in_child(which, matrices, nmeas, ncon):
    """(CPU seconds, gamma) of SB10AD ("sb10ad": slycot called directly) or of
    ``control.hinfsyn`` ("ct") on the plant ``matrices``, in this (child) process."""
    from slycot import sb10ad
    warnings.simplefilter("ignore")
    A, B, C, D = (np.asarray(x, float) for x in matrices)
    with threadpool_limits(1):
        t0 = time.process_time()
        try:
            if which == "sb10ad":
                gamma = sb10ad(A.shape[0], B.shape[1], C.shape[0], ncon, nmeas, 1e100,
                               A, B, C, D)[0]
            else:
                gamma = ct.hinfsyn(ct.ss(A, B, C, D), nmeas, ncon)[2]
        except Exception:                 # a peer's failure is reported, not fatal
            gamma = float("nan")
        return time.process_time() - t0, float(gamma)


class Peers:
    """SB10AD and ct.hinfsyn run in a child process, killed after ``timeout`` s (SB10AD
    is known to run for minutes on some plants)."""

    def __init__(self, timeout):
        self.timeout, self.pool = timeout, ProcessPoolExecutor(max_workers=1)

    def run(self, which, P, nmeas, ncon):
        """(CPU seconds or inf after the timeout, gamma)."""
        future = self.pool.submit(peer_in_child, which, (P.A, P.B, P.C, P.D), nmeas, ncon)
        try:
            return future.result(timeout=self.timeout)
        except FuturesTimeout:
            for proc in list((self.pool._processes or {}).values()):
                proc.kill()
            self.pool.shutdown(wait=False, cancel_futures=True)
            self.pool = ProcessPoolExecutor(max_workers=1)
            return math.inf, float("nan")


def cpu(fn):
    """(CPU seconds, result) of fn(); an exception counts as the result."""
    t0 = time.process_time()
    try:
        out = fn()
    except Exception as exc:              # a peer's failure is reported, not fatal
        out = exc
    return time.process_time() - t0, out


def interleaved(fns, repeats):
    """Median CPU time of each of ``fns`` over ``repeats`` interleaved rounds, and the
    last results; a function may time itself by returning (seconds, result)."""
    times, results = [[] for _ in fns], [None] * len(fns)
    for _ in range(repeats):
        for k, (fn, self_timed) in enumerate(fns):
            t, results[k] = cpu(fn)
            if self_timed:
                t, results[k] = results[k]
            times[k].append(t)
    return [float(np.median(t)) for t in times], results


def row(cells, widths):
    """One line of a table, printed as soon as it is measured."""
    print("  ".join(str(x).rjust(w) if i else str(x).ljust(w)
                    for i, (x, w) in enumerate(zip(cells, widths))), flush=True)


def bench_hinfsyn(problems, repeats, timeout):
    loops, ratios, peers = {}, {}, Peers(timeout)
    widths = (22, 3, 11, 12, 13, 12, 16, 8, 6)
    row(("plant", "n", "gamma", "SB10AD gamma", "hinfsyn [ms]", "SB10AD [ms]",
         "ct.hinfsyn [ms]", "/SB10AD", "/ct"), widths)
    for name, (P, nmeas, ncon, G) in problems.items():
        (t_ours, t_sb, t_ct), (res, gamma_sb, _) = interleaved(
            [(lambda: hinfsyn(P, nmeas, ncon), False),
             (lambda: peers.run("sb10ad", P, nmeas, ncon), True),
             (lambda: peers.run("ct", P, nmeas, ncon), True)], repeats)
        if isinstance(res, Exception):
            row((name, P.nstates, "raised", f"{gamma_sb:.6g}", "", "", "", "", ""), widths)
            continue
        ratios[name] = (t_ours / t_sb, t_ours / t_ct)
        row((name, P.nstates, f"{res.gamma:.6g}", f"{gamma_sb:.6g}", f"{1e3 * t_ours:.1f}",
             f"{1e3 * t_sb:.1f}", f"{1e3 * t_ct:.1f}", f"{t_ours / t_sb:.2f}",
             f"{t_ours / t_ct:.2f}"), widths)
        loops[name] = (G if G is not None else -P[P.noutputs - 1, P.ninputs - 1], res.K) \
            if nmeas == ncon == 1 else None
    peers.pool.shutdown(wait=False, cancel_futures=True)
    textbook = [r for n, r in ratios.items() if not n.startswith("random")]
    random = [r for n, r in ratios.items() if n.startswith("random")]
    print(f"\nhinfsyn / SB10AD on the random plants: median {np.median([r[0] for r in random]):.2f}, "
          f"max {max(r[0] for r in random):.2f}; slower than SB10AD on "
          f"{sum(r[0] > 1 for r in random)} of {len(random)}")
    print(f"hinfsyn / ct.hinfsyn on the textbook plants: "
          + ", ".join(f"{r[1]:.2f}" for r in textbook) + " (goal <= 2)\n")
    return {n: loop for n, loop in loops.items() if loop is not None}


def bench_margins(loops, repeats):
    G, _, _, _, K = paper.problem()
    loops = {"paper (published K)": (G, K), **loops}
    ratios, widths = [], (22, 14, 10, 17, 8, 6)
    row(("loop", "modulus margin", "ct sm", "loop_margins [ms]", "ct [ms]", "ratio"), widths)
    for name, (G, K) in loops.items():
        (t_ours, t_ct), (m, ref) = interleaved(
            [(lambda: loop_margins(G, K), False),
             (lambda: ct.stability_margins(G * K), False)], repeats)
        sm = ref[2] if not isinstance(ref, Exception) else float("nan")
        ratios.append(t_ours / t_ct)
        row((name, f"{m.modulus_margin:.6g}", f"{sm:.6g}", f"{1e3 * t_ours:.1f}",
             f"{1e3 * t_ct:.1f}", f"{t_ours / t_ct:.2f}"), widths)
    print(f"\nloop_margins / ct.stability_margins: median {np.median(ratios):.2f}, "
          f"max {max(ratios):.2f} (goal <= 2)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=22, help="random plants")
    ap.add_argument("--repeats", type=int, default=3, help="runs per timing (median)")
    ap.add_argument("--timeout", type=float, default=30.0, help="SB10AD time limit [s]")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    with threadpool_limits(1):
        loops = bench_hinfsyn(plants(args.count), args.repeats, args.timeout)
        bench_margins(loops, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
