"""Models of the CubeSpec fine steering mirror benchmark, identified and scored (notebook 10).

The steps of the benchmark's identification, each returning a result that
holds its tables and the ``checks`` it states ({what it states: bool}):

* :func:`level_blas`: the training records and the best linear
  approximation (robust method) at each excitation level;
* :func:`fit_linear_models`: per level a linear model of the order chosen by
  validation on the other group of realisations, one of the baselines' order,
  and one model for all levels (the mean BLA);
* :func:`score_linear_models`: the benchmark's metric of every model on every
  test set, beside the published baselines and the metric's noise floor;
* :func:`level_change`: where in frequency the BLA moves with the level;
* :func:`fit_nonlinear_models`: one model for all levels that is not linear in
  amplitude (Hammerstein with Prandtl-Ishlinskii operators; amplitude-scheduled);
* :func:`level_spread_weight`: the relative error of the levels' models against
  the all-levels model for one input-output pair and a weight that covers it;
* :func:`derive_order_curve`: the order validation curve over a wide range (up to
  the subspace fit's largest order), committed as :data:`ORDER_CURVE_FILE`
  (:func:`read_order_curve`): where its best point lies.

Frequencies in Hz, inputs in V, outputs in m (the models) or um (tables).
"""

import json
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from piezolib import files
from piezolib import identification as ident
from piezolib import uncertainty as unc
from piezolib._checks import (check_band, check_finite_array, check_index_pair, check_integer,
                              check_integers, check_nonnegative, check_path, check_type)
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import paths

__all__ = ["LevelBLAs", "level_blas", "LinearModels", "fit_linear_models", "LinearScores",
           "score_linear_models", "LevelChange", "level_change", "NonlinearModels",
           "fit_nonlinear_models", "LevelSpreadWeight", "level_spread_weight",
           "level_label", "BANDS_HZ", "HAMMERSTEIN", "SCHEDULED", "WIDE_ORDERS",
           "ORDER_CURVE_FILE", "OrderCurve", "derive_order_curve", "write_order_curve",
           "read_order_curve", "CurveSelection"]

#: Frequency bands [Hz] over which the BLA's change with the level is split.
BANDS_HZ = ((0, 600), (600, 900), (900, 1100), (1100, 1500), (1500, 3000))
#: The bands around the mirror's resonances [Hz] (a sum of bands of :data:`BANDS_HZ`).
RESONANCE_BANDS_HZ = ((600, 900), (900, 1100), (1100, 1500))
#: Names of the two models for all levels that are not linear in amplitude.
HAMMERSTEIN = "Hammerstein (PI + all-levels linear)"
SCHEDULED = "amplitude-scheduled (per-level models blended by input RMS)"
LFR = "nonlinear LFR (neural network), all levels"
SAME_LEVEL_BLA = "BLA (28th order) trained at the same level"
ALL_LEVELS_BLA = "one BLA on all levels"


def level_label(level_mV):
    """The column label of a level, e.g. ``"100 mV"``.

    Examples
    --------
    >>> level_label(200)
    '200 mV'
    """
    return f"{fsm._level(level_mV)} mV"


def _power(x):
    return float(np.mean(np.abs(x) ** 2))


def _per_level(values):
    return {level_label(lv): v for lv, v in zip(fsm.LEVELS_MV, values)}


@dataclass(frozen=True)
class LevelBLAs:
    """The training records and the BLA of every level (:func:`level_blas`).

    Attributes
    ----------
    train : dict {int: (ndarray, ndarray)}
        Inputs [V] and outputs [m] of the training set per level [mV].
    blas : dict {int: identification.PeriodicBLA}
        The BLA with its noise and distortion variances per level.
    file_problems : dict
        :func:`piezolib.problem.fsm_benchmark.check_files` (empty: all intact).
    """

    train: dict
    blas: dict
    file_problems: dict

    @property
    def frequency_Hz(self):
        """The excited lines [Hz] (the same at every level)."""
        return self.blas[fsm.LEVELS_MV[0]].frequency_Hz

    def description(self):
        """One line: the files, the lines, the groups and periods per level."""
        b = self.blas[fsm.LEVELS_MV[0]]
        files = "all intact" if not self.file_problems else self.file_problems
        return (f"data files checked against the manifest: {files}; {b.lines.size} excited "
                f"lines, {b.frequency_Hz[0]:.3f}-{b.frequency_Hz[-1]:.1f} Hz; {b.n_groups} "
                f"groups x {b.n_periods} periods per level")

    def curves(self):
        """BLA, noise and distortion standard deviations per level label (for the figure)."""
        return ({level_label(lv): bl.G for lv, bl in self.blas.items()},
                {level_label(lv): bl.std_noise for lv, bl in self.blas.items()},
                {level_label(lv): bl.std_distortion for lv, bl in self.blas.items()})

    def table(self):
        """Noise and distortion relative to the BLA, its change and its first peak per level."""
        b200 = self.blas[200].G
        return pd.DataFrame({level_label(lv): {
            "noise / BLA (rms ratio) [%]": 100 * np.sqrt(np.mean(bl.var_noise) / _power(bl.G)),
            "distortion / BLA (rms ratio) [%]":
                100 * np.sqrt(np.mean(bl.var_distortion) / _power(bl.G)),
            "total / noise variance": float(np.mean(bl.var_total) / np.mean(bl.var_noise)),
            "BLA change from 200 mV (rms) [%]": 100 * np.sqrt(_power(bl.G - b200) / _power(b200)),
            "peak of |G[0,0]| at [Hz]": float(self.frequency_Hz[np.argmax(np.abs(bl.G[0, 0]))]),
        } for lv, bl in self.blas.items()})

    @property
    def checks(self):
        """The robust method's variances on every line, distortion above the noise."""
        out = {}
        for lv, bl in self.blas.items():
            out[f"{lv} mV: BLA of 3 x 3 on 3839 lines, noise variance on every line"] = bool(
                bl.G.shape == (3, 3, 3839) and np.all(bl.var_noise > 0))
            out[f"{lv} mV: total variance > 1.5 x noise variance (nonlinear distortions)"] = \
                bool(np.mean(bl.var_total) > 1.5 * np.mean(bl.var_noise))
        return out


