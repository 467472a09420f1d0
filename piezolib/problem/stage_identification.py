"""The virtual stage identified as in Sec. III-A (notebook 01): calibration, chirps, RLS, validation.

The four steps of Fig. 3 on the stage's experiment files, and what they are judged against:

* :func:`case_I_calibration` -- the stage's one calibration: hysteresis % (eq. 25-26) of the
  recorded Case I loops against Table 4, the chord gains, the measure at the widest loop;
* :func:`chirp_settings_table`, :func:`chirp_checks` -- Step I, the two chirps and that they
  stay inside the stage's linear zone;
* :func:`identify_chirp` -- Steps II-III, RLS output-error identification and d2c
  (:func:`piezolib.identification.identify`), with the discrete poles against the stage's truth;
* :func:`coefficient_table` -- the identified coefficients against eq. 4 as printed;
* :func:`validate_on_chirp` -- Step IV, the fit on the independent chirp and the residual's
  whiteness;
* :func:`compare_with_truth` -- DC gain, natural frequencies and damping against the stage's
  small-signal truth.

::

    from piezolib.problem import stage, stage_data, stage_identification

    vstage = stage.VirtualStage(seed=0)
    chirp = stage_data.load_chirp("identification")
    identified = stage_identification.identify_chirp(chirp, vstage)
"""

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from piezolib._checks import check_lti, check_positive, check_type
from piezolib.hysteresis import hysteresis_measure
from piezolib.identification import (identify, monic_coefficients, pole_pairs, whiteness,
                                     zoh_coefficients, zoh_simulate, fit_percent)
from piezolib.problem import paper
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_calibration import case_I_hysteresis
from piezolib.problem.stage_data import ChirpExperiment

__all__ = ["CALIBRATION_ATOL_PERCENT", "ACCEPTANCE_RTOL", "WHITENESS_LAGS",
           "CaseICalibration", "case_I_calibration", "chirp_settings_table", "chirp_checks",
           "ChirpIdentification", "identify_chirp", "coefficient_table",
           "ChirpValidation", "validate_on_chirp", "TruthComparison", "compare_with_truth",
           "pole_pair_frequencies_Hz"]

#: Tolerance [percentage points] of the stage's Case I hysteresis against Table 4 (its
#: calibration target).
CALIBRATION_ATOL_PERCENT = 0.5
#: Relative tolerance of the identified DC gain and natural frequencies against the truth.
ACCEPTANCE_RTOL = 0.02
#: Lags of the residual's whiteness test (Ljung-Box, 95 % band).
WHITENESS_LAGS = 25


def _check_stage(stage):
    return check_type("stage", stage, VirtualStage, "a VirtualStage")


def _check_chirp(name, chirp):
    return check_type(name, chirp, ChirpExperiment,
                      "a ChirpExperiment (piezolib.problem.stage_data.load_chirp)")


@dataclass(frozen=True)
class CaseICalibration:
    """The stage's hysteresis on the recorded Case I loops against Table 4 (its calibration).

    Attributes
    ----------
    percent : dict
        {actuator amplitude [V]: hysteresis % (eq. 25-26) of the recorded loop}.
    paper : pandas.Series
        Table 4, Case I [%], indexed by amplitude [V].
    chord_gain : dict
        {amplitude [V]: the loop's displacement range over that of the small-signal model}.
    widest : float
        Amplitude [V] of the widest loop.
    measure : piezolib.hysteresis.HysteresisMeasure
        Eq. 25-26 read off the widest loop (Fig. 13).
    """

    percent: dict
    paper: pd.Series = field(repr=False)
    chord_gain: dict
    widest: float
    measure: object = field(repr=False)

    @property
    def table(self):
        """Table 4 Case I, the stage's value and the chord gain, one row per amplitude [V]."""
        table = pd.DataFrame({"paper Case I [%]": self.paper,
                              "virtual stage [%]": pd.Series(self.percent),
                              "chord gain of the loop": list(self.chord_gain.values())})
        table.index.name = "actuator amplitude [V]"
        return table

    @property
    def checks(self):
        """``{what it states: bool}``: the calibration holds and the measure reads it."""
        amplitudes = ", ".join(f"{A:g}" for A in self.percent)
        big = self.widest
        return {
            f"Case I within {CALIBRATION_ATOL_PERCENT} points of Table 4 at {amplitudes} V":
                all(abs(value - self.paper[A]) <= CALIBRATION_ATOL_PERCENT
                    for A, value in self.percent.items()),
            f"eq. 25-26 at {big:g} V give the calibration table's value":
                abs(self.measure.percent - self.percent[big]) < 1e-9,
            f"both branches of the {big:g} V loop cross its mid-input":
                self.measure.n_up >= 2 and self.measure.n_down >= 2,
        }


