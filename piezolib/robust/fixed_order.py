"""Fixed-order mu-synthesis: optimise a given-order SISO controller's parameters.

:func:`fixed_order_musyn` alternates D-steps (optimal scalings of the mu upper
bound from :func:`~piezolib.robust.mu.mussv` at the current controller) with
K-steps that minimise the peak over a frequency grid of
sigma_max(D_l M(K) D_r^-1) with the scalings fixed.  The peak is a nonsmooth
maximum; the K-step solves its epigraph form (minimise t subject to
sigma_k(theta) <= t at every grid frequency) with SLSQP and analytic
gradients, inside a trust region, and a step is accepted only if the closed
loop is stable and the mu upper bound (with freshly optimised scalings) has
decreased.  This is the idea behind MATLAB's ``musyn`` with a tunable
controller; the parametrisation and the safeguards are described in
``docs/robust.md``.

The controller is kept in a modal (partial-fraction) form in ordinary time,

    K(s) = d + sum_i (a_i w_i^2 + b_i w_i s) / (s^2 + 2 z_i w_i s + w_i^2)
             [+ c w_r / (s + w_r) for odd orders],

with log w_i, log z_i (z_i > 1 gives two real poles), dimensionless residues
a_i, b_i, c and the feedthrough d [output/input units]: the controller is
stable by construction and every parameter is of order one whatever the
frequency range.
"""

import logging
import time
from dataclasses import dataclass, field

import control as ct
import numpy as np
from scipy import optimize

from piezolib._checks import (check_finite_array, check_finite_lti, check_frequency_grid,
                              check_integer, check_model, check_positive, check_siso)
from piezolib.progress import finish, postfix, progress
from piezolib.robust.blocks import parse_blk
from piezolib.robust.lti import time_scale_of, to_scaled, with_signals
from piezolib.robust.mu import MuResult, mussv

__all__ = ["ModalController", "FixedOrderResult", "modal_controller", "fixed_order_musyn"]

logger = logging.getLogger(__name__)

_HISTORY_COLUMNS = ("iteration", "mu_upper", "mu_lower", "fixed_d_peak", "omega_peak", "grid_size",
                    "trust_radius", "accepted", "seconds")


