"""What rounding second-order sections to float32 does: :class:`Float32Check`.

A real-time target runs a controller's sections in float32.  Rounding the
coefficients moves each section's poles and zeros; near the unit circle a
pole can land on it (a lag becomes an integrator) or outside it.  The check
compares the float32 sections with the float64 ones (stability of each
section exactly, on its coefficients; the response at DC, over a grid up to
Nyquist and at every pole and zero frequency, against the first-order
rounding bound) and :meth:`Float32Check.enforce` refuses
(:class:`ExportError`) or warns (:class:`ExportWarning`) with numbers.
:mod:`piezolib.robust.export` applies it wherever sections become float32.
"""

import math
import warnings
from dataclasses import dataclass

import numpy as np

from piezolib._checks import check_positive

__all__ = ["Float32Check", "ExportError", "ExportWarning"]
# sections_response: shared with export.py, not part of the API


class ExportError(ValueError):
    """Rounding to float32 makes a stable (or marginal) section marginal (or unstable)."""


class ExportWarning(UserWarning):
    """The float32 sections differ from the float64 ones more than rounding explains."""


def sections_response(sos, z):
    """prod_i (b0 + b1/z + b2/z^2) / (a0 + a1/z + a2/z^2) at the points ``z``."""
    w = 1 / z
    h = np.ones_like(z)
    for b0, b1, b2, a0, a1, a2 in sos:
        h *= (b0 + b1 * w + b2 * w ** 2) / (a0 + a1 * w + a2 * w ** 2)
    return h


class ResponseError:
    """:attr:`max_error` and where it occurs, for a check holding ``error`` (relative error of
    the float32 response, NaN where undefined) on the grid ``omega``."""

    @property
    def max_error(self):
        """Largest relative error of the float32 response on the check grid."""
        return float(np.nanmax(self.error)) if np.any(np.isfinite(self.error)) else 0.0

    @property
    def omega_max_error(self):
        """Frequency of :attr:`max_error` [rad/s] (rad/sample when fs is None)."""
        if not np.any(np.isfinite(self.error)):
            return math.nan
        return float(self.omega[np.nanargmax(self.error)])


