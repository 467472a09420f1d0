"""Notebook 08's claim rows and closing checks: every stage's results in its claim table, the
checks that hold for any user's data, the checks this example's known truth states, and the
summary lines.

::

    record_claims(nb.claims, records, model, weight, choice, design, verification,
                  experiments, truth=truth)
    nb.require(stage_checks(records, data, model, weight, choice, design, verification,
                            feedforward, experiments))
    nb.require(known_truth_checks(truth, model, weight, choice, verification, experiments))

A stage that did not run (:class:`~piezolib.workbook.your_stage.Skipped`) adds
no row and no check.
"""

import control as ct
import pandas as pd

from piezolib._checks import check_nonnegative, check_type
from piezolib.workbook.report import ClaimTable
from piezolib.workbook.your_stage import (NO_PLANT_NOTE, TRUTH_TOP_RAD_S, Identification,
                                          KnownTruth, OwnRecords, Skipped, UncertaintyWeight,
                                          _Shown, ran)
from piezolib.workbook.your_stage_control import Experiments, LoopDesign, Verification
from piezolib.workbook.your_stage_hysteresis import HysteresisChoice

__all__ = ["record_claims", "written_tables", "stage_checks", "known_truth_checks",
           "summary_lines"]

#: Section of the claims this notebook writes.
SECTION = "own stage"

#: The class of each stage's result (a stage that did not run gives None or Skipped).
_RESULTS = {"identification": Identification, "weight": UncertaintyWeight,
            "choice": HysteresisChoice, "loop": LoopDesign, "verification": Verification,
            "experiments": Experiments, "truth": KnownTruth}


def _check_results(**results):
    for name, value in results.items():
        if value is not None and not isinstance(value, Skipped):
            check_type(name, value, _RESULTS[name],
                       f"the {_RESULTS[name].__name__} of that stage, Skipped or None")


def record_claims(claims, records, identification, weight, choice, loop, verification,
                  experiments, truth=None):
    """Add the notebook's results to its claim table (no published values: the paper has no
    such stage), in the order the notebook computes them.

    Parameters
    ----------
    claims : piezolib.workbook.report.ClaimTable
    records : OwnRecords
    identification, weight, loop, verification, experiments
        The stages' results (or :class:`~piezolib.workbook.your_stage.Skipped`: their rows
        are left out).
    choice : HysteresisChoice
    truth : KnownTruth, optional
        Adds the comparisons with the true plant.

    Returns
    -------
    ClaimTable
        ``claims``.
    """
    check_type("claims", claims, ClaimTable, "a report.ClaimTable")
    check_type("records", records, OwnRecords, "the OwnRecords of load_records")
    _check_results(identification=identification, weight=weight, choice=choice, loop=loop,
                   verification=verification, experiments=experiments, truth=truth)
    c = SECTION
    claims.add(c, "record sampling rate", None, next(iter(records.loops.values())).fs, unit="Hz")
    known = ran(truth)
    if ran(identification):
        claims.add(c, "control-loop rate of the design", None, loop.design.fs, unit="Hz")
        claims.add(c, "validation fit on the held-out chirp", None, identification.fit_held_out,
                   unit="%", note=f"true plant on the same samples: {truth.fit_truth:.2f} % "
                   "(noise ceiling)" if known else "")
        claims.add(c, "DC gain of the identified model", None,
                   float(ct.dcgain(identification.model)), unit="V/V",
                   note=f"true {truth.dc_true:.4f}" if known else "")
        if known:
            claims.add(c, "largest |G_true/G_id - 1| below 1 kHz", None, truth.error_below_top)
            claims.add(c, "weight covers the true error up to", None, weight.covered_rad_s,
                       unit="rad/s")
    for name, f in choice.fits.items():
        claims.add(c, f"{name}: validation RMS on {', '.join(choice.validation_names)}", None,
                   choice.validation_rms(name), unit="% of stroke",
                   note=f"fit RMS {f.pooled_rms_percent:.3f} %" + (
                       "; held out in time: no validation record that was not fitted"
                       if choice.held_out_in_time else ""))
    claims.add(c, "hysteresis model chosen by validation", None, choice.chosen_name)
    if ran(verification):
        p, e = verification.mu_pade, verification.mu_exact
        claims.add(c, "mu_RP upper bound (Pade delay)", None, float(p.upper.max()),
                   note=f"lower {p.lower.max():.4f}; exact delay {e.upper.max():.4f}")
        delay = verification.loop.delay_samples
        for name in verification.plants:
            claims.add(c, f"sampled loop spectral radius, {delay} delay, {name}", None,
                       verification.radius(name, delay))
            claims.add(c, f"||H_y T||, {name}", None,
                       float(verification.table.loc["||H_y T||", name]))
    if ran(experiments):
        for quantity, result, row, column in _experiment_cells(experiments):
            value = float(result.table.loc[row, column])
            if result.seeds is None:
                claims.add(c, quantity, None, value, unit="%")
            else:
                claims.add(c, quantity, None, value, unit="%",
                           interval=result.interval(row, column),
                           note=f"mean over {len(result.seeds)} noise seeds, 95 % interval")
    return claims


def _experiment_cells(experiments):
    """(quantity, result, row, column) of each Table 4/5-style claim, in the claims' order."""
    t4, t5 = experiments.table4, experiments.table5
    for A in t4.table.columns:
        for case in ("I", "II", "III"):
            yield f"hysteresis %, {A:g} V, case {case}", t4, f"case_{case}", A
        if experiments.chosen4 is not None:
            yield (f"hysteresis %, {A:g} V, case II with {experiments.chosen_name}",
                   experiments.chosen4, "case_II", A)
    for f in t5.table.columns:
        for case in ("I", "II", "III"):
            yield f"tracking error %, {f:g} Hz, case {case}", t5, f"case_{case}", f