def level_blas(folder=None):
    """The training records of every level and their BLA (robust method).

    Parameters
    ----------
    folder : str or Path, optional
        The benchmark's data folder (default :func:`fsm_benchmark.data_folder`).

    Returns
    -------
    LevelBLAs
    """
    problems = fsm.check_files(folder)
    train = {lv: fsm.load(lv, "train", folder) for lv in fsm.LEVELS_MV}
    blas = {lv: ident.bla_periodic(*train[lv], fsm.SAMPLING_FREQUENCY_HZ) for lv in fsm.LEVELS_MV}
    return LevelBLAs(train=train, blas=blas, file_problems=problems)


@dataclass(frozen=True)
class LinearModels:
    """Linear models per level and for all levels (:func:`fit_linear_models`).

    Attributes
    ----------
    models : dict {str: (int or "all", control.StateSpace)}
        Name -> (training level [mV], discrete model, 3 inputs [V] -> 3 outputs [m]).
    selections : dict {int: identification.OrderSelection or CurveSelection}
        The order selection per level (``order``, ``orders``, ``validation_error``).
    baseline_order : int
    G_all : ndarray, shape (3, 3, F)
        The mean BLA of the levels [m/V] (the all-levels model's data).
    """

    models: dict
    selections: dict
    baseline_order: int
    G_all: np.ndarray

    def chosen(self, level_mV):
        """Name of the model of ``level_mV`` at the order chosen by validation."""
        return f"ours, order chosen ({self.selections[level_mV].order}), trained at {level_mV} mV"

    def at_baseline(self, level_mV):
        """Name of the model of ``level_mV`` at the baselines' order."""
        return f"ours, order {self.baseline_order}, trained at {level_mV} mV"

    @property
    def order_all(self):
        """Order of the all-levels model (the one chosen at 200 mV)."""
        return self.selections[200].order

    @property
    def all_name(self):
        """Name of the all-levels model."""
        return f"ours, one model for all levels (order {self.order_all})"

    def model(self, name):
        """The model called ``name``."""
        return self.models[name][1]

    def validation_table(self):
        """Validation error per candidate order (rows) and level (columns)."""
        return pd.DataFrame({level_label(lv): pd.Series(sel.validation_error, index=sel.orders)
                             for lv, sel in self.selections.items()}).rename_axis("order")


@dataclass(frozen=True)
class CurveSelection:
    """An order chosen from a committed validation curve (:meth:`OrderCurve.selection`).

    Attributes
    ----------
    order : int
        The candidate with the smallest validation error.
    orders : ndarray of int
        The candidates.
    validation_error : ndarray
        Their validation errors (relative FRF error on the other group).
    """

    order: int
    orders: np.ndarray
    validation_error: np.ndarray


