"""Export a discrete controller as second-order sections: JSON, C header, reference filter.

A discrete SISO controller K_d(z) at the loop's sample time is factored into
poles, zeros and gain and paired into second-order sections (scipy's
``zpk2sos``, poles nearest the unit circle last), each

    H_i(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2),

K_d = prod_i H_i (the gain sits in the first section's numerator).  A real
time target runs them in Direct Form II transposed, two state words per
section:

    y    = b0 x + s1
    s1   = b1 x - a1 y + s2
    s2   = b2 x - a2 y

:class:`SectionFilter` is that reference implementation in numpy, in the
precision asked for (float32 arithmetic for the float32 coefficients),
:class:`SectionFilterBatch` the same on N signals at once (bit for bit), and
:func:`sos_filter` runs it over a signal.  :func:`write_json` and
:func:`write_c_header` write the coefficients in float64 and rounded to
float32; :func:`read_json` reads them back.

Rounding the coefficients to float32 moves every pole and zero.  Wherever
that happens for a target (:func:`export_controller`, :func:`write_json`,
:func:`write_c_header`, a float32 :class:`SectionFilter` and so
:func:`sos_filter`) the float32 sections are checked against the float64
ones (:meth:`SOSController.check_float32`): a section that rounding makes
marginal or unstable is refused (:class:`ExportError`), and a response error
larger than the first-order effect of the rounding (or than ``rtol``) is
reported (:class:`ExportWarning`).
"""

import functools
import json
import math
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import control as ct
import numpy as np
import scipy.linalg as la
import scipy.signal as sig

from piezolib._checks import (check_finite_array, check_finite_lti, check_integer, check_positive,
                              check_proper, check_siso)
from piezolib.files import CONTENT_KEY, atomic_write, seal, seal_problem
from piezolib.robust.float32_check import (ExportError, ExportWarning, Float32Check,
                                           sections_response)

__all__ = ["SOSController", "controller_sos", "SectionFilter", "SectionFilterBatch",
           "sos_filter", "write_json",
           "read_json", "write_c_header", "export_controller", "Float32Check", "ExportError",
           "ExportWarning"]

_DTYPES = {"float64": np.float64, "float32": np.float32}
#: relative error allowed between the float64 sections and K_d on the check grid
_SOS_RTOL = 1e-6


@dataclass(frozen=True, eq=False)
class SOSController:
    """A discrete SISO controller as second-order sections.

    Attributes
    ----------
    sos : ndarray, shape (n_sections, 6)
        Rows [b0, b1, b2, 1, a1, a2], float64 (read-only copy).
    fs : float
        Sampling rate [Hz].
    name : str
        Identifier (used for the C symbol names): letters, digits and
        underscores, starting with a letter.

    Raises
    ------
    ValueError, TypeError
        A section matrix that is not finite, real and (n >= 1, 6), a section
        not normalised (a0 != 1: every formula here divides by a0 = 1), a
        non-positive fs or a name that is not a C identifier.

    Examples
    --------
    >>> c = SOSController(np.array([[0.5, 0.0, 0.0, 1.0, -0.5, 0.0]]), fs=1e3, name="K")
    >>> c.sos.shape, c.fs, c.name                               # 0.5 / (1 - 0.5 z^-1)
    ((1, 6), 1000.0, 'K')
    """

    sos: np.ndarray
    fs: float
    name: str = "K"

    def __post_init__(self):
        sos = _normalised_sections("sos", self.sos)
        sos.flags.writeable = False        # the float32 check is cached: no edits behind it
        object.__setattr__(self, "sos", sos)
        object.__setattr__(self, "fs", check_positive("fs", self.fs))
        _check_name(self.name)

    @property
    def n_sections(self):
        """Number of second-order sections."""
        return self.sos.shape[0]

    def coefficients(self, dtype="float64"):
        """The section matrix rounded to ``dtype`` ('float64' or 'float32').

        No check here: this is the float32 controller as it is, for analysis
        (:meth:`check_float32` says whether it is still the controller).
        """
        return self.sos.astype(_dtype(dtype))

    def frequency_response(self, omega, dtype="float64"):
        """K_d(e^{j omega / fs}) of the sections with ``dtype`` coefficients (evaluated in float64).

        Parameters
        ----------
        omega : array_like
            Frequencies [rad/s], below the Nyquist frequency pi fs.
        dtype : {'float64', 'float32'}

        Returns
        -------
        ndarray of complex
        """
        omega = check_finite_array("omega", omega, ndim=1, min_length=1)
        return sections_response(self.coefficients(dtype).astype(np.float64),
                                  np.exp(1j * omega / self.fs))

    def to_statespace(self, dtype="float64"):
        """The sections (``dtype`` coefficients) as a control.StateSpace at dt = 1/fs."""
        # section by section in series, each in controllable form (one state for a first-order
        # row, none for a gain): the product of the sections' polynomials and a tf2ss kept or
        # dropped their common factors by rounding, so the state count changed between BLAS
        # kernels (8 or 6 for the deployed controller); here it follows the coefficients
        A, B, C, D = np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.ones((1, 1))
        for b0, b1, b2, _, a1, a2 in self.coefficients(dtype).astype(np.float64):
            order = 2 if (b2 != 0 or a2 != 0) else (1 if (b1 != 0 or a1 != 0) else 0)
            As = np.array([[-a1, -a2], [1.0, 0.0]])[:order, :order]
            Bs = np.array([[1.0], [0.0]])[:order]
            Cs = np.array([[b1 - b0 * a1, b2 - b0 * a2]])[:, :order]
            n, m = A.shape[0], order
            A = np.block([[A, np.zeros((n, m))], [Bs @ C, As]])
            B, C, D = np.vstack([B, Bs @ D]), np.hstack([b0 * C, Cs]), b0 * D
        return ct.ss(A, B, C, D, 1.0 / self.fs, inputs="v_e", outputs="u_b", name=self.name)

    def check_float32(self, rtol=None, what="controller"):
        """Check the float32 sections against these (float64) ones.

        Parameters
        ----------
        rtol : float, optional
            Relative response error allowed at every frequency.  Default: the
            first-order effect of rounding each coefficient to float32,
            sum over sections and coefficients of half an ulp times
            |d ln H / d c| (:class:`Float32Check`), which the rounding exceeds
            only when it is no longer a small perturbation of the sections.
        what : str
            Name of the argument the sections came from (for the messages).

        Returns
        -------
        Float32Check

        Raises
        ------
        ExportError
            A section stable in float64 is marginal or unstable in float32 (or
            a marginal one unstable): the message names the section and gives
            its pole radius in float64 and float32.

        Warns
        -----
        ExportWarning
            The float32 response error exceeds the tolerance somewhere (worst
            error, its frequency, the tolerance there and the DC gains), or a
            pole's distance to the unit circle changed by more than the
            tolerance at the pole's frequency.
        """
        return self._float32_check.enforce(rtol, what, stacklevel=3)

    @functools.cached_property
    def _float32_check(self):
        # computed once per controller (the sections are read-only), enforced at every use
        return Float32Check.of(self.sos, self.fs, self.name)


