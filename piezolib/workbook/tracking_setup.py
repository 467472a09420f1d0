"""Sec. V on one study, before the tables: what notebook 06's experiments run on and what holds of it.

This module's concern is the set-up of the experiments of Sec. V and what
can be said of it before Tables 4-5 are run, in notebook 06's order:

* :func:`ingredients`: the virtual stage, the workbook's Dahl feedforward and
  the three Case III controllers (continuous, Tustin, float32 sections);
* :func:`loop_margins` and :func:`mu_certificate`: the margins of the loop
  and the lower bound on the μ_RP any controller can reach;
* :func:`error_definition_evidence`: which tracking-error reading Case I
  supports (max |e| or max e − min e), the reading every table then uses.

The runs themselves (both tests with and without the computation delay,
Case IV, the saturation of every run) and what notebook 06 concludes from
them (claims, findings) are :mod:`piezolib.workbook.tracking_study`, which
takes the :class:`Ingredients` made here.

Each result exposes ``checks`` (what must hold in every study) and, where
the notebook states reproduced numbers, ``reference_checks`` (asserted in the
reference study only): ``nb.require(result.checks)``.  Every run of the stage
here raises on a :class:`~piezolib.problem.stage.StageSaturationWarning`:
saturation must not go unseen.
"""

import contextlib
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from piezolib._checks import check_lti, check_positive, check_type
from piezolib.hysteresis import FitWarning
from piezolib.problem import analysis, paper
from piezolib.problem import stage as vstage
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.robust.achievable import achievable_range
from piezolib.robust.export import SOSController
from piezolib.workbook import experiments, pipeline
from piezolib.workbook import study as studies

__all__ = ["Ingredients", "ingredients", "sections_error", "LoopMarginChecks", "loop_margins",
           "MuCertificate", "mu_certificate", "ErrorDefinitionEvidence", "error_definition_evidence",
           "SECTIONS_TOLERANCE"]

#: Largest relative error of the float32 sections against K_d(e^{jωT}): above
#: 10 Hz, and from 1 Hz on (where a pole near z = 1 magnifies the rounding).
SECTIONS_TOLERANCE = {"above 10 Hz": 1e-3, "from 1 Hz": 5e-2}


