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

    P and K are in ordinary time; the loop is closed and evaluated in scaled
    time (s -> s/omega_s), where the realisations are well conditioned.

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
    """
    _split(P, K)
    omega = check_finite_array("omega", omega, ndim=1)
    omega_s = time_scale_of(P, K) if omega_s is None else check_positive("omega_s", omega_s)
    if omega_s != 1.0:
        P, K = to_scaled(ct.ss(P), omega_s), to_scaled(ct.ss(K), omega_s)
    CL = ct.ss(P).lft(ct.ss(K), nu=K.noutputs, ny=K.ninputs)
    return np.moveaxis(CL(1j * omega / omega_s, squeeze=False), -1, 0)
