"""Classical and disk margins of a SISO loop, and the delay tolerance of its sampled loop.

Continuous loop L(s) = G(s) K(s) with negative feedback (any SISO plant and
controller):

* gain margin: 1 / |L(jw_pc)| at the phase crossovers (Im L = 0, Re L < 0),
  w_pc = 0 and w_pc = inf included (a negative DC gain L(0), a negative
  high-frequency gain L(j inf) = D_G D_K of a biproper loop: gain k brings
  the closed-loop pole 1 + k L = 0 through s = 0 or through infinity);
  the upward margin is the smallest such factor > 1 (inf when none), the
  downward one the largest factor < 1 (0 when none);
* phase margin: 180 deg + arg L(jw_gc) at the gain crossovers |L| = 1,
  smallest over all crossovers;
* delay margin: the smallest extra delay that brings one gain crossover onto
  -1, min_i ((arg L(jw_i) + pi) mod 2 pi) / w_i  [s]; 0 when |L(j inf)| >= 1
  (a delay then turns the high-frequency gain into a circle of radius
  |D_G D_K| around 0 that encircles -1 however small the delay);
* balanced disk margin (skew 0, Seiler, Packard and Gahinet 2020):
  alpha = 1 / ||S - 1/2||_inf = 2 / ||S - T||_inf, the largest alpha for which every simultaneous gain/phase change f in the disk
  |(f - 1)/(f + 1)| < alpha/2 keeps the loop stable; the disk gain margin is
  [(2 - alpha)/(2 + alpha), (2 + alpha)/(2 - alpha)] and the disk phase
  margin 2 atan(alpha / 2).

All four are computed on the frequency response of G and K realised in
scaled time (so a controller with polynomial coefficients up to 1e23 is
evaluated accurately); crossovers are located on a dense grid and refined by
root finding, and the two ends w = 0 and w = inf, which no grid reaches, are
evaluated exactly (L(0) from the models as given, so that an integrator is
an infinite DC gain, not a large one).  They are meaningful only when the
nominal closed loop is stable, which :attr:`LoopMargins.closed_loop_stable`
reports.

Sampled loop: the plant's zero-order-hold equivalent G_d at the controller's
sample time, the discrete controller K_d, and d whole samples of
computation delay z^-d between them; its closed-loop poles are the
eigenvalues of the state-space interconnection and the loop is stable when
their spectral radius is below 1 (:func:`sampled_loop_radius`,
:func:`delay_tolerance`).
"""

import math
from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq, minimize_scalar

from piezolib._checks import check_finite_lti, check_frequency_grid, check_integer, check_siso
from piezolib.robust.lti import balance, frequency_grid, realize, time_scale_of, to_scaled

__all__ = ["LoopMargins", "loop_margins", "sampled_loop_radius", "DelayTolerance",
           "delay_tolerance"]


