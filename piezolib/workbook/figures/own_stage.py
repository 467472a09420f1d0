"""Figures of notebook 08 (your own stage): records, identification, weight, hysteresis,
mu verification and the Tables 4-5-style experiment.

Every ``extra_own_stage_<what>`` function takes the computed arrays and models
with their units spelled out by the caller (nothing here assumes the paper's
3 um/V or x10 amplifier), draws one figure, names it ``extra_own_stage_<what>``
and returns it.  Each ``own_stage_<what>`` function draws the same figure from
the result of a stage of :mod:`piezolib.workbook.your_stage`,
:mod:`~piezolib.workbook.your_stage_hysteresis` or
:mod:`~piezolib.workbook.your_stage_control` (what the notebook calls); for a stage
that did not run (:class:`~piezolib.workbook.your_stage.Skipped`, no identification
record) it draws a figure of the same name that says why.
"""

import numpy as np

from piezolib._checks import check_finite_array, check_signals, check_positive
from piezolib.records import Record
from piezolib import robust
from piezolib.workbook import plotting
from piezolib.workbook import your_stage_claims
from piezolib.workbook.your_stage import ran
from piezolib.workbook.style import PALETTE, db, new_figure
from piezolib.workbook.figures.identification import bode_overlay

__all__ = ["extra_own_stage_records", "extra_own_stage_identification",
           "extra_own_stage_uncertainty", "extra_own_stage_hysteresis",
           "extra_own_stage_mu", "extra_own_stage_experiments",
           "own_stage_records", "own_stage_identification", "own_stage_uncertainty",
           "own_stage_hysteresis", "own_stage_mu", "own_stage_experiments"]

def extra_own_stage_records(records, marks=None):
    """The raw records as loaded: input and output against time, one panel per record.

    Parameters
    ----------
    records : dict
        {label: piezolib.records.Record}.
    marks : dict, optional
        {label: [(t [s], text), ...]}: vertical lines drawn on that record's
        panel (e.g. the operating-point window, the validation split).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_records.png``.
    """
    if not records:
        raise ValueError("records must hold at least one record")
    for label, rec in records.items():
        if not isinstance(rec, Record):
            raise TypeError(f"records[{label!r}] must be a piezolib.records.Record, "
                            f"got {type(rec).__name__}")
    marks = {} if marks is None else dict(marks)
    fig, axes = new_figure(len(records), 1, figsize=(9.0, 2.3 * len(records)),
                           squeeze=False)
    for ax, (label, rec) in zip(axes[:, 0], records.items()):
        ax.plot(rec.time, rec.input, lw=0.7, color=PALETTE.peer)
        ax.set_ylabel(f"{rec.input_name} [{rec.input_unit}]", color=PALETTE.peer)
        right = ax.twinx()
        right.plot(rec.time, rec.output, lw=0.7, color=PALETTE.contrast)
        right.set_ylabel(f"{rec.output_name} [{rec.output_unit}]", color=PALETTE.contrast)
        mine = list(marks.get(label, ()))
        for t, text in mine:
            ax.axvline(t, color="0.3", ls="--", lw=0.8)
        if mine:        # the marks' names as ticks of a top axis, clear of the curves
            top = ax.secondary_xaxis("top")
            top.set_xticks([t for t, _ in mine], [text for _, text in mine], fontsize=7)
        ax.set_title(f"{label}: {len(rec)} samples at {rec.fs:g} Hz", fontsize=9,
                     pad=14 if mine else 6)
    axes[-1, 0].set_xlabel("time [s]")
    plotting.name_figure(fig, None, "own_stage_records")
    return fig


