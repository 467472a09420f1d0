"""Hammerstein models with Prandtl-Ishlinskii hysteresis ahead of MIMO linear dynamics.

For identification from periodic multi-input records (e.g. multisine benchmarks),
the linear part given; the single-input model fitted to raw records in the time
domain, dynamics included, is :class:`piezolib.hysteresis.HammersteinModel`.

Each input channel j passes a Prandtl-Ishlinskii operator
v_j = sum_k w_jk F_{r_k}[u_j] (play operators F_r of thresholds r_k, r_0 = 0
the identity), and the vector v drives a discrete linear model G(q):
y = G(q) v.  With G fixed the output is linear in the weights:
y = sum_jk w_jk G_{:,j}(q) F_{r_k}[u_j], so :func:`fit_play_weights` finds
them by one linear least-squares problem.  The data are periodic
steady-state records (periods of a multisine): every play output is computed
over a warm-up period first, filtered by G exactly in the frequency domain
(on the chosen DFT lines) and compared with the measured output spectrum.

Each record and output is weighted by the inverse of the output's standard
deviation, so the fit minimises the sum of squared NRMSEs of a flat
multisine (Parseval) - the quantity a benchmark metric such as
:func:`piezolib.metrics.simulation_error` averages.

Inputs and thresholds share one unit (e.g. V); ``fs`` [Hz].

Examples
--------
A play operator of threshold 0.5 on a triangle: the output lags by 0.5 on each stroke.

>>> import numpy as np
>>> u = np.r_[np.linspace(0, 2, 5), np.linspace(1.5, -2, 8)][:, None]   # (N, 1 channel)
>>> p = play_operators(u, [0.0, 0.5])                                 # (N, 1, 2 thresholds)
>>> p[4, 0].tolist(), p[-1, 0].tolist()
([2.0, 1.5], [-2.0, -1.5])
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import check_finite_array, check_type
from piezolib.hysteresis.pi import play_outputs
from piezolib.identification.freqfit import simulate_discrete

__all__ = ["play_operators", "MIMOHammerstein", "fit_play_weights"]


def _thresholds(thresholds):
    r = check_finite_array("thresholds", thresholds, ndim=1, min_length=1, real=True)
    if np.any(r < 0) or np.any(np.diff(r) <= 0):
        raise ValueError(f"thresholds must be non-negative and strictly increasing, got {r}")
    return r


def _records(name, u, min_ndim=2):
    u = check_finite_array(name, u, real=True)
    if u.ndim < min_ndim:
        raise ValueError(f"{name} must have shape (N, n_channels, ...), got {u.shape}")
    return u


def play_operators(u, thresholds):
    """Outputs of play operators on every channel and record, from rest.

    Parameters
    ----------
    u : array_like, shape (N, n_u, ...)
        Input samples; axis 0 is time, axis 1 the channels, further axes
        independent records.
    thresholds : array_like, shape (K,)
        Thresholds r_k >= 0, strictly increasing [unit of ``u``].

    Returns
    -------
    ndarray, shape (N, n_u, K, ...)
        F_{r_k}[u_j]: y[t] = min(max(y[t-1], u[t] - r), u[t] + r), started
        at rest (y[-1] = 0, clipped onto [u[0] - r, u[0] + r]).
    """
    u = _records("u", u)
    r = _thresholds(thresholds)
    flat = u.reshape(u.shape[0], -1)                  # (N, n_u x records)
    plays = play_outputs(flat, r, np.zeros(r.size))    # from rest: y[-1] = 0, clipped
    plays = plays.reshape(u.shape + (r.size,))         # (N, n_u, ..., K)
    return np.moveaxis(plays, -1, 2)


@dataclass(frozen=True)
class MIMOHammerstein:
    """Prandtl-Ishlinskii operators per input channel, then a discrete linear model.

    Attributes
    ----------
    linear : control.StateSpace
        Discrete linear dynamics, n_u inputs -> n_y outputs.
    thresholds : ndarray, shape (K,)
        Play thresholds [unit of the input].
    weights : ndarray, shape (n_u, K)
        Weight of each play operator on each channel (column 0: the identity
        if ``thresholds[0] == 0``).
    """

    linear: ct.StateSpace
    thresholds: np.ndarray
    weights: np.ndarray

    def operator_outputs(self, u):
        """v = the hysteresis operators' outputs, shape (N, n_u, ...), from rest."""
        p = play_operators(u, self.thresholds)
        return np.einsum("tjk...,jk->tj...", p, self.weights)

    def simulate(self, u):
        """Model output, shape (N, n_y, ...), for inputs (N, n_u, ...), from rest."""
        u = _records("u", u)
        if u.shape[1] != self.linear.ninputs:
            raise ValueError(f"u must have {self.linear.ninputs} channels on axis 1, got "
                             f"{u.shape[1]}")
        return simulate_discrete(self.linear, self.operator_outputs(u))