def case_I_calibration(stage, loops):
    """Hysteresis % of the recorded Case I loops against Table 4, Case I.

    Parameters
    ----------
    stage : piezolib.problem.stage.VirtualStage
        The stage whose hysteresis truth gives the chord gains.
    loops : dict
        {actuator amplitude [V]: record} (:func:`piezolib.problem.stage_data.load_hysteresis_loops`).

    Returns
    -------
    CaseICalibration
    """
    _check_stage(stage)
    check_type("loops", loops, dict, "a dict {amplitude [V]: record}")
    if not loops:
        raise ValueError("loops must hold at least one loop, got an empty dict")
    percent = case_I_hysteresis(loops)
    big = max(loops)
    return CaseICalibration(
        percent=percent, paper=paper.table4().loc["case_I"],
        chord_gain={A: stage.hysteresis.chord_gain(A) for A in percent}, widest=big,
        measure=hysteresis_measure(loops[big].v_a_V, loops[big].x_measured_um))


def _check_chirps(chirps):
    check_type("chirps", chirps, dict, "a dict {name: ChirpExperiment}")
    if not chirps:
        raise ValueError("chirps must hold at least one chirp, got an empty dict")
    for name, chirp in chirps.items():
        _check_chirp(f"chirps[{name!r}]", chirp)
    return chirps


def chirp_settings_table(chirps):
    """Step I: the settings of each chirp, its peak-to-peak sweep and saturated samples.

    Parameters
    ----------
    chirps : dict
        {name: ChirpExperiment} (:func:`piezolib.problem.stage_data.load_chirp`).

    Returns
    -------
    pandas.DataFrame
        One column per chirp.
    """
    _check_chirps(chirps)
    keys = ("top_V", "amplitude_V", "f0_Hz", "f1_Hz", "duration_s", "method", "seed")
    return pd.DataFrame(
        {which: {**{k: ex.metadata[k] for k in keys},
                 "peak-to-peak u_c in sweep [V]": float(np.ptp(ex.sweep.u_c_V)),
                 "saturated samples": int(ex.record.saturated)}
         for which, ex in chirps.items()})


def chirp_checks(chirps, stage):
    """``{what it states: bool}``: every chirp stays inside the stage's linear zone, unsaturated.

    Parameters
    ----------
    chirps : dict
        {name: ChirpExperiment}.
    stage : piezolib.problem.stage.VirtualStage
        Its :attr:`~piezolib.problem.stage.VirtualStage.small_signal_limit_V` is the zone.

    Returns
    -------
    dict
    """
    _check_chirps(chirps)
    _check_stage(stage)
    checks = {}
    for which, ex in chirps.items():
        checks[f"{which} chirp inside the linear zone"] = bool(
            np.ptp(ex.sweep.u_c_V) < stage.small_signal_limit_V)
        checks[f"{which} chirp not saturated"] = not ex.record.saturated
    return checks


@dataclass(frozen=True)
class ChirpIdentification:
    """Steps II-III on one chirp: the identified model and the discrete poles.

    Attributes
    ----------
    result : piezolib.identification.IdentifiedModel
        :func:`piezolib.identification.identify` of the chirp's deviations.
    sweep_start : int
        First sweep sample of the identification data.
    truth_a : ndarray
        Denominator of the ZOH-sampled small-signal truth (highest power first).
    seconds : float
        Wall time of the identification [s].
    """

    result: object = field(repr=False)
    sweep_start: int
    truth_a: np.ndarray = field(repr=False)
    seconds: float

    @property
    def model(self):
        """The identified continuous model G(s), u_c [V] -> v_y [V]."""
        return self.result.model

    @property
    def discrete(self):
        """The discrete output-error model (prefilter passes, final RLS run)."""
        return self.result.discrete

    def pole_table(self):
        """Discrete poles of plain ARX (pass 0), of the output-error estimate and of the truth."""
        d = self.discrete
        table = pd.DataFrame({
            "plain ARX (pass 0)": np.sort_complex(np.roots(d.prefilters[0])),
            "output error (RLS)": np.sort_complex(np.roots(d.a)),
            "stage truth (ZOH of G)": np.sort_complex(np.roots(self.truth_a)),
        })
        table.index.name = "discrete pole"
        return table


