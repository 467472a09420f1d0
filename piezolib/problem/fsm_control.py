"""A μ controller for one axis of the fine steering mirror (notebook 10), designed and checked.

Four steps, each a function returning a result with the ``checks`` it states:

* :func:`axis_nominal`: the nominal model of one input-output pair, the entry
  of the all-levels MIMO model (discrete, um/V) reduced by balanced truncation
  in the w-plane (the exact inverse of Tustin's map), with the table of
  reduction errors against the BLA and the levels' spread;
* :func:`design_axis`: the uncertainty weight of the levels' spread around the
  reduced nominal, the performance and roll-off weights, the synthesis plant
  with output-multiplicative uncertainty
  (:func:`piezolib.problem.fsm_benchmark.axis_design_plant`) of z^-1 G(z) in
  the w-plane, DK-iteration, and the controller mapped back with Tustin;
* :func:`verify_axis`: μ bounds on a fine grid, the w-plane closed loop, the
  sampled loop with 0-3 samples of delay, and for each level's own model the
  sampled loop's largest pole and its margins;
* :func:`axis_coupling`: what one SISO loop leaves of the mirror: the BLA's
  coupling in the loop's band and how far the other displacements move.

The DK-iteration takes about 10 CPU-s, so its end point is committed
(:func:`write_axis_design`, ``data/controllers/fsm_axis_design.json``) and
notebook 10 reads it (:func:`read_axis_design`): the record's K with the
weights rebuilt around the given nominal, refused when the nominal or the
design's parameters differ from the record's; the slow test re-derives it.

In the w-plane of the sampled loop, a continuous design mapped back with Tustin
(no pre-warping) *is* the sampled loop: stability, margins and μ are those of
the sampled loop on the warped axis nu = (2/T) tan(omega T / 2).
"""

import json
import time
from dataclasses import dataclass, field

import control as ct
import numpy as np
import pandas as pd

from piezolib import identification as ident
from piezolib import robust
from piezolib import uncertainty as unc
from piezolib._checks import (check_band, check_index_pair, check_integer, check_integers,
                              check_lti, check_mapping, check_nonnegative, check_positive,
                              check_path, check_positive_values, check_type)
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import genplant, paths
from piezolib.problem.fsm_models import LevelBLAs, LinearModels

__all__ = ["UM_PER_M", "REDUCTION_ORDERS", "BLOCKS", "axis_entry", "AxisNominal", "axis_nominal",
           "AxisDesign", "design_axis", "AxisVerification", "verify_axis", "AxisCoupling",
           "axis_coupling", "hz_of_w_plane", "significant", "AXIS_RECORD_NAME", "AxisDKRecord",
           "axis_record_path", "write_axis_design", "read_axis_design"]

#: Micrometres per metre (the axis is designed in um/V).
UM_PER_M = 1e6
#: The orders of the reduction table (below the full entry's).
REDUCTION_ORDERS = (6, 8, 10, 16)
#: Block structure of the axis' robust-performance problem: Delta, then performance.
BLOCKS = ((1, 1), (1, 3))
#: Lines of the resonances where the reduced model must keep the levels' spread [Hz].
RESONANCES_HZ = (500, 1100)
#: The w-plane grid of the verification [rad/s].
FINE_W_PLANE = np.logspace(-1, 7, 1500)
#: The w-plane grid of DK-iteration [rad/s].
DK_W_PLANE = np.logspace(0, 5.5, 200)
#: File name of the committed axis design under ``data/controllers/``.
AXIS_RECORD_NAME = "fsm_axis_design.json"
#: Largest relative difference of the nominal's response from the record's on the excited
#: lines for the record to belong to it (a refit of the same data differs by ~1e-12).
RECORD_NOMINAL_TOLERANCE = 1e-6


def significant(x, digits=3):
    """``x`` rounded to ``digits`` significant digits (the precision a claim states).

    Examples
    --------
    >>> significant(0.76218)
    0.762
    """
    digits = check_integer("digits", digits, minimum=1)
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"x must be a number, got {type(x).__name__}")
    return float(f"{x:.{digits}g}")


def hz_of_w_plane(nu_rad_s, fs=fsm.SAMPLING_FREQUENCY_HZ):
    """Ordinary frequency [Hz] of a w-plane frequency nu [rad/s] at the rate ``fs`` [Hz].

    Examples
    --------
    >>> round(hz_of_w_plane(2 * 6400 * np.tan(np.pi * 100 / 6400)), 6)
    100.0
    """
    nu_rad_s = check_nonnegative("nu_rad_s", nu_rad_s)
    T_s = 1 / check_positive("fs", fs)
    return float(np.arctan(nu_rad_s * T_s / 2) * 2 / T_s / (2 * np.pi))


