"""Benchmark: piezolib's DK-iteration (musyn) against dkpy's on this problem.

Both get the same synthesis plant (eq. 16 with the effort output 1e-3 u_b,
``genplant.design_plant``), the same block structure (Delta_r 1x1, the
performance block 1x3) and the same 300-point grid 1e-2 ... 1e7 rad/s, with
4th-order D-scaling fits.  dkpy receives the plant in scaled time
(s -> s/1e4, the grid scaled alike): on the plant in seconds its H-infinity
step (python-control's hinfsyn = SLICOT SB10AD) did not return within minutes.
Prints, in one run:

* musyn: wall time (best of ``--repeats``), iterations, controller order and
  the mu_RP peak;
* dkpy ``DkIterFixedOrder`` (``HinfSynSlicot``, ``SsvLmiBisection``,
  ``DScaleFitSlicot``): wall time, controller order, its own mu and ours;
* both controllers measured with one yardstick: closed-loop stability (the
  largest real part of the closed-loop poles) and, for a stable loop, the mu
  upper bound (``piezolib.robust.mu.mussv``) of the exact M of eq. 18 on the
  grid, evaluated in scaled time.  A controller that fails a check is
  reported as such, with the number that failed (e.g. an unstable closed
  loop and its right-half-plane pole), never as a bare NaN;
* the wall time of notebook 05 executed headless (goal: under 30 s).

dkpy is not a project dependency: run this in the benchmark environment (see
benchmarks/README.md); without dkpy its part is skipped with a message.
dkpy runs in a child process that is stopped after ``--dkpy-timeout`` s; its
joblib workers are shut down when it finishes, so the script exits as soon as
the last timed part is done.

Usage, from the repository root (``sh benchmarks/setup_dkpy.sh`` creates the
environment)::

    benchmarks/.dkpy-venv/bin/python benchmarks/bench_musyn.py [--dkpy-iterations 3]
"""

import argparse
import multiprocessing as mp
import os
import pathlib
import sys
import time
import warnings

import numpy as np

from piezolib.problem import genplant
from piezolib import paper, robust
from piezolib.robust.dk import musyn
from piezolib.robust.mu import mussv

OMEGA_S = 1e4                      # time scale handed to dkpy [rad/s]
DESIGN_BLK = genplant.DESIGN_BLOCK_STRUCTURE
MODELS = paper.problem()[:4]      # G, H_m, H_e, H_y
ROOT = pathlib.Path(__file__).resolve().parents[1]


def exact_mu(K_scaled, omega):
    """Check a controller given in scaled time on the exact M (eq. 18).

    Returns ``(mu, stable, max_real)``: the mu upper-bound peak (None when the
    closed loop is unstable: mu is then meaningless), closed-loop stability
    and the largest real part of the closed-loop poles [rad/s, unscaled].
    """
    P = robust.to_scaled(genplant.generalized_plant(*MODELS), OMEGA_S)
    poles = np.linalg.eigvals(P.lft(K_scaled).A)
    max_real = float(poles.real.max()) * OMEGA_S
    if max_real >= 0:
        return None, False, max_real
    M = robust.lft_response(P, K_scaled, omega / OMEGA_S, omega_s=1.0)
    return float(mussv(M, genplant.BLOCK_STRUCTURE, lower=False).upper.max()), True, max_real


def describe(mu, stable, max_real):
    """One line: the mu peak of a stable loop, or which check failed and by how much."""
    if not stable:
        return (f"closed loop UNSTABLE (a closed-loop pole at Re s = {max_real:+.4g} rad/s), "
                "so its mu is not defined")
    return f"{mu:.5f}; closed loop stable (slowest pole Re s = {max_real:.4g} rad/s)"


def shutdown_joblib_workers():
    """Stop joblib's reusable loky workers, which otherwise idle for 300 s before exiting."""
    try:
        from joblib.externals.loky import get_reusable_executor
    except ImportError:
        return
    get_reusable_executor().shutdown(wait=True)