@dataclass(frozen=True)
class ModalController:
    """A SISO controller in the modal form of this module.

    Attributes
    ----------
    log_w : ndarray
        log of the natural frequencies w_i [rad/s] of the pole pairs.
    log_z : ndarray
        log of their damping ratios z_i (z_i > 1: two real poles).
    a, b : ndarray
        Dimensionless residues of the pole pairs.
    log_wr : float or None
        log of the real pole w_r [rad/s] (odd orders only).
    c : float or None
        Its residue.
    d : float
        Feedthrough.

    Examples
    --------
    >>> m = modal_controller(ct.tf([1, 3], [1, 2, 4]))
    >>> m.theta.shape, m.log_wr is None                    # (log_w, log_z, a, b, d)
    ((5,), True)
    >>> ModalController.from_theta(m.theta, 2).order
    2
    """

    log_w: np.ndarray
    log_z: np.ndarray
    a: np.ndarray
    b: np.ndarray
    log_wr: float | None
    c: float | None
    d: float

    @property
    def order(self):
        """Number of states."""
        return 2 * self.log_w.size + (self.log_wr is not None)

    @property
    def theta(self):
        """All parameters as one vector (log_w, log_z, a, b[, log_wr, c], d)."""
        extra = [] if self.log_wr is None else [self.log_wr, self.c]
        return np.r_[self.log_w, self.log_z, self.a, self.b, extra, self.d]

    @classmethod
    def from_theta(cls, theta, order):
        """Inverse of :attr:`theta` for a controller of ``order`` states."""
        theta = np.asarray(theta, float)
        n = order // 2
        parts = [theta[k * n:(k + 1) * n] for k in range(4)]
        if order % 2:
            return cls(*parts, float(theta[4 * n]), float(theta[4 * n + 1]),
                       float(theta[4 * n + 2]))
        return cls(*parts, None, None, float(theta[4 * n]))

    def response(self, omega, jacobian=False):
        """K(j omega) and optionally dK/dtheta, shapes (nf,) and (nf, ntheta)."""
        s = 1j * np.asarray(omega, float)[:, None]
        w, z = np.exp(self.log_w), np.exp(self.log_z)
        Q = s ** 2 + 2 * z * w * s + w ** 2
        N = self.a * w ** 2 + self.b * w * s
        K = self.d + np.sum(N / Q, axis=1)
        if self.log_wr is not None:
            wr = np.exp(self.log_wr)
            R = wr / (s[:, 0] + wr)
            K = K + self.c * R
        if not jacobian:
            return K
        dlogw = ((2 * self.a * w ** 2 + self.b * w * s) / Q
                 - N * (2 * z * w * s + 2 * w ** 2) / Q ** 2)
        dlogz = -N * 2 * z * w * s / Q ** 2
        cols = [dlogw, dlogz, w ** 2 / Q, w * s / Q]
        if self.log_wr is not None:
            cols += [(self.c * R * s[:, 0] / (s[:, 0] + wr))[:, None], R[:, None]]
        cols.append(np.ones((s.shape[0], 1)))
        return K, np.concatenate(cols, axis=1)

    def state_space(self, inputs=None, outputs=None, name="K"):
        """Block-diagonal state-space realisation, ordinary time.

        Pair i has states x1 = w^2/Q u and x2 = w s/Q u, so every state is of
        the size of the input at its own frequency.
        """
        n = self.order
        A, B, C = np.zeros((n, n)), np.zeros((n, 1)), np.zeros((1, n))
        for i, (lw, lz, a, b) in enumerate(zip(self.log_w, self.log_z, self.a, self.b)):
            w, z = np.exp(lw), np.exp(lz)
            k = 2 * i
            A[k:k + 2, k:k + 2] = [[0.0, w], [-w, -2 * z * w]]
            B[k + 1, 0] = w
            C[0, k:k + 2] = [a, b]
        if self.log_wr is not None:
            wr = np.exp(self.log_wr)
            A[-1, -1], B[-1, 0], C[0, -1] = -wr, wr, self.c
        K = ct.ss(A, B, C, [[self.d]])
        return with_signals(K, inputs or ["u[0]"], outputs or ["y[0]"], name=name)