def axis_entry(model, pair):
    """One SISO entry of a discrete MIMO model in um/V.

    Parameters
    ----------
    model : control.StateSpace
        Discrete, inputs [V] -> outputs [m].
    pair : (int, int)
        (output, input) indices.

    Returns
    -------
    control.StateSpace
        The entry, input [V] -> output [um], with the model's states.

    Examples
    --------
    >>> g = axis_entry(ct.ss([[0.5]], [[1e-6, 2e-6]], [[1.0], [3.0]], [[0, 0], [0, 1e-6]], 1.0),
    ...                (1, 1))
    >>> float(g.B[0, 0]), float(g.C[0, 0]), float(g.D[0, 0])
    (2.0, 3.0, 1.0)
    """
    check_type("model", check_lti("model", model), ct.StateSpace, "a control.StateSpace")
    if not model.isdtime(strict=True):
        raise ValueError("model must be a discrete-time model (the FSM's sampled model), got "
                         "a continuous-time one")
    o, i = check_index_pair("pair", pair, (model.noutputs, model.ninputs))
    return ct.ss(model.A, model.B[:, [i]] * UM_PER_M, model.C[[o]],
                 model.D[[o]][:, [i]] * UM_PER_M, model.dt)


def _response(g, zl):
    return np.ravel(g(zl))


def _levels_spread(g_level, g, zl, level_responses=None):
    """The levels' relative error around ``g`` on every line (max over levels); ``g`` and the
    levels' models may be given as their responses on ``zl`` (arrays) to evaluate them once."""
    resp = g if isinstance(g, np.ndarray) else _response(g, zl)
    if level_responses is None:
        level_responses = [_response(gl, zl) for gl in g_level.values()]
    return np.max([np.abs(r / resp - 1) for r in level_responses], axis=0)


@dataclass(frozen=True)
class AxisNominal:
    """The nominal model of one axis and the reduction that made it (:func:`axis_nominal`).

    Attributes
    ----------
    pair : (int, int)
    g_full : control.StateSpace
        The entry of the all-levels model [um/V], discrete.
    g_level : dict {int: control.StateSpace}
        The entry of each level's own model [um/V].
    g_nominal : control.StateSpace
        The reduced entry (feedthrough zero), discrete.
    reduction : pandas.DataFrame
        Per order: relative FRF errors against the BLA [%] and the levels' spread.
    hankel_relative : ndarray
        Hankel singular values of the full entry in the w-plane over the largest.
    frequency_Hz : ndarray
        The excited lines.
    nominal_order : int
    level_responses : list of ndarray, optional
        The responses of ``g_level`` on the excited lines (computed once; default computed
        when needed).
    """

    pair: tuple
    g_full: object
    g_level: dict
    g_nominal: object
    reduction: pd.DataFrame
    hankel_relative: np.ndarray
    frequency_Hz: np.ndarray
    nominal_order: int
    level_responses: list = field(default=None, repr=False)

    @property
    def zl(self):
        """z on the unit circle at the excited lines."""
        return np.exp(2j * np.pi * self.frequency_Hz / fsm.SAMPLING_FREQUENCY_HZ)

    def spread(self, g):
        """The levels' relative error around ``g`` on every line (max over levels)."""
        return _levels_spread(self.g_level, g, self.zl, self.level_responses)

    def description(self):
        """The pair, the full and nominal orders and the leading Hankel singular values."""
        return (f"pair {fsm.INPUT_LABELS[self.pair[1]]} -> {fsm.OUTPUT_LABELS[self.pair[0]]}: "
                f"full entry {self.g_full.nstates} states, nominal {self.g_nominal.nstates}; "
                f"Hankel singular values (relative) "
                + ", ".join(f"{x:.3f}" for x in self.hankel_relative[:self.nominal_order + 2]))

    def rms_error_below_100Hz(self, order=None):
        """RMS relative FRF error to the BLA below 100 Hz [%] at ``order`` (default nominal)."""
        return float(self.reduction.loc[self.nominal_order if order is None else order,
                                        "rms error < 100 Hz [%]"])

    @property
    def checks(self):
        """The nominal model is within 10 % of the BLA below 100 Hz."""
        return {f"the {self.nominal_order}-state nominal is within 10 % (rms) of the BLA "
                "below 100 Hz": bool(self.rms_error_below_100Hz() < 10)}


