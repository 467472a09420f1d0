"""Notebook 08's control stages on a user's own records: the mu controller for the real-time
loop, its verification independent of the synthesis, and the Tables 4-5-style experiments on
the virtual stage.

One call per stage, each returning a result with its display and ``checks``
(as the stages of :mod:`piezolib.workbook.your_stage`)::

    design = design_for_loop(model, weight, error_weight, output_weight, rolloff, ...)
    verification = verify_design(design, model, weight)
    experiments = run_experiments(design, choice, seed=7, ...)   # on the virtual stage

Each needs the plant: without an identification record it passes on the
:class:`~piezolib.workbook.your_stage.Skipped` it is given.
"""

import time
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from piezolib import hysteresis as hy
from piezolib import robust
from piezolib._checks import (check_integer, check_mapping, check_positive,
                              check_positive_values, check_type)
from piezolib.problem import analysis, genplant
from piezolib.problem.design import design_controller
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments as exps
from piezolib.workbook.loop import DISCARD_PERIODS
from piezolib.workbook.your_stage import (Identification, KnownTruth, Skipped,
                                          UncertaintyWeight, _Shown, ran)
from piezolib.workbook.your_stage_hysteresis import HysteresisChoice

__all__ = ["LoopDesign", "Verification", "Experiments", "design_for_loop", "verify_design",
           "run_experiments"]

#: Grid of the design's verification: mu bounds and the roll-off [rad/s].
VERIFICATION_GRID = (-2, 7, 1200)


# -- 6. the mu controller at the control-loop rate ---------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class LoopDesign(_Shown):
    """The mu controller designed for the real-time loop, reduced and discretised.

    Attributes
    ----------
    H_e, H_y : control.TransferFunction
        Error and output weights.
    rolloff : piezolib.problem.genplant.RolloffWeight
    design : piezolib.problem.design.ControllerDesign
        What :func:`~piezolib.problem.design.design_controller` returned.
    delay_samples : int
        The loop's computation delay [samples].
    seconds : float
    """

    H_e: object
    H_y: object
    rolloff: object
    design: object
    delay_samples: int
    seconds: float

    @property
    def K(self):
        """The reduced continuous controller."""
        return self.design.K_reduced

    @property
    def K_d(self):
        """The discrete controller the loop runs."""
        return self.design.K_discrete

    @property
    def lines(self):
        d = self.design
        return (f"design {self.seconds:.1f} s: DK mu_RP {d.musyn.mu_peak:.3f} "
                f"(lower {d.musyn.mu_lower_peak:.3f}), {d.K_full.nstates} -> {self.K.nstates} "
                f"states; discretised at {d.fs:g} Hz, response match below "
                f"{d.discrete.check_Hz:g} Hz: {d.discrete.matches}",)

    @property
    def checks(self):
        d, h = self.design, self.design.musyn.history
        return {"DK bounds ordered (lower <= upper)":
                bool(np.all(h.mu_lower <= h.mu_upper * (1 + 1e-6))),
                "the discrete controller matches and its loop is stable":
                bool(d.discrete.matches and d.discrete.loop_stable)}


def _check_plant_results(identification, weight, truth=None):
    check_type("identification", identification, Identification,
               "the Identification of your_stage.identify")
    check_type("weight", weight, UncertaintyWeight,
               "the UncertaintyWeight of your_stage.uncertainty_weight")
    if truth is not None and not isinstance(truth, Skipped):
        check_type("truth", truth, KnownTruth, "the KnownTruth of your_stage.known_truth, or None")


