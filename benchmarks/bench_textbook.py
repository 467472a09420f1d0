"""Benchmark: piezolib.robust on textbook problems with published or exact answers.

Runs the problems of ``tests/robust/textbook_problems.py`` (S&P's S/KS design of the
disturbance process, the spinning satellite, matrices with known mu, a two-mass spring,
S&P's distillation column) and prints one table:

    problem | quantity | known | ours | rel. diff | time [s] | dkpy value | dkpy time

"known" is a published value (quoted to the digits printed in the source), a closed
form, or an independent computation (SLICOT SB10AD through python-control, a
frequency-by-frequency closed loop, exact rational arithmetic), named in the quantity.
Rows whose relative difference exceeds the tolerance in the last column are marked
``<-``; they are findings, listed again below the table.

dkpy is not a project dependency.  When it is importable the dkpy columns are computed
here; otherwise, when ``benchmarks/.dkpy-venv`` exists (``sh benchmarks/setup_dkpy.sh``,
see benchmarks/README.md), this script runs itself with ``--dkpy-only`` in that
environment as a subprocess and reads its values; else the columns show "n/a".

Usage, from the repository root::

    python benchmarks/bench_textbook.py              # about 30 s, plus about 30 s for dkpy
    python benchmarks/bench_textbook.py --no-dkpy
"""

import argparse
import json
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


class Row(NamedTuple):
    problem: str
    quantity: str
    known: float
    ours: float
    seconds: float         # wall time of our computation (None: not timed)
    key: str = ""          # which dkpy value belongs in this row
    tol: float = 1e-3      # relative difference above which the row is a finding


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def peak_upper(M, blk, **kw):
    from piezolib import robust
    return float(robust.mussv(M, blk, **kw).upper.max())


# --- the matrices of problem 3, deterministic so that dkpy sees the same ones ------------