def axis_nominal(linear, frequency_Hz, nominal_order, pair=(2, 2),
                 orders=REDUCTION_ORDERS):
    """The nominal model of one axis: its entry of the all-levels model, balanced-truncated.

    The discrete entry is mapped to the w-plane by the exact inverse of
    Tustin's map (which keeps the Hankel singular values), truncated there
    (``control.balred``, DC matched) and mapped back; its feedthrough is set to
    zero.  The table gives, for each order of ``orders``, ``nominal_order`` and
    the full entry, the relative FRF error against the BLA (the levels' mean)
    and the levels' spread at 500-1100 Hz.

    Parameters
    ----------
    linear : piezolib.problem.fsm_models.LinearModels
        The all-levels model, the per-level models and the mean BLA.
    frequency_Hz : array_like
        The excited lines [Hz].
    nominal_order : int
        States of the nominal model.
    pair : (int, int)
        (output, input) indices.
    orders : sequence of int
        Further orders of the reduction table.

    Returns
    -------
    AxisNominal
    """
    nominal_order = check_integer("nominal_order", nominal_order, minimum=1)
    check_type("linear", linear, LinearModels, "a LinearModels (fsm_models.fit_linear_models)")
    f = check_positive_values("frequency_Hz", frequency_Hz)
    pair = check_index_pair("pair", pair, (len(fsm.OUTPUT_LABELS), len(fsm.INPUT_LABELS)))
    orders = check_integers("orders", orders, minimum=1)
    T_s = 1 / fsm.SAMPLING_FREQUENCY_HZ
    zl = np.exp(2j * np.pi * f / fsm.SAMPLING_FREQUENCY_HZ)
    g_full = axis_entry(linear.model(linear.all_name), pair)
    g_level = {lv: axis_entry(linear.model(linear.chosen(lv)), pair) for lv in fsm.LEVELS_MV}
    bla_pair = UM_PER_M * linear.G_all[tuple(pair)]
    g_w_full = ident.d2c(g_full, method="tustin")                      # exact, w-plane

    def truncated(order):
        r = ct.c2d(ct.balred(g_w_full, order, method="matchdc"), T_s, "tustin")
        return ct.ss(r.A, r.B, r.C, np.zeros((1, 1)), T_s)

    def frf_error(resp, f_max):
        m = f <= f_max
        r = resp[m] - bla_pair[m]
        return (100 * np.sqrt(np.mean(np.abs(r) ** 2) / np.mean(np.abs(bla_pair[m]) ** 2)),
                100 * np.max(np.abs(r) / np.abs(bla_pair[m])))

    resonances = (f >= RESONANCES_HZ[0]) & (f <= RESONANCES_HZ[1])
    level_responses = [_response(g, zl) for g in g_level.values()]     # evaluated once
    rows, reduced = {}, {}
    table_orders = sorted({*orders, nominal_order}) + [g_full.nstates]
    for order in table_orders:
        g = g_full if order == g_full.nstates else truncated(order)
        reduced[order] = g
        resp = _response(g, zl)
        below_100 = frf_error(resp, 100)
        rows[order] = {
            "rms error < 100 Hz [%]": below_100[0],
            "max error < 100 Hz [%]": below_100[1],
            "rms error < 300 Hz [%]": frf_error(resp, 300)[0],
            "rms error < 1100 Hz [%]": frf_error(resp, 1100)[0],
            "levels' spread, peak 500-1100 Hz":
                float(_levels_spread(g_level, resp, zl, level_responses)[resonances].max())}
    hankel = ct.hankel_singular_values(g_w_full)
    return AxisNominal(pair=tuple(pair), g_full=g_full, g_level=g_level,
                       g_nominal=reduced[nominal_order],
                       reduction=pd.DataFrame(rows).T.rename_axis("order"),
                       hankel_relative=hankel / hankel[0], frequency_Hz=f,
                       nominal_order=nominal_order, level_responses=level_responses)


