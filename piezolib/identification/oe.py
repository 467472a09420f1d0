"""Output-error models by Steiglitz-McBride passes over RLS (bias-free under output noise).

Why output-error passes follow ARX: ``docs/stage.md``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib._checks import check_integer, check_positive
from piezolib.identification.arx import (DEFAULT_INITIAL_GAIN, ArxModel, arx_regressors,
                                         excitation_band,
                                         checked_arx_regressors, discrete_tf, fit_arx,
                                         least_squares)

__all__ = ["OutputErrorModel", "fit_output_error"]


@dataclass(frozen=True)
class OutputErrorModel:
    """Discrete output-error model B/A from Steiglitz-McBride iterations.

    Attributes
    ----------
    a, b : ndarray
        Final [1, a1 ... a_na] and [0 ... 0, b1 ... b_nb] (as in ArxModel).
    dt : float
        Sample time [s].
    final : ArxModel
        The RLS estimate (eq. 1-3, with parameter histories) on the data
        prefiltered by the converged denominator; ``a`` and ``b`` are its
        parameters.
    prefilters : tuple of ndarray
        Denominators A_i of the prefiltering passes (pass 0: plain ARX).
    converged : bool
        True when the passes converged within ``tol``.
    system : control.TransferFunction
        B/A as a discrete-time transfer function.
    """

    a: np.ndarray
    b: np.ndarray
    dt: float
    final: ArxModel
    prefilters: tuple
    converged: bool
    system: ct.TransferFunction


def fit_output_error(u, y, fs, na=6, nb=6, nk=1, iterations=50, tol=1e-8,
                     initial_gain=DEFAULT_INITIAL_GAIN):
    """Output-error estimate by RLS on prefiltered ARX regressors.

    With white measurement noise on y, the ARX (equation-error) estimate is
    biased: the noise enters the regression multiplied by A(q), which weights
    the high frequencies where the stage's response is small.  The
    Steiglitz-McBride iteration removes the bias: pass i fits the ARX
    regression to u and y filtered by 1/A_{i-1}(q), the denominator of the
    previous pass (pass 0 is plain ARX).  At convergence the equation error
    of the filtered data is the output error y - (B/A) u.  The prefiltering
    passes use batch least squares (the limit of RLS for large W(0), and
    fifty times faster); the final estimate is RLS, eq. 1-3, on the data
    filtered by the converged denominator.

    Parameters
    ----------
    u, y : array_like
        Input and output deviations [V], from rest.
    fs : float
        Sampling frequency [Hz].
    na, nb, nk : int, optional
        Orders and delay.
    iterations : int, optional
        Maximum number of prefiltering passes.
    tol : float, optional
        Stop when max |change of a parameter| / max |parameter| < tol.
    initial_gain : float, optional
        RLS W(0) relative to the data power in every pass (see ``rls``).

    Returns
    -------
    OutputErrorModel
    """
    iterations = check_integer("iterations", iterations, minimum=1)
    tol = check_positive("tol", tol)
    fs = check_positive("fs", fs)
    checked_arx_regressors(u, y, na, nb, nk)          # raw data: length, excitation
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    den = np.array([1.0])
    prefilters, previous, converged = [], None, False
    for _ in range(iterations):
        phi, target, _ = arx_regressors(sg.lfilter([1.0], den, u),
                                        sg.lfilter([1.0], den, y), na, nb, nk)
        params = least_squares(phi, target)
        den = np.concatenate(([1.0], params[:na]))
        if np.any(np.abs(np.roots(den)) >= 1):
            band = excitation_band(u, fs)
            raise ValueError(
                "an intermediate model is unstable, so it cannot prefilter the data: 99 % of "
                f"the input's power lies below {band:.3g} Hz (Nyquist {fs / 2:.4g} Hz).  "
                "A record without broadband excitation (a hysteresis loop, a step from rest) "
                "cannot identify a model of this order: identify from a chirp or another "
                "broadband input, or lower the order")
        prefilters.append(den)
        if previous is not None and (np.max(np.abs(params - previous))
                                     < tol * np.max(np.abs(params))):
            converged = True
            break
        previous = params
    final = fit_arx(sg.lfilter([1.0], den, u), sg.lfilter([1.0], den, y), fs,
                    na, nb, nk, initial_gain)
    return OutputErrorModel(final.a, final.b, final.dt, final, tuple(prefilters),
                            converged, discrete_tf(final.b, final.a, final.dt, "oe"))