def design_for_loop(identification, weight, error_weight, output_weight, rolloff, *, order,
                    d_order, iterations, fs, delay_samples):
    """A mu controller for the identified model at the real-time loop's rate and delay.

    The synthesis plant models the loop's hold and computation delay (Padé)
    and the roll-off weight (:func:`piezolib.problem.design.design_controller`):
    a quick DK-iteration, balanced reduction to ``order`` states, Tustin
    discretisation.

    Parameters
    ----------
    identification : Identification or Skipped
    weight : UncertaintyWeight or Skipped
        H_m is its covering weight.
    error_weight, output_weight : dict
        Keyword arguments of :func:`piezolib.robust.sensitivity_weight` (H_e on |S|)
        and :func:`~piezolib.robust.complementary_sensitivity_weight` (H_y on |T|).
    rolloff : dict
        Keyword arguments of :class:`piezolib.problem.genplant.RolloffWeight`;
        its frequency [rad/s] must lie below the loop's Nyquist frequency pi fs.
    order, d_order, iterations : int
        Controller states, D-scaling order, DK-iterations.
    fs : float
        The real-time loop's rate [Hz] (not the records').
    delay_samples : int
        The loop's computation delay [samples].

    Returns
    -------
    LoopDesign or Skipped

    Raises
    ------
    ValueError
        When the roll-off corner lies above the loop's Nyquist frequency.
    """
    if not ran(identification):
        return identification
    _check_plant_results(identification, weight)
    for name, fields in (("error_weight", error_weight), ("output_weight", output_weight),
                         ("rolloff", rolloff)):
        check_mapping(name, fields, "a dict of keyword arguments", empty=True)
    order = check_integer("order", order, minimum=1)
    d_order = check_integer("d_order", d_order, minimum=0)
    iterations = check_integer("iterations", iterations, minimum=1)
    fs = check_positive("fs", fs)
    delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
    H_e = robust.sensitivity_weight(**error_weight, inputs="v_e", outputs="y1", name="H_e")
    H_y = robust.complementary_sensitivity_weight(**output_weight, inputs="v_y", outputs="y2",
                                                  name="H_y")
    rolloff = genplant.RolloffWeight(**rolloff)
    if not rolloff.frequency < np.pi * fs:
        raise ValueError(f"rolloff: its frequency {rolloff.frequency:g} rad/s lies above the "
                         f"loop's Nyquist frequency {np.pi * fs:g} rad/s")
    t0 = time.perf_counter()
    design = design_controller(identification.model, weight.weight, H_e, H_y, order=order,
                               d_order=d_order, max_iter=iterations, fs=fs,
                               delay_samples=delay_samples, rolloff=rolloff, fixed_order=False)
    return LoopDesign(H_e, H_y, rolloff, design, delay_samples, time.perf_counter() - t0)


# -- verification, independent of the synthesis ------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class Verification(_Shown):
    """The designed loop recomputed: mu bounds (Padé and exact delay) and loop figures per plant.

    Attributes
    ----------
    loop : LoopDesign
    omega : ndarray
        The fine grid of the mu bounds [rad/s].
    mu_pade, mu_exact : piezolib.robust.MuResult
        mu_RP bounds of the reduced controller, with the Padé and the exact delay.
    plants : dict
        {"identified": G_id, ...}: the plants the loop is checked with.
    table : pandas.DataFrame
        One column per plant: closed-loop poles, Table 3's nominal norms,
        the sampled loop's spectral radius per delay, delay, phase and disk margins.
    seconds : float
    """

    loop: object
    omega: np.ndarray
    mu_pade: object
    mu_exact: object
    plants: dict
    table: pd.DataFrame
    seconds: float

    @property
    def lines(self):
        p, e = self.mu_pade, self.mu_exact
        return (f"mu_RP of the {self.loop.K.nstates}-state controller: Pade delay "
                f"{p.upper.max():.3f} (lower {p.lower.max():.3f}); exact delay "
                f"{e.upper.max():.3f} (lower {e.lower.max():.3f}); verification "
                f"{self.seconds:.1f} s",)

    def _tables(self):
        return ((self.table, True),)

    def radius(self, plant, delay):
        """Spectral radius of the sampled loop with ``delay`` samples, for one plant."""
        return float(self.table.loc[f"radius, {delay} delay", plant])

    @property
    def checks(self):
        K, r, delay = self.loop.K, self.loop.rolloff, self.loop.delay_samples
        high = self.omega[self.omega > 2 * r.frequency]
        col = self.table["identified"]
        return {
            "mu bounds ordered (Pade and exact delay)":
            all(bool(np.all(m.lower <= m.upper * (1 + 1e-6)))
                for m in (self.mu_pade, self.mu_exact)),
            "continuous loop stable": bool(col["max Re closed-loop pole [rad/s]"] < 0),
            f"sampled loop stable with {delay} sample(s) of delay":
            bool(col[f"radius, {delay} delay"] < 1),
            f"the controller rolls off: |K| < {r.hf_gain:g} above twice the roll-off frequency":
            bool(np.all(np.abs(np.ravel(K(1j * high))) < r.hf_gain))}


