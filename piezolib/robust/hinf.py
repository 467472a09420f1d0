"""Dependable H-infinity synthesis: bounded gamma search, verified result (:func:`hinfsyn`).

Its own gamma-iteration around the central-controller formulas (Zhou, Doyle
and Glover 1996, Ch. 17), in scaled time, with every answer verified on the
closed loop.  Why not ``control.hinfsyn``, and how each step works, is in
``docs/robust.md``.
"""

import time
from dataclasses import dataclass, field, replace

import control as ct
import numpy as np
import scipy.linalg as la

from piezolib._checks import (check_channels, check_finite_array, check_integer, check_lti,
                              check_positive, check_proper)
from piezolib.robust.hinf_central import _AXIS_REL_TOL, _central, _eig_errors, _marginal
from piezolib.robust.lft import _LoopResponse
from piezolib.robust.lti import (balance, from_scaled, max_singular_value,
                                 time_scale_of, to_scaled)

__all__ = ["HinfResult", "HinfSynthesisError", "hinfsyn", "DEFAULT_EFFORT_WEIGHT"]

#: Effort / noise weight added when D12 / D21 is rank deficient ("auto").
DEFAULT_EFFORT_WEIGHT = 1e-3
_RANK_TOL = 1e-9      # relative to the peak gain of P12 / P21
_SPREAD_LIMIT = 1e11  # pole spread beyond which failures are reported as numerical
_MAX_CHECKS = 16      # final verifications of the best controllers (each two dense sweeps)
_MAX_BACKOFFS = 8     # then raises of gamma by growing steps
_MAX_SAMPLES = 24     # trials spread over the last rtol when no controller landed there
_GOLDEN = (np.sqrt(5.0) - 1) / 2   # low-discrepancy spacing of those trials
_MODAL_COND = 1e6     # eigenvector condition below which a response is evaluated modally


class HinfSynthesisError(ValueError):
    """No verified H-infinity controller: unstabilisable, infeasible or out of trials.

    Examples
    --------
    An unstable mode the control cannot reach:

    >>> P = ct.ss([[1.0]], [[1.0, 0.0]], [[1.0], [1.0]], np.zeros((2, 2)))
    >>> hinfsyn(P, 1, 1)
    Traceback (most recent call last):
    ...
    piezolib.robust.hinf.HinfSynthesisError: P cannot be stabilised: the mode at 1 rad/s is not controllable ...
    """


class _ControllersFailed(HinfSynthesisError):
    """The Riccati conditions held at some gamma, but no central controller verified;
    ``rho_u``, ``rho_n``: the regularisation weights that were in use."""

    def __init__(self, message, rho_u, rho_n):
        super().__init__(message)
        self.rho_u, self.rho_n = rho_u, rho_n


@dataclass(frozen=True)
class HinfResult:
    """A verified H-infinity controller and how it was obtained.

    Attributes
    ----------
    K : control.StateSpace
        Controller in ordinary time, from P's measurements to P's controls.
    gamma : float
        Verified bound: ||F_l(P_reg, K)||_inf <= gamma (1 + verify_rtol),
        with P_reg the plant including any regularisation.
    gamma_infeasible : float
        Largest gamma at which the Riccati conditions failed (lower end of
        the final bracket), so the optimum lies in (gamma_infeasible, gamma]
        up to numerical error; the D11 bound (0 without D11) where the search
        went down to 1e-9 gamma without meeting an infeasible gamma.  A gamma
        whose central controller merely failed the closed-loop check is never
        counted as infeasible, nor one above the returned controller's own
        norm on P_reg (such verdicts were numerical; ``converged`` is then
        False).
    norm, omega_peak : float
        ||F_l(P, K)||_inf recomputed on the plant as given (no
        regularisation) and the frequency of its peak [rad/s].
    closed_loop : control.StateSpace
        F_l(P, K) in ordinary time.
    closed_loop_poles : ndarray
        Its poles [rad/s] (all with negative real part).
    regularization : str
        What was added to meet the synthesis assumptions ('' if nothing).
    effort_weight, noise_weight : float
        The weights actually added (0 when not needed).
    time_scale : float
        Internal time scale omega_s [rad/s].
    iterations : int
        Number of gamma trials.
    elapsed : float
        Wall time [s] (information only: no stopping rule uses time).
    converged : bool
        True exactly when ``gamma <= gamma_infeasible (1 + rtol)``: False when
        ``max_iter`` ended the search first, when no controller within
        ``rtol`` of the optimum passed the final checks (numerically
        ill-conditioned problem), or when the returned controller beat a
        gamma judged infeasible.
    attempts : tuple
        (gamma, outcome) of every trial, in order.
    realization : str
        "as given", or how P was re-realised when the given realisation gave
        no converged controller and the re-realised one did better (the
        result is then checked on the plant as given too).

    Examples
    --------
    >>> s = ct.tf("s")
    >>> G, W1 = 1 / (s + 1), 0.5 * (s + 10) / (s + 0.1)
    >>> P = ct.ss(ct.combine_tf([[W1, -W1 * G], [0, 0.1], [1, -G]]))   # z = (W1 e, 0.1 u), y = e
    >>> r = hinfsyn(P, 1, 1)
    >>> bool(np.all(r.closed_loop_poles.real < 0)), r.regularization == ""
    (True, True)
    >>> bool(abs(r.norm - r.gamma) < 1e-2 * r.gamma)       # the norm on P as given
    True
    """

    K: ct.StateSpace
    gamma: float
    gamma_infeasible: float
    norm: float
    omega_peak: float
    closed_loop: ct.StateSpace
    closed_loop_poles: np.ndarray
    regularization: str
    effort_weight: float
    noise_weight: float
    time_scale: float
    iterations: int
    elapsed: float
    converged: bool = True
    attempts: tuple = field(default=(), repr=False)
    realization: str = "as given"


# --- plant partition, regularisation and normalisation ----------------------

