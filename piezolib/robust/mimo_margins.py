"""Multi-loop and loop-at-a-time disk margins of a square MIMO loop (MATLAB's ``diskmargin``).

The loop: an n x n loop transfer L (continuous or discrete) in negative feedback with I_n,
sensitivity S = (I + L)^-1.  Each channel i is multiplied by an independent complex factor
f_i in the skewed disk (Seiler, Packard and Gahinet 2020)

    D(alpha, sigma) = { (1 + (1 - sigma)/2 delta) / (1 - (1 + sigma)/2 delta) : |delta| < alpha },

so the perturbed loop is L F, F = diag(f_1, ..., f_n).  With Delta = diag(delta_i),

    I + L F = (I + L) [I - M Delta] (I - (1 + sigma)/2 Delta)^-1,   M = S + (sigma - 1)/2 I,

so the loop stays stable for every such F exactly when ||Delta|| < 1 / mu_Delta(M(j w)) at
every frequency: the **multi-loop disk margin** is alpha = 1 / max_w mu_Delta(M), mu over
n independent complex scalars.  mu is bounded by :func:`piezolib.robust.mu.mussv`:
``alpha_lower`` = 1 / max upper bound (guaranteed: every F in that disk keeps the loop
stable), ``alpha_upper`` = 1 / max lower bound (a destabilising F of that size exists;
``worst_factors`` gives one).  For n <= 3 channels the D-scaled bound is mu itself
(Doyle 1982), so the two meet up to the bounds' stopping rule.

The **loop-at-a-time** margin of channel i perturbs that channel alone: its matrix is the
1 x 1 entry M_ii = S_ii + (sigma - 1)/2, and S_ii = 1/(1 + L_i) with L_i the SISO loop seen
at channel i when the other loops stay closed.  A disk margin alpha gives the gain interval
[gmin, gmax] = [(2 - alpha (1 - sigma)) / (2 + alpha (1 + sigma)),
(2 + alpha (1 - sigma)) / (2 - alpha (1 + sigma))] (gmax = inf when alpha (1 + sigma) >= 2)
and the phase margin arccos((4 - alpha^2 (1 + sigma^2)) / (4 + alpha^2 (1 - sigma^2)))
(180 deg when the disk holds all of the unit circle).

Margins of an unstable closed loop mean nothing (the nominal loop is already past the
boundary): every function here raises ``ValueError`` naming the unstable closed-loop poles.
Frequencies are in rad/s; a discrete loop is evaluated at z = exp(j w dt) up to the Nyquist
frequency pi / dt.
"""

import math
from dataclasses import dataclass
from typing import NamedTuple

import control as ct
import numpy as np
import scipy.linalg as la
from scipy.optimize import minimize_scalar

from piezolib._checks import check_finite_lti, check_frequency_grid, check_real
from piezolib.robust.lti import frequency_grid
from piezolib.robust.mu import mussv

__all__ = ["MIMODiskMargin", "MIMOLoopMargins", "disk_margin_mimo",
           "loop_at_a_time_disk_margins", "loop_margins_mimo"]

#: frequencies of the default grid
_N_GRID = 600