def written_tables(experiments, path):
    """Tables 4-5 of ``experiments`` with the values its claim table at ``path`` holds.

    A rerun whose means move within their precision leaves the claim table
    as it was (:func:`piezolib.workbook.report.save_results`); a figure drawn
    from these tables is then unchanged too.

    Parameters
    ----------
    experiments : Experiments
    path : path-like
        The claim table written after :func:`record_claims` (``nb.claims.save()``).

    Returns
    -------
    table4, table5 : pandas.DataFrame
        As ``experiments.table4_view`` (Table 4 with the chosen model's Case II
        as a further row) and ``experiments.table5.table``.

    Raises
    ------
    ValueError
        When the file lacks one of the experiments' claims.
    """
    check_type("experiments", experiments, Experiments, "the Experiments of run_experiments")
    frame = pd.read_csv(path)
    if not {"quantity", "ours"} <= set(frame.columns):
        raise ValueError(f"path: {path} is not a claim table (no 'quantity' and 'ours' columns)")
    ours = dict(zip(frame["quantity"], frame["ours"]))
    table4, table5 = experiments.table4_view, experiments.table5.table.copy()
    extra = next(iter(experiments.extra4), None)
    for quantity, result, row, column in _experiment_cells(experiments):
        if quantity not in ours:
            raise ValueError(f"path: {path} has no claim {quantity!r}: write the claims of "
                             "these experiments first (record_claims, then save)")
        if result is experiments.table5:
            table5.loc[row, column] = float(ours[quantity])
        else:
            table4.loc[extra if result is experiments.chosen4 else row, column] = \
                float(ours[quantity])
    return table4, table5


def stage_checks(*results):
    """The checks of every stage that ran, in one dict (what holds for any user's data).

    Examples
    --------
    >>> from piezolib.workbook.your_stage import Skipped
    >>> stage_checks(Skipped("no plant"), None)
    {}
    """
    for result in results:
        if result is not None and not isinstance(result, _Shown):
            raise TypeError(f"results must be the stages' results (or None), got "
                            f"{type(result).__name__}")
    out = {}
    for result in results:
        if ran(result):
            out.update(result.checks)
    return out


def known_truth_checks(truth, identification, weight, choice, verification, experiments):
    """What this example's known truth states (the records come from the virtual stage).

    The stage's hysteresis is made of plays, so the PI model fits its loops
    within 0.5 % of stroke; with a plant: the identified model within 1 % in
    DC gain and 5 % below
    1 kHz of the true one, its held-out fit within 15 points of the true
    plant's, the weight covering the real error past 1 kHz, the loop
    with the true plant stable (continuous and sampled with the delay),
    robust performance (mu_RP < 1) with the exact delay, and feedback and the
    chosen feedforward beating the open loop.

    Returns
    -------
    dict
        {what it states: bool}.
    """
    check_type("choice", choice, HysteresisChoice, "the HysteresisChoice of fit_hysteresis")
    _check_results(truth=truth, identification=identification, weight=weight,
                   verification=verification, experiments=experiments)
    # which hysteresis model validates best is no consequence of the truth: the stage's plays
    # act through its dynamics, and on the triangle (corners, a range below the fitted sine's)
    # the Dahl model validates best once the loops are decimated without edge artefacts; what
    # the plays do imply is that a sum of plays reproduces the loops it is fitted to
    out = {"PI fits its loops within 0.5 % of stroke (the stage's hysteresis is made of plays)":
           bool(choice.fits["PI"].pooled_rms_percent < 0.5)}
    if not ran(truth):
        return out
    delay = verification.loop.delay_samples
    col = verification.table["true G (known here)"]
    t4, t5 = experiments.table4.table, experiments.table5.table
    out.update({
        "DC gain within 1 % of the true plant's":
        bool(abs(truth.dc_identified / truth.dc_true - 1) < 0.01),
        "|G_true/G_id - 1| below 5 % up to 1 kHz": truth.error_below_top < 0.05,
        "held-out fit within 15 points of the true plant's":
        bool(identification.fit_held_out > truth.fit_truth - 15),
        "the weight covers the real error past 1 kHz": weight.covered_rad_s > TRUTH_TOP_RAD_S,
        "loop with the true plant stable": bool(col["max Re closed-loop pole [rad/s]"] < 0),
        f"sampled loop with the true plant stable with {delay} sample(s) of delay":
        bool(col[f"radius, {delay} delay"] < 1),
        "robust performance with the exact loop delay (mu_RP < 1)":
        bool(verification.mu_exact.upper.max() < 1),
        "feedback beats open loop (Table 4)": bool((t4.loc["case_III"] < t4.loc["case_I"]).all()),
        "feedback beats open loop (Table 5)": bool((t5.loc["case_III"] < t5.loc["case_I"]).all())})
    if experiments.extra4:
        chosen_II = experiments.extra4[f"II: {experiments.chosen_name} feedforward"].values
        out[f"the {experiments.chosen_name} feedforward beats open loop (Table 4)"] = bool(
            (chosen_II < t4.loc["case_I"].values).all())
    return out


def summary_lines(records, seconds):
    """Findings of the notebook that are not claims: what ran, and how long it took.

    Examples
    --------
    >>> from piezolib.workbook.your_stage import OwnRecords
    >>> summary_lines(OwnRecords(None, {}, 5e3), 12.34)[-1]
    'the notebook ran in 12.3 s'
    """
    check_type("records", records, OwnRecords, "the OwnRecords of load_records")
    seconds = check_nonnegative("seconds", seconds)
    out = [] if records.have_plant else [NO_PLANT_NOTE]
    return out + [f"the notebook ran in {seconds:.1f} s"]
