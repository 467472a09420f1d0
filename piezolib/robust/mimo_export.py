"""Float32 export of a discrete MIMO controller as a state-space realisation, with a C header.

A MIMO controller K_d (p outputs u, m inputs e, n states, sample time 1/fs) runs on the
target as

    u[k]   = C x[k] + D e[k]
    x[k+1] = A x[k] + B e[k]

in float32.  Which realisation is exported matters, because rounding its entries to float32
moves the controller:

* a **block-diagonal real modal form** (default when it is well conditioned): A holds the
  poles themselves, 1 x 1 blocks for real poles and 2 x 2 blocks [[s, w], [-w, s]] for
  s +- j w, so rounding A moves each pole by about one float32 ulp of s and w (the least
  any realisation can do: a pole near z = 1 has a decay 1 - |p| of which that ulp is the
  relative error, as in second-order sections); each block's states are scaled so that its
  rows of B and columns of C have equal norms.  The modal basis T is refused (``form='auto'``
  falls back to Schur) when cond(T) > 1e6: nearly repeated poles make it ill conditioned
  and its B and C large;
* a **real Schur form** (the fallback): an orthogonal similarity (cond 1) to a quasi-upper-
  triangular A whose eigenvalues sit in its diagonal 1 x 1 and 2 x 2 blocks only, so rounding
  the entries above them moves no pole at all; a diagonal balancing of the states follows;
* the realisation as given (``form='given'``, for comparison): a companion form, as
  ``tf2ss`` gives, turns float32 rounding of its last row into pole errors multiplied by
  the polynomial's conditioning, orders of magnitude larger.

The float32 checks (:class:`MIMOExport`), as for the SISO sections
(:mod:`piezolib.robust.float32_check`):

* **poles**: the spectral radius of the float32 A (its entries evaluated in float64); a
  stable controller whose float32 A is marginal or unstable is refused (``ExportError``);
* **response**: sigma_max(H32 - H) / sigma_max(H) over 600 frequencies up to Nyquist and at
  every pole frequency, H the controller given, against the first-order bound of the
  rounding, (||C R|| ||E_A||_F ||R B|| + ||E_C||_F ||R B|| + ||C R|| ||E_B||_F + ||E_D||_F) /
  sigma_max(H) with R = (zI - A)^-1 and E_X the half-ulp of each entry; an error above it
  (or above ``rtol``) warns (``ExportWarning``);
* **time domain**: a random input (float32 values) through the float32 arithmetic, compared
  with float64 arithmetic on the same float32 matrices, against the a-posteriori rounding
  bound of the recursion (each dot product of m terms errs by at most gamma_m |M| |v|,
  gamma_m = m u / (1 - m u), u = 2^-24, and a state error propagates through C A^j:
  sum_j ||C A^j||_inf max_k ||d_k||_inf + max_k ||d'_k||_inf); and the total error against
  the float64 controller, bounded by that plus ||Delta h||_l1 max |e| (Delta h the impulse
  response of H32 - H).

:func:`c_header` writes the float32 matrices as ``static const float`` arrays and a
``<name>_step`` function computing u[k] from e[k] and x[k] (x updated in place), summing
in the order of the formulas above.
"""

import math
import re
import warnings
from dataclasses import dataclass, field

import control as ct
import numpy as np
import scipy.linalg as la

from piezolib._checks import check_count, check_finite_lti, check_integer, check_positive
from piezolib.robust.float32_check import ExportError, ExportWarning, ResponseError

__all__ = ["MIMOExport", "export_mimo", "c_header"]

#: largest condition number of the modal basis before ``form='auto'`` uses the Schur form
MODAL_CONDITION_LIMIT = 1e6
_U32 = 2.0 ** -24                   # unit roundoff of float32
_FORMS = ("auto", "modal", "schur", "given")