def extra_own_stage_identification(t, y, y_model, models, omega, measured=None, y_truth=None,
                                   output_label="y", zoom_s=None):
    """Held-out validation in time and the identified model against the truth in frequency.

    Parameters
    ----------
    t : array_like
        Time of the held-out samples [s].
    y, y_model : array_like
        Measured output and the identified model's simulated output on them.
    models : dict
        {label: control.LTI}: the Bode panels (identified model, the true
        plant where it is known).
    omega : array_like
        Bode grid [rad/s].
    measured : tuple, optional
        (omega [rad/s], complex response): empirical frequency response.
    y_truth : array_like, optional
        The true plant's simulated output on the same samples (known only on
        the virtual stage), drawn for reference.
    output_label : str
        Name and unit of y, e.g. ``"v_y [V]"``.
    zoom_s : (float, float), optional
        Time window [s] of panel (a) (default: all of ``t``); panel (b)
        always shows all of it.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_identification.png``.
    """
    t, y, y_model = check_signals(2, t=t, y=y, y_model=y_model)
    fig, axes = new_figure(2, 2, figsize=(11.0, 5.6))
    axes[0, 0].plot(t, y, color="0.6", lw=1.2, label="measured (held out)")
    axes[0, 0].plot(t, y_model, lw=0.8, color=PALETTE.peer, label="identified model")
    axes[1, 0].plot(t, y_model - y, lw=0.7, color=PALETTE.peer, label="identified - measured")
    if y_truth is not None:
        t, y_truth = check_signals(2, t=t, y_truth=y_truth)
        axes[0, 0].plot(t, y_truth, "--", lw=0.8, color=PALETTE.agreement, label="true plant")
        axes[1, 0].plot(t, y_truth - y, lw=0.7, color=PALETTE.agreement, alpha=0.7,
                        label="true plant - measured (noise)")
    axes[0, 0].set(ylabel=output_label, xlabel="time [s]",
                   title="(a) held-out part of the record" + ("" if zoom_s is None else ", zoom"))
    if zoom_s is not None:
        lo, hi = (float(z) for z in zoom_s)
        if not hi > lo:
            raise ValueError(f"zoom_s must be (start, stop) with stop > start, got {zoom_s!r}")
        axes[0, 0].set_xlim(lo, hi)
    axes[1, 0].set(xlabel="time [s]", ylabel=f"error, {output_label}",
                   title="(b) simulation error on the held-out part")
    shown = np.ones(t.size, bool) if zoom_s is None else (t >= zoom_s[0]) & (t <= zoom_s[1])
    y_lo, y_hi = (float(f(y[shown] if shown.any() else y)) for f in (np.min, np.max))
    if y_hi > y_lo:                                          # room for the legend on top
        axes[0, 0].set_ylim(y_lo - 0.05 * (y_hi - y_lo), y_hi + 0.6 * (y_hi - y_lo))
    axes[0, 0].legend(fontsize=7, loc="upper center", ncol=3)
    axes[1, 0].legend(fontsize=7)
    bode_overlay(models, omega, measured=measured, axes=(axes[0, 1], axes[1, 1]))
    axes[0, 1].set_title("(c) frequency response")
    axes[0, 1].legend(fontsize=7)
    plotting.name_figure(fig, None, "own_stage_identification")
    return fig


def extra_own_stage_uncertainty(omega, envelope, weight, spread, true_error=None):
    """Relative error envelope of the model set, the fitted weight and the true model error.

    Parameters
    ----------
    omega : array_like
        Frequencies [rad/s].
    envelope : array_like
        E_m(omega) of the coefficient set of the identified model.
    weight : control.LTI
        The covering weight.
    spread : float
        Relative coefficient spread of the set (e.g. 0.02).
    true_error : array_like, optional
        |G_true / G_identified - 1| where the truth is known.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_uncertainty.png``.
    """
    omega = check_finite_array("omega", omega, ndim=1, min_length=2)
    envelope = np.asarray(envelope, dtype=float)
    if envelope.shape != omega.shape:
        raise ValueError("envelope must have the shape of omega")
    spread = check_positive("spread", spread)
    fig, ax = new_figure(figsize=(7.5, 4.0))
    ax.loglog(omega, envelope, color="0.55", lw=1.5,
              label=f"E_m: coefficients +-{100 * spread:g} % (stable members)")
    ax.loglog(omega, np.abs(np.ravel(weight(1j * omega))), color=PALETTE.peer,
              label="covering weight |W|")
    if true_error is not None:
        true_error = np.asarray(true_error, dtype=float)
        if true_error.shape != omega.shape:
            raise ValueError("true_error must have the shape of omega")
        ax.loglog(omega, true_error, "--", color=PALETTE.contrast,
                  label="|G_true / G_identified - 1| (known here)")
    ax.set(xlabel="frequency [rad/s]", ylabel="relative error",
           title="Uncertainty weight of the identified model")
    ax.legend(fontsize=7)
    plotting.name_figure(fig, None, "own_stage_uncertainty")
    return fig


