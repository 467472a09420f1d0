"""Benchmark: mixed-mu synthesis (D,G-K) beside complex DK on problems with known answers.

For each problem of ``tests/robust/textbook_problems.py`` with a real parameter (the
gain-margin problem of Tannenbaum / Doyle-Francis-Tannenbaum, the ACC two-cart benchmark
of Wie & Bernstein) it designs a controller three ways and prints one table:

    problem | method | time [s] | K order | own mu | mixed mu (same yardstick) |
    certified range | exact range | ratio hi/lo | known answer | settling [s]

* ``mixed_musyn``: piezolib's mixed-mu synthesis (complex DK start, then D,G-K steps), the
  parameter as a real scalar block; for the gain problem also started (``K0``) from the
  closed-form controller of ``textbook_problems.gain_margin_controller`` (its own row);
* ``musyn (complex)``: piezolib's DK iteration with the parameter as a complex 1 x 1 block;
* ``dkpy DK (complex)``: dkpy's fixed-order DK iteration (complex blocks only), run in the
  benchmark venv ``benchmarks/.dkpy-venv`` as a subprocess (``sh benchmarks/setup_dkpy.sh``),
  "n/a" without it.

Every controller is then measured with one yardstick: "own mu" is what its method reports,
"mixed mu" is piezolib's mixed-mu upper bound of its loop on the problem's grid, the
"certified range" is what that mixed mu certifies (k0 (1 +- r/mu) or k0 +- r/mu), and
the "exact range" is the stable interval of the physical parameter around its nominal
value from the exact crossing gains (``textbook_problems.real_stability_interval``, no
piezolib code).  "settling" is the ACC benchmark's nominal (k = 1) settling time of x2
after a unit impulse force on cart 2, to |x2| <= 0.1.  No timing is asserted.

The last rows are the paper's problem (G's +-5 % coefficient box as six real blocks, the
loop's delay, the paper's performance weights): the D,G-K steps of notebook 09 from our
deployed 6th-order K (``problem.design.design_mixed_controller``) beside complex DK on the
same plant (ours and dkpy's), each judged by mixed mu_RP on ``problem.design.MIXED_GRID``
and by the exact parametric margin with the loop's delay (zero exclusion).

Usage, from the repository root (``PYTHONPATH=.`` when this checkout is not the one the
environment has installed)::

    python benchmarks/bench_mixed_musyn.py              # about 4 minutes, plus dkpy
    python benchmarks/bench_mixed_musyn.py --no-dkpy
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import time
import warnings
from typing import NamedTuple

import control as ct
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
DKPY_PYTHON = ROOT / "benchmarks" / ".dkpy-venv" / "bin" / "python"

sys.path.insert(0, str(ROOT / "tests" / "robust"))      # its test-data modules
import textbook_problems as tp  # noqa: E402

# design grids [rad/s] (the same as tests/robust/test_dgk_textbook.py)
GAIN_GRID = np.logspace(-3, 3, 200)
ACC_GRID = np.logspace(-3, 2, 200)
# dkpy's mu bound is an LMI per frequency (about 0.1 s each): it gets every 4th point
DKPY_STRIDE = 4
DKPY_ITERATIONS = 3


class Problem(NamedTuple):
    name: str
    P: ct.StateSpace
    blk_mixed: list
    blk_complex: list
    grid: np.ndarray
    loop: object           # K -> (A0, b, c, k0), the physical loop affine in the parameter
    k0: float
    r: float
    additive: bool         # k = k0 + r delta (True) or k0 (1 + r delta)
    known: str
    settling: object = None    # K -> settling time [s] or None
    reference: object = None   # () -> (label, K) of a known controller, or None


class Row(NamedTuple):
    problem: str
    method: str
    seconds: float
    order: object
    own_mu: object
    mixed_mu: object
    certified: object
    exact: object
    known: str
    settling: object


def problems():
    """The textbook problems with a real parameter, in table order."""
    gain = tp.gain_margin()
    carts = tp.acc_benchmark()
    return [
        Problem(f"gain margin p={gain.p:g}, z={gain.z:g}, k in [{gain.k_lo:g}, {gain.k_hi:g}]",
                gain.P, gain.blk_mixed, gain.blk_complex, GAIN_GRID,
                lambda K: tp.gain_loop(gain, K), gain.k0, gain.r, False,
                f"ratio < (z/p)^2 = {tp.gain_ratio_sup_real(gain.p, gain.z):g}; complex "
                f"certifies < z/p = {tp.gain_ratio_sup_complex(gain.p, gain.z):g}",
                reference=lambda: ("closed form, ratio 3.5", -ct.ss(
                    tp.gain_margin_controller(gain.p, gain.z, 1.0, 3.5, 30.0)) * 2.25)),
        Problem("ACC two carts, k in [0.5, 2]", carts.P, carts.blk_mixed, carts.blk_complex,
                ACC_GRID, lambda K: tp.spring_loop(carts, K), carts.k0, carts.r, True,
                "[0.5, 2] stabilisable (WB92)", lambda K: cart_settling(carts, K)),
    ]


def paper_plant(scale=1.0):
    """The paper's problem with G's +-5 % coefficient box as six real blocks, the loop's delay
    (one sample) and the performance weights times ``scale``: (P, mixed blk, complex blk)."""
    from piezolib import paper
    from piezolib.problem import genplant
    G, _, H_e, H_y, _ = paper.problem()
    P = genplant.parametric_design_plant(G, scale * H_e, scale * H_y, paper.UNCERTAINTY_SPREAD,
                                        fs=paper.SAMPLING_FREQUENCY_HZ)
    blk = list(genplant.parametric_block_structure(6))
    return P, blk, [(1, 1)] * 6 + [blk[-1]]


def paper_measure(method, K, seconds, own_mu):
    """A row of the paper's problem: mixed mu_RP on the design grid, exact margin (delay 1)."""
    from piezolib import paper, robust
    from piezolib import uncertainty as unc
    from piezolib.problem import design
    P, blk, _ = paper_plant()
    G = paper.plant()
    poles = np.linalg.eigvals(robust.lower_lft(P, K).A)
    if poles.real.max() >= 0:
        return Row(PAPER, method, seconds, K.nstates, own_mu,
                   f"unstable loop (pole at {poles.real.max():+.3g})", "-", "-", PAPER_KNOWN, None)
    N = robust.lft_response(P, K, design.MIXED_GRID)
    mu = float(robust.mussv(N, blk, lower=False).upper.max())
    margin = unc.parametric_stability_margin(G, K, delay=1.5 / paper.SAMPLING_FREQUENCY_HZ).spread
    return Row(PAPER, method, seconds, K.nstates, own_mu, mu, "-",
               f"+-{100 * margin:.3g} % (delay 1)", PAPER_KNOWN, None)