def _check_name(name):
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name):
        raise ValueError(f"name must be a C identifier, got {name!r}")
    return name


def _normalised_sections(name, sos):
    """``sos`` as a float64 (n >= 1, 6) array of real, finite rows with a0 = 1."""
    sos = np.array(check_finite_array(name, sos, ndim=2, min_length=1, shape=(None, 6),
                                      real=True), dtype=np.float64)
    bad = np.nonzero(sos[:, 3] != 1)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name} section {i} has a0 = {float(sos[i, 3])!r}: sections must be "
                         "normalised (a0 = 1), the Direct Form II transposed step assumes it")
    return sos


def _dtype(dtype):
    if dtype not in _DTYPES:
        raise ValueError(f"dtype must be one of {sorted(_DTYPES)}, got {dtype!r}")
    return _DTYPES[dtype]


def controller_sos(Kd, name="K"):
    """Second-order sections of a discrete SISO controller.

    The poles are the eigenvalues of a state-space realisation and the zeros
    its invariant zeros (never the roots of transfer-function polynomials
    formed on the way); the gain matches K_d's frequency response, evaluated
    on a balanced realisation (a product of sections realised one after the
    other can be so badly scaled that the plain evaluation loses every digit).

    Parameters
    ----------
    Kd : control.LTI
        Discrete-time SISO controller with a numeric sample time (e.g. the
        Tustin controller of :func:`piezolib.robust.discrete.discretize`),
        best as a state-space model: the coefficients of a high-order
        transfer function can fix its poles only loosely.
    name : str
        Identifier: letters, digits and underscores, starting with a letter.

    Returns
    -------
    SOSController

    Raises
    ------
    ValueError
        A continuous-time or improper controller, one that is identically
        zero, a bad name, or a factorisation that does not reproduce K_d
        (relative error above 1e-6 on a grid up to the Nyquist frequency,
        measured against max(|K_d|, 1e-6 max |K_d|) so that deep notches are
        held to an absolute accuracy).

    Examples
    --------
    >>> import control as ct
    >>> controller_sos(ct.tf(1, [1, -1, 0.25], 1e-4)).sos    # double pole at z = 0.5
    array([[ 0. ,  0. ,  1. ,  1. , -0.5,  0. ],
           [ 1. ,  0. ,  0. ,  1. , -0.5,  0. ]])
    """
    check_siso("Kd", Kd)
    check_finite_lti("Kd", Kd)
    if not Kd.isdtime(strict=True) or Kd.dt is True:
        raise ValueError("Kd must be a discrete-time controller with a numeric sample time")
    _check_name(name)
    check_proper("Kd", Kd)
    fs = 1.0 / float(Kd.dt)
    K = _state_space(Kd)
    Kb = _balanced(K)
    theta = np.linspace(0.01, 0.99, 97) * np.pi
    z = np.exp(1j * theta)
    k_ref = np.ravel(Kb(z))
    if not np.any(k_ref != 0):
        raise ValueError(f"Kd is identically zero (its response is 0 at all {theta.size} "
                         f"frequencies from {theta[0] * fs / (2 * np.pi):.4g} to "
                         f"{theta[-1] * fs / (2 * np.pi):.4g} Hz): there is nothing to export")
    # k_ref is the balanced realisation's response: the reference every candidate must meet
    best = (math.inf, theta[0])
    for realisation, zeros in _candidates(K, Kb):
        try:
            out = SOSController(_sections(realisation, zeros, z), fs, name)
        except ValueError:          # zeros without their conjugate: not a real factorisation
            continue
        err, i = _relative_error(out.frequency_response(theta * fs), k_ref)
        if err <= _SOS_RTOL:
            return out
        best = min(best, (err, theta[i]))
    raise ValueError(_mismatch_message(Kd, *best, fs))


