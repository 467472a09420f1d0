"""Argument checks shared by every piezolib module.

Each check raises a ``ValueError`` or ``TypeError`` whose message names the
argument and the expected form, so that bad input never reaches numpy,
scipy or SLICOT as a silent NaN or a deep traceback.
"""

import numbers
import os
from collections.abc import Mapping
from pathlib import Path

import control as ct
import numpy as np

__all__ = [
    "check_positive", "check_nonnegative", "check_finite_array", "check_siso",
    "check_lti", "check_stable", "check_proper", "check_same_length",
    "check_integer", "check_continuous", "check_finite_lti", "check_signals",
    "check_frequency_grid", "check_type", "check_path", "check_count", "check_bool",
    "check_positive_values", "check_integers", "check_band", "check_index_pair",
    "check_mapping", "check_real",
]


def check_type(name, value, types, what=None):
    """Return ``value`` after checking it is an instance of ``types``.

    ``what`` describes the expected kind in the message (default: the type names),
    so that a wrong object fails here, naming the argument, and not later as an
    AttributeError deep inside the computation.
    """
    if not isinstance(value, types):
        if what is None:
            names = [t.__name__ for t in (types if isinstance(types, tuple) else (types,))]
            what = " or ".join(names)
        raise TypeError(f"{name} must be {what}, got {type(value).__name__}")
    return value


def check_bool(name, value):
    """Return ``value`` after checking it is a bool (``"yes"`` or ``3`` is no flag)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_mapping(name, value, what="a dict", empty=False):
    """Return ``value`` after checking it is a mapping (and, unless ``empty``, not empty)."""
    if not isinstance(value, Mapping):
        raise TypeError(f"{name} must be {what}, got {type(value).__name__}")
    if not empty and not value:
        raise ValueError(f"{name} must not be empty")
    return value


def check_path(name, value):
    """Return ``value`` as a :class:`pathlib.Path` after checking it is a str or path."""
    if isinstance(value, bool) or not isinstance(value, (str, os.PathLike)) or value == "":
        raise TypeError(f"{name} must be a file path (str or pathlib.Path), got {value!r}")
    return Path(value)


def check_real(name, value):
    """Return ``value`` as a float after checking it is a finite real number (an offset,
    a level: any sign).

    Examples
    --------
    >>> check_real("x_offset", -2)
    -2.0
    """
    return _as_real_scalar(name, value)


def check_positive(name, value):
    """Return ``value`` as a float after checking it is finite and > 0."""
    value = _as_real_scalar(name, value)
    if not value > 0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    return value


def check_bisection_tol(name, value):
    """A bisection's (relative) tolerance as a float in [1e-12, 1).

    Below ~1e-12 a bisection on floats can stall between adjacent numbers and
    never meet the tolerance; 0 never ends at all.
    """
    value = check_positive(name, value)
    if not 1e-12 <= value < 1:
        raise ValueError(f"{name} must be in [1e-12, 1), got {value!r}")
    return value


def check_nonnegative(name, value):
    """Return ``value`` as a float after checking it is finite and >= 0."""
    value = _as_real_scalar(name, value)
    if value < 0:
        raise ValueError(f"{name} must be non-negative, got {value!r}")
    return value


def check_integer(name, value, minimum=None):
    """Return ``value`` as an int after checking it is an integer >= minimum."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {value!r}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return value


def check_count(name, value, maximum, minimum=1, why=None):
    """Return ``value`` as an int after checking ``minimum <= value <= maximum``.

    A size that comes from the user (rows, plays, members, samples) is bounded before
    any work starts: past ``maximum`` the computation would take minutes or gigabytes
    instead of failing clearly. ``why`` says what the limit protects (in the message).

    Examples
    --------
    >>> check_count("n_rows", 12, maximum=1000)
    12
    """
    value = check_integer(name, value, minimum=minimum)
    if value > maximum:
        reason = f" ({why})" if why else ""
        raise ValueError(f"{name} must be at most {maximum:,}{reason}, got {value:,}")
    return value


def check_positive_values(name, values, upper=None):
    """Return a non-empty 1-D float array of finite values > 0 (and < ``upper``, if given).

    Examples
    --------
    >>> check_positive_values("spreads", [0.02, 0.1], upper=1.0)
    array([0.02, 0.1 ])
    """
    if isinstance(values, (str, bytes)) or isinstance(values, numbers.Number):
        raise TypeError(f"{name} must be a sequence of positive numbers, got {values!r}")
    arr = check_finite_array(name, values, ndim=1, min_length=1, real=True)
    if np.any(arr <= 0):
        raise ValueError(f"{name} must be positive, got {arr[arr <= 0][0]!r}")
    if upper is not None and np.any(arr >= upper):
        raise ValueError(f"{name} must be below {upper}, got {arr[arr >= upper][0]!r}")
    return arr