def extra_own_stage_hysteresis(v, x, models, scores, first=0, input_scale=1.0,
                               output_scale=1.0, input_label="v", output_label="x"):
    """A validation loop (not fitted) against each hysteresis model: loops and errors.

    Parameters
    ----------
    v, x : array_like
        Validation input and measured output, in the models' units.
    models : dict
        {name: model with ``simulate(v) -> x``}.
    scores : pandas.DataFrame
        Validation table with an ``RMS %`` column indexed by model name
        (first index level), e.g. from :func:`piezolib.hysteresis.validation_table`.
    first : int
        First sample drawn (the models still run from sample 0).
    input_scale, output_scale : float
        Factors from the models' units to the axes' units (e.g. amplifier
        gain, um per sensor volt).
    input_label, output_label : str
        Axis labels with units.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_hysteresis.png``.
    """
    v, x = check_signals(8, v=v, x=x)
    if not models:
        raise ValueError("models must hold at least one model")
    late = slice(int(first), None)
    fig, (ax, bx) = new_figure(1, 2, figsize=(10.5, 4.0))
    ax.plot(input_scale * v[late], output_scale * x[late], color="0.6", lw=2.0, label="measured")
    for (name, model), color in zip(models.items(), PALETTE.peers):
        x_model = np.asarray(model.simulate(v), dtype=float)
        rms = float(scores.xs(name, level=0)["RMS %"].iloc[0]) if scores.index.nlevels > 1 \
            else float(scores.loc[name, "RMS %"])
        ax.plot(input_scale * v[late], output_scale * x_model[late], lw=0.9, color=color,
                label=f"{name}: RMS {rms:.2f} % of stroke")
        bx.plot(input_scale * v[late], output_scale * (x_model[late] - x[late]), lw=0.8,
                color=color, label=name)
    ax.set(xlabel=input_label, ylabel=output_label, title="(a) validation loop (not fitted)")
    bx.set(xlabel=input_label, ylabel=f"model - measured, {output_label}",
           title="(b) model error along the loop")
    ax.legend(fontsize=7)
    bx.legend(fontsize=7)
    plotting.name_figure(fig, None, "own_stage_hysteresis")
    return fig