def _candidates(K, Kb):
    """(realisation the gain is fitted to, zeros) to try, in order.

    First the realisation as given with SLICOT's zeros (a well-scaled
    controller keeps the sections it always had, e.g. the committed exports
    in data/controllers); then the balanced realisation (a product of
    sections realised one after the other can be scaled so badly that the
    plain response loses every digit); then the zeros by QZ on the balanced
    Rosenbrock pencil, which keeps digits that SLICOT's reduction loses on
    such realisations (and sometimes loses digits SLICOT keeps), with
    SLICOT's count of finite zeros and with the pencil's own.  Each
    candidate is checked against K_d's response.
    """
    if not K.nstates:
        yield K, np.zeros(0)
        return
    zeros = _finite(ct.zeros(K))
    yield K, zeros
    if Kb is not K:
        yield Kb, zeros
    pencil = _pencil_eigenvalues(K)
    counts = dict.fromkeys([zeros.size, int(np.count_nonzero(np.isfinite(pencil)))])
    for count in counts:
        yield Kb, pencil[:count]


def _finite(values):
    return values[np.isfinite(values)]


def _pencil_eigenvalues(K):
    """Generalised eigenvalues of the Rosenbrock pencil of ``K``, finite ones first by modulus.

    [A - z I, B; C, D] drops rank at the invariant zeros.  The pencil is
    balanced first (a diagonal similarity by powers of two: the same zeros,
    and diag(I, 0) is unchanged); of its n + 1 eigenvalues the relative
    degree plus one are infinite (inf or huge in floating point), so the
    finite zeros are the first ones.
    """
    n = K.nstates
    L = np.block([[K.A, K.B], [K.C, K.D]])
    _, (scale, _) = la.matrix_balance(L, permute=False, separate=True)
    w = la.eigvals(L / scale[:, None] * scale, np.diag(np.r_[np.ones(n), 0.0]))
    return w[np.argsort(np.where(np.isfinite(w), np.abs(w), np.inf), kind="stable")]


def _state_space(Kd):
    """``ct.ss(Kd)``, a transfer function's numerator scaled to O(1) first (by a power of two,
    put back exactly): the conversion drops coefficients below an absolute tolerance, so
    that 1e-46 / (z - 0.5) would become the zero system."""
    if not isinstance(Kd, ct.TransferFunction):
        return ct.ss(Kd)
    num = np.atleast_1d(np.asarray(Kd.num[0][0], dtype=float))
    peak = float(np.max(np.abs(num)))
    if peak == 0:
        return ct.ss(Kd)
    scale = 2.0 ** np.round(np.log2(peak))
    K = ct.ss(ct.tf(num / scale, Kd.den[0][0], Kd.dt))
    return ct.ss(K.A, K.B, K.C * scale, K.D * scale, K.dt)


def _balanced(K):
    """``K`` with its states scaled by powers of two (the same system to the last bit).

    ``K`` itself when the balancing scales nothing.
    """
    if not K.nstates:
        return K
    _, (scale, _) = la.matrix_balance(K.A, permute=False, separate=True)
    if np.all(scale == 1):
        return K
    return ct.ss(K.A / scale[:, None] * scale, K.B / scale[:, None], K.C * scale, K.D, K.dt)


def _sections(K, zeros, z):
    """Section matrix of the realisation ``K``: its eigenvalues, the invariant ``zeros`` and
    the gain that matches its response at the points ``z`` (the median over them)."""
    if not K.nstates:
        return np.array([[float(K.D[0, 0]), 0, 0, 1, 0, 0]])
    poles = np.linalg.eigvals(K.A)
    k = np.ravel(K(z))
    shape = np.array([np.prod(zz - zeros) / np.prod(zz - poles) for zz in z])
    use = np.abs(shape) > 1e-300
    gain = np.median((k[use] / shape[use]).real) if np.any(use) else 0.0
    delay = poles.size - zeros.size        # relative degree: zeros at z = 0 become z^-1
    sos = sig.zpk2sos(np.r_[zeros, np.zeros(delay)], poles, gain, pairing="nearest")
    return np.asarray(_split_real(_delay_numerators(sos, delay)), float)


