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
"""

import json
import os
import re
from dataclasses import dataclass
from pathlib import Path

import control as ct
import numpy as np
import scipy.signal as sig

from piezolib._checks import (check_finite_array, check_finite_lti, check_integer, check_positive,
                              check_siso)

__all__ = ["SOSController", "controller_sos", "SectionFilter", "SectionFilterBatch",
           "sos_filter", "write_json",
           "read_json", "write_c_header", "export_controller"]

_DTYPES = {"float64": np.float64, "float32": np.float32}


@dataclass(frozen=True, eq=False)
class SOSController:
    """A discrete SISO controller as second-order sections.

    Attributes
    ----------
    sos : ndarray, shape (n_sections, 6)
        Rows [b0, b1, b2, 1, a1, a2], float64.
    fs : float
        Sampling rate [Hz].
    name : str
        Identifier (used for the C symbol names).
    """

    sos: np.ndarray
    fs: float
    name: str = "K"

    @property
    def n_sections(self):
        """Number of second-order sections."""
        return self.sos.shape[0]

    def coefficients(self, dtype="float64"):
        """The section matrix rounded to ``dtype`` ('float64' or 'float32')."""
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
        z = np.exp(1j * omega / self.fs)
        sos = self.coefficients(dtype).astype(np.float64)
        h = np.ones_like(z)
        for b0, b1, b2, _, a1, a2 in sos:
            h *= (b0 + b1 / z + b2 / z ** 2) / (1 + a1 / z + a2 / z ** 2)
        return h

    def to_statespace(self, dtype="float64"):
        """The sections (``dtype`` coefficients) as a control.StateSpace at dt = 1/fs."""
        sos = self.coefficients(dtype).astype(np.float64)
        sys = ct.tf([1.0], [1.0], 1.0 / self.fs)
        for row in sos:
            sys = sys * ct.tf(row[:3], row[3:], 1.0 / self.fs)
        return ct.ss(sys, inputs="v_e", outputs="u_b", name=self.name)


def _dtype(dtype):
    if dtype not in _DTYPES:
        raise ValueError(f"dtype must be one of {sorted(_DTYPES)}, got {dtype!r}")
    return _DTYPES[dtype]


def controller_sos(Kd, name="K"):
    """Second-order sections of a discrete SISO controller.

    Parameters
    ----------
    Kd : control.LTI
        Discrete-time SISO controller with a numeric sample time (e.g. the
        Tustin controller of :func:`piezolib.robust.discrete.discretize`).
    name : str
        Identifier: letters, digits and underscores, starting with a letter.

    Returns
    -------
    SOSController

    Raises
    ------
    ValueError
        A continuous-time or improper controller, a bad name, or a
        factorisation that does not reproduce K_d (relative error above
        1e-6 on a grid up to the Nyquist frequency).
    """
    check_siso("Kd", Kd)
    check_finite_lti("Kd", Kd)
    if not Kd.isdtime(strict=True) or Kd.dt is True:
        raise ValueError("Kd must be a discrete-time controller with a numeric sample time")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name):
        raise ValueError(f"name must be a C identifier, got {name!r}")
    fs = 1.0 / float(Kd.dt)
    K = ct.ss(Kd)
    poles = np.linalg.eigvals(K.A) if K.nstates else np.zeros(0)
    zeros = ct.zeros(K) if K.nstates else np.zeros(0)
    zeros = zeros[np.isfinite(zeros)]
    if zeros.size > poles.size:
        raise ValueError("Kd must be proper")
    theta = np.linspace(0.01, 0.99, 97) * np.pi
    z = np.exp(1j * theta)
    k_ref = np.ravel(K(z))
    shape = np.array([np.prod(zz - zeros) / np.prod(zz - poles) for zz in z])
    use = np.abs(shape) > 1e-300
    gain = np.median((k_ref[use] / shape[use]).real) if np.any(use) else 0.0
    if poles.size:
        delay = poles.size - zeros.size        # relative degree: zeros at z = 0 become z^-1
        sos = sig.zpk2sos(np.r_[zeros, np.zeros(delay)], poles, gain, pairing="nearest")
        for _ in range(delay):
            i = next(i for i, row in enumerate(sos) if row[2] == 0 and row[0] != 0)
            sos[i, :3] = [0.0, sos[i, 0], sos[i, 1]]
        sos = _split_real(sos)
    else:
        sos = np.array([[float(K.D[0, 0]), 0, 0, 1, 0, 0]])
    out = SOSController(np.asarray(sos, float), fs, name)
    err = np.max(np.abs(out.frequency_response(theta * fs) / k_ref - 1))
    if not err <= 1e-6:
        raise ValueError(f"the sections do not reproduce Kd (relative error {err:.2g}); "
                         "is Kd minimal?")
    return out


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


class SectionFilter:
    """Reference Direct Form II transposed implementation of the sections.

    Parameters
    ----------
    controller : SOSController or array_like
        The sections (or an (n, 6) section matrix).
    dtype : {'float64', 'float32'}
        Precision of the coefficients, the states and every operation.

    Examples
    --------
    >>> f = SectionFilter(np.array([[0.5, 0, 0, 1, -0.5, 0]]))
    >>> [round(f.step(1.0), 4) for _ in range(3)]
    [0.5, 0.75, 0.875]
    """

    def __init__(self, controller, dtype="float64"):
        sos = controller.sos if isinstance(controller, SOSController) else controller
        sos = check_finite_array("controller", sos, ndim=2, shape=(None, 6))
        if np.any(sos[:, 3] != 1):
            raise ValueError("controller sections must be normalised (a0 = 1)")
        self.dtype = _dtype(dtype)
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
        ref = SectionFilter(controller, dtype)          # checks the sections and dtype
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
        self.reset()

    def reset(self):
        """Zero the states."""
        self._s = np.zeros((2, len(self._b0), self.size), self.dtype)   # [s1; s2] per section

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
    """
    x = check_finite_array("x", x, ndim=1, min_length=1, real=True)
    f = SectionFilter(controller, dtype)
    return np.array([f.step(v) for v in x.tolist()])


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
    return meta


