"""Linear fractional transformations of state-space models, computed in scaled time."""

import control as ct
import numpy as np
import scipy.optimize as opt

from piezolib._checks import (check_continuous, check_finite_array, check_finite_lti,
                              check_lti, check_positive)
from piezolib.robust.lti import balance, from_scaled, time_scale_of, to_scaled

__all__ = ["lower_lft", "lft_response", "lft_hinf_norm"]


def _split(P, K):
    """(nmeas, ncon) of the loop of P and K, checked."""
    for name, sys in (("P", P), ("K", K)):
        check_lti(name, sys)
        check_finite_lti(name, sys)
        check_continuous(name, sys)   # a discrete K used to come back continuous
    nmeas, ncon = K.ninputs, K.noutputs
    if P.noutputs <= nmeas or P.ninputs <= ncon:
        raise ValueError(f"P ({P.noutputs}x{P.ninputs}) is too small for a "
                         f"{ncon}x{nmeas} controller")
    return nmeas, ncon


def lower_lft(P, K, omega_s=None):
    """Lower LFT F_l(P, K) (eq. 17), computed in scaled time, names kept.

    Parameters
    ----------
    P : control.LTI
        Generalized plant; its last ``K.ninputs`` outputs are the
        measurements and its last ``K.noutputs`` inputs the controls.
    K : control.LTI
        Controller.
    omega_s : float, optional
        Internal time scale [rad/s]; default :func:`~piezolib.robust.lti.time_scale_of`
        ``(P, K)``.

    Returns
    -------
    control.StateSpace
        F_l(P, K) in ordinary time, named ``"M"``, with P's remaining
        input and output names.

    Raises
    ------
    ValueError
        P has no channels left besides the controller's, a non-finite
        coefficient, or a discrete-time P or K (use python-control's
        ``lft`` on discrete models directly).

    Examples
    --------
    >>> G = ct.tf([1], [1, 1])
    >>> P = ct.ss(ct.tf([[[1], [-1]], [[1], [-1]]], [[[1], [1, 1]], [[1], [1, 1]]]))  # z = y = w - G u
    >>> S = lower_lft(P, ct.tf(10, 1))                     # S = 1/(1 + K G) for K = 10
    >>> S.poles(), round(float(ct.dcgain(S)), 4), S.name
    (array([-11.+0.j]), 0.0909, 'M')
    """
    nmeas, ncon = _split(P, K)
    omega_s = time_scale_of(P, K) if omega_s is None else check_positive("omega_s", omega_s)
    # realise first, then scale: for transfer-function inputs this closed
    # loop was found more accurate than realising the scaled coefficients
    Ps, Ks = to_scaled(ct.ss(P), omega_s), to_scaled(ct.ss(K), omega_s)
    M = balance(Ps.lft(Ks, nu=ncon, ny=nmeas))
    return from_scaled(M, omega_s, P.input_labels[:-ncon], P.output_labels[:-nmeas], name="M")


def lft_response(P, K, omega, omega_s=None):
    """Frequency response of F_l(P, K) on ``omega`` [rad/s], shape (nf, p1, m1).

    Evaluated frequency by frequency as P11 + P12 K (I - P22 K)^-1 P21 from
    the responses of P and K (each realised in scaled time, s -> s/omega_s,
    and balanced by :func:`~piezolib.robust.lti.to_scaled`).  No closed-loop realisation is formed: where the loop
    nearly cancels a pole (a slow controller pole against a plant zero, as in
    DK-iteration K-steps) the closed loop's state matrix is ill-conditioned
    and its direct evaluation can be wrong by O(1), while the responses of P
    and K stay as accurate as the models themselves.

    Parameters
    ----------
    P, K : control.LTI
        Generalized plant and controller (as in :func:`lower_lft`).
    omega : array_like
        Frequencies [rad/s].
    omega_s : float, optional
        Internal time scale [rad/s]; default :func:`~piezolib.robust.lti.time_scale_of`
        ``(P, K)``; ``omega_s = 1`` evaluates the models as given.

    Returns
    -------
    ndarray, shape (len(omega), p1, m1)

    Raises
    ------
    ValueError
        As :func:`lower_lft`, or when I - P22 K is singular at a frequency of
        ``omega`` (the closed loop has a pole there).

    Examples
    --------
    >>> G = ct.tf([1], [1, 1])
    >>> P = ct.ss(ct.tf([[[1], [-1]], [[1], [-1]]], [[[1], [1, 1]], [[1], [1, 1]]]))  # z = y = w - G u
    >>> M = lft_response(P, ct.tf(10, 1), [0.0, 1e3])
    >>> M.shape, np.abs(M[:, 0, 0]).round(4)
    ((2, 1, 1), array([0.0909, 0.9999]))
    """
    loop = _LoopResponse(P, K, omega_s)
    return loop(check_finite_array("omega", omega, ndim=1, min_length=1, real=True))