def _relative_error(h, reference):
    """max |h / reference - 1| with |reference| floored at _SOS_RTOL max |reference|; where.

    Near a zero of K_d on the unit circle the pointwise relative error means
    nothing (the response is at rounding level); below the floor the error is
    absolute, relative to the controller's peak.  Never NaN: a non-finite
    error counts as inf.
    """
    floor = max(_SOS_RTOL * float(np.max(np.abs(reference))), np.finfo(float).tiny)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        err = np.abs(h - reference) / np.maximum(np.abs(reference), floor)
    err = np.where(np.isfinite(err), err, np.inf)
    i = int(np.argmax(err))
    return float(err[i]), i


def _mismatch_message(Kd, err, theta, fs):
    """Why the sections may not reproduce Kd (worst error ``err`` at ``theta`` rad/sample)."""
    where = (f"relative error {err:.2g} at {theta * fs / (2 * np.pi):.4g} Hz, "
             f"tolerance {_SOS_RTOL:g}")
    if isinstance(Kd, ct.TransferFunction):
        # how far the coefficients themselves pin the response down there
        z = np.exp(1j * theta)
        cond = sum(np.polyval(np.abs(c), abs(z)) / abs(np.polyval(c, z))
                   for c in (Kd.num[0][0], Kd.den[0][0]))
        if cond * np.finfo(float).eps > 0.1 * _SOS_RTOL:
            return (f"the sections do not reproduce Kd ({where}): Kd's transfer-function "
                    f"coefficients fix its response there only to about "
                    f"{cond * np.finfo(float).eps:.1g} (condition number {cond:.2g}); give Kd "
                    "as a state-space model (e.g. the realisation it was formed from)")
    return (f"the sections do not reproduce Kd ({where}); is Kd minimal (a pole cancelled "
            "by a zero)? try control.minreal(Kd)")


def _delay_numerators(sos, delay):
    """Turn ``delay`` zeros at z = 0 of the sections into zeros at infinity (z^-1 factors).

    A section with a zero at 0 (b2 = 0) takes a factor z^-1 as
    [b0, b1, 0] -> [0, b0, b1]; one with two, [b0, 0, 0], takes two, the
    second as [0, b0, 0] -> [0, 0, b0].  Sections with b0 != 0 go first
    (as always: the sections of earlier exports stay as they were).
    """
    sos = np.array(sos, float)
    for _ in range(delay):
        zero_at_0 = sos[:, 2] == 0
        rows = np.nonzero(zero_at_0 & (sos[:, 0] != 0))[0]
        if not rows.size:
            rows = np.nonzero(zero_at_0 & (sos[:, 1] != 0))[0]
        if not rows.size:   # cannot happen: ``delay`` zeros at 0 were padded
            raise RuntimeError("no section has a zero at z = 0 left for the delay")
        i = rows[0]
        sos[i, :3] = [0.0, sos[i, 0], sos[i, 1]]
    return sos


def _split_real(sos):
    """Split sections with two real poles into two first-order sections.

    A pair of real poles p1, p2 near z = 1 (an integrator-like controller)
    gives 1 + a1 + a2 = (1 - p1)(1 - p2), tiny beside the rounding of a2 in
    float32, so the section's low-frequency gain would be lost in single
    precision; first-order sections keep 1 - p to full relative precision.
    Real zero pairs are split alike, each zero going with the nearer pole.
    """
    out = []
    for b0, b1, b2, _, a1, a2 in sos:
        p = np.roots([1.0, a1, a2]) if a2 != 0 else np.array([])
        if p.size == 2 and a1 * a1 >= 4 * a2:
            p = p.real     # a double real pole may come out as a pair with a tiny imaginary part
        if p.size != 2 or np.any(np.abs(p.imag) > 0):
            out.append([b0, b1, b2, 1.0, a1, a2])
            continue
        p = np.sort(p.real)
        zr = np.roots([b0, b1, b2]) if b0 != 0 and b2 != 0 else np.array([])
        if zr.size == 2 and not np.any(np.abs(zr.imag) > 0):
            z1, z2 = (zr.real if abs(zr.real[0] - p[0]) + abs(zr.real[1] - p[1])
                      <= abs(zr.real[1] - p[0]) + abs(zr.real[0] - p[1]) else zr.real[::-1])
            out.append([b0, -b0 * z1, 0.0, 1.0, -p[0], 0.0])
            out.append([1.0, -z2, 0.0, 1.0, -p[1], 0.0])
        else:
            out.append([b0, b1, b2, 1.0, -p[0], 0.0])
            out.append([1.0, 0.0, 0.0, 1.0, -p[1], 0.0])
    return np.array(out)