def cplx(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


def matrix_cases():
    """name -> (M, blk, exact mu, dkpy can take it)."""
    rng = np.random.default_rng(2024)
    a, b = cplx(rng, 8), cplx(rng, 8)
    blk8 = [(1, 1)] * 8
    cases = {"8 scalars, rank one": (np.outer(a, b.conj()), blk8, tp.rank_one_mu(a, b, blk8))}
    blk = [(1, 1), (2, 2), (3, 3)]
    a, b = cplx(rng, 6), cplx(rng, 6)
    cases["full blocks 1+2+3, rank one"] = (np.outer(a, b.conj()), blk, tp.rank_one_mu(a, b, blk))
    M = cplx(rng, 3, 4)
    cases["full 4x3 block: sigma_max"] = (M, [(4, 3)], np.linalg.norm(M, 2))
    M = cplx(rng, 4, 4)
    cases["repeated scalar: rho"] = (M, [(4, 0)], np.abs(np.linalg.eigvals(M)).max())
    a, b = np.array([1.0, 1.0], complex), np.array([1 + 1j, 0.5 - 0.3j])
    blk = [(-1, 0), (1, 1)]
    cases["real + complex, rank one"] = (np.outer(a, b.conj()), blk, tp.rank_one_mu(a, b, blk))
    return cases


# --- our rows ------------------------------------------------------------------------------

def rows_mixed_sensitivity():
    from piezolib import robust
    prob = tp.disturbance_process()
    res, t = timed(lambda: robust.hinfsyn(prob.P, 1, 1, rtol=1e-5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, gamma_sb10ad, _ = ct.hinfsyn(prob.P, 1, 1)
    loop = robust.loop_functions(prob.G, res.K)
    omega = np.logspace(-3, 4, 20000)
    S, KS = (np.ravel(f(1j * omega)) for f in (loop.S, loop.KS))
    sweep = np.sqrt(np.abs(np.ravel(prob.W1(1j * omega)) * S) ** 2 + np.abs(KS) ** 2).max()
    name = "S&P 2.8.3 S/KS"
    return [Row(name, "gamma_min (book, 3 digits)", tp.MIXSENS_GAMMA_BOOK, res.gamma, t,
                "mixsens_gamma", tol=5e-3),
            Row(name, "gamma_min (SLICOT SB10AD)", gamma_sb10ad, res.gamma, t, "mixsens_gamma"),
            Row(name, "||[W1 S; KS]|| (loop_functions sweep)", sweep, res.norm, t)]


def rows_satellite():
    from piezolib import robust
    sat = tp.spinning_satellite()
    omega = np.r_[0.0, np.logspace(-2, 2, 401)]
    T, t_lft = timed(lambda: robust.lft_response(sat.P, sat.K, omega))
    (peak, _), t_norm = timed(lambda: robust.hinf_norm(robust.lower_lft(sat.P, sat.K)))
    root = np.sqrt(1 + sat.a ** 2)
    mu_diag, t_diag = timed(lambda: peak_upper(T, [(1, 1), (1, 1)]))
    mu_one, t_one = timed(lambda: peak_upper(T[:, :1, :1], [(1, 1)]))
    at_1 = np.array([1.0])
    real_1, t_real = timed(lambda: robust.mussv(tp.satellite_T(at_1), [(-1, 0), (-1, 0)]))
    real_0 = robust.mussv(tp.satellite_T([0.0]), [(-1, 0), (-1, 0)])
    name = "S&P 3.7.1 satellite"
    return [Row(name, "||T_I||_inf = sqrt(1+a^2)", root, peak, t_norm),
            Row(name, "mu diag. complex = sqrt(1+a^2)", root, mu_diag, t_diag + t_lft,
                "satellite_mu"),
            Row(name, "mu one channel = 1", 1.0, mu_one, t_one),
            Row(name, "mu diag. real at DC = sqrt(1+a^2)", root, float(real_0.lower[0]), None),
            Row(name, "mu diag. real at w=1, lower", float(tp.satellite_mu_real(at_1)[0]),
                float(real_1.lower[0]), t_real),
            Row(name, "mu diag. real at w=1, upper (D,G)", float(tp.satellite_mu_real(at_1)[0]),
                float(real_1.upper[0]), t_real, tol=np.inf)]


def rows_matrices():
    from piezolib import robust
    rows = []
    for name, (M, blk, exact) in matrix_cases().items():
        r, t = timed(lambda: robust.mussv(M, blk))
        rows.append(Row("mu, known matrices", f"{name} (upper)", exact, float(r.upper[0]), t,
                        f"matrix:{name}" if blk[0][0] > 0 else "", tol=1e-6))
        rows.append(Row("mu, known matrices", f"{name} (lower)", exact, float(r.lower[0]), t,
                        tol=1e-6))
    return rows


def rows_two_mass():
    from piezolib import robust
    prob = tp.two_mass_spring()
    res, t = timed(lambda: robust.hinfsyn(prob.P, 1, 1, rtol=1e-5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, gamma_sb10ad, _ = ct.hinfsyn(prob.P, 1, 1)
    omega = np.logspace(-2, 2, 8000)
    sweep = np.linalg.svd(tp.pointwise_lft(prob.P, res.K, omega), compute_uv=False)[:, 0].max()
    name = "two-mass spring"
    return [Row(name, "gamma_opt (SLICOT SB10AD)", gamma_sb10ad, res.gamma, t, "two_mass_gamma"),
            Row(name, "||F_l(P,K)|| (pointwise sweep)", sweep, res.norm, t)]


def rows_distillation():
    from piezolib import robust
    col = tp.distillation_column()
    grid, dense = tp.SP_GRID, np.logspace(-3, 3, 2000)
    N, t_lft = timed(lambda: robust.lft_response(col.P, col.K, grid))
    rp, t_rp = timed(lambda: robust.mussv(N, tp.BLK_RP))
    Nd = robust.lft_response(col.P, col.K, dense)
    rp_dense, t_dense = timed(lambda: robust.mussv(Nd, tp.BLK_RP, lower=False))
    rs = robust.mussv(N[:, :2, :2], [(1, 1), (1, 1)])
    nom = robust.mussv(N[:, 2:, 2:], [(2, 2)])
    h1, t_h1 = timed(lambda: robust.hinfsyn(col.P, 2, 2, rtol=1e-4))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, gamma_sb10ad, _ = ct.hinfsyn(col.P, 2, 2)
    mu_h1 = peak_upper(tp.pointwise_lft(col.P, h1.K, grid), tp.BLK_RP)
    exact_1e3 = tp.exact_response(ct.ss(col.P).lft(h1.K, nu=2, ny=2), 1e-3)
    lft_1e3 = robust.lft_response(col.P, h1.K, [1e-3])[0]
    dk, t_dk = timed(lambda: robust.musyn(col.P, tp.BLK_RP, 2, 2, grid, d_order=4, max_iter=3))
    mu_dk = peak_upper(tp.pointwise_lft(col.P, dk.K, grid), tp.BLK_RP)
    d = tp.lundstrom_scaling()
    Pd = robust.dk.scaled_plant(col.P, tp.BLK_RP, [d, d], 2, 2)
    hd, t_hd = timed(lambda: robust.hinfsyn(Pd, 2, 2))
    mu_hd = peak_upper(tp.pointwise_lft(col.P, hd.K, grid), tp.BLK_RP)
    exact_peak = tp.distillation_mu(dense).max()
    name = "S&P 8.12 distillation"
    return [
        Row(name, "mu_RP, book grid (Table 8.1)", tp.SP_MU_RP, rp.upper.max(), t_rp + t_lft,
            "column_mu_rp", tol=1e-5),
        Row(name, "mu_RP, lower bound, book grid", tp.SP_MU_RP, rp.lower.max(), t_rp, tol=1e-5),
        Row(name, "mu_RP true peak (closed form)", exact_peak, rp_dense.upper.max(), t_dense,
            tol=1e-6),
        Row(name, "mu_RS, book grid", tp.SP_MU_RS, rs.upper.max(), None, "column_mu_rs",
            tol=1e-4),
        Row(name, "mu_NP, book grid", tp.SP_MU_NP, nom.upper.max(), None, tol=1e-3),
        Row(name, "DK it. 1: gamma (SLICOT SB10AD)", gamma_sb10ad, h1.gamma, t_h1, "column_gamma"),
        Row(name, "DK it. 1: mu_RP (book's K: 1.1798)", tp.SP_DK_MU[0], mu_h1, t_h1, tol=2e-3),
        Row(name, "DK it. 1: sigma_max at 1e-3, lft_response vs exact",
            np.linalg.norm(exact_1e3, 2), np.linalg.norm(lft_1e3, 2), None, tol=1e-6),
        Row(name, "musyn 3 it. (book's DK: 1.0207)", tp.SP_DK_MU[2], mu_dk, t_dk, "column_dk",
            tol=np.inf),
        Row(name, "K-step with Lundstrom d_opt (book: 0.974)", tp.SP_DOPT_MU, mu_hd, t_hd,
            tol=np.inf),
    ]


# --- dkpy ----------------------------------------------------------------------------------

def dkpy_values():
    """key -> [value or error text, seconds], computed with dkpy in this interpreter."""
    import dkpy

    def attempt(fn):
        t0 = time.perf_counter()
        try:
            value = fn()
            value = None if value is None else float(np.max(value))
        except Exception as exc:                  # report dkpy's failure in the table
            value = f"failed: {type(exc).__name__}"
        return [value if value is not None else "failed: no result", time.perf_counter() - t0]

    def gamma(P, n):
        return dkpy.HinfSynLmi().synthesize(P, n, n)[2]

    def ssv(M, blk):
        M = M if M.ndim == 3 else M[None]
        return dkpy.SsvLmiBisection().compute_ssv(np.moveaxis(M, 0, -1), [list(b) for b in blk])[0]

    def dk(P):
        it = dkpy.DkIterFixedOrder(controller_synthesis=dkpy.HinfSynSlicot(),
                                   structured_singular_value=dkpy.SsvLmiBisection(),
                                   d_scale_fit=dkpy.DScaleFitSlicot(), n_iterations=3, fit_order=4)
        return it.synthesize(P, 2, 2, tp.SP_GRID, [list(b) for b in tp.BLK_RP])[2]

    warnings.simplefilter("ignore")
    sat = tp.spinning_satellite()
    omega = np.r_[0.0, np.logspace(-2, 2, 401)]
    col = tp.distillation_column()
    N = tp.distillation_N(tp.SP_GRID)
    out = {"mixsens_gamma": attempt(lambda: gamma(tp.disturbance_process().P, 1)),
           "two_mass_gamma": attempt(lambda: gamma(tp.two_mass_spring().P, 1)),
           "column_gamma": attempt(lambda: gamma(col.P, 2)),
           "satellite_mu": attempt(lambda: ssv(tp.satellite_T(omega), [(1, 1), (1, 1)])),
           "column_mu_rp": attempt(lambda: ssv(N, tp.BLK_RP)),
           "column_mu_rs": attempt(lambda: ssv(N[:, :2, :2], [(1, 1), (1, 1)])),
           "column_dk": attempt(lambda: dk(col.P))}
    for name, (M, blk, _) in matrix_cases().items():
        if blk[0][0] > 0:                          # dkpy has no real blocks
            out[f"matrix:{name}"] = attempt(lambda: ssv(M, blk))
    return out


def dkpy_columns(skip):
    """(values, note): dkpy's values here, through the benchmark venv, or none."""
    if skip:
        return {}, "dkpy columns skipped (--no-dkpy)"
    try:
        import dkpy  # noqa: F401
    except ImportError:
        pass
    else:
        return dkpy_values(), "dkpy run in this interpreter"
    if not DKPY_PYTHON.exists():
        return {}, ("dkpy columns n/a: dkpy is not importable and benchmarks/.dkpy-venv does "
                    "not exist; create it with `sh benchmarks/setup_dkpy.sh`")
    proc = subprocess.run([str(DKPY_PYTHON), str(pathlib.Path(__file__).resolve()), "--dkpy-only"],
                          capture_output=True, text=True, cwd=ROOT, timeout=1800)
    if proc.returncode != 0:
        return {}, f"dkpy subprocess failed:\n{proc.stderr.strip()[-2000:]}"
    return json.loads(proc.stdout.strip().splitlines()[-1]), f"dkpy run by {DKPY_PYTHON}"


# --- table ----------------------------------------------------------------------------------

def fmt(x):
    return f"{x:.6g}" if isinstance(x, (float, int, np.floating)) else str(x)


def print_table(rows, dk):
    head = ("problem", "quantity", "known", "ours", "rel. diff", "time [s]", "dkpy value",
            "dkpy time")
    lines = []
    findings = []
    for r in rows:
        rel = r.ours / r.known - 1 if r.known else r.ours - r.known
        flag = " <-" if abs(rel) > r.tol else ""
        if flag:
            findings.append(r)
        value, seconds = dk.get(r.key, ("n/a", None)) if r.key else ("-", None)
        lines.append((r.problem, r.quantity, fmt(r.known), fmt(r.ours), f"{rel:+.2e}{flag}",
                      "-" if r.seconds is None else f"{r.seconds:.3f}", fmt(value),
                      "" if seconds is None else f"{seconds:.2f}"))
    widths = [max(len(str(x)) for x in col) for col in zip(head, *lines)]
    for line in (head, tuple("-" * w for w in widths), *lines):
        print(" | ".join(str(x).ljust(w) for x, w in zip(line, widths)))
    return findings


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-dkpy", action="store_true", help="skip the dkpy columns")
    ap.add_argument("--dkpy-only", action="store_true",
                    help="print dkpy's values as JSON (used in the dkpy venv subprocess)")
    args = ap.parse_args()
    if args.dkpy_only:
        print(json.dumps(dkpy_values()))
        return 0
    warnings.simplefilter("ignore")
    rows = (rows_mixed_sensitivity() + rows_satellite() + rows_matrices() + rows_two_mass()
            + rows_distillation())
    dk, note = dkpy_columns(args.no_dkpy)
    findings = print_table(rows, dk)
    print(f"\n{note}")
    print("tolerances: 1e-3 relative unless the row is exact (1e-6) or a printed value "
          "(its last digit); rows with tol = inf are comparisons, not checks")
    if findings:
        print("\nrows outside their tolerance (findings, see docs/robust.md):")
        for r in findings:
            print(f"  {r.problem}: {r.quantity}: known {fmt(r.known)}, ours {fmt(r.ours)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
