"""The hysteresis model chosen for this stage: the Dahl candidates fitted to Case I, and the
Dahl and Prandtl-Ishlinskii models compared on records neither was fitted to.

:func:`case_I_fits` fits every candidate of
:data:`~piezolib.problem.hysteresis_fits.CASE_I_CANDIDATES` jointly to the
four Case I loops and applies the selection rule (:class:`CaseIFits`, its
parameter table and checks); :func:`lower_reversals` is where the loops sit
at v = 0 (the offset eq. 13 lacks), :func:`start_effect` what the initial
state changes after the first period, :func:`implied_unit_scale` whether a
unit of x could turn one parameter set into the other, and
:func:`per_amplitude_fits` the chosen configuration fitted to each loop alone.
:func:`compare_models` scores the workbook Dahl model, the fit of eq. 10-13 as
printed and the PI model on :func:`~piezolib.problem.hysteresis_fits.validation_loops`.
Notebook 03, sections 3 and 6; background in ``docs/hysteresis.md``.
"""

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from piezolib._checks import check_type
from piezolib.hysteresis.dahl import simulate_dahl
from piezolib.hysteresis.fit import DahlFit, choose_fit, fit_dahl
from piezolib.hysteresis.select import pooled_rms, validation_table
from piezolib.problem import paper
from piezolib.problem.hysteresis_fits import (CASE_I_CANDIDATES, PI_PLAYS, WORKBOOK_DAHL,
                                              fit_case_I_loops, validation_loops,
                                              workbook_dahl_fit, workbook_pi_fit)

__all__ = ["PAPER_FORM", "BLIMAN_SORINE_PAPER", "PI_NAME", "DAHL_NAME", "PRINTED_NAME",
           "candidate_label", "case_I_loops", "CaseIFits", "case_I_fits", "Finding",
           "lower_reversals", "start_effect", "implied_unit_scale", "PerAmplitudeFits",
           "per_amplitude_fits", "ModelComparison", "compare_models"]

#: The candidate that is eq. 10-13 exactly as printed (sign inside A_H, no offset, virgin).
PAPER_FORM = ("printed", False, "virgin")
#: The sign term in Bliman-Sorine position, nothing else added.
BLIMAN_SORINE_PAPER = ("bliman_sorine", False, "virgin")
#: Names of the models compared by validation (rows of :class:`ModelComparison`).
PI_NAME = f"PI ({PI_PLAYS} plays)"
DAHL_NAME = "workbook Dahl"
PRINTED_NAME = "eq. 10-13 as printed"