def _check_float32(controller, sos, what, stacklevel, rtol=None, refuse=True):
    """Enforce the float32 check of ``controller`` (an SOSController or its matrix ``sos``).

    ``stacklevel`` is that of a warning issued by the caller of this function.
    """
    big = np.abs(sos) > np.finfo(np.float32).max
    if np.any(big):
        raise ExportError(f"{what} has a section coefficient {sos[big][0]:.3g} outside the "
                          f"float32 range (|x| <= {np.finfo(np.float32).max:.3g}): the target's "
                          "float32 sections cannot hold it (scale the controller's input or "
                          "output)")
    # below float32's normal range rounding is no longer relative (the first-order bound
    # does not hold): a numerator row whose largest coefficient is there is refused
    scale = np.max(np.abs(sos[:, :3]), axis=1)
    tiny = (scale > 0) & (scale < np.finfo(np.float32).tiny)
    if np.any(tiny):
        message = (f"{what} has a section numerator of scale {scale[tiny][0]:.3g} below the "
                   f"float32 normal range (|x| >= {np.finfo(np.float32).tiny:.3g}): float32 "
                   "sections round it to zero or lose its digits (scale the controller's input "
                   "or output)")
        if refuse:
            raise ExportError(message)
        warnings.warn(message, ExportWarning, stacklevel=stacklevel)
        return
    if np.array_equal(sos.astype(np.float32).astype(np.float64), sos):
        return          # float32 holds every coefficient: nothing moves
    check = (controller._float32_check if isinstance(controller, SOSController)
             else Float32Check.of(sos))
    check.enforce(rtol, what, stacklevel=stacklevel + 2, refuse=refuse)


class SectionFilter:
    """Reference Direct Form II transposed implementation of the sections.

    Parameters
    ----------
    controller : SOSController or array_like
        The sections (or an (n, 6) section matrix).
    dtype : {'float64', 'float32'}
        Precision of the coefficients, the states and every operation.
        float32 coefficients are checked against the given (float64) ones
        (:meth:`SOSController.check_float32`); sections already rounded to
        float32 (as :func:`read_json` gives them) pass unchanged.

    Raises
    ------
    ExportError
        float32 rounding makes a section marginal or unstable.

    Warns
    -----
    ExportWarning
        float32 rounding changes the response more than it should.

    Examples
    --------
    >>> f = SectionFilter(np.array([[0.5, 0, 0, 1, -0.5, 0]]))
    >>> [round(f.step(1.0), 4) for _ in range(3)]
    [0.5, 0.75, 0.875]
    """

    def __init__(self, controller, dtype="float64", _stacklevel=2):
        sos = (controller.sos if isinstance(controller, SOSController)
               else _normalised_sections("controller", controller))
        self.dtype = _dtype(dtype)
        if self.dtype is np.float32:
            _check_float32(controller, sos, "controller", stacklevel=_stacklevel)
        c = sos.astype(self.dtype)
        self._coef = [tuple(self.dtype(x) for x in row) for row in c]
        self._py = self.dtype is np.float64     # float64: Python floats are IEEE doubles
        if self._py:
            self._coef = [tuple(float(x) for x in row) for row in c]
        self.reset()

    def reset(self):
        """Zero the states."""
        zero = 0.0 if self._py else self.dtype(0)
        self._s = [[zero, zero] for _ in self._coef]

    def step(self, x):
        """One sample: input x, output y (as a Python float)."""
        y = float(x) if self._py else self.dtype(x)
        for (b0, b1, b2, _, a1, a2), s in zip(self._coef, self._s):
            u = y
            y = b0 * u + s[0]
            s[0] = b1 * u - a1 * y + s[1]
            s[1] = b2 * u - a2 * y
        return float(y)


class SectionFilterBatch:
    """:class:`SectionFilter` run on N signals at once (e.g. N noise seeds).

    The states are arrays of shape (N,) and every operation of
    :meth:`SectionFilter.step` is applied elementwise in the same order and
    precision, so channel i of the output is identical, float for float, to
    a :class:`SectionFilter` fed with channel i of the input.

    Parameters
    ----------
    controller : SOSController or array_like
        The sections (or an (n, 6) section matrix), shared by all channels.
    dtype : {'float64', 'float32'}
        Precision of the coefficients, the states and every operation.
    size : int
        Number of channels N >= 1.

    Examples
    --------
    >>> f = SectionFilterBatch(np.array([[0.5, 0, 0, 1, -0.5, 0]]), size=2)
    >>> f.step([1.0, 2.0])
    array([0.5, 1. ])
    """

    def __init__(self, controller, dtype="float64", size=1):
        ref = SectionFilter(controller, dtype, _stacklevel=3)   # checks sections and dtype
        self.dtype = ref.dtype
        self.size = check_integer("size", size, minimum=1)
        c = np.array(ref._coef, dtype=self.dtype)       # (n_sections, 6) in dtype
        n_sec = len(c)
        self._b0 = [np.array(x, self.dtype) for x in c[:, 0]]
        # the state updates of all sections at once (they need only the sections'
        # inputs u and outputs y): [s1; s2] <- [b1; b2] u - [a1; a2] y, s1 += old s2
        self._bb = np.stack([c[:, 1:2], c[:, 2:3]])     # (2, n_sections, 1)
        self._aa = np.stack([c[:, 4:5], c[:, 5:6]])
        self._v = np.empty((n_sec + 1, self.size), self.dtype)  # v[0] input, v[i+1] section i out
        self._rows = list(self._v)
        self._u, self._y = self._v[:-1], self._v[1:]
        self._t = np.empty((2, n_sec, self.size), self.dtype)
        self._t2 = np.empty_like(self._t)
        self._coef = c
        self.reset()

    def reset(self):
        """Zero the states."""
        self._s = np.zeros((2, len(self._b0), self.size), self.dtype)   # [s1; s2] per section

    @property
    def arrays(self):
        """``(coefficients, states)``: the (n_sections, 6) rows ``[b0 b1 b2 1 a1 a2]``
        and the (2, n_sections, N) states ``[s1; s2]``, in :attr:`dtype` (the states are
        the filter's own: a compiled loop that runs the filter updates them in place)."""
        return self._coef, self._s

    def step(self, x):
        """One sample of every channel.

        Parameters
        ----------
        x : array_like, shape (N,)
            Input of each channel.

        Returns
        -------
        ndarray, shape (N,)
            Output of each channel, float64 holding the ``dtype`` results.
        """
        x = np.asarray(x, dtype=float)
        if x.shape != (self.size,):
            raise ValueError(f"x must have shape ({self.size},), got {x.shape}")
        v, s, t, t2 = self._rows, self._s, self._t, self._t2
        v[0][...] = x                      # rounds to dtype like SectionFilter's dtype(x)
        # y = b0 u + s1, section after section (u of section i = y of section i - 1) ...
        s1 = s[0]
        for i, b0 in enumerate(self._b0):
            np.multiply(b0, v[i], v[i + 1])
            np.add(v[i + 1], s1[i], v[i + 1])
        # ... then every section's states, in SectionFilter's order of operations:
        # s1 <- (b1 u - a1 y) + s2,  s2 <- b2 u - a2 y
        np.multiply(self._bb, self._u, t)
        np.multiply(self._aa, self._y, t2)
        np.subtract(t, t2, t)
        np.add(t[0], s[1], t[0])
        self._s, self._t = t, s
        return v[-1].astype(np.float64)