@dataclass(frozen=True)
class AxisDesign:
    """The μ design of one axis in the w-plane of the sampled loop (:func:`design_axis`).

    Attributes
    ----------
    G_w : control.StateSpace
        z^-1 G_nominal(z) mapped to the w-plane (exact inverse of Tustin).
    spread, hull : ndarray
        The levels' spread around the nominal on each line and its running maximum.
    W_m : control.StateSpace
        First-order weight covering ``hull`` on the w-plane frequencies.
    coverage : uncertainty.Coverage
        Of ``W_m`` over the raw spread.
    plant : control.StateSpace
        The synthesis plant (:func:`fsm_benchmark.axis_design_plant`, no Pade delay).
    dk : robust.MusynResult
    K_w, K_d : control.StateSpace
        The w-plane controller and the discrete one to implement (Tustin).
    zinv : control.StateSpace
        One sample of delay.
    bandwidth_Hz : float
        Where the template on |S| crosses 1 [Hz].
    params : dict
        The design's choices (the keyword arguments of :func:`design_axis`).
    """

    G_w: object
    spread: np.ndarray
    hull: np.ndarray
    W_m: object
    coverage: object
    plant: object
    dk: object
    K_w: object
    K_d: object
    zinv: object
    bandwidth_Hz: float
    params: dict = field(default_factory=dict)

    def weight_at(self, f_Hz):
        """|W_m| at the ordinary frequency ``f_Hz`` [Hz] (through the w-plane)."""
        T_s = 1 / fsm.SAMPLING_FREQUENCY_HZ
        return float(np.abs(np.ravel(self.W_m(1j * 2 / T_s * np.tan(np.pi * f_Hz * T_s))))[0])

    def description(self):
        """The weight at 10 Hz, 923 Hz and 3 kHz, its coverage, the plant and the DK result."""
        dk = self.dk
        return (f"weight: |W_m| {self.weight_at(10):.3f} at 10 Hz, {self.weight_at(923):.2f} "
                f"at 923 Hz, {self.weight_at(3000):.2f} at 3 kHz; covers the raw spread: "
                f"{self.coverage.covers}; synthesis plant {self.plant.nstates} states; DK: mu "
                f"{dk.mu_peak:.3f} (lower {dk.mu_lower_peak:.3f}), {self.K_w.nstates} states, "
                f"{dk.stop_reason}")

    @property
    def checks(self):
        """The uncertainty weight covers the spread and is stable."""
        return {"the axis' uncertainty weight covers the levels' spread around the nominal":
                    bool(self.coverage.covers),
                "the axis' uncertainty weight is stable": bool(
                    np.all(np.real(self.W_m.poles()) < 0))}


def design_axis(nominal, *, bandwidth_Hz, error_weight, output_weight, output_corner, rolloff,
                dk_iterations):
    """DK-iteration on the w-plane plant of the sampled loop with one sample of delay.

    Uncertainty: the relative error of each level's entry against the reduced
    nominal, made non-decreasing in frequency (its running maximum), covered by
    a first-order weight on every excited line (w-plane frequencies).
    Performance: templates on S (crossing 1 near ``bandwidth_Hz``) and on T
    (roll-off above ``output_corner`` x the bandwidth), a roll-off weight on the
    controller output.

    Parameters
    ----------
    nominal : AxisNominal
    bandwidth_Hz : float
        Where the template on |S| crosses 1 [Hz].
    error_weight, output_weight : dict
        Keyword arguments of :func:`piezolib.robust.sensitivity_weight` and
        :func:`piezolib.robust.complementary_sensitivity_weight` (bounds).
    output_corner : float
        The T template's corner over the bandwidth [-].
    rolloff : dict
        Fields of :class:`piezolib.problem.genplant.RolloffWeight`.
    dk_iterations : int
        At most this many DK iterations.

    Returns
    -------
    AxisDesign
    """
    params = _design_params(nominal, bandwidth_Hz, error_weight, output_weight, output_corner,
                            rolloff, dk_iterations)
    parts = _axis_problem(nominal, params)
    dk = robust.musyn(parts["plant"], BLOCKS, 1, 1, DK_W_PLANE, d_order="auto",
                      max_iter=params["dk_iterations"])
    return _axis_design(parts, dk, params)


def _design_params(nominal, bandwidth_Hz, error_weight, output_weight, output_corner, rolloff,
                   dk_iterations):
    check_type("nominal", nominal, AxisNominal, "an AxisNominal (axis_nominal)")
    bandwidth_Hz = check_positive("bandwidth_Hz", bandwidth_Hz)
    for name, fields in (("error_weight", error_weight), ("output_weight", output_weight),
                         ("rolloff", rolloff)):
        check_mapping(name, fields, "a dict of keyword arguments", empty=True)
    output_corner = check_positive("output_corner", output_corner)
    dk_iterations = check_integer("dk_iterations", dk_iterations, minimum=1)
    return {"bandwidth_Hz": float(bandwidth_Hz),
            "error_weight": {k: float(v) for k, v in error_weight.items()},
            "output_weight": {k: float(v) for k, v in output_weight.items()},
            "output_corner": float(output_corner),
            "rolloff": {k: (int(v) if k == "order" else float(v)) for k, v in rolloff.items()},
            "dk_iterations": int(dk_iterations)}