def _period():
    """Samples per 10 Hz period of the Table 4 triangle at the DAQ rate."""
    return int(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"])


def candidate_label(key):
    """A (form, offset, start) candidate as text, e.g. ``"bliman-sorine, offset, rest"``.

    Examples
    --------
    >>> candidate_label(("printed", False, "virgin"))
    'printed, no offset, virgin'
    """
    if not (isinstance(key, tuple) and len(key) == 3 and isinstance(key[0], str)
            and isinstance(key[2], str)):
        raise TypeError(f"key must be a (form, offset, start) tuple, got {key!r}")
    form, offset, start_state = key
    return f"{form.replace('_', '-')}, {'offset' if offset else 'no offset'}, {start_state}"


def case_I_loops():
    """The Table 4 Case I experiment files of ``data/``: {amplitude [V]: StageRecord}
    (:func:`piezolib.problem.stage_data.load_hysteresis_loops`)."""
    from piezolib.problem import stage_data     # lazy: the stage modules are heavier than this one
    return stage_data.load_hysteresis_loops()


@dataclass(frozen=True)
class CaseIFits:
    """Every Dahl candidate fitted jointly to the Case I loops, and the one chosen.

    Attributes
    ----------
    loops : dict
        {actuator amplitude [V]: StageRecord} of the Case I files.
    fits : dict
        {(form, offset, start): DahlFit}, one per candidate.
    choice : tuple
        The candidate :func:`piezolib.hysteresis.choose_fit` selects (smallest
        pooled RMS error on Case I).
    workbook : DahlFit
        The workbook's shared feedforward model
        (:func:`~piezolib.problem.hysteresis_fits.workbook_dahl_fit`).
    """

    loops: dict
    fits: dict
    choice: tuple
    workbook: DahlFit

    @property
    def amplitudes(self):
        """The actuator amplitudes [V] of the loops, in order."""
        return tuple(self.loops)

    @property
    def fit_data(self):
        """The loops as (u_c [V], v_y [V]) pairs, in the order of :attr:`amplitudes`."""
        return [(rec.u_c_V, rec.v_y_V) for rec in self.loops.values()]

    @property
    def paper_form(self):
        """The fit of eq. 10-13 as printed (:data:`PAPER_FORM`)."""
        return self.fits[PAPER_FORM]

    def parameter_table(self):
        """One row per candidate: its parameters, bounds reached and RMS / max errors
        [% of each loop's range] per amplitude and pooled."""
        rows = {}
        for key, fit in self.fits.items():
            m = fit.model
            row = {"alpha1 [1/V]": m.alpha1, "alpha2 [1/V^2]": m.alpha2,
                   "lambda = alpha2/alpha1 [1/V]": m.alpha2 / m.alpha1, "zeta": m.damping,
                   "beta2": m.beta2, "g_a [V/V]": m.g_a, "x0 [V]": m.x0,
                   "H steady [V]": m.steady_state(1),
                   "on a bound": int(np.count_nonzero(fit.result.active_mask))}
            for A, rms, worst in zip(self.amplitudes, fit.rms_percent, fit.max_percent):
                row[f"RMS % {A:.0f} V"] = rms
                row[f"max % {A:.0f} V"] = worst
            row["pooled RMS %"] = fit.pooled_rms_percent
            rows[candidate_label(key)] = row
        return pd.DataFrame(rows).T

    @property
    def selection_checks(self):
        """What the notebook states of the choice and the fits, each with whether it holds."""
        by_worst = min(self.fits, key=lambda key: self.fits[key].worst_rms_percent)
        return {
            "the rule picks the candidate the workbook shares": self.choice == WORKBOOK_DAHL,
            "the worst-loop RMS picks the same candidate": by_worst == self.choice,
            "the workbook model is an interior optimum":
                not bool(self.workbook.result.active_mask.any()),
            "Bliman-Sorine without offset: alpha1 at the first-order bound":
                bool(self.fits[BLIMAN_SORINE_PAPER].result.active_mask[1] == 1),
            "workbook model: close match, RMS < 2.5 % at every amplitude":
                bool(np.all(self.workbook.rms_percent < 2.5)),
            "eq. 10-13 as printed: RMS > 2 % at every amplitude":
                bool(np.all(self.paper_form.rms_percent > 2)),
            "the printed form has no use for an offset (|x0| < 0.01 V)":
                bool(abs(self.fits[("printed", True, "virgin")].model.x0) < 0.01),
        }

    @property
    def gain_checks(self):
        """What the notebook states of g_a and x0, each with whether it holds."""
        model = self.workbook.model
        return {
            "eq. 10-13 as printed: 0.85 < g_a < 1.0 (paper 0.925)":
                0.85 < self.paper_form.model.g_a < 1.0,
            "workbook model: 1.0 < g_a < 1.5 (the saturated branches' slope)":
                1.0 < model.g_a < 1.5,
            "workbook model: -0.3 V < x0 < 0 (below the symmetric Dahl loop)":
                -0.3 < model.x0 < 0.0,
        }


def case_I_fits(loops=None):
    """Fit every candidate jointly to the Case I loops and choose the feedforward model.

    Parameters
    ----------
    loops : dict, optional
        {amplitude [V]: StageRecord}, the Case I files as read by
        :func:`case_I_loops` (default: read them).  The fits read the same
        files themselves (:func:`~piezolib.problem.hysteresis_fits.fit_case_I_loops`,
        cached in-process).

    Returns
    -------
    CaseIFits
    """
    loops = case_I_loops() if loops is None else check_type("loops", loops, dict,
                                                            "a dict {amplitude: StageRecord}")
    if not loops:
        raise ValueError("loops must hold at least one Case I loop, got an empty dict")
    for A, rec in loops.items():
        if not hasattr(rec, "v_y_V"):
            raise TypeError(f"loops[{A!r}] must be a StageRecord, got {type(rec).__name__}")
    fits = {key: fit_case_I_loops(*key) for key in CASE_I_CANDIDATES}
    return CaseIFits(loops, fits, choose_fit(fits), workbook_dahl_fit())


def _check_fits(case_I):
    return check_type("case_I", case_I, CaseIFits, "a CaseIFits (case_I_fits())")


@dataclass(frozen=True)
class Finding:
    """A table the notebook shows and what it states of it.

    Attributes
    ----------
    table : pandas.DataFrame
    checks : dict
        {what it states: bool}.
    """

    table: pd.DataFrame
    checks: dict


def lower_reversals(case_I):
    """Where the loops sit at v = 0: the stage against the Bliman-Sorine fit without offset.

    Parameters
    ----------
    case_I : CaseIFits

    Returns
    -------
    Finding
        Per amplitude: the stage's x at the lower reversals after periods 2
        and 3 [V], the fit's, and the loop's range [V]; checks that the stage
        is back at (nearly) zero and the Dahl loop at +h.
    """
    case_I = _check_fits(case_I)
    period = _period()
    reversals = [2 * period, 3 * period]                 # v = 0 after periods 2 and 3
    bliman_sorine = case_I.fits[BLIMAN_SORINE_PAPER]
    tips = pd.DataFrame({f"{A:.0f} V": {
        "stage: x at v = 0 [V]": float(np.mean(rec.v_y_V[reversals])),
        "Bliman-Sorine fit without offset [V]":
            float(np.mean(bliman_sorine.x_model[k][reversals])),
        "loop range [V]": float(np.ptp(rec.v_y_V[period:]))}
        for k, (A, rec) in enumerate(case_I.loops.items())}).T
    checks = {
        "the stage is back at (nearly) 0 at every lower reversal (|x| < 0.03 V)":
            bool((tips["stage: x at v = 0 [V]"].abs() < 0.03).all()),
        "the Dahl loop without offset sits at +h there (> 0.07 V)":
            bool((tips["Bliman-Sorine fit without offset [V]"] > 0.07).all()),
    }
    return Finding(tips, checks)


def start_effect(case_I):
    """The chosen model run from the virgin state instead of from rest.

    Parameters
    ----------
    case_I : CaseIFits

    Returns
    -------
    Finding
        The largest difference in periods 2 and 3 [% of each loop's range],
        one column per amplitude; checks that it is below 0.5 % in period 3
        and below 0.1 % at 20-40 V.
    """
    case_I = _check_fits(case_I)
    period, model = _period(), case_I.workbook.model
    virgin = replace(model, start="virgin")
    effect = {}
    for (A, rec), (u, v_y) in zip(case_I.loops.items(), case_I.fit_data):
        diff = np.abs(simulate_dahl(model, u).x - simulate_dahl(virgin, u).x)
        span = np.ptp(v_y[period:])
        effect[f"{A:.0f} V"] = {
            "period 2 [% of range]": 100 * diff[period:2 * period].max() / span,
            "period 3 [% of range]": 100 * diff[2 * period:].max() / span}
    effect = pd.DataFrame(effect)
    checks = {
        "period 3: the start changes < 0.5 % of the range":
            bool(effect.loc["period 3 [% of range]"].max() < 0.5),
        "20-40 V: the start changes < 0.1 % after the first period":
            bool((effect.iloc[:, 1:] < 0.1).all().all()),
    }
    return Finding(effect, checks)


def implied_unit_scale(case_I):
    """The unit factor k (x_pub = x / k) that alpha1 and alpha2 would each imply.

    alpha1 scales with k and alpha2 with k^2, so one parameter set is another
    in a different unit of x only if the two agree.

    Parameters
    ----------
    case_I : CaseIFits

    Returns
    -------
    pandas.DataFrame
        Columns: the fit of eq. 10-13 as printed and the chosen fit.
    """
    case_I = _check_fits(case_I)
    return pd.DataFrame({candidate_label(key): {
        "k from alpha1": case_I.fits[key].model.alpha1 / paper.DAHL.alpha1,
        "k from alpha2": np.sqrt(case_I.fits[key].model.alpha2 / paper.DAHL.alpha2)}
        for key in (PAPER_FORM, case_I.choice)})


@dataclass(frozen=True)
class PerAmplitudeFits:
    """The chosen configuration fitted to each Case I loop alone (:func:`per_amplitude_fits`).

    Attributes
    ----------
    fits : dict
        {amplitude [V]: DahlFit}.
    table : pandas.DataFrame
        Per amplitude: the joint fit's RMS %, the fit's own RMS %, g_a and x0 [V].
    """

    fits: dict
    table: pd.DataFrame

    @property
    def models(self):
        """{amplitude [V]: DahlModel} of the fits."""
        return {A: fit.model for A, fit in self.fits.items()}

    @property
    def checks(self):
        """What the notebook states of the fits per amplitude, each with whether it holds."""
        t = self.table
        return {
            "each loop alone is fitted to < 0.5 % RMS": bool(np.all(t["fit per amplitude RMS %"] < 0.5)),
            "g_a grows with the amplitude": bool(t["g_a per amplitude"].is_monotonic_increasing),
            "x0 falls with the amplitude": bool(t["x0 per amplitude [V]"].is_monotonic_decreasing),
            "a loop alone fits no worse than the joint fit":
                bool(np.all(t["fit per amplitude RMS %"] <= t["joint fit RMS %"] + 1e-9)),
        }


def per_amplitude_fits(case_I):
    """The chosen (form, offset, start) fitted to each Case I loop alone.

    The same fit as the joint one (gamma_a held at the published 30, first
    period left out, every 10th sample), one loop at a time.

    Parameters
    ----------
    case_I : CaseIFits

    Returns
    -------
    PerAmplitudeFits
    """
    case_I = _check_fits(case_I)
    form, offset, start_state = case_I.choice
    fits = {A: fit_dahl([(u, v_y)], gamma_a=paper.DAHL.gamma_a, form=form, offset=offset,
                        start=start_state, discard=_period(), stride=10)
            for A, (u, v_y) in zip(case_I.amplitudes, case_I.fit_data)}
    table = pd.DataFrame(
        {"joint fit RMS %": case_I.workbook.rms_percent,
         "fit per amplitude RMS %": [fits[A].rms_percent[0] for A in case_I.amplitudes],
         "g_a per amplitude": [fits[A].model.g_a for A in case_I.amplitudes],
         "x0 per amplitude [V]": [fits[A].model.x0 for A in case_I.amplitudes]},
        index=pd.Index(case_I.amplitudes, name="amplitude [V]"))
    return PerAmplitudeFits(fits, table)


@dataclass(frozen=True)
class ModelComparison:
    """The Dahl and PI models compared on records neither was fitted to (:func:`compare_models`).

    Attributes
    ----------
    pi_fit : PIFit
        The PI model fitted to the Case I loops.
    dahl_fit : DahlFit
        The workbook Dahl model's fit.
    models : dict
        {:data:`PI_NAME`, :data:`DAHL_NAME`, :data:`PRINTED_NAME`: model}.
    records : dict
        {label: (u_c [V], v_y [V], first scored sample)} of the validation records.
    validation : pandas.DataFrame
        :func:`piezolib.hysteresis.validation_table` of the models on the records.
    """

    pi_fit: object
    dahl_fit: DahlFit
    models: dict
    records: dict
    validation: pd.DataFrame

    @property
    def pooled(self):
        """Pooled validation RMS [% of stroke] per model (:func:`piezolib.hysteresis.pooled_rms`)."""
        return pooled_rms(self.validation)

    @property
    def case_I_rms(self):
        """RMS error [% of range] of the PI and the workbook Dahl fit on each Case I loop."""
        return pd.DataFrame({PI_NAME: self.pi_fit.rms_percent,
                             DAHL_NAME: self.dahl_fit.rms_percent})

    @property
    def parameter_table(self):
        """Both fits' parameters with 95 % intervals, bound and identifiability flags."""
        return pd.concat({DAHL_NAME: self.dahl_fit.parameter_table(),
                          "PI": self.pi_fit.parameter_table()})

    @property
    def fit_checks(self):
        """What the notebook states of the two fits to Case I, each with whether it holds."""
        dahl = self.dahl_fit.parameter_table()
        return {
            "Dahl: H_ss is identifiable": bool(dahl.loc["H_ss = beta2 gamma_a / alpha2",
                                                       "identifiable"]),
            "Dahl: the rate alpha2 / alpha1 is identifiable":
                bool(dahl.loc["rate alpha2 / alpha1", "identifiable"]),
            "Dahl: alpha1 alone is not (first-order limit)":
                not dahl.loc["alpha1", "identifiable"],
            "the PI model is invertible": bool(self.models[PI_NAME].invertible),
            "the PI fit's worst loop beats the Dahl fit's":
                self.pi_fit.worst_rms_percent < self.dahl_fit.worst_rms_percent,
        }

    @property
    def validation_checks(self):
        """What the notebook states of the validation, each with whether it holds."""
        pooled, worst = self.pooled, self.validation["max %"]
        return {
            "pooled validation RMS: PI < workbook Dahl < eq. 10-13 as printed":
                pooled[PI_NAME] < pooled[DAHL_NAME] < pooled[PRINTED_NAME],
            "PI: pooled validation RMS < 1 % (the stage's truth is of PI type)":
                pooled[PI_NAME] < 1.0,
            "PI: its largest error is below the workbook Dahl model's":
                worst.loc[PI_NAME].max() < worst.loc[DAHL_NAME].max(),
        }


def compare_models(case_I):
    """Score the PI, the workbook Dahl and the printed-form models on unseen records.

    Parameters
    ----------
    case_I : CaseIFits
        Gives the workbook Dahl fit and the fit of eq. 10-13 as printed; the
        PI model is :func:`~piezolib.problem.hysteresis_fits.workbook_pi_fit`.

    Returns
    -------
    ModelComparison
    """
    case_I = _check_fits(case_I)
    pi_fit = workbook_pi_fit()
    models = {PI_NAME: pi_fit.model, DAHL_NAME: case_I.workbook.model,
              PRINTED_NAME: case_I.paper_form.model}
    records = validation_loops()
    table = validation_table(models, list(records.values()), names=list(records))
    return ModelComparison(pi_fit, case_I.workbook, models, records, table)
