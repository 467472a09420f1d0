"""Notebook 08's hysteresis stages on a user's own records: the loops after their start-up,
the Dahl, Prandtl-Ishlinskii and Hammerstein fits with the model chosen by validation, and the
feedforward cross-check.

One call per stage, each returning a result with its display and ``checks``
(as the stages of :mod:`piezolib.workbook.your_stage`)::

    loops = prepare_loops(records, um_per_volt=3.0, decimation=5, skip_transient=True)
    choice = fit_hysteresis(loops, ("sine",), ("triangle",), gamma_a=30.0, plays=10,
                            ceiling_percent=5.0)
    feedforward = feedforward_cross_check(choice)

They need no plant: a folder of hysteresis records only runs them all.
"""

import time
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from piezolib import hysteresis as hy
from piezolib import records as recs
from piezolib._checks import check_bool, check_integer, check_positive, check_type
from piezolib.workbook.your_stage import OwnRecords, _Shown

__all__ = ["HysteresisLoops", "HysteresisChoice", "FeedforwardCheck", "prepare_loops",
           "fit_hysteresis", "feedforward_cross_check"]


# -- 5. hysteresis -----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class HysteresisLoops(_Shown):
    """The hysteresis records after their start-up, from an input minimum, decimated.

    Attributes
    ----------
    data : dict
        {label: (u_c [V], v_y [V])}.
    dropped : dict
        {label: what was dropped at the start} (empty without ``skip_transient``).
    fs : float
        Sampling rate of the loops after decimation [Hz] (the Hammerstein
        model's dynamics are sampled at it).
    """

    data: dict
    dropped: dict
    fs: float

    @property
    def lines(self):
        return tuple(f"{label}: dropped the {text}" for label, text in self.dropped.items())


def prepare_loops(records, um_per_volt, decimation, skip_transient=True):
    """Each hysteresis record after its start-up, cut to start at an input minimum, decimated.

    The start-up (rest, the voltage step, the ringing after it, the virgin
    stroke: :func:`piezolib.records.find_start_up`) is dropped with
    ``skip_transient``; a record whose first turning point is a maximum is cut
    at the next one, so that every record starts after a descending stroke.

    Parameters
    ----------
    records : OwnRecords
    um_per_volt : float
        Output unit per sensor volt: the output becomes v_y [V].
    decimation : int
        Decimation factor (behind an anti-alias filter, :func:`piezolib.records.decimate`).
    skip_transient : bool

    Returns
    -------
    HysteresisLoops
    """
    check_type("records", records, OwnRecords, "the OwnRecords of load_records")
    um_per_volt = check_positive("um_per_volt", um_per_volt)
    decimation = check_integer("decimation", decimation, 1)
    skip_transient = check_bool("skip_transient", skip_transient)
    data, dropped, fs = {}, {}, records.fs / decimation
    for label, rec in records.loops.items():
        cut = recs.cut_at_turning_points(rec, skip_transient=skip_transient)
        if cut.metadata["starts_at"] == "maximum":
            cut = recs.cut_at_turning_points(rec, first=1, skip_transient=skip_transient)
        if skip_transient:
            dropped[label] = f"{cut.metadata['dropped']}; {cut.metadata['cut_note']}"
        cut = recs.decimate(cut, decimation)
        data[label] = (cut.input, cut.output / um_per_volt)
    return HysteresisLoops(data, dropped, fs)


