"""Case IV's feedforward: the stage's linear dynamics inverted with preview, then its hysteresis.

The virtual stage, like the paper's, is a hysteresis followed by linear
dynamics: v_y = G_n(s) H[u_c], with G_n = G / G(0) the dynamics of unit DC
gain and H the static hysteretic map (with G(0) inside it) that a hysteresis
model is fitted to.  Cases II–III invert H only (eq. 14), so the dynamics'
lag and ringing are left to the feedback, which one sample of computation
delay slows down.  :class:`TwoDofFeedforward` inverts both, in the order
the signal meets them backwards: w = G_n^-1 v_r by zero-phase-error tracking
with preview (:func:`piezolib.robust.preview.zpetc` on the exact ZOH model,
run as exported float32 sections), then u_f = H^-1 w (the hysteresis model's
feedforward).  The references of the tracking test are known in advance,
so the preview costs nothing.  With the feedback K on v_e = v_r - v_y it is
the two-degree-of-freedom loop of Case IV (:func:`two_dof_feedforward`;
``docs/controller_design.md`` argues the choice).

A :class:`TwoDofFeedforward` is itself a model of the stage with an inverse
(``simulate``: H, then G_n), so every experiment that takes a hysteresis
model runs it: Case II of :func:`piezolib.workbook.experiments.tracking_test`
becomes the 2-DOF feedforward alone and Case III the 2-DOF loop, Case IV.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib._checks import check_positive, check_siso, check_type
from piezolib.hysteresis.common import check_hysteresis_model
from piezolib.hysteresis.hammerstein import unit_dc_dynamics
from piezolib.robust.export import SOSController, controller_sos, sos_filter
from piezolib.robust.preview import PreviewFeedforward, zpetc

__all__ = ["TwoDofFeedforward", "dynamics_inverse", "two_dof_feedforward"]


@dataclass(frozen=True, eq=False)
class TwoDofFeedforward:
    """u_f = H^-1(F(z) v_r[k + preview]): dynamics inverse with preview, then hysteresis inverse.

    Attributes
    ----------
    dynamics : PreviewFeedforward
        ZPETC of the unit-DC-gain ZOH model G_n = G / G(0), v_r [V] -> w [V].
    sections : SOSController
        ``dynamics.F`` as second-order sections, run in float32 as a target would.
    model : HysteresisModel
        The hysteresis model (workbook convention v = u_c, x = v_y [V]) whose
        feedforward maps w to u_f.
    plant_b, plant_a : ndarray
        Direct-form coefficients of G_n's ZOH model (for :meth:`simulate`).

    Examples
    --------
    >>> import numpy as np
    >>> from piezolib.problem import paper
    >>> class Linear:                        # a hysteresis model without hysteresis
    ...     def simulate(self, v): return 0.9 * v
    ...     def feedforward(self, x_r): return x_r / 0.9
    >>> ff = two_dof_feedforward(paper.plant(), Linear(), 10e3)
    >>> v_r = np.ones(200)                    # 1 V step, known in advance
    >>> v_y = ff.simulate(ff.feedforward(v_r))
    >>> bool(np.abs(v_y[20:] - 1).max() < 1e-5)   # the stage it inverts follows v_r
    True
    """

    dynamics: PreviewFeedforward
    sections: SOSController
    model: object
    plant_b: np.ndarray
    plant_a: np.ndarray

    @property
    def preview(self):
        """Samples of the reference used ahead [samples]."""
        return self.dynamics.preview

    def dynamics_inverse(self, v_r):
        """w [V]: the reference through the float32 sections of G_n^-1, ``preview`` samples ahead."""
        return sos_filter(self.sections, self.dynamics.shifted(v_r), "float32")

    def feedforward(self, v_r):
        """u_f [V] for the reference v_r [V] (sensor volts, x_r = 3 um/V v_r)."""
        return self.model.feedforward(self.dynamics_inverse(v_r))

    def simulate(self, u_c):
        """The stage this feedforward inverts: v_y [V] = G_n(z) of the model's output."""
        return sg.lfilter(self.plant_b, self.plant_a, self.model.simulate(u_c))

    @property
    def static_part(self):
        """(g, x0) of the hysteresis model's static line (Case I applies it)."""
        return self.model.static_part