def _axis_problem(nominal, params, W_m=None):
    """The w-plane plant, the spread, its weight (fitted unless given) and the synthesis plant."""
    fs = fsm.SAMPLING_FREQUENCY_HZ
    T_s = 1 / fs
    omega_rad_s = 2 * np.pi * nominal.frequency_Hz
    zinv = ct.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]], T_s)                # one sample of delay
    nu = 2 / T_s * np.tan(omega_rad_s * T_s / 2)                        # w-plane frequency
    G_w = ident.d2c(ct.series(zinv, nominal.g_nominal), method="tustin")
    spread = nominal.spread(nominal.g_nominal)
    hull = np.maximum.accumulate(spread)                                # non-decreasing
    if W_m is None:
        W_m = unc.fit_covering_weight(nu, hull, order=1, starts=1, inputs="u",
                                      outputs="y_Delta", name="W_m")
    cover = unc.coverage(W_m, nu, spread)
    omega_b = 2 * np.pi * params["bandwidth_Hz"]
    H_e = robust.sensitivity_weight(**params["error_weight"], bandwidth_rad_s=omega_b,
                                    inputs="v_e", outputs="y1", name="H_e")
    H_y = robust.complementary_sensitivity_weight(
        **params["output_weight"], bandwidth_rad_s=params["output_corner"] * omega_b,
        inputs="v_y", outputs="y2", name="H_y")
    W_u = genplant.rolloff_weight(genplant.RolloffWeight(**params["rolloff"]))
    plant = fsm.axis_design_plant(G_w, W_m, H_e, H_y, W_u, fs=fs, delay_samples=None)
    return dict(G_w=G_w, spread=spread, hull=hull, W_m=W_m, coverage=cover, plant=plant,
                zinv=zinv)


def _axis_design(parts, dk, params):
    return AxisDesign(**parts, dk=dk, K_w=dk.K,
                      K_d=ct.c2d(dk.K, 1 / fsm.SAMPLING_FREQUENCY_HZ, "tustin"),
                      bandwidth_Hz=params["bandwidth_Hz"], params=params)


@dataclass(frozen=True)
class AxisDKRecord:
    """The DK-iteration's end point as committed (:func:`read_axis_design`): the fields of
    :class:`piezolib.robust.MusynResult` that the notebook shows.

    Attributes
    ----------
    K : control.StateSpace
        The w-plane controller.
    mu_peak, mu_lower_peak : float
        μ_RP upper and lower bound peaks on :data:`DK_W_PLANE`.
    stop_reason : str
    history : pandas.DataFrame
        One row per iteration (:attr:`piezolib.robust.MusynResult.history`).
    elapsed : float
        Wall time of the DK-iteration when it ran [s] (information only).
    """

    K: object
    mu_peak: float
    mu_lower_peak: float
    stop_reason: str
    history: pd.DataFrame
    elapsed: float


def axis_record_path():
    """Where the committed axis design lives: ``data/controllers/fsm_axis_design.json``.

    Examples
    --------
    >>> axis_record_path().name
    'fsm_axis_design.json'
    """
    return paths.data_dir() / "controllers" / AXIS_RECORD_NAME


def _ss_dict(sys):
    sys = ct.ss(sys)
    return {"A": sys.A.tolist(), "B": sys.B.tolist(), "C": sys.C.tolist(), "D": sys.D.tolist(),
            "dt": (None if sys.dt in (None, 0) else float(sys.dt))}


def _ss_of(d, name="record"):
    """The state space of a :func:`_ss_dict` (also of the mirror's records, fsm_mimo)."""
    try:
        D = np.array(d["D"], dtype=float)
        A = np.array(d["A"], dtype=float)
        n = A.size and int(round(np.sqrt(A.size)))
        A, B, C = (A.reshape(n, n), np.array(d["B"], dtype=float).reshape(n, D.shape[1]),
                   np.array(d["C"], dtype=float).reshape(D.shape[0], n))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{name}: not a state-space record ({exc})") from None
    return ct.ss(A, B, C, D, 0 if d.get("dt") is None else d["dt"])