@dataclass(frozen=True, eq=False, repr=False)
class HysteresisChoice(_Shown):
    """Dahl, Prandtl-Ishlinskii and Hammerstein fits and the model chosen by validation.

    Attributes
    ----------
    fits : dict
        {"Dahl": fit, "PI": fit, "Hammerstein": fit} (:func:`piezolib.hysteresis.fit_dahl`,
        :func:`~piezolib.hysteresis.fit_pi`, :func:`~piezolib.hysteresis.fit_hammerstein`).
    scores : pandas.DataFrame
        :func:`piezolib.hysteresis.validation_table` on the validation data.
    chosen_name : str
    validation_data : list of (v, x)
    validation_names : list of str
    held_out_in_time : bool
        No validation record that was not fitted: the second half of each
        fitted record was held out.
    fit_loops : tuple of str
    warnings : tuple of str
        The fits' warnings (a parameter on a bound or not identifiable).
    seconds : dict
        {name: fit time [s]}.
    ceiling_percent : float
        Largest acceptable validation RMS [% of stroke] (a check).
    """

    fits: dict
    scores: pd.DataFrame
    chosen_name: str
    validation_data: list
    validation_names: list
    held_out_in_time: bool
    fit_loops: tuple
    warnings: tuple
    seconds: dict
    ceiling_percent: float

    @property
    def chosen(self):
        """The chosen model."""
        return self.fits[self.chosen_name].model

    @property
    def models(self):
        """{name: fitted model}."""
        return {name: f.model for name, f in self.fits.items()}

    def validation_rms(self, name):
        """Pooled validation RMS of a model [% of stroke]."""
        return float(self.scores.loc[name, "pooled RMS %"].iloc[0])

    @property
    def lines(self):
        out = []
        if self.held_out_in_time:
            out.append("No validation record that was not fitted: the models are fitted to the "
                       f"first half of {', '.join(self.fit_loops)} and validated on the second "
                       "half (held out in time).")
        out += [f"fit warning: {w}" for w in self.warnings]
        out.append("fit times: " + ", ".join(f"{name} {s:.2f} s"
                                             for name, s in self.seconds.items())
                   + "; fit RMS: " + ", ".join(f"{name} {f.pooled_rms_percent:.2f} %"
                                               for name, f in self.fits.items()))
        starts = {name: f.model.hysteresis.start if name == "Hammerstein" else f.model.start
                  for name, f in self.fits.items()}
        out.append("start states: " + ", ".join(f"{name} {s!r}" for name, s in starts.items())
                   + f"; validated on {', '.join(self.validation_names)}; chosen: "
                   f"{self.chosen_name}")
        hammerstein = self.fits["Hammerstein"]
        if hammerstein.extrapolation_scores:
            ends = hammerstein.extrapolation_scores
            out.append(f"Hammerstein operator: {hammerstein.operator} (held out after the "
                       "middle: " + ", ".join(f"{k} {v:.3g} %" for k, v in
                                              hammerstein.operator_scores.items())
                       + "; beyond the inner 80 % of the range: "
                       + ", ".join(f"{k} {v:.3g} %" for k, v in ends.items()) + ")")
        return tuple(out)

    def _tables(self):
        return ((self.scores, True),)

    @property
    def checks(self):
        s = self.scores
        return {f"a model validates below {self.ceiling_percent:g} % of stroke":
                bool(min(s["RMS %"]) < self.ceiling_percent),
                "the chosen model validates best":
                bool(self.validation_rms(self.chosen_name) == s["pooled RMS %"].min())}


def _labels(name, labels):
    """Record labels as a tuple of str."""
    if isinstance(labels, str) or not hasattr(labels, "__iter__"):
        raise TypeError(f"{name} must be a sequence of record labels (str), got {labels!r}")
    labels = tuple(labels)
    if not all(isinstance(x, str) for x in labels):
        raise TypeError(f"{name} must hold record labels (str), got {labels!r}")
    return labels