def sos_filter(controller, x, dtype="float64"):
    """Run :class:`SectionFilter` from zero state over the signal ``x``.

    Parameters
    ----------
    controller : SOSController or array_like
    x : array_like
        Input samples (1-D).
    dtype : {'float64', 'float32'}

    Returns
    -------
    ndarray
        Output samples (float64 array holding the ``dtype`` results).

    Examples
    --------
    >>> sos_filter(np.array([[0.5, 0.0, 0.0, 1.0, -0.5, 0.0]]), [1.0, 1.0, 1.0, 1.0])   # a step
    array([0.5   , 0.75  , 0.875 , 0.9375])
    """
    x = check_finite_array("x", x, ndim=1, min_length=1, real=True)
    f = SectionFilter(controller, dtype, _stacklevel=3)
    coef = np.array(f._coef, dtype=f.dtype).reshape(-1, 6)
    # compiled: SectionFilter.step's operations, in its order and precision, per sample
    return _sections_kernel()(coef, x.astype(f.dtype), np.zeros(x.size))


@functools.cache
def _sections_kernel():
    """The compiled loop of :func:`sos_filter` (numba imported and the function compiled or
    loaded from its disk cache once; a process that never filters does not pay for it)."""
    import numba

    @numba.njit(cache=True, nogil=True)
    def run(coef, x, out):
        n_sec = coef.shape[0]
        s = np.zeros((n_sec, 2), coef.dtype)
        for k in range(x.size):
            y = x[k]
            for q in range(n_sec):
                u = y
                y = coef[q, 0] * u + s[q, 0]
                s[q, 0] = coef[q, 1] * u - coef[q, 4] * y + s[q, 1]
                s[q, 1] = coef[q, 2] * u - coef[q, 5] * y
            out[k] = np.float64(y)
        return out

    return run


def _path(name, path, *, directory=False):
    """``path`` as a Path, checked to be a path (and, to write a file, not a directory)."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{name} must be a str or path, got {type(path).__name__}")
    path = Path(path)
    if directory and path.exists() and not path.is_dir():
        raise ValueError(f"{name} {path} exists and is not a directory")
    if not directory and path.is_dir():
        raise ValueError(f"{name} {path} is a directory, not a file")
    return path


def _meta_json(meta):
    """``meta`` (a dict or None) checked to be JSON-serialisable."""
    if meta is None:
        return {}
    if not isinstance(meta, dict):
        raise TypeError(f"meta must be a dict, got {type(meta).__name__}")
    try:
        json.dumps(meta)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"meta must be JSON-serialisable: {exc}") from None
    try:
        json.dumps(meta, allow_nan=False)
    except ValueError:      # NaN / Infinity are no JSON: a strict reader refuses the file
        raise ValueError(f"meta must hold finite numbers only (JSON has no NaN or infinity), "
                         f"got {_non_finite(meta)}") from None
    return meta


def _non_finite(value, where="meta"):
    """The first path in ``value`` (nested dicts and lists) holding a non-finite float."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{where} = {value}"
    items = value.items() if isinstance(value, dict) else (
        enumerate(value) if isinstance(value, (list, tuple)) else ())
    for key, item in items:
        found = _non_finite(item, f"{where}[{key!r}]")
        if found:
            return found
    return None


