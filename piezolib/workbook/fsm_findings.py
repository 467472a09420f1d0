"""Notebook 10's claim rows and closing findings (the fine steering mirror benchmark).

:func:`claim_rows` turns the benchmark's results into the rows of the
notebook's claim table (``data/results/real_benchmark.csv``), each a dict of
the arguments of :meth:`piezolib.workbook.session.Session.check`;
:func:`summary_lines` writes the findings that are more than one claim (the
comparisons with the published baselines, why the Hammerstein model fails, what
the axis controller does and does not do), for
:meth:`~piezolib.workbook.session.Session.summary`.
"""

import numpy as np

from piezolib._checks import check_type
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_causal, fsm_control, fsm_mimo, fsm_models

__all__ = ["claim_rows", "summary_lines", "slashed", "mimo_claim_rows", "mimo_summary_lines",
           "causal_claim_rows", "nonlinear_loop_claim_rows", "order_curve_claim_rows",
           "order_curve_summary_line"]


#: The result class of each argument of :func:`claim_rows` and :func:`summary_lines`.
_RESULTS = {
    "blas": fsm_models.LevelBLAs,
    "scores": fsm_models.LinearScores,
    "change": fsm_models.LevelChange,
    "nonlinear": fsm_models.NonlinearModels,
    "weight": fsm_models.LevelSpreadWeight,
    "nominal": fsm_control.AxisNominal,
    "design": fsm_control.AxisDesign,
    "verified": fsm_control.AxisVerification,
    "coupling": fsm_control.AxisCoupling,
    "mirror": fsm_mimo.MirrorNominal,
    "record": fsm_mimo.MirrorRecord,
    "checked": fsm_mimo.MirrorVerification,
    "exported": fsm_mimo.MirrorExport,
}


def _check_results(**results):
    for name, value in results.items():
        cls = _RESULTS[name]
        check_type(name, value, cls, f"a {cls.__module__.rsplit('.', 1)[-1]}.{cls.__name__}")