def identify_chirp(chirp, stage, fs=paper.SAMPLING_FREQUENCY_HZ):
    """Identify G(s) from a chirp record (Steps II-III of Fig. 3).

    Parameters
    ----------
    chirp : piezolib.problem.stage_data.ChirpExperiment
        The identification chirp.
    stage : piezolib.problem.stage.VirtualStage
        Its small-signal model is the truth the discrete poles are compared with.
    fs : float, optional
        Sampling frequency [Hz]; default the paper's DAQ rate.

    Returns
    -------
    ChirpIdentification
    """
    _check_chirp("chirp", chirp)
    _check_stage(stage)
    fs = check_positive("fs", fs)
    u, y, sweep_start = chirp.deviations()       # from the hold, at rest
    start = time.perf_counter()
    result = identify(u, y, fs)
    seconds = time.perf_counter() - start
    _, truth_a = zoh_coefficients(stage.small_signal_model(), 1 / fs)
    return ChirpIdentification(result=result, sweep_start=sweep_start, truth_a=truth_a,
                               seconds=seconds)


def coefficient_table(G):
    """The coefficients a0 ... a5, b0 ... b3 of a 6-pole / 3-zero model against eq. 4 as printed.

    Parameters
    ----------
    G : control.LTI
        Continuous-time model with 6 poles and at most 3 zeros.

    Returns
    -------
    pandas.DataFrame
        Index ``a0`` ... ``b3``; columns ``identified`` (:func:`~piezolib.identification.monic_coefficients`),
        ``published (eq. 4)`` (:data:`piezolib.problem.paper.PLANT`) and ``relative error``.

    Examples
    --------
    >>> table = coefficient_table(paper.plant())
    >>> bool((table["relative error"].abs() < 1e-9).all())
    True
    """
    check_lti("G", G)
    a, b = monic_coefficients(G)
    ours = np.r_[a, b]
    published = np.r_[paper.PLANT.a, paper.PLANT.b]
    index = [f"a{i}" for i in range(len(a))] + [f"b{i}" for i in range(len(b))]
    return pd.DataFrame({"identified": ours, "published (eq. 4)": published,
                         "relative error": (ours - published) / published},
                        index=pd.Index(index, name="coefficient"))


@dataclass(frozen=True)
class ChirpValidation:
    """Step IV: a model simulated on the independent chirp, its fit and its residual.

    Attributes
    ----------
    u, y : ndarray
        Input and measured output deviations [V] from the hold on.
    y_sim : ndarray
        The model's ZOH simulation from rest [V].
    sweep_start : int
        First sweep sample of ``u``, ``y``.
    fit_percent : float
        100 (1 - ||y - y_sim|| / ||y - mean y||) over the sweep.
    fit_truth_percent : float
        The same fit of the stage's small-signal truth (the noise-limited best).
    whiteness : piezolib.identification.WhitenessTest
        Autocorrelation and Ljung-Box test of the residual over :data:`WHITENESS_LAGS` lags.
    noise_ratio : float
        Residual rms over the stage's sensor-noise rms.
    """

    u: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)
    y_sim: np.ndarray = field(repr=False)
    sweep_start: int
    fit_percent: float
    fit_truth_percent: float
    whiteness: object = field(repr=False)
    noise_ratio: float

    @property
    def sweep(self):
        """The sweep's samples of ``u``, ``y``, ``y_sim``."""
        return slice(self.sweep_start, None)


