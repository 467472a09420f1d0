"""The Table 4 Case I experiment on the virtual stage, and the stage's hysteresis calibrated on it.

Case I (open loop, no compensator) is the one experiment the hysteresis
truth is fitted to: :func:`case_I_input` (the triangle of the actuator
voltage), :func:`run_case_I` (the loops), :func:`case_I_hysteresis` (their
hysteresis %, eq. 25-26, as an experimenter measures it) and
:func:`calibrate_hysteresis` (the law's parameters re-derived from Table 4's
Case I row, the rule of ``docs/stage.md``).  They run stages; they are not
part of one: :mod:`piezolib.problem.stage` simulates whatever input it is
given and knows nothing of the paper's experiments, and the experiment files
recorded with these helpers are :mod:`piezolib.problem.stage_data`.
"""

import math
from collections.abc import Iterable
from dataclasses import replace

import numpy as np
import scipy.optimize as opt

from piezolib import signals
from piezolib._checks import check_integer, check_positive, check_type
from piezolib.hysteresis.measure import hysteresis_percent
from piezolib.problem import paper
from piezolib.problem.stage import StageRecord, StageSettings, VirtualStage
from piezolib.problem.stage_hysteresis import CALIBRATED_HYSTERESIS, HysteresisLaw

__all__ = ["case_I_input", "run_case_I", "case_I_hysteresis", "calibrate_hysteresis"]


def case_I_input(amplitude_V, stage=None, periods=3, frequency_Hz=None):
    """u_c [V] of the Table 4 experiment: a triangle of the actuator voltage
    from 0 to ``amplitude_V`` [V] (u_c from 0 to amplitude/gain).

    ``amplitude_V`` must lie within what the stage can drive: the DAC's top
    times the amplifier gain and the amplifier's output limit (120 V for the
    paper's stage); above it the run would be clipped, not a Case I loop.

    Examples
    --------
    >>> float(case_I_input(10.0).max())
    1.0
    """
    if stage is not None:
        check_type("stage", stage, VirtualStage, "a VirtualStage or None")
    settings = StageSettings() if stage is None else stage.settings
    gain = paper.AMPLIFIER_GAIN if stage is None else stage.gain
    fs = paper.SAMPLING_FREQUENCY_HZ if stage is None else stage.fs
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_Hz is None else frequency_Hz
    amplitude_V = check_positive("amplitude_V", amplitude_V)
    top_V = min(settings.dac_range_V[1] * gain, settings.amplifier_output_range_V[1])
    if amplitude_V > top_V:
        raise ValueError(f"amplitude_V must be at most {top_V:g} V (the stage's DAC range "
                         f"times its gain, within the amplifier's output), got {amplitude_V:g}")
    return signals.triangle(amplitude_V / gain, f, periods=periods, fs=fs)[1]


def run_case_I(stage, amplitudes_V=None, periods=3):
    """Run the Table 4 Case I experiment (open loop, no compensator).

    Parameters
    ----------
    stage : VirtualStage
    amplitudes_V : sequence of float, optional
        Actuator amplitudes [V], each positive; default Table 4's 10 ... 40 V.
    periods : int, optional
        Periods of the triangle per amplitude.

    Returns
    -------
    dict
        {actuator amplitude [V]: StageRecord}.

    Raises
    ------
    TypeError, ValueError
        Naming the argument, before any run: ``stage`` not a :class:`VirtualStage`,
        ``amplitudes_V`` empty or with an amplitude that is not positive, ``periods``
        not a positive integer.
    """
    check_type("stage", stage, VirtualStage, "a VirtualStage")
    amplitudes_V = _check_amplitudes(
        paper.HYSTERESIS_TEST["actuator_amplitudes_V"] if amplitudes_V is None
        else amplitudes_V)
    check_integer("periods", periods, minimum=1)
    return {A: stage.run(case_I_input(A, stage, periods)) for A in amplitudes_V}