@dataclass(frozen=True)
class LoopMargins:
    """Margins of the continuous loop L = G K (negative feedback).

    Attributes
    ----------
    gain_margin : float
        Upward gain margin [ratio] (inf: no phase crossover with |L| < 1).
    gain_margin_low : float
        Downward gain margin [ratio] (0: none).
    omega_gain_margin : float
        Phase crossover of ``gain_margin`` [rad/s] (nan when inf; 0 for the
        DC gain, inf for the high-frequency gain of a biproper loop).
    phase_margin_deg : float
        Smallest phase margin over the gain crossovers [deg] (inf: no crossover).
    omega_crossover : float
        Gain crossover of ``phase_margin_deg`` [rad/s].
    delay_margin_s : float
        Smallest extra loop delay that destabilises [s] (inf: no crossover).
    omega_delay_margin : float
        Gain crossover that sets it [rad/s].
    disk_margin : float
        Balanced disk margin alpha (dimensionless).
    disk_gain_margin : float
        Upper end of the disk-based gain interval [ratio] (inf when alpha >= 2).
    disk_phase_margin_deg : float
        Disk-based phase margin [deg].
    omega_disk : float
        Frequency of the disk margin [rad/s].
    modulus_margin : float
        min_w |1 + L(jw)| = 1 / ||S||_inf.
    closed_loop_stable : bool
        All closed-loop poles in the open left half-plane.
    crossovers : ndarray
        All gain crossover frequencies [rad/s].
    omega_gain_margin_low : float
        Phase crossover of ``gain_margin_low`` [rad/s] (nan when 0; 0 or inf
        as for ``omega_gain_margin``).

    Examples
    --------
    >>> m = loop_margins(ct.tf([1], [1, 1, 0]), ct.tf([1], [1]))     # L = 1/(s (s+1))
    >>> round(m.omega_crossover, 3), round(m.delay_margin_s, 3), m.closed_loop_stable
    (0.786, 1.151, True)
    >>> round(m.modulus_margin, 3), round(m.as_dict()["disk margin alpha"], 3)
    (0.681, 0.894)
    """

    gain_margin: float
    gain_margin_low: float
    omega_gain_margin: float
    phase_margin_deg: float
    omega_crossover: float
    delay_margin_s: float
    omega_delay_margin: float
    disk_margin: float
    disk_gain_margin: float
    disk_phase_margin_deg: float
    omega_disk: float
    modulus_margin: float
    closed_loop_stable: bool
    crossovers: np.ndarray
    omega_gain_margin_low: float = math.nan

    @property
    def gain_margin_dB(self):
        """Upward gain margin [dB]."""
        return 20 * math.log10(self.gain_margin) if math.isfinite(self.gain_margin) else math.inf

    def as_dict(self):
        """The margins as a flat dict (for tables), units in the keys."""
        return {"gain margin [dB]": self.gain_margin_dB,
                "phase margin [deg]": self.phase_margin_deg,
                "crossover [rad/s]": self.omega_crossover,
                "delay margin [us]": 1e6 * self.delay_margin_s,
                "disk margin alpha": self.disk_margin,
                "disk gain margin [dB]": (20 * math.log10(self.disk_gain_margin)
                                          if math.isfinite(self.disk_gain_margin) else math.inf),
                "disk phase margin [deg]": self.disk_phase_margin_deg,
                "modulus margin 1/||S||": self.modulus_margin,
                "closed loop stable": self.closed_loop_stable}


def _default_grid(G, K, poles):
    """4000 points spanning ``poles`` and the zeros of G and K by three decades either side."""
    zeros = [z for sys in (G, K) for z in np.atleast_1d(ct.zeros(sys))]
    mags = np.abs(np.r_[poles, zeros])
    mags = mags[(mags > 0) & np.isfinite(mags)]
    lo, hi = (mags.min(), mags.max()) if mags.size else (1.0, 1.0)
    return frequency_grid(lo / 1e3, hi * 1e3, 4000)


def _evaluator(S, omega_s):
    """sys(j w) as a vectorised function of w [rad/s], for the SISO model S realised in
    scaled time (:func:`~piezolib.robust.lti.to_scaled`): :func:`_response_at` at
    p = j w / omega_s."""
    response = _response_at(S)
    return lambda w: response(1j * np.atleast_1d(np.asarray(w, float)) / omega_s)


def _response_at(S):
    """C (p I - A)^-1 B + D of the SISO realisation S as a vectorised function of the
    complex points p (s for a continuous model, z for a discrete one).

    As SLICOT's TB05AD, which python-control calls once per frequency (most of the
    margins' former cost), but for all points together: A reduced once to
    Hessenberg form H = Q' A Q, then (p I - H) x = Q' B by elimination with
    partial pivoting, one row pair at a time.  (A modal form was tried: on a
    controller with a weight pole at 1e-3 beside one at 2e4 its residues lost
    1e-5 at the crossover.)
    """
    A, B, C, D = (np.asarray(x, float) for x in (S.A, S.B, S.C, S.D))
    d, n = complex(D[0, 0]), A.shape[0]
    if n == 0:
        return lambda p: np.full(np.shape(np.atleast_1d(p)), d)
    H, Q = la.hessenberg(A, calc_q=True)
    b, c = (Q.T @ B)[:, 0], (C @ Q)[0]

    def response(p):
        p = np.atleast_1d(np.asarray(p, complex))
        if p.size <= 4:     # the root finders' single points: LAPACK's solve is cheaper
            return np.array([c @ np.linalg.solve(q * np.eye(n) - H, b.astype(complex)) + d
                             for q in p])
        M = p[:, None, None] * np.eye(n) - H
        x = np.broadcast_to(b, (p.size, n)).astype(complex)
        for k in range(n - 1):
            # pivot: the larger of rows k and k + 1 in column k
            swap = (np.abs(M[:, k + 1, k]) > np.abs(M[:, k, k]))[:, None]
            top = np.where(swap, M[:, k + 1, k:], M[:, k, k:])
            bottom = np.where(swap, M[:, k, k:], M[:, k + 1, k:])
            x_top = np.where(swap[:, 0], x[:, k + 1], x[:, k])
            x_bottom = np.where(swap[:, 0], x[:, k], x[:, k + 1])
            factor = bottom[:, 0] / top[:, 0]
            M[:, k, k:], M[:, k + 1, k:] = top, bottom - factor[:, None] * top
            x[:, k], x[:, k + 1] = x_top, x_bottom - factor * x_top
        for k in range(n - 1, -1, -1):
            x[:, k] = (x[:, k] - np.einsum("fj,fj->f", M[:, k, k + 1:], x[:, k + 1:])) \
                / M[:, k, k]
        return x @ c + d
    return response