@dataclass(frozen=True)
class MIMODiskMargin:
    """Disk margin of a loop: all channels at once (multi-loop) or one channel.

    Attributes
    ----------
    alpha : float
        The disk margin (dimensionless): ``alpha_lower``, the guaranteed one.
    alpha_lower, alpha_upper : float
        1 / (peak mu upper bound) and 1 / (peak mu lower bound): the true margin lies in
        [alpha_lower, alpha_upper] (equal for a single channel).
    gain_margin : tuple of float
        (gmin, gmax) [ratio]: every gain change in it, on all perturbed channels at once,
        keeps the loop stable (gmax = inf when the disk reaches infinity).
    phase_margin_deg : float
        Every phase change within +- this on all perturbed channels keeps the loop stable [deg].
    frequency : float
        Where mu's upper bound peaks [rad/s] (0 or inf for the ends of a continuous loop).
    skew : float
        The disk's skew sigma (0: balanced, the gain interval symmetric in dB).
    channel : int or None
        The channel perturbed alone (loop at a time), None for all channels at once.
    worst_factors : ndarray of complex, shape (n,)
        Per-channel factors f_i of a destabilising perturbation of size ``alpha_upper``
        (at ``worst_frequency``): I + L F is singular there.  All ones when mu = 0.
    worst_frequency : float
        Frequency of ``worst_factors`` [rad/s] (the lower bound's peak).

    Examples
    --------
    Two static, decoupled loops L = diag(1, 3): |S_i - 1/2| = 0 and 1/4, so alpha = 4.

    >>> m = disk_margin_mimo(ct.ss([], [], [], np.diag([1.0, 3.0])))
    >>> round(m.alpha, 6), m.gain_margin, round(m.phase_margin_deg, 1)
    (4.0, (0.0, inf), 126.9)
    """

    alpha: float
    alpha_lower: float
    alpha_upper: float
    gain_margin: tuple
    phase_margin_deg: float
    frequency: float
    skew: float
    channel: int | None
    worst_factors: np.ndarray
    worst_frequency: float

    @property
    def gain_margin_dB(self):
        """(gmin, gmax) in dB (-inf for gmin <= 0, inf for gmax = inf)."""
        return tuple(20 * math.log10(g) if 0 < g < math.inf else (math.inf if g > 1 else -math.inf)
                     for g in self.gain_margin)

    def as_dict(self):
        """The margin as a flat dict (for tables), units in the keys."""
        low, high = self.gain_margin_dB
        return {"disk margin alpha": self.alpha, "alpha upper": self.alpha_upper,
                "gain margin low [dB]": low, "gain margin high [dB]": high,
                "phase margin [deg]": self.phase_margin_deg,
                "frequency [rad/s]": self.frequency}


@dataclass(frozen=True)
class MIMOLoopMargins:
    """Disk margins of the loop (P, K) at the plant input and the plant output.

    Attributes
    ----------
    input, output : MIMODiskMargin
        Multi-loop margins of L = K P (perturbing every plant input at once) and of
        L = P K (every plant output at once).
    input_loops, output_loops : list of MIMODiskMargin
        Loop-at-a-time margins at each plant input and each plant output.
    input_output : MIMODiskMargin or None
        Every plant input and every plant output perturbed at once, independently
        (MATLAB's MMIO): nu + ny factors, ``worst_factors`` inputs first (None when
        not asked for).

    Examples
    --------
    The spinning satellite with the static controller of MATLAB's ``diskmargin`` example:
    each input loop alone has alpha = 2, both together 0.376.

    >>> a = 10.0
    >>> P = ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))
    >>> m = loop_margins_mimo(P, ct.ss([], [], [], [[1.0, -2.0], [0.0, 1.0]]))
    >>> round(m.input.alpha, 3), [round(x.alpha, 3) for x in m.input_loops]
    (0.376, [2.0, 2.0])
    """

    input: MIMODiskMargin
    output: MIMODiskMargin
    input_loops: list
    output_loops: list
    input_output: MIMODiskMargin = None


def _check_skew(skew):
    skew = check_real("skew", skew)
    return skew


def _check_loop(name, L):
    """(A, B, C, D, dt) of the square loop ``L`` as float arrays, dt 0 for continuous."""
    check_finite_lti(name, L)
    if L.ninputs != L.noutputs:
        raise ValueError(f"{name} must be square (a loop transfer, n x n), got "
                         f"{L.noutputs} outputs x {L.ninputs} inputs")
    if isinstance(L, ct.TransferFunction):
        L = ct.tf2ss(L) if L.ninputs > 1 else ct.ss(L)
    L = ct.ss(L)
    dt = L.dt
    if dt is True:
        raise ValueError(f"{name} must have a numeric sample time (dt=True leaves the "
                         "Nyquist frequency unknown)")
    dt = float(dt) if dt else 0.0
    return tuple(np.asarray(x, float) for x in (L.A, L.B, L.C, L.D)) + (dt,)


def _sensitivity(name, A, B, C, D, dt):
    """(A_S, B_S, C_S, D_S) of S = (I + L)^-1, balanced; raises when ill-posed or unstable."""
    n = D.shape[0]
    E = np.eye(n) + D
    if np.linalg.cond(E) > 1e12:
        raise ValueError(f"the loop {name} is not well posed: I + D is singular "
                         f"(I + {name}(inf) has condition number {np.linalg.cond(E):.3g})")
    Ei = np.linalg.inv(E)
    As, Bs, Cs = A - B @ Ei @ C, B @ Ei, -Ei @ C
    if As.size:
        _, (scale, _) = la.matrix_balance(As, permute=False, separate=True)
        As = As * scale[None, :] / scale[:, None]
        Bs, Cs = Bs / scale[:, None], Cs * scale[None, :]
        poles = np.linalg.eigvals(As)
        bad = poles[poles.real >= 0] if dt == 0 else poles[np.abs(poles) >= 1]
        if bad.size:
            raise ValueError(f"the closed loop feedback({name}, I) is unstable (poles "
                             f"{np.round(bad, 6)}): disk margins measure how far a stable "
                             "loop is from instability; this one has none (alpha = 0)")
    return As, Bs, Cs, Ei