def fit_linear_models(blas, orders, baseline_order, curve=None):
    """Per level: the order chosen by validation and the baselines' order; one for all levels.

    Candidate orders are fitted on the BLA of one group of realisations and
    scored on the other's; the chosen order is refitted on the level's whole
    BLA.  The all-levels model is fitted to the mean of the levels' BLAs at
    the order chosen at 200 mV.  Given a committed ``curve`` whose orders
    include the candidates, the choice is read from its validation errors
    instead of fitting every candidate (the same numbers: the curve is the
    same validation; its slow test re-derives it), and only the chosen orders
    are fitted.

    Parameters
    ----------
    blas : LevelBLAs
    orders : sequence of int
        Candidate orders.
    baseline_order : int
        The published baselines' order (28), fitted too.
    curve : OrderCurve, optional
        The validation curve (:func:`read_order_curve`) the choice is read from.

    Returns
    -------
    LinearModels
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (level_blas)")
    orders = check_integers("orders", orders, minimum=1)
    baseline_order = check_integer("baseline_order", baseline_order, minimum=1)
    if curve is not None:
        check_type("curve", curve, OrderCurve, "an OrderCurve (read_order_curve)")
        curve.selection(fsm.LEVELS_MV[0], orders)          # the candidates lie on the curve
    fs = fsm.SAMPLING_FREQUENCY_HZ
    common = dict(input_labels=fsm.INPUT_LABELS, output_labels=fsm.OUTPUT_LABELS)
    models, selections = {}, {}
    for lv, bl in blas.blas.items():
        if curve is None:
            sel = ident.select_order(bl.G_groups[0], bl.G_groups[1], bl.frequency_Hz, fs, orders)
        else:
            sel = curve.selection(lv, orders)
        selections[lv] = sel
        models[f"ours, order chosen ({sel.order}), trained at {lv} mV"] = (lv, ident.fit_frf(
            bl.G, bl.frequency_Hz, fs, sel.order, **common))
        models[f"ours, order {baseline_order}, trained at {lv} mV"] = (lv, ident.fit_frf(
            bl.G, bl.frequency_Hz, fs, baseline_order, **common))
    G_all = np.mean([bl.G for bl in blas.blas.values()], axis=0)
    order_all = selections[200].order
    models[f"ours, one model for all levels (order {order_all})"] = ("all", ident.fit_frf(
        G_all, blas.frequency_Hz, fs, order_all, **common))
    return LinearModels(models=models, selections=selections, baseline_order=baseline_order,
                        G_all=G_all)


@dataclass(frozen=True)
class LinearScores:
    """The benchmark's metric of every linear model on every level (:func:`score_linear_models`).

    Attributes
    ----------
    linear : LinearModels
    scores : dict {str: {int: fsm_benchmark.Score}}
        Per model name, per test level [mV].
    floors, train_floors : dict {int: fsm_benchmark.Score}
        The metric's noise floor on the test and on the training sets.
    largest_pole_radius : float
        The largest pole radius of all models (stable below 1).
    """

    linear: LinearModels
    scores: dict
    floors: dict
    train_floors: dict
    largest_pole_radius: float

    def nrmse(self, name, level_mV):
        """Test NRMSE [%] of the model ``name`` at ``level_mV``."""
        return self.scores[name][level_mV].nrmse_percent

    def own(self, level_mV):
        """Test NRMSE [%] of the level's own model (order chosen) on its test set."""
        return self.nrmse(self.linear.chosen(level_mV), level_mV)

    def table(self):
        """Every model on every level, the published baselines and the noise floor [%]."""
        rows = {name: {level_label(lv): s.nrmse_percent for lv, s in per_level.items()}
                for name, per_level in self.scores.items()}
        for name, per_level in fsm.PUBLISHED_NRMSE_PERCENT.items():
            rows[f"published: {name}"] = {level_label(lv): v for lv, v in per_level.items()}
        rows["noise floor of the metric (a perfect model)"] = {
            level_label(lv): self.floors[lv].nrmse_percent for lv in fsm.LEVELS_MV}
        return pd.DataFrame(rows).T

    def same_level_table(self):
        """Each level's own models on its test set beside the baselines and the floor [%]."""
        levels, lin, pub = fsm.LEVELS_MV, self.linear, fsm.PUBLISHED_NRMSE_PERCENT
        return pd.DataFrame({
            "ours, order chosen": [self.own(lv) for lv in levels],
            "order": [lin.selections[lv].order for lv in levels],
            f"ours, order {lin.baseline_order}": [self.nrmse(lin.at_baseline(lv), lv)
                                                  for lv in levels],
            "published BLA (28), same level": [pub[SAME_LEVEL_BLA][lv] for lv in levels],
            "ours, one model all levels": [self.nrmse(lin.all_name, lv) for lv in levels],
            "published one BLA all levels": [pub[ALL_LEVELS_BLA][lv] for lv in levels],
            "published nonlinear LFR": [pub[LFR][lv] for lv in levels],
            "noise floor": [self.floors[lv].nrmse_percent for lv in levels],
            "RMSE ours [um]": [self.scores[lin.chosen(lv)][lv].mean_rmse_um for lv in levels],
        }, index=[level_label(lv) for lv in levels])

    def figure_scores(self):
        """The bars of the scores figure: NRMSE [%] per model, per level; and the floor."""
        t = self.same_level_table()
        order = self.linear.baseline_order
        bars = {"ours, order chosen, same level": t["ours, order chosen"],
                f"ours, order {order}, same level": t[f"ours, order {order}"]}
        bars |= {name: t[name] for name in ("published BLA (28), same level",
                                             "ours, one model all levels",
                                             "published one BLA all levels",
                                             "published nonlinear LFR")}
        return list(t.index), bars, t["noise floor"]

    def noise_share_table(self):
        """The noise floor, our NRMSE, the share of the squared error that is noise [%]."""
        return pd.DataFrame({level_label(lv): {
            "noise floor [%]": self.floors[lv].nrmse_percent,
            "noise std per output [um]": ", ".join(f"{x:.4f}" for x in self.floors[lv].rmse_um),
            "ours [%]": self.own(lv),
            "share of the squared error that is noise [%]":
                100 * (self.floors[lv].nrmse_percent / self.own(lv)) ** 2,
            "model error without the noise [%]": np.sqrt(self.own(lv) ** 2
                                                         - self.floors[lv].nrmse_percent ** 2),
            "train-set noise floor [%]": self.train_floors[lv].nrmse_percent,
        } for lv in fsm.LEVELS_MV})

    @property
    def checks(self):
        """Above the noise floor, every model stable, each model best on its own level."""
        out = {f"{lv} mV: the noise floor is below our NRMSE": bool(
            self.floors[lv].nrmse_percent < self.own(lv)) for lv in fsm.LEVELS_MV}
        out["every linear model is stable"] = bool(self.largest_pole_radius < 1)
        for lv in fsm.LEVELS_MV:
            own = self.scores[self.linear.chosen(lv)]
            out[f"the {lv} mV model is best on its own level"] = bool(
                own[lv].nrmse_percent == min(s.nrmse_percent for s in own.values()))
        return out

    @property
    def reference_checks(self):
        """Our per-level model at or below the published 28th-order BLA (the reference's claim)."""
        return {f"{lv} mV: ours at or below the published 28th-order BLA "
                f"({fsm.PUBLISHED_NRMSE_PERCENT[SAME_LEVEL_BLA][lv]} %)": bool(
                    self.own(lv) <= fsm.PUBLISHED_NRMSE_PERCENT[SAME_LEVEL_BLA][lv])
                for lv in fsm.LEVELS_MV}