def _loop(G, K):
    """(L, closed-loop poles [rad/s], open-loop poles [rad/s]) of L = G K: L(w) a
    vectorised function of w [rad/s] from G and K realised in scaled time, the poles
    from the same realisations (balanced, as
    :func:`~piezolib.robust.lti.closed_loop_poles` forms them)."""
    ws = time_scale_of(G, K)
    Gs, Ks = to_scaled(G, ws), to_scaled(K, ws)
    g, k = _evaluator(Gs, ws), _evaluator(Ks, ws)

    def L(w):
        w = np.atleast_1d(np.asarray(w, float))
        return g(w) * k(w)
    Ls = ct.ss(Gs) * ct.ss(Ks)
    open_poles = np.linalg.eigvals(Ls.A) * ws if Ls.nstates else np.zeros(0)
    cl = balance(ct.feedback(balance(Ls), 1))
    closed = np.linalg.eigvals(cl.A) * ws if cl.nstates else np.zeros(0)
    return L, closed, open_poles


def _end_gains(sys):
    """(sys(0), sys(inf)) of a proper continuous SISO model, from the model as given.

    An exact pole at s = 0 (a zero constant coefficient of the denominator,
    a singular A) gives an infinite DC gain; a balanced realisation would
    turn it into a pole at 1e-9 and a large finite gain.
    """
    if isinstance(sys, ct.TransferFunction):
        num, den = (np.trim_zeros(np.atleast_1d(np.asarray(c, float)), "f")
                    for c in (sys.num[0][0], sys.den[0][0]))
        at_inf = (num[0] / den[0] if num.size == den.size
                  else 0.0 if num.size < den.size else math.copysign(math.inf, num[0] / den[0]))
        # lowest-order coefficients; equal powers of s cancel
        num_b, den_b = np.trim_zeros(num, "b"), np.trim_zeros(den, "b")
        lag = (num.size - num_b.size) - (den.size - den_b.size)
        if num_b.size == 0:
            return 0.0, at_inf
        at_0 = num_b[-1] / den_b[-1] if lag == 0 else (0.0 if lag > 0 else math.inf)
        return float(at_0), float(at_inf)
    S = ct.ss(sys)
    at_inf = float(S.D[0, 0])
    if not S.nstates:
        return at_inf, at_inf
    try:
        x = np.linalg.solve(S.A, S.B)
    except np.linalg.LinAlgError:
        return math.inf, at_inf
    return float((S.D - S.C @ x)[0, 0]), at_inf


def _loop_ends(G, K):
    """(L(0), L(j inf)) of L = G K; nan where 0 * inf leaves it undetermined."""
    (g0, ginf), (k0, kinf) = _end_gains(G), _end_gains(K)
    with np.errstate(invalid="ignore"):
        return float(np.float64(g0) * k0), float(ginf * kinf)


def _crossings(f, omega, values):
    """Roots of f between grid points where ``values`` changes sign, refined."""
    out = []
    idx = np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]
    for i in idx:
        out.append(brentq(f, omega[i], omega[i + 1], xtol=1e-12 * omega[i], rtol=1e-13))
    return np.array(out)