def _default_grid(A, As, dt):
    """Log grid over the poles' range, plus the closed-loop poles' own frequencies (where a
    lightly damped sensitivity peak sits, narrower than the grid's spacing), 0 and inf or
    Nyquist."""
    closed = np.linalg.eigvals(As) if As.size else np.zeros(0)
    mags = np.abs(np.r_[np.linalg.eigvals(A) if A.size else [], closed])
    if dt:
        nyquist = math.pi / dt
        mags = np.abs(np.log(mags[mags > 0].astype(complex))) / dt if mags.size else mags
        mags = mags[(mags > 0) & np.isfinite(mags)]
        lo = min(mags.min() / 100, nyquist / 1e3) if mags.size else nyquist / 1e4
        own = np.abs(np.angle(closed)) / dt
        own = own[(own > lo) & (own < nyquist)]
        return np.unique(np.r_[0.0, frequency_grid(lo, nyquist, _N_GRID), own])
    mags = mags[mags > 1e-12 * max(1.0, mags.max(initial=0.0))]
    lo, hi = (mags.min(), mags.max()) if mags.size else (1.0, 1.0)
    own = np.abs(closed.imag)
    own = own[(own > lo / 100) & (own < hi * 100)]
    return np.unique(np.r_[0.0, frequency_grid(lo / 100, hi * 100, _N_GRID), own, math.inf])


def _response(As, Bs, Cs, Ds, dt, omega):
    """S at each frequency of ``omega`` [rad/s], shape (nf, n, n); omega may hold 0 and inf."""
    omega = np.atleast_1d(np.asarray(omega, float))
    out = np.broadcast_to(Ds, (omega.size,) + Ds.shape).astype(complex)
    ns = As.shape[0]
    if ns == 0:
        return out.copy()
    out = out.copy()
    finite = np.isfinite(omega)
    if dt:
        point = np.exp(1j * omega[finite] * dt)
        scale = 1.0
    else:
        scale = max(float(np.max(np.abs(np.linalg.eigvals(As)))), 1e-300)
        point = 1j * omega[finite] / scale
    idx = np.nonzero(finite)[0]
    for start in range(0, idx.size, 256):
        k = idx[start:start + 256]
        p = point[start:start + 256]
        Mat = p[:, None, None] * np.eye(ns) - As / scale
        X = np.linalg.solve(Mat, np.broadcast_to(Bs / scale, (p.size,) + Bs.shape))
        out[k] += Cs @ X
    return out


def _grid_of(name, omega, A, As, dt):
    if omega is None:
        return _default_grid(A, As, dt)
    omega = check_frequency_grid("omega", omega, min_length=2)
    if dt and omega[-1] > math.pi / dt * (1 + 1e-12):
        raise ValueError(f"omega must not exceed the Nyquist frequency pi/dt = "
                         f"{math.pi / dt:.6g} rad/s of the discrete loop {name}, got "
                         f"{omega[-1]:.6g}")
    return omega


def _margins_from_alpha(alpha, skew):
    if alpha == math.inf:
        return (0.0, math.inf), 180.0
    lo_den = 2 + alpha * (1 + skew)
    gmin = (2 - alpha * (1 - skew)) / lo_den if lo_den > 0 else 0.0
    gmin = max(gmin, 0.0)
    hi_den = 2 - alpha * (1 + skew)
    gmax = (2 + alpha * (1 - skew)) / hi_den if hi_den > 0 else math.inf
    c = (4 - alpha ** 2 * (1 + skew ** 2)) / (4 + alpha ** 2 * (1 - skew ** 2))
    pm = 180.0 if c <= -1 else math.degrees(math.acos(min(c, 1.0)))
    return (float(gmin), float(gmax)), float(pm)


