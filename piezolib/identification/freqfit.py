"""Discrete-time MIMO state-space models fitted to frequency-response data.

:func:`fit_frf` fits a model of given order to an FRF (e.g. a
:class:`~piezolib.identification.frf.BLA`) on its frequency lines in two
steps:

1. a frequency-domain subspace step (the observability range of a block
   Hankel matrix of the data with the input's part projected out, then A and C
   from its shift invariance) gives the poles;
2. unstable poles are reflected into the unit disc, and B, D, then C, D are
   solved by weighted linear least squares, alternately (the model is linear
   in them with the others fixed).  The poles are not refined further (no
   Gauss-Newton step over A yet).

The cost is sum over lines and entries of w |G_model - G|^2.  The weight
``w`` is the caller's: the inverse of the BLA's estimated variance gives the
(approximate) maximum-likelihood fit; a uniform weight scaled per output
follows the simulation error of a flat multisine (Parseval).

:func:`select_order` fits each candidate order on one FRF and scores it on
another, independent estimate (another group of realisations, another data
set): the order with the smallest validation error wins.
:func:`simulate_discrete` runs a discrete model on long records in modal form
(:func:`scipy.signal.lfilter`), much faster than a Python time loop.

Frequencies in Hz; ``fs`` [Hz] is the sampling frequency of the model
(``dt = 1/fs``).

Examples
--------
A 4th-order 2 x 2 system is found from noise-free data:

>>> import control as ct, numpy as np
>>> true = ct.ss(ct.tf([[[0.2, 0.1], [0.1]], [[0.3], [0.1, 0.05]]],
...                    [[[1, -1.6, 0.8], [1, -0.5]], [[1, -1.6, 0.8], [1, -0.5]]], 1e-3))
>>> f = np.linspace(1.0, 490.0, 200)
>>> G = true(np.exp(2j * np.pi * f / 1e3))
>>> model = fit_frf(G, f, fs=1e3, order=true.nstates)
>>> err = np.abs(model(np.exp(2j * np.pi * f / 1e3)) - G).max() / np.abs(G).max()
>>> model.nstates == true.nstates, bool(err < 1e-8), model.isdtime()
(True, True, True)
"""

import warnings
from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg
import scipy.signal

from piezolib._checks import (check_count, check_finite_array, check_integer, check_positive,
                              check_type)

__all__ = ["fit_frf", "frf_error", "select_order", "OrderSelection", "simulate_discrete",
           "FitQualityWarning", "POOR_FIT_ERROR", "MAX_ROWS"]

#: Largest pole radius the fitted model may have.
MAX_POLE_RADIUS = 0.9995
#: Most block rows of the subspace step: its block-Hankel matrix has n_rows (n_y + n_u) rows
#: and F n_u columns, its memory grows as n_rows and its QR's time as n_rows squared.  A 3 x 3
#: FRF on 3839 lines (the mirror benchmark of notebook 10), n_rows = order + 8, one process on
#: a shared 2-core machine: 100 rows 2.7-3.0 CPU-s and +450 MiB, 136 rows 3.5-4.3 CPU-s and
#: +610 MiB, 168 rows (order 160) the largest allowed (``benchmarks/bench_size_limits.py``
#: prints the time and memory at the limit).
MAX_ROWS = 168


def _check_frf(G, frequency_Hz, fs, name="G"):
    G = check_finite_array(name, G)
    if G.ndim == 1:
        G = G[None, None, :]
    if G.ndim != 3:
        raise ValueError(f"{name} must have shape (n_y, n_u, F), got {G.shape}")
    f = check_finite_array("frequency_Hz", frequency_Hz, ndim=1, min_length=2, real=True)
    fs = check_positive("fs", fs)
    if f.size != G.shape[2]:
        raise ValueError(f"frequency_Hz has {f.size} values, {name} has {G.shape[2]} lines")
    if np.any(f <= 0) or np.any(f >= fs / 2) or np.any(np.diff(f) <= 0):
        raise ValueError(f"frequency_Hz must increase strictly within (0, fs/2 = {fs / 2:g}) Hz")
    return G.astype(complex), f, fs


def _check_weight(weight, shape):
    if weight is None:
        return np.ones(shape)
    w = check_finite_array("weight", weight, real=True)
    try:
        w = np.broadcast_to(w, shape)
    except ValueError:
        raise ValueError(f"weight must broadcast to {shape}, got {w.shape}") from None
    if np.any(w < 0) or not np.any(w > 0):
        raise ValueError("weight must be non-negative with a positive entry")
    return w


def _z(f, fs):
    return np.exp(2j * np.pi * f / fs)