def write_json(controller, path, meta=None):
    """Write the sections (float64 and float32) and ``meta`` to a JSON file.

    Parameters
    ----------
    controller : SOSController
    path : str or Path
        File to write.
    meta : dict, optional
        JSON-serialisable extra information (units, origin, ...); its
        ``"input"`` and ``"output"`` entries, if any, name the signals
        (default ``v_e [V]`` and ``u_b [V]``: a feedback controller).

    Returns
    -------
    Path

    Raises
    ------
    ExportError
        The float32 sections written are marginal or unstable where the
        float64 ones are not (:meth:`SOSController.check_float32`); nothing
        is written.

    Warns
    -----
    ExportWarning
        The float32 sections' response is off by more than the rounding explains.

    Examples
    --------
    >>> import tempfile
    >>> Kd = ct.c2d(ct.tf([100], [1, 100]), 1e-3, "tustin")       # a 100 rad/s low-pass at 1 kHz
    >>> c = controller_sos(Kd, "K_lp")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_json(c, Path(folder) / "K_lp.json", meta={"method": "tustin"})
    ...     back = read_json(path)
    >>> path.name, bool(np.array_equal(back.sos, c.sos)), back.fs
    ('K_lp.json', True, 1000.0)
    """
    _check_controller(controller)
    meta = _meta_json(meta)
    path = _path("path", path)
    _check_float32(controller, controller.sos, "controller", stacklevel=2)
    return _write_json(controller, path, meta)


def _check_controller(controller):
    if not isinstance(controller, SOSController):
        raise TypeError(f"controller must be an SOSController, got {type(controller).__name__}")


def _signals(meta):
    """{"input", "output"}: a feedback controller's v_e [V] and u_b [V] unless ``meta`` names others."""
    signals = {"input": "v_e [V]", "output": "u_b [V]"}
    signals.update({k: str(meta[k]) for k in signals if k in meta})
    return signals


def _write_json(controller, path, meta):
    signals = _signals(meta)
    doc = {"name": controller.name, "fs_Hz": controller.fs,
           "form": "second-order sections [b0, b1, b2, 1, a1, a2], Direct Form II transposed",
           **signals,
           "sos_float64": controller.sos.tolist(),
           # float32 values written as the exact decimal of the rounded number
           "sos_float32": [[float(np.float32(v)) for v in row] for row in controller.sos],
           "meta": {k: v for k, v in meta.items() if k not in signals}}
    # sealed (a content SHA-256 that read_json checks) and written atomically
    return atomic_write(path, json.dumps(seal(doc), indent=1) + "\n")


def read_json(path, dtype="float64"):
    """Read a file of :func:`write_json`; the ``dtype`` coefficients as an SOSController.

    Raises
    ------
    ValueError
        Not such a file, its content differs from the checksum write_json
        stored in it (edited or corrupted), or its sections are not
        normalised (a0 != 1: the file names the section and the value;
        write_json always writes 1).

    Examples
    --------
    >>> import tempfile
    >>> Kd = ct.c2d(ct.tf([100], [1, 100]), 1e-3, "tustin")       # a 100 rad/s low-pass at 1 kHz
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_json(controller_sos(Kd, "K_lp"), Path(folder) / "K_lp.json")
    ...     c32 = read_json(path, dtype="float32")                   # what a float target runs
    >>> bool(np.array_equal(c32.sos, c32.sos.astype(np.float32))), c32.name   # float32 values
    (True, 'K_lp')
    """
    key = {"float64": "sos_float64", "float32": "sos_float32"}[_dtype(dtype).__name__]
    path = _path("path", path)
    try:
        doc = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"path {path} is not a JSON file: {exc}") from None
    if isinstance(doc, dict) and CONTENT_KEY in doc and (problem := seal_problem(doc)):
        # a file written by write_json and changed since (a hand-written one has no checksum)
        raise ValueError(f"path {path}: {problem}")
    try:
        sos, fs, name = np.array(doc[key], float), float(doc["fs_Hz"]), doc["name"]
    except (KeyError, TypeError, ValueError) as err:
        raise ValueError(f"path {path} is not a controller file of write_json "
                         f"(missing or bad {err})") from None
    try:
        sos = check_finite_array(key, sos, ndim=2, min_length=1, shape=(None, 6))
        bad = np.nonzero(sos[:, 3] != 1)[0]
        if bad.size:
            i = int(bad[0])
            raise ValueError(f"section {i} of {key} has a0 = {float(sos[i, 3])!r}, not 1 (sections "
                             "must be normalised; write_json writes a0 = 1)")
        return SOSController(sos, check_positive("fs_Hz", fs), name)
    except (ValueError, TypeError) as err:
        raise type(err)(f"path {path}: {err}") from None


def _c_rows(sos, fmt):
    return ",\n".join("    {" + ", ".join(fmt(v) for v in row) + "}" for row in sos)