def _factors(delta, skew):
    """Per-channel factors f_i of the disk from the diagonal delta_i."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return (1 + (1 - skew) / 2 * delta) / (1 - (1 + skew) / 2 * delta)


class _ScalarMu(NamedTuple):
    """mussv's bounds and Delta for one 1 x 1 complex block (exact: no iterations)."""

    upper: np.ndarray
    lower: np.ndarray
    Delta: np.ndarray


def _disk(parts, omega, skew, channel, S_grid=None):
    """MIMODiskMargin of the loop whose S realisation is ``parts`` (channel: one only;
    ``S_grid``: S on ``omega`` when the caller has it, shared by the channels of a loop)."""
    As, Bs, Cs, Ds, dt = parts
    n = Ds.shape[0]
    shift = (skew - 1) / 2

    def matrices(w, S=None):
        S = _response(As, Bs, Cs, Ds, dt, w) if S is None else S
        if channel is not None:
            return S[:, channel:channel + 1, channel:channel + 1] + shift
        return S + shift * np.eye(n)

    blk = [(1, 1)] * (1 if channel is not None else n)

    def upper(w):
        M = matrices(w)
        if M.shape[1] == 1:
            return np.abs(M[:, 0, 0])
        return mussv(M, blk, lower=False).upper

    def mu(M):
        if M.shape[1] == 1:         # one scalar block: mu = |M| exactly, Delta = 1 / M
            with np.errstate(divide="ignore"):
                return _ScalarMu(np.abs(M[:, 0, 0]), np.abs(M[:, 0, 0]),
                                 np.where(M == 0, 0, 1 / np.where(M == 0, 1, M)))
        return mussv(M, blk)

    Mgrid = matrices(omega, S_grid)
    r = mu(Mgrid)
    ub, lb = r.upper, r.lower
    k = int(np.argmax(ub))
    w_peak, peak = float(omega[k]), float(ub[k])
    # refine the upper bound's peak between the grid neighbours (finite frequencies only;
    # at the peak alpha is flat: 1e-7 of the frequency moves it by far less than 1e-7)
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, omega.size - 1)]
    if np.isfinite(hi) and hi > lo:
        res = minimize_scalar(lambda w: -float(upper(np.array([w]))[0]), bounds=(lo, hi),
                              method="bounded", options={"xatol": 1e-7 * max(hi, 1e-300)})
        if -res.fun > peak:
            peak, w_peak = float(-res.fun), float(res.x)
    # the lower bound at the refined point and on the grid
    r_peak = mu(matrices(np.array([w_peak])))
    lows = np.r_[lb, r_peak.lower]
    deltas = np.concatenate([r.Delta, r_peak.Delta])
    freqs = np.r_[omega, w_peak]
    j = int(np.argmax(lows))
    low = float(lows[j])
    peak = max(peak, float(r_peak.upper[0]))
    alpha_lower = 1.0 / peak if peak > 0 else math.inf
    alpha_upper = 1.0 / low if low > 0 else math.inf
    if low > 0:
        delta = np.diag(deltas[j])
        f = np.ones(n, complex)
        if channel is not None:
            f[channel] = _factors(delta[0], skew)
        else:
            f = _factors(delta, skew)
    else:
        f = np.ones(n, complex)
    gm, pm = _margins_from_alpha(alpha_lower, skew)
    return MIMODiskMargin(alpha=alpha_lower, alpha_lower=alpha_lower, alpha_upper=alpha_upper,
                          gain_margin=gm, phase_margin_deg=pm, frequency=w_peak,
                          skew=float(skew), channel=channel, worst_factors=f,
                          worst_frequency=float(freqs[j]))


def _each_channel(parts, omega, skew, S_grid=None):
    """The loop-at-a-time margins, S on the grid computed once for all channels."""
    S_grid = _response(*parts, omega) if S_grid is None else S_grid
    return [_disk(parts, omega, skew, i, S_grid) for i in range(parts[3].shape[0])]


def _prepare(name, L, omega, skew):
    skew = _check_skew(skew)
    A, B, C, D, dt = _check_loop(name, L)
    As, Bs, Cs, Ds = _sensitivity(name, A, B, C, D, dt)
    omega = _grid_of(name, omega, A, As, dt)
    return (As, Bs, Cs, Ds, dt), omega, skew