PAPER = "paper: G's +-5 % box, delay 1, paper's weights"
PAPER_KNOWN = "goal: exact margin >= +-5 %"


def paper_problem_rows(dkpy_design=None):
    """The paper's problem (performance scale 1): D,G-K steps from our deployed K against
    complex DK on the same plant (ours, and dkpy's when given)."""
    from piezolib import paper
    from piezolib.problem import design
    from piezolib.robust.dk import musyn
    from piezolib.workbook import pipeline
    G, _, H_e, H_y, _ = paper.problem()
    K0 = pipeline.study_controllers("reference").K_deployed
    rows = [paper_measure("start: our deployed K (6)", K0, None, "-")]
    t0 = time.perf_counter()
    res = design.design_mixed_controller(G, H_e, H_y, K0, performance_scale=1.0)
    rows.append(paper_measure("D,G-K steps from it", res.K, time.perf_counter() - t0,
                              res.mu_peak))
    P, _, blk_complex = paper_plant()
    t0 = time.perf_counter()
    dk = musyn(P, blk_complex, 1, 1, design.MIXED_GRID, d_order=2)
    rows.append(paper_measure("musyn (complex)", dk.K, time.perf_counter() - t0, dk.mu_peak))
    if dkpy_design is not None:
        if "error" in dkpy_design:
            rows.append(Row(PAPER, "dkpy DK (complex)", dkpy_design["seconds"], "-",
                            dkpy_design["error"], "-", "-", "-", PAPER_KNOWN, None))
        else:
            K = ct.ss(*(np.array(m, float) for m in dkpy_design["K"]))
            rows.append(paper_measure("dkpy DK (complex)", K, dkpy_design["seconds"],
                                      dkpy_design["mu"]))
    return rows


# --- yardstick -------------------------------------------------------------------------------