@dataclass(frozen=True, eq=False)
class Float32Check(ResponseError):
    """What rounding the sections to float32 does to the controller.

    The float32 response H32 is compared with the float64 one H64 at DC, at
    600 log-spaced frequencies up to Nyquist and at the frequency of every
    section pole and zero.  The tolerance at each frequency is, by default,
    the first-order effect of the rounding,

        bound = sum_i [ sum_k ulp(b_ik)/2 / |b_i| + sum_k ulp(a_ik)/2 / |a_i| ],

    (b_i, a_i the numerator and denominator of section i at e^{j omega/fs},
    ulp the float32 spacing, 0 for a coefficient float32 holds exactly): a
    sensitive section (a pole near z = 1) is allowed its large but
    predictable error; the error exceeds the bound only when the rounding is
    no longer a small perturbation of the sections.

    Attributes
    ----------
    name : str
        The controller's name.
    fs : float or None
        Sampling rate [Hz] (None: a bare section matrix, frequencies in rad/sample).
    omega : ndarray
        Check frequencies [rad/s] (rad/sample when fs is None).
    error : ndarray
        |H32 / H64 - 1| there (nan where H64 is 0 or infinite, e.g. at a
        zero on the unit circle or at the DC pole of an integrator).
    bound : ndarray
        The first-order bound there (dimensionless).
    dc_gain : tuple of float
        DC gain of the float64 and of the float32 sections (inf with a pole at z = 1).
    radius64, radius32 : ndarray
        Largest pole radius of each section in float64 and float32.
    stability64, stability32 : ndarray of int
        Each section's poles: 2 all strictly inside the unit circle, 1 some on
        it (marginal), 0 some outside; decided on the coefficients (|a2| < 1,
        |a1| < 1 + a2, or <=), not on computed roots.
    decay_change : ndarray
        For each pole (two per section), |d32 - d64| / d64 with d = 1 - |p|
        its distance to the unit circle (nan for a pole on or outside it).
    omega_pole : ndarray
        Frequency of each pole [rad/s] (rad/sample when fs is None).
    """

    name: str
    fs: float | None
    omega: np.ndarray
    error: np.ndarray
    bound: np.ndarray
    dc_gain: tuple
    radius64: np.ndarray
    radius32: np.ndarray
    stability64: np.ndarray
    stability32: np.ndarray
    decay_change: np.ndarray
    omega_pole: np.ndarray


    @classmethod
    def of(cls, sos, fs=None, name="K"):
        """The check of the (normalised, float64) section matrix ``sos`` at rate ``fs`` [Hz]."""
        sos32 = sos.astype(np.float32).astype(np.float64)
        poles64, poles32 = _section_poles(sos), _section_poles(sos32)
        angles = np.abs(np.angle(np.r_[poles64.ravel(), _section_zeros(sos)]))
        theta = np.unique(np.r_[0.0, np.geomspace(1e-6 * np.pi, np.pi, 600), angles])
        z = np.exp(1j * theta)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            h64, h32 = sections_response(sos, z), sections_response(sos32, z)
            error = np.abs(h32 - h64) / np.abs(h64)
            bound = _rounding_bound(sos, z)
            d64, d32 = 1 - np.abs(poles64), 1 - np.abs(poles32)
            decay = np.where(d64 > 0, np.abs(d32 - d64) / d64, np.nan)
        error[~(np.isfinite(h64) & (h64 != 0) & np.isfinite(error))] = np.nan
        scale = 1.0 if fs is None else fs
        return cls(name=name, fs=fs, omega=theta * scale, error=error, bound=bound,
                   dc_gain=(_dc_gain(sos), _dc_gain(sos32)),
                   radius64=np.max(np.abs(poles64), axis=1),
                   radius32=np.max(np.abs(poles32), axis=1),
                   stability64=_stability(sos), stability32=_stability(sos32),
                   decay_change=decay.ravel(),
                   omega_pole=np.abs(np.angle(poles64)).ravel() * scale)

    def enforce(self, rtol=None, what="controller", stacklevel=2, refuse=True):
        """Raise :class:`ExportError` or warn :class:`ExportWarning` as the check finds; self.

        Parameters
        ----------
        rtol : float, optional
            Relative error allowed at every frequency (default: :attr:`bound`).
        what : str
            Name of the argument the sections came from (for the messages).
        stacklevel : int
            Passed to :func:`warnings.warn`.
        refuse : bool
            Raise on a section made marginal or unstable (False: warn, for
            a float64 target, where the float32 coefficients are only written
            alongside).
        """
        tol = (self.bound if rtol is None
               else np.full_like(self.bound, check_positive("rtol", rtol)))
        told = "rtol" if rtol is not None else "the first-order effect of the rounding"
        unstable = self._unstable_message(what)
        if unstable and refuse:
            raise ExportError(unstable)
        if unstable:
            warnings.warn(unstable, ExportWarning, stacklevel=stacklevel)
        moved = self._moved_pole_message(tol, told, what)
        if moved:
            warnings.warn(moved, ExportWarning, stacklevel=stacklevel)
        with np.errstate(invalid="ignore"):
            over = np.nan_to_num(self.error / tol, nan=0.0)
        if np.any(over > 1):
            i = int(np.argmax(over))
            warnings.warn(
                f"{what}: rounding {self.name}'s sections to float32 changes its response by "
                f"{self.error[i]:.3g} (relative) at {self._where(self.omega[i])}, more than "
                f"{told} ({tol[i]:.3g}) allows; worst error {self.max_error:.3g} at "
                f"{self._where(self.omega_max_error)}; DC gain {self.dc_gain[0]:.7g} in "
                f"float64, {self.dc_gain[1]:.7g} in float32", ExportWarning,
                stacklevel=stacklevel)
        return self

    def _unstable_message(self, what):
        """The first section rounding makes marginal or unstable, in words ('' if none)."""
        worse = np.nonzero(self.stability32 < self.stability64)[0]
        if not worse.size:
            return ""
        i = int(worse[0])
        kinds = ("unstable", "marginal", "stable")
        r64, r32 = self.radius64[i], self.radius32[i]
        return (f"{what}: rounding to float32 makes section {i} of {self.name} "
                f"{kinds[self.stability32[i]]} (it is {kinds[self.stability64[i]]} in float64): "
                f"pole radius {r64:.12g} (1 - {1 - r64:.3g}) in float64, {r32:.12g} "
                f"(1 - {1 - r32:.3g}) in float32; a pole this close to the unit circle needs "
                "float64 sections (export_controller(..., dtype='float64'))")

    def _moved_pole_message(self, tol, told, what):
        """The pole whose distance to the unit circle moved most beyond ``tol``, in words."""
        # each pole's tolerance is the response tolerance at its own frequency (a grid point)
        at = np.minimum(np.searchsorted(self.omega, self.omega_pole), self.omega.size - 1)
        tol_p = tol[at]
        with np.errstate(invalid="ignore", divide="ignore"):
            over = np.nan_to_num(self.decay_change / tol_p, nan=0.0, posinf=0.0)
        if not np.any(over > 1):
            return ""
        j = int(np.argmax(over))
        return (f"{what}: rounding {self.name}'s sections to float32 moves pole {j % 2} of "
                f"section {j // 2} (at {self._where(self.omega_pole[j])}): its distance to the "
                f"unit circle changes by {self.decay_change[j]:.3g} (relative), more than "
                f"{told} ({tol_p[j]:.3g}) allows")

    def _where(self, omega):
        if self.fs is None:
            return f"{omega / np.pi:.4g} pi rad/sample"
        return "DC" if omega == 0 else f"{omega / (2 * np.pi):.4g} Hz"


