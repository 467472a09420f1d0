"""Magnitude model of a gain times first- and second-order sections, in log parameters.

Shared by the D-scaling fit (:mod:`piezolib.robust.dfit`) and the covering-weight
fit (:mod:`piezolib.uncertainty.weight`).  The model of order ``n`` is

    H(s) = k * prod_{j < n//2} (s^2/w_zj^2 + 2 zeta_zj s/w_zj + 1)
                               / (s^2/w_pj^2 + 2 zeta_pj s/w_pj + 1)
             * [(s/w_z + 1) / (s/w_p + 1)]              (only when n is odd)

with every section of unit DC gain, so |H(0)| = k.  Its parameter vector
``theta`` (length :func:`n_parameters`) holds logarithms:

    theta[0]                      log k
    theta[1 + 4 j : 5 + 4 j]      log w_zj, log zeta_zj, log w_pj, log zeta_pj
    theta[-2:] (n odd)            log w_z, log w_p  of the first-order section

Frequencies are in rad/s (or any unit consistent with the frequency grid).
Every real ``theta`` gives a stable, minimum-phase, biproper H (all w and zeta
are positive), so fits over ``theta`` need no projection.
"""

import control as ct
import numpy as np

__all__ = ["n_parameters", "log_magnitude", "transfer_function", "parameter_bounds"]


def n_parameters(order):
    """Length of ``theta`` for a model of ``order`` poles (= zeros).

    Parameters
    ----------
    order : int
        Number of poles of H, >= 0.

    Returns
    -------
    int
        ``1 + 4 * (order // 2) + 2 * (order % 2)``.

    Examples
    --------
    >>> [n_parameters(order) for order in range(4)]      # k, then (w_z, z_z, w_p, z_p) or (w_z, w_p)
    [1, 3, 5, 7]
    """
    order = int(order)
    if order < 0:
        raise ValueError(f"order must be >= 0, got {order}")
    return 1 + 4 * (order // 2) + 2 * (order % 2)


def _check_theta(theta, order):
    theta = np.asarray(theta, dtype=float)
    expected = n_parameters(order)
    if theta.shape != (expected,):
        raise ValueError(f"theta must have shape ({expected},) for order {order}, "
                         f"got {theta.shape}")
    return theta


def log_magnitude(theta, log_omega, order, jacobian=False):
    """Natural log of |H(j omega)| on a grid, and optionally its Jacobian in ``theta``.

    Parameters
    ----------
    theta : array_like, shape (n_parameters(order),)
        Log parameters (layout in the module docstring).
    log_omega : ndarray
        Natural logarithms of the frequencies [log rad/s], 1-D.
    order : int
        Order of H.
    jacobian : bool, optional
        Also return d log|H| / d theta.

    Returns
    -------
    value : ndarray, shape (len(log_omega),)
        log|H(j omega)|.
    J : ndarray, shape (len(log_omega), len(theta))
        Only with ``jacobian=True``.

    Examples
    --------
    >>> theta = np.log([2.0, 10.0, 0.5, 100.0, 0.3])       # k, w_z, zeta_z, w_p, zeta_p
    >>> value = log_magnitude(theta, np.log([1e-3, 1e6]), 2)
    >>> np.round(np.exp(value), 3)                          # k at DC, k (w_p/w_z)^2 above
    array([  2., 200.])
    """
    theta = _check_theta(theta, order)
    log_omega = np.asarray(log_omega, dtype=float)
    u = np.exp(2 * log_omega)                       # omega^2
    out = np.full_like(log_omega, theta[0])
    J = np.zeros((log_omega.size, theta.size)) if jacobian else None
    if jacobian:
        J[:, 0] = 1.0
    i = 1
    for _ in range(order // 2):
        for sign in (1.0, -1.0):                    # zero pair, then pole pair
            a, z2 = np.exp(2 * theta[i]), np.exp(2 * theta[i + 1])    # w^2, zeta^2
            N = (a - u) ** 2 + 4 * z2 * a * u       # |w^2 - omega^2 + 2 j zeta w omega|^2
            out += sign * 0.5 * (np.log(N) - 2 * np.log(a))
            if jacobian:
                J[:, i] = sign * (a * (2 * (a - u) + 4 * z2 * u) / N - 2.0)
                J[:, i + 1] = sign * 4 * z2 * a * u / N
            i += 2
    if order % 2:
        for sign in (1.0, -1.0):                    # zero, then pole
            z2 = np.exp(2 * theta[i])
            out += sign * 0.5 * np.log1p(u / z2)
            if jacobian:
                J[:, i] = -sign * u / (z2 + u)
            i += 1
    return (out, J) if jacobian else out


def transfer_function(theta, order, inputs=None, outputs=None, name=None):
    """The model H(s) for ``theta`` as a transfer function.

    Parameters
    ----------
    theta : array_like, shape (n_parameters(order),)
        Log parameters (layout in the module docstring).
    order : int
        Order of H.
    inputs, outputs, name : str, optional
        Signal and system names of the result.

    Returns
    -------
    control.TransferFunction
        Stable, minimum phase and biproper; the denominator is monic.

    Examples
    --------
    >>> H = transfer_function(np.log([2.0, 1.0, 10.0]), 1)     # k = 2, w_z = 1, w_p = 10
    >>> H.num[0][0], H.den[0][0]                            # 2 (s/1 + 1) / (s/10 + 1)
    (array([20., 20.]), array([ 1., 10.]))
    """
    theta = _check_theta(theta, order)
    num, den = np.array([np.exp(theta[0])]), np.ones(1)
    i = 1
    for _ in range(order // 2):
        wz, zz, wp, zp = np.exp(theta[i:i + 4])
        num = np.polymul(num, [1 / wz ** 2, 2 * zz / wz, 1.0])
        den = np.polymul(den, [1 / wp ** 2, 2 * zp / wp, 1.0])
        i += 4
    if order % 2:
        wz, wp = np.exp(theta[i:i + 2])
        num = np.polymul(num, [1 / wz, 1.0])
        den = np.polymul(den, [1 / wp, 1.0])
    kwargs = {key: value for key, value in
              (("inputs", inputs), ("outputs", outputs), ("name", name)) if value is not None}
    return ct.tf(num / den[0], den / den[0], **kwargs)


def parameter_bounds(order, log_frequency, log_damping, log_gain=(-np.inf, np.inf)):
    """Lower and upper bounds of ``theta`` from bounds on each kind of parameter.

    Parameters
    ----------
    order : int
        Order of H.
    log_frequency : (float, float)
        Bounds of every log w_z, log w_p [log rad/s].
    log_damping : (float, float)
        Bounds of every log zeta.
    log_gain : (float, float), optional
        Bounds of log k (default unbounded).

    Returns
    -------
    lower, upper : ndarray, shape (n_parameters(order),)

    Examples
    --------
    >>> lower, upper = parameter_bounds(1, (-5.0, 5.0), (-3.0, 3.0))
    >>> lower, upper
    (array([-inf,  -5.,  -5.]), array([inf,  5.,  5.]))
    """
    lw, lz = tuple(log_frequency), tuple(log_damping)
    pairs = [tuple(log_gain)] + [lw, lz, lw, lz] * (order // 2) + [lw, lw] * (order % 2)
    bounds = np.array(pairs, dtype=float)
    return bounds[:, 0], bounds[:, 1]