def _realify(x):
    return np.concatenate([x.real, x.imag], axis=-1)


def _subspace_AC(G, z, order, n_rows):
    """A, C of ``order`` from the observability range of the data's block Hankel matrix."""
    n_y, n_u, F = G.shape
    powers = z[None, :] ** np.arange(n_rows)[:, None]                  # (q, F)
    # block row i: z^i G_k (n_y x n_u) for every k, side by side -> (q n_y, F n_u)
    Gh = np.einsum("qf,yuf->qyfu", powers, G).reshape(n_rows * n_y, F * n_u)
    Wh = np.einsum("qf,uv,f->qufv", powers, np.eye(n_u), np.ones(F)).reshape(
        n_rows * n_u, F * n_u)
    H = _realify(np.vstack([Wh, Gh]))
    r = scipy.linalg.qr(H.T, mode="r")[0].T                           # lower triangular
    k = n_rows * n_u
    L22 = r[k:, k:k + n_rows * n_y]
    Us, _, _ = np.linalg.svd(L22, full_matrices=False)
    O = Us[:, :order]
    C = O[:n_y]
    A = np.linalg.lstsq(O[:-n_y], O[n_y:], rcond=None)[0]
    return A, C


def _stabilise(A):
    """Reflect poles outside ``MAX_POLE_RADIUS`` into it, keeping A real."""
    lam, V = np.linalg.eig(A)
    r = np.abs(lam)
    if np.all(r <= MAX_POLE_RADIUS):
        return A
    lam = np.where(r > 1, lam / r ** 2, lam)
    lam = np.where(np.abs(lam) > MAX_POLE_RADIUS, lam * MAX_POLE_RADIUS / np.abs(lam), lam)
    return np.real(V @ np.diag(lam) @ np.linalg.inv(V))


def _eig(A):
    """Eigenvalues and eigenvectors of A, with V^-1."""
    lam, V = np.linalg.eig(A)
    return lam, V, np.linalg.inv(V)


def _resolvent_right(A, B, z):
    """(z_k I - A)^-1 B for every line: (F, n, n_u) (complex)."""
    lam, V, Vi = _eig(A)
    return np.einsum("ni,fi,iu->fnu", V, 1.0 / (z[:, None] - lam), Vi @ B, optimize=True)


def _resolvent_left(A, C, z):
    """C (z_k I - A)^-1 for every line: (F, n_y, n) (complex)."""
    lam, V, Vi = _eig(A)
    return np.einsum("yi,fi,in->fyn", C @ V, 1.0 / (z[:, None] - lam), Vi, optimize=True)


def _solve_BD(A, C, G, z, w):
    """Weighted least squares for B, D with A, C fixed (one column of B, D per input)."""
    n_y, n_u, F = G.shape
    n = A.shape[0]
    Phi = _resolvent_left(A, C, z)                                    # (F, n_y, n)
    B, D = np.zeros((n, n_u)), np.zeros((n_y, n_u))
    for j in range(n_u):
        sw = np.sqrt(w[:, j, :]).T[:, :, None]                          # (F, n_y, 1)
        X = np.concatenate([Phi, np.broadcast_to(np.eye(n_y), (F, n_y, n_y))], axis=2) * sw
        rhs = G[:, j, :].T[:, :, None] * sw
        X, rhs = X.reshape(F * n_y, n + n_y), rhs.reshape(F * n_y)
        theta = np.linalg.lstsq(np.vstack([X.real, X.imag]), np.r_[rhs.real, rhs.imag],
                                rcond=None)[0]
        B[:, j], D[:, j] = theta[:n], theta[n:]
    return B, D


def _solve_CD(A, B, G, z, w):
    """Weighted least squares for C, D with A, B fixed: :func:`_solve_BD` of the transposed
    model (G^T = B^T (zI - A^T)^-1 C^T + D^T)."""
    Ct, Dt = _solve_BD(A.T, B.T, np.swapaxes(G, 0, 1), z, np.swapaxes(w, 0, 1))
    return Ct.T, Dt.T


def _response(A, B, C, D, z):
    """G_model (n_y, n_u, F)."""
    return np.transpose(C @ _resolvent_right(A, B, z), (1, 2, 0)) + D[:, :, None]