def run_dkpy(queue, omega, iterations, d_order, n_jobs):
    """Child process: dkpy's DK-iteration; puts (seconds, mu, A, B, C, D) or an error."""
    try:
        import dkpy
        warnings.simplefilter("ignore")
        Ps = robust.to_scaled(genplant.design_plant(*MODELS), OMEGA_S)
        dk = dkpy.DkIterFixedOrder(controller_synthesis=dkpy.HinfSynSlicot(),
                                   structured_singular_value=dkpy.SsvLmiBisection(n_jobs=n_jobs),
                                   d_scale_fit=dkpy.DScaleFitSlicot(),
                                   n_iterations=iterations, fit_order=d_order)
        t0 = time.perf_counter()
        K, _, mu, _, _ = dk.synthesize(Ps, 1, 1, omega / OMEGA_S, [list(b) for b in DESIGN_BLK])
        seconds = time.perf_counter() - t0
        if K is None:
            queue.put(("error", f"dkpy returned no controller after {seconds:.1f} s"))
            return
        queue.put(("ok", seconds, float(mu), K.A, K.B, K.C, K.D))
    except Exception as exc:                      # report, do not hide, dkpy's failure
        queue.put(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        shutdown_joblib_workers()


def time_notebook(path):
    import nbformat
    from nbclient import NotebookClient
    nb = nbformat.read(path, as_version=4)
    os.environ.setdefault("MPLBACKEND", "Agg")
    t0 = time.perf_counter()
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=300, help="grid points, 1e-2 ... 1e7 rad/s")
    ap.add_argument("--d-order", type=int, default=4, help="order of the D-scaling fits")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs of musyn (best kept)")
    ap.add_argument("--dkpy-iterations", type=int, default=3, help="dkpy D-K iterations")
    ap.add_argument("--dkpy-timeout", type=float, default=900.0, help="[s] for dkpy")
    ap.add_argument("--dkpy-jobs", type=int, default=1,
                    help="joblib processes of dkpy's mu bound (1: sequential, like mussv)")
    ap.add_argument("--skip-notebook", action="store_true", help="do not time notebook 05")
    args = ap.parse_args()
    omega = np.logspace(-2, 7, args.n)
    P = genplant.design_plant(*MODELS)
    print(f"synthesis plant: {P.nstates} states, outputs {P.output_labels}; blk {DESIGN_BLK}; "
          f"{args.n} frequencies {omega[0]:g} ... {omega[-1]:g} rad/s; D order {args.d_order}; "
          f"{os.cpu_count()} CPU(s)")

    times, res = [], None
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = musyn(P, DESIGN_BLK, 1, 1, omega, d_order=args.d_order)
        times.append(time.perf_counter() - t0)
    K_ours = robust.to_scaled(res.K, OMEGA_S)
    ours = exact_mu(K_ours, omega)
    print("\npiezolib.robust.dk.musyn")
    print(f"  time                    : {min(times):8.2f} s (best of {args.repeats})")
    print(f"  iterations (K-steps)    : {len(res.history)}; stop: {res.stop_reason}")
    print(f"  controller order        : {res.K.nstates}")
    print(f"  mu peak, design M       : {res.mu_peak:.5f} (lower bound {res.mu_lower_peak:.5f})")
    print(f"  mu peak, exact M eq. 18 : {describe(*ours)}")

    try:
        import dkpy  # noqa: F401
    except ImportError as exc:
        print(f"\ndkpy comparison skipped: dkpy is not importable here ({exc}).\n"
              "Run in the benchmark environment: see benchmarks/README.md.")
    else:
        ctx = mp.get_context("fork")
        queue = ctx.Queue()
        proc = ctx.Process(target=run_dkpy,
                           args=(queue, omega, args.dkpy_iterations, args.d_order,
                                 args.dkpy_jobs))
        sys.stdout.flush()                      # the forked child inherits the buffer
        t0 = time.perf_counter()
        proc.start()
        proc.join(args.dkpy_timeout)
        if proc.is_alive():
            proc.terminate()
            proc.join()
            print(f"\ndkpy: no result within {args.dkpy_timeout:.0f} s (stopped)")
        else:
            out = queue.get(timeout=5) if not queue.empty() else \
                ("error", f"the child process exited with code {proc.exitcode} and no output")
            print(f"\ndkpy DkIterFixedOrder ({args.dkpy_iterations} iterations, "
                  f"HinfSynSlicot, SsvLmiBisection, DScaleFitSlicot)")
            if out[0] != "ok":
                print(f"  failed after {time.perf_counter() - t0:.1f} s: {out[1]}")
            else:
                import control as ct
                seconds, mu_dk_own = out[1], out[2]
                K_dk = ct.ss(*out[3:])
                theirs = exact_mu(K_dk, omega)
                print(f"  time                    : {seconds:8.2f} s")
                print(f"  controller order        : {K_dk.nstates}")
                print(f"  mu peak, dkpy's own     : {mu_dk_own:.5f}")
                print(f"  mu peak, exact M eq. 18 : {describe(*theirs)}")
                print("\ncomparison (same plant, grid and D order; one machine)")
                print(f"  time ratio dkpy / musyn : {seconds / min(times):8.1f} x")
                if ours[1] and theirs[1]:
                    print(f"  mu_RP peak musyn - dkpy : {ours[0] - theirs[0]:+.5f}")
                    print(f"  goal 'mu_RP peak at least as low as dkpy's': "
                          f"{'met' if ours[0] <= theirs[0] * (1 + 1e-6) else 'NOT met'}")
                else:
                    failed = [name for name, r in (("musyn", ours), ("dkpy", theirs)) if not r[1]]
                    print(f"  mu_RP peaks not compared: the closed loop of {' and '.join(failed)}"
                          f"'s controller is unstable (see above)")

    if not args.skip_notebook:
        seconds = time_notebook(ROOT / "notebooks" / "05_mu_synthesis.ipynb")
        print(f"\nnotebook 05 executed headless: {seconds:.1f} s "
              f"(goal < 30 s: {'met' if seconds < 30 else 'NOT met'})")
    K_pub = robust.to_scaled(paper.controller(), OMEGA_S)
    print(f"\npublished K for reference: mu_RP of the exact M {describe(*exact_mu(K_pub, omega))}")
    shutdown_joblib_workers()
    return 0


if __name__ == "__main__":
    sys.exit(main())
