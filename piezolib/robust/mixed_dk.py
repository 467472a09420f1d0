"""mu-synthesis with real parametric blocks: :func:`mixed_musyn`.

A D,G-K iteration in its "scaled complex" form: the K-step is the
H-infinity problem of :func:`piezolib.robust.dk.musyn` with the real blocks
treated as complex, but their channels shrunk by a factor alpha(omega) <= 1
chosen in each D-step so that the scaled complex bound of the current
closed loop equals its mixed (D,G) mu upper bound at every frequency.  The
G-scalings' benefit (a real block cannot rotate phase) thus reaches the
K-step through alpha; every iterate is judged by the mixed bound itself.

Caveats (measured): alpha is exact only for the controller it was computed
from, so the shrunk K-steps are damped (``alpha_power``) and preceded by plain
complex DK steps (``complex_iter``); the returned controller is the iterate
with the lowest mixed peak.  On the S&P disturbance process with a real
+-60 % gain offset (tests/robust/test_mixed_dk.py) the best iterate has mixed
mu 0.732 against 0.740 for the complex DK design, and it came from a complex
step; the shrunk steps themselves gave 0.93.  On the paper's six-coefficient
problem the K-steps on the scaled plant (45 states) were slow and did not
converge.  Not a true D,G-K iteration (no fitted G-scalings).
"""

import logging
import time
from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib._checks import (check_bisection_tol, check_finite_array, check_frequency_grid,
                              check_integer, check_lti, check_positive)
from piezolib.progress import postfix, progress
from piezolib.robust.blocks import block_slices, parse_blk
from piezolib.robust.dfit import fit_magnitude
from piezolib.robust.dk import _hinf_options
from piezolib.robust.hinf import HinfSynthesisError, hinfsyn
from piezolib.robust.lft import lft_response, lower_lft
from piezolib.robust.lti import balance, from_scaled, time_scale_of, to_scaled
from piezolib.robust.mu import MuResult, mussv
from piezolib.robust.mu_upper import scaled_matrix

__all__ = ["MixedMusynResult", "mixed_musyn", "complex_relaxation", "real_block_shrink"]

logger = logging.getLogger(__name__)

_HISTORY_COLUMNS = ("iteration", "gamma", "mu_upper", "mu_complex", "omega_peak", "K_order",
                    "alpha_min", "seconds")
_ALPHA_MIN = 1e-3


@dataclass(frozen=True)
class MixedMusynResult:
    """Outcome of :func:`mixed_musyn`.

    Attributes
    ----------
    K : control.StateSpace
        Controller with the lowest peak of the mixed mu upper bound (ordinary time).
    mu_peak, mu_lower_peak : float
        Peaks over the grid of the mixed mu upper and lower bounds for ``K``.
    mu_complex_peak : float
        Peak of the mu upper bound for ``K`` with the real blocks taken as complex.
    omega_peak : float
        Frequency of the upper-bound peak [rad/s].
    gamma : float
        H-infinity level of the K-step that produced ``K``.
    records : tuple of dict
        One dict per iteration: ``iteration``, ``gamma``, ``mu_upper`` (mixed),
        ``mu_complex`` (complex relaxation), ``omega_peak`` [rad/s],
        ``K_order``, ``alpha_min`` (smallest shrink factor of the D-step that
        followed; NaN for the last), ``seconds``.  :attr:`history` as a DataFrame.
    best_iteration : int
    stop_reason : str
    alpha : ndarray, shape (nf,)
        Shrink factor alpha(omega) computed from ``K`` (1 where G-scalings do not help).
    omega : ndarray
        Frequency grid [rad/s].
    mu : piezolib.robust.mu.MuResult
        Mixed mu bounds (upper and lower) of ``K`` on ``omega``.
    closed_loop_poles : ndarray
        Poles of F_l(P, K) [rad/s], recomputed from P and K.
    elapsed : float
        Wall time [s] (information only: no stopping rule uses time).
    time_scale : float
        Internal time scale omega_s [rad/s].
    """

    K: ct.StateSpace
    mu_peak: float
    mu_lower_peak: float
    mu_complex_peak: float
    omega_peak: float
    gamma: float
    records: tuple
    best_iteration: int
    stop_reason: str
    alpha: np.ndarray
    omega: np.ndarray
    mu: MuResult = field(repr=False)
    closed_loop_poles: np.ndarray = field(repr=False)
    elapsed: float = 0.0
    time_scale: float = 1.0

    @property
    def history(self):
        """``records`` as a pandas.DataFrame (pandas imported here)."""
        import pandas as pd

        return pd.DataFrame(list(self.records), columns=list(_HISTORY_COLUMNS))