class _LoopResponse:
    """F_l(P, K)'s response as a function of frequency, with P and K realised once.

    :func:`lft_response` is ``_LoopResponse(P, K, omega_s)(omega)``; a search that
    evaluates the same loop at many frequency sets (a peak's refinement)
    scales and balances P and K once instead of at every call.

    Examples
    --------
    >>> P = ct.ss(ct.tf([[[1], [-1]], [[1], [-1]]], [[[1], [1, 1]], [[1], [1, 1]]]))
    >>> loop, w = _LoopResponse(P, ct.tf(10, 1)), np.array([0.0, 1e3])
    >>> bool(np.array_equal(loop(w), lft_response(P, ct.tf(10, 1), w)))
    True
    """

    def __init__(self, P, K, omega_s=None):
        self.nmeas, self.ncon = _split(P, K)
        self.omega_s = (time_scale_of(P, K) if omega_s is None
                        else check_positive("omega_s", omega_s))
        self.Ps, self.Ks = to_scaled(ct.ss(P), self.omega_s), to_scaled(ct.ss(K), self.omega_s)
        self.shape = (P.noutputs - self.nmeas, P.ninputs - self.ncon)

    def __call__(self, omega):
        """The response on ``omega`` [rad/s] (1-D, finite), shape (len(omega), p1, m1)."""
        nmeas, ncon, Ps, Ks = self.nmeas, self.ncon, self.Ps, self.Ks
        s = 1j * omega / self.omega_s
        (Pw, P_cond), (Kw, K_cond) = _response(Ps, s), _response(Ks, s)
        M = np.empty((omega.size, *self.shape), complex)
        # near a pole of P or K on the axis (a plant resonance, an integrator) their
        # responses are huge and the pointwise formula cancels them; there the
        # balanced closed-loop realisation is the accurate one
        near_pole = np.maximum(P_cond, K_cond) > _POLE_CONDITION
        if np.any(near_pole):
            CL = balance(Ps.lft(Ks, nu=ncon, ny=nmeas))
            M[near_pole] = _response(CL, s[near_pole])[0]
        ok = ~near_pole
        P11, P12 = Pw[ok, :-nmeas, :-ncon], Pw[ok, :-nmeas, -ncon:]
        P21, P22 = Pw[ok, -nmeas:, :-ncon], Pw[ok, -nmeas:, -ncon:]
        PK = P22 @ Kw[ok]
        loop = np.eye(nmeas) - PK
        # singular relative to the terms it is the difference of (round-off level)
        sigma_min = np.linalg.svd(loop, compute_uv=False)[:, -1]
        singular = sigma_min <= 8 * np.finfo(float).eps * (1 + np.linalg.norm(PK, 2, axis=(1, 2)))
        if np.any(singular):
            raise ValueError(f"I - P22 K is singular at omega = {omega[ok][singular][0]:.6g} "
                             "rad/s: F_l(P, K) has a pole on the imaginary axis there")
        M[ok] = P11 + P12 @ Kw[ok] @ np.linalg.solve(loop, P21)
        return M