def verify_design(loop, identification, weight, truth=None):
    """Recompute the designed loop independently of the synthesis.

    mu upper and lower bounds of the reduced controller on a fine grid, with
    the synthesis plant's Padé delay and with the exact delay; with each plant
    (the identified one, and the true one where known): the continuous
    closed-loop poles, Table 3's nominal conditions, the spectral radius of the
    sampled loop (ZOH plant, z^-d, discrete controller) for 0 ... d + 1 samples
    of delay, the delay margin and the classical margins.

    Parameters
    ----------
    loop : LoopDesign or Skipped
    identification : Identification
    weight : UncertaintyWeight
    truth : KnownTruth, optional

    Returns
    -------
    Verification or Skipped
    """
    if not ran(loop):
        return loop
    check_type("loop", loop, LoopDesign, "the LoopDesign of design_for_loop")
    _check_plant_results(identification, weight, truth)
    d = loop.design
    fs, delay = d.fs, loop.delay_samples
    t0 = time.perf_counter()
    fine = np.logspace(*VERIFICATION_GRID)                               # rad/s
    blk = genplant.DESIGN_BLOCK_STRUCTURE
    G_id, W_m, K = identification.model, weight.weight, loop.K
    mu_pade = robust.mussv(robust.lft_response(d.plant, K, fine), blk, fine)
    mu_exact = robust.mussv(genplant.delayed_closed_loop_response(
        K, G_id, W_m, loop.H_e, loop.H_y, fine, fs=fs, delay_samples=delay,
        rolloff=loop.rolloff), blk, fine)
    plants = {"identified": G_id, **({"true G (known here)": truth.plant} if ran(truth) else {})}
    rows = {}
    for name, G in plants.items():
        a = analysis.analyze(K, G, W_m, loop.H_e, loop.H_y, name=name)
        tol = robust.delay_tolerance(G, loop.K_d, delays=range(delay + 2))
        m = robust.loop_margins(G, K)
        rows[name] = {"max Re closed-loop pole [rad/s]": robust.closed_loop_poles(G, K).real.max(),
                      "||H_e S||": a.norm_He_S, "||H_y T||": a.norm_Hy_T, "mu_RS (H_m T)": a.mu_RS,
                      **{f"radius, {k} delay": r for k, r in zip(tol.delays, tol.spectral_radius)},
                      "delay margin [samples]": tol.delay_margin_samples,
                      "phase margin [deg]": m.phase_margin_deg, "disk margin": m.disk_margin}
    table = pd.DataFrame(rows)
    return Verification(loop, fine, mu_pade, mu_exact, plants, table, time.perf_counter() - t0)


# -- 8. the Tables 4-5-style experiment on the virtual stage -----------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class Experiments(_Shown):
    """Tables 4-5-style runs on the virtual stage with the Dahl feedforward (Cases I-III).

    Attributes
    ----------
    table4, table5 : piezolib.workbook.experiments results
        :func:`~piezolib.workbook.experiments.hysteresis_test` and
        :func:`~piezolib.workbook.experiments.tracking_test`.
    chosen4 : result or None
        Table 4 with the chosen model's feedforward when it is not the Dahl model.
    chosen_name : str
    n_warnings : int
        Warnings the runs raised.
    seconds : float
    """

    table4: object
    table5: object
    chosen4: object
    chosen_name: str
    n_warnings: int
    seconds: float

    @property
    def extra4(self):
        """{label: Series}: Case II with the chosen model's feedforward (empty for Dahl)."""
        return {} if self.chosen4 is None else {
            f"II: {self.chosen_name} feedforward": self.chosen4.table.loc["case_II"]}

    @property
    def table4_view(self):
        """Table 4 with the chosen model's Case II as a further row."""
        view = self.table4.table.copy()
        for label, series in self.extra4.items():
            view.loc[label] = series.values
        return view

    @property
    def saturated(self):
        """Samples at an output limit in all runs."""
        return int(self.table4.saturation.values.sum() + self.table5.saturation.values.sum())

    @property
    def lines(self):
        return (f"experiments {self.seconds:.1f} s; {self.n_warnings} warning(s); saturated "
                f"samples: {self.saturated}",)

    def _tables(self):
        return ((self.table4_view, True), (self.table5.table, True))

    @property
    def checks(self):
        cases = ["case_I", "case_II", "case_III"]
        return {"no experiment diverged (every Table 4-5 value finite)":
                all(bool(np.all(np.isfinite(t.loc[cases].values)))
                    for t in (self.table4.table, self.table5.table))}