def score_linear_models(linear):
    """The benchmark's metric of every model on every test set, and the noise floors.

    Parameters
    ----------
    linear : LinearModels

    Returns
    -------
    LinearScores
    """
    check_type("linear", linear, LinearModels, "a LinearModels (fit_linear_models)")
    levels = fsm.LEVELS_MV
    scores = {name: {lv: fsm.score(model, lv) for lv in levels}
              for name, (_, model) in linear.models.items()}
    floors = {lv: fsm.noise_floor(lv) for lv in levels}
    radius = max(float(np.max(np.abs(model.poles()))) for _, model in linear.models.values())
    train_floors = {lv: fsm.noise_floor(lv, "train") for lv in levels}
    return LinearScores(linear=linear, scores=scores, floors=floors, train_floors=train_floors,
                        largest_pole_radius=radius)


@dataclass(frozen=True)
class LevelChange:
    """Where the BLA moves between 100 and 300 mV (:func:`level_change`).

    Attributes
    ----------
    table : pandas.DataFrame
        Per band: the share of the change's power [%] and its size relative to
        the 200 mV BLA in that band [%].
    gain_ratio : list of float
        |G_300 / G_100| on the diagonal at 5-80 Hz (mean over the lines).
    """

    table: pd.DataFrame
    gain_ratio: list

    @property
    def resonance_share_percent(self):
        """Share of the change's power at 600-1500 Hz, around the resonances [%]."""
        return float(self.table.loc["share of the change's power [%]",
                                    [f"{lo}-{hi} Hz" for lo, hi in RESONANCE_BANDS_HZ]].sum())

    def description(self):
        """The low-frequency gain ratio on the diagonal, one line."""
        return ("low-frequency gain 300 mV / 100 mV on the diagonal (5-80 Hz): "
                + ", ".join(f"{g:.3f}" for g in self.gain_ratio))

    @property
    def checks(self):
        """The change lies at the resonances, not at low frequency."""
        return {"less than 5 % of the BLA's change with the level lies below 600 Hz": bool(
            self.table.loc["share of the change's power [%]", "0-600 Hz"] < 5)}


def _check_bands(bands_Hz):
    if isinstance(bands_Hz, (str, bytes)) or not hasattr(bands_Hz, "__len__"):
        raise TypeError(f"bands_Hz must be a sequence of (low, high) bands [Hz], got "
                        f"{bands_Hz!r}")
    if not len(bands_Hz):
        raise ValueError("bands_Hz must hold at least one band")
    for i, band in enumerate(bands_Hz):
        check_band(f"bands_Hz[{i}]", band)


