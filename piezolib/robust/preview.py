"""Reference feedforward with preview: zero-phase-error tracking (ZPETC) of a discrete plant.

When the reference is known ahead of time (a scanning trajectory, the
triangles of a tracking test), a feedforward can invert the plant's model
instead of waiting for the feedback to react.  A sampled plant of relative
degree three or more has zeros outside the unit circle (the sampling zeros
of the ZOH), whose exact inverse is unstable.  Tomizuka's ZPETC cancels the
poles and the zeros inside the unit circle and replaces the inverse of each
zero outside it by its mirror image, so that the model's response to the
feedforward has zero phase at every frequency and a gain that is exactly 1
at DC and falls off only near the Nyquist frequency.  The feedforward is a
causal filter F(z) run on the reference ``preview`` samples ahead:
u_ff[k] = F(z) r[k + preview].

Derivation and choice against the alternatives: ``docs/controller_design.md``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib._checks import check_finite_array, check_positive, check_siso

__all__ = ["PreviewFeedforward", "zpetc"]


@dataclass(frozen=True, eq=False)
class PreviewFeedforward:
    """A causal filter run on the reference ``preview`` samples ahead.

    Attributes
    ----------
    F : control.TransferFunction
        The causal filter at the plant's sample time, r -> u_ff (biproper).
    preview : int
        Samples of the reference needed ahead: u_ff[k] = F(z) r[k + preview].
    tracking : control.TransferFunction
        What the plant's model gives from the reference when driven by u_ff:
        G_d(z) F(z) z^preview, real and positive on the unit circle (zero
        phase), 1 at DC.
    cancelled_zeros, mirrored_zeros : ndarray
        The plant's zeros inverted exactly (inside ``radius``) and those
        whose inverse is replaced by their mirror image.
    """

    F: ct.TransferFunction
    preview: int
    tracking: ct.TransferFunction
    cancelled_zeros: np.ndarray
    mirrored_zeros: np.ndarray

    @property
    def dt(self):
        """Sample time [s]."""
        return float(self.F.dt)

    def apply(self, r):
        """The feedforward of a whole reference known in advance.

        The filter starts from rest (zero state), so the reference should
        start where the plant rests; past its end the reference is held at
        its last value for the ``preview`` samples the filter looks ahead.

        Parameters
        ----------
        r : array_like
            Reference samples (1-D, finite) in the plant's output unit.

        Returns
        -------
        ndarray
            u_ff in the plant's input unit, same length as ``r``.
        """
        num, den = _coefficients(self.F)
        return sg.lfilter(num, den, self.shifted(r))

    def shifted(self, r):
        """The reference ``preview`` samples ahead, r[k + preview] (held at its end):
        the input of :attr:`F` (for running F elsewhere, e.g. as exported sections)."""
        r = check_finite_array("r", r, ndim=1, min_length=2, real=True)
        return np.concatenate([r[self.preview:], np.full(min(self.preview, len(r)), r[-1])])


def _coefficients(tf):
    return (np.asarray(tf.num[0][0], dtype=float), np.asarray(tf.den[0][0], dtype=float))


def zpetc(Gd, radius=1.0):
    """Zero-phase-error tracking feedforward of a discrete SISO plant (Tomizuka, 1987).

    With G_d(z) = b_a(z) b_u(z) / a(z) (b_a: zeros inside ``radius``, b_u:
    the others, monic, of degree s) and relative degree d,

        F(z) = a(z) b_u*(z) / (b_lead b_a(z) b_u(1)^2 z^(d + 2 s)),

    b_u*(z) = z^s b_u(1/z) (coefficients reversed), so that
    G_d(z) F(z) z^(d + s) = b_u(z) b_u*(z) / (b_u(1)^2 z^s): zero phase,
    gain 1 at DC.  The preview is d + s samples.

    Parameters
    ----------
    Gd : control.LTI
        Discrete SISO proper plant with a sample time, e.g. the ZOH model
        of a continuous plant (``control.c2d(G, dt, "zoh")``).  Its poles
        may lie anywhere (they become zeros of F); it must have at least
        one zero or a relative degree >= 1, and no zero at z = 1.
    radius : float
        Zeros with |z| < radius are inverted exactly (default 1: every
        stable zero); a smaller radius also mirrors lightly damped stable
        zeros, whose exact inverse would ring.

    Returns
    -------
    PreviewFeedforward

    Raises
    ------
    ValueError
        A continuous-time or non-finite plant, a zero numerator, a zero at
        z = 1 (the plant blocks DC: no feedforward tracks a constant), or a
        cancelled zero on which F would have a pole outside ``radius``.

    Examples
    --------
    >>> import control as ct
    >>> Gd = ct.c2d(ct.tf([1], [1, 2, 1]), 0.1, "zoh")
    >>> ff = zpetc(Gd)
    >>> ff.preview, abs(complex(ff.tracking(1.0)))
    (1, 1.0)
    """
    check_siso("Gd", Gd)
    if Gd.isctime(strict=False) or Gd.dt is True:
        raise ValueError(f"Gd must be a discrete-time model with a sample time, got dt = {Gd.dt!r}")
    radius = check_positive("radius", radius)
    if radius > 1:
        raise ValueError(f"radius must be at most 1 (an inverted zero outside the unit circle "
                         f"is an unstable pole of F), got {radius!r}")
    tf = ct.tf(Gd)
    num = np.trim_zeros(np.asarray(tf.num[0][0], dtype=float), "f")
    den = np.trim_zeros(np.asarray(tf.den[0][0], dtype=float), "f")
    if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise ValueError(f"Gd must have finite coefficients, got numerator {tf.num[0][0]} and "
                         f"denominator {tf.den[0][0]}")
    if num.size == 0:
        raise ValueError(f"Gd is identically zero (numerator {tf.num[0][0]}): no feedforward "
                         f"inverts it; a high-order plant can lose its numerator in a transfer "
                         f"function conversion (ct.c2d of a tf): discretise its state space")
    d = len(den) - len(num)
    if d < 0:
        raise ValueError("Gd must be proper")
    lead = num[0] / den[0]
    den = den / den[0]
    zeros = np.roots(num)
    near_one = np.abs(zeros - 1.0)
    if np.any(near_one <= _UNIT_ZERO_DISTANCE):
        raise ValueError(f"Gd has a zero at z = 1 (within {near_one.min():.1e}): it blocks "
                         "constant inputs, so no feedforward can track a constant reference "
                         "(its inverse would need a gain of order 1/distance^2)")
    inside = np.abs(zeros) < radius
    b_a, b_u = (np.atleast_1d(np.real(np.poly(z))) for z in (zeros[inside], zeros[~inside]))
    s = int(np.count_nonzero(~inside))
    # F = a b_u* / (lead b_a b_u(1)^2 z^(d + 2s)): biproper (degrees n + s both sides)
    F_num = np.polymul(den, b_u[::-1]) / (lead * np.polyval(b_u, 1.0) ** 2)
    F_den = np.polymul(b_a, np.r_[1.0, np.zeros(d + 2 * s)])
    dt = Gd.dt
    F = ct.tf(F_num, F_den, dt, inputs="r_ahead", outputs="u_ff", name="F_zpetc")
    # G_d F z^(d + s) = b_u(z) b_u*(z) / (b_u(1)^2 z^s)
    tracking = ct.tf(np.polymul(b_u, b_u[::-1]) / np.polyval(b_u, 1.0) ** 2,
                     np.r_[1.0, np.zeros(s)], dt, inputs="r", outputs="y_model",
                     name="zero_phase")
    _check_zero_phase(Gd, F, tracking, d + s)
    return PreviewFeedforward(F=F, preview=d + s, tracking=tracking,
                              cancelled_zeros=zeros[inside], mirrored_zeros=zeros[~inside])


#: Zeros closer than this to z = 1 are refused: the ZPETC's DC normalisation divides by
#: the square of their distance.
_UNIT_ZERO_DISTANCE = 1e-6
#: Relative error allowed between G_d F z^p and the zero-phase ``tracking`` it must equal.
_ZERO_PHASE_RTOL = 1e-6


def _check_zero_phase(Gd, F, tracking, preview):
    """Raise unless G_d F z^preview equals ``tracking`` (real, 1 at DC) on a grid: the
    factorisation can lose that to rounding (zeros near z = 1, ill-conditioned roots)."""
    w = np.linspace(0.0, np.pi, 64)
    z = np.exp(1j * w)
    got = np.ravel(Gd(z)) * np.ravel(F(z)) * z ** preview
    want = np.ravel(tracking(z))
    scale = max(1.0, np.abs(want).max())
    error = max(np.abs(got - want).max(), np.abs(want.imag).max(), abs(want[0] - 1.0)) / scale
    if not error <= _ZERO_PHASE_RTOL:
        raise ValueError(f"the ZPETC of Gd is numerically unreliable: G_d F z^{preview} "
                         f"differs from its zero-phase target by {error:.2g} (relative), F's "
                         f"gain reaches {np.abs(np.ravel(F(z))).max():.3g}; zeros of Gd near "
                         "z = 1 or badly conditioned coefficients (balance or reduce the "
                         "model first)")