def write_json(controller, path, meta=None):
    """Write the sections (float64 and float32) and ``meta`` to a JSON file.

    Parameters
    ----------
    controller : SOSController
    path : str or Path
        File to write.
    meta : dict, optional
        JSON-serialisable extra information (units, origin, ...).

    Returns
    -------
    Path
    """
    if not isinstance(controller, SOSController):
        raise TypeError(f"controller must be an SOSController, got {type(controller).__name__}")
    doc = {"name": controller.name, "fs_Hz": controller.fs,
           "form": "second-order sections [b0, b1, b2, 1, a1, a2], Direct Form II transposed",
           "input": "v_e [V]", "output": "u_b [V]",
           "sos_float64": controller.sos.tolist(),
           # float32 values written as the exact decimal of the rounded number
           "sos_float32": [[float(np.float32(v)) for v in row] for row in controller.sos],
           "meta": _meta_json(meta)}
    path = _path("path", path)
    path.write_text(json.dumps(doc, indent=1) + "\n")
    return path


def read_json(path, dtype="float64"):
    """Read a file of :func:`write_json`; the ``dtype`` coefficients as an SOSController."""
    key = {"float64": "sos_float64", "float32": "sos_float32"}[_dtype(dtype).__name__]
    path = _path("path", path)
    try:
        doc = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"path {path} is not a JSON file: {exc}") from None
    try:
        sos, fs, name = np.array(doc[key], float), float(doc["fs_Hz"]), doc["name"]
    except (KeyError, TypeError) as err:
        raise ValueError(f"path {path} is not a controller file of write_json "
                         f"(missing {err})") from None
    return SOSController(check_finite_array("sos", sos, ndim=2, shape=(None, 6)),
                         check_positive("fs_Hz", fs), name)


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
    """
    if not isinstance(controller, SOSController):
        raise TypeError(f"controller must be an SOSController, got {type(controller).__name__}")
    n, N = controller.n_sections, controller.name.upper()
    f32 = controller.sos.astype(np.float32)
    guard = f"{N}_SOS_H"
    text = f"""/* {controller.name}: discrete controller v_e [V] -> u_b [V] at {controller.fs:g} Hz,
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
    path = _path("path", path)
    path.write_text(text)
    return path


def export_controller(Kd, directory, name, meta=None, dtype="float32"):
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

    Returns
    -------
    SOSController
        The sections read back from the JSON file in ``dtype``: what is deployed.
    """
    directory = _path("directory", directory, directory=True)
    meta = _meta_json(meta)
    sos = controller_sos(Kd, name)
    directory.mkdir(parents=True, exist_ok=True)
    path = write_json(sos, directory / f"{name}.json", meta=meta)
    write_c_header(sos, directory / f"{name}.h")
    return read_json(path, dtype)