def cart_settling(carts, K, k=1.0, band=0.1, t_end=60.0):
    """Time [s] after which |x2| <= band for a unit impulse force on cart 2 at spring k."""
    A0, b, c, k0 = tp.spring_loop(carts, K)
    A = A0 + (k - k0) * b @ c
    B = np.zeros((A.shape[0], 1))
    B[3, 0] = 1 / carts.m2                      # impulse on cart 2: v2(0+) = 1/m2
    C = np.zeros((1, A.shape[0]))
    C[0, 1] = 1.0
    t = np.linspace(0, t_end, 6001)
    _, y = ct.impulse_response(ct.ss(A, B, C, 0), t)
    outside = np.nonzero(np.abs(np.ravel(y)) > band)[0]
    return float(t[outside[-1] + 1]) if outside.size and outside[-1] + 1 < t.size else (
        0.0 if not outside.size else np.inf)


def measure(prob, method, K, seconds, own_mu):
    """One table row: K judged by mixed mu on the problem's grid and by its exact range."""
    from piezolib import robust
    A0, b, c, k0 = prob.loop(K)
    worst = np.linalg.eigvals(A0).real.max()
    if worst >= 0:
        return Row(prob.name, method, seconds, K.nstates, own_mu,
                   f"unstable loop (pole at {worst:+.3g})", "-", "-", prob.known, None)
    N = tp.pointwise_lft(prob.P, K, prob.grid)
    mu = float(robust.mussv(N, prob.blk_mixed, lower=False).upper.max())
    rho = prob.r / mu
    if prob.additive:
        certified = (k0 - rho, k0 + rho)
    else:
        certified = (k0 * max(1 - rho, 0.0), k0 * (1 + rho))
    t_lo, t_hi = tp.real_stability_interval(A0, b, c)
    settling = prob.settling(K) if prob.settling else None
    return Row(prob.name, method, seconds, K.nstates, own_mu, mu, certified,
               (k0 + t_lo, k0 + t_hi), prob.known, settling)


def our_rows(prob):
    from piezolib.robust.dgk import mixed_musyn
    from piezolib.robust.dk import musyn
    rows = []
    if prob.reference:
        # a known controller (tp.gain_margin_controller, its interval [1, 3.5] rescaled by
        # (1 + 3.5)/2 to be centred on k0 = 1): what the mixed design can aim at
        label, K = prob.reference()
        rows.append(measure(prob, label, K, None, "-"))
    starts = [("mixed_musyn", {})]
    if prob.reference:
        starts.append(("mixed_musyn from it", {"K0": prob.reference()[1]}))
    for method, options in starts:
        t0 = time.perf_counter()
        try:
            res = mixed_musyn(prob.P, prob.blk_mixed, prob.grid, **options)
        except Exception as exc:                  # a failure is a finding, printed in the table
            rows.append(Row(prob.name, method, time.perf_counter() - t0, "-",
                            f"failed: {type(exc).__name__}: {exc}"[:60], "-", "-", "-",
                            prob.known, None))
        else:
            rows.append(measure(prob, method, res.K, time.perf_counter() - t0, res.mu_peak))
    t0 = time.perf_counter()
    res = musyn(prob.P, prob.blk_complex, 1, 1, prob.grid, d_order=2)
    rows.append(measure(prob, "musyn (complex)", res.K, time.perf_counter() - t0, res.mu_peak))
    return rows


# --- dkpy --------------------------------------------------------------------------------------

def dkpy_design(P, grid, blk_complex):
    """{'seconds', 'mu', 'K': [A, B, C, D]} or {'seconds', 'error'}: dkpy's DK on P."""
    import dkpy
    t0 = time.perf_counter()
    try:
        it = dkpy.DkIterFixedOrder(controller_synthesis=dkpy.HinfSynSlicot(),
                                   structured_singular_value=dkpy.SsvLmiBisection(),
                                   d_scale_fit=dkpy.DScaleFitSlicot(),
                                   n_iterations=DKPY_ITERATIONS, fit_order=2)
        K, _, mu, _, _ = it.synthesize(P, 1, 1, grid[::DKPY_STRIDE],
                                       [list(b) for b in blk_complex])
        if K is None:
            raise RuntimeError("no controller")
        K = ct.ss(K)
        return {"seconds": time.perf_counter() - t0, "mu": float(np.max(mu)),
                "K": [np.asarray(m, float).tolist() for m in (K.A, K.B, K.C, K.D)]}
    except Exception as exc:                      # report dkpy's failure in the table
        return {"seconds": time.perf_counter() - t0, "error": f"failed: {type(exc).__name__}"}