def extra_own_stage_mu(omega, mu_bounds, loops, omega_loops, H_e, H_y):
    """mu bounds of the designed loop and its sensitivities with the identified and true plants.

    Parameters
    ----------
    omega : array_like
        mu grid [rad/s].
    mu_bounds : dict
        {label: MussvResult-like with ``upper`` and ``lower`` arrays on omega}.
    loops : dict
        {label: LoopFunctions-like with ``S`` and ``T`` (control.LTI)}.
    omega_loops : array_like
        Grid of panel (b) [rad/s].
    H_e, H_y : control.LTI
        Error and output weights: 1/|H_e| and 1/|H_y| are the templates.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_mu.png``.
    """
    omega = check_finite_array("omega", omega, ndim=1, min_length=2)
    omega_loops = check_finite_array("omega_loops", omega_loops, ndim=1, min_length=2)
    fig, (ax, bx) = new_figure(1, 2, figsize=(11.0, 4.2))
    for (label, res), color in zip(mu_bounds.items(), PALETTE.peers):
        ax.semilogx(omega, res.upper, color=color, label=f"{label}: upper")
        ax.semilogx(omega, res.lower, ":", color=color, lw=2.0, label=f"{label}: lower")
    ax.axhline(1.0, color="0.3", lw=0.8)
    ax.set(xlabel="frequency [rad/s]", ylabel="mu_RP", title="(a) mu bounds, robust performance")
    ax.legend(fontsize=7)
    s = 1j * omega_loops
    bx.semilogx(omega_loops, db(1 / np.ravel(H_e(s))), color="0.5", ls="--",
                label="1/|H_e|")
    bx.semilogx(omega_loops, db(1 / np.ravel(H_y(s))), color="0.5", ls=":",
                label="1/|H_y|")
    for (label, lf), color in zip(loops.items(), PALETTE.peers):
        bx.semilogx(omega_loops, db(np.ravel(lf.S(s))), color=color,
                    label=f"|S|, {label}")
        bx.semilogx(omega_loops, db(np.ravel(lf.T(s))), color=color, ls="-.",
                    label=f"|T|, {label}")
    bx.set(xlabel="frequency [rad/s]", ylabel="magnitude [dB]", ylim=(-80, 20),
           title="(b) sensitivity and complementary sensitivity")
    bx.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    plotting.name_figure(fig, None, "own_stage_mu")
    return fig


def extra_own_stage_experiments(table4, table5, extra4=None, feedforward="feedforward"):
    """The Tables 4-5-style experiment: hysteresis % and tracking error % per case.

    Parameters
    ----------
    table4, table5 : pandas.DataFrame
        Rows ``case_I``, ``case_II``, ``case_III`` (as in
        :func:`piezolib.workbook.experiments.hysteresis_test` /
        :func:`~piezolib.workbook.experiments.tracking_test`), columns the
        amplitudes [V] and frequencies [Hz].
    extra4 : dict, optional
        {label: pandas.Series over table4's columns}: further hysteresis
        rows (e.g. another feedforward), drawn dashed.
    feedforward : str
        Name of Cases II-III's feedforward in the legend (e.g. ``"Dahl feedforward"``).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_own_stage_experiments.png``.
    """
    fig, (ax, bx) = new_figure(1, 2, figsize=(10.5, 4.0))
    labels = {"case_I": "I: open loop", "case_II": f"II: {feedforward}",
              "case_III": f"III: {feedforward} + mu controller"}
    for (row, label), color in zip(labels.items(), PALETTE.peers):
        ax.plot(table4.columns.astype(float), table4.loc[row], "o-", color=color, label=label)
        bx.plot(table5.columns.astype(float), table5.loc[row], "o-", color=color, label=label)
    for (label, series), color in zip((extra4 or {}).items(), PALETTE.peers[3:] + PALETTE.peers):
        ax.plot(series.index.astype(float), series.values, "s--", color=color, label=label)
    ax.set(xlabel="actuator amplitude [V]", ylabel="hysteresis [%]", yscale="log",
           title="(a) Table 4-style: 10 Hz triangles")
    bx.set(xlabel="triangle frequency [Hz]", ylabel="tracking error [%]", yscale="log",
           title="(b) Table 5-style: tracking")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center",
               ncol=min(4, len(ax.get_lines())), fontsize=7)
    plotting.name_figure(fig, None, "own_stage_experiments")
    return fig


# -- the same figures from the stages' results (notebook 08 calls these) ----------------------

def _skipped(what, stage):
    """A figure named ``extra_own_stage_<what>`` that says why its stage did not run."""
    fig, ax = new_figure(figsize=(7.5, 1.2))
    ax.set_axis_off()
    ax.text(0.5, 0.5, stage.reason, ha="center", va="center", wrap=True, fontsize=9)
    plotting.name_figure(fig, None, f"own_stage_{what}")
    return fig