def _check_amplitudes(amplitudes_V):
    """The amplitudes as floats, all checked before the first (slow) run."""
    if isinstance(amplitudes_V, (str, bytes)) or not isinstance(amplitudes_V, Iterable):
        raise TypeError("amplitudes_V must be a sequence of amplitudes [V], got "
                        f"{type(amplitudes_V).__name__}")
    amplitudes_V = [check_positive(f"amplitudes_V[{i}]", A) for i, A in enumerate(amplitudes_V)]
    if not amplitudes_V:
        raise ValueError("amplitudes_V must hold at least one amplitude, got none")
    return amplitudes_V


def case_I_hysteresis(records):
    """Hysteresis % (eq. 25-26) of each loop: measured displacement
    (3 um/V x v_y) against actuator voltage v_a, as an experimenter sees it.

    Parameters
    ----------
    records : dict
        {amplitude: StageRecord}, e.g. from :func:`run_case_I` or
        :func:`piezolib.problem.stage_data.load_hysteresis_loops`.

    Returns
    -------
    dict
        {amplitude [V]: hysteresis %}.

    Raises
    ------
    TypeError, ValueError
        ``records`` is not a non-empty dict of :class:`StageRecord`.
    """
    check_type("records", records, dict, "a dict {amplitude [V]: StageRecord}")
    if not records:
        raise ValueError("records must hold at least one StageRecord, got an empty dict")
    for A, rec in records.items():
        check_type(f"records[{A!r}]", rec, StageRecord, "a StageRecord")
    return {A: hysteresis_percent(rec.v_a_V, rec.x_measured_um) for A, rec in records.items()}


def _check_targets(targets):
    """{amplitude [V]: hysteresis [%]} with both positive and finite (log-parameter fit)."""
    if not isinstance(targets, dict) or not targets:
        raise TypeError(f"targets must be a non-empty dict {{amplitude [V]: %}}, got {targets!r}")
    return {check_positive("targets (amplitude)", A):
            check_positive(f"targets[{A!r}] (hysteresis %)", value)
            for A, value in targets.items()}


def calibrate_hysteresis(law=CALIBRATED_HYSTERESIS, targets=None):
    """Re-derive the hysteresis parameters from Table 4 Case I only.

    Least squares on (log c, log rho) of :class:`HysteresisLaw` so that the
    noise-free stage's Case I hysteresis % matches Table 4's first row.  The
    noise is switched off so that the parameters do not depend on one noise
    realisation; everything else (DAC, ADC, dynamics of G) is as in the
    experiment files.

    Parameters
    ----------
    law : HysteresisLaw, optional
        Starting point; its fixed fields (threshold grid) are kept.
    targets : dict, optional
        {amplitude [V]: %}; default Table 4 Case I.

    Returns
    -------
    law : HysteresisLaw
        Calibrated law (c and rho rounded to 6 significant digits).
    achieved : dict
        {amplitude: %} of the noise-free stage with that law.

    Raises
    ------
    TypeError, ValueError
        ``law`` not a :class:`HysteresisLaw`; ``targets`` not a dict of positive, finite
        amplitudes and percentages.
    """
    check_type("law", law, HysteresisLaw, "a HysteresisLaw")
    if targets is None:
        targets = paper.table4().loc["case_I"].to_dict()
    targets = _check_targets(targets)
    amplitudes = sorted(targets)
    want = np.array([targets[A] for A in amplitudes])

    def percents(law_):
        stage = VirtualStage(seed=0, noise_rms_V=0.0, hysteresis=law_)
        got = case_I_hysteresis(run_case_I(stage, amplitudes))
        return np.array([got[A] for A in amplitudes])

    def residual(p):
        return percents(replace(law, density_per_V=math.exp(p[0]), decay_V=math.exp(p[1]))) - want

    sol = opt.least_squares(residual, [math.log(law.density_per_V), math.log(law.decay_V)],
                            diff_step=1e-4, xtol=1e-10, ftol=1e-10)
    fitted = replace(law, density_per_V=float(f"{math.exp(sol.x[0]):.6g}"),
                     decay_V=float(f"{math.exp(sol.x[1]):.6g}"))
    return fitted, dict(zip(amplitudes, percents(fitted).tolist()))