def _section_poles(sos):
    """The two poles of each section, shape (n, 2) (a first-order section has one at 0)."""
    return np.array([np.roots(row[3:]) for row in sos], dtype=complex).reshape(-1, 2)


def _section_zeros(sos):
    """The finite zeros of all sections (flat)."""
    rows = [np.roots(row[:3]) for row in sos if np.any(row[:3] != 0)]
    return np.concatenate(rows).astype(complex) if rows else np.zeros(0, complex)


def _stability(sos):
    """2 (poles inside the unit circle), 1 (on it) or 0 (outside), per section.

    The Jury conditions of z^2 + a1 z + a2 on the coefficients themselves, so
    that a pole rounded exactly onto the circle is seen exactly.
    """
    a1, a2 = sos[:, 4], sos[:, 5]
    inside = (np.abs(a2) < 1) & (np.abs(a1) < 1 + a2)
    closed = (np.abs(a2) <= 1) & (np.abs(a1) <= 1 + a2)
    return np.where(inside, 2, np.where(closed, 1, 0))


def _half_ulp32(c):
    """Largest float32 rounding error of each coefficient (0 where float32 holds it exactly)."""
    c32 = c.astype(np.float32)
    return np.where(c32.astype(np.float64) == c, 0.0,
                    np.spacing(np.abs(c32)).astype(np.float64) / 2)


def _rounding_bound(sos, z):
    """First-order bound on |H32 / H64 - 1| at ``z``: sum of |d ln H / d c| ulp(c)/2."""
    h = _half_ulp32(sos)
    w = 1 / z
    powers = np.stack([np.ones_like(w), w, w ** 2])        # |w| = 1 on the unit circle
    bound = np.zeros(z.shape)
    for row, err in zip(sos, h):
        num, den = np.abs(row[:3] @ powers), np.abs(row[3:] @ powers)
        bound += err[:3].sum() / num + err[3:].sum() / den
    return bound


def _dc_gain(sos):
    """prod_i b_i(1) / a_i(1) (inf with a pole at z = 1)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.prod(sos[:, :3].sum(axis=1) / sos[:, 3:].sum(axis=1))
    return float(g) if np.isfinite(g) else math.inf
