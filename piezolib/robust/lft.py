"""Linear fractional transformations of state-space models, computed in scaled time."""

import control as ct
import numpy as np

from piezolib._checks import (check_continuous, check_finite_array, check_finite_lti,
                              check_lti, check_positive)
from piezolib.robust.lti import balance, from_scaled, time_scale_of, to_scaled

__all__ = ["lower_lft", "lft_response"]


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
    """
    nmeas, ncon = _split(P, K)
    omega = check_finite_array("omega", omega, ndim=1)
    omega_s = time_scale_of(P, K) if omega_s is None else check_positive("omega_s", omega_s)
    s = 1j * omega / omega_s
    Ps, Ks = to_scaled(ct.ss(P), omega_s), to_scaled(ct.ss(K), omega_s)
    (Pw, P_cond), (Kw, K_cond) = _response(Ps, s), _response(Ks, s)
    M = np.empty((omega.size, P.noutputs - nmeas, P.ninputs - ncon), complex)
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
    loop = np.eye(nmeas) - P22 @ Kw[ok]
    singular = np.linalg.cond(loop) > 1 / np.finfo(float).eps
    if np.any(singular):
        raise ValueError(f"I - P22 K is singular at omega = {omega[ok][singular][0]:.6g} rad/s: "
                         "F_l(P, K) has a pole on the imaginary axis there")
    M[ok] = P11 + P12 @ Kw[ok] @ np.linalg.solve(loop, P21)
    return M


#: cond(sI - A) above which a frequency counts as at a pole of P or K.
_POLE_CONDITION = 1e8


def _response(sys, s):
    """Response C (sI - A)^-1 B + D of a state-space model at the points ``s``,
    shape (ns, p, m), and cond(sI - A) at each (inf where singular)."""
    D = np.broadcast_to(sys.D, (s.size, *sys.D.shape)).astype(complex)
    if sys.nstates == 0:
        return D, np.ones(s.size)
    resolvent = s[:, None, None] * np.eye(sys.nstates) - sys.A
    cond = np.linalg.cond(resolvent)
    regular = np.isfinite(cond) & (cond < 1 / np.finfo(float).eps)
    out = np.full_like(D, np.nan)
    out[regular] = sys.C @ np.linalg.solve(resolvent[regular], sys.B) + D[regular]
    return out, np.where(regular, cond, np.inf)