@dataclass(frozen=True, eq=False)
class MIMOExport(ResponseError):
    """A discrete MIMO controller in a well-conditioned realisation, its float32 matrices
    and what rounding to float32 does to it.

    Attributes
    ----------
    name : str
        C identifier of the controller.
    fs : float
        Sampling rate [Hz].
    form : str
        Realisation exported: 'modal', 'schur' or 'given'.
    A, B, C, D : ndarray
        The realisation in float64 (n x n, n x m, p x n, p x m).
    A32, B32, C32, D32 : ndarray of float32
        The same rounded to float32: what the target runs.
    basis_condition : float
        Condition number of the state transformation from the given realisation (1 for
        'given' and Schur up to the diagonal balancing).
    realisation_error : float
        max sigma_max(H_form - H) / sigma_max(H) on the check grid, float64 (how faithful
        the transformation itself is).
    radius64, radius32 : float
        Spectral radius of A and of the float32 A (in float64 arithmetic).
    omega : ndarray
        Check frequencies [rad/s], up to Nyquist.
    error : ndarray
        sigma_max(H32 - H) / sigma_max(H) there (nan where H is infinite or below 1e-8
        of its peak, at a transmission zero such as Tustin's at Nyquist).
    bound : ndarray
        The first-order rounding bound there.
    time_error : float
        max |u32 - u64| / max |u64| of the float32-arithmetic run against float64
        arithmetic on the same float32 matrices (the arithmetic's rounding).
    time_bound : float
        The a-posteriori bound of that error (same normalisation).
    time_error_total : float
        max |u32 - u| / max |u| against the float64 controller given.
    time_bound_total : float
        ``time_bound`` plus ||Delta h||_l1 max |e| / max |u| (coefficient rounding).
    time_input : ndarray
        The input of the time-domain run (n_time x m, float32 values).

    Examples
    --------
    >>> Kd = ct.c2d(ct.ss(ct.tf([[[1.0], [2.0]], [[0.5], [1.0, 1.0]]],
    ...                         [[[1.0, 10.0], [1.0, 20.0]], [[1.0, 30.0], [1.0, 40.0]]])),
    ...             1e-3, "tustin")
    >>> x = export_mimo(Kd, name="K2")
    >>> x.form, x.A32.dtype.name, bool(x.radius32 < 1), bool(x.max_error <= x.bound.max())
    ('modal', 'float32', True, True)
    """

    name: str
    fs: float
    form: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    A32: np.ndarray
    B32: np.ndarray
    C32: np.ndarray
    D32: np.ndarray
    basis_condition: float
    realisation_error: float
    radius64: float
    radius32: float
    omega: np.ndarray
    error: np.ndarray
    bound: np.ndarray
    time_error: float
    time_bound: float
    time_error_total: float
    time_bound_total: float
    time_input: np.ndarray = field(repr=False, default=None)

    @property
    def n_states(self):
        """Number of states n."""
        return self.A.shape[0]

    def to_statespace(self, dtype="float64"):
        """The realisation (float64 or float32 entries, as float64) as a control.StateSpace."""
        A, B, C, D = self._matrices(dtype)
        return ct.ss(A.astype(float), B.astype(float), C.astype(float), D.astype(float),
                     1.0 / self.fs, name=self.name)

    def simulate(self, e, dtype="float32"):
        """u[k] for the input e (N x m, or N for one input) from x[0] = 0, in ``dtype``
        arithmetic with that precision's matrices ('float32': as the target).

        Returns
        -------
        ndarray, shape (N, p), float64
        """
        e = np.asarray(e, float)
        e = e[:, None] if e.ndim == 1 else e
        if e.ndim != 2 or e.shape[1] != self.B.shape[1]:
            raise ValueError(f"e must be N x {self.B.shape[1]} (one column per controller "
                             f"input), got shape {e.shape}")
        u, _ = _run(*self._matrices(dtype), e, np.float32 if dtype == "float32" else np.float64)
        return u

    def _matrices(self, dtype):
        if dtype == "float32":
            return self.A32, self.B32, self.C32, self.D32
        if dtype == "float64":
            return self.A, self.B, self.C, self.D
        raise ValueError(f"dtype must be 'float32' or 'float64', got {dtype!r}")