@contextlib.contextmanager
def _saturation_raises():
    """Within: a StageSaturationWarning is an error (saturation must not go unseen)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", vstage.StageSaturationWarning)
        yield


def _with_plural(n, word):
    return f"{n} {word}{'s' if n != 1 else ''}"


# --------------------------------------------------------------------------- the ingredients
@dataclass(frozen=True, eq=False)
class Ingredients:
    """What every experiment of Sec. V uses: the stage, the feedforward and the controllers.

    Attributes
    ----------
    study : piezolib.workbook.study.Study
    stage : piezolib.problem.stage.VirtualStage
        Seeded with the study's ``experiments.stage_seed``, at the loop's rate.
    fit : piezolib.hysteresis.fit.DahlFit
        The workbook's shared Dahl fit (:func:`~piezolib.problem.hysteresis_fits.workbook_dahl_fit`).
    problem : piezolib.problem.paper.DesignProblem
        G, H_m, H_e, H_y and the published K of the study.
    design : piezolib.workbook.pipeline.StudyControllers
    continuous : dict
        {label: K}: our deployed, our full-order and the published controller
        (v_e [V] -> u_b [V]), in that order.
    discrete : dict
        {label: DiscreteController}: their Tustin discretisations at ``fs``.
    sections : dict
        {label: SOSController}: the float32 sections every Case III run uses.
    sections_errors : dict
        {label: {"above 10 Hz": float, "from 1 Hz": float}}: the largest
        relative error of the float32 sections against K_d(e^{jωT}) over
        1 Hz ... 4 kHz (:func:`sections_error`).
    """

    study: object
    stage: object
    fit: object
    problem: object
    design: object
    continuous: dict
    discrete: dict
    sections: dict = field(repr=False)
    sections_errors: dict = field(repr=False)

    @property
    def dahl(self):
        """The Dahl feedforward model (workbook convention v = u_c, x = v_y [V])."""
        return self.fit.model

    @property
    def ours(self):
        """Label of our deployed controller (Case III of Tables 4-5)."""
        return list(self.continuous)[0]

    @property
    def published(self):
        """Label of the published K of eq. 24."""
        return list(self.continuous)[2]

    @property
    def fs(self):
        """Loop rate [Hz]."""
        return self.study.loop.fs_Hz

    @property
    def delay(self):
        """Computation delay of the loop [samples]."""
        return self.study.loop.delay_samples

    def dahl_description(self):
        """One line: the Dahl feedforward's parameters, its Case I fit and what is not identifiable."""
        dahl, fit = self.dahl, self.fit
        unidentified = fit.parameter_table().query("not identifiable").index
        return (f"Dahl feedforward model ({dahl.form}, start {dahl.start}): g_a = {dahl.g_a:.4f} "
                f"V/V, x0 = {dahl.x0:.4f} V, alpha1 = {dahl.alpha1:.4g} 1/V, alpha2 = "
                f"{dahl.alpha2:.4g} 1/V^2, beta2 = {dahl.beta2:.4g}, gamma_a = {dahl.gamma_a:g}; "
                f"Case I fit RMS {np.array2string(fit.rms_percent, precision=2)} % of range; not "
                f"identifiable one by one: {', '.join(unidentified) or 'none'}; controllers of "
                f"study {self.study.name}: {self.design.source}")

    def discretization_table(self):
        """Per controller: states, pre-warp, Tustin's error, the sampled loop and the sections.

        Returns
        -------
        pandas.DataFrame
            One column per controller.
        """
        rows = {}
        for name, d in self.discrete.items():
            err = self.sections_errors[name]
            rows[name] = {"states": d.K.nstates, "prewarp [rad/s]": d.prewarp_frequency,
                          "max |K_d/K - 1| below 1 kHz": d.max_relative_error,
                          "K_d within 10 % of K below 1 kHz": bool(d.matches),
                          "sampled loop stable": d.loop_stable,
                          "loop spectral radius": d.loop_spectral_radius,
                          "sections": self.sections[name].n_sections,
                          "float32 sections vs K_d, above 10 Hz": err["above 10 Hz"],
                          "float32 sections vs K_d, from 1 Hz": err["from 1 Hz"]}
        return pd.DataFrame(rows)

    @property
    def checks(self):
        """Every study: each sampled loop is stable and each float32 export implements K_d."""
        out = {}
        for name, d in self.discrete.items():
            err = self.sections_errors[name]
            out[f"{name}: sampled loop stable"] = bool(d.loop_stable)
            out[f"{name}: float32 sections within {SECTIONS_TOLERANCE['above 10 Hz']:g} of K_d "
                f"above 10 Hz and {SECTIONS_TOLERANCE['from 1 Hz']:g} from 1 Hz"] = bool(
                all(err[k] < tol for k, tol in SECTIONS_TOLERANCE.items()))
        return out

    @property
    def reference_checks(self):
        """Reference study: Tustin reproduces each K within 10 % below 1 kHz."""
        return {f"{name}: K_d within 10 % of K below 1 kHz": bool(d.matches)
                for name, d in self.discrete.items()}


def ingredients(study):
    """The stage, the Dahl feedforward and the Case III controllers of ``study``.

    Parameters
    ----------
    study : str, path or Study

    Returns
    -------
    Ingredients

    Raises
    ------
    ValueError
        The virtual stage does not sample at the study's loop rate.
    """
    study = studies.load(study)
    stage = vstage.VirtualStage(seed=study.experiments.stage_seed)
    if stage.fs != study.loop.fs_Hz:
        raise ValueError(f"the virtual stage samples at {stage.fs:g} Hz; the study's "
                         f"loop.fs_Hz is {study.loop.fs_Hz:g} Hz")
    with warnings.catch_warnings():
        # notebook 03 (section 6) chose this fit knowing that alpha1, alpha2 and beta2 are not
        # identifiable one by one: Ingredients.dahl_description says so instead
        warnings.simplefilter("ignore", FitWarning)
        fit = workbook_dahl_fit()
    problem = pipeline.study_problem(study)
    design = pipeline.study_controllers(study)       # committed for the reference study
    cases = pipeline.case_III_controllers(study, design)          # {file stem: (label, K)}
    continuous = {label: K for label, K in cases.values()}
    discrete = {cases[stem][0]: d
                for stem, d in pipeline.discretized_controllers(study, design).items()}
    sections = {cases[stem][0]: sos for stem, sos in pipeline.study_sections(study).items()}
    errors = {name: sections_error(d.K, sections[name], study.loop.fs_Hz)
              for name, d in discrete.items()}
    return Ingredients(study, stage, fit, problem, design, continuous, discrete, sections, errors)