def _structure(blk, p, q):
    """Blocks of a structure of real 1 x 1 scalars and complex full blocks, last one full."""
    blocks = parse_blk(blk, p, q)
    for b in blocks:
        if not (b.is_full or (b.is_real and b.size == 1)):
            raise ValueError("mixed_musyn supports real 1 x 1 scalars (-1, 0) and complex full "
                             f"blocks; got the {b.kind} repeated scalar block {b.blk_row}")
    if not blocks[-1].is_full:
        raise ValueError("the last block of blk must be a complex full block (the performance "
                         "block, whose scaling is fixed to 1)")
    return blocks


def complex_relaxation(blk):
    """The structure with every real 1 x 1 scalar replaced by a complex 1 x 1 block.

    Parameters
    ----------
    blk : sequence of (int, int) or of Block

    Returns
    -------
    tuple of (int, int)
    """
    return tuple((1, 1) if b.is_real else b.blk_row for b in parse_blk(blk))


def real_block_shrink(M, blk, target, *, rounds=2, tol=1e-6):
    """Shrink factor alpha of the real blocks matching a target bound, with its D-scaling.

    Finds alpha(omega) in [1e-3, 1] and complex D-scalings (Dl, Dr) with

        sigma_max(Dl L_alpha M Dr^-1) = target   (or alpha = 1 when below),

    where L_alpha multiplies the outputs of M read by the real blocks by
    alpha.  Each round re-optimises D for the complex relaxation at the
    current alpha (:func:`~piezolib.robust.mu.mussv`) and then solves for
    alpha with D fixed (bisection; sigma_max is monotone in alpha).

    Parameters
    ----------
    M : ndarray, shape (nf, p, q)
    blk : sequence of (int, int) or of Block
        Real 1 x 1 scalars and complex full blocks.
    target : array_like, shape (nf,)
        Bound to match, e.g. the mixed mu upper bound of M (> 0).
    rounds : int, optional
        D re-optimisations.
    tol : float, optional
        Relative tolerance of alpha.

    Returns
    -------
    alpha : ndarray, shape (nf,)
    Dl, Dr : ndarray
        Scalings of the complex relaxation (diagonal).
    """
    M = check_finite_array("M", M)
    if M.ndim != 3:
        raise ValueError(f"M must have shape (nf, p, q), got {M.shape}")
    nf, p, q = M.shape
    blocks = parse_blk(blk, p, q)
    target = check_finite_array("target", target, shape=(nf,))
    if np.any(target <= 0):
        raise ValueError("target must be positive")
    rounds = check_integer("rounds", rounds, minimum=1)
    tol = check_bisection_tol("tol", tol)
    real_rows = np.zeros(p, bool)
    for b, (_, out) in zip(blocks, block_slices(blocks)):
        real_rows[out] = b.is_real
    relaxed = complex_relaxation(blocks)
    alpha = np.ones(nf)

    def shrunk(a):
        return np.where(real_rows[None, :, None], a[:, None, None] * M, M)

    for _ in range(rounds):
        res = mussv(shrunk(alpha), relaxed, lower=False)
        Dl, Dr = res.Dl, res.Dr
        A = scaled_matrix(M, Dl, Dr)

        def sigma(a):
            B = np.where(real_rows[None, :, None], a[:, None, None] * A, A)
            return np.linalg.norm(B, 2, axis=(1, 2))

        lo, hi = np.full(nf, np.log(_ALPHA_MIN)), np.zeros(nf)
        while np.any(hi - lo > tol):
            mid = (lo + hi) / 2
            above = sigma(np.exp(mid)) > target
            hi, lo = np.where(above, mid, hi), np.where(above, lo, mid)
        alpha = np.exp(lo)
        alpha = np.where(sigma(np.ones(nf)) <= target, 1.0, alpha)
    return alpha, Dl, Dr


def _scaled_plant(Ps, blocks, alpha_tf, d_tfs, nmeas, ncon):
    """L P R^-1 with L = d_i (alpha for real blocks), R = d_i, on the block channels."""
    one = ct.ss([], [], [], [[1.0]])
    left, right = [], []
    for i, b in enumerate(blocks):
        d = d_tfs[i] if i < len(d_tfs) else None
        d_ss = one if d is None else ct.ss(d)
        d_inv = one if d is None else ct.ss(1 / ct.tf(d))
        lft_i = d_ss * ct.ss(alpha_tf) if (b.is_real and alpha_tf is not None) else d_ss
        left += [lft_i] * b.cols
        right += [d_inv] * b.rows
    left += [one] * nmeas
    right += [one] * ncon
    return balance(ct.ss(ct.append(*left) * Ps * ct.append(*right)))