def disk_margin_mimo(L, omega=None, skew=0.0):
    """Multi-loop disk margin: every channel of L perturbed at once, independently.

    Parameters
    ----------
    L : control.LTI
        Square n x n loop transfer (negative feedback with I_n), continuous or discrete
        (numeric sample time); the closed loop must be stable.
    omega : array_like, optional
        Frequency grid [rad/s], positive and increasing (a discrete loop's up to pi / dt).
        Default: 600 log-spaced points spanning the open- and closed-loop poles by two
        decades either side, the frequencies of the closed-loop poles (Im p, or arg z / dt),
        plus w = 0 and w = inf (continuous) or w = 0 (discrete, whose grid ends at the
        Nyquist frequency).  The peak of mu is refined between the grid
        neighbours of the grid's largest value.
    skew : float
        Skew sigma of the disk (0: balanced; > 0 biases it toward gain increase).

    Returns
    -------
    MIMODiskMargin
        ``channel`` is None.

    Raises
    ------
    ValueError
        A non-square, ill-posed (I + L(inf) singular) or non-finite loop, an unstable
        closed loop (its margins would be 0: the message names the unstable poles), a
        bad grid or skew.
    TypeError
        L not an LTI model.

    Examples
    --------
    The spinning satellite with K = I (Doyle 1986): each loop alone tolerates any gain,
    both together tolerate about 10 %.

    >>> a = 10.0
    >>> P = ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))
    >>> m = disk_margin_mimo(P)
    >>> round(m.alpha, 5), [round(g, 3) for g in m.gain_margin], round(m.frequency, 4)
    (0.09975, [0.905, 1.105], 0.0499)
    """
    parts, omega, skew = _prepare("L", L, omega, skew)
    return _disk(parts, omega, skew, None)


def loop_at_a_time_disk_margins(L, omega=None, skew=0.0):
    """Disk margin of each channel of L perturbed alone, the other loops closed.

    Channel i's margin is the SISO disk margin of the loop L_i seen at channel i with the
    other loops closed (1 / (1 + L_i) = S_ii, S = (I + L)^-1).

    Parameters
    ----------
    L : control.LTI
        Square n x n loop transfer (negative feedback), continuous or discrete; stable
        closed loop.
    omega : array_like, optional
        Frequency grid [rad/s] as in :func:`disk_margin_mimo`.
    skew : float
        Skew sigma of the disk.

    Returns
    -------
    list of MIMODiskMargin
        One per channel (``channel`` = i, ``alpha_lower`` = ``alpha_upper``).

    Raises
    ------
    ValueError, TypeError
        As :func:`disk_margin_mimo`.

    Examples
    --------
    >>> a = 10.0
    >>> P = ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))
    >>> [(round(m.alpha, 4), round(m.phase_margin_deg, 1)) for m in loop_at_a_time_disk_margins(P)]
    [(2.0, 90.0), (2.0, 90.0)]
    """
    parts, omega, skew = _prepare("L", L, omega, skew)
    return _each_channel(parts, omega, skew)


def _check_pair(P, K):
    check_finite_lti("P", P)
    check_finite_lti("K", K)
    if K.ninputs != P.noutputs or K.noutputs != P.ninputs:
        raise ValueError(f"K must map P's {P.noutputs} outputs to its {P.ninputs} inputs "
                         f"(shape {P.ninputs} x {P.noutputs}), got {K.noutputs} x {K.ninputs}")
    dts = [0.0 if not s.dt else s.dt for s in (P, K)]
    static = [ct.ss(s).nstates == 0 for s in (P, K)]
    if dts[0] != dts[1] and not any(static):
        raise ValueError(f"P and K must share one sample time, got P dt={P.dt}, K dt={K.dt}")


def _series(first, second):
    """ss of ``second`` after ``first`` (second(s) first(s)), sample time of either."""
    a, b = ct.ss(first), ct.ss(second)
    dt = a.dt if (a.dt and a.nstates) else (b.dt if b.nstates else a.dt or b.dt)
    a = ct.ss(a.A, a.B, a.C, a.D, dt)
    b = ct.ss(b.A, b.B, b.C, b.D, dt)
    return b * a