@dataclass
class _Plant:
    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C1: np.ndarray
    C2: np.ndarray
    D11: np.ndarray
    D12: np.ndarray
    D21: np.ndarray
    D22: np.ndarray

    @classmethod
    def split(cls, sys, nmeas, ncon):
        m1, p1 = sys.ninputs - ncon, sys.noutputs - nmeas
        A, B, C, D = (np.asarray(x, float) for x in (sys.A, sys.B, sys.C, sys.D))
        return cls(A, B[:, :m1], B[:, m1:], C[:p1], C[p1:],
                   D[:p1, :m1], D[:p1, m1:], D[p1:, :m1], D[p1:, m1:])

    def system(self):
        B = np.hstack([self.B1, self.B2])
        C = np.vstack([self.C1, self.C2])
        D = np.block([[self.D11, self.D12], [self.D21, self.D22]])
        return ct.ss(self.A, B, C, D)


def _balance_states(pl, sweeps=30):
    """Scale the states (powers of two) so that every state's row of [A B1 B2]
    and column of [A; C1; C2] have similar norms (in place; the transfer
    function is unchanged).  Balancing A alone left weight states with B ~ 5e-8
    and C ~ 2e6, and Riccati solutions spanning 15 decades."""
    n = pl.A.shape[0]
    if n == 0:
        return pl
    B = np.hstack([pl.B1, pl.B2])
    C = np.vstack([pl.C1, pl.C2])
    A = pl.A
    d = np.ones(n)
    off = ~np.eye(n, dtype=bool)
    for _ in range(sweeps):
        As = np.abs(A * d[None, :] / d[:, None]) * off
        rows = np.sqrt((As ** 2).sum(1) + ((B / d[:, None]) ** 2).sum(1))
        cols = np.sqrt((As ** 2).sum(0) + ((C * d[None, :]) ** 2).sum(0))
        ok = (rows > 0) & (cols > 0)
        step = np.ones(n)
        step[ok] = np.sqrt(rows[ok] / cols[ok])
        if np.all(np.abs(np.log2(step)) < 0.5):
            break
        d *= step
    d = np.exp2(np.round(np.log2(d)))
    pl.A = A * d[None, :] / d[:, None]
    pl.B1, pl.B2 = pl.B1 / d[:, None], pl.B2 / d[:, None]
    pl.C1, pl.C2 = pl.C1 * d[None, :], pl.C2 * d[None, :]
    return pl


def _gains(A, B, C, D, omega):
    """Largest singular value of C (j omega I - A)^-1 B + D at each ``omega`` [scaled rad/s].

    All frequencies at once, from the eigenvectors of A when they are well
    conditioned, else by one batched LU solve: a fraction of the cost of
    python-control's frequency-by-frequency evaluation, which took half of a
    small synthesis.  An exactly singular point (an undamped pole on the grid) is
    left to :func:`~piezolib.robust.lti.max_singular_value`.
    """
    omega = np.atleast_1d(np.asarray(omega, float))
    n = A.shape[0]
    if n == 0:
        return np.full(omega.size, np.linalg.norm(D, 2))
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) < _MODAL_COND:
        # well-conditioned eigenvectors: C V diag(1 / (j omega - lam)) V^-1 B + D, the
        # rounding amplified by at most cond(V)
        CV, VB = C @ V, np.linalg.solve(V, B)
        H = np.einsum("ik,fk,kj->fij", CV, 1.0 / (1j * omega[:, None] - lam), VB) + D
    else:
        try:
            resolvent = 1j * omega[:, None, None] * np.eye(n) - A
            H = C @ np.linalg.solve(resolvent, B.astype(complex)) + D
        except np.linalg.LinAlgError:
            return max_singular_value(ct.ss(A, B, C, D), omega)
    return _largest_singular_values(H)


def _largest_singular_values(H):
    """sigma_max of each matrix of a stack (f, p, m): closed forms for one and two columns
    (or rows), where a batched SVD spends microseconds per matrix in LAPACK's overhead."""
    if min(H.shape[1:]) == 1:
        return np.sqrt(np.sum(np.abs(H) ** 2, axis=(1, 2)))
    if min(H.shape[1:]) == 2:
        # the larger eigenvalue of the 2 x 2 Gram matrix [[a, b], [b*, d]], without the
        # cancellation of the smaller one
        M = H if H.shape[2] == 2 else np.swapaxes(H, 1, 2)
        a, d = (np.sum(np.abs(M[:, :, k]) ** 2, axis=1) for k in (0, 1))
        b = np.sum(M[:, :, 0].conj() * M[:, :, 1], axis=1)
        return np.sqrt((a + d) / 2 + np.sqrt(((a - d) / 2) ** 2 + np.abs(b) ** 2))
    return np.linalg.svd(H, compute_uv=False)[:, 0]


def _peak_gain(A, B, C, D, omega):
    """Largest gain on the grid only (cheap: every gamma trial is checked this way)."""
    return float(np.max(_gains(A, B, C, D, omega)))


def _refined_peak(gains, omega, xtol=1e-9):
    """(peak, omega_peak) of ``gains`` (a vectorised function of frequency) on the grid
    ``omega`` and at DC, refined around the best grid point by nested geometric grids of
    65 points until the bracket is ``xtol`` wide (relative).

    Five batched evaluations instead of the ~25 scalar ones of a Brent search, for
    the same peak: each round narrows the bracket 32-fold.
    """
    omega = np.asarray(omega, float)
    values = gains(omega)
    k = int(np.argmax(values))
    peak, w_peak = float(values[k]), float(omega[k])
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, omega.size - 1)]
    while lo > 0 and hi > lo * (1 + xtol):
        sub = np.geomspace(lo, hi, 65)
        values = gains(sub)
        j = int(np.argmax(values))
        if values[j] > peak:
            peak, w_peak = float(values[j]), float(sub[j])
        lo, hi = sub[max(j - 1, 0)], sub[min(j + 1, sub.size - 1)]
    dc = float(gains(np.zeros(1))[0])
    return (dc, 0.0) if dc >= peak else (peak, w_peak)