def write_axis_design(design, nominal, path=None):
    """Write the end point of :func:`design_axis` as JSON (default :func:`axis_record_path`).

    The record holds the design's parameters, the nominal it was designed on
    (to refuse another), the weight W_m, the controller K_w and the DK history.

    Parameters
    ----------
    design : AxisDesign
        From :func:`design_axis`.
    nominal : AxisNominal
        The nominal it was designed on.
    path : str or Path, optional

    Returns
    -------
    Path
    """
    check_type("design", design, AxisDesign, "an AxisDesign (design_axis)")
    check_type("nominal", nominal, AxisNominal, "an AxisNominal (axis_nominal)")
    path = axis_record_path() if path is None else check_path("path", path)
    if not design.params:
        raise ValueError("design: has no params (make it with design_axis)")
    W = ct.tf(design.W_m)
    hist = design.dk.history
    doc = {"format": 1,
           "what": "mu controller of one mirror axis (notebook 10): "
                   "piezolib.problem.fsm_control.design_axis, w-plane of the 6400 Hz loop with "
                   "one sample of delay; re-derived by the slow test "
                   "tests/problem/test_fsm_control.py",
           "pair": list(nominal.pair), "nominal_order": int(nominal.g_nominal.nstates),
           "params": design.params, "g_nominal": _ss_dict(nominal.g_nominal),
           "W_m": {"num": np.ravel(W.num[0][0]).tolist(), "den": np.ravel(W.den[0][0]).tolist()},
           "K_w": _ss_dict(design.K_w),
           "mu_peak": float(design.dk.mu_peak), "mu_lower_peak": float(design.dk.mu_lower_peak),
           "stop_reason": str(design.dk.stop_reason),
           "history": {"columns": [str(c) for c in hist.columns],
                       "rows": [[(None if x is None else float(x)) for x in r]
                                for r in hist.itertuples(index=False)]},
           "seconds": float(getattr(design.dk, "elapsed", float("nan")))}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def read_axis_design(nominal, *, bandwidth_Hz, error_weight, output_weight, output_corner,
                     rolloff, dk_iterations, path=None):
    """The committed axis design rebuilt around ``nominal`` (no DK-iteration).

    The parameters are those of :func:`design_axis`; the record must have been
    designed with the same ones and on the same nominal (its response on the
    excited lines within :data:`RECORD_NOMINAL_TOLERANCE`), else ``ValueError``
    says to re-derive it.  The synthesis plant is rebuilt from the parameters
    and the record's weight W_m, whose coverage of the levels' spread is
    recomputed.

    Parameters
    ----------
    nominal : AxisNominal
    bandwidth_Hz, error_weight, output_weight, output_corner, rolloff, dk_iterations
        As :func:`design_axis`.
    path : str or Path, optional
        Default :func:`axis_record_path`.

    Returns
    -------
    AxisDesign
        Its ``dk`` is an :class:`AxisDKRecord`.
    """
    params = _design_params(nominal, bandwidth_Hz, error_weight, output_weight, output_corner,
                            rolloff, dk_iterations)
    path = axis_record_path() if path is None else check_path("path", path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        g_rec = _ss_of(doc["g_nominal"])
        W_m = ct.tf(doc["W_m"]["num"], doc["W_m"]["den"], inputs="u", outputs="y_Delta",
                    name="W_m")
        K_w = _ss_of(doc["K_w"])
        hist = pd.DataFrame(doc["history"]["rows"], columns=doc["history"]["columns"])
        dk = AxisDKRecord(K=K_w, mu_peak=float(doc["mu_peak"]),
                          mu_lower_peak=float(doc["mu_lower_peak"]),
                          stop_reason=str(doc["stop_reason"]), history=hist,
                          elapsed=float(doc["seconds"]))
        rec_params, rec_pair = doc["params"], tuple(doc["pair"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"path: {path} is not an axis design record ({exc})") from None
    if rec_params != params:
        raise ValueError(f"path: the record {path} was designed with {rec_params}, not "
                         f"{params}: re-derive it (design_axis, write_axis_design)")
    zl = nominal.zl
    ref = _response(nominal.g_nominal, zl)
    diff = float(np.max(np.abs(_response(g_rec, zl) - ref)) / np.max(np.abs(ref)))
    if rec_pair != tuple(nominal.pair) or not diff <= RECORD_NOMINAL_TOLERANCE:
        raise ValueError(f"nominal: the record {path} was designed on another nominal (pair "
                         f"{rec_pair}, response differs by {diff:.2g} relative): re-derive it "
                         "(design_axis, write_axis_design)")
    return _axis_design(_axis_problem(nominal, params, W_m=W_m), dk, params)


@dataclass(frozen=True)
class AxisVerification:
    """Checks of the axis controller independent of the synthesis (:func:`verify_axis`).

    Attributes
    ----------
    mu : robust.MuResult
        μ bounds of the loop on :data:`FINE_W_PLANE`.
    mu_upper, mu_lower : float
        Their peaks.
    peak_Hz : float
        Where the upper bound peaks [Hz].
    wplane_max_real : float
        Largest real part of the w-plane closed-loop poles [rad/s].
    delay_radius : ndarray
        Spectral radius of the sampled loop (ZOH of the nominal) with 0-3
        samples of delay.
    loops : pandas.DataFrame
        Per model (nominal, each level's): states, the sampled loop's largest
        |pole|, stability, gain, phase and disk margins, crossover [Hz].
    """

    mu: object
    mu_upper: float
    mu_lower: float
    peak_Hz: float
    wplane_max_real: float
    delay_radius: np.ndarray
    loops: pd.DataFrame

    def description(self, design):
        """The μ bounds, the closed-loop poles and the delay tolerance, one paragraph."""
        return (f"mu_RP of the {design.K_w.nstates}-state controller on {FINE_W_PLANE.size} "
                f"frequencies: upper {self.mu_upper:.3f}, lower {self.mu_lower:.3f} (largest at "
                f"{self.peak_Hz:.2g} Hz: flat below the bandwidth: the 1 % template on S and the "
                f"{100 * design.weight_at(1):.0f} % spread); w-plane closed loop: largest real "
                f"part {self.wplane_max_real:.1f} rad/s; sampled loop (ZOH of the nominal, "
                f"toolkit) with 0-3 samples of delay: largest |pole| "
                + ", ".join(f"{r:.5f}" for r in self.delay_radius))

    @property
    def checks(self):
        """Bounds ordered, RP met, every loop stable with positive margins."""
        loops = self.loops
        return {
            "mu lower bound <= upper bound on every frequency": bool(
                np.all(self.mu.lower <= self.mu.upper * (1 + 1e-6))),
            "robust performance: mu_RP upper bound < 1": bool(self.mu_upper < 1),
            "the w-plane closed loop is stable": bool(self.wplane_max_real < 0),
            "the sampled loop is stable with 0-3 samples of delay": bool(
                np.all(self.delay_radius < 1)),
            "the sampled loop is stable with the nominal and each level's model": bool(
                loops["stable"].all()),
            "gain margins > 1 and phase margins > 0 with every model": bool(
                (loops["gain margin [x]"] > 1).all() and (loops["phase margin [deg]"] > 0).all()),
            "disk margins > 0 with every model": bool((loops["disk margin"] > 0).all()),
        }


def verify_axis(nominal, design):
    """μ bounds, closed-loop poles, delay tolerance and each level's sampled loop.

    Parameters
    ----------
    nominal : AxisNominal
    design : AxisDesign

    Returns
    -------
    AxisVerification
    """
    check_type("nominal", nominal, AxisNominal, "an AxisNominal (axis_nominal)")
    check_type("design", design, AxisDesign, "an AxisDesign (design_axis)")
    fine = FINE_W_PLANE
    K_w, K_d = design.K_w, design.K_d
    mu = robust.mussv(robust.lft_response(design.plant, K_w, fine), BLOCKS, fine)
    tol = robust.delay_tolerance(ident.d2c(nominal.g_nominal), K_d, delays=(0, 1, 2, 3))
    rows = {}
    models = {"nominal (reduced)": nominal.g_nominal,
              **{f"{lv} mV model": g for lv, g in nominal.g_level.items()}}
    for name, g in models.items():
        L_d = ct.series(design.zinv, g)
        radius = float(np.abs(ct.poles(ct.feedback(ct.series(K_d, L_d), 1))).max())
        m = robust.loop_margins(ident.d2c(L_d, method="tustin"), K_w)
        rows[name] = {"states": g.nstates, "sampled loop: largest |pole|": radius,
                      "stable": radius < 1, "gain margin [x]": m.gain_margin,
                      "phase margin [deg]": m.phase_margin_deg, "disk margin": m.disk_margin,
                      "disk gain margin [x]": m.disk_gain_margin,
                      "disk phase margin [deg]": m.disk_phase_margin_deg,
                      "crossover [Hz]": hz_of_w_plane(m.omega_crossover)}
    return AxisVerification(
        mu=mu, mu_upper=float(mu.upper.max()), mu_lower=float(mu.lower.max()),
        peak_Hz=hz_of_w_plane(fine[np.argmax(mu.upper)]),
        wplane_max_real=float(robust.closed_loop_poles(design.G_w, K_w).real.max()),
        delay_radius=np.asarray(tol.spectral_radius), loops=pd.DataFrame(rows).T)


@dataclass(frozen=True)
class AxisCoupling:
    """What one SISO loop leaves of the mirror (:func:`axis_coupling`).

    Attributes
    ----------
    band : pandas.DataFrame
        RMS gain of the 200 mV BLA at 5-50 Hz relative to the diagonal entry
        of the same output.
    moves : pandas.DataFrame
        |d_i / r| at 10 Hz and its largest value at 5-50 Hz, with the loop
        closed on the axis' actuator and the other actuators open.
    """

    band: pd.DataFrame
    moves: pd.DataFrame
    pair: tuple

    @property
    def off_diagonal(self):
        """The off-diagonal entries of :attr:`band`."""
        return self.band.values[~np.eye(3, dtype=bool)]

    def description(self):
        """The band's off-diagonal range and the axis actuator's column."""
        off = self.off_diagonal
        return (f"coupling in the band 5-50 Hz (rms gain relative to the output's diagonal "
                f"entry): off-diagonal {off.min():.2f}-{off.max():.2f}; column "
                f"{fsm.INPUT_LABELS[self.pair[1]]}: "
                + ", ".join(f"{self.band.iloc[i, self.pair[1]]:.2f}" for i in range(3)))


def axis_coupling(blas, linear, design, pair=(2, 2), band_Hz=(5, 50)):
    """The mirror's coupling in the loop's band and the displacements one loop drags along.

    With the loop z^-1 G_ii K closed on the axis' actuator (G from the mean
    BLA) and the other actuators open, |G_ji K S| is how far displacement j
    moves per um of reference on the axis.

    Parameters
    ----------
    blas : piezolib.problem.fsm_models.LevelBLAs
        The 200 mV BLA gives the coupling table.
    linear : piezolib.problem.fsm_models.LinearModels
        The mean BLA ``G_all`` closes the loop.
    design : AxisDesign
        The discrete controller.
    pair : (int, int)
    band_Hz : (float, float)

    Returns
    -------
    AxisCoupling
    """
    check_type("blas", blas, LevelBLAs, "a LevelBLAs (fsm_models.level_blas)")
    check_type("linear", linear, LinearModels, "a LinearModels (fsm_models.fit_linear_models)")
    check_type("design", design, AxisDesign, "an AxisDesign (design_axis)")
    o, i = check_index_pair("pair", pair, (len(fsm.OUTPUT_LABELS), len(fsm.INPUT_LABELS)))
    low, high = check_band("band_Hz", band_Hz)
    f = blas.frequency_Hz
    band = (f >= low) & (f <= high)
    G200 = blas.blas[200].G
    rms = np.sqrt(np.mean(np.abs(G200[..., band]) ** 2, axis=2))
    coupling = pd.DataFrame(rms / rms.diagonal()[:, None], index=fsm.OUTPUT_LABELS,
                            columns=fsm.INPUT_LABELS)
    zl = np.exp(2j * np.pi * f / fsm.SAMPLING_FREQUENCY_HZ)
    G_all = linear.G_all
    k_lines = np.ravel(design.K_d(zl))
    S_lines = 1 / (1 + zl ** -1 * UM_PER_M * G_all[o, i] * k_lines)      # the loop on the BLA
    moves = {fsm.OUTPUT_LABELS[j]: np.abs(UM_PER_M * G_all[j, i] * k_lines * S_lines)
             for j in range(3)}
    at10 = int(np.argmin(np.abs(f - 10)))
    table = pd.DataFrame({name: {f"|d_i / r_{o + 1}| at 10 Hz": float(v[at10]),
                                 f"largest |d_i / r_{o + 1}| ({band_Hz[0]}-{band_Hz[1]} Hz)":
                                     float(v[band].max())}
                          for name, v in moves.items()}).T
    return AxisCoupling(band=coupling, moves=table, pair=tuple(pair))