def _periodic(name, x, n_channels=None):
    x = check_finite_array(name, x, real=True)
    if x.ndim != 4:
        raise ValueError(f"{name} must have shape (N, channels, R, P), got {x.shape}")
    if n_channels is not None and x.shape[1] != n_channels:
        raise ValueError(f"{name} must have {n_channels} channels on axis 1, got {x.shape[1]}")
    return x


def fit_play_weights(linear, u, y, thresholds, lines):
    """Least-squares play weights of a Hammerstein model with the linear part fixed.

    Parameters
    ----------
    linear : control.StateSpace
        Discrete linear dynamics (n_u inputs, n_y outputs), kept fixed.
    u : array_like, shape (N, n_u, R, P) or a list of such arrays
        Inputs: R realisations of P >= 1 steady-state periods of N samples
        (a list holds data sets of different levels or sizes).
    y : array_like, shape (N, n_y, R, P) or a list
        Measured outputs, matching ``u``.
    thresholds : array_like, shape (K,)
        Play thresholds (strictly increasing, >= 0) [unit of ``u``].
    lines : array_like of int
        DFT lines 1 <= k < N/2 on which the output is fitted (e.g. the
        excited lines of a multisine).

    Returns
    -------
    MIMOHammerstein
        ``linear`` as given and the weights minimising
        sum over records, outputs and lines |Y - G V|^2 / std(y)^2.
    """
    check_type("linear", linear, ct.StateSpace, "a discrete StateSpace")
    if not linear.isdtime(strict=True):
        raise ValueError("linear must be discrete-time (dt > 0)")
    r = _thresholds(thresholds)
    us, ys = (list(u), list(y)) if isinstance(u, (list, tuple)) else ([u], [y])
    if not isinstance(y, type(u)) or len(us) != len(ys) or not us:
        raise ValueError("u and y must be two arrays or two lists of the same length")
    rows, rhs = [], []
    for k, (uk, yk) in enumerate(zip(us, ys)):
        uk = _periodic(f"u[{k}]" if len(us) > 1 else "u", uk, linear.ninputs)
        yk = _periodic(f"y[{k}]" if len(us) > 1 else "y", yk, linear.noutputs)
        if yk.shape[0] != uk.shape[0] or yk.shape[2:] != uk.shape[2:]:
            raise ValueError(f"y must match u in samples, realisations and periods: "
                             f"{yk.shape} against {uk.shape}")
        N = uk.shape[0]
        ln = check_finite_array("lines", lines, ndim=1, min_length=1, real=True)
        if np.any(ln != np.round(ln)) or ln.min() < 1 or ln.max() >= N / 2:
            raise ValueError(f"lines must be integers in [1, {N / 2:g}), got {ln.min()}..."
                             f"{ln.max()}")
        ln = ln.astype(int)
        # steady state: one warm-up period, then the periods themselves
        x = np.concatenate([uk[..., 0]] + [uk[..., p] for p in range(uk.shape[3])], axis=0)
        plays = play_operators(x, r)[N:]
        plays = np.stack(np.split(plays, uk.shape[3], axis=0), axis=-1)  # (N, n_u, K, R, P)
        Pk = np.fft.fft(plays, axis=0)[ln]                                # (F, n_u, K, R, P)
        Yk = np.fft.fft(yk, axis=0)[ln]                                   # (F, n_y, R, P)
        s = np.std(yk, axis=0)                                            # (n_y, R, P)
        if np.any(s <= 0):
            raise ValueError("y is constant on a record")
        Gm = np.asarray(linear(np.exp(2j * np.pi * ln / N))).reshape(
            linear.noutputs, linear.ninputs, ln.size)
        X = np.einsum("ijf,fjkrp->firpjk", Gm, Pk) / s[None, :, :, :, None, None]
        X = X.reshape(-1, linear.ninputs * r.size)
        b = (Yk / s[None]).reshape(-1)
        rows.append(np.vstack([X.real, X.imag]))
        rhs.append(np.r_[b.real, b.imag])
    w = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    return MIMOHammerstein(linear=linear, thresholds=r, weights=w.reshape(linear.ninputs, r.size))