def modal_controller(K, omega=None):
    """The modal form (:class:`ModalController`) of a stable SISO controller.

    Poles are paired (complex pairs as they are, real poles in order of
    magnitude); the residues follow by linear least squares on ``omega``.

    Parameters
    ----------
    K : control.LTI
        Stable, proper SISO controller, continuous time, no pole at 0.
    omega : array_like, optional
        Fit frequencies [rad/s]; default 400 points spanning the poles.

    Returns
    -------
    ModalController

    Raises
    ------
    ValueError
        K not SISO, not continuous, unstable or not represented to 1e-6.

    Examples
    --------
    >>> m = modal_controller(ct.tf([1, 3], [1, 2, 4]))          # poles -1 +- j sqrt(3)
    >>> m.order, np.exp(m.log_w).round(6), np.exp(m.log_z).round(6)   # w = 2, zeta = 0.5
    (2, array([2.]), array([0.5]))
    """
    check_finite_lti("K", K)
    K = ct.ss(K)
    if K.ninputs != 1 or K.noutputs != 1:
        raise ValueError(f"K must be SISO, got {K.noutputs} outputs x {K.ninputs} inputs")
    if not K.isctime(strict=False):          # dt = None (a static gain) counts as continuous
        raise ValueError(f"K must be a continuous-time controller, got dt = {K.dt}")
    poles = np.linalg.eigvals(K.A) if K.nstates else np.zeros(0)
    if np.any(poles.real >= 0):
        raise ValueError(f"K must be stable (poles {poles[poles.real >= 0]}); the modal "
                         "form keeps the controller stable")
    cplx = poles[poles.imag > 1e-9 * np.abs(poles)]
    real = np.sort(-poles[np.abs(poles.imag) <= 1e-9 * np.abs(poles)].real)
    log_w = list(np.log(np.abs(cplx)))
    log_z = list(np.log(-cplx.real / np.abs(cplx)))
    if real.size % 2:
        log_wr, real = float(np.log(real[-1])), real[:-1]
    else:
        log_wr = None
    for r1, r2 in zip(real[0::2], real[1::2]):
        w = np.sqrt(r1 * r2)
        log_w.append(np.log(w))
        log_z.append(np.log((r1 + r2) / (2 * w)))
    n = len(log_w)
    if omega is None:
        mags = np.abs(poles) if poles.size else np.ones(1)
        omega = np.logspace(np.log10(mags.min()) - 2, np.log10(mags.max()) + 2, 400)
    omega = check_finite_array("omega", omega, ndim=1, min_length=4)
    target = np.ravel(K(1j * omega))
    if not np.any(target):
        raise ValueError("K is zero at every frequency: the modal form needs a nonzero controller")
    probe = ModalController(np.array(log_w), np.array(log_z), np.zeros(n), np.zeros(n),
                            log_wr, 0.0 if log_wr is not None else None, 0.0)
    _, J = probe.response(omega, jacobian=True)
    basis = J[:, 2 * n:]                     # columns for a, b[, log_wr, c], d
    if log_wr is not None:
        basis = np.delete(basis, 2 * n, axis=1)
    scale = 1.0 / np.maximum(np.abs(target), 1e-300)
    Ab = basis * scale[:, None]
    coef = np.linalg.lstsq(np.r_[Ab.real, Ab.imag], np.r_[(target * scale).real,
                                                           (target * scale).imag], rcond=None)[0]
    a, b = coef[:n], coef[n:2 * n]
    c = float(coef[2 * n]) if log_wr is not None else None
    modal = ModalController(np.array(log_w), np.array(log_z), a, b, log_wr, c, float(coef[-1]))
    err = np.max(np.abs(modal.response(omega) / target - 1))
    if err > 1e-6:
        raise ValueError(f"the modal form of K misses its response by {err:.2g} (relative)")
    return modal


@dataclass(frozen=True)
class FixedOrderResult:
    """Outcome of :func:`fixed_order_musyn`.

    Attributes
    ----------
    K : control.StateSpace
        Best controller (ordinary time), named after the plant's signals.
    modal : ModalController
        Its parameters.
    mu_peak, mu_lower_peak : float
        Peak over the grid of the mu upper and lower bounds for ``K``.
    omega_peak : float
        Frequency of the upper-bound peak [rad/s].
    start_mu_peak : float
        Peak of the mu upper bound for the starting controller.
    mu : MuResult
        mu bounds and scalings on ``omega`` for ``K``.
    closed_loop_poles : ndarray
        Poles of F_l(P, K) [rad/s]; all in the open left half-plane.
    records : tuple of dict
        One dict per D-K step (keys ``iteration``, ``mu_upper`` (best so
        far; with real blocks also bounded between the grid points), ``mu_lower``
        (peak of the lower bound for the best controller so far), ``fixed_d_peak``
        (K-step optimum with the scalings fixed),
        ``omega_peak``, ``grid_size``, ``trust_radius``, ``accepted``,
        ``seconds``); :attr:`history` is the same as a DataFrame.
    stop_reason : str
        Why the last round of D-K steps ended.
    omega : ndarray
        Final (possibly refined) frequency grid [rad/s].
    elapsed : float
        Wall time [s] (information only: no stopping rule uses time).

    Examples
    --------
    >>> s = ct.tf("s")
    >>> G, W1, Wm = 1 / (s + 1), 0.5 * (s + 10) / (s + 0.1), (s + 2) / (s + 20)
    >>> P = ct.ss(ct.combine_tf([[0, 0, Wm], [-W1 * G, W1, -W1 * G], [0, 0, 0.1], [-G, 1, -G]]))
    >>> K0 = ct.tf([2], [0.1, 1])                            # a stabilising first-order start
    >>> r = fixed_order_musyn(P, [(1, 1), (1, 2)], K0, np.logspace(-2, 3, 30), max_iter=2,
    ...                       refinements=0)
    >>> r.modal.order, len(r.records), r.omega.size
    (1, 2, 30)
    >>> bool(r.mu_lower_peak <= r.mu_peak * (1 + 1e-6))
    True
    """

    K: ct.StateSpace
    modal: ModalController
    mu_peak: float
    mu_lower_peak: float
    omega_peak: float
    start_mu_peak: float
    mu: MuResult = field(repr=False)
    closed_loop_poles: np.ndarray = field(repr=False)
    records: tuple = field(repr=False)
    stop_reason: str
    omega: np.ndarray = field(repr=False)
    elapsed: float

    @property
    def history(self):
        """``records`` as a pandas.DataFrame (pandas imported here)."""
        import pandas as pd

        return pd.DataFrame(list(self.records), columns=list(_HISTORY_COLUMNS))