def fit_frf(G, frequency_Hz, fs, order, weight=None, *, n_rows=None, iterations=2,
            input_labels=None, output_labels=None):
    """Stable discrete-time state-space model of given order fitted to an FRF.

    Parameters
    ----------
    G : array_like of complex, shape (n_y, n_u, F)
        Frequency response on the lines ``frequency_Hz`` (e.g. ``BLA.G``).
    frequency_Hz : array_like, shape (F,)
        Strictly increasing, within (0, fs/2) [Hz].
    fs : float
        Sampling frequency of the model [Hz]; ``dt = 1/fs``.
    order : int
        Number of states (>= 1).
    weight : array_like, optional
        Non-negative weight of each entry and line, broadcast to (n_y, n_u,
        F); e.g. ``1 / BLA.var_total``.  Default uniform.
    n_rows : int, optional
        Block rows of the subspace step (> order, at most :data:`MAX_ROWS`); default
        ``order + 8``.
    iterations : int, optional
        Alternations of the (B, D) and (C, D) least-squares steps.
    input_labels, output_labels : list of str, optional
        Signal names (default ``u[i]``, ``y[i]``).

    Returns
    -------
    control.StateSpace
        Discrete (``dt = 1/fs``), every pole inside the unit circle.

    Examples
    --------
    >>> fs, f = 64.0, np.linspace(1.0, 20.0, 30)
    >>> z = np.exp(2j * np.pi * f / fs)
    >>> G = (0.5 / (z - 0.5)).reshape(1, 1, -1)          # FRF of 0.5 / (z - 0.5)
    >>> model = fit_frf(G, f, fs, order=1)
    >>> model.dt, model.poles().real.round(6)
    (0.015625, array([0.5]))
    """
    G, f, fs = _check_frf(G, frequency_Hz, fs)
    n_y, n_u, F = G.shape
    order = check_integer("order", order, minimum=1)
    if order >= F * min(n_y, n_u):
        raise ValueError(f"order must be below the number of data lines ({F}), got {order}")
    w = _check_weight(weight, G.shape)
    n_rows = order + 8 if n_rows is None else check_integer("n_rows", n_rows, minimum=order + 1)
    check_count("n_rows", n_rows, maximum=MAX_ROWS, minimum=order + 1,
                why="the block-Hankel matrix grows as n_rows squared")
    if n_rows <= order:
        raise ValueError(f"n_rows must exceed order = {order}, got {n_rows}")
    iterations = check_integer("iterations", iterations, minimum=0)
    # scale each output so that the subspace step sees balanced rows
    scale = _output_scales(G)
    Gs = G / scale[:, None, None]
    with np.errstate(under="ignore", over="ignore"):
        ws = w * scale[:, None, None] ** 2
    if not (np.isfinite(ws).all() and ws.max() > 0):     # scales beyond float range squared
        ws = w * (scale / scale.max())[:, None, None] ** 2
    ws = ws / ws.max()
    z = _z(f, fs)
    A, C = _subspace_AC(Gs, z, order, n_rows)
    reflected = int(np.count_nonzero(np.abs(np.linalg.eigvals(A)) > MAX_POLE_RADIUS))
    A = _stabilise(A)
    B, D = _solve_BD(A, C, Gs, z, ws)
    for _ in range(iterations):
        C, D = _solve_CD(A, B, Gs, z, ws)
        B, D = _solve_BD(A, C, Gs, z, ws)
    C, D = C * scale[:, None], D * scale[:, None]
    model = ct.ss(A, B, C, D, 1.0 / fs,
                  inputs=input_labels or [f"u[{i}]" for i in range(n_u)],
                  outputs=output_labels or [f"y[{i}]" for i in range(n_y)])
    if reflected:
        error = frf_error(model, G, f, w)
        if error > POOR_FIT_ERROR:
            warnings.warn(
                f"fit_frf: the subspace step found {reflected} pole(s) outside the unit circle "
                f"and reflected them inside; the stable model misses the FRF by {error:.3g} "
                "(relative): the data may come from an unstable system (fit it in closed loop) "
                "or need another order", FitQualityWarning, stacklevel=2)
    return model


#: Relative error (:func:`frf_error`) above which a fit whose poles had to be reflected is
#: reported (:class:`FitQualityWarning`).
POOR_FIT_ERROR = 0.1


class FitQualityWarning(UserWarning):
    """A fitted model misses its data by far (e.g. a stable model of an unstable system)."""


def _output_scales(G):
    """RMS of each output's FRF over inputs and lines (1 for an all-zero output), computed
    without overflow or underflow for FRFs at the ends of the float range."""
    with np.errstate(over="ignore", under="ignore"):
        scale = np.sqrt(np.mean(np.abs(G) ** 2, axis=(1, 2)))
    peak = np.abs(G).max(axis=(1, 2))
    bad = (~np.isfinite(scale) | (scale == 0)) & (peak > 0)
    if np.any(bad):       # |G|^2 out of range: the same RMS from G / peak
        scale[bad] = peak[bad] * np.sqrt(np.mean(np.abs(G[bad] / peak[bad, None, None]) ** 2,
                                                 axis=(1, 2)))
    return np.where(scale > 0, scale, 1.0)