def _lft_peak(P, K, omega, omega_s):
    """||F_l(P, K)||_inf and its frequency [rad/s] from the pointwise loop
    (:func:`~piezolib.robust.lft.lft_response`, as ``lft_hinf_norm`` computes it),
    refined by :func:`_refined_peak`."""
    loop = _LoopResponse(P, K, omega_s)          # P and K scaled and balanced once
    return _refined_peak(lambda w: _largest_singular_values(loop(w)), omega)


def _regularization_weight(name, D, rank, reference, weight, option, what):
    """(0, '') when D has rank ``rank`` numerically, else (weight to add, note); may raise."""
    s = la.svdvals(D) if min(D.shape) else np.zeros(0)
    smallest = float(s[rank - 1]) if s.size >= rank else 0.0
    if smallest >= _RANK_TOL * reference:
        return 0.0, ""
    if weight is None or (not isinstance(weight, str) and weight == 0):
        raise HinfSynthesisError(
            f"{name} is rank deficient (smallest singular value {smallest:.3g} vs. gain "
            f"{reference:.3g}); pass {option}='auto' or a positive weight to add {what}")
    rho = DEFAULT_EFFORT_WEIGHT if weight == "auto" else check_positive(option, weight)
    return rho, f"{name} rank deficient (sigma_min {smallest:.2g}): added {what} {rho:g}"


def _regularize(pl, effort_weight, noise_weight, omega):
    """Add effort outputs / noise inputs when D12 / D21 lose rank.

    "Rank" is judged against the peak gain of P12 / P21 with a tolerance near
    sqrt(eps) (``_RANK_TOL``): with 1e-6 a full-rank D12 = 1 beside a weight
    of DC gain 1e7 was called rank deficient and regularised, although the
    Riccati equations are well posed up to ratios ~1e-9.
    """
    n, m2, p2 = pl.A.shape[0], pl.B2.shape[1], pl.C2.shape[0]
    ref12 = max(_peak_gain(pl.A, pl.B2, pl.C1, pl.D12, omega), 1e-300)
    rho_u, note_u = _regularization_weight("D12", pl.D12, m2, ref12, effort_weight,
                                           "effort_weight", "control-effort output(s) on u:")
    if rho_u:
        pl.C1 = np.vstack([pl.C1, np.zeros((m2, n))])
        pl.D11 = np.vstack([pl.D11, np.zeros((m2, pl.D11.shape[1]))])
        pl.D12 = np.vstack([pl.D12, rho_u * np.eye(m2)])
    ref21 = max(_peak_gain(pl.A, pl.B1, pl.C2, pl.D21, omega), 1e-300)
    rho_n, note_n = _regularization_weight("D21", pl.D21.T, p2, ref21, noise_weight,
                                           "noise_weight", "measurement-noise input(s), gain")
    if rho_n:
        pl.B1 = np.hstack([pl.B1, np.zeros((n, p2))])
        pl.D11 = np.hstack([pl.D11, np.zeros((pl.D11.shape[0], p2))])
        pl.D21 = np.hstack([pl.D21, rho_n * np.eye(p2)])
    return "; ".join(x for x in (note_u, note_n) if x), rho_u, rho_n


def _check_stabilisable(pl, scale):
    """Raise when an unstable or marginal mode is uncontrollable/unobservable.

    Works on the scaled, balanced plant; ``scale`` [rad/s] only converts the
    reported mode back to ordinary time.
    """
    n = pl.A.shape[0]
    eigs, err = _eig_errors(pl.A)
    for lam in eigs[_marginal(eigs, err)]:
        shifted = pl.A - lam * np.eye(n)
        tol = 1e-9 * max(1.0, np.linalg.norm(pl.A, 1))
        if la.svdvals(np.hstack([shifted, pl.B2]))[-1] <= tol * max(1, np.linalg.norm(pl.B2)):
            raise HinfSynthesisError(_lost_mode_message(pl.A, lam, scale, "controllable from "
                                                                           "the control inputs"))
        if la.svdvals(np.vstack([shifted, pl.C2]))[-1] <= tol * max(1, np.linalg.norm(pl.C2)):
            raise HinfSynthesisError(_lost_mode_message(pl.A, lam, scale, "observable from "
                                                                           "the measurements"))


def _lost_mode_message(A, lam, scale, what):
    """Why the mode ``lam`` (scaled time) fails the stabilisability test.

    A mode that is stable by its own magnitude but within rounding of the
    axis, in a plant whose poles span more than double precision can resolve
    (G = 1e36 / (s + 1e12)^3 beside a weight pole at -1e-3 rad/s), proves
    nothing about stabilisability.
    """
    spread = _pole_spread(A, scale)
    own_stable = lam.real < -_AXIS_REL_TOL * abs(lam)
    lam = lam.real if lam.imag == 0 else lam
    if own_stable and spread:
        return (f"the mode at {lam * scale:.4g} rad/s is stable but within rounding of the "
                f"imaginary axis, and not {what} to that precision: {spread}, beyond double "
                "precision, so this is not a proof that P cannot be stabilised; move the "
                "slowest weight pole up or drop dynamics far beyond the bandwidth")
    return f"P cannot be stabilised: the mode at {lam * scale:.4g} rad/s is not {what}"


def _pole_spread(A, scale):
    """The phrase "P's poles span N decades (lo to hi rad/s)" beyond ``_SPREAD_LIMIT``, else ''."""
    mags = np.abs(np.linalg.eigvals(A)) * scale if A.shape[0] else np.zeros(0)
    mags = mags[mags > 0]
    if mags.size < 2 or mags.max() / mags.min() < _SPREAD_LIMIT:
        return ""
    return (f"P's poles span {np.log10(mags.max() / mags.min()):.1f} decades "
            f"({mags.min():.3g} to {mags.max():.3g} rad/s)")


@dataclass
class _Normalized:
    plant: _Plant          # D12 = [0; I], D21 = [0, I], D22 = 0
    Tu: np.ndarray         # u = Tu u~
    Ty: np.ndarray         # y~ = Ty y
    D22: np.ndarray        # original D22 (loop-shifted back at the end)