class _Loop:
    """Frequency response of P on the grid and closed-loop checks in scaled time."""

    def __init__(self, P, omega, ws):
        self.Ps = to_scaled(ct.ss(P), ws)
        self.ws = ws
        R = np.moveaxis(self.Ps(1j * omega / ws, squeeze=False), -1, 0)
        self.P11, self.P12 = R[:, :-1, :-1], R[:, :-1, -1]
        self.P21, self.P22 = R[:, -1, :-1], R[:, -1, -1]

    def M(self, k):
        f = k / (1 - self.P22 * k)
        return self.P11 + f[:, None, None] * self.P12[:, :, None] * self.P21[:, None, :]

    def closed_loop_poles(self, modal):
        Ks = to_scaled(modal.state_space(), self.ws)
        A = self.Ps.lft(Ks, nu=1, ny=1).A
        return np.linalg.eigvals(A) * self.ws if A.size else np.zeros(0)


def _scalings(mu_res):
    """(dl, 1/dr, Gh) of a MuResult: diagonals of Dl, Dr^-1 and Gh = Dr^-1 G Dl^-1 (or None)."""
    dl = np.diagonal(mu_res.Dl, axis1=1, axis2=2)
    dr_inv = 1.0 / np.diagonal(mu_res.Dr, axis1=1, axis2=2)
    Gh = None if mu_res.G is None else dr_inv[:, :, None] * mu_res.G.real / dl[:, None, :]
    return dl, dr_inv, Gh


def _scalings_between(omega, scalings, fine, fine_loop, modal):
    """Scalings at the points ``fine`` between the grid points, the best of three.

    Any D > 0 and structured Gh give an upper bound of mu, so each fine point
    takes, of its two neighbours' scalings and their interpolation (log D and
    Gh linear in log omega), the one with the lowest bound for ``modal``.
    """
    lw, lf = np.log(omega), np.log(fine)
    right = np.clip(np.searchsorted(lw, lf), 1, lw.size - 1)
    left = right - 1
    t = np.clip((lf - lw[left]) / (lw[right] - lw[left]), 0.0, 1.0)

    def mix(y, log):
        y = np.log(y) if log else y
        shape = (-1,) + (1,) * (y.ndim - 1)
        out = y[left] + t.reshape(shape) * (y[right] - y[left])
        return np.exp(out) if log else out

    def pick(idx):
        return tuple(None if y is None else y[idx] for y in scalings)

    interp = (mix(scalings[0], True), mix(scalings[1], True),
              None if scalings[2] is None else mix(scalings[2], False))
    options = [pick(left), pick(right), interp]
    zero = np.zeros(modal.theta.size)
    bounds = np.stack([_scaled_bound(fine_loop, modal, fine, sc, np.ones(zero.size))(zero, False)
                       for sc in options])
    best = np.argmin(bounds, axis=0)
    chosen = []
    for part in range(3):
        if options[0][part] is None:
            chosen.append(None)
            continue
        stack = np.stack([o[part] for o in options])
        chosen.append(stack[best, np.arange(fine.size)])
    return tuple(chosen)