def frf_error(model, G, frequency_Hz, weight=None):
    """Relative weighted error of a discrete model against an FRF.

    Parameters
    ----------
    model : control.StateSpace or control.TransferFunction
        Discrete-time, ``n_y`` outputs and ``n_u`` inputs.
    G : array_like of complex, shape (n_y, n_u, F)
    frequency_Hz : array_like, shape (F,)
        [Hz], below the model's Nyquist frequency.
    weight : array_like, optional
        As in :func:`fit_frf`.

    Returns
    -------
    float
        sqrt(sum w |G_model - G|^2 / sum w |G|^2).

    Examples
    --------
    >>> fs, f = 64.0, np.linspace(1.0, 20.0, 30)
    >>> z = np.exp(2j * np.pi * f / fs)
    >>> G = (0.5 / (z - 0.5)).reshape(1, 1, -1)          # FRF of 0.5 / (z - 0.5)
    >>> bool(frf_error(fit_frf(G, f, fs, order=1), G, f) < 1e-9)
    True
    >>> round(frf_error(ct.tf([0.5], [1, -0.4], 1 / fs), G, f), 2) > 0.05     # a wrong pole
    True
    """
    check_type("model", model, (ct.StateSpace, ct.TransferFunction), "a discrete LTI model")
    if not model.isdtime(strict=True):
        raise ValueError("model must be discrete-time (dt > 0)")
    f = check_finite_array("frequency_Hz", frequency_Hz, ndim=1, min_length=2, real=True)
    f_top = float(f.max())
    if f_top >= 0.5 / model.dt:      # the FRF's lines lie past the model's own Nyquist frequency
        raise ValueError(f"model is sampled at {1 / model.dt:g} Hz (dt = {model.dt:g} s), but "
                         f"frequency_Hz reaches {f_top:g} Hz, at or above its Nyquist frequency "
                         f"{0.5 / model.dt:g} Hz: give the model at the FRF's sampling rate")
    G, f, fs = _check_frf(G, frequency_Hz, 1.0 / model.dt)
    if (model.noutputs, model.ninputs) != G.shape[:2]:
        raise ValueError(f"model has {model.noutputs} outputs, {model.ninputs} inputs; G has "
                         f"shape {G.shape}")
    w = _check_weight(weight, G.shape)
    Gm = np.asarray(model(_z(f, fs))).reshape(G.shape)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        error = np.sqrt(np.sum(w * np.abs(Gm - G) ** 2) / np.sum(w * np.abs(G) ** 2))
    if not np.isfinite(error):       # |G|^2 beyond float range: the same ratio from G / peak
        peak = np.abs(G).max()
        error = np.sqrt(np.sum(w * np.abs((Gm - G) / peak) ** 2)
                        / np.sum(w * np.abs(G / peak) ** 2))
    return float(error)


@dataclass(frozen=True)
class OrderSelection:
    """Result of :func:`select_order`.

    Attributes
    ----------
    order : int
        The order with the smallest validation error.
    orders : ndarray of int
    fit_error, validation_error : ndarray
        :func:`frf_error` of each order's model on the fitting and the
        validation FRF.
    model : control.StateSpace
        The chosen order's model (fitted on the fitting FRF).

    Examples
    --------
    >>> fs, f = 64.0, np.linspace(1.0, 20.0, 30)
    >>> z = np.exp(2j * np.pi * f / fs)
    >>> G = (0.5 / (z - 0.5)).reshape(1, 1, -1)          # FRF of 0.5 / (z - 0.5)
    >>> noise = 1e-3 * np.random.default_rng(0).standard_normal((2, 30))
    >>> sel = select_order(G + noise[0], G + noise[1], f, fs, orders=[1, 2, 3])
    >>> sel.orders, sel.validation_error.shape, sel.model.nstates == sel.order
    (array([1, 2, 3]), (3,), True)
    """

    order: int
    orders: np.ndarray
    fit_error: np.ndarray
    validation_error: np.ndarray
    model: ct.StateSpace