def lft_hinf_norm(P, K, omega, omega_s=None, rtol=1e-9):
    """H-infinity norm of F_l(P, K) from its pointwise response, with the peak's frequency.

    The largest singular value of :func:`lft_response` is maximised on
    ``omega`` (and at DC) and refined around the best grid point, as
    :func:`~piezolib.robust.lti.hinf_norm` does for a realisation.  Working
    from the responses of P and K avoids the closed loop's state matrix, whose
    evaluation can be ill-conditioned where the loop nearly cancels a pole.
    Stability is not checked here: the caller checks the closed-loop poles.

    Parameters
    ----------
    P, K : control.LTI
        Generalized plant and controller (as in :func:`lower_lft`).
    omega : array_like
        Search grid [rad/s], at least 2 points.
    omega_s : float, optional
        Internal time scale [rad/s] (see :func:`lft_response`).
    rtol : float, optional
        Relative tolerance of the refinement in log-frequency.

    Returns
    -------
    peak : float
    omega_peak : float
        [rad/s]; 0 for a peak at DC.

    Examples
    --------
    GS = G/(1 + K G) of a lightly damped G: z = G (d + u), y = -G (d + u).

    >>> G = ct.tf([1], [1, 0.2, 1])
    >>> num, den = G.num[0][0], G.den[0][0]
    >>> P = ct.ss(ct.tf([[num, num], [-num, -num]], [[den, den], [den, den]]))
    >>> peak, w = lft_hinf_norm(P, ct.tf(0.1, 1), np.logspace(-1, 1, 200))
    >>> round(peak, 3), round(w, 3)                      # 1 / (0.2 sqrt(1.09)) at sqrt(1.08)
    (4.789, 1.039)
    """
    _split(P, K)
    omega = check_finite_array("omega", omega, ndim=1, min_length=2, real=True)
    omega_s = time_scale_of(P, K) if omega_s is None else check_positive("omega_s", omega_s)

    loop = _LoopResponse(P, K, omega_s)

    def sigma(w):
        return np.linalg.norm(loop(np.atleast_1d(np.asarray(w, float))), 2, axis=(1, 2))

    g = sigma(omega)
    k = int(np.argmax(g))
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, omega.size - 1)]
    if lo > 0:
        res = opt.minimize_scalar(lambda lw: -sigma(np.exp(lw))[0],
                                  bounds=(np.log(lo), np.log(hi)), method="bounded",
                                  options={"xatol": rtol})
        peak, w_peak = max((g[k], omega[k]), (-res.fun, float(np.exp(res.x))))
    else:
        peak, w_peak = g[k], omega[k]
    dc = float(sigma(0.0)[0])
    if dc >= peak:
        return dc, 0.0
    return float(peak), float(w_peak)


#: cond(sI - A) above which a frequency counts as at a pole of P or K.
_POLE_CONDITION = 1e8


def _resolvent_condition(resolvent):
    """cond_2 of each matrix of a stack where it may exceed :data:`_POLE_CONDITION`;
    elsewhere an upper bound below it.

    ||R||_F ||R^-1||_F >= cond_2(R) costs one inversion; the SVD (twice that) is
    computed only where this bound exceeds the threshold, so every comparison with
    :data:`_POLE_CONDITION` comes out as with the exact cond_2.
    """
    try:
        bound = (np.linalg.norm(resolvent, axis=(1, 2))
                 * np.linalg.norm(np.linalg.inv(resolvent), axis=(1, 2)))
    except np.linalg.LinAlgError:       # an exactly singular point: all exact
        return np.linalg.cond(resolvent)
    cond = np.where(np.isfinite(bound), bound, np.inf)
    exact = cond > _POLE_CONDITION
    if np.any(exact):
        cond[exact] = np.linalg.cond(resolvent[exact])
    return cond


def _response(sys, s):
    """Response C (sI - A)^-1 B + D of a state-space model at the points ``s``,
    shape (ns, p, m), and cond(sI - A) at each as :func:`_resolvent_condition`
    gives it (inf, and a NaN response, only where sI - A is exactly singular)."""
    D = np.broadcast_to(sys.D, (s.size, *sys.D.shape)).astype(complex)
    if sys.nstates == 0:
        return D, np.ones(s.size)
    resolvent = s[:, None, None] * np.eye(sys.nstates) - sys.A
    cond = _resolvent_condition(resolvent)
    out = np.full_like(D, np.nan)
    finite = np.isfinite(cond)
    try:
        out[finite] = sys.C @ np.linalg.solve(resolvent[finite], sys.B) + D[finite]
    except np.linalg.LinAlgError:           # an exact pole on the grid: point by point
        for k in np.flatnonzero(finite):
            try:
                out[k] = sys.C @ np.linalg.solve(resolvent[k], sys.B) + D[k]
            except np.linalg.LinAlgError:
                cond[k] = np.inf
    return out, cond