def _check_name(name):
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name):
        raise ValueError(f"name must be a C identifier (a letter, then letters, digits or "
                         f"underscores), got {name!r}")
    return name


def _check_discrete(Kd):
    check_finite_lti("Kd", Kd)
    if Kd.isctime() or Kd.dt is True or not Kd.dt:
        raise ValueError("Kd must be a discrete-time controller with a numeric sample time "
                         f"(dt = 1/fs), got dt={Kd.dt}")
    if isinstance(Kd, ct.TransferFunction):
        Kd = ct.tf2ss(Kd) if Kd.ninputs * Kd.noutputs > 1 else ct.ss(Kd)
    return ct.ss(Kd)


def _modal(A, B, C):
    """(A_m, B_m, C_m, cond T) of the block-diagonal real modal form, blocks scaled."""
    lam, V = np.linalg.eig(A)
    order = np.lexsort((lam.imag, np.abs(lam)))
    cols, blocks = [], []
    used = np.zeros(lam.size, bool)
    for i in order:
        if used[i]:
            continue
        used[i] = True
        if abs(lam[i].imag) <= 1e-12 * max(1.0, abs(lam[i])):
            v = V[:, i].real if np.linalg.norm(V[:, i].real) > np.linalg.norm(V[:, i].imag) \
                else V[:, i].imag
            cols.append([v / np.linalg.norm(v)])
            blocks.append(np.array([[lam[i].real]]))
            continue
        # its conjugate partner: the unused eigenvalue nearest conj(lam[i])
        rest = np.nonzero(~used)[0]
        j = rest[np.argmin(np.abs(lam[rest] - np.conj(lam[i])))]
        used[j] = True
        k = i if lam[i].imag > 0 else j
        v = V[:, k]
        s, w = lam[k].real, lam[k].imag
        scale = np.linalg.norm(np.c_[v.real, v.imag])
        cols.append([v.real / scale, v.imag / scale])
        blocks.append(np.array([[s, w], [-w, s]]))
    T = np.column_stack([c for group in cols for c in group]) if cols else np.zeros((0, 0))
    cond = float(np.linalg.cond(T)) if T.size else 1.0
    if not np.isfinite(cond) or cond > 1e15:
        return None, None, None, math.inf
    Bm, Cm = np.linalg.solve(T, B), C @ T
    # scale each block's states: equal norms of its rows of B and columns of C
    start = 0
    for blk in blocks:
        k = blk.shape[0]
        nb, nc = np.linalg.norm(Bm[start:start + k]), np.linalg.norm(Cm[:, start:start + k])
        if nb > 0 and nc > 0:
            r = math.sqrt(nb / nc)
            Bm[start:start + k] /= r
            Cm[:, start:start + k] *= r
        start += k
    return la.block_diag(*blocks) if blocks else np.zeros((0, 0)), Bm, Cm, cond


def _schur(A, B, C):
    """(A_s, B_s, C_s, cond) of the balanced real Schur form."""
    T, Z = la.schur(A, output="real")
    Bs, Cs = Z.T @ B, C @ Z
    _, (scale, _) = la.matrix_balance(T, permute=False, separate=True)
    T = T * scale[None, :] / scale[:, None]
    return T, Bs / scale[:, None], Cs * scale[None, :], float(scale.max() / scale.min())


def _response(A, B, C, D, z):
    """H(z) at each point of z, shape (nf, p, m), float64 or complex arithmetic."""
    n = A.shape[0]
    out = np.broadcast_to(D, (z.size,) + D.shape).astype(complex)
    if n == 0:
        return out.copy()
    M = z[:, None, None] * np.eye(n) - A
    X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (z.size,) + B.shape))
    return out + C @ X