def _fit(omega_s, data, order, weight, prev):
    data = np.clip(data, 1e-12, 1e12)
    init = prev if prev is not None and prev.order == order else None
    return fit_magnitude(omega_s, data, order, weight, initial=init)


def mixed_musyn(P, blk, nmeas=1, ncon=1, omega=None, *, d_order=2, alpha_order=2, max_iter=6,
                complex_iter=2, alpha_power=0.5, rtol=5e-3, patience=2, hinf_options=None,
                time_scale=None):
    """mu-synthesis for structures with real scalar blocks (scaled-complex D,G-K iteration).

    Each iteration: K-step (:func:`~piezolib.robust.hinf.hinfsyn` on the
    scaled plant), mixed mu upper bound of the recomputed closed loop on
    ``omega`` (:func:`~piezolib.robust.mu.mussv` with the real blocks), then
    the D-step: alpha and D from :func:`real_block_shrink`, fitted by stable
    minimum-phase transfer functions (``alpha_order``, ``d_order``).  The
    controller with the lowest mixed peak is returned, with the lower bound
    computed on the grid and its closed-loop poles recomputed.  As in
    :func:`~piezolib.robust.dk.musyn`, only counts (``max_iter``, the K-steps'
    gamma trials) and the mu peaks stop the iteration, never wall time.

    Parameters
    ----------
    P : control.StateSpace
        Generalized plant, ordinary time: uncertainty/performance channels
        first, then ``nmeas`` measurements / ``ncon`` controls.
    blk : sequence of (int, int) or of Block
        Real 1 x 1 scalars ``(-1, 0)`` and complex full blocks (r, c), the
        performance block (complex, full) last.
    nmeas, ncon : int
        Number of measurements and controls.
    omega : array_like, optional
        Frequency grid [rad/s] (default 100 points, 1e0 ... 1e6 rad/s).
    d_order, alpha_order : int
        Orders of the fitted D-scalings and of the fitted alpha(s).
    complex_iter : int
        Leading iterations that are plain complex DK steps (alpha = 1): the
        mixed steps start from the complex design, and since the best iterate
        is chosen by the mixed bound the result is never worse than the
        complex DK iterates it passed through.
    alpha_power : float
        The K-step uses alpha ** alpha_power (0 < power <= 1): a damped shrink,
        because alpha is exact only for the controller it was computed from.
    max_iter, rtol, patience, hinf_options, time_scale
        As in :func:`piezolib.robust.dk.musyn`.

    Returns
    -------
    MixedMusynResult

    Raises
    ------
    ValueError, TypeError
        Unsupported or ill-fitting structure, bad grid or options.
    HinfSynthesisError
        The first K-step fails, or no iterate gives a stable closed loop.
    """
    t0 = time.perf_counter()
    check_lti("P", P)
    P = ct.ss(P)
    nmeas = check_integer("nmeas", nmeas, minimum=1)
    ncon = check_integer("ncon", ncon, minimum=1)
    p, q = P.noutputs - nmeas, P.ninputs - ncon
    if p < 1 or q < 1:
        raise ValueError(f"P ({P.noutputs}x{P.ninputs}) has no channels besides "
                         f"{nmeas} measurement(s) and {ncon} control(s)")
    blocks = _structure(blk, p, q)
    omega = np.logspace(0, 6, 100) if omega is None else omega
    omega = check_frequency_grid("omega", omega, min_length=16)
    d_order = check_integer("d_order", d_order, minimum=0)
    alpha_order = check_integer("alpha_order", alpha_order, minimum=0)
    max_iter = check_integer("max_iter", max_iter, minimum=1)
    patience = check_integer("patience", patience, minimum=1)
    rtol = check_positive("rtol", rtol)
    complex_iter = check_integer("complex_iter", complex_iter, minimum=0)
    alpha_power = check_positive("alpha_power", alpha_power)
    if alpha_power > 1:
        raise ValueError(f"alpha_power must be in (0, 1], got {alpha_power}")
    options = _hinf_options(hinf_options)

    ws = time_scale_of(P) if time_scale is None else check_positive("time_scale", time_scale)
    Ps = to_scaled(P, ws)
    omega_s = omega / ws
    relaxed = complex_relaxation(blocks)
    has_real = any(b.is_real for b in blocks)
    rows, best, stall, reason = [], None, 0, "max_iter reached"
    alpha_fit, d_fits = None, []
    with progress(total=max_iter, desc="mixed_musyn DK", unit="iter") as bar:
        for it in range(max_iter):
            t_it = time.perf_counter()
            plant = (_scaled_plant(Ps, blocks, alpha_fit and alpha_fit.tf, [f.tf for f in d_fits],
                                   nmeas, ncon) if it else Ps)
            try:
                hinf = hinfsyn(plant, nmeas, ncon, **options)
            except HinfSynthesisError as exc:
                if best is None:
                    raise
                reason = f"K-step failed: {exc}"
                break
            K = hinf.K
            poles = lower_lft(Ps, K, omega_s=1.0).poles()
            M = lft_response(Ps, K, omega_s, omega_s=1.0)
            mixed = mussv(M, blocks, omega, lower=False)
            cplx = mussv(M, relaxed, omega, lower=False) if has_real else mixed
            k = int(np.argmax(mixed.upper))
            row = {"iteration": it, "gamma": hinf.gamma, "mu_upper": float(mixed.upper[k]),
                   "mu_complex": float(cplx.upper.max()), "omega_peak": float(omega[k]),
                   "K_order": K.nstates, "alpha_min": np.nan, "seconds": 0.0}
            rows.append(row)
            stable = bool(np.all(poles.real < 0))
            improved = best is None or row["mu_upper"] < best["row"]["mu_upper"] * (1 - rtol)
            stall = 0 if improved or it < complex_iter else stall + 1
            if stable and (best is None or row["mu_upper"] < best["row"]["mu_upper"]):
                best = {"row": row, "K": K, "M": M, "iteration": it, "poles": poles}
            last = stall >= patience or it == max_iter - 1
            if not last:
                if it + 1 < complex_iter or not has_real:
                    alpha = np.ones(omega.size)
                    Dl = mussv(M, relaxed, lower=False).Dl
                else:
                    alpha, Dl, _ = real_block_shrink(M, blocks, mixed.upper)
                    alpha = alpha ** alpha_power
                row["alpha_min"] = float(alpha.min())
                weight = (mixed.upper / mixed.upper.max()) ** 4 + 1e-3
                alpha_fit = (_fit(omega_s, alpha, alpha_order, weight, alpha_fit)
                             if has_real else None)
                slots = block_slices(blocks)
                d_fits = [_fit(omega_s, Dl[:, out.start, out.start].real, d_order, weight,
                               d_fits[i] if i < len(d_fits) else None)
                          for i, (_, out) in enumerate(slots[:-1])]
            row["seconds"] = time.perf_counter() - t_it
            logger.info("mixed DK %2d: gamma %7.4f  mixed mu %.4f (complex %.4f) at %9.4g rad/s  "
                        "K order %3d  alpha_min %.3g  %.2f s", it, hinf.gamma, row["mu_upper"],
                        row["mu_complex"], row["omega_peak"], K.nstates, row["alpha_min"],
                        row["seconds"])
            postfix(bar, mu=row["mu_upper"], gamma=hinf.gamma)
            bar.update()
            if stall >= patience:
                reason = f"no improvement > {rtol:g} in {patience} iterations"
                break
    if best is None:
        raise HinfSynthesisError("no K-step gave a stable closed loop F_l(P, K)")

    M = best["M"]
    mu = mussv(M, blocks, omega)
    cplx = mussv(M, relaxed, omega, lower=False) if has_real else mu
    alpha = real_block_shrink(M, blocks, mu.upper)[0] if has_real else np.ones(omega.size)
    K = from_scaled(best["K"], ws, P.output_labels[-nmeas:], P.input_labels[-ncon:], name="K")
    return MixedMusynResult(
        K=K, mu_peak=float(mu.upper.max()), mu_lower_peak=float(mu.lower.max()),
        mu_complex_peak=float(cplx.upper.max()), omega_peak=float(omega[np.argmax(mu.upper)]),
        gamma=best["row"]["gamma"], records=tuple(rows), best_iteration=best["iteration"],
        stop_reason=reason, alpha=alpha, omega=omega, mu=mu,
        closed_loop_poles=best["poles"] * ws, elapsed=time.perf_counter() - t0, time_scale=ws)