def _check_ingredients(ing):
    return check_type("ing", ing, Ingredients, "an Ingredients (tracking_setup.ingredients)")


def sections_error(Kd, sections, fs):
    """Largest relative error of float32 sections against the discrete controller they export.

    Parameters
    ----------
    Kd : control.LTI
        Discrete controller at ``fs``.
    sections : piezolib.robust.export.SOSController
        Its second-order sections, evaluated in float32 arithmetic.
    fs : float
        Loop rate [Hz].

    Returns
    -------
    dict
        {"above 10 Hz": float, "from 1 Hz": float}: max |sections / K_d - 1| over
        10 Hz ... 4 kHz and 1 Hz ... 4 kHz.

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.robust.export import controller_sos
    >>> Kd = ct.ss(ct.tf([0.5, 0.1], [1.0, -0.9], 1e-4))
    >>> err = sections_error(Kd, controller_sos(Kd), 1e4)
    >>> err["from 1 Hz"] < 1e-4
    True
    """
    check_lti("Kd", Kd)
    if not Kd.isdtime(strict=True):
        raise ValueError("Kd must be a discrete-time controller (at fs), got a continuous-time one")
    check_type("sections", sections, SOSController, "an SOSController (robust.controller_sos)")
    fs = check_positive("fs", fs)
    w = 2 * np.pi * np.logspace(0, np.log10(4e3), 400)                # [rad/s]
    ref = np.ravel(Kd(np.exp(1j * w / fs)))
    err = np.abs(sections.frequency_response(w, "float32") / ref - 1)
    return {"above 10 Hz": float(err[w >= 2 * np.pi * 10].max()), "from 1 Hz": float(err.max())}


# --------------------------------------------------------------------------- margins
@dataclass(frozen=True, eq=False)
class LoopMarginChecks:
    """The margins table of the Case III controllers and what it must show.

    Attributes
    ----------
    table : pandas.DataFrame
        :func:`piezolib.problem.analysis.margins_table`, one column per controller.
    ours : str
        Label of the deployed controller.
    delay : int
        The loop's computation delay [samples].
    """

    table: pd.DataFrame
    ours: str
    delay: int

    @property
    def checks(self):
        """Every study: every closed loop stable; the deployed one also with the loop's delay."""
        out = {f"{name}: closed loop stable": bool(self.table.loc["closed loop stable", name])
               for name in self.table.columns}
        out[f"{self.ours}: sampled loop stable with {_with_plural(self.delay, 'sample')} of "
            "delay"] = bool(self.table.loc[f"stable, delay {self.delay}", self.ours])
        return out

    @property
    def reference_checks(self):
        """Reference study: every sampled loop stable with the loop's delay."""
        return {f"{name}: sampled loop stable with {_with_plural(self.delay, 'sample')} of delay":
                bool(self.table.loc[f"stable, delay {self.delay}", name])
                for name in self.table.columns}


def loop_margins(ing):
    """Classical, disk and sampled-loop margins of the Case III controllers on the study's G.

    Parameters
    ----------
    ing : Ingredients

    Returns
    -------
    LoopMarginChecks
    """
    _check_ingredients(ing)
    return LoopMarginChecks(analysis.margins_table(ing.continuous, ing.problem.G, ing.fs),
                            ing.ours, ing.delay)


# --------------------------------------------------------------------------- mu_RP certificate
@dataclass(frozen=True, eq=False)
class MuCertificate:
    """The lower bound on μ_RP over all stabilising controllers, and each controller's μ_RP.

    Attributes
    ----------
    lower : piezolib.robust.achievable.LowerBound
    mu_rp : dict
        {label: peak μ_RP} (no delay modelled).
    paper_mu : float
        The paper's μ_RP (Sec. IV-C).
    """

    lower: object
    mu_rp: dict
    paper_mu: float

    @property
    def paper_attainable(self):
        """True when the paper's μ_RP is not below the bound."""
        return bool(self.paper_mu >= self.lower.value)

    def description(self):
        """The bound, and where the paper's μ_RP lies against it."""
        side = "below" if self.paper_mu < self.lower.value else "above"
        return (f"{self.lower}\npaper's mu_RP {self.paper_mu} is {side} the lower bound "
                f"{self.lower.value:.4f} by {abs(self.lower.value - self.paper_mu):.4f}")

    def table(self):
        """Per controller: μ_RP and the bracket of the achievable μ_RP."""
        return pd.DataFrame({"mu_RP (no delay modelled)": self.mu_rp,
                             "achievable": {n: achievable_range(self.lower.value, mu)
                                            for n, mu in self.mu_rp.items()}})

    @property
    def checks(self):
        """Every study: the bound holds for every controller."""
        return {f"{name}: mu_RP >= the lower bound": bool(mu >= self.lower.value)
                for name, mu in self.mu_rp.items()}