def validate_on_chirp(model, chirp, stage, fs=paper.SAMPLING_FREQUENCY_HZ):
    """Simulate ``model`` on a chirp and judge the fit and the residual (Step IV, Fig. 4).

    Parameters
    ----------
    model : control.LTI
        Identified model u_c [V] -> v_y [V].
    chirp : piezolib.problem.stage_data.ChirpExperiment
        The validation chirp (independent of the identification data).
    stage : piezolib.problem.stage.VirtualStage
        Its small-signal model and sensor noise are the references of the fit.
    fs : float, optional
        Sampling frequency [Hz]; default the paper's DAQ rate.

    Returns
    -------
    ChirpValidation
    """
    check_lti("model", model)
    _check_chirp("chirp", chirp)
    _check_stage(stage)
    fs = check_positive("fs", fs)
    u, y, start = chirp.deviations()
    y_sim = zoh_simulate(model, u, fs)
    sweep = slice(start, None)
    y_truth = zoh_simulate(stage.small_signal_model(), u, fs)
    residual = y[sweep] - y_sim[sweep]
    return ChirpValidation(
        u=u, y=y, y_sim=y_sim, sweep_start=start, fit_percent=fit_percent(y[sweep], y_sim[sweep]),
        fit_truth_percent=fit_percent(y[sweep], y_truth[sweep]),
        whiteness=whiteness(residual, max_lag=WHITENESS_LAGS),
        noise_ratio=float(np.std(residual) / stage.settings.noise_rms_V))


@dataclass(frozen=True)
class TruthComparison:
    """An identified model against the stage's small-signal truth (Sec. III-A, eq. 4).

    Attributes
    ----------
    wn, zeta : ndarray
        Natural frequencies [rad/s] and damping ratios of the identified pole pairs.
    wn_truth, zeta_truth : ndarray
        The same of the truth.
    dc, dc_truth : float
        DC gains [V/V].
    """

    wn: np.ndarray
    zeta: np.ndarray
    wn_truth: np.ndarray
    zeta_truth: np.ndarray
    dc: float
    dc_truth: float

    @property
    def f_Hz(self):
        """Natural frequencies [Hz] of the identified pole pairs, ascending."""
        return self.wn / (2 * np.pi)

    @property
    def table(self):
        """DC gain, natural frequency [Hz] and damping of each pair: identified, truth, error."""
        table = pd.DataFrame({
            "identified": np.r_[self.dc, self.wn / (2 * np.pi), self.zeta],
            "stage truth": np.r_[self.dc_truth, self.wn_truth / (2 * np.pi), self.zeta_truth],
        }, index=["DC gain [V/V]"] + [f"f_n pair {k} [Hz]" for k in range(1, self.wn.size + 1)]
                 + [f"zeta pair {k}" for k in range(1, self.wn.size + 1)])
        table["relative error"] = table["identified"] / table["stage truth"] - 1
        return table

    @property
    def checks(self):
        """``{what it states: bool}``: DC gain and natural frequencies within
        :data:`ACCEPTANCE_RTOL` of the truth."""
        pct = f"{ACCEPTANCE_RTOL:.0%}"
        return {f"DC gain within {pct} of the truth": abs(self.dc / self.dc_truth - 1)
                < ACCEPTANCE_RTOL,
                f"natural frequencies within {pct} of the truth": bool(
                    np.all(np.abs(self.wn / self.wn_truth - 1) < ACCEPTANCE_RTOL))}


def pole_pair_frequencies_Hz(sys):
    """Natural frequencies [Hz] of a model's complex pole pairs, ascending.

    Parameters
    ----------
    sys : control.LTI
        SISO continuous-time model.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> import control as ct
    >>> pole_pair_frequencies_Hz(ct.tf([1.0], [1.0, 0.2, (2 * np.pi) ** 2])).round(3)
    array([1.])
    """
    return pole_pairs(sys)[0] / (2 * np.pi)


def compare_with_truth(model, truth):
    """DC gain and pole pairs of an identified model against the truth.

    Parameters
    ----------
    model, truth : control.LTI
        SISO continuous-time models with the same number of complex pole pairs.

    Returns
    -------
    TruthComparison

    Examples
    --------
    >>> comparison = compare_with_truth(paper.plant(), paper.plant())
    >>> all(comparison.checks.values())
    True
    """
    check_lti("model", model)
    check_lti("truth", truth)
    wn, zeta = pole_pairs(model)
    wn_truth, zeta_truth = pole_pairs(truth)
    if wn.shape != wn_truth.shape:
        raise ValueError(f"model has {wn.size} complex pole pairs and truth {wn_truth.size}: "
                         "they must have the same number")
    return TruthComparison(wn=wn, zeta=zeta, wn_truth=wn_truth, zeta_truth=zeta_truth,
                           dc=float(model.dcgain()), dc_truth=float(truth.dcgain()))