def run_experiments(loop, choice, *, seed, noise_rms_V, amplitudes_V, periods, frequencies_Hz,
                    amplitude_um, delay_samples, loop_rate_Hz, noise_seeds=None):
    """Tables 4-5-style runs on the virtual stage: Cases I-III with the Dahl feedforward.

    The tables use the Dahl feedforward (the paper's method); when another
    model is chosen, Table 4 runs with its feedforward as well.

    Parameters
    ----------
    loop : LoopDesign or Skipped
    choice : HysteresisChoice
    seed : int
        The stage's noise seed.
    noise_rms_V : float
        Sensor noise [V].
    amplitudes_V : sequence of float
        Table 4's actuator amplitudes [V].
    periods : int
        Periods per amplitude.
    frequencies_Hz : sequence of float
        Table 5's triangle frequencies [Hz].
    amplitude_um : float
        Table 5's amplitude [um].
    delay_samples : int
        The loop's computation delay [samples].
    loop_rate_Hz : float
        The rate the controller was designed for; the stage's loop must run at it.
    noise_seeds : int, optional
        Run every case for this many noise seeds (``seed``, ``seed + 1``, ...; at
        least 2) at once and report the mean with its 95 % interval.  A single run's
        small errors (Case III) move by a few % between machines' rounding paths,
        since the 16-bit converters turn a last-digit change into another code; the
        mean over seeds is a statistic that stays within its interval.  Default: one
        run with ``seed``.

    Returns
    -------
    Experiments or Skipped

    Raises
    ------
    ValueError
        When the virtual stage's loop does not run at ``loop_rate_Hz``.
    """
    if not ran(loop):
        return loop
    check_type("loop", loop, LoopDesign, "the LoopDesign of design_for_loop")
    check_type("choice", choice, HysteresisChoice, "the HysteresisChoice of fit_hysteresis")
    amplitudes_V = check_positive_values("amplitudes_V", amplitudes_V).tolist()
    periods = check_integer("periods", periods, minimum=1)
    frequencies_Hz = check_positive_values("frequencies_Hz", frequencies_Hz).tolist()
    amplitude_um = check_positive("amplitude_um", amplitude_um)
    delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
    loop_rate_Hz = check_positive("loop_rate_Hz", loop_rate_Hz)
    seeds = None
    if noise_seeds is not None:
        noise_seeds = check_integer("noise_seeds", noise_seeds, minimum=2)
        seeds = tuple(range(seed, seed + noise_seeds))
    stage = VirtualStage(seed=seed, noise_rms_V=noise_rms_V)
    if stage.fs != loop_rate_Hz:
        raise ValueError(f"loop_rate_Hz: the experiment loop runs at {stage.fs:g} Hz, the "
                         f"controller was designed for {loop_rate_Hz:g} Hz")
    chosen = choice.chosen
    dahl_ff = chosen if isinstance(chosen, hy.DahlModel) else choice.fits["Dahl"].model
    test4 = dict(amplitudes_V=amplitudes_V, periods=periods, discard_periods=DISCARD_PERIODS,
                 delay_samples=delay_samples, seeds=seeds)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as run_warnings:
        warnings.simplefilter("always")
        table4 = exps.hysteresis_test(stage, dahl_ff, loop.K_d, **test4)
        table5 = exps.tracking_test(stage, dahl_ff, loop.K_d, frequencies_Hz=frequencies_Hz,
                                    amplitude_um=amplitude_um, delay_samples=delay_samples,
                                    seeds=seeds)
        chosen4 = None if chosen is dahl_ff else exps.hysteresis_test(stage, chosen, loop.K_d,
                                                                      **test4)
    return Experiments(table4, table5, chosen4, choice.chosen_name, len(run_warnings),
                       time.perf_counter() - t0)