def _normalize(pl):
    m2, p2 = pl.B2.shape[1], pl.C2.shape[0]
    U, s12, Vt = la.svd(pl.D12)
    theta = np.hstack([U[:, m2:], U[:, :m2]])
    Tu = Vt.T / s12
    U2, s21, V2t = la.svd(pl.D21)
    V2 = V2t.T
    phi = np.hstack([V2[:, p2:], V2[:, :p2]])
    Ty = (U2 / s21).T
    out = _Plant(pl.A, pl.B1 @ phi, pl.B2 @ Tu, theta.T @ pl.C1, Ty @ pl.C2,
                 theta.T @ pl.D11 @ phi, theta.T @ pl.D12 @ Tu, Ty @ pl.D21 @ phi,
                 np.zeros((p2, m2)))
    out.D12 = np.vstack([np.zeros((out.D12.shape[0] - m2, m2)), np.eye(m2)])
    out.D21 = np.hstack([np.zeros((p2, out.D21.shape[1] - p2)), np.eye(p2)])
    return _Normalized(out, Tu, Ty, pl.D22.copy())


def _check_axis_zeros(pl, scale):
    """Raise when P12 or P21 of the normalised plant has a zero on the jw axis.

    With D12 = [0; I] the zeros of P12 are the unobservable modes of
    (A - B2 C12, C11); with D21 = [0, I] those of P21 the uncontrollable modes
    of (A - B12 C2, B11).  Such a zero makes the gamma-iteration converge to a
    controller that cancels it (a closed-loop pole on the axis, infinite norm).
    """
    n, m2, p2 = pl.A.shape[0], pl.B2.shape[1], pl.C2.shape[0]
    if n == 0:
        return
    q1, r1 = pl.C1.shape[0] - m2, pl.B1.shape[1] - p2
    cases = (("P12", pl.A - pl.B2 @ pl.C1[q1:], pl.C1[:q1], False, "the controls u to the "
              "performance outputs z"),
             ("P21", pl.A - pl.B1[:, r1:] @ pl.C2, pl.B1[:, :r1], True, "the disturbances w "
              "to the measurements y"))
    for name, At, M, transpose, what in cases:
        size = np.linalg.norm(At, 1)
        eigs, err = _eig_errors(At)
        for lam in eigs[_marginal(eigs, err) & _marginal(-eigs, err)]:
            shifted = At - lam * np.eye(n)
            stack = np.hstack([shifted, M]) if transpose else np.vstack([shifted, M])
            if la.svdvals(stack)[-1] <= 1e-8 * max(size, np.linalg.norm(M, 1), 1e-300):
                raise HinfSynthesisError(
                    f"{name} (from {what}) has a zero at s = {lam * scale:.4g} rad/s on the "
                    "imaginary axis, so no H-infinity controller attains a finite optimum "
                    "(it would cancel that zero); move the weight pole or zero that causes "
                    "it slightly into the left half-plane")


# --- one gamma ---------------------------------------------------------------

def _d11_bound(pl):
    m2, p2 = pl.B2.shape[1], pl.C2.shape[0]
    q1, r1 = pl.C1.shape[0] - m2, pl.B1.shape[1] - p2
    D = pl.D11
    a = la.norm(D[:q1, :], 2) if q1 > 0 and D.shape[1] else 0.0
    b = la.norm(D[:, :r1], 2) if r1 > 0 and D.shape[0] else 0.0
    return float(max(a, b))


def _close_loop(pl, K):
    """State-space closed loop F_l(pl, K) for D22 = 0."""
    Ak, Bk, Ck, Dk = K
    A = np.block([[pl.A + pl.B2 @ Dk @ pl.C2, pl.B2 @ Ck], [Bk @ pl.C2, Ak]])
    B = np.vstack([pl.B1 + pl.B2 @ Dk @ pl.D21, Bk @ pl.D21])
    C = np.hstack([pl.C1 + pl.D12 @ Dk @ pl.C2, pl.D12 @ Ck])
    D = pl.D11 + pl.D12 @ Dk @ pl.D21
    return A, B, C, D


def _check_grid(A, n_base):
    """Frequencies covering the poles of A: a log grid plus the pole frequencies."""
    mags = np.abs(np.linalg.eigvals(A)) if A.shape[0] else np.ones(1)
    mags = mags[mags > 0] if np.any(mags > 0) else np.ones(1)
    lo, hi = mags.min() / 100, mags.max() * 100
    base = np.logspace(np.log10(lo), np.log10(hi), n_base)
    poles = np.linalg.eigvals(A) if A.shape[0] else np.zeros(0)
    extra = np.abs(poles.imag[poles.imag > 0])
    return np.unique(np.r_[base, extra, extra * 0.999, extra * 1.001])


def _spread_hint(A, scale):
    """A sentence on P's pole spread when it is too wide for double precision."""
    spread = _pole_spread(A, scale)
    if not spread:
        return ("  P12 and P21 have no zeros on the imaginary axis (checked), so either "
                "gamma_max is too small or the Riccati equations are ill-conditioned.")
    return (f"  {spread}: the Hamiltonian eigenvalues of "
            "the slowest modes cannot be told from the imaginary axis in double precision, "
            "so this is not a proof of infeasibility; move the slowest weight pole up or drop "
            "dynamics far beyond the bandwidth.")


# --- the search ----------------------------------------------------------------