def _scaled_bound(loop, modal, omega, scalings, scale):
    """sigma(x, grad): the scaled mu bound at theta0 + scale x on the grid (and its gradient).

    The ``scalings`` (from :func:`_scalings`) are held fixed.  With complex blocks the bound
    is sigma_max(X), X = Dl M Dr^-1.  With real blocks it is the smallest beta
    for which the D,G inequality ``M^H Dl^2 M + j (G M - M^H G^T) <= beta^2 Dr^2``
    holds with these D and G, i.e. sqrt(lambda_max(X^H X + j (Gh X - X^H Gh^T)))
    with Gh = Dr^-1 G Dl^-1 (``docs/robust.md``): an upper bound of mixed mu
    for every controller, equal to ``mu_res.upper`` at the current one.
    """
    dl, dr_inv, Gh = scalings
    A0 = dl[:, :, None] * loop.P11 * dr_inv[:, None, :]
    u = dl * loop.P12
    v = loop.P21 * dr_inv
    theta0, order = modal.theta, modal.order

    def sigma(x, grad):
        m = ModalController.from_theta(theta0 + scale * x, order)
        k, J = m.response(omega, jacobian=True)
        f = k / (1 - loop.P22 * k)
        X = A0 + f[:, None, None] * u[:, :, None] * v[:, None, :]
        if Gh is None:
            U, S, Vh = np.linalg.svd(X)
            bound = S[:, 0]
            if not grad:
                return bound
            dbound = (np.einsum("ki,ki->k", U[:, :, 0].conj(), u)
                      * np.einsum("ki,ki->k", v, Vh[:, 0, :].conj()))
        else:
            GX = Gh @ X
            Q = np.conj(np.swapaxes(X, 1, 2)) @ X + 1j * (GX - np.conj(np.swapaxes(GX, 1, 2)))
            lam, vec = np.linalg.eigh(Q)
            bound = np.sqrt(np.maximum(lam[:, -1], 0.0))
            if not grad:
                return bound
            # d lambda = 2 Re(df (v^T e) ((X e)^H u + j e^H Gh u)), e the top eigenvector
            e = vec[:, :, -1]
            Xe = np.einsum("kij,kj->ki", X, e)
            Ge = np.einsum("kij,ki->kj", Gh, e.conj())
            dbound = (np.einsum("ki,ki->k", v, e)
                      * (np.einsum("ki,ki->k", Xe.conj(), u) + 1j * np.einsum("ki,ki->k", Ge, u))
                      / np.maximum(bound, 1e-300))
        c = dbound / (1 - loop.P22 * k) ** 2
        return bound, np.real(c[:, None] * J) * scale

    return sigma


def _k_step(loop, modal, omega, scalings, radius, scale, maxiter):
    """Minimise the peak of the scaled mu bound over a trust region; return (theta, peak)."""
    theta0 = modal.theta
    sigma = _scaled_bound(loop, modal, omega, scalings, scale)
    s0 = sigma(np.zeros(theta0.size), False)
    active = s0 >= 0.3 * s0.max()
    idx = np.flatnonzero(active)

    def cons(z):
        return z[-1] - sigma(z[:-1], False)[idx]

    def cons_jac(z):
        _, g = sigma(z[:-1], True)
        return np.c_[-g[idx], np.ones(idx.size)]

    z0 = np.r_[np.zeros(theta0.size), s0.max()]
    bounds = [(-radius, radius)] * theta0.size + [(0.0, None)]
    res = optimize.minimize(lambda z: z[-1], z0, jac=lambda z: np.r_[np.zeros(theta0.size), 1.0],
                            method="SLSQP", bounds=bounds,
                            constraints=[{"type": "ineq", "fun": cons, "jac": cons_jac}],
                            options={"maxiter": maxiter, "ftol": 1e-9})
    x = res.x[:-1]
    return theta0 + scale * x, float(sigma(x, False).max())