def _resolvent_norms(A, B, C, z):
    """(||C R||_2, ||R B||_2) at each z."""
    n = A.shape[0]
    if n == 0:
        return np.zeros(z.size), np.zeros(z.size)
    M = z[:, None, None] * np.eye(n) - A
    RB = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (z.size,) + B.shape))
    CR = np.swapaxes(np.linalg.solve(np.swapaxes(M, 1, 2),
                                     np.broadcast_to(C.T.astype(complex), (z.size,) + C.T.shape)),
                     1, 2)
    return (np.linalg.svd(CR, compute_uv=False)[:, 0], np.linalg.svd(RB, compute_uv=False)[:, 0])


def _half_ulp(X):
    X32 = X.astype(np.float32)
    return np.where(X32.astype(np.float64) == X, 0.0,
                    np.spacing(np.abs(X32)).astype(np.float64) / 2)


def _sigma_max(M):
    return np.linalg.svd(M, compute_uv=False)[:, 0] if M.shape[1] and M.shape[2] else \
        np.zeros(M.shape[0])


def _run(A, B, C, D, e, dtype):
    """(u, x) of the recursion in ``dtype`` arithmetic; x holds x[0..N-1] (N x n)."""
    A, B, C, D = (np.asarray(M, dtype) for M in (A, B, C, D))
    e = np.asarray(e, dtype)
    n, N = A.shape[0], e.shape[0]
    x = np.zeros(n, dtype)
    u = np.empty((N, C.shape[0]), dtype)
    xs = np.empty((N, n), dtype)
    for k in range(N):
        xs[k] = x
        u[k] = C @ x + D @ e[k]
        x = A @ x + B @ e[k]
    return u.astype(np.float64), xs.astype(np.float64)


def _time_check(Ax, Bx, Cx, Dx, A32, B32, C32, D32, Kd, e):
    """(time_error, time_bound, total_error, total_bound) of the float32 run on ``e``."""
    m32 = [M.astype(np.float64) for M in (A32, B32, C32, D32)]
    u32, x32 = _run(A32, B32, C32, D32, e, np.float32)
    u64, _ = _run(*m32, e, np.float64)
    ref, _ = _run(*(np.asarray(M, float) for M in (Kd.A, Kd.B, Kd.C, Kd.D)), e, np.float64)
    n, m, p = Ax.shape[0], Bx.shape[1], Cx.shape[0]
    N = e.shape[0]
    peak = max(float(np.max(np.abs(u64))), 1e-300)
    peak_ref = max(float(np.max(np.abs(ref))), 1e-300)

    def gamma(k):
        return k * _U32 / (1 - k * _U32)
    absA, absB, absC, absD = (np.abs(M) for M in m32)
    d_out = gamma(n + m) * (np.abs(x32) @ absC.T + np.abs(e) @ absD.T)       # N x p
    d_state = gamma(n + m) * (np.abs(x32) @ absA.T + np.abs(e) @ absB.T)     # N x n
    # sum_j ||C A^j||_inf over the record (the float32 matrices), a propagation gain
    gain, CAj = 0.0, m32[2].copy()
    for _ in range(N):
        gain += float(np.max(np.sum(np.abs(CAj), axis=1))) if n else 0.0
        if n == 0:
            break
        CAj = CAj @ m32[0]
        if not np.all(np.isfinite(CAj)):
            gain = math.inf
            break
    bound = gain * (float(np.max(d_state)) if n else 0.0) + float(np.max(d_out))
    # coefficient rounding: impulse response of H32 - H over the record, per input channel
    dh_l1 = 0.0
    for j in range(m):
        imp = np.zeros((N, m))
        imp[0, j] = 1.0
        h32, _ = _run(*m32, imp, np.float64)
        h, _ = _run(*(np.asarray(M, float) for M in (Kd.A, Kd.B, Kd.C, Kd.D)), imp, np.float64)
        dh_l1 = max(dh_l1, float(np.max(np.sum(np.abs(h32 - h), axis=0))))
    total_bound = bound + m * dh_l1 * float(np.max(np.abs(e)))
    return (float(np.max(np.abs(u32 - u64))) / peak, bound / peak,
            float(np.max(np.abs(u32 - ref))) / peak_ref, total_bound / peak_ref)