def select_order(G_fit, G_validation, frequency_Hz, fs, orders, weight=None, **options):
    """The model order that predicts an independent FRF estimate best.

    Parameters
    ----------
    G_fit, G_validation : array_like of complex, shape (n_y, n_u, F)
        Two independent estimates on the same lines (e.g. two groups of
        realisations, ``BLA.G_groups``).
    frequency_Hz : array_like, shape (F,)
        [Hz].
    fs : float
        [Hz].
    orders : sequence of int
        Candidate orders.
    weight : array_like, optional
        As in :func:`fit_frf`, used for fitting and scoring.
    **options
        Passed to :func:`fit_frf`.

    Returns
    -------
    OrderSelection

    Examples
    --------
    >>> fs, f = 64.0, np.linspace(1.0, 20.0, 30)
    >>> z = np.exp(2j * np.pi * f / fs)
    >>> G = (0.5 / (z - 0.5)).reshape(1, 1, -1)          # FRF of 0.5 / (z - 0.5)
    >>> noise = 1e-3 * np.random.default_rng(0).standard_normal((2, 30))
    >>> sel = select_order(G + noise[0], G + noise[1], f, fs, orders=[1, 2, 3])
    >>> bool(sel.validation_error[0] < 1e-2)                  # order 1 already predicts it
    True
    """
    G_fit, f, fs = _check_frf(G_fit, frequency_Hz, fs, "G_fit")
    G_validation, _, _ = _check_frf(G_validation, f, fs, "G_validation")
    if G_validation.shape != G_fit.shape:
        raise ValueError(f"G_validation must have the shape of G_fit {G_fit.shape}, "
                         f"got {G_validation.shape}")
    orders = np.atleast_1d(check_finite_array("orders", orders, real=True))
    if orders.ndim != 1 or orders.size < 1 or np.any(orders != np.round(orders)) \
            or orders.min() < 1:
        raise ValueError("orders must be a non-empty sequence of positive integers")
    orders = orders.astype(int)
    models, e_fit, e_val = [], [], []
    for n in orders:
        model = fit_frf(G_fit, f, fs, int(n), weight, **options)
        models.append(model)
        e_fit.append(frf_error(model, G_fit, f, weight))
        e_val.append(frf_error(model, G_validation, f, weight))
    best = int(np.argmin(e_val))
    return OrderSelection(order=int(orders[best]), orders=orders, fit_error=np.array(e_fit),
                          validation_error=np.array(e_val), model=models[best])


def simulate_discrete(model, u):
    """Response of a discrete model from zero initial state, in modal form.

    Parameters
    ----------
    model : control.StateSpace
        Discrete-time, diagonalisable A (distinct poles).
    u : array_like, shape (N, n_u, ...)
        Input samples; axis 0 is time, axis 1 the model's inputs, further axes
        independent records.

    Returns
    -------
    ndarray, shape (N, n_y, ...)

    Examples
    --------
    >>> model = ct.ss(ct.tf([0.5], [1, -0.5], 1.0))
    >>> simulate_discrete(model, np.ones((4, 1)))[:, 0]        # a step from rest
    array([0.   , 0.5  , 0.75 , 0.875])
    """
    check_type("model", model, ct.StateSpace, "a discrete StateSpace")
    if not model.isdtime(strict=True):
        raise ValueError("model must be discrete-time (dt > 0)")
    u = check_finite_array("u", u, real=True)
    if u.ndim < 2 or u.shape[1] != model.ninputs:
        raise ValueError(f"u must have shape (N, {model.ninputs}, ...), got {u.shape}")
    lam, V = np.linalg.eig(model.A)
    if np.linalg.cond(V) > 1e10:
        raise ValueError("model must have a diagonalisable A (its eigenvectors are "
                         "nearly dependent)")
    # A is real, so its complex modes come in conjugate pairs whose states are conjugate:
    # one mode of each pair is run and counted twice (2 Re), half the filtering work
    keep = lam.imag >= 0
    Bm = np.linalg.solve(V, model.B)[keep]             # (m, n_u)
    Cm = (model.C @ V)[:, keep] * np.where(lam[keep].imag > 0, 2.0, 1.0)   # (n_y, m)
    N, n_u, rest = u.shape[0], u.shape[1], u.shape[2:]
    flat = np.moveaxis(u, 0, 1).reshape(n_u, -1)       # (n_u, N R): one product per matrix
    drive = (Bm @ flat).reshape(-1, N, flat.shape[1] // N)
    states = np.empty_like(drive)
    for i, pole in enumerate(lam[keep]):
        # x[k+1] = pole x[k] + drive[k]  ->  x = z^-1 / (1 - pole z^-1) drive
        states[i] = scipy.signal.lfilter([0.0, 1.0], [1.0, -pole], drive[i], axis=0)
    y = (Cm @ states.reshape(states.shape[0], -1)).real + model.D @ flat
    return np.moveaxis(y.reshape((model.noutputs, N) + rest), 0, 1)
