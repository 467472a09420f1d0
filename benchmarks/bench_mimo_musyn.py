"""Benchmark: piezolib's MIMO DK-iteration (musyn) beside dkpy's on the mirror's 3 x 3 problem.

The problem is notebook 10's (``piezolib.problem.fsm_mimo``): the fine steering mirror's
all-levels 3 x 3 model in the w-plane of the 6.4 kHz loop with one sample of delay, a full
complex 3 x 3 output-multiplicative block (the levels' spread), per-axis templates on S, T and
the controller output; blocks ((3, 3), (3, 9)), 3 measurements and 3 controls.  Both get the
same plant (handed to dkpy in scaled time s -> s / OMEGA_S, as bench_musyn.py does; OMEGA_S
is 1e3 here, see there), the same grid, the same number of
DK iterations and the same D-scaling order.  Prints, for each: wall time, controller order,
its own mu and, with one yardstick (``piezolib.robust.mussv`` on the same grid, the loop's
closed-loop poles), whether its closed loop is stable and its mu_RP upper bound.

dkpy is not a project dependency: run in the benchmark environment
(``sh benchmarks/setup_dkpy.sh``); without dkpy its part is skipped with a message.  dkpy runs
in a child process stopped after ``--dkpy-timeout`` seconds.

Usage, from the repository root::

    benchmarks/.dkpy-venv/bin/python benchmarks/bench_mimo_musyn.py [--iterations 3]
"""

import argparse
import multiprocessing as mp
import os
import sys
import time
import warnings

import numpy as np

from piezolib import robust
from piezolib.problem import fsm_mimo, fsm_models

#: Time scale handed to dkpy [rad/s].  At 1e4 (bench_musyn.py's) SLICOT's SB10AD returns no
#: controller for this plant in the first K-step and dkpy, not checking, fails on the NaN loop
#: (numpy "SVD did not converge" inside control's lft); at 1e3 and in seconds it returns one.
OMEGA_S = 1e3


def problem():
    """The mirror's 3 x 3 synthesis plant (nominal of DESIGN_PARAMETERS)."""
    data = fsm_models.level_blas()
    linear = fsm_models.fit_linear_models(data, (24, 32, 40, 48), 28)
    nominal = fsm_mimo.mirror_nominal(linear, data.frequency_Hz,
                                      fsm_mimo.DESIGN_PARAMETERS["nominal_order"])
    rec = fsm_mimo.read_mirror_record()
    return fsm_mimo.synthesis_plant(nominal, rec.params, rec.weights)[0]


def check(P, K, omega):
    """(stable, largest real part of the closed-loop poles [rad/s], mu peak or None)."""
    cl = robust.lower_lft(P, K)
    max_real = float(np.linalg.eigvals(cl.A).real.max())
    if max_real >= 0:
        return False, max_real, None
    mu = robust.mussv(robust.lft_response(P, K, omega), fsm_mimo.MIMO_BLOCKS, omega, lower=False)
    return True, max_real, float(mu.upper.max())


def describe(stable, max_real, mu):
    if not stable:
        return f"closed loop UNSTABLE (a pole at Re s = {max_real:+.4g} rad/s): mu undefined"
    return f"mu_RP {mu:.4f}; closed loop stable (slowest pole Re s = {max_real:.4g} rad/s)"


def run_dkpy(queue, P, omega, iterations, d_order, omega_s):
    try:
        import dkpy
        warnings.simplefilter("ignore")
        Ps = robust.to_scaled(P, omega_s)
        dk = dkpy.DkIterFixedOrder(controller_synthesis=dkpy.HinfSynSlicot(),
                                   structured_singular_value=dkpy.SsvLmiBisection(n_jobs=1),
                                   d_scale_fit=dkpy.DScaleFitSlicot(),
                                   n_iterations=iterations, fit_order=d_order)
        t0 = time.perf_counter()
        K, _, mu, _, _ = dk.synthesize(Ps, 3, 3, omega / omega_s,
                                       [list(b) for b in fsm_mimo.MIMO_BLOCKS])
        seconds = time.perf_counter() - t0
        if K is None:
            queue.put(("error", f"dkpy returned no controller after {seconds:.1f} s"))
            return
        queue.put(("ok", seconds, float(mu), K.A, K.B, K.C, K.D))
    except Exception as exc:                      # report dkpy's failure, do not hide it
        queue.put(("error", f"{type(exc).__name__}: {exc}"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=3, help="DK iterations of each")
    ap.add_argument("--d-order", type=int, default=4, help="order of the D-scaling fits")
    ap.add_argument("--n", type=int, default=120, help="grid points, 0.1 ... 3e5 rad/s")
    ap.add_argument("--dkpy-timeout", type=float, default=1800.0, help="[s] for dkpy")
    ap.add_argument("--omega-s", type=float, default=OMEGA_S,
                    help="time scale [rad/s] of the plant handed to dkpy (1: seconds)")
    args = ap.parse_args()
    import control as ct

    omega = np.logspace(-1, 5.5, args.n)
    P = problem()
    print(f"mirror 3 x 3 plant: {P.nstates} states, {P.ninputs} inputs, {P.noutputs} outputs; "
          f"blk {fsm_mimo.MIMO_BLOCKS}; {args.n} frequencies; {args.iterations} iterations, "
          f"D order {args.d_order}; {os.cpu_count()} CPU(s), load {os.getloadavg()[0]:.1f}")
    t0 = time.perf_counter()
    res = robust.musyn(P, fsm_mimo.MIMO_BLOCKS, 3, 3, omega, d_order=args.d_order,
                       max_iter=args.iterations)
    ours_s = time.perf_counter() - t0
    ours = check(P, res.K, omega)
    print("\npiezolib.robust.musyn")
    print(f"  time              : {ours_s:8.1f} s; {len(res.history)} K-steps ({res.stop_reason})")
    print(f"  controller order  : {res.K.nstates}")
    print(f"  mu, its own       : {res.mu_peak:.4f} (lower {res.mu_lower_peak:.4f})")
    print(f"  one yardstick     : {describe(*ours)}")
    try:
        import dkpy  # noqa: F401
    except ImportError as exc:
        print(f"\ndkpy part skipped: dkpy is not importable here ({exc}); see benchmarks/README.md")
        return 0
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=run_dkpy, args=(queue, P, omega, args.iterations, args.d_order,
                                                   args.omega_s))
    sys.stdout.flush()
    t0 = time.perf_counter()
    proc.start()
    proc.join(args.dkpy_timeout)
    print(f"\ndkpy DkIterFixedOrder ({args.iterations} iterations, HinfSynSlicot, "
          f"SsvLmiBisection, DScaleFitSlicot; plant in time scale {args.omega_s:g} rad/s)")
    if proc.is_alive():
        proc.terminate()
        proc.join()
        print(f"  no result within {args.dkpy_timeout:.0f} s (stopped)")
        return 0
    out = queue.get(timeout=5) if not queue.empty() else \
        ("error", f"the child exited with code {proc.exitcode} and no output")
    if out[0] != "ok":
        print(f"  failed after {time.perf_counter() - t0:.1f} s: {out[1]}")
        return 0
    seconds, mu_own = out[1], out[2]
    K_dk = robust.from_scaled(ct.ss(*out[3:]), args.omega_s)
    theirs = check(P, K_dk, omega)
    print(f"  time              : {seconds:8.1f} s")
    print(f"  controller order  : {K_dk.nstates}")
    print(f"  mu, its own       : {mu_own:.4f}")
    print(f"  one yardstick     : {describe(*theirs)}")
    print(f"\ntime ratio dkpy / musyn: {seconds / ours_s:.1f} x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