def loop_margins(G, K, omega=None):
    """Gain, phase, delay and disk margins of the loop L = G K.

    Parameters
    ----------
    G : control.LTI
        Continuous-time SISO plant.
    K : control.LTI
        Continuous-time SISO controller (negative feedback).
    omega : array_like, optional
        Search grid [rad/s]; default 4000 log-spaced points spanning the
        poles and zeros of G and K by three decades either side.  Crossovers
        are refined between grid points; the disk margin is the maximum on
        the grid refined by a local search.

    Returns
    -------
    LoopMargins

    Raises
    ------
    ValueError, TypeError
        Non-SISO or discrete-time models, bad grid.

    Notes
    -----
    How the results map to ``gm, pm, sm, wpc, wgc, wms = ct.stability_margins(G * K)``:

    * ``gm, wpc``: python-control reports one gain margin, the phase crossover
      whose 1/|L| is closest to 1 in dB, above or below 1; here the two sides
      are kept apart: ``gain_margin`` (upward, the smallest factor > 1, inf when
      none) and ``gain_margin_low`` (downward, the largest factor < 1, 0 when
      none), so ``gm`` is whichever of the two has the smaller |log|.
    * w -> inf: python-control finds phase crossovers as finite roots of a
      polynomial, so the crossover at infinity of a biproper loop with
      L(j inf) = D_G D_K < 0 never enters ``gm``; here it does, as
      ``omega_gain_margin`` (or ``omega_gain_margin_low``) = inf.  The ends
      w = 0 and w = inf also enter ``modulus_margin`` and the disk margin.
    * ``pm, wgc``: ``phase_margin_deg`` and ``omega_crossover`` (the crossover
      with the smallest |phase margin|, in (-180, 180] deg).
    * ``sm``: ``modulus_margin``, min |1 + L| over the grid refined by a
      bounded scalar search between the grid minimum's neighbours, and over the
      ends; ``wms`` is not returned.

    Examples
    --------
    >>> import control as ct
    >>> m = loop_margins(ct.tf([1], [1, 1, 0]), ct.tf([1], [1]))
    >>> round(m.phase_margin_deg, 1), m.gain_margin
    (51.8, inf)
    """
    for name, sys in (("G", G), ("K", K)):
        check_siso(name, sys)
        check_finite_lti(name, sys)
        if sys.isdtime(strict=True):
            raise ValueError(f"{name} must be a continuous-time model")
    L, closed_poles, open_poles = _loop(G, K)
    omega = _default_grid(G, K, open_poles) if omega is None else check_frequency_grid(
        "omega", omega, min_length=8)
    Lw = L(omega)

    # gain crossovers |L| = 1
    def lg(w):
        return float(np.log(np.abs(L(w))[0]))
    wc = _crossings(lg, omega, np.log(np.abs(Lw)))
    # phase crossovers: Im L = 0 with Re L < 0, on the grid and at its two ends w = 0, inf
    def im(w):
        return float(L(w).imag[0])
    wp = _crossings(im, omega, Lw.imag)
    wp = wp[np.array([L(w).real[0] < 0 for w in wp], bool)] if wp.size else wp
    inv = np.array([1.0 / abs(L(w)[0]) for w in wp])
    L0, Linf = _loop_ends(G, K)
    for w, value in ((0.0, L0), (math.inf, Linf)):
        if math.isfinite(value) and value < 0:
            wp, inv = np.r_[wp, w], np.r_[inv, -1.0 / value]
    up, low = inv > 1, inv < 1
    gm = float(inv[up].min()) if np.any(up) else math.inf
    w_gm = float(wp[up][np.argmin(inv[up])]) if np.any(up) else math.nan
    gm_low = float(inv[low].max()) if np.any(low) else 0.0
    w_gm_low = float(wp[low][np.argmax(inv[low])]) if np.any(low) else math.nan

    if wc.size:
        ang = np.array([np.angle(L(w)[0]) for w in wc])
        pm = np.degrees((ang + np.pi + np.pi) % (2 * np.pi) - np.pi)   # in (-180, 180]
        i = int(np.argmin(np.abs(pm)))
        pm_min, w_pm = float(pm[i]), float(wc[i])
        delays = ((ang + np.pi) % (2 * np.pi)) / wc
        j = int(np.argmin(delays))
        dm, w_dm = float(delays[j]), float(wc[j])
    else:
        pm_min = w_pm = dm = w_dm = math.inf
        w_pm = w_dm = math.nan
    if abs(Linf) >= 1:
        # |L(j inf)| >= 1: the delayed loop circles -1 at high frequency for any delay
        dm, w_dm = 0.0, math.inf

    # disk margin (skew 0): alpha = 1 / max |S - 1/2|; modulus margin min |1 + L|
    def s_half(w):
        return -abs(1.0 / (1.0 + L(w)[0]) - 0.5)
    dist = np.abs(1.0 / (1.0 + Lw) - 0.5)
    k = int(np.argmax(dist))
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, len(omega) - 1)]
    r = minimize_scalar(s_half, bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-10 * omega[k]})
    peak, w_disk = (-r.fun, r.x) if -r.fun >= dist[k] else (dist[k], omega[k])
    # the ends: S(0) (0 with an integrator), S(j inf) = 1 / (1 + D_G D_K)
    ends = [(w, 1.0 + value) for w, value in ((0.0, L0), (math.inf, Linf))
            if not math.isnan(value)]
    for w, one_plus_L in ends:
        s_end = 0.0 if math.isinf(one_plus_L) else (
            math.inf if one_plus_L == 0 else 1.0 / one_plus_L)
        if abs(s_end - 0.5) > peak:
            peak, w_disk = abs(s_end - 0.5), w
    alpha = 1.0 / peak
    dgm = (2 + alpha) / (2 - alpha) if alpha < 2 else math.inf
    dpm = math.degrees(2 * math.atan(alpha / 2))
    mod = float(min([_modulus_minimum(L, omega, np.abs(1.0 + Lw))]
                    + [abs(v) for _, v in ends]))
    stable = bool(np.all(closed_poles.real < 0))
    return LoopMargins(gain_margin=gm, gain_margin_low=gm_low, omega_gain_margin=w_gm,
                       phase_margin_deg=pm_min, omega_crossover=w_pm, delay_margin_s=dm,
                       omega_delay_margin=w_dm, disk_margin=float(alpha),
                       disk_gain_margin=float(dgm), disk_phase_margin_deg=dpm,
                       omega_disk=float(w_disk), modulus_margin=mod,
                       closed_loop_stable=stable, crossovers=wc, omega_gain_margin_low=w_gm_low)


