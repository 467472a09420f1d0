"""Tustin discretisation of a continuous controller, with response and loop checks.

:func:`discretize` pre-warps at the controller's least-damped feature,
reports the largest relative response error below a check frequency and,
given a plant, whether the sampled loop is stable.  Why pre-warping matters
is explained in ``docs/robust.md``.

SISO and MIMO (square or rectangular) controllers alike: for a MIMO controller the
response error is the largest singular value of the error relative to that of the
controller, sigma_max(K_d - K) / sigma_max(K) at each frequency (for SISO it is the same
number, |K_d / K - 1|, which is computed as before), and the sampled loop is the MIMO
loop of the zero-order-hold plant and K_d in negative feedback.
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import check_finite_lti, check_model, check_positive
from piezolib.robust.lti import realize, with_signals

__all__ = ["DiscreteController", "discretize", "least_damped_frequency"]


@dataclass(frozen=True)
class DiscreteController:
    """Result of :func:`discretize`.

    Attributes
    ----------
    K : control.StateSpace
        Discrete controller, sample time 1/fs.
    fs : float
        Sampling frequency [Hz].
    prewarp_frequency : float or None
        Pre-warping frequency [rad/s] used (None: plain Tustin).
    check_Hz : float
        Upper end of the frequency band compared [Hz].
    max_relative_error : float
        max |K_d(e^{j omega T}) / K(j omega) - 1| for omega up to check_Hz (SISO);
        for a MIMO controller max sigma_max(K_d - K) / sigma_max(K).
    omega_max_error : float
        Where that maximum occurs [rad/s].
    matches : bool
        ``max_relative_error <= rtol``.
    loop_stable : bool or None
        Sampled loop with the zero-order-hold plant stable (None if no plant).
    loop_spectral_radius : float or None
        Largest |pole| of that sampled loop.

    Examples
    --------
    >>> d = discretize(ct.tf([100], [1, 100]), 10e3, G=ct.tf([1], [1, 1]), check_Hz=100.0)
    >>> d.fs, d.prewarp_frequency, d.matches, d.loop_stable
    (10000.0, None, True, True)
    >>> bool(d.max_relative_error < 1e-3), bool(d.loop_spectral_radius < 1)
    (True, True)
    """

    K: ct.StateSpace
    fs: float
    prewarp_frequency: float | None
    check_Hz: float
    max_relative_error: float
    omega_max_error: float
    matches: bool
    loop_stable: bool | None
    loop_spectral_radius: float | None


def least_damped_frequency(K, omega_max):
    """Natural frequency [rad/s] of the least-damped pole or zero of K below omega_max.

    Returns None when K has no complex pole or zero below omega_max.  For a MIMO K
    the zeros are its transmission zeros.

    Examples
    --------
    >>> K = ct.tf([1, 0.2, 1e6], [1, 100, 1e6])           # a notch at 1000 rad/s
    >>> least_damped_frequency(K, omega_max=1e5)
    1000.0
    >>> print(least_damped_frequency(ct.tf([1], [1, 1]), 1e3))   # no complex root
    None
    """
    check_model("K", K)
    omega_max = check_positive("omega_max", omega_max)
    siso = K.ninputs == 1 and K.noutputs == 1
    roots = np.r_[ct.poles(K), ct.zeros(K if siso else ct.ss(K))]
    roots = roots[(np.abs(roots.imag) > 0) & (np.abs(roots) < omega_max)]
    if roots.size == 0:
        return None
    damping = -roots.real / np.abs(roots)
    return float(np.abs(roots[np.argmin(damping)]))


def discretize(K, fs, *, prewarp="auto", check_Hz=1000.0, rtol=0.1, G=None, n_check=2000):
    """Tustin discretisation of a controller with a frequency-response check.

    Parameters
    ----------
    K : control.LTI
        Continuous-time controller, SISO or MIMO (square or rectangular).
    fs : float
        Sampling frequency [Hz].
    prewarp : 'auto', float or None
        Pre-warping frequency [rad/s]; 'auto' uses
        :func:`least_damped_frequency` below 1.5 * check_Hz, None gives plain
        Tustin.
    check_Hz : float
        Compare the responses from 0 to this frequency [Hz].
    rtol : float
        Largest relative error for ``matches``.
    G : control.LTI, optional
        Continuous plant (K's inputs x K's outputs: it maps K's outputs to its
        inputs); if given, the sampled loop with its zero-order-hold
        discretisation is checked for stability.
    n_check : int
        Number of check frequencies.

    Returns
    -------
    DiscreteController

    Raises
    ------
    ValueError
        A discrete-time K, ``check_Hz`` or ``prewarp`` at or above the
        Nyquist frequency, non-positive rates.

    Examples
    --------
    >>> import control as ct
    >>> d = discretize(ct.tf([1e3], [1, 1e3]), 10e3, prewarp=None)
    >>> d.K.dt, bool(d.matches)
    (0.0001, True)

    A 2 x 2 controller: the error is measured on the largest singular value.

    >>> K2 = ct.ss([[-100.0, 0.0], [0.0, -2000.0]], np.eye(2), [[1.0, 2.0], [0.0, 1.0]],
    ...            np.zeros((2, 2)))
    >>> d2 = discretize(K2, 10e3, prewarp=None, check_Hz=200.0)
    >>> d2.K.ninputs, d2.K.noutputs, round(d2.max_relative_error, 4)
    (2, 2, 0.001)
    """
    check_finite_lti("K", K)
    if not K.isctime(strict=True):
        raise ValueError("K must be a continuous-time controller")
    fs = check_positive("fs", fs)
    check_Hz = check_positive("check_Hz", check_Hz)
    rtol = check_positive("rtol", rtol)
    if check_Hz >= fs / 2:
        raise ValueError(f"check_Hz ({check_Hz}) must be below the Nyquist frequency {fs / 2}")
    Ts = 1.0 / fs
    if prewarp == "auto":
        w_pre = least_damped_frequency(K, 2 * np.pi * 1.5 * check_Hz)
    elif prewarp is None:
        w_pre = None
    else:
        w_pre = check_positive("prewarp", prewarp)
        if w_pre >= np.pi * fs:
            raise ValueError(f"prewarp ({w_pre} rad/s) must be below the Nyquist "
                             f"frequency {np.pi * fs:.4g} rad/s")
    Kc = realize(K)
    Kd = ct.c2d(ct.ss(Kc), Ts, method="tustin", prewarp_frequency=w_pre)
    Kd = with_signals(Kd, K.input_labels, K.output_labels, name=f"{K.name}_d")
    omega = np.linspace(2 * np.pi * check_Hz / n_check, 2 * np.pi * check_Hz, n_check)
    siso = K.ninputs == 1 and K.noutputs == 1
    if siso:
        kc = np.ravel(Kc(1j * omega))
        kd = np.ravel(Kd(np.exp(1j * omega * Ts)))
        err = np.abs(kd / kc - 1)
    else:
        kc = np.moveaxis(Kc(1j * omega, squeeze=False), -1, 0)
        kd = np.moveaxis(Kd(np.exp(1j * omega * Ts), squeeze=False), -1, 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            err = (np.linalg.svd(kd - kc, compute_uv=False)[:, 0]
                   / np.linalg.svd(kc, compute_uv=False)[:, 0])
        err = np.where(np.isnan(err), np.inf, err)
    k = int(np.argmax(err))
    stable = radius = None
    if G is not None:
        check_finite_lti("G", G)
        if G.noutputs != K.ninputs or G.ninputs != K.noutputs:
            raise ValueError(f"G must map K's {K.noutputs} outputs to its {K.ninputs} "
                             f"inputs ({K.ninputs} x {K.noutputs}), got "
                             f"{G.noutputs} x {G.ninputs}")
        Gd = ct.c2d(ct.ss(realize(G)), Ts, method="zoh")
        if siso:
            loop = ct.feedback(Gd * Kd, 1)
        else:
            loop = ct.feedback(Gd * Kd, ct.ss([], [], [], np.eye(K.ninputs), Ts))
        radius = float(np.max(np.abs(ct.poles(loop)))) if ct.ss(loop).nstates else 0.0
        stable = bool(radius < 1)
    return DiscreteController(K=Kd, fs=fs, prewarp_frequency=w_pre, check_Hz=check_Hz,
                              max_relative_error=float(err[k]), omega_max_error=float(omega[k]),
                              matches=bool(err[k] <= rtol), loop_stable=stable,
                              loop_spectral_radius=radius)