def fit_hysteresis(loops, fit_loops, validation_loops, *, gamma_a, plays, ceiling_percent):
    """Fit a Dahl, a Prandtl-Ishlinskii and a Hammerstein model; choose the one that validates best.

    The Dahl model (Bliman-Sorine form, output offset, from rest), a PI
    model with ``plays`` plays (its start chosen by the data) and a
    Hammerstein model (the same plays, or a Preisach grid where it predicts
    and extrapolates as well, followed by linear dynamics of unit DC gain at
    the loops' rate, operator and order chosen by validation:
    :func:`piezolib.hysteresis.fit_hammerstein`) are fitted to
    ``fit_loops``; the smallest pooled RMS error on ``validation_loops`` (the
    ones not fitted) decides.  With no validation record that was not fitted,
    the models are fitted to the first half of each fitted record and scored
    on its second half: never on the samples they were fitted to.

    Parameters
    ----------
    loops : HysteresisLoops
    fit_loops, validation_loops : sequence of str
        Labels of the records fitted and validated on.
    gamma_a : float
        Dahl input weight (only beta2 gamma_a is identifiable).
    plays : int
        Prandtl-Ishlinskii plays (the linear one included).
    ceiling_percent : float
        Largest acceptable validation RMS [% of stroke] (a check).

    Returns
    -------
    HysteresisChoice
    """
    check_type("loops", loops, HysteresisLoops, "the HysteresisLoops of prepare_loops")
    fit_loops = _labels("fit_loops", fit_loops)
    validation_loops = _labels("validation_loops", validation_loops)
    gamma_a = check_positive("gamma_a", gamma_a)
    plays = check_integer("plays", plays, minimum=1)
    ceiling_percent = check_positive("ceiling_percent", ceiling_percent)
    unknown = sorted(set(fit_loops + validation_loops) - set(loops.data))
    if unknown or not fit_loops:
        raise ValueError(f"fit_loops and validation_loops must name records among "
                         f"{sorted(loops.data)} (fit_loops at least one), got unknown {unknown}")
    held_out_in_time = not (set(validation_loops) - set(fit_loops))
    if held_out_in_time:
        halves = {label: hy.split_record(*loops.data[label], 0.5) for label in fit_loops}
        fit_data = [halves[label][0] for label in fit_loops]
        validation_data = [halves[label][1] for label in fit_loops]
        validation_names = [f"{label} (second half)" for label in fit_loops]
    else:
        fit_data = [loops.data[label] for label in fit_loops]
        validation_names = [label for label in validation_loops if label not in fit_loops]
        validation_data = [loops.data[label] for label in validation_names]
    candidates = {
        "Dahl": lambda: hy.fit_dahl(fit_data, gamma_a, form="bliman_sorine", offset=True,
                                    start="rest"),
        "PI": lambda: hy.fit_pi(fit_data, n_plays=plays, offset=True),   # start: by the data
        "Hammerstein": lambda: hy.fit_hammerstein(fit_data, fs=loops.fs, n_plays=plays)}
    fits, seconds = {}, {}
    with warnings.catch_warnings(record=True) as fit_warnings:
        warnings.simplefilter("always", hy.FitWarning)
        for name, fit in candidates.items():
            t0 = time.perf_counter()
            fits[name] = fit()
            seconds[name] = time.perf_counter() - t0
    scores = hy.validation_table({name: f.model for name, f in fits.items()}, validation_data,
                                 names=validation_names)
    return HysteresisChoice(fits, scores, hy.pooled_rms(scores).idxmin(), validation_data,
                            validation_names, held_out_in_time, fit_loops,
                            tuple(str(w.message) for w in fit_warnings), seconds,
                            float(ceiling_percent))


# -- 7. feedforward ----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class FeedforwardCheck(_Shown):
    """Each fitted model's feedforward applied to every fitted model
    (:func:`piezolib.hysteresis.cross_check`).

    Attributes
    ----------
    table : pandas.DataFrame
        Indexed by (compensator, plant): RMS %, max %, hysteresis %.
    x_ref : ndarray
        The reference [sensor V]: the validation loop's input mapped through the chosen model.
    chosen_name : str
    """

    table: pd.DataFrame
    x_ref: np.ndarray
    chosen_name: str

    @property
    def lines(self):
        return ()

    def _tables(self):
        return ((self.table, True),)

    @property
    def checks(self):
        n = self.chosen_name
        return {"the chosen model's feedforward inverts it (RMS below 0.5 %)":
                bool(np.isclose(self.table.loc[(n, n), "RMS %"], 0, atol=0.5))}


def feedforward_cross_check(choice):
    """The fitted models' feedforwards, each applied to every fitted model.

    The reference is the first validation record's input mapped through the
    chosen model (a reachable displacement).

    Parameters
    ----------
    choice : HysteresisChoice

    Returns
    -------
    FeedforwardCheck
    """
    check_type("choice", choice, HysteresisChoice, "the HysteresisChoice of fit_hysteresis")
    x_ref = choice.chosen.simulate(choice.validation_data[0][0])
    models = choice.models
    return FeedforwardCheck(hy.cross_check(models, models, x_ref), x_ref, choice.chosen_name)