def check_integers(name, values, minimum=None):
    """Return a non-empty list of ints, each >= ``minimum`` (orders, delays, sizes).

    Examples
    --------
    >>> check_integers("orders", (4, 6), minimum=1)
    [4, 6]
    """
    if isinstance(values, (str, bytes)) or isinstance(values, numbers.Number):
        raise TypeError(f"{name} must be a sequence of integers, got {values!r}")
    try:
        items = list(values)
    except TypeError:
        raise TypeError(f"{name} must be a sequence of integers, got "
                        f"{type(values).__name__}") from None
    if not items:
        raise ValueError(f"{name} must hold at least one integer, got none")
    return [check_integer(f"{name}[{i}]", v, minimum=minimum) for i, v in enumerate(items)]


def check_band(name, band):
    """Return a frequency band ``(low, high)`` as floats, 0 <= low < high, both finite.

    Examples
    --------
    >>> check_band("band_Hz", (5, 50))
    (5.0, 50.0)
    """
    if isinstance(band, (str, bytes)):
        raise TypeError(f"{name} must be a pair (low, high), got {band!r}")
    arr = check_finite_array(name, band, shape=(2,), real=True)
    low, high = float(arr[0]), float(arr[1])
    if low < 0 or high <= low:
        raise ValueError(f"{name} must be (low, high) with 0 <= low < high, got {tuple(arr)}")
    return low, high


def check_index_pair(name, pair, shape):
    """Return ``(i, j)`` as ints after checking 0 <= i < shape[0] and 0 <= j < shape[1].

    Examples
    --------
    >>> check_index_pair("pair", (0, 2), (3, 3))
    (0, 2)
    """
    if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
        raise TypeError(f"{name} must be a pair (output, input) of indices, got {pair!r}")
    i = check_integer(f"{name}[0]", pair[0], minimum=0)
    j = check_integer(f"{name}[1]", pair[1], minimum=0)
    if i >= shape[0] or j >= shape[1]:
        raise ValueError(f"{name} must index a {shape[0]} x {shape[1]} (outputs x inputs) "
                         f"model, got {(i, j)}")
    return i, j


