"""Linear fractional transformations of state-space models, computed in scaled time."""

import control as ct
import numpy as np

from piezolib._checks import check_finite_array, check_lti, check_positive
from piezolib.robust.lti import DEFAULT_TIME_SCALE, balance, scale_time

__all__ = ["lower_lft", "lft_response"]


def lower_lft(P, K, omega_s=DEFAULT_TIME_SCALE):
    """Lower LFT F_l(P, K) of eq. 17, computed in scaled time, names kept.

    The last ``K.ninputs`` outputs of P are the measurements and the last
    ``K.noutputs`` inputs are the controls.
    """
    check_lti("P", P)
    check_lti("K", K)
    omega_s = check_positive("omega_s", omega_s)
    nmeas, ncon = K.ninputs, K.noutputs
    if P.noutputs <= nmeas or P.ninputs <= ncon:
        raise ValueError(f"P ({P.noutputs}x{P.ninputs}) is too small for a "
                         f"{ncon}x{nmeas} controller")
    Ps = balance(scale_time(ct.ss(P), omega_s))
    Ks = balance(scale_time(ct.ss(K), omega_s))
    M = balance(Ps.lft(Ks, nu=ncon, ny=nmeas))
    M = balance(scale_time(M, 1.0 / omega_s))
    return ct.ss(M.A, M.B, M.C, M.D, inputs=list(P.input_labels[:-ncon]),
                 outputs=list(P.output_labels[:-nmeas]), name="M")


def lft_response(P, K, omega, omega_s=DEFAULT_TIME_SCALE):
    """Frequency response of F_l(P, K) on ``omega`` [rad/s], shape (nf, p1, m1).

    P and K are in ordinary time; the loop is closed and evaluated in scaled
    time (s -> s/omega_s), where the realisations are well conditioned.
    ``omega_s = 1`` evaluates the models as given.
    """
    check_lti("P", P)
    check_lti("K", K)
    omega = check_finite_array("omega", omega, ndim=1)
    omega_s = check_positive("omega_s", omega_s)
    if omega_s != 1.0:
        P, K = balance(scale_time(ct.ss(P), omega_s)), balance(scale_time(ct.ss(K), omega_s))
    CL = ct.ss(P).lft(ct.ss(K), nu=K.noutputs, ny=K.ninputs)
    return np.moveaxis(CL(1j * omega / omega_s, squeeze=False), -1, 0)