def level_change(blas, bands_Hz=BANDS_HZ):
    """The BLA's change from 100 to 300 mV split by frequency band.

    Parameters
    ----------
    blas : LevelBLAs
    bands_Hz : sequence of (float, float)
        Bands [Hz], lower edge included.

    Returns
    -------
    LevelChange
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (level_blas)")
    _check_bands(bands_Hz)
    f = blas.frequency_Hz
    G = blas.blas
    change = G[300].G - G[100].G
    table = pd.DataFrame({f"{lo}-{hi} Hz": {
        "share of the change's power [%]": 100 * np.sum(np.abs(change[..., m]) ** 2)
                                            / np.sum(np.abs(change) ** 2),
        "change relative to the 200 mV BLA [%]": 100 * np.sqrt(
            np.mean(np.abs(change[..., m]) ** 2) / np.mean(np.abs(G[200].G[..., m]) ** 2)),
    } for lo, hi in bands_Hz for m in [(f >= lo) & (f < hi)]})
    low = (f > 5) & (f < 80)
    gain_ratio = [float(np.abs(np.mean(G[300].G[i, i, low] / G[100].G[i, i, low])))
                  for i in range(3)]
    return LevelChange(table=table, gain_ratio=gain_ratio)


@dataclass(frozen=True)
class NonlinearModels:
    """Two models for all levels that are not linear in amplitude (:func:`fit_nonlinear_models`).

    Attributes
    ----------
    hammerstein : identification.PlayHammerstein
        Play operators per actuator ahead of the all-levels linear model.
    scheduled : identification.ScheduledModel
        The per-level models blended by the input's measured RMS.
    level_rms_V : list of float
        The schedule points: the training inputs' RMS per level [V].
    scores : dict {str: {int: fsm_benchmark.Score}}
        :data:`HAMMERSTEIN` and :data:`SCHEDULED` on each test set.
    blend : dict {int: ndarray}
        The schedule's weights on each level's test records.
    """

    hammerstein: object
    scheduled: object
    level_rms_V: list
    scores: dict
    blend: dict

    @property
    def own_weight(self):
        """The smallest weight of a record's own level's model on any test record."""
        return min(float(self.blend[lv][i].min()) for i, lv in enumerate(fsm.LEVELS_MV))

    def description(self):
        """The schedule points, the own level's smallest weight and the play weights."""
        return (f"schedule points (training input RMS) "
                f"{', '.join(f'{x:.4f}' for x in self.level_rms_V)} V; smallest weight of the "
                f"own level's model on a test record {self.own_weight:.5f}; play weights "
                f"(rows: actuators)\n{np.round(self.hammerstein.weights, 3)}")

    def table(self, linear_scores):
        """NRMSE [%] of both models beside the linear all-levels model, the LFR, the floor."""
        levels = fsm.LEVELS_MV
        lfr = fsm.PUBLISHED_NRMSE_PERCENT[LFR]
        t = pd.DataFrame({
            **{name: [s[lv].nrmse_percent for lv in levels] for name, s in self.scores.items()},
            "ours, one linear model all levels": [
                linear_scores.nrmse(linear_scores.linear.all_name, lv) for lv in levels],
            "published nonlinear LFR": [lfr[lv] for lv in levels],
            "noise floor": [linear_scores.floors[lv].nrmse_percent for lv in levels],
        }, index=[level_label(lv) for lv in levels])
        t["scheduled: error without noise [%]"] = np.sqrt(
            t[SCHEDULED] ** 2 - t["noise floor"] ** 2)
        t["LFR: error without noise [%]"] = np.sqrt(
            t["published nonlinear LFR"] ** 2 - t["noise floor"] ** 2)
        return t

    def checks(self, linear_scores):
        """The schedule picks the own level; the scheduled model below the linear all-levels
        model and above the floor; the Hammerstein model more than 1 point above it (an input
        operator cannot follow the resonances' shift)."""
        out = {}
        for i, lv in enumerate(fsm.LEVELS_MV):
            sched = self.scores[SCHEDULED][lv].nrmse_percent
            out[f"{lv} mV: the schedule weighs the own level's model above 0.99"] = bool(
                self.blend[lv][i].min() > 0.99)
            out[f"{lv} mV: scheduled below the one linear model for all levels"] = bool(
                sched < linear_scores.nrmse(linear_scores.linear.all_name, lv))
            out[f"{lv} mV: scheduled above the noise floor"] = bool(
                sched > linear_scores.floors[lv].nrmse_percent)
            out[f"{lv} mV: Hammerstein more than 1 point above scheduled"] = bool(
                self.scores[HAMMERSTEIN][lv].nrmse_percent > sched + 1)
        return out

    @property
    def reference_checks(self):
        """The scheduled model below the published LFR at 100 mV (the reference's claim)."""
        lfr = fsm.PUBLISHED_NRMSE_PERCENT[LFR][100]
        return {f"100 mV: scheduled below the published LFR ({lfr} %)": bool(
            self.scores[SCHEDULED][100].nrmse_percent < lfr)}