def slashed(values):
    """Values per level as ``"a / b / c"`` with two decimals.

    Examples
    --------
    >>> slashed([8.381, 7.95, 5.6])
    '8.38 / 7.95 / 5.60'
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise TypeError(f"values must be a sequence of numbers, got {values!r}")
    values = list(values)
    if not all(isinstance(x, (int, float, np.integer, np.floating)) for x in values):
        raise TypeError(f"values must hold numbers only, got {values!r}"[:200])
    return " / ".join(f"{x:.2f}" for x in values)


def _row(section, quantity, ours, **claim):
    return dict(section=section, quantity=quantity, paper=None, ours=ours, **claim)


def _range(orders):
    orders = [int(n) for n in orders]
    return f"{min(orders)}-{max(orders)}"


def order_curve_claim_rows(curve, scores):
    """The linear baseline per level: the order chosen over the wide range and its test NRMSE.

    Parameters
    ----------
    curve : piezolib.problem.fsm_models.OrderCurve
        The committed validation curve (:func:`~piezolib.problem.fsm_models.read_order_curve`).
    scores : piezolib.problem.fsm_models.LinearScores
        The working models' scores (for the notes).

    Returns
    -------
    list of dict
        Arguments of ``nb.check``: per level the chosen order, whether it lies inside the
        range, and its model's test NRMSE.
    """
    check_type("curve", curve, fsm_models.OrderCurve, "a fsm_models.OrderCurve")
    _check_results(scores=scores)
    pub, span = fsm.PUBLISHED_NRMSE_PERCENT, _range(curve.orders)
    rows = []
    for lv in fsm.LEVELS_MV:
        best = curve.best(lv)
        rows += [
            _row("benchmark", f"linear model at {lv} mV: order chosen by validation over {span}",
                 best, note=f"validation error {100 * min(curve.validation_error[lv]):.2f} %, "
                            f"the next-best order's {100 * curve.margin(lv):.2f} points above"),
            _row("benchmark", f"linear model at {lv} mV: the chosen order lies inside {span}",
                 bool(curve.interior(lv))),
            _row("benchmark", f"test NRMSE, linear model at {lv} mV (order {best}, best of "
                 f"{span})", round(float(curve.test_nrmse[lv]), 3), unit="%", precision=0.01,
                 note=f"committed curve (re-derived by a slow test); published 28th-order BLA "
                      f"at the same level: {pub[fsm_models.SAME_LEVEL_BLA][lv]} %; working "
                      f"model (order {scores.linear.selections[lv].order}): "
                      f"{scores.own(lv):.2f} %")]
    return rows


def order_curve_summary_line(curve, scores):
    """One finding: the linear baseline's orders over the wide range against the working ones.

    Parameters
    ----------
    curve : piezolib.problem.fsm_models.OrderCurve
    scores : piezolib.problem.fsm_models.LinearScores

    Returns
    -------
    str
    """
    check_type("curve", curve, fsm_models.OrderCurve, "a fsm_models.OrderCurve")
    _check_results(scores=scores)
    levels, linear = fsm.LEVELS_MV, scores.linear
    inside = all(curve.interior(lv) for lv in levels)
    return (f"linear baseline per level, order chosen by validation over {_range(curve.orders)}: "
            f"{', '.join(str(curve.best(lv)) for lv in levels)} "
            f"({'each inside the range' if inside else 'NOT all inside the range'}), test NRMSE "
            f"{slashed([curve.test_nrmse[lv] for lv in levels])} %; the working models "
            f"downstream keep orders {', '.join(str(linear.selections[lv].order) for lv in levels)} "
            f"(best of {_range(linear.selections[levels[0]].orders)}): "
            f"{slashed([scores.own(lv) for lv in levels])} %")


def claim_rows(scores, nonlinear, weight, nominal, verified, design):
    """The notebook's claims, in the order of its claim table.

    Parameters
    ----------
    scores : piezolib.problem.fsm_models.LinearScores
    nonlinear : piezolib.problem.fsm_models.NonlinearModels
    weight : piezolib.problem.fsm_models.LevelSpreadWeight
    nominal : piezolib.problem.fsm_control.AxisNominal
    verified : piezolib.problem.fsm_control.AxisVerification
    design : piezolib.problem.fsm_control.AxisDesign

    Returns
    -------
    list of dict
        Arguments of ``nb.check`` (``section, quantity, paper, ours`` and the
        claim's ``unit``, ``note``, ``precision``); none published (``paper``
        None): the benchmark's published numbers are in the notes.
    """
    _check_results(scores=scores, nonlinear=nonlinear, weight=weight, nominal=nominal,
                   verified=verified, design=design)
    linear, pub, sig3 = scores.linear, fsm.PUBLISHED_NRMSE_PERCENT, fsm_control.significant
    rows = []
    for lv in fsm.LEVELS_MV:
        rows += [
            _row("benchmark", f"test NRMSE, working linear model at {lv} mV "
                 f"(order {linear.selections[lv].order}, best of "
                 f"{_range(linear.selections[lv].orders)})", scores.own(lv), unit="%",
                 note=f"the model the scheduled model, the weights and the mu designs use; "
                      f"published 28th-order BLA at the same level: "
                      f"{pub[fsm_models.SAME_LEVEL_BLA][lv]} %; lower is better"),
            _row("benchmark", f"test NRMSE, linear model of order {linear.baseline_order} at "
                 f"{lv} mV", scores.nrmse(linear.at_baseline(lv), lv), unit="%"),
            _row("benchmark", f"test NRMSE, one linear model for all levels, at {lv} mV",
                 scores.nrmse(linear.all_name, lv), unit="%",
                 note=f"published: {pub[fsm_models.ALL_LEVELS_BLA][lv]} %"),
            _row("benchmark", f"noise floor of the metric at {lv} mV",
                 scores.floors[lv].nrmse_percent, unit="%")]
    for name, per_level in nonlinear.scores.items():
        rows += [_row("benchmark", f"test NRMSE, {name}, at {lv} mV", per_level[lv].nrmse_percent,
                      unit="%", note=f"published nonlinear LFR: {pub[fsm_models.LFR][lv]} %; "
                                     "one model for all levels") for lv in fsm.LEVELS_MV]
    o, i = weight.pair
    pair = f"{fsm.INPUT_LABELS[i]} -> {fsm.OUTPUT_LABELS[o]}"
    rows += [
        _row("benchmark", f"level-spread envelope of {pair}, peak",
             float(weight.envelope[weight.i_peak]),
             note=f"at {weight.frequency_Hz[weight.i_peak]:.1f} Hz"),
        _row("benchmark", "covering weight of the level spread covers the envelope",
             bool(weight.coverage.covers)),
        _row("axis mu", f"nominal model of {pair}: order (balanced truncation of "
             f"{nominal.g_full.nstates})", int(nominal.g_nominal.nstates),
             note="lowest order whose levels' spread at 500-1100 Hz is the full model's"),
        _row("axis mu", "nominal model: rms relative FRF error to the BLA below 100 Hz",
             sig3(nominal.rms_error_below_100Hz()), unit="%", precision=0.1,
             note=f"full {nominal.g_full.nstates}-state entry: "
                  f"{nominal.rms_error_below_100Hz(nominal.g_full.nstates):.2f} %"),
        _row("axis mu", "mu_RP upper bound, sampled loop (w-plane)", sig3(verified.mu_upper),
             precision=0.002, note=f"DK controller (its order follows the D-fits), S template "
                                   f"crossing 1 near {design.bandwidth_Hz:g} Hz, one sample of "
                                   "delay"),
        _row("axis mu", "mu_RP lower bound", sig3(verified.mu_lower), precision=0.002)]
    for name, row in verified.loops.iterrows():
        rows += [
            # the slowest pole of a DK controller whose order (22-24 states) moves with the
            # BLAS kernel: 0.994-0.997 under four kernels; the claim is "below 1"
            _row("axis mu", f"sampled loop with the {name}: largest |pole|",
                 sig3(row["sampled loop: largest |pole|"]), precision=0.01, note="stable below 1"),
            _row("axis mu", f"gain margin, {name}", float(f"{row['gain margin [x]']:.2g}"),
                 precision=1.0,
                 note="2 significant digits: the phase crossover sits where K is small"),
            _row("axis mu", f"phase margin, {name}", round(row["phase margin [deg]"]),
                 unit="deg", precision=1.0),
            _row("axis mu", f"disk margin, {name}", round(row["disk margin"], 2),
                 precision=0.02)]
    return rows


def _levels_where(condition):
    return ", ".join(f"{lv} mV" for lv in fsm.LEVELS_MV if condition(lv))


def summary_lines(blas, scores, change, nonlinear, weight, nominal, design, verified, coupling):
    """The closing findings of notebook 10 that are more than one claim, one line each.

    Parameters
    ----------
    blas : piezolib.problem.fsm_models.LevelBLAs
    scores : piezolib.problem.fsm_models.LinearScores
    change : piezolib.problem.fsm_models.LevelChange
    nonlinear : piezolib.problem.fsm_models.NonlinearModels
    weight : piezolib.problem.fsm_models.LevelSpreadWeight
    nominal : piezolib.problem.fsm_control.AxisNominal
    design : piezolib.problem.fsm_control.AxisDesign
    verified : piezolib.problem.fsm_control.AxisVerification
    coupling : piezolib.problem.fsm_control.AxisCoupling

    Returns
    -------
    list of str
        Markdown lines, numbers in the notebook's tables' values.
    """
    _check_results(blas=blas, scores=scores, change=change, nonlinear=nonlinear, weight=weight,
                   nominal=nominal, design=design, verified=verified, coupling=coupling)
    levels, linear = fsm.LEVELS_MV, scores.linear
    same, share = scores.same_level_table(), scores.noise_share_table()
    levels_table, nl = blas.table(), nonlinear.table(scores)
    lfr = fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
    sched = fsm_models.SCHEDULED
    below = _levels_where(lambda lv: nl.loc[fsm_models.level_label(lv), sched] < lfr[lv])
    above = _levels_where(lambda lv: nl.loc[fsm_models.level_label(lv), sched] >= lfr[lv])
    peak_off = weight.coupling.values[~np.eye(3, dtype=bool)]
    loops, i_peak = verified.loops, weight.i_peak
    off = coupling.off_diagonal
    change_from_200 = levels_table.loc["BLA change from 200 mV (rms) [%]"]
    return [
        f"working linear models per level (orders "
        f"{', '.join(str(linear.selections[lv].order) for lv in levels)}, chosen by validation "
        f"on the other group over {_range(linear.selections[levels[0]].orders)}): test NRMSE {slashed(same['ours, order chosen'])} % against the "
        f"published 28th-order BLA's {slashed(same['published BLA (28), same level'])} % "
        f"(100 / 200 / 300 mV)",
        f"at the baseline's order {linear.baseline_order}: "
        f"{slashed(same[f'ours, order {linear.baseline_order}'])} %",
        f"one linear model for all levels: {slashed(same['ours, one model all levels'])} % "
        f"(published {slashed(same['published one BLA all levels'])} %); the published "
        f"nonlinear LFR: {slashed(same['published nonlinear LFR'])} %",
        f"noise floor of the metric: {slashed(same['noise floor'])} %, i.e. "
        f"{slashed(share.loc['share of the squared error that is noise [%]'])} % of our squared "
        f"error is measurement noise: the rest is model error (linear dynamics and hysteresis)",
        f"nonlinear distortion above the noise on the BLA: total/noise variance "
        f"{slashed(levels_table.loc['total / noise variance'])}; the BLA moves by "
        f"{change_from_200['100 mV']:.1f} % (100 mV) and {change_from_200['300 mV']:.1f} % "
        f"(300 mV) from 200 mV",
        f"one model for all levels, not linear in amplitude: amplitude-scheduled (input RMS) "
        f"{slashed(nl[sched])} %, Hammerstein with Prandtl–Ishlinskii operators "
        f"{slashed(nl[fsm_models.HAMMERSTEIN])} %, against the LFR's "
        f"{slashed(nl['published nonlinear LFR'])} %: the scheduled model is below the LFR at "
        f"{below}; above it at {above}, where its error without the noise floor "
        f"({slashed(nl['scheduled: error without noise [%]'])} %) exceeds the LFR's "
        f"({slashed(nl['LFR: error without noise [%]'])} %): the noise floor "
        f"({slashed(nl['noise floor'])} %) explains at most "
        f"{slashed(100 * nl['noise floor'] ** 2 / nl[sched] ** 2)} % of the squared error; the "
        f"rest is the linear models' own error (the per-level linear fits, no pole refinement) "
        f"and the distortions a linear model per level cannot follow",
        f"why the Hammerstein model fails: {change.resonance_share_percent:.0f} % of the BLA's "
        f"change between 100 and 300 mV lies at 600-1500 Hz, around the resonances, which move "
        f"down with the level (a softening stiffness); an operator on the input changes the gain "
        f"at all frequencies alike (low-frequency gain "
        f"+{100 * (np.mean(change.gain_ratio) - 1):.0f} % from 100 to 300 mV) and cannot move a "
        f"resonance",
        f"uncertainty weight of the levels' spread ({weight.pair_label} against the all-levels "
        f"model): envelope peak {weight.envelope[i_peak]:.2f} at "
        f"{weight.frequency_Hz[i_peak]:.0f} Hz, covered by an order-{weight.order} "
        f"weight; cross-coupling: off-diagonal peak gains {peak_off.min():.2f}-"
        f"{peak_off.max():.2f} of the diagonal ones, so a SISO loop is a design of one axis only",
        f"μ controller for the axis {weight.pair_label}: nominal model the (3,3) entry of the "
        f"all-levels model reduced from {nominal.g_full.nstates} to {nominal.g_nominal.nstates} "
        f"states (rms FRF error to the BLA below 100 Hz {nominal.rms_error_below_100Hz():.1f} %, "
        f"the full entry's {nominal.rms_error_below_100Hz(nominal.g_full.nstates):.1f} %), "
        f"designed in the w-plane of the sampled loop with one sample of delay: μ_RP "
        f"{verified.mu_upper:.3f} (lower bound {verified.mu_lower:.3f}) with a "
        f"{design.K_w.nstates}-state controller; crossover {loops['crossover [Hz]'].min():.0f}-"
        f"{loops['crossover [Hz]'].max():.0f} Hz; the sampled loop is stable with each level's "
        f"own model, gain margins {loops['gain margin [x]'].min():.1f}-"
        f"{loops['gain margin [x]'].max():.1f}, phase margins "
        f"{loops['phase margin [deg]'].min():.0f}-{loops['phase margin [deg]'].max():.0f}°, "
        f"disk margins {loops['disk margin'].min():.2f}-{loops['disk margin'].max():.2f}",
        f"a SISO loop is one axis, not the mirror: in the band 5-50 Hz the off-diagonal gains "
        f"are {off.min():.2f}-{off.max():.2f} of the diagonal ones, and with the loop on "
        f"actuator {coupling.pair[1] + 1} the displacements d_1, d_2 move by "
        f"{coupling.moves.iloc[0, 0]:.2f}, {coupling.moves.iloc[1, 0]:.2f} µm per µm of "
        f"d_{coupling.pair[0] + 1}'s reference at 10 Hz (other actuators open)",
        "the mirror as a whole: the 3 × 3 μ controller of the last section (its lines follow)",
    ]


def mimo_claim_rows(mirror, record, checked, exported=None):
    """The 3 x 3 section's claims: the MIMO controller beside the three SISO loops.

    Every quantity names "MIMO" (the 3 x 3 problem), and the margin and step rows
    "disk margin" and "cross-talk"; each row of the 3 x 3 controller has its twin for the
    three SISO loops closed together on the coupled mirror.

    Parameters
    ----------
    mirror : piezolib.problem.fsm_mimo.MirrorNominal
    record : piezolib.problem.fsm_mimo.MirrorRecord
    checked : piezolib.problem.fsm_mimo.MirrorVerification
    exported : piezolib.problem.fsm_mimo.MirrorExport, optional
        The float32 export of the 3 x 3 controller (its rows follow the controller's).

    Returns
    -------
    list of dict
        Arguments of ``nb.check`` (none published).
    """
    _check_results(mirror=mirror, record=record, checked=checked)
    if exported is not None:
        _check_results(exported=exported)
    sig3 = fsm_control.significant
    rows = [_row("MIMO mu", "MIMO: nominal 3 x 3 model, states (of the all-levels model's "
                 f"{mirror.G_full.nstates})", int(mirror.G_nominal.nstates),
                 note="lowest order whose levels' spread at 500-1100 Hz is the full model's "
                      "(reduction table)")]
    table = checked.table()
    for name in table.columns:
        col = table[name]
        who = "3 x 3 mu controller" if name == fsm_mimo.MIMO else "3 SISO loops together"
        rows += [
            _row("MIMO mu", f"MIMO problem, {who}: controller states", int(col["states"]),
                 note=(f"reduced from {record.K_full_order} (DK) to the lowest order within "
                       f"{record.params['reduction_precision']} of its mu_RP"
                       if name == fsm_mimo.MIMO else "three axis designs of fsm_control, "
                       "same weights, each on its diagonal entry")),
            _row("MIMO mu", f"MIMO problem, {who}: mu_RP upper bound (w-plane, fine grid)",
                 sig3(col["mu_RP upper"]), precision=0.01,
                 note="full 3 x 3 output-multiplicative block, performance block 3 x 9"),
            _row("MIMO mu", f"MIMO problem, {who}: mu_RP lower bound",
                 sig3(col["mu_RP lower"]), precision=0.01)]
        for (cname, mname), r in checked.loops.iterrows():
            if cname != name:
                continue
            rows.append(_row("MIMO mu", f"MIMO sampled loop, {who}, {mname}: largest |pole|",
                             round(float(r["largest |pole|"]), 4), precision=0.002,
                             note="stable below 1; one sample of delay; 4 decimals (the "
                                  "slowest closed-loop pole is near z = 1)"))
        rows.append(_row("MIMO mu", f"MIMO step cross-talk, {who}: worst off-diagonal peak "
                         "over the diagonal step (all models)",
                         sig3(col["worst cross-talk (all models)"]), precision=0.005,
                         note="0.25 s after a 1 um step on one reference; inf where a loop is "
                              "unstable"))
        if checked.margins is not None:
            m = checked.margins.xs(name, level=0)
            for col_name, short in (("multi-loop disk margin, input", "multi-loop disk margin "
                                     "at the plant input"),
                                    ("multi-loop disk margin, output", "multi-loop disk margin "
                                     "at the plant output"),
                                    ("loop-at-a-time disk margin, input (smallest)",
                                     "loop-at-a-time disk margin at the plant input, smallest")):
                rows.append(_row("MIMO mu", f"MIMO {who}: {short} (worst model)",
                                 sig3(float(m[col_name].min())), precision=0.002,
                                 note="diskmargin's alpha; NaN where a loop is unstable"))
        if exported is not None and name == fsm_mimo.MIMO:
            x = exported.export
            rows += [
                _row("MIMO mu", "MIMO 3 x 3 mu controller, float32 export: largest relative "
                     "response error", float(f"{x.max_error:.1g}"), precision=1e-4,
                     note=f"{x.form} form, basis condition {x.basis_condition:.3g}; first-order "
                          f"rounding bound {np.nanmax(x.bound):.2g}"),
                _row("MIMO mu", "MIMO 3 x 3 mu controller, float32 export: sampled loop, "
                     "largest |pole| (worst model)", round(max(exported.radius32.values()), 4),
                     precision=0.002, note="stable below 1")]
    return rows


def mimo_summary_lines(mirror, record, checked):
    """The 3 x 3 section's findings, one line each (Markdown).

    Parameters
    ----------
    mirror : piezolib.problem.fsm_mimo.MirrorNominal
    record : piezolib.problem.fsm_mimo.MirrorRecord
    checked : piezolib.problem.fsm_mimo.MirrorVerification

    Returns
    -------
    list of str
    """
    _check_results(mirror=mirror, record=record, checked=checked)
    t = checked.table()
    mimo, siso = t[fsm_mimo.MIMO], t[fsm_mimo.SISO]

    def stab(col):
        return "stable with every level's model" if col["stable with every model"] else \
            f"NOT stable with every model (largest |pole| {col['largest |pole| (all models)']:.3f})"

    lines = [
        f"3 x 3 μ controller of the whole mirror: nominal the all-levels model "
        f"({mirror.G_nominal.nstates} states), the levels' spread as one full complex 3 × 3 "
        f"output block; DK {record.K_full_order} states, reduced to {int(mimo['states'])}: "
        f"μ_RP {mimo['mu_RP upper']:.3f} (lower {mimo['mu_RP lower']:.3f}), {stab(mimo)}, "
        f"worst step cross-talk {mimo['worst cross-talk (all models)']:.3g}",
        f"three SISO loops (one per diagonal entry, the same weights) closed together on the "
        f"coupled mirror: μ_RP of the 3 × 3 problem {siso['mu_RP upper']:.3f} (lower "
        f"{siso['mu_RP lower']:.3f}), {stab(siso)}, worst step cross-talk "
        f"{siso['worst cross-talk (all models)']:.3g}"]
    if checked.margins is not None:
        m = checked.margins
        lines.append(
            "multi-loop disk margins (all channels at once, worst model), input / output: "
            f"3 × 3 {m.xs(fsm_mimo.MIMO)['multi-loop disk margin, input'].min():.3g} / "
            f"{m.xs(fsm_mimo.MIMO)['multi-loop disk margin, output'].min():.3g}, three SISO "
            f"loops {m.xs(fsm_mimo.SISO)['multi-loop disk margin, input'].min():.3g} / "
            f"{m.xs(fsm_mimo.SISO)['multi-loop disk margin, output'].min():.3g}")
    return lines


def causal_claim_rows(causal):
    """The claim rows of the causal all-levels model: its test NRMSE per level beside the
    published neural LFR's, and the drift-free noise floor per level.

    Parameters
    ----------
    causal : piezolib.problem.fsm_causal.CausalScores

    Returns
    -------
    list of dict
        Arguments of ``nb.check``: ``paper`` the LFR's NRMSE (the model to beat, not a value
        to reproduce: a "differs" verdict with the reason "method", lower is better).
    """
    check_type("causal", causal, fsm_causal.CausalScores,
               "a fsm_causal.CausalScores (fsm_causal.score_causal_model)")
    lfr = fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
    rows = []
    for lv in fsm.LEVELS_MV:
        ours = causal.nrmse(lv)
        rows.append(dict(section="benchmark", quantity=f"{fsm_causal.CAUSAL}, test NRMSE, {lv} mV",
                         paper=lfr[lv], ours=ours, unit="%", precision=0.01, reason="method",
                         note=f"paper: the published neural LFR (one model, all levels); lower is "
                              f"better: {'below' if ours < lfr[lv] else 'above'} it by "
                              f"{abs(lfr[lv] - ours):.2f} points; {causal.fit.chosen}, causal, "
                              f"one least-squares fit"))
    for lv in fsm.LEVELS_MV:
        rows.append(_row("benchmark", f"noise floor of the metric without the drift at {lv} mV",
                         causal.drift_free_floors[lv].nrmse_percent, unit="%",
                         note="the periods' difference minus its constant offset per record"))
    return rows



def nonlinear_loop_claim_rows(loop):
    """Claims of the 3 x 3 controller's loop closed with the causal nonlinear model: per
    reference stepped, the final value over the reference and the worst cross-talk.

    Parameters
    ----------
    loop : piezolib.problem.fsm_mimo.NonlinearLoop

    Returns
    -------
    list of dict
        Arguments of ``nb.check``.
    """
    check_type("loop", loop, fsm_mimo.NonlinearLoop, "a fsm_mimo.NonlinearLoop (nonlinear_loop)")
    nl = loop.table.xs("causal nonlinear model", axis=1, level=0)
    lin = loop.table.xs("all-levels linear model", axis=1, level=0)
    rows = []
    for i, (step, row) in enumerate(nl.iterrows()):
        where = f"MIMO 3 x 3 mu controller with the causal nonlinear model, {step}"
        rows.append(_row("MIMO mu", f"{where}: final value / reference", float(row.iloc[0]),
                         precision=1e-3, note=f"a {loop.step_um[i]:.2f} um step, after "
                         f"{fsm_mimo.STEP_SAMPLES} samples; with the all-levels linear model "
                         f"{lin.iloc[i, 0]:.4f}"))
        rows.append(_row("MIMO mu", f"{where}: cross-talk", float(row.iloc[1]), precision=1e-3,
                         note=f"peak of the other two outputs over the final value; linear "
                              f"model {lin.iloc[i, 1]:.4f}; largest |u| {row.iloc[2]:.3f} V"))
    return rows