def export_mimo(Kd, name="K", *, form="auto", rtol=None, n_time=2000, seed=0):
    """A discrete MIMO controller in a well-conditioned realisation, checked in float32.

    Parameters
    ----------
    Kd : control.StateSpace or control.TransferFunction
        Discrete controller (numeric sample time), p outputs x m inputs, any sizes
        (SISO too).
    name : str
        C identifier for :func:`c_header`.
    form : {'auto', 'modal', 'schur', 'given'}
        Realisation exported (module docstring): 'auto' is 'modal' when its basis has
        condition number <= :data:`MODAL_CONDITION_LIMIT`, else 'schur'.
    rtol : float, optional
        Relative response error of the float32 matrices allowed at every frequency
        (default: the first-order bound of the rounding).
    n_time : int
        Samples of the random-input run of the time-domain check (100 ... 100,000).
    seed : int
        Seed of that input (uniform in [-1, 1], float32 values).

    Returns
    -------
    MIMOExport

    Raises
    ------
    ExportError
        Kd is stable (or marginal) and its float32 A is marginal (or unstable).
    ValueError, TypeError
        A continuous-time or non-finite Kd, an unknown form, a modal form asked for
        where the poles are defective, a bad name, rtol or n_time.

    Warns
    -----
    ExportWarning
        The float32 response error exceeds the bound (or rtol) somewhere, or the
        time-domain error exceeds its bound.

    Examples
    --------
    >>> Kd = ct.c2d(ct.ss([[-50.0, 0.0], [0.0, -400.0]], [[1.0, 0.0], [1.0, 1.0]],
    ...                   [[100.0, 0.0], [0.0, 300.0]], np.zeros((2, 2))), 1e-4, "tustin")
    >>> x = export_mimo(Kd, name="K_demo")
    >>> x.form, x.n_states, bool(x.time_error <= x.time_bound), bool(x.max_error < 1e-5)
    ('modal', 2, True, True)
    """
    S = _check_discrete(Kd)
    name = _check_name(name)
    if form not in _FORMS:
        raise ValueError(f"form must be one of {_FORMS}, got {form!r}")
    rtol = None if rtol is None else check_positive("rtol", rtol)
    n_time = check_count("n_time", n_time, maximum=100_000, minimum=100,
                         why="the time-domain run costs n_time steps")
    seed = check_integer("seed", seed, minimum=0)
    fs = 1.0 / float(S.dt)
    A, B, C, D = (np.asarray(M, float) for M in (S.A, S.B, S.C, S.D))
    cond = 1.0
    used = form
    if form in ("auto", "modal"):
        Am, Bm, Cm, cond = _modal(A, B, C)
        if Am is None or (form == "auto" and cond > MODAL_CONDITION_LIMIT):
            if form == "modal":
                raise ValueError(f"form='modal': Kd's poles are defective (modal basis "
                                 f"condition {cond:.3g}); use form='schur'")
            used = "schur"
        else:
            used = "modal"
            A, B, C = Am, Bm, Cm
    if used == "schur":
        A, B, C, cond = _schur(A, B, C)
    A32, B32, C32, D32 = (M.astype(np.float32) for M in (A, B, C, D))
    n = A.shape[0]
    radius64 = float(np.max(np.abs(np.linalg.eigvals(A)))) if n else 0.0
    radius32 = float(np.max(np.abs(np.linalg.eigvals(A32.astype(float))))) if n else 0.0
    given = np.asarray(S.A, float)
    radius_given = float(np.max(np.abs(np.linalg.eigvals(given)))) if n else 0.0

    def kind(r):
        return 2 if r < 1 - 1e-12 else (1 if r <= 1 + 1e-12 else 0)
    if kind(radius32) < kind(radius_given):
        words = ("unstable", "marginal", "stable")
        raise ExportError(f"Kd: rounding the {used} realisation of {name} to float32 makes it "
                          f"{words[kind(radius32)]} (it is {words[kind(radius_given)]}): pole "
                          f"radius {radius_given:.12g} in float64, {radius32:.12g} in float32; "
                          "such a controller needs float64 arithmetic on the target")
    # response check on 600 frequencies up to Nyquist and at the pole frequencies
    poles = np.linalg.eigvals(A) if n else np.zeros(0)
    theta = np.unique(np.r_[0.0, np.geomspace(1e-5 * np.pi, np.pi, 600),
                            np.abs(np.angle(poles))])
    z = np.exp(1j * theta)
    with np.errstate(all="ignore"):
        H = _response(*(np.asarray(M, float) for M in (S.A, S.B, S.C, S.D)), z)
        Hx = _response(A, B, C, D, z)
        H32 = _response(*(M.astype(float) for M in (A32, B32, C32, D32)), z)
        scale = _sigma_max(H)
        error = _sigma_max(H32 - H) / scale
        realisation = _sigma_max(Hx - H) / scale
        cr, rb = _resolvent_norms(A, B, C, z)
        eA, eB, eC, eD = (np.linalg.norm(_half_ulp(M)) for M in (A, B, C, D))
        bound = (cr * eA * rb + eC * rb + cr * eB + eD) / scale
    # a relative error means nothing at a transmission zero (Tustin's at Nyquist): drop the
    # frequencies where sigma_max(H) is below 1e-8 of its peak
    peak = np.nanmax(np.where(np.isfinite(scale), scale, np.nan)) if np.any(np.isfinite(scale)) \
        else 0.0
    bad = ~(np.isfinite(scale) & (scale > 1e-8 * peak) & np.isfinite(error))
    error[bad], bound[bad] = np.nan, np.nan
    realisation[bad] = np.nan
    rng = np.random.default_rng(seed)
    e = rng.uniform(-1, 1, (n_time, B.shape[1])).astype(np.float32).astype(float)
    t_err, t_bound, t_total, t_total_bound = _time_check(A, B, C, D, A32, B32, C32, D32, S, e)
    out = MIMOExport(name=name, fs=fs, form=used, A=A, B=B, C=C, D=D, A32=A32, B32=B32,
                     C32=C32, D32=D32, basis_condition=float(cond),
                     realisation_error=(float(np.nanmax(realisation))
                                        if np.any(np.isfinite(realisation)) else 0.0),
                     radius64=radius64, radius32=radius32, omega=theta * fs, error=error,
                     bound=bound, time_error=t_err, time_bound=t_bound,
                     time_error_total=t_total, time_bound_total=t_total_bound, time_input=e)
    _warn(out, rtol)
    return out