def dkpy_designs():
    """problem name -> :func:`dkpy_design` of it, the paper's problem under ``PAPER``."""
    from piezolib.problem import design
    out = {prob.name: dkpy_design(prob.P, prob.grid, prob.blk_complex) for prob in problems()}
    P, _, blk_complex = paper_plant()
    out[PAPER] = dkpy_design(P, design.MIXED_GRID, blk_complex)
    return out


def dkpy_results(skip):
    """(designs, note): dkpy's designs, through the benchmark venv, or none."""
    if skip:
        return {}, "dkpy rows skipped (--no-dkpy)"
    try:
        import dkpy  # noqa: F401
    except ImportError:
        pass
    else:
        return dkpy_designs(), "dkpy run in this interpreter"
    if not DKPY_PYTHON.exists():
        return {}, ("dkpy rows n/a: dkpy is not importable and benchmarks/.dkpy-venv does not "
                    "exist; create it with `sh benchmarks/setup_dkpy.sh`")
    env = dict(os.environ, PIEZOLIB_PROGRESS="0")
    proc = subprocess.run([str(DKPY_PYTHON), str(pathlib.Path(__file__).resolve()), "--dkpy-only"],
                          capture_output=True, text=True, cwd=ROOT, timeout=3600, env=env)
    if proc.returncode != 0:
        return {}, f"dkpy subprocess failed:\n{proc.stderr.strip()[-2000:]}"
    return json.loads(proc.stdout.strip().splitlines()[-1]), f"dkpy run by {DKPY_PYTHON}"


def dkpy_row(prob, design):
    if design is None:
        return Row(prob.name, "dkpy DK (complex)", None, "-", "n/a", "-", "-", "-", prob.known,
                   None)
    if "error" in design:
        return Row(prob.name, "dkpy DK (complex)", design["seconds"], "-", design["error"], "-",
                   "-", "-", prob.known, None)
    K = ct.ss(*(np.array(m, float) for m in design["K"]))
    return measure(prob, "dkpy DK (complex)", K, design["seconds"], design["mu"])


# --- table -------------------------------------------------------------------------------------

def fmt(x):
    if x is None:
        return "-"
    if isinstance(x, tuple):
        return "[" + ", ".join(f"{v:.4g}" for v in x) + "]"
    return f"{x:.4g}" if isinstance(x, (float, int, np.floating)) else str(x)


def print_table(rows):
    head = ("problem", "method", "time [s]", "K order", "own mu", "mixed mu", "certified range",
            "exact range", "ratio hi/lo", "settling [s]", "known answer")
    lines = []
    for r in rows:
        # the ratio is the gain problem's measure; the spring's range always ends at k = 0
        # (the carts decouple and cart 2's double integrator is lost), so it has none
        ratio = (r.exact[1] / r.exact[0] if isinstance(r.exact, tuple) and r.exact[0] > 0
                 and r.problem.startswith("gain") else "-")
        lines.append((r.problem, r.method, fmt(r.seconds), fmt(r.order), fmt(r.own_mu),
                      fmt(r.mixed_mu), fmt(r.certified), fmt(r.exact), fmt(ratio),
                      fmt(r.settling), r.known))
    widths = [max(len(str(x)) for x in col) for col in zip(head, *lines)]
    for line in (head, tuple("-" * w for w in widths), *lines):
        print(" | ".join(str(x).ljust(w) for x, w in zip(line, widths)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-dkpy", action="store_true", help="skip the dkpy rows")
    ap.add_argument("--dkpy-only", action="store_true",
                    help="print dkpy's designs as JSON (used in the dkpy venv subprocess)")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    if args.dkpy_only:
        print(json.dumps(dkpy_designs()))
        return 0
    os.environ.setdefault("PIEZOLIB_PROGRESS", "0")
    dk, note = dkpy_results(args.no_dkpy)
    rows = []
    for prob in problems():
        rows += our_rows(prob)
        rows.append(dkpy_row(prob, dk.get(prob.name)) if dk or not args.no_dkpy
                    else dkpy_row(prob, None))
    rows += paper_problem_rows(dk.get(PAPER))
    print_table(rows)
    print(f"\n{note}; dkpy: {DKPY_ITERATIONS} DK iterations, D-fit order 2, every "
          f"{DKPY_STRIDE}th grid point; ours: the full grid, d_order 2")
    print("mixed mu: piezolib's mixed upper bound of each loop on the problem's grid; "
          "exact range: crossing gains of the physical loop (no piezolib code)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