def fit_nonlinear_models(blas, linear, play_thresholds_V):
    """The Hammerstein and the amplitude-scheduled model for all levels, scored on the tests.

    Parameters
    ----------
    blas : LevelBLAs
        The training records (all three levels) and the excited lines.
    linear : LinearModels
        The all-levels model (the Hammerstein model's linear part) and the
        per-level models (the scheduled model's members).
    play_thresholds_V : sequence of float
        Play thresholds [V] of the Prandtl-Ishlinskii operator on each input.

    Returns
    -------
    NonlinearModels
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (level_blas)")
    check_type("linear", linear, LinearModels, "a LinearModels (fit_linear_models)")
    thresholds = check_finite_array("play_thresholds_V", play_thresholds_V, ndim=1,
                                    min_length=1, real=True)
    if thresholds[0] < 0 or np.any(np.diff(thresholds) <= 0):
        raise ValueError(f"play_thresholds_V must be >= 0 and strictly increasing [V], got "
                         f"{thresholds}")
    levels = fsm.LEVELS_MV
    lines = blas.blas[levels[0]].lines
    hammerstein = ident.fit_play_weights(linear.model(linear.all_name),
                                         [blas.train[lv][0] for lv in levels],
                                         [blas.train[lv][1] for lv in levels],
                                         play_thresholds_V, lines)
    level_rms_V = [float(np.mean(ident.input_rms(blas.train[lv][0]))) for lv in levels]
    scheduled = ident.ScheduledModel(tuple(linear.model(linear.chosen(lv)) for lv in levels),
                                     level_rms_V)
    scores = {HAMMERSTEIN: {lv: fsm.score_simulation(hammerstein.simulate, lv) for lv in levels},
              SCHEDULED: {lv: fsm.score_simulation(scheduled.simulate, lv) for lv in levels}}
    blend = {lv: scheduled.blend_weights(fsm.load(lv, "test")[0]) for lv in levels}
    return NonlinearModels(hammerstein=hammerstein, scheduled=scheduled, level_rms_V=level_rms_V,
                           scores=scores, blend=blend)


@dataclass(frozen=True)
class LevelSpreadWeight:
    """The levels' spread around the all-levels model for one pair, and its weight.

    Attributes
    ----------
    pair : (int, int)
        (output, input) indices.
    coupling : pandas.DataFrame
        Peak |G| of the 200 mV BLA relative to the diagonal entry of the same output.
    relative_errors : dict {str: ndarray}
        |G_level / G_all - 1| per level label on the excited lines.
    envelope : ndarray
        Their maximum.
    weight : control.StateSpace
        Stable minimum-phase covering weight of order 4.
    coverage : uncertainty.Coverage
    weight_magnitude : ndarray
        |W| on the lines.
    frequency_Hz : ndarray
    pair_is_largest : bool
        Whether the pair is the diagonal pair with the largest peak gain.
    order : int
        The covering weight's order.
    """

    pair: tuple
    coupling: pd.DataFrame
    relative_errors: dict
    envelope: np.ndarray
    weight: object
    coverage: object
    weight_magnitude: np.ndarray
    frequency_Hz: np.ndarray
    pair_is_largest: bool
    order: int

    @property
    def i_peak(self):
        """Index of the envelope's peak line."""
        return int(np.argmax(self.envelope))

    @property
    def pair_label(self):
        """E.g. ``"v_a3 → d_3"``."""
        return f"{fsm.INPUT_LABELS[self.pair[1]]} → {fsm.OUTPUT_LABELS[self.pair[0]]}"

    def description(self):
        """The envelope's peak and median, the coverage and |W| at 10 Hz and at its peak."""
        i = self.i_peak
        return (f"pair {fsm.INPUT_LABELS[self.pair[1]]} -> {fsm.OUTPUT_LABELS[self.pair[0]]}: "
                f"envelope peak {self.envelope[i]:.3f} at {self.frequency_Hz[i]:.1f} Hz, median "
                f"{np.median(self.envelope):.3f}; weight covers: {self.coverage.covers}, |W| at "
                f"10 Hz {np.interp(10, self.frequency_Hz, self.weight_magnitude):.3f}, peak "
                f"{self.weight_magnitude.max():.3f}")

    @property
    def checks(self):
        """The pair is the largest diagonal one; the weight is stable and covers the envelope."""
        return {"the pair is the diagonal pair with the largest peak gain": self.pair_is_largest,
                "the level-spread weight covers the envelope on every line": bool(
                    self.coverage.covers
                    and np.all(self.weight_magnitude >= self.envelope * (1 - 1e-9))),
                "the level-spread weight is stable": bool(np.all(np.real(self.weight.poles()) < 0))}