def hinfsyn(P, nmeas=1, ncon=1, *, gamma_max=1e6, rtol=1e-3, max_iter=60,
            effort_weight="auto", noise_weight="auto", time_scale=None, verify_rtol=1e-3):
    """H-infinity controller for P by a bounded, verified gamma-iteration.

    The Riccati verdicts only guide the search: they bracket the optimum,
    where every trial's central controller counts at its own closed-loop
    peak, gammas within ``rtol`` above the bracket are sampled until one
    controller passes, and a controller is returned only when its loop
    passes the final checks (dense-grid peak, stability of the loop closed
    around the given plant, norm recomputed on it); see ``docs/robust.md``.
    The search is bounded by counts only (``max_iter`` gamma trials, at most
    16 final checks, then at most 8 back-off steps), never by wall time, so
    the controller returned does not depend on the machine's speed or load;
    ``elapsed`` reports the time taken.

    Parameters
    ----------
    P : control.StateSpace or control.TransferFunction
        Continuous-time generalized plant; the last ``nmeas`` outputs are the
        measurements, the last ``ncon`` inputs the controls.
    nmeas, ncon : int
        Number of measurements and controls.
    gamma_max : float
        Largest gamma tried; none feasible up to it raises.
    rtol : float
        Relative width of the final gamma bracket.
    max_iter : int
        Maximum number of gamma trials (each costs two Riccati solves), at
        least 2; when they are used up the search stops, returning the best
        verified controller (``converged`` False) or raising if there is none.
    effort_weight, noise_weight : 'auto', float or None
        Regularisation used when D12 / D21 is rank deficient: 'auto' adds
        1e-3 * u (1e-3 * n), a float sets the weight, None raises instead.
        With 'auto', where the Riccati conditions hold but no central
        controller verifies within ``rtol`` of the optimum, the weights 1e-2,
        1e-1 and 1 are tried in turn until one converges
        (``HinfResult.regularization`` then says so); if none does, the
        smallest weight's result is returned.
    time_scale : float, optional
        Internal time scale omega_s [rad/s]; default
        :func:`piezolib.robust.lti.time_scale_of` ``(P)``.
    verify_rtol : float
        Tolerance of the verification ||F_l(P_reg, K)||_inf <= gamma (1 + verify_rtol).

    Returns
    -------
    HinfResult

    Raises
    ------
    HinfSynthesisError
        Unstabilisable or undetectable plant, rank-deficient D12/D21 with
        regularisation switched off, no feasible gamma <= gamma_max, or no
        verified controller within ``max_iter`` trials and the final back-offs
        (up to 8 raises of gamma, by 1 %, 2 %, 4 %, ... or 10 ``rtol`` if larger:
        the controller must pass the dense-grid check, stabilise the given
        plant with a margin and meet gamma on it).

    Examples
    --------
    Mixed sensitivity for G = 1/(s+1): ||(W1 S, 0.1 K S)||_inf.

    >>> s = ct.tf("s")
    >>> G, W1 = 1 / (s + 1), 0.5 * (s + 10) / (s + 0.1)
    >>> P = ct.ss(ct.combine_tf([[W1, -W1 * G], [0, 0.1], [1, -G]]))   # z = (W1 e, 0.1 u), y = e
    >>> r = hinfsyn(P, nmeas=1, ncon=1)
    >>> round(r.gamma, 2), r.converged, r.K.nstates
    (0.8, True, 2)
    >>> bool(r.gamma_infeasible < r.gamma <= r.gamma_infeasible * (1 + 1e-3))
    True
    """
    options = dict(gamma_max=gamma_max, rtol=rtol, max_iter=max_iter, time_scale=time_scale,
                   verify_rtol=verify_rtol)
    t0 = time.perf_counter()
    try:
        res = _hinfsyn_escalating(P, nmeas, ncon, effort_weight, noise_weight, options)
        failure = None
    except HinfSynthesisError as exc:
        res, failure = None, exc
    if res is not None and res.converged:
        return res
    # A badly scaled realisation of the same system (a plant built by direct interconnection
    # of transfer functions with coefficients up to 1e23: A entries to 5e11) can make the
    # Riccati verdicts false: "no gamma <= 1e6 feasible" where the optimum is 1.87, also after
    # diagonal balancing.  Its block-diagonal (modal) realisation, which separates the modes
    # by well-conditioned similarities, does not have the problem: one retry on it.
    retry = _on_modal_realization(P, nmeas, ncon, effort_weight, noise_weight, options)
    if retry is not None and (res is None or retry.converged or retry.gamma < res.gamma):
        return replace(retry, elapsed=time.perf_counter() - t0)
    if res is None:
        raise failure
    return res


def _on_modal_realization(P, nmeas, ncon, effort_weight, noise_weight, options):
    """:func:`hinfsyn` on a block-diagonal realisation of P, with its controller checked on
    P as given (stable loop, norm within the tolerance); None if that fails anywhere."""
    P = ct.ss(P)
    try:
        Pm = ct.ss(ct.modal_form(P)[0], inputs=P.input_labels, outputs=P.output_labels)
        res = _hinfsyn_escalating(Pm, nmeas, ncon, effort_weight, noise_weight, options)
    except (HinfSynthesisError, np.linalg.LinAlgError, ValueError, ArithmeticError):
        return None
    loop = P.lft(res.K, nu=ncon, ny=nmeas)
    if np.any(np.linalg.eigvals(np.asarray(loop.A, float)).real >= 0):
        return None
    norm, w_peak = _lft_peak(P, res.K, _check_grid(np.asarray(loop.A, float), 2000),
                             res.time_scale)
    if not norm <= res.gamma * (1 + options["verify_rtol"]):
        return None
    return replace(res, norm=float(norm), omega_peak=float(w_peak),
                   realization="block-diagonal (modal) form: the given realisation "
                               "gave no converged controller")


