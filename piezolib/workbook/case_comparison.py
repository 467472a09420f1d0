"""Cases I–III of Sec. V with several Case III controllers side by side (notebook 09).

The hysteresis and tracking tests of notebook 06 (Tables 4–5) on the study's
virtual stage: its noise seeds, the workbook's Dahl feedforward, the loop's
computation delay, each controller as the float32 sections a target runs.
Cases I and II have no feedback, so they are the same for every controller.
"""

import warnings
from dataclasses import dataclass

import pandas as pd

from piezolib.hysteresis import FitWarning
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments
from piezolib.workbook import study as studies

__all__ = ["CaseComparison", "case_III_comparison"]


@dataclass(frozen=True)
class CaseComparison:
    """Cases I–III with each controller in Case III (:func:`case_III_comparison`).

    Attributes
    ----------
    tracking : pandas.DataFrame
        Tracking error [%] (mean over the seeds): rows ``"Case I"``, ``"Case II"``
        and ``"Case III, <controller>"`` per controller; columns the frequencies [Hz].
    hysteresis : pandas.DataFrame
        Case III hysteresis [%], one row per controller; columns the amplitudes [V].
    tracking_runs, hysteresis_runs : dict
        {controller: ExperimentResult} of :func:`piezolib.workbook.experiments.tracking_test`
        and :func:`~piezolib.workbook.experiments.hysteresis_test`.
    """

    tracking: pd.DataFrame
    hysteresis: pd.DataFrame
    tracking_runs: dict
    hysteresis_runs: dict


def case_III_comparison(study, controllers, model=None):
    """Run Table 4's and Table 5's experiments of ``study`` once per Case III controller.

    Parameters
    ----------
    study : str, path or Study
        Its stage seed, noise seeds, amplitudes, frequencies, range and loop delay are used.
    controllers : dict
        {name: controller} as :func:`piezolib.workbook.experiments.tracking_test`
        takes it (e.g. an exported SOSController, run in float32); entries that
        are None (a controller the study does not have) are left out.
    model : HysteresisModel, optional
        The feedforward of Cases II-III; default the workbook's Dahl fit
        (:func:`piezolib.problem.hysteresis_fits.workbook_dahl_fit`).

    Returns
    -------
    CaseComparison

    Raises
    ------
    TypeError
        When ``controllers`` is not a dict with at least one controller.
    """
    study = studies.load(study)
    if not isinstance(controllers, dict):
        raise TypeError(f"controllers must be a dict {{name: controller}}, got "
                        f"{type(controllers).__name__}")
    controllers = {name: K for name, K in controllers.items() if K is not None}
    if not controllers:
        raise TypeError("controllers must hold at least one controller that is not None")
    stage = VirtualStage(seed=study.experiments.stage_seed)
    if model is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FitWarning)     # notebook 03 discusses them
            model = workbook_dahl_fit().model
    runs = dict(delay_samples=study.loop.delay_samples, seeds=study.experiments.seeds)
    ex = study.experiments
    hysteresis = {name: experiments.hysteresis_test(stage, model, K, ex.amplitudes_V, **runs)
                  for name, K in controllers.items()}
    tracking = {name: experiments.tracking_test(stage, model, K, ex.frequencies_Hz, ex.range_um,
                                                **runs)
                for name, K in controllers.items()}
    last = tracking[list(controllers)[-1]].table
    rows = {"Case I": last.loc["case_I"], "Case II": last.loc["case_II"],
            **{f"Case III, {name}": res.table.loc["case_III"] for name, res in tracking.items()}}
    return CaseComparison(
        tracking=pd.DataFrame(rows).T.rename_axis(
            f"tracking error [%], delay {study.loop.delay_samples}"),
        hysteresis=pd.DataFrame({name: res.table.loc["case_III"]
                                 for name, res in hysteresis.items()}).T
        .rename_axis("hysteresis error [%], Case III"),
        tracking_runs=tracking, hysteresis_runs=hysteresis)
