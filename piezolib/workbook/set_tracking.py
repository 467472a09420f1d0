"""Tracking over a model set: the Table 5 test on every member of the uncertainty set.

The experiments of :mod:`piezolib.workbook.experiments` run the nominal
virtual stage.  :func:`tracking_over_set` runs one case of the tracking test
on a copy of the stage per member of a
:class:`~piezolib.uncertainty.ModelSet` (the paper's 729 models with ±5 % on
a0…a5, or a random sample of the box), all members at once on the batched
loop (one state array per state, :meth:`VirtualStage.over_model_set`), at
the loop's rate with its computation delay.  Members whose loop is unstable
are named, not run: for Case II the open-loop unstable plants, for Cases
III–IV the members whose sampled loop (exact ZOH plant, the controller's
float32 sections, the delay) has a pole on or outside the unit circle
(:func:`piezolib.uncertainty.sampled.sampled_loop_unstable`).  Every member
uses the stage's own noise seed, so members differ by their plant only.
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from piezolib._checks import check_integer, check_type
from piezolib.problem import paper
from piezolib.problem.stage import StageSaturationWarning, VirtualStage
from piezolib.robust.export import SOSController
from piezolib.uncertainty.modelset import ModelSet, check_model_set, unstable_members
from piezolib.uncertainty.sampled import sampled_loop_poles
from piezolib.workbook.experiments import (MIN_MEASURED_S, _positive_values, run_case,
                                           tracking_periods, tracking_reference)
from piezolib.workbook.loop import (COMPUTATION_DELAY_SAMPLES, DISCARD_PERIODS,
                                    discrete_controller)

__all__ = ["SetTracking", "tracking_over_set", "MEMBERS_PER_BATCH", "LIGHT_DAMPING"]

#: Members run in one batch: the 1 Hz run of 200 members logs about 0.35 GB, and
#: batches of a few hundred run faster per member than one of all 729 (cache).
MEMBERS_PER_BATCH = 200

#: Damping ratio below which a stable loop's oscillatory pole rings through a
#: tracking run (zeta = 0.01 at 1 kHz decays by 1/e only after 16 ms).
LIGHT_DAMPING = 0.01


@dataclass(frozen=True, eq=False)
class SetTracking:
    """One case of the tracking test over a model set.

    Attributes
    ----------
    errors : pandas.DataFrame
        Tracking error [%] (:meth:`LoopResult.tracking_error_percent`), one
        row per member (index ``member``), one column per frequency [Hz];
        NaN for the members not run (unstable).
    unstable : ndarray of int
        Members whose loop is unstable: the open-loop plant (Case II) or
        the sampled closed loop (Cases III-IV).
    spectral_radius, damping : ndarray or None
        Of each member's sampled loop (Cases III-IV): the largest pole
        radius and the smallest damping ratio of its poles, zeta =
        -Re(s) / |s| with s = ln(z) / T (1 for a pole on the positive real
        axis; negative for an unstable pole).
    saturated : pandas.DataFrame
        Limited samples per member and frequency (DAC/amplifier input,
        amplifier output, ADC; 0 where not run).
    case : str
        The case run ("II", "III").
    mset : ModelSet
    delay_samples : int
    seconds : float
        Wall time of the runs [s].
    samples : int
        Loop samples run (members × samples of every reference).
    """

    errors: pd.DataFrame
    unstable: np.ndarray
    spectral_radius: object
    damping: object
    saturated: pd.DataFrame
    case: str
    mset: ModelSet = field(repr=False)
    delay_samples: int
    seconds: float
    samples: int

    @property
    def stable(self):
        """Indices of the members that were run."""
        return np.setdiff1d(np.arange(self.mset.size), self.unstable)

    def lightly_damped(self):
        """Stable members whose sampled loop has a pole damped less than :data:`LIGHT_DAMPING`."""
        if self.damping is None:
            return np.array([], dtype=int)
        return np.flatnonzero((self.damping < LIGHT_DAMPING) & (self.spectral_radius < 1.0))

    def summary(self):
        """Per frequency: members run, unstable, lightly damped and saturated; the median,
        95th percentile and worst error [%] and the worst member."""
        e = self.errors
        return pd.DataFrame({
            "members run": e.notna().sum(),
            "unstable": len(self.unstable),
            "lightly damped": len(self.lightly_damped()),
            "saturated": (self.saturated > 0).sum(),
            "median [%]": e.median(),
            "95th percentile [%]": e.quantile(0.95),
            "worst [%]": e.max(),
            "worst member": e.idxmax(),
        }).rename_axis("frequency [Hz]")


    def overview(self, frequencies_Hz=(10.0, 50.0)):
        """One line of the set: members run, unstable, lightly damped and saturated, and the
        median, 95th percentile and worst error [%] at each of ``frequencies_Hz`` it has."""
        s = self.summary()
        at = [f for f in frequencies_Hz if f in s.index]
        return {"members run": int(s["members run"].iloc[0]),
                "unstable": len(self.unstable),
                f"lightly damped (zeta < {LIGHT_DAMPING:g})": len(self.lightly_damped()),
                "saturated": int((self.saturated > 0).any(axis=1).sum()),
                **{f"median at {f:g} Hz [%]": s.loc[f, "median [%]"] for f in at},
                **{f"95th pct at {f:g} Hz [%]": s.loc[f, "95th percentile [%]"] for f in at},
                **{f"worst at {f:g} Hz [%]": s.loc[f, "worst [%]"] for f in at}}

    def goal_shares(self, goals=None, stretch_pct=2.0):
        """Share [%] of the stable members meeting each goal of Sec. IV-B, both, and
        < ``stretch_pct`` at 50 Hz (NaN without a 50 Hz column).

        Parameters
        ----------
        goals : dict, optional
            Default the paper's :data:`~piezolib.problem.paper.DESIGN_GOALS`.
        stretch_pct : float
            The stricter bound at 50 Hz [%].
        """
        goals = paper.DESIGN_GOALS if goals is None else goals
        g10, g50 = goals["peak_to_peak_error_pct_up_to_10Hz"], goals["peak_to_peak_error_pct_at_50Hz"]
        e = self.errors.dropna()
        low = e[[f for f in e.columns if f <= 10.0]].max(axis=1) < g10
        at_50 = (e[50.0] < g50) if 50.0 in e else None
        return {f"meets < {g10:g} % up to 10 Hz [%]": 100 * low.mean(),
                f"meets < {g50:g} % at 50 Hz [%]": np.nan if at_50 is None else 100 * at_50.mean(),
                "meets both [%]": np.nan if at_50 is None else 100 * (low & at_50).mean(),
                f"< {stretch_pct:g} % at 50 Hz [%]":
                    100 * (e[50.0] < stretch_pct).mean() if 50.0 in e else np.nan}


def _loop_poles(mset, controller, fs, delay):
    """(spectral radius, smallest damping ratio) of each member's sampled loop with the
    controller as it runs."""
    if isinstance(controller, SOSController):
        Kd = controller.to_statespace("float32")      # the coefficients the loop runs
    else:
        Kd = discrete_controller(controller, fs)
    z = sampled_loop_poles(mset, Kd, 1.0 / fs, delay)
    s = np.log(np.where(z == 0, np.finfo(float).tiny, z))     # in units of 1/T
    return np.abs(z).max(axis=1), (-s.real / np.abs(s)).min(axis=1)


def _subset(mset, members):
    return ModelSet(mset.plant, mset.spread, mset.levels, mset.offsets[members])


def tracking_over_set(stage, mset, model, controller=None, case="III", frequencies_Hz=None,
                      amplitude_um=None, discard_periods=DISCARD_PERIODS,
                      min_measured_s=MIN_MEASURED_S, delay_samples=COMPUTATION_DELAY_SAMPLES):
    """Run one case of the tracking test on every member of a model set.

    Parameters
    ----------
    stage : VirtualStage
        The nominal stage; member k is ``stage.over_model_set(mset)`` member k
        (its plant replaced, everything else kept).
    mset : ModelSet
        The members (normally around ``stage.settings.plant``).
    model : HysteresisModel
        The feedforward of Cases II-III (a
        :class:`~piezolib.workbook.two_dof.TwoDofFeedforward` makes Case III
        the 2-DOF loop of Case IV).
    controller : see :func:`piezolib.workbook.loop.run_loop`
        Case III's feedback (an SOSController runs in float32).
    case : {"II", "III"}
    frequencies_Hz : sequence of float, optional
        Default the paper's 1, 10, 20, 30, 40, 50 Hz.
    amplitude_um : float, optional
        Default 12 um.
    discard_periods, min_measured_s, delay_samples
        As in :func:`piezolib.workbook.experiments.tracking_test`.

    Returns
    -------
    SetTracking
    """
    check_type("stage", stage, VirtualStage, "a VirtualStage")
    check_model_set(mset)
    if case not in ("II", "III"):
        raise ValueError(f"case must be 'II' or 'III' (Case IV is Case III with a "
                         f"TwoDofFeedforward), got {case!r}")
    if case == "III" and controller is None:
        raise ValueError("controller must be given for case III")
    frequencies_Hz = _positive_values("frequencies_Hz", frequencies_Hz,
                                      paper.TRACKING_TEST["frequencies_Hz"])
    amplitude_um = paper.TRACKING_TEST["amplitude_um"] if amplitude_um is None else amplitude_um
    delay = check_integer("delay_samples", delay_samples, minimum=0)
    start, samples = time.perf_counter(), 0
    if case == "III":
        rho, zeta = _loop_poles(mset, controller, stage.fs, delay)
        unstable = np.flatnonzero(rho >= 1.0)
    else:
        (rho, zeta), unstable = (None, None), unstable_members(mset)
    stable = np.setdiff1d(np.arange(mset.size), unstable)
    chunks = [stable[i:i + MEMBERS_PER_BATCH] for i in range(0, len(stable), MEMBERS_PER_BATCH)]
    batches = [stage.over_model_set(_subset(mset, members)) for members in chunks]
    errors = np.full((mset.size, len(frequencies_Hz)), np.nan)
    saturated = np.zeros((mset.size, len(frequencies_Hz)), dtype=int)
    for j, f in enumerate(frequencies_Hz):
        periods = tracking_periods(f, discard_periods, min_measured_s)
        v_r = tracking_reference(f, periods, amplitude_um, stage.fs)[1]
        for members, batch in zip(chunks, batches):
            with warnings.catch_warnings():
                # counted per member below: a warning per batch would say less
                warnings.simplefilter("ignore", StageSaturationWarning)
                runs = run_case(case, batch, v_r, model, controller, delay_samples=delay)
            errors[members, j] = [r.tracking_error_percent(f, discard_periods, amplitude_um)
                                  for r in runs]
            saturated[members, j] = [r.saturation_count for r in runs]
            samples += len(members) * len(v_r)
    columns = pd.Index(frequencies_Hz, name="frequency_Hz")
    index = pd.RangeIndex(mset.size, name="member")
    return SetTracking(pd.DataFrame(errors, index, columns), unstable, rho, zeta,
                       pd.DataFrame(saturated, index, columns), case, mset, delay,
                       time.perf_counter() - start, samples)