def _hinfsyn_escalating(P, nmeas, ncon, effort_weight, noise_weight, options):
    """:func:`hinfsyn` on P as realised: the default regularisation, raised while no
    controller verifies near the optimum."""
    t0 = time.perf_counter()
    # the default regularisation can leave the central controllers too ill-conditioned to
    # verify near the optimum (a random plant with D12 = 0: X spanning 14 decades, every
    # loop unstable up to gamma 1e9 under one BLAS kernel, a few far above the optimum under
    # another, where 1.0 gives the optimum): stronger weights, each reported, until one
    # converges; if none does, the smallest weight's result
    first, fallback, auto_u, auto_n = None, None, False, False
    for factor in (1, 10, 100, 1000):
        weight = DEFAULT_EFFORT_WEIGHT * factor
        try:
            res, unverified = _hinfsyn_once(
                P, nmeas, ncon, effort_weight=weight if auto_u else effort_weight,
                noise_weight=weight if auto_n else noise_weight, **options)
            rho_u, rho_n = res.effort_weight, res.noise_weight
        except _ControllersFailed as exc:
            first, res, unverified, rho_u, rho_n = first or exc, None, True, exc.rho_u, exc.rho_n
        if factor == 1:
            auto_u = isinstance(effort_weight, str) and bool(rho_u)
            auto_n = isinstance(noise_weight, str) and bool(rho_n)
        if not (auto_u or auto_n) and res is None:
            raise first
        if res is not None and factor > 1:
            res = replace(res, regularization=f"{res.regularization} (raised from the default "
                          f"{DEFAULT_EFFORT_WEIGHT:g}: smaller weights left no controller "
                          "verifiable near the optimum)")
        if res is not None and not (unverified and (auto_u or auto_n)):
            return replace(res, elapsed=time.perf_counter() - t0)
        fallback = fallback or res
    if fallback is None:
        raise first
    return replace(fallback, elapsed=time.perf_counter() - t0)


def _hinfsyn_once(P, nmeas, ncon, *, gamma_max, rtol, max_iter, effort_weight, noise_weight,
                  time_scale, verify_rtol):
    """:func:`hinfsyn` with the given regularisation weights (no escalation), and whether
    the Riccati conditions' bracket closed with no controller verified within it."""
    t0 = time.perf_counter()
    P, nmeas, ncon = _checked_plant(P, nmeas, ncon)
    gamma_max = check_positive("gamma_max", gamma_max)
    rtol = check_positive("rtol", rtol)
    max_iter = check_integer("max_iter", max_iter, minimum=2)
    verify_rtol = check_positive("verify_rtol", verify_rtol)
    ws = time_scale_of(P) if time_scale is None else check_positive("time_scale", time_scale)
    search = _GammaSearch(P, nmeas, ncon, ws, effort_weight, noise_weight, max_iter,
                          verify_rtol)
    search.bracket(gamma_max)
    search.bisect(rtol)
    found = search.near_optimum(rtol)
    return search.result(found, rtol, t0)


def _checked_plant(P, nmeas, ncon):
    """(P as a StateSpace, nmeas, ncon) of a continuous, proper, finite, dynamic plant."""
    check_lti("P", P)
    if P.isdtime(strict=True):
        raise ValueError(f"P must be a continuous-time system, got a discrete one (dt={P.dt}); "
                         "convert it first (e.g. control.sample_system's inverse d2c) or "
                         "design in continuous time")
    check_proper("P", P)
    P = ct.ss(P)
    if P.nstates == 0:
        raise ValueError("P is static (it has no states): there is no dynamic H-infinity "
                         "problem to solve; the best static gain follows from a constant-"
                         "matrix LFT, or add the weights' dynamics to P")
    nmeas, ncon = check_channels(P, nmeas, ncon)
    for name, mat in (("A", P.A), ("B", P.B), ("C", P.C), ("D", P.D)):
        check_finite_array(f"P.{name}", mat)
    return P, nmeas, ncon