def level_spread_weight(blas, linear, pair=(2, 2), order=4):
    """Relative error of each level's model against the all-levels model, and its weight.

    E(omega) = max over levels |G_level(e^{j omega T}) / G_all(e^{j omega T}) - 1|
    on the excited lines for one input-output pair, covered by a stable
    minimum-phase weight (:func:`piezolib.uncertainty.fit_covering_weight`).

    Parameters
    ----------
    blas : LevelBLAs
    linear : LinearModels
    pair : (int, int)
        (output, input) indices; default the (3, 3) entry.
    order : int
        Order of the covering weight.

    Returns
    -------
    LevelSpreadWeight
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (level_blas)")
    check_type("linear", linear, LinearModels, "a LinearModels (fit_linear_models)")
    pair = check_index_pair("pair", pair, (len(fsm.OUTPUT_LABELS), len(fsm.INPUT_LABELS)))
    order = check_integer("order", order, minimum=1)
    f = blas.frequency_Hz
    peak_um_V = 1e6 * np.abs(blas.blas[200].G).max(axis=2)              # (3, 3) peak |G| [um/V]
    coupling = pd.DataFrame(peak_um_V / np.diag(peak_um_V)[:, None], index=fsm.OUTPUT_LABELS,
                            columns=fsm.INPUT_LABELS)
    largest = bool(pair[0] == pair[1] == int(np.argmax(np.diag(peak_um_V))))
    zl = np.exp(2j * np.pi * f / fsm.SAMPLING_FREQUENCY_HZ)
    omega_rad_s = 2 * np.pi * f
    G_nominal = np.asarray(linear.model(linear.all_name)(zl))[pair[0], pair[1]]
    rel_err = {level_label(lv): np.abs(np.asarray(linear.model(linear.chosen(lv))(zl))[
        pair[0], pair[1]] / G_nominal - 1) for lv in fsm.LEVELS_MV}
    envelope = np.max(list(rel_err.values()), axis=0)
    W = unc.fit_covering_weight(omega_rad_s, envelope, order=order, starts=1, inputs="u",
                                outputs="y_Delta", name="W_levels")
    cover = unc.coverage(W, omega_rad_s, envelope)
    W_resp = np.abs(np.ravel(W(1j * omega_rad_s)))
    return LevelSpreadWeight(pair=tuple(pair), coupling=coupling, relative_errors=rel_err,
                             envelope=envelope, weight=W, coverage=cover, weight_magnitude=W_resp,
                             frequency_Hz=f, pair_is_largest=largest, order=order)


#: The wide candidate range of the order validation curve: up to the subspace fit's largest
#: order (``identification.MAX_ROWS`` block rows, order + 8 by default).
WIDE_ORDERS = (24, 32, 40, 48, 56, 64, 72, 80, 88, 92, 96, 104, 112, 120, 128, 136, 144, 152,
               ident.MAX_ROWS - 8)
#: The committed curve, relative to ``data/``.
ORDER_CURVE_FILE = "models/fsm_order_curve.json"


@dataclass(frozen=True)
class OrderCurve:
    """The order validation curve over a wide range (:func:`derive_order_curve`).

    Attributes
    ----------
    orders : tuple of int
    validation_error : dict {int: list of float}
        Per level [mV]: the relative FRF error of each order fitted on group 0 and scored on
        group 1 (:func:`piezolib.identification.select_order`).
    test_nrmse : dict {int: float}
        Per level: the test NRMSE [%] of the level's model at the curve's best order, refitted
        on the whole BLA (as :func:`fit_linear_models` does).
    seconds : float
        Wall time of the derivation [s].
    """

    orders: tuple
    validation_error: dict
    test_nrmse: dict
    seconds: float

    def best(self, level_mV):
        """The order with the smallest validation error at ``level_mV``."""
        return int(self.orders[int(np.argmin(self.validation_error[level_mV]))])

    def selection(self, level_mV, orders):
        """The choice among ``orders`` (all on the curve) at ``level_mV``.

        Parameters
        ----------
        level_mV : int
        orders : sequence of int
            Candidates, each one of :attr:`orders`.

        Returns
        -------
        CurveSelection

        Examples
        --------
        >>> read_order_curve().selection(300, (24, 32, 40, 48)).order
        40
        """
        level = fsm._level(level_mV)
        if level not in self.validation_error:
            raise ValueError(f"level_mV: the curve has levels {sorted(self.validation_error)} "
                             f"mV, got {level_mV}")
        orders = np.asarray(check_integers("orders", orders, minimum=1), dtype=int)
        missing = [int(n) for n in orders if int(n) not in self.orders]
        if missing:
            raise ValueError(f"orders: {missing} are not on the curve (orders {self.orders})")
        errors = np.array([self.validation_error[level][self.orders.index(int(n))]
                           for n in orders])
        return CurveSelection(order=int(orders[int(np.argmin(errors))]), orders=orders,
                              validation_error=errors)

    def margin(self, level_mV):
        """How far the next-lowest validation error lies above the best (absolute, [-])."""
        e = np.sort(np.asarray(self.validation_error[level_mV]))
        return float(e[1] - e[0])

    def smallest_within(self, level_mV, tolerance):
        """The smallest order whose validation error is within ``tolerance`` (absolute, [-])
        of the curve's minimum at ``level_mV`` (the choice robust to the curve's jitter)."""
        tolerance = check_nonnegative("tolerance", tolerance)
        e = np.asarray(self.validation_error[level_mV])
        return int(self.orders[int(np.flatnonzero(e <= e.min() + tolerance)[0])])

    def percent(self):
        """The validation errors [%] per level label (for the figure)."""
        return {level_label(lv): 100 * np.asarray(e) for lv, e in self.validation_error.items()}

    def interior(self, level_mV):
        """Whether the best order lies inside the range (not at either end)."""
        return self.orders[0] < self.best(level_mV) < self.orders[-1]

    def table(self):
        """Validation error [%] per order (rows) and level (columns)."""
        return pd.DataFrame({level_label(lv): pd.Series(100 * np.asarray(e), index=self.orders)
                             for lv, e in self.validation_error.items()}).rename_axis("order")

    def description(self, linear=None):
        """One line per level: the best order, whether it is inside the range, its test NRMSE
        (beside the notebook's chosen order's, given ``linear``: a LinearScores)."""
        lines = []
        for lv in fsm.LEVELS_MV:
            where = "inside the range" if self.interior(lv) else "AT THE END of the range"
            own = "" if linear is None else (f" (order chosen from the notebook's candidates, "
                                             f"{linear.linear.selections[lv].order}: "
                                             f"{linear.own(lv):.2f} %)")
            lines.append(f"{lv} mV: best order {self.best(lv)} of {self.orders[0]}-"
                         f"{self.orders[-1]}, {where} (the next-best order "
                         f"{100 * self.margin(lv):.3f} points above; the smallest order within "
                         f"0.1 points of the minimum: {self.smallest_within(lv, 1e-3)}); its "
                         f"test NRMSE {self.test_nrmse[lv]:.2f} %{own}")
        return "\n".join(lines)


def derive_order_curve(blas, orders=WIDE_ORDERS):
    """The order validation curve of every level over a wide range, and the best order's test
    score.

    Parameters
    ----------
    blas : LevelBLAs
    orders : sequence of int, optional
        Candidate orders (default :data:`WIDE_ORDERS`).

    Returns
    -------
    OrderCurve
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (level_blas)")
    orders = tuple(int(n) for n in check_integers("orders", orders, minimum=1))
    t0 = time.perf_counter()
    fs = fsm.SAMPLING_FREQUENCY_HZ
    errors, test = {}, {}
    for lv, bl in blas.blas.items():
        sel = ident.select_order(bl.G_groups[0], bl.G_groups[1], bl.frequency_Hz, fs, orders)
        errors[lv] = [float(e) for e in sel.validation_error]
        test[lv] = fsm.score(ident.fit_frf(bl.G, bl.frequency_Hz, fs, sel.order), lv).nrmse_percent
    return OrderCurve(orders=orders, validation_error=errors, test_nrmse=test,
                      seconds=time.perf_counter() - t0)