def write_c_header(controller, path):
    """Write a C header with the sections in float and double and a DF-II-T step function.

    Parameters
    ----------
    controller : SOSController
    path : str or Path

    Returns
    -------
    Path

    Raises
    ------
    ExportError
        The float sections are marginal or unstable where the double ones are
        not (:meth:`SOSController.check_float32`); nothing is written.

    Warns
    -----
    ExportWarning
        The float sections' response is off by more than the rounding explains.

    Examples
    --------
    >>> import tempfile
    >>> Kd = ct.c2d(ct.tf([100], [1, 100]), 1e-3, "tustin")       # a 100 rad/s low-pass at 1 kHz
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_c_header(controller_sos(Kd, "K_lp"), Path(folder) / "K_lp.h")
    ...     text = path.read_text()
    >>> path.suffix, "K_lp" in text, "float" in text and "double" in text
    ('.h', True, True)
    """
    _check_controller(controller)
    path = _path("path", path)
    _check_float32(controller, controller.sos, "controller", stacklevel=2)
    return _write_c_header(controller, path)


def _write_c_header(controller, path, meta=None):
    n, N = controller.n_sections, controller.name.upper()
    f32 = controller.sos.astype(np.float32)
    guard = f"{N}_SOS_H"
    signals = _signals(meta or {})
    kind = "controller" if signals == _signals({}) else "filter"
    text = f"""/* {controller.name}: discrete {kind} {signals["input"]} -> {signals["output"]} at {controller.fs:g} Hz,
 * {n} second-order sections [b0, b1, b2, 1, a1, a2], Direct Form II transposed:
 *   y = b0 x + s1;  s1 = b1 x - a1 y + s2;  s2 = b2 x - a2 y  (per section, in order).
 * Generated by piezolib.robust.export; do not edit. */
#ifndef {guard}
#define {guard}

#define {N}_N_SECTIONS {n}
#define {N}_FS_HZ {controller.fs!r}

static const double {N}_SOS_F64[{n}][6] = {{
{_c_rows(controller.sos, lambda v: repr(float(v)))}
}};

static const float {N}_SOS_F32[{n}][6] = {{
{_c_rows(f32, lambda v: np.format_float_scientific(v, unique=True) + "f")}
}};

/* one sample through the float sections; state: {n} x 2 floats, zero at start */
static inline float {controller.name.lower()}_step_f32(float state[{n}][2], float x)
{{
    float y = x;
    for (int i = 0; i < {N}_N_SECTIONS; ++i) {{
        const float *c = {N}_SOS_F32[i];
        float u = y;
        y = c[0] * u + state[i][0];
        state[i][0] = c[1] * u - c[4] * y + state[i][1];
        state[i][1] = c[2] * u - c[5] * y;
    }}
    return y;
}}

#endif /* {guard} */
"""
    return atomic_write(path, text)


def export_controller(Kd, directory, name, meta=None, dtype="float32", rtol=None):
    """Export a discrete controller as ``<name>.json`` and ``<name>.h``; read it back.

    Parameters
    ----------
    Kd : control.StateSpace or control.TransferFunction
        Discrete SISO controller.
    directory : str or Path
        Folder of the two files (created if missing).
    name : str
        Base name of the files and of the C identifiers.
    meta : dict, optional
        Extra fields of the JSON file (e.g. the discretisation used).
    dtype : {"float32", "float64"}
        Precision of the controller returned, as the target would run it.
    rtol : float, optional
        Relative error of the float32 response allowed at every frequency
        (default: the first-order effect of the rounding, see
        :class:`Float32Check`).

    Returns
    -------
    SOSController
        The sections read back from the JSON file in ``dtype``: what is deployed.

    Raises
    ------
    ExportError
        ``dtype`` 'float32' and rounding to float32 makes a section marginal
        or unstable (nothing is written).  For ``dtype`` 'float64' that is
        an :class:`ExportWarning`: the float32 coefficients are only written
        alongside.

    Warns
    -----
    ExportWarning
        The float32 response differs from the float64 one by more than
        ``rtol`` (or than the rounding explains), with the worst error, its
        frequency and the DC gains.

    Examples
    --------
    >>> import tempfile
    >>> Kd = ct.c2d(ct.tf([100], [1, 100]), 1e-3, "tustin")       # a 100 rad/s low-pass at 1 kHz
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     deployed = export_controller(Kd, folder, "K_lp")
    ...     files = sorted(p.name for p in Path(folder).iterdir())
    >>> files, deployed.fs, deployed.sos.shape
    (['K_lp.h', 'K_lp.json'], 1000.0, (1, 6))
    >>> bool(np.array_equal(deployed.sos, deployed.sos.astype(np.float32)))   # float32 values
    True
    >>> round(float(deployed.sos[0, 4]), 4)                      # the pole at z = 0.9048
    -0.9048
    """
    directory = _path("directory", directory, directory=True)
    meta = _meta_json(meta)
    dtype = _dtype(dtype).__name__
    rtol = None if rtol is None else check_positive("rtol", rtol)
    sos = controller_sos(Kd, name)
    # one check for both files, before anything is written
    _check_float32(sos, sos.sos, "Kd", stacklevel=2, rtol=rtol, refuse=dtype == "float32")
    directory.mkdir(parents=True, exist_ok=True)
    path = _write_json(sos, directory / f"{name}.json", meta)
    _write_c_header(sos, directory / f"{name}.h", meta)
    return read_json(path, dtype)