class _GammaSearch:
    """One gamma-iteration on a scaled, balanced, regularised and normalised plant: the
    trials' Riccati verdicts, their central controllers and the final checks.

    Only a failed Riccati condition proves a gamma infeasible: where the conditions hold
    but the central controller fails its closed-loop check (ill-conditioned near the
    optimum), the optimum is still below, so ``lo`` never moves there.
    """

    def __init__(self, P, nmeas, ncon, ws, effort_weight, noise_weight, max_iter,
                 verify_rtol):
        self.P, self.nmeas, self.ncon, self.ws = P, nmeas, ncon, ws
        self.max_iter, self.verify_rtol = max_iter, verify_rtol
        self.Ps = to_scaled(P, ws)
        self.pl = _balance_states(_Plant.split(self.Ps, nmeas, ncon))
        _check_stabilisable(self.pl, ws)
        grid = _check_grid(self.pl.A, 200)
        self.regularization, self.rho_u, self.rho_n = _regularize(
            self.pl, effort_weight, noise_weight, grid)
        self.nz = _normalize(self.pl)
        _check_axis_zeros(self.nz.plant, ws)
        self.gamma_d = _d11_bound(self.nz.plant)
        self.attempts = []
        # verified controllers by gamma, verdicts by gamma, failed ones by closed-loop peak
        self.cache, self.tried, self.candidates = {}, {}, {}
        self.rejected, self.n_checks = set(), 0

    # -- one trial ------------------------------------------------------------------------

    def check(self, K, gamma):
        """(verdict, status) of a central controller closed around the normalised plant."""
        A, B, C, D = _close_loop(self.nz.plant, K)
        if np.any(_marginal(*_eig_errors(A))):
            return "numerical", "closed loop unstable (numerical failure)"
        peak = _peak_gain(A, B, C, D, _check_grid(A, 150))
        if peak > gamma * (1 + self.verify_rtol):
            self.candidates[peak] = K
            return "numerical", f"closed-loop peak {peak:.4g} > gamma (numerical failure)"
        return "verified", "ok"

    def outcome(self, gamma):
        """'verified', 'numerical' (the Riccati conditions hold but the central
        controller fails the closed-loop check) or 'infeasible'."""
        if gamma in self.tried:
            return self.tried[gamma]
        K, status = _central(self.nz.plant, gamma)
        verdict = "infeasible" if K is None else "verified"
        if K is not None:
            verdict, status = self.check(K, gamma)
        if verdict == "numerical":
            # the same conditions solved the other way round (scipy's Riccati solver
            # first): on the Lundstrom K-step at effort weight 1e-6 the pencil's X, Y
            # gave a controller 72 % above gamma = 1.0 and scipy's one 0.06 % below it
            K2, _ = _central(self.nz.plant, gamma, scipy_first=True)
            if K2 is not None and self.check(K2, gamma)[0] == "verified":
                K, verdict, status = K2, "verified", "ok (scipy's Riccati solutions)"
        self.attempts.append((float(gamma), status))
        if verdict == "verified":
            self.cache[gamma] = K
        self.tried[gamma] = verdict
        return verdict

    def feasible(self, gamma):
        return self.outcome(gamma) == "verified"

    def out_of_trials(self):
        return len(self.attempts) >= self.max_iter

    # -- the bracket ----------------------------------------------------------------------

    def bracket(self, gamma_max):
        """Find a verified gamma (upwards), then an infeasible one (downwards): sets
        ``hi`` (best verified), ``hi_cond`` (smallest gamma where the conditions hold),
        ``lo`` (largest proven infeasible) and ``floor``."""
        hi = max(2.0 * self.gamma_d, 1.0)
        while not self.feasible(hi):
            if hi >= gamma_max or self.out_of_trials():
                self._raise_no_feasible(hi, gamma_max)
            hi = min(4.0 * hi, gamma_max)
        self.lo = self.floor = max(self.gamma_d, 1e-9 * hi)
        self.hi = self.hi_cond = hi
        trial = hi / 4.0
        while trial > self.floor and not self.out_of_trials():
            verdict = self.outcome(trial)
            if verdict == "infeasible":
                self.lo = trial
                break
            self.hi_cond = trial
            if verdict == "verified":
                self.hi = trial
            trial = self.hi_cond / 4.0

    def _raise_no_feasible(self, hi, gamma_max):
        """The bracket found no verified gamma: say whether the conditions ever held."""
        held = [g for g, v in self.tried.items() if v == "numerical"]
        rho_u, rho_n, attempts = self.rho_u, self.rho_n, self.attempts
        if held:
            raise _ControllersFailed(
                f"the Riccati conditions hold at gamma = {min(held):.4g} ... {max(held):.4g}, "
                f"but no central controller there passed the closed-loop check (last: "
                f"{attempts[-1][1]}): the synthesis is ill-conditioned at these gammas "
                f"({len(attempts)} trials, gamma_max={gamma_max:.3g})."
                + (f"  A larger effort_weight / noise_weight than the {max(rho_u, rho_n):g} "
                   "added may help." if rho_u or rho_n else _spread_hint(self.pl.A, self.ws)),
                rho_u, rho_n)
        raise HinfSynthesisError(
            f"no gamma <= {min(hi, gamma_max):.3g} is feasible within gamma_max="
            f"{gamma_max:.3g} and max_iter={self.max_iter} ({len(attempts)} trials); last "
            f"outcome: {attempts[-1][1]}.{_spread_hint(self.pl.A, self.ws)}")

    def bisect(self, rtol):
        """Bisect (geometrically) between ``lo`` and ``hi_cond`` to width ``rtol``."""
        while self.hi_cond > self.lo * (1 + rtol) and not self.out_of_trials():
            mid = np.sqrt(self.lo * self.hi_cond) if self.lo > 0 else self.hi_cond / 2
            verdict = self.outcome(mid)
            if verdict == "infeasible":
                self.lo = mid
            else:
                self.hi_cond = mid
                if verdict == "verified":
                    self.hi = mid

    # -- the final checks -----------------------------------------------------------------

    def given_loop(self, K):
        """(Ks, CLs, poles_s, err): K for the given plant and the loop it closes there."""
        nz = self.nz
        Ak, Bk, Ck, Dk = K
        Ks = ct.ss(Ak, Bk @ nz.Ty, nz.Tu @ Ck, nz.Tu @ Dk @ nz.Ty)
        if np.any(nz.D22):
            # loop shift: K designed for y - D22 u  ->  K (I + D22 K)^-1 on y
            p2, m2 = nz.D22.shape
            static = ct.ss(np.zeros((0, 0)), np.zeros((0, m2)), np.zeros((p2, 0)), nz.D22)
            Ks = ct.feedback(Ks, static, sign=-1)
        CLs = balance(self.Ps.lft(balance(Ks), nu=self.ncon, ny=self.nmeas))
        return (Ks, CLs, *_eig_errors(np.asarray(CLs.A, float)))

    def final_check(self, K, level):
        """(peak, K, CLs, poles_s, norm, w_peak), K in ordinary time, when the normalised
        plant's controller K passes every check at ``level``, else
        None (the reason is appended to ``attempts``).  The ground truth is the loop
        itself: its peak on a dense grid, its poles when closed around the given plant
        (near the optimum a controller can be so ill-conditioned that the same loop,
        realised from the given plant, has a pole at or across the axis) and its norm
        recomputed pointwise on the given plant."""
        P, ws, verify_rtol = self.P, self.ws, self.verify_rtol
        A, B, C, D = _close_loop(self.nz.plant, K)
        peak, _ = _refined_peak(lambda w: _gains(A, B, C, D, w), _check_grid(A, 2000))
        if peak > level * (1 + verify_rtol):
            self.attempts.append((float(level), f"dense-grid peak {peak:.4g} > gamma"))
            return None
        Ks, CLs, poles_s, err = self.given_loop(K)
        # and closed once more as a user would, in ordinary time: near an ill-conditioned
        # optimum one realisation of the same loop can be stable and another not
        K_out = from_scaled(balance(Ks), ws, P.output_labels[-self.nmeas:],
                            P.input_labels[-self.ncon:], name="K")
        lam, lam_err = _eig_errors(np.asarray(P.lft(K_out, nu=self.ncon, ny=self.nmeas).A,
                                              float))
        for poles, errs in ((poles_s, err), (lam / ws, lam_err / ws)):
            if np.any(_marginal(poles, errs)):
                worst = poles[np.argmax(poles.real)] * ws
                self.attempts.append((float(level),
                                      f"given plant's loop: pole at {worst:.4g} rad/s"))
                return None
        # the norm from the pointwise loop, not from CLs: near pole-zero cancellations the
        # closed loop's realisation is evaluated badly (1.7e5 instead of 1.38 seen at DC)
        norm, w_peak = _lft_peak(self.Ps, balance(Ks), _check_grid(CLs.A, 2000), 1.0) \
            if CLs.nstates else (float(np.linalg.norm(CLs.D, 2)), 0.0)
        if not np.isfinite(norm) or norm > level * (1 + verify_rtol):
            self.attempts.append((float(level), f"recomputed norm {norm:.4g} on the given "
                                                "plant > gamma"))
            return None
        return peak, K_out, CLs, poles_s, norm, w_peak

    # -- a controller near the optimum ------------------------------------------------------
    #
    # Near an ill-conditioned optimum whether a central controller passes its checks is
    # decided by rounding (the Lundstrom K-step: peaks from gamma to 14 gamma within 0.1 %
    # above the optimum, in a different pattern under every BLAS kernel), so neither a
    # bisection on "verified" nor the first controller to pass is reproducible.  Every
    # trial's controller counts at its own closed-loop peak, the best ones go through the
    # final checks, and gammas spread over (lo, lo (1 + rtol)] by a golden-ratio sequence
    # are tried until one passes.

    def pool(self):
        """(level, K, at_peak) of the controllers not rejected by the final checks, best
        first: verified ones at their gamma, the others at their closed-loop peak."""
        items = [(g, K, False) for g, K in self.cache.items()] + \
            [(c, K, True) for c, K in self.candidates.items()]
        return sorted((item for item in items if item[0] not in self.rejected),
                      key=lambda x: x[0])

    def first_passing(self, limit):
        """(level, K, at_peak, checked) of the best pooled controller at a level <= limit
        that passes :meth:`final_check`, or None; the ones that fail are rejected."""
        for level, K, at_peak in self.pool():
            if level > limit or self.n_checks >= _MAX_CHECKS:
                return None
            self.n_checks += 1
            checked = self.final_check(K, level)
            if checked is not None:
                return level, K, at_peak, checked
            self.rejected.add(level)
        return None

    def near_optimum(self, rtol):
        """:meth:`first_passing` within ``rtol`` of the optimum, sampling the window; if
        nothing passes there, bisection towards the best verified gamma.  None when no
        pooled controller passes."""
        found, samples = None, 0
        while self.hi_cond <= self.lo * (1 + rtol):
            found = self.first_passing(self.lo * (1 + rtol))
            if (found or samples >= _MAX_SAMPLES or self.n_checks >= _MAX_CHECKS
                    or self.out_of_trials()):
                break
            samples += 1
            gamma = self.lo * (1 + rtol) ** ((samples * _GOLDEN) % 1.0)
            verdict = self.outcome(gamma)
            if verdict == "infeasible" and gamma < self.hi_cond:
                self.lo = gamma
            elif verdict != "infeasible":
                # an "infeasible" above a gamma where the conditions hold is a flipped verdict
                self.hi_cond = min(self.hi_cond, gamma)
        if found is None:
            # nothing in the window: bisect between the conditions' optimum and the best
            # verified gamma, as long as the verdicts there keep improving it
            hi = min([g for g in self.cache if g not in self.rejected] + [self.hi])
            v_lo = self.hi_cond
            while (hi > self.lo * (1 + rtol) and hi > v_lo * (1 + rtol / 8)
                   and not self.out_of_trials()):
                mid = np.sqrt(v_lo * hi)
                if self.feasible(mid):
                    hi = mid
                else:
                    v_lo = mid
            self.hi = hi
            found = self.first_passing(np.inf)
        return found

    def backed_off(self, rtol):
        """(gamma, checked) backing off from the best controller by growing steps (1 %,
        2 %, 4 %, ...); ``checked`` None when none passes."""
        gamma, result = (self.pool() or [(self.hi,)])[0][0], None
        for k in range(_MAX_BACKOFFS):
            gamma *= 1 + max(10 * rtol, 0.01) * 2 ** k
            if self.feasible(gamma):
                result = self.final_check(self.cache[gamma], gamma)
                if result is not None:
                    break
        return gamma, result

    # -- the result -------------------------------------------------------------------------

    def result(self, found, rtol, t0):
        """(HinfResult, unverified) of the search, from :meth:`near_optimum`'s find."""
        if found is not None:
            gamma, K, at_peak, result = found
            if at_peak:
                self.attempts.append((float(gamma),
                                      "a trial's central controller, verified at its peak"))
        else:
            gamma, result = self.backed_off(rtol)
        attempts, tried, lo, floor = self.attempts, self.tried, self.lo, self.floor
        if result is None:
            raise HinfSynthesisError(f"no controller passed verification (last: "
                                     f"{attempts[-1][1]}; {len(attempts)} trials)")
        peak, K, CLs, poles_s, norm, w_peak = result
        converged = gamma <= lo * (1 + rtol) or lo <= floor
        unverified = not converged and self.hi_cond <= lo * (1 + rtol)
        if tried.get(lo) == "infeasible" and peak < lo:
            # the controller itself does better than gammas judged infeasible: those
            # verdicts were rounding in ill-conditioned Riccati equations (seen on the
            # distillation K-step: gamma 2.378 "infeasible", this controller 1.457)
            lo = max([g for g, v in tried.items() if v == "infeasible" and g < peak] + [floor])
            converged = False
            attempts.append((float(peak), "controller beats gammas judged infeasible: those "
                                           "verdicts were numerical"))
        ws, P = self.ws, self.P
        CL = from_scaled(CLs, ws, P.input_labels[:-self.ncon], P.output_labels[:-self.nmeas],
                         name="closed_loop")
        if tried.get(lo) != "infeasible":
            # the search reached its floor (1e-9 gamma) without an infeasible gamma: only the
            # D11 bound is proven (0 without D11), e.g. for square D12 and D21, where gamma -> 0
            lo = self.gamma_d
        return HinfResult(K=K, gamma=float(gamma), gamma_infeasible=float(lo),
                          norm=float(norm), omega_peak=float(w_peak * ws), closed_loop=CL,
                          closed_loop_poles=np.sort_complex(poles_s * ws),
                          regularization=self.regularization, effort_weight=self.rho_u,
                          noise_weight=self.rho_n, time_scale=ws, iterations=len(attempts),
                          elapsed=time.perf_counter() - t0, converged=bool(converged),
                          attempts=tuple(attempts)), unverified