def check_finite_array(name, x, ndim=None, min_length=None, shape=None, real=False):
    """Return ``x`` as a float (or complex) array after checking its form.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    x : array_like
        Values to check.
    ndim : int, optional
        Required number of dimensions.
    min_length : int, optional
        Required minimum length of the first axis.
    shape : tuple, optional
        Required shape; ``None`` entries match any size.
    real : bool, optional
        Reject complex input (signals, states): a later ``astype(float)``
        would otherwise drop the imaginary part with only a warning.
    """
    try:
        arr = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"{name} must be array-like: {exc}") from None
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.number):
        raise TypeError(f"{name} must be numeric, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.complexfloating):
        if real:
            raise TypeError(f"{name} must be real-valued, got complex dtype {arr.dtype}")
    else:
        arr = arr.astype(float)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    if shape is not None:
        if arr.ndim != len(shape) or any(
                want is not None and want != got for want, got in zip(shape, arr.shape)):
            want = tuple("any" if s is None else s for s in shape)
            raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    if min_length is not None and (arr.ndim == 0 or arr.shape[0] < min_length):
        got = 0 if arr.ndim == 0 else arr.shape[0]
        raise ValueError(f"{name} must have at least {min_length} samples, got {got}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise ValueError(f"{name} contains {bad} non-finite value(s) (NaN or inf)")
    return arr


def check_same_length(**arrays):
    """Check that all keyword arrays have the same first-axis length."""
    lengths = {name: len(a) for name, a in arrays.items()}
    if len(set(lengths.values())) > 1:
        desc = ", ".join(f"{n} has {k}" for n, k in lengths.items())
        raise ValueError(f"arguments must have equal lengths: {desc}")


def check_signals(min_length=2, **signals):
    """Check named 1-D finite signals of one record; return them as arrays.

    Each must be 1-D, finite and at least ``min_length`` long, and all must
    have the same length; errors name the argument(s).
    """
    arrays = tuple(check_finite_array(name, x, ndim=1, min_length=min_length, real=True)
                   for name, x in signals.items())
    check_same_length(**dict(zip(signals, arrays)))
    return arrays


def check_frequency_grid(name, omega, min_length=2):
    """Return a 1-D, finite, positive and strictly increasing frequency grid [rad/s]."""
    omega = check_finite_array(name, omega, ndim=1, min_length=min_length, real=True)
    if np.any(omega <= 0) or np.any(np.diff(omega) <= 0):
        raise ValueError(f"{name} must be positive and increasing [rad/s]")
    return omega


def check_lti(name, sys):
    """Check that ``sys`` is a python-control LTI system."""
    if not isinstance(sys, ct.LTI):
        raise TypeError(
            f"{name} must be a control.TransferFunction or control.StateSpace, "
            f"got {type(sys).__name__}")
    return sys


def check_finite_lti(name, sys):
    """Check that every coefficient / matrix entry of LTI ``sys`` is finite.

    A NaN coefficient otherwise surfaces far away (python-control reports an
    "algebraic loop", SLICOT a bare error code).
    """
    check_lti(name, sys)
    if isinstance(sys, ct.TransferFunction):
        parts = [(f"{kind}[{i}][{j}]", c) for kind, poly in (("num", sys.num), ("den", sys.den))
                 for i, row in enumerate(poly) for j, c in enumerate(row)]
    else:
        parts = [(m, getattr(sys, m)) for m in ("A", "B", "C", "D")]
    for part, values in parts:
        values = np.asarray(values)
        if not np.all(np.isfinite(values)):
            kind = "NaN" if np.any(np.isnan(values)) else "inf"
            raise ValueError(f"{name} has a {kind} coefficient (in {name}.{part})")
    return sys


def check_continuous(name, sys):
    """Check that ``sys`` is a continuous-time LTI system (dt = 0 or None).

    Discrete-time models otherwise silently lose their sample time when
    realised in scaled time.
    """
    check_lti(name, sys)
    if sys.isdtime(strict=True):
        raise ValueError(f"{name} must be continuous-time, got a discrete-time model "
                         f"(dt={sys.dt}); pass the continuous-time model (discretise results "
                         "afterwards, e.g. with piezolib.robust.discrete)")
    return sys


def check_model(name, sys, proper=False):
    """Check a continuous-time LTI model with finite coefficients (and, optionally, proper)."""
    check_finite_lti(name, sys)
    check_continuous(name, sys)
    if proper:
        check_proper(name, sys)
    return sys


def check_channels(P, nmeas, ncon):
    """(nmeas, ncon) as ints, checked to leave ``P`` at least one performance output and input.

    ``P`` is a generalized plant whose last ``nmeas`` outputs are measurements
    and last ``ncon`` inputs controls.
    """
    nmeas = check_integer("nmeas", nmeas, minimum=1)
    ncon = check_integer("ncon", ncon, minimum=1)
    if nmeas >= P.noutputs:
        raise ValueError(f"nmeas={nmeas} leaves no performance output: P has "
                         f"{P.noutputs} outputs")
    if ncon >= P.ninputs:
        raise ValueError(f"ncon={ncon} leaves no performance input: P has {P.ninputs} inputs")
    return nmeas, ncon


def check_siso(name, sys):
    """Check that ``sys`` is a single-input single-output LTI system."""
    check_lti(name, sys)
    if sys.ninputs != 1 or sys.noutputs != 1:
        raise ValueError(
            f"{name} must be SISO, got {sys.noutputs} outputs x {sys.ninputs} inputs")
    return sys


def check_proper(name, sys):
    """Check that a transfer function is proper (deg num <= deg den)."""
    check_lti(name, sys)
    if isinstance(sys, ct.TransferFunction):
        for i in range(sys.noutputs):
            for j in range(sys.ninputs):
                num = np.trim_zeros(np.atleast_1d(sys.num[i][j]), "f")
                den = np.trim_zeros(np.atleast_1d(sys.den[i][j]), "f")
                if len(num) > len(den):
                    raise ValueError(
                        f"{name} must be proper: numerator degree {len(num) - 1} "
                        f"exceeds denominator degree {len(den) - 1}")
    return sys


def check_stable(name, sys):
    """Check that a continuous-time LTI system has all poles in Re s < 0."""
    check_lti(name, sys)
    poles = ct.poles(sys)
    if sys.isctime(strict=False):
        bad = poles[poles.real >= 0]
    else:
        bad = poles[np.abs(poles) >= 1]
    if bad.size:
        raise ValueError(f"{name} must be stable; unstable poles: {np.round(bad, 6)}")
    return sys


def _as_real_scalar(name, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return value