def dynamics_inverse(G, fs, radius=1.0):
    """ZPETC of the exact ZOH model of G / G(0) at ``fs`` (the dynamics Case IV inverts).

    Parameters
    ----------
    G : control.LTI
        Continuous SISO model u_c [V] -> v_y [V] with a finite nonzero DC gain.
    fs : float
        Loop rate [Hz].
    radius : float
        Passed to :func:`~piezolib.robust.preview.zpetc`.

    Returns
    -------
    PreviewFeedforward

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> F = dynamics_inverse(paper.plant(), 10e3)
    >>> type(F).__name__, F.preview           # samples of the reference used ahead
    ('PreviewFeedforward', 2)
    """
    fs = check_positive("fs", fs)
    return zpetc(ct.tf(*_unit_dc_zoh(G, fs), 1.0 / fs), radius=radius)


def _unit_dc_zoh(G, fs):
    """(b, a) of the exact ZOH model of G / G(0) at ``fs``, G checked (errors name it)."""
    check_siso("G", G)
    if not G.isctime(strict=True):
        raise ValueError("G must be a continuous-time model (u_c [V] -> v_y [V])")
    dc = float(np.real(ct.dcgain(G)))
    if not np.isfinite(dc) or dc == 0:
        raise ValueError(f"G must have a finite nonzero DC gain, got {dc!r}")
    return unit_dc_dynamics(G, fs)


def two_dof_feedforward(G, model, fs, radius=1.0, sections=None):
    """The Case IV feedforward for the plant G and a hysteresis model.

    Parameters
    ----------
    G : control.LTI
        Continuous SISO model u_c [V] -> v_y [V] with a nonzero DC gain (the
        study's identified or published G); only G / G(0) is inverted, the
        static gain belongs to the hysteresis model.
    model : HysteresisModel
        With ``feedforward(x_r)`` (the workbook's Dahl or PI model).
    fs : float
        Loop rate [Hz].
    radius : float
        Passed to :func:`~piezolib.robust.preview.zpetc`.
    sections : SOSController, optional
        The sections of the dynamics inverse as exported before (e.g. read
        from a committed JSON file, so that every machine runs the same
        float32 coefficients); checked against the ZPETC of G.  Default:
        factored here (:func:`~piezolib.robust.export.controller_sos`).

    Returns
    -------
    TwoDofFeedforward

    Raises
    ------
    ValueError
        ``sections`` at another rate, or whose response is not the ZPETC
        of G's dynamics (relative error above 1e-6 below 0.49 fs).

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> class Linear:
    ...     def simulate(self, v): return 0.9 * v
    ...     def feedforward(self, x_r): return x_r / 0.9
    >>> ff = two_dof_feedforward(paper.plant(), Linear(), 10e3)
    >>> ff.preview, ff.sections.fs
    (2, 10000.0)
    """
    fs = check_positive("fs", fs)
    b, a = _unit_dc_zoh(G, fs)
    dynamics = zpetc(ct.tf(b, a, 1.0 / fs), radius=radius)
    check_hysteresis_model("model", model)
    if sections is None:
        sections = controller_sos(ct.ss(dynamics.F), name="F_zpetc")
    else:
        _check_sections(sections, dynamics, fs)
    sections.check_float32(what="the dynamics inverse")
    return TwoDofFeedforward(dynamics, sections, model, b, a)


def _check_sections(sections, dynamics, fs):
    """Raise unless ``sections`` implement ``dynamics.F`` at ``fs`` (float64 coefficients)."""
    check_type("sections", sections, SOSController, "an SOSController (robust.export)")
    if not np.isclose(sections.fs, fs, rtol=1e-9):
        raise ValueError(f"sections run at {sections.fs:g} Hz, the loop at {fs:g} Hz")
    omega = 2 * np.pi * fs * np.linspace(0.001, 0.49, 200)
    want = np.ravel(dynamics.F(np.exp(1j * omega / fs)))
    err = np.abs(sections.frequency_response(omega) / want - 1).max()
    if not err < 1e-6:
        raise ValueError(f"sections do not implement the ZPETC of G's dynamics (largest "
                         f"relative error {err:.2g}): export them anew for this G and rate")