def _order_curve_path(path):
    return paths.data_dir() / ORDER_CURVE_FILE if path is None else check_path("path", path)


def write_order_curve(curve, path=None):
    """Save an :class:`OrderCurve` as JSON (default ``data/`` + :data:`ORDER_CURVE_FILE`).

    Parameters
    ----------
    curve : OrderCurve
    path : str or Path, optional

    Returns
    -------
    Path
    """
    check_type("curve", curve, OrderCurve, "an OrderCurve (derive_order_curve)")
    doc = {"about": "piezolib.problem.fsm_models.derive_order_curve on the FSM benchmark's "
                    "training BLAs (validation: group 0 fit, group 1 scored); re-derived by the "
                    "slow test tests/problem/test_fsm_models.py",
           "orders": list(curve.orders),
           "validation_error": {str(lv): [round(e, 8) for e in v]
                                for lv, v in curve.validation_error.items()},
           "test_nrmse_percent_at_best": {str(lv): round(v, 4) for lv, v in curve.test_nrmse.items()},
           "seconds": round(curve.seconds, 1)}
    return files.atomic_write(_order_curve_path(path), json.dumps(doc, indent=1) + "\n")


def read_order_curve(path=None):
    """The committed :class:`OrderCurve`.

    Parameters
    ----------
    path : str or Path, optional

    Returns
    -------
    OrderCurve

    Examples
    --------
    >>> curve = read_order_curve()
    >>> curve.orders[0], curve.orders[-1]
    (24, 160)
    """
    path = _order_curve_path(path)
    try:
        doc = json.loads(path.read_text())
        return OrderCurve(orders=tuple(doc["orders"]),
                          validation_error={int(k): v for k, v in doc["validation_error"].items()},
                          test_nrmse={int(k): v for k, v in doc["test_nrmse_percent_at_best"].items()},
                          seconds=float(doc["seconds"]))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"path: cannot read an order curve from {path} ({exc})") from None