def _dense(omega, factor):
    """``factor - 1`` log-spaced points inserted between neighbours of ``omega``."""
    logw = np.log(omega)
    t = np.arange(factor) / factor
    return np.exp(np.r_[(logw[:-1, None] + np.diff(logw)[:, None] * t).ravel(), logw[-1]])


def _refine(omega, fine, upper):
    """``omega`` with the fine-grid points around every local peak near the top added."""
    peaks = np.flatnonzero((upper >= 0.97 * upper.max())
                           & (upper >= np.r_[-np.inf, upper[:-1]])
                           & (upper >= np.r_[upper[1:], -np.inf]))
    near = np.unique(np.clip((peaks[:, None] + np.arange(-3, 4)).ravel(), 0, fine.size - 1))
    return np.union1d(omega, fine[near])


def _iterate(P, blk, modal, omega, ws, opts, rows, bar):
    """D-K steps on one grid (advancing ``bar`` per step); return (modal, stop reason)."""
    loop = _Loop(P, omega, ws)
    mu_res = mussv(loop.M(modal.response(omega)), blk, omega)
    # with real blocks mu has narrow peaks that a K-step would push between the
    # grid points: the K-step and the acceptance also bound mu on a grid four
    # times as dense, with the scalings interpolated (a valid upper bound there)
    mixed = mu_res.G is not None
    if mixed:
        fine = _dense(omega, 4)
        fine_loop = _Loop(P, fine, ws)

    def certified(m, res):
        peak = float(res.upper.max())
        if not mixed:
            return peak
        sc = _scalings_between(omega, _scalings(res), fine, fine_loop, m)
        between = _scaled_bound(fine_loop, m, fine, sc, np.ones(m.theta.size))
        return max(peak, float(between(np.zeros(m.theta.size), False).max()))

    best, radius, stall = certified(modal, mu_res), opts["radius"], 0
    lin = _linear_mask(modal)
    for _ in range(opts["max_iter"]):
        t_it = time.perf_counter()
        theta0 = modal.theta
        scale = np.ones(theta0.size)
        size = max(np.sqrt(np.mean(theta0[lin] ** 2)), 1e-12)
        scale[lin] = np.maximum(np.abs(theta0[lin]), 0.1 * size)
        if mixed:
            sc = _scalings_between(omega, _scalings(mu_res), fine, fine_loop, modal)
            theta, fixed_peak = _k_step(fine_loop, modal, fine, sc, radius, scale,
                                        opts["k_step_iterations"])
        else:
            theta, fixed_peak = _k_step(loop, modal, omega, _scalings(mu_res), radius, scale,
                                        opts["k_step_iterations"])
        cand = ModalController.from_theta(theta, modal.order)
        accepted, improvement = False, 0.0
        if np.all(loop.closed_loop_poles(cand).real < 0):
            cand_mu = mussv(loop.M(cand.response(omega)), blk, omega)
            peak = certified(cand, cand_mu)
            if peak < best:
                accepted, improvement = True, (best - peak) / best
                modal, mu_res, best = cand, cand_mu, peak
        k = int(np.argmax(mu_res.upper))
        rows.append({"iteration": len(rows), "mu_upper": best,
                     "mu_lower": float(mu_res.lower.max()), "fixed_d_peak": fixed_peak,
                     "omega_peak": float(omega[k]), "grid_size": omega.size,
                     "trust_radius": radius, "accepted": accepted,
                     "seconds": time.perf_counter() - t_it})
        logger.info("fixed-order %2d: mu %.4f (fixed-D %.4f) at %9.4g rad/s on %d points, "
                    "radius %.3g, %s", len(rows) - 1, best, fixed_peak, omega[k], omega.size,
                    radius, "accepted" if accepted else "rejected")
        postfix(bar, mu=best, grid=omega.size)
        bar.update()
        if not accepted:                 # shrink the trust region and retry
            radius /= 2
            if radius < 1e-3 * opts["radius"]:
                return modal, "trust region collapsed"
            continue
        radius = min(2 * radius, opts["radius"])
        stall = 0 if improvement > opts["rtol"] else stall + 1
        if stall >= opts["patience"]:
            return modal, f"no improvement > {opts['rtol']:g} in {opts['patience']} steps"
    return modal, "max_iter reached"