def _warn(x, rtol):
    tol = x.bound if rtol is None else np.full_like(x.bound, rtol)
    told = "rtol" if rtol is not None else "the first-order bound of the rounding"
    with np.errstate(invalid="ignore"):
        over = np.nan_to_num(x.error / tol, nan=0.0)
    if np.any(over > 1):
        i = int(np.argmax(over))
        warnings.warn(f"Kd: rounding {x.name}'s {x.form} realisation to float32 changes its "
                      f"response by {x.error[i]:.3g} (relative, largest singular value) at "
                      f"{x.omega[i] / (2 * np.pi):.4g} Hz, more than {told} ({tol[i]:.3g}) "
                      "allows", ExportWarning, stacklevel=3)
    if x.time_error > x.time_bound:
        warnings.warn(f"Kd: the float32 run of {x.name} differs from float64 arithmetic by "
                      f"{x.time_error:.3g} (relative to its peak), above the rounding bound "
                      f"{x.time_bound:.3g}", ExportWarning, stacklevel=3)


def _c_matrix(M):
    rows = M if M.size else np.zeros((max(M.shape[0], 1), 1), np.float32)
    return ",\n".join("    {" + ", ".join(np.format_float_scientific(np.float32(v), unique=True)
                                          + "f" for v in row) + "}" for row in rows)