def _input_output_parts(P, K, Li):
    """S-like realisation (A, B, C, D, dt) of N + I, N: [w_i; w_o] -> [u_c; y].

    With a factor f = 1 + delta / (1 - b delta), b = (1 + sigma)/2, on every plant input
    (u_p = u_c + w_i) and output (y_m = y + w_o), w = delta z and z = [u_c; y] + b w, so
    z = (N + b I) w = (S' + (sigma - 1)/2 I) w with S' = N + I:
    N = [[-T_i, -S_i K], [S_o P, -T_o]] (S_i, T_i at the input, S_o, T_o at the output).
    """
    Pn, Kn = ct.ss(P), ct.ss(K)
    dt = Li.dt
    nu, ny = P.ninputs, P.noutputs
    Ap, Bp, Cp, Dp = (np.asarray(x, float) for x in (Pn.A, Pn.B, Pn.C, Pn.D))
    Ak, Bk, Ck, Dk = (np.asarray(x, float) for x in (Kn.A, Kn.B, Kn.C, Kn.D))
    npx, nkx = Ap.shape[0], Ak.shape[0]
    # z = [u_c; y] with u_c = -(C_k x_k + D_k (y + w_o)), y = C_p x_p + D_p (u_c + w_i):
    # E z = C_z x + D_z w, solved in closed form (feedthrough on both sides is an algebraic
    # loop, which ct.interconnect refuses)
    E = np.block([[np.eye(nu), Dk], [-Dp, np.eye(ny)]])
    if np.linalg.cond(E) > 1 / np.finfo(float).eps:
        raise ValueError("K: the loop is not well-posed: I + D_K D_P is singular (the "
                         "feedthroughs of K and P cancel)")
    Cz = np.block([[np.zeros((nu, npx)), -Ck], [Cp, np.zeros((ny, nkx))]])
    Dz = np.block([[np.zeros((nu, nu)), -Dk], [Dp, np.zeros((ny, ny))]])
    C, D = np.linalg.solve(E, Cz), np.linalg.solve(E, Dz)
    Bx = np.block([[Bp, np.zeros((npx, ny))], [np.zeros((nkx, nu)), Bk]])  # [u_p; y_m] -> x
    A = la.block_diag(Ap, Ak) + Bx @ C
    B = Bx @ (D + np.eye(nu + ny))                    # u_p = u_c + w_i, y_m = y + w_o
    if A.size:
        _, (scale, _) = la.matrix_balance(A, permute=False, separate=True)
        A = A * scale[None, :] / scale[:, None]
        B, C = B / scale[:, None], C * scale[None, :]
    return A, B, C, D + np.eye(nu + ny), (float(dt) if dt else 0.0)


def loop_margins_mimo(P, K, omega=None, skew=0.0, input_output=True):
    """Multi-loop and loop-at-a-time disk margins at the plant input and output.

    As MATLAB's ``diskmargin(P, C)`` (its MMI/MMO, DMI/DMO and MMIO): L = K P broken at
    the plant inputs, L = P K at the plant outputs, and both sides perturbed at once.

    Parameters
    ----------
    P : control.LTI
        Plant, ny x nu.
    K : control.LTI
        Controller, nu x ny (negative feedback), same sample time as P (a static
        gain may be continuous).
    omega : array_like, optional
        Frequency grid [rad/s] as in :func:`disk_margin_mimo`.
    skew : float
        Skew sigma of the disk.
    input_output : bool
        Also the margin with every input and output perturbed at once (MMIO, nu + ny
        blocks: the most expensive of the five); False leaves it None.

    Returns
    -------
    MIMOLoopMargins

    Raises
    ------
    ValueError, TypeError
        Shapes that do not chain, different sample times, an unstable closed loop,
        and as :func:`disk_margin_mimo`.

    Examples
    --------
    >>> a = 10.0
    >>> P = ct.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))
    >>> m = loop_margins_mimo(P, ct.ss([], [], [], [[1.0, -2.0], [0.0, 1.0]]))
    >>> round(m.input.alpha, 4), round(m.output.alpha, 4), m.input.frequency
    (0.3762, 0.3762, 0.0)
    """
    _check_pair(P, K)
    Li, Lo = _series(P, K), _series(K, P)
    pi, wi, skew = _prepare("K P", Li, omega, skew)
    po, wo, _ = _prepare("P K", Lo, omega, skew)
    if not isinstance(input_output, bool):
        raise TypeError(f"input_output must be True or False, got {input_output!r}")
    both = None
    if input_output:
        wio = wi if omega is not None else np.union1d(wi, wo)
        both = _disk(_input_output_parts(P, K, Li), wio, skew, None)
    Si, So = _response(*pi, wi), _response(*po, wo)
    return MIMOLoopMargins(input=_disk(pi, wi, skew, None, Si),
                           output=_disk(po, wo, skew, None, So),
                           input_loops=_each_channel(pi, wi, skew, Si),
                           output_loops=_each_channel(po, wo, skew, So),
                           input_output=both)