def own_stage_records(records, data):
    """:func:`extra_own_stage_records` of the loaded records, the identification run marked.

    Parameters
    ----------
    records : piezolib.workbook.your_stage.OwnRecords
    data : IdentificationData or Skipped
        Marks the operating window and the start of the held-out part on the
        identification run (Skipped: the loops alone).
    """
    if not ran(data):
        return extra_own_stage_records(records.loops)
    lo, hi = data.window_s
    return extra_own_stage_records(
        {"identification": records.chirp, **records.loops},
        marks={"identification": [(lo, "operating window"), (hi, ""),
                                  (data.held_out.t0, "held out")]})


def own_stage_identification(identification, omega, truth=None, zoom_s=0.02):
    """:func:`extra_own_stage_identification` of an identification (and the true plant).

    Parameters
    ----------
    identification : Identification or Skipped
    omega : array_like
        Bode grid [rad/s], drawn below the records' Nyquist frequency.
    truth : KnownTruth, optional
    zoom_s : float
        Length of the zoom on the start of the held-out part [s].
    """
    if not ran(identification):
        return _skipped("identification", identification)
    d, n_est = identification.data, identification.n_estimation
    omega = np.asarray(omega, dtype=float)
    models = {"identified": identification.model,
              **({"true G (known here)": truth.plant} if ran(truth) else {})}
    h, rec = d.held_out, d.record
    return extra_own_stage_identification(
        h.time, h.output, identification.y_sim[n_est:], models, omega[omega < np.pi * rec.fs],
        measured=identification.measured,
        y_truth=truth.y_true[n_est:] if ran(truth) else None,
        output_label=f"{rec.output_name} [{rec.output_unit}]", zoom_s=(h.t0, h.t0 + zoom_s))


def own_stage_uncertainty(weight, truth=None):
    """:func:`extra_own_stage_uncertainty` of an uncertainty weight (and the true error)."""
    if not ran(weight):
        return _skipped("uncertainty", weight)
    return extra_own_stage_uncertainty(weight.omega, weight.envelope, weight.weight,
                                       weight.spread,
                                       true_error=truth.error if ran(truth) else None)


def own_stage_hysteresis(choice, input_scale=1.0, output_scale=1.0, input_label="v",
                         output_label="x"):
    """:func:`extra_own_stage_hysteresis` of the first validation record of a hysteresis choice.

    Parameters
    ----------
    choice : piezolib.workbook.your_stage_hysteresis.HysteresisChoice
    input_scale, output_scale, input_label, output_label
        As :func:`extra_own_stage_hysteresis`.
    """
    label = choice.validation_names[0]
    return extra_own_stage_hysteresis(
        *choice.validation_data[0][:2], choice.models, choice.scores.xs(label, level="record"),
        input_scale=input_scale, output_scale=output_scale, input_label=input_label,
        output_label=output_label)


def own_stage_mu(verification, omega):
    """:func:`extra_own_stage_mu` of a verification: mu bounds, S and T per plant.

    Parameters
    ----------
    verification : Verification or Skipped
    omega : array_like
        Grid of the S and T panel [rad/s].
    """
    if not ran(verification):
        return _skipped("mu", verification)
    v, K = verification, verification.loop.K
    return extra_own_stage_mu(
        v.omega, {"Pade delay": v.mu_pade, "exact delay": v.mu_exact},
        {name: robust.loop_functions(G, K) for name, G in v.plants.items()}, omega,
        v.loop.H_e, v.loop.H_y)


def own_stage_experiments(experiments, feedforward="Dahl feedforward", written=None):
    """:func:`extra_own_stage_experiments` of the Tables 4-5-style runs.

    ``written``: the claim table they were written to (``nb.claims.save()``); the
    figure then draws the values it holds (:func:`your_stage_claims.written_tables`).
    """
    if not ran(experiments):
        return _skipped("experiments", experiments)
    if written is None:
        return extra_own_stage_experiments(experiments.table4.table, experiments.table5.table,
                                           experiments.extra4, feedforward=feedforward)
    table4, table5 = your_stage_claims.written_tables(experiments, written)
    extra = {label: table4.loc[label] for label in experiments.extra4}
    return extra_own_stage_experiments(table4.drop(index=list(extra)), table5, extra,
                                       feedforward=feedforward)