def mu_certificate(ing):
    """μ_RP of each controller and the H∞ lower bound no controller can beat (eq. 16-21).

    Parameters
    ----------
    ing : Ingredients

    Returns
    -------
    MuCertificate
    """
    _check_ingredients(ing)
    G, H_m, H_e, H_y = ing.problem.G, ing.problem.H_m, ing.problem.H_e, ing.problem.H_y
    lower = analysis.achievable_mu_lower_bound(G, H_m, H_e, H_y)
    mu_rp = {name: analysis.robust_performance_peak(K, G, H_m, H_e, H_y)[0]
             for name, K in ing.continuous.items()}
    return MuCertificate(lower, mu_rp, paper.FIGURES_OF_MERIT["mu_RP"])


# --------------------------------------------------------------------------- which error
@dataclass(frozen=True, eq=False)
class ErrorDefinitionEvidence:
    """Case I on the virtual stage under the two readings of Table 5's "tracking error".

    Attributes
    ----------
    table : pandas.DataFrame
        Index frequency [Hz]; the paper's Case I row, ours as max |e| / 12 um
        and as (max e - min e) / 12 um [%].
    bound : float
        Table 4's Case I hysteresis at 40 V [%]: the literal reading's lower bound.
    frequencies : list of float
        The study's frequencies [Hz].
    """

    table: pd.DataFrame
    bound: float
    frequencies: list

    @property
    def max_abs_nearer(self):
        """Per common frequency: max |e| lies nearer the paper's Case I than max e - min e."""
        common = self.table.dropna().index
        dist = (self.table.loc[common].iloc[:, 1:]
                .sub(self.table.loc[common, "paper Case I"], axis=0)).abs()
        return dist["ours: max|e| / 12 um"] < dist["ours: (max e - min e) / 12 um"]

    def description(self):
        """The paper-internal bound and whether the paper's Case I row excludes the literal reading."""
        at_1 = paper.table5().loc["case_I", 1.0]
        finding = (f"paper: Case I at 1 Hz {at_1:.2f} % < {self.bound:.2f} %: the literal reading "
                   "is excluded" if at_1 < self.bound else "not excluded")
        return (f"paper-internal bound for the literal reading: >= {self.bound:.2f} % x (loop "
                f"range / 12 um)\n{finding}")

    def shown(self):
        """The table transposed, with the reading nearer the paper's row per frequency."""
        nearer = self.max_abs_nearer.map({True: "max|e|", False: "max e - min e"})
        return pd.concat([self.table.T, nearer.rename("nearer the paper's Case I").to_frame().T])

    @property
    def reference_checks(self):
        """Reference study: max |e| is the nearer reading at 1 Hz only."""
        nearer = self.max_abs_nearer
        return {"max|e| lies nearer the paper's Case I at 1 Hz": bool(nearer[1.0]),
                "max e - min e lies nearer at every other frequency":
                    not nearer[list(self.frequencies[1:])].any()}


def error_definition_evidence(ing):
    """Case I of the tracking test read both ways, beside the paper's Case I row.

    Parameters
    ----------
    ing : Ingredients

    Returns
    -------
    ErrorDefinitionEvidence
    """
    _check_ingredients(ing)
    ex = ing.study.experiments
    with _saturation_raises():
        runs = {f: experiments.run_case("I", ing.stage, experiments.tracking_reference(
                    f, experiments.tracking_periods(f), ex.range_um, fs=ing.fs)[1], ing.dahl)
                for f in ex.frequencies_Hz}
    table = pd.DataFrame({
        "paper Case I": paper.table5().loc["case_I"],
        "ours: max|e| / 12 um": {f: r.tracking_error_percent(f, range_um=ex.range_um)
                                 for f, r in runs.items()},
        "ours: (max e - min e) / 12 um": {f: r.peak_to_peak_error_percent(f, range_um=ex.range_um)
                                          for f, r in runs.items()}})
    table.index.name = "frequency [Hz]"
    return ErrorDefinitionEvidence(table, float(paper.table4().loc["case_I", 40.0]),
                                   list(ex.frequencies_Hz))