def _modulus_minimum(L, omega, distance):
    """min |1 + L(jw)|: the grid minimum ``distance`` refined by a bounded scalar search
    between its two neighbours (the grid alone overstated 0.559085 as 0.559341)."""
    k = int(np.argmin(distance))
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, len(omega) - 1)]
    r = minimize_scalar(lambda w: abs(1.0 + L(w)[0]), bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-10 * omega[k]})
    return float(min(r.fun, distance[k]))


def _discrete_parts(G, Kd):
    for name, sys in (("G", G), ("Kd", Kd)):
        check_siso(name, sys)
        check_finite_lti(name, sys)
    if G.isdtime(strict=True):
        raise ValueError("G must be a continuous-time plant (it is sampled with a zero-order hold)")
    if Kd.isctime() or Kd.dt is True or not Kd.dt:
        raise ValueError("Kd must be a discrete-time controller with a numeric sample time")
    Gd = ct.c2d(realize(G), float(Kd.dt), method="zoh")
    return ct.ss(Gd), ct.ss(Kd)


def _series(first, second):
    """(A, B, C, D) of ``second`` after ``first`` (SISO matrices)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    return A, np.vstack([B1, B2 @ D1]), np.hstack([D2 @ C1, C2]), D2 @ D1


def _radius(Gd, Kd, d):
    """Spectral radius of the loop Kd -> z^-d -> Gd (negative feedback), by state space."""
    # delay line on the controller output: x[k+1] = shift(x) + e_1 u_b[k], u_c = x_d
    delay = (np.eye(d, k=-1), np.eye(d, 1), np.eye(1, d, d - 1),
             np.zeros((1, 1))) if d else (np.zeros((0, 0)), np.zeros((0, 1)),
                                          np.zeros((1, 0)), np.ones((1, 1)))
    parts = [tuple(np.asarray(x, float) for x in (S.A, S.B, S.C, S.D)) for S in (Kd, Gd)]
    A, B, C, D = _series(_series(parts[0], delay), parts[1])
    den = 1.0 + float(D[0, 0])
    if abs(den) < 1e-12:
        raise ValueError("the sampled loop is not well posed (1 + D_G D_K = 0)")
    Acl = A - B @ C / den
    return float(np.max(np.abs(np.linalg.eigvals(Acl)))) if Acl.size else 0.0


def sampled_loop_radius(G, Kd, delay_samples=0):
    """Spectral radius of the sampled loop: ZOH plant, ``delay_samples``, discrete controller.

    Parameters
    ----------
    G : control.LTI
        Continuous-time SISO plant, sampled with a zero-order hold at Kd's
        sample time.
    Kd : control.LTI
        Discrete-time SISO controller (negative feedback).
    delay_samples : int
        Whole samples of computation delay between K's output and the DAC (>= 0).

    Returns
    -------
    float
        Largest |closed-loop pole|; the loop is stable when it is below 1.

    Examples
    --------
    >>> G, Kd = ct.tf([100], [1, 1]), ct.tf([5], [1], 0.001)        # 1 kHz, gain 500
    >>> round(sampled_loop_radius(G, Kd), 3), round(sampled_loop_radius(G, Kd, 3), 3)
    (0.499, 1.024)
    """
    Gd, Kd = _discrete_parts(G, Kd)
    d = check_integer("delay_samples", delay_samples, minimum=0)
    return _radius(Gd, Kd, d)


@dataclass(frozen=True)
class DelayTolerance:
    """Stability of the sampled loop against whole samples of computation delay.

    Attributes
    ----------
    delays : ndarray of int
        Delays tried [samples].
    spectral_radius : ndarray
        Largest |closed-loop pole| for each delay.
    stable : ndarray of bool
        ``spectral_radius < 1``.
    fs : float
        Sampling rate [Hz].
    delay_margin_samples : float
        Delay margin of the undelayed sampled loop in samples: the smallest
        ((arg L_d + pi) mod 2 pi) / theta over the gain crossovers
        |L_d(e^{j theta})| = 1, theta in (0, pi) (inf: no crossover; nan
        when the undelayed sampled loop is unstable, where it means nothing);
        a whole-sample delay d destabilises the loop when d exceeds it.

    Examples
    --------
    >>> t = delay_tolerance(ct.tf([100], [1, 1]), ct.tf([5], [1], 0.001), delays=range(5))
    >>> t.stable, t.max_stable_delay, t.fs
    (array([ True,  True,  True, False, False]), 2, 1000.0)
    """

    delays: np.ndarray
    spectral_radius: np.ndarray
    stable: np.ndarray
    fs: float
    delay_margin_samples: float

    @property
    def max_stable_delay(self):
        """Largest d such that every delay 0 ... d tried is stable (-1 if d = 0 is not)."""
        bad = np.nonzero(~self.stable)[0]
        return int(self.delays[bad[0]] - 1) if bad.size else int(self.delays[-1])


def delay_tolerance(G, Kd, delays=(0, 1, 2, 3)):
    """:func:`sampled_loop_radius` for each delay in ``delays``.

    Parameters
    ----------
    G : control.LTI
        Continuous-time SISO plant.
    Kd : control.LTI
        Discrete-time SISO controller.
    delays : sequence of int
        Consecutive delays from 0 [samples], increasing.

    Returns
    -------
    DelayTolerance

    Examples
    --------
    >>> t = delay_tolerance(ct.tf([100], [1, 1]), ct.tf([5], [1], 0.001))   # delays 0 ... 3
    >>> t.spectral_radius.round(3), round(t.delay_margin_samples, 2)
    (array([0.499, 0.707, 0.94 , 1.024]), 2.61)
    """
    Gd, Kd_ = _discrete_parts(G, Kd)
    d = np.array([check_integer("delays", x, minimum=0) for x in delays], int)
    if d.size == 0 or np.any(np.diff(d) != 1) or d[0] != 0:
        raise ValueError(f"delays must be 0, 1, 2, ... consecutive, got {list(delays)}")
    r = np.array([_radius(Gd, Kd_, int(x)) for x in d])
    margin = _discrete_delay_margin(Gd, Kd_) if r[0] < 1 else math.nan
    return DelayTolerance(delays=d, spectral_radius=r, stable=r < 1, fs=1.0 / float(Kd.dt),
                          delay_margin_samples=margin)


def _discrete_delay_margin(Gd, Kd, n=20000):
    """Delay margin [samples] of the sampled loop from its frequency response."""
    theta = np.linspace(np.pi / n, np.pi * (1 - 1e-9), n)
    g, k = _response_at(Gd), _response_at(Kd)

    def L(t):
        z = np.exp(1j * np.atleast_1d(t))
        return g(z) * k(z)

    wc = _crossings(lambda t: float(np.log(np.abs(L(t))[0])), theta, np.log(np.abs(L(theta))))
    if wc.size == 0:
        return math.inf
    ang = np.angle(L(wc))
    return float(np.min(((ang + np.pi) % (2 * np.pi)) / wc))