def c_header(controller):
    """The text of a C header running the exported controller in float32.

    Parameters
    ----------
    controller : MIMOExport
        From :func:`export_mimo`.

    Returns
    -------
    str
        ``#define <NAME>_N_STATES``, ``_N_INPUTS``, ``_N_OUTPUTS``, ``_FS_HZ``;
        ``static const float <NAME>_A[n][n]``, ``_B``, ``_C``, ``_D`` (float32 values, each
        printed with the digits that round-trip it); and
        ``static inline void <name>_step(float x[n], const float e[m], float u[p])``:
        u = C x + D e, then x = A x + B e (x updated in place; zero it at start).  A static
        controller (n = 0) gets 1-element placeholder arrays that the loops never read.

    Raises
    ------
    TypeError
        ``controller`` is not a :class:`MIMOExport`.

    Examples
    --------
    >>> Kd = ct.c2d(ct.ss([[-50.0]], [[1.0, 2.0]], [[100.0], [10.0]], np.zeros((2, 2))),
    ...             1e-4, "tustin")
    >>> text = c_header(export_mimo(Kd, name="K_demo"))
    >>> "static const float K_DEMO_A[1][1]" in text, "void k_demo_step(" in text
    (True, True)
    """
    if not isinstance(controller, MIMOExport):
        raise TypeError(f"controller must be a MIMOExport (from export_mimo), got "
                        f"{type(controller).__name__}")
    x = controller
    N, low = x.name.upper(), x.name.lower()
    n, m, p = x.n_states, x.B.shape[1], x.C.shape[0]
    nn = max(n, 1)
    A = x.A32 if n else np.zeros((1, 1), np.float32)
    B = x.B32 if n else np.zeros((1, m), np.float32)
    C = x.C32 if n else np.zeros((p, 1), np.float32)
    guard = f"{N}_SS_H"
    return f"""/* {x.name}: discrete MIMO controller e ({m}) -> u ({p}) at {x.fs:g} Hz, {n} states,
 * {x.form} realisation in float32:  u[k] = C x[k] + D e[k];  x[k+1] = A x[k] + B e[k].
 * Generated by piezolib.robust.mimo_export; do not edit. */
#ifndef {guard}
#define {guard}

#define {N}_N_STATES {n}
#define {N}_N_INPUTS {m}
#define {N}_N_OUTPUTS {p}
#define {N}_FS_HZ {x.fs!r}

static const float {N}_A[{nn}][{nn}] = {{
{_c_matrix(A)}
}};

static const float {N}_B[{nn}][{m}] = {{
{_c_matrix(B)}
}};

static const float {N}_C[{p}][{nn}] = {{
{_c_matrix(C)}
}};

static const float {N}_D[{p}][{m}] = {{
{_c_matrix(x.D32)}
}};

/* one sample: u from e and the state x, then x advanced in place (x zero at start) */
static inline void {low}_step(float x[{nn}], const float e[{m}], float u[{p}])
{{
    float next[{nn}];
    for (int i = 0; i < {N}_N_OUTPUTS; ++i) {{
        float acc = 0.0f;
        for (int j = 0; j < {N}_N_STATES; ++j) acc += {N}_C[i][j] * x[j];
        for (int j = 0; j < {N}_N_INPUTS; ++j) acc += {N}_D[i][j] * e[j];
        u[i] = acc;
    }}
    for (int i = 0; i < {N}_N_STATES; ++i) {{
        float acc = 0.0f;
        for (int j = 0; j < {N}_N_STATES; ++j) acc += {N}_A[i][j] * x[j];
        for (int j = 0; j < {N}_N_INPUTS; ++j) acc += {N}_B[i][j] * e[j];
        next[i] = acc;
    }}
    for (int i = 0; i < {N}_N_STATES; ++i) x[i] = next[i];
}}

#endif /* {guard} */
"""