def fixed_order_musyn(P, blk, K0, omega, *, max_iter=20, rtol=1e-3, patience=2,
                      trust_radius=0.5, k_step_iterations=60, refinements=2, time_scale=None):
    """mu-synthesis of a controller of fixed order by D-K alternation on its parameters.

    After the D-K steps converge on a grid, the mu upper bound is checked on
    a grid four times as dense; if its peak is higher (by more than
    ``rtol``), the dense points around the peaks are added to the grid and
    the D-K steps resume (at most ``refinements`` times).

    The work is bounded by counts only: at most ``max_iter`` D-K steps per
    grid, so ``max_iter * (refinements + 1)`` in all, each K-step at most
    ``k_step_iterations`` SLSQP iterations.  No rule uses wall time, so the
    controller does not depend on the machine's speed or load.  Each step
    writes an INFO line to the logger ``piezolib.robust.fixed_order`` and
    advances a progress bar that ends saying which rule stopped the search
    (:func:`piezolib.progress.progress`; ``PIEZOLIB_PROGRESS=0`` hides it).

    Parameters
    ----------
    P : control.StateSpace
        Generalized plant, ordinary time; its last output is the measurement
        and its last input the control (SISO controller).
    blk : sequence of (int, int) or of Block
        Complex block structure of the performance/uncertainty channels
        (MATLAB ``mussv`` convention, as for :func:`~piezolib.robust.mu.mussv`).
    K0 : control.LTI
        Starting controller: stable, SISO, stabilising P; its order is kept.
    omega : array_like
        Frequency grid [rad/s] of the D- and K-steps (at least 16 points).
    max_iter : int
        Maximum number of D-K steps per grid (accepted or rejected), at least 1.
    rtol, patience : float, int
        Stop when the mu peak has not dropped by more than ``rtol``
        (relative) in ``patience`` consecutive steps.
    trust_radius : float
        Initial bound on each normalised parameter change per step (log
        frequencies and dampings change by at most this; residues by this
        times their size); halved after a rejected step (a destabilising
        one or one that does not lower the mu peak), down to 1e-3 times
        its initial value, and doubled (up to its initial value) after an
        accepted one.
    k_step_iterations : int
        Maximum number of SLSQP iterations per K-step, at least 1.
    refinements : int
        Maximum number of grid refinements (0: keep ``omega``).
    time_scale : float, optional
        Internal time scale [rad/s] of the frequency responses and
        closed-loop checks; default :func:`~piezolib.robust.lti.time_scale_of`
        ``(P, K0)``.

    Returns
    -------
    FixedOrderResult

    Raises
    ------
    ValueError, TypeError
        A non-SISO or unstable K0, a K0 that does not stabilise P, a
        structure with real blocks or not fitting P, a bad grid or option.

    Examples
    --------
    Robust performance of 1/(s+1) (as in :func:`~piezolib.robust.dk.musyn`), order kept at 1:

    >>> s = ct.tf("s")
    >>> G, W1, Wm = 1 / (s + 1), 0.5 * (s + 10) / (s + 0.1), (s + 2) / (s + 20)
    >>> P = ct.ss(ct.combine_tf([[0, 0, Wm], [-W1 * G, W1, -W1 * G], [0, 0, 0.1], [-G, 1, -G]]))
    >>> K0 = ct.tf([2], [0.1, 1])                            # a stabilising first-order start
    >>> r = fixed_order_musyn(P, [(1, 1), (1, 2)], K0, np.logspace(-2, 3, 30), max_iter=3,
    ...                       refinements=0)
    >>> r.K.nstates, bool(r.mu_peak < r.start_mu_peak), bool(np.all(r.closed_loop_poles.real < 0))
    (1, True, True)
    """
    t0 = time.perf_counter()
    check_model("P", P, proper=True)
    check_model("K0", K0, proper=True)
    check_siso("K0", K0)
    omega = check_frequency_grid("omega", omega, min_length=16)
    blocks = parse_blk(blk, P.noutputs - 1, P.ninputs - 1)
    if any(b.is_real and b.size > 1 for b in blocks):
        raise ValueError("fixed_order_musyn supports real 1 x 1 scalars (-1, 0) and complex "
                         "blocks; write a repeated real parameter as independent (-1, 0) "
                         "blocks (conservative)")
    opts = {"max_iter": check_integer("max_iter", max_iter, minimum=1),
            "patience": check_integer("patience", patience, minimum=1),
            "k_step_iterations": check_integer("k_step_iterations", k_step_iterations,
                                               minimum=1),
            "rtol": check_positive("rtol", rtol),
            "radius": check_positive("trust_radius", trust_radius)}
    refinements = check_integer("refinements", refinements, minimum=0)
    ws = time_scale_of(P, K0) if time_scale is None else check_positive("time_scale", time_scale)

    modal = modal_controller(K0, omega)
    loop = _Loop(P, omega, ws)
    poles = loop.closed_loop_poles(modal)
    if np.any(poles.real >= 0):
        raise ValueError("K0 does not stabilise P (closed-loop poles "
                         f"{poles[poles.real >= 0]})")
    start = float(mussv(loop.M(modal.response(omega)), blk, omega, lower=False).upper.max())
    rows = []
    with progress(total=opts["max_iter"] * (refinements + 1), desc=f"fixed-order {modal.order}",
                  unit="step") as bar:
        for refinement in range(refinements + 1):
            modal, reason = _iterate(P, blk, modal, omega, ws, opts, rows, bar)
            if refinement == refinements:
                break
            fine = _dense(omega, 4)
            dense = _Loop(P, fine, ws)
            upper = mussv(dense.M(modal.response(fine)), blk, fine, lower=False).upper
            on_grid = rows[-1]["mu_upper"]
            if upper.max() <= on_grid * (1 + opts["rtol"]):
                break
            omega = _refine(omega, fine, upper)
            logger.info("fixed-order: peak %.4f between grid points (grid %.4f); grid refined "
                        "to %d points", upper.max(), on_grid, omega.size)
        # fewer steps than the bound is the stopping rule working: the bar says why
        finish(bar, reason)
    loop = _Loop(P, omega, ws)
    final = mussv(loop.M(modal.response(omega)), blk, omega)
    k = int(np.argmax(final.upper))
    K = modal.state_space(inputs=[P.output_labels[-1]], outputs=[P.input_labels[-1]],
                          name=f"K_fixed{modal.order}")
    return FixedOrderResult(K=K, modal=modal, mu_peak=float(final.upper[k]),
                            mu_lower_peak=float(final.lower.max()), omega_peak=float(omega[k]),
                            start_mu_peak=start, mu=final,
                            closed_loop_poles=loop.closed_loop_poles(modal),
                            records=tuple(rows), stop_reason=reason, omega=omega,
                            elapsed=time.perf_counter() - t0)


def _linear_mask(modal):
    """True for the parameters that enter K linearly (residues, feedthrough)."""
    n = modal.log_w.size
    mask = np.zeros(modal.theta.size, bool)
    mask[2 * n:4 * n] = True
    if modal.log_wr is not None:
        mask[4 * n + 1] = True
    mask[-1] = True
    return mask
