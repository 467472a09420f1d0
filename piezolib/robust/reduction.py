"""Controller order reduction by (frequency-weighted) balanced truncation.

:func:`reduce_controller` keeps unstable poles, reduces the stable part with
an optional input weight W (Enns), and reports ||K - K_r||_inf and, with
W = G S, the small-gain certificate ||(K - K_r) G S||_inf < 1.  Rationale and
numerics in ``docs/robust.md``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la
import slycot

from piezolib._checks import check_integer, check_lti, check_model, check_positive
from piezolib.robust.lti import (balance, from_scaled, hinf_norm, max_singular_value,
                                 time_scale_of, to_scaled)

__all__ = ["ReducedController", "reduce_controller", "hankel_singular_values"]


@dataclass(frozen=True)
class ReducedController:
    """Result of :func:`reduce_controller`.

    Attributes
    ----------
    K : control.StateSpace
        Reduced controller, ordinary time, same signal names as the input.
    order : int
        Its order.
    hsv : ndarray
        (Weighted) Hankel singular values of the stable part, descending.
    n_unstable : int
        Number of controller poles with Re >= 0 (kept unchanged).
    error : float
        ||K - K_r||_inf (unweighted, grid + refinement).
    relative_error : float
        ``error / ||K||_inf`` (for a controller with a near-integrator,
        ||K||_inf is its large low-frequency gain).
    weighted_error : float or None
        ||(K - K_r) W||_inf when a weight was given; with W = G S a value
        below 1 guarantees closed-loop stability with K_r.
    method : str
        'truncate' or 'residualize' (DC-matching singular perturbation).

    Examples
    --------
    >>> K = ct.ss(ct.tf([10, 10], [1, 1.1]) * ct.tf([1], [0.01, 1]) * ct.tf([1, 100.5], [1, 100]))
    >>> from piezolib.robust.lti import loop_functions
    >>> r = reduce_controller(K, 1, weight=loop_functions(ct.tf([1], [1, 1]), K).GS)
    >>> r.order, r.n_unstable, r.method, r.hsv.shape
    (1, 0, 'truncate', (3,))
    >>> bool(r.weighted_error < 1)              # below 1: K_r also stabilises G = 1/(s+1)
    True
    """

    K: ct.StateSpace
    order: int
    hsv: np.ndarray
    n_unstable: int
    error: float
    relative_error: float
    weighted_error: float | None
    method: str


def _lyapunov_factor(A, B):
    """L with L L' = X, where A X + X A' + B B' = 0 (A stable), by Hammarling's method.

    SLICOT SB03OD computes the Cholesky factor directly, which keeps the
    accuracy that forming X and factorising it afterwards loses when X is
    nearly singular.
    """
    n, m = B.shape
    work = np.zeros((n, max(n, m)), order="F")   # SB03OD returns U in B's storage
    work[:, :m] = B
    U, scale, _ = slycot.sb03od(n, m, np.array(A, order="F", copy=True),
                                np.zeros((n, n), order="F"), work, "C", trans="T")
    return np.triu(U[:n, :n]) / scale


def _empty(p, m, D=None):
    return ct.ss(np.zeros((0, 0)), np.zeros((0, m)), np.zeros((p, 0)),
                 np.zeros((p, m)) if D is None else D)


def _split_stable(sys):
    """Additive split sys = stable + antistable (D kept with the stable part)."""
    T, Z, k = la.schur(sys.A, output="real", sort="lhp")
    n, p, m = sys.nstates, sys.noutputs, sys.ninputs
    B, C = Z.T @ sys.B, sys.C @ Z
    if k == n:
        return ct.ss(T, B, C, sys.D), _empty(p, m)
    if k == 0:
        return _empty(p, m, sys.D), ct.ss(T, B, C, np.zeros((p, m)))
    # block-diagonalise [[T11, T12], [0, T22]]: X solves T11 X - X T22 = -T12
    X = la.solve_sylvester(T[:k, :k], -T[k:, k:], -T[:k, k:])
    stable = ct.ss(T[:k, :k], B[:k] - X @ B[k:], C[:, :k], sys.D)
    unstable = ct.ss(T[k:, k:], B[k:], C[:, k:] + C[:, :k] @ X, np.zeros((p, m)))
    return stable, unstable


def _gramian_factors(sys, weight):
    """Factors Lc, Lo of the (input-weighted) controllability and the observability Gramians."""
    A, B, C = sys.A, sys.B, sys.C
    n = A.shape[0]
    if weight is None:
        Lc = _lyapunov_factor(A, B)
    else:
        W = weight
        Aa = np.block([[A, B @ W.C], [np.zeros((W.nstates, n)), W.A]])
        Ba = np.vstack([B @ W.D, W.B])
        Lc = _lyapunov_factor(Aa, Ba)[:n, :]   # (Lc Lc')_11 is K's block of the Gramian
    Lo = _lyapunov_factor(A.T, C.T)
    return Lc, Lo


def _balanced(sys, weight):
    """Balancing transformation of the stable ``sys`` and its (weighted) HSVs."""
    Lc, Lo = _gramian_factors(sys, weight)
    U, hsv, Vt = np.linalg.svd(Lo.T @ Lc, full_matrices=False)
    keep = hsv > 1e-14 * hsv[0]
    s_inv = hsv[keep] ** -0.5
    T = Lc @ Vt[keep].T * s_inv[None, :]
    Ti = (U[:, keep] * s_inv[None, :]).T @ Lo.T
    bal = ct.ss(Ti @ sys.A @ T, Ti @ sys.B, sys.C @ T, sys.D)
    return bal, hsv


def hankel_singular_values(K, weight=None, omega_s=None):
    """(Weighted) Hankel singular values of the stable part of ``K``, descending.

    Parameters
    ----------
    K : control.LTI
        Controller, ordinary time.
    weight : control.LTI, optional
        Stable input weight W (see :func:`reduce_controller`).
    omega_s : float, optional
        Internal time scale [rad/s]; default :func:`~piezolib.robust.lti.time_scale_of`
        of K (and W).  Hankel singular values do not depend on it.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> K = ct.ss(ct.tf([10, 10], [1, 1.1]) * ct.tf([1], [0.01, 1]) * ct.tf([1, 100.5], [1, 100]))
    >>> hankel_singular_values(K).round(3)      # the third is the near cancellation
    array([5.012, 0.444, 0.   ])
    """
    K = ct.ss(check_model("K", K))
    omega_s = _time_scale(K, weight, omega_s)
    Ks = to_scaled(K, omega_s)
    stable, _ = _split_stable(Ks)
    if stable.nstates == 0:
        return np.zeros(0)
    W = None if weight is None else to_scaled(weight, omega_s)
    return _balanced(stable, W)[1]


def _time_scale(K, weight, omega_s):
    if omega_s is not None:
        return check_positive("omega_s", omega_s)
    return time_scale_of(K) if weight is None else time_scale_of(K, weight)


def reduce_controller(K, order, weight=None, *, method="truncate", omega_s=None):
    """Reduce ``K`` to ``order`` states by (weighted) balanced truncation.

    Parameters
    ----------
    K : control.StateSpace
        Controller, ordinary time.
    order : int
        Target order (>= number of unstable poles of K).
    weight : control.LTI, optional
        Stable input weight W (ninputs(W) arbitrary, noutputs(W) =
        ninputs(K)); e.g. ``loop_functions(G, K).GS`` for a SISO loop.
    method : {'truncate', 'residualize'}
        Truncation (exact at high frequency) or singular perturbation
        (exact at DC).
    omega_s : float, optional
        Internal time scale [rad/s]; default :func:`~piezolib.robust.lti.time_scale_of`
        of K (and W).

    Returns
    -------
    ReducedController

    Examples
    --------
    A third-order controller with a nearly cancelling pole-zero pair at 100 rad/s:

    >>> K = ct.ss(ct.tf([10, 10], [1, 1.1]) * ct.tf([1], [0.01, 1]) * ct.tf([1, 100.5], [1, 100]))
    >>> r = reduce_controller(K, 2)
    >>> r.K.nstates, bool(r.relative_error < 1e-4)
    (2, True)
    >>> r1 = reduce_controller(K, 1, method="residualize")          # exact at DC
    >>> bool(np.isclose(ct.dcgain(r1.K), ct.dcgain(K))), round(r1.relative_error, 3)
    (True, 0.089)
    """
    check_model("K", K)
    K = ct.ss(K)
    order = check_integer("order", order, minimum=0)
    if method not in ("truncate", "residualize"):
        raise ValueError(f"method must be 'truncate' or 'residualize', got {method!r}")
    if weight is not None:
        check_lti("weight", weight)
        if weight.noutputs != K.ninputs:
            raise ValueError(f"weight must have {K.ninputs} output(s) to drive K, "
                             f"got {weight.noutputs}")
        if np.any(ct.poles(weight).real >= 0):
            raise ValueError("weight must be stable")
    if order > K.nstates:
        raise ValueError(f"order ({order}) exceeds the controller order ({K.nstates})")
    omega_s = _time_scale(K, weight, omega_s)
    Ks = to_scaled(K, omega_s)
    stable, unstable = _split_stable(Ks)
    n_unstable = unstable.nstates
    if order < n_unstable:
        raise ValueError(f"order ({order}) is below the number of unstable controller "
                         f"poles ({n_unstable}), which are kept")
    W = None if weight is None else to_scaled(weight, omega_s)
    bal, hsv = _balanced(stable, W)
    k = min(order - n_unstable, bal.nstates)
    A, B, C, D = bal.A, bal.B, bal.C, bal.D
    if method == "truncate" or k == bal.nstates:
        red = ct.ss(A[:k, :k], B[:k], C[:, :k], D)
    else:
        A22 = A[k:, k:]
        X, Y = np.linalg.solve(A22, A[k:, :k]), np.linalg.solve(A22, B[k:])
        red = ct.ss(A[:k, :k] - A[:k, k:] @ X, B[:k] - A[:k, k:] @ Y,
                    C[:, :k] - C[:, k:] @ X, D - C[:, k:] @ Y)
    if n_unstable:
        red = ct.parallel(red, unstable)
    red = balance(red)
    diff = balance(ct.parallel(Ks, -red))
    grid = np.logspace(-8, 6, 3000)      # scaled frequencies
    if n_unstable == 0:
        error = hinf_norm(diff, omega=grid)[0]
        ref = hinf_norm(Ks, omega=grid)[0]
    else:
        # unstable parts: the peak gain on the grid (no H-infinity norm exists)
        error = float(np.max(max_singular_value(diff, grid)))
        ref = float(np.max(max_singular_value(Ks, grid)))
    werr = None
    if W is not None and n_unstable == 0:
        werr = hinf_norm(balance(diff * W), omega=grid)[0]
    Kr = from_scaled(red, omega_s, K.input_labels, K.output_labels, name=f"K{red.nstates}")
    return ReducedController(K=Kr, order=Kr.nstates, hsv=hsv, n_unstable=n_unstable,
                             error=float(error), relative_error=float(error / ref),
                             weighted_error=None if werr is None else float(werr),
                             method=method)
