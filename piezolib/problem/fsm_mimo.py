"""A 3 x 3 μ controller for the whole fine steering mirror (notebook 10), designed and checked.

The SISO design of :mod:`piezolib.problem.fsm_control` closes one axis; the
mirror's off-diagonal gains are as large as its diagonal ones, so a
controller for the mirror is a 3 x 3 one.  The steps, each a function:

* :func:`mirror_nominal`: the all-levels 3 x 3 model (discrete, um/V) reduced
  by balanced truncation in the w-plane (exact inverse of Tustin's map), with
  the table of reduction errors and the levels' spread at the resonances;
* :func:`relative_spread`: the levels' spread as output-multiplicative
  uncertainty, sigma_max((G_level - G) G^-1) on every line (max over levels);
* :func:`mirror_design_plant`: the generalized plant of the sampled loop in
  the w-plane with one sample of delay: a full complex 3 x 3 block
  Delta at the output, per-axis templates W_S (on S), W_T (on T), W_u (on
  the controller output);
* :func:`derive_mirror_design`: the DK-iteration (expensive, run once; its end
  point is ``data/controllers/fsm_mimo_design.json``), the controller reduced
  to the lowest order that keeps μ_RP, and three SISO loops designed the same
  way on the diagonal entries (:func:`piezolib.problem.fsm_control.design_axis`);
* :func:`verify_mirror`: independent of the synthesis: μ bounds on a fine grid,
  the sampled loop with each level's own 3 x 3 model, the step cross-talk,
  for the 3 x 3 controller and the three SISO loops closed together.

How the weights bound cross-talk: the performance block maps the three
references to W_S S (3 x 3), so μ_RP < 1 gives ||W_S S||_2 < 1 on every
frequency; every entry of S, the off-diagonal ones included, is then below
1/|W_S| (1 % at low frequency, the template crossing 1 near the bandwidth):
the response of displacement j to a reference on axis i, (T)_ji = -(S)_ji,
is bounded like the tracking error, for every model of the uncertainty set.
"""

import json
from dataclasses import dataclass, field

import control as ct
import numpy as np
import pandas as pd

from piezolib import identification as ident
from piezolib import robust
from piezolib import uncertainty as unc
from piezolib._checks import (check_frequency_grid, check_integer, check_integers, check_lti,
                              check_mapping, check_path, check_positive, check_positive_values,
                              check_stable, check_type)
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_control, genplant, paths
from piezolib.problem.fsm_control import _ss_dict, _ss_of
from piezolib.problem.fsm_models import LinearModels

__all__ = ["N_AXES", "MIMO_BLOCKS", "DESIGN_PARAMETERS", "RECORD_NAME", "mirror_model",
           "relative_spread", "MirrorNominal", "mirror_nominal", "mirror_weights",
           "mirror_design_plant", "delay_matrix", "MirrorRecord", "derive_mirror_design",
           "write_mirror_record", "read_mirror_record", "record_path", "block_diagonal",
           "step_crosstalk", "step_matrix", "sampled_radius", "MirrorVerification", "verify_mirror",
           "mirror_margins", "synthesis_plant",
           "reduce_mirror_controller", "MirrorExport", "export_mirror", "NONLINEAR_STEP_RMS_V",
           "NonlinearLoop", "nonlinear_loop"]

#: Axes (inputs = outputs) of the mirror.
N_AXES = 3
#: Block structure of the 3 x 3 robust-performance problem: full 3 x 3 Delta, then
#: performance (3 references -> W_S S, W_T T, W_u K S: 9 outputs).
MIMO_BLOCKS = ((3, 3), (3, 9))
#: The design's choices: the SISO axis design's weights (notebook 10), a nominal of 20 states.
DESIGN_PARAMETERS = {
    "nominal_order": 48,
    "bandwidth_Hz": 20.0,
    "error_weight": {"low_frequency_bound": 0.01, "high_frequency_bound": 2.0},
    "output_weight": {"low_frequency_bound": 5.0, "high_frequency_bound": 0.1},
    "output_corner": 5.0,
    "rolloff": {"hf_gain": 0.1, "lf_gain": 1e3, "frequency": 2 * np.pi * 2000.0, "order": 2},
    "dk_iterations": 20,
    "siso_nominal_order": 12,
    "siso_dk_iterations": 8,
    "reduction_precision": 0.005,
}
#: File name of the committed design under ``data/controllers/``.
RECORD_NAME = "fsm_mimo_design.json"
#: The orders of the reduction table.
REDUCTION_ORDERS = (12, 24, 32, 40, 44)
#: Lines where the reduced model must keep the levels' spread [Hz].
RESONANCES_HZ = (500, 1100)
#: The w-plane grids of DK-iteration and of the verification [rad/s].
DK_W_PLANE = np.logspace(-1, 5.5, 180)
FINE_W_PLANE = np.logspace(-1, 6.5, 700)
#: Grid of the disk margins [rad/s]: 200 points up to the Nyquist frequency (the margins'
#: peaks are refined between grid neighbours; on the mirror's loops 200 points and the
#: toolkit's default 600 give the same margins to 1e-12).
MARGIN_GRID = np.logspace(-1, np.log10(np.pi * 6400) - 1e-9, 200)
#: Samples of the step responses (0.25 s at 6400 Hz).
STEP_SAMPLES = 1600


def _T():
    return 1 / fsm.SAMPLING_FREQUENCY_HZ


def _zl(frequency_Hz):
    return np.exp(2j * np.pi * np.asarray(frequency_Hz) / fsm.SAMPLING_FREQUENCY_HZ)


def _frf(sys, zl):
    """Response of a MIMO model as an array (F, p, m)."""
    return np.moveaxis(np.asarray(sys(zl)).reshape(sys.noutputs, sys.ninputs, -1), -1, 0)


def _w_of_f(f_Hz):
    T = _T()
    return 2 / T * np.tan(np.pi * np.asarray(f_Hz, dtype=float) * T)


def _hz_of_w(nu):
    T = _T()
    return np.arctan(np.asarray(nu) * T / 2) * 2 / T / (2 * np.pi)


def _check_square3(name, sys):
    check_lti(name, sys)
    if sys.ninputs != N_AXES or sys.noutputs != N_AXES:
        raise ValueError(f"{name} must have {N_AXES} inputs and {N_AXES} outputs, got "
                         f"{sys.ninputs} x {sys.noutputs}")
    return ct.ss(sys)


def _check_discrete(name, sys):
    if not sys.isdtime(strict=True) or not np.isclose(sys.dt, _T()):
        raise ValueError(f"{name} must be discrete at {fsm.SAMPLING_FREQUENCY_HZ:g} Hz, "
                         f"got dt = {sys.dt!r}")
    return sys


def mirror_model(model):
    """The discrete 3 x 3 mirror model in um/V (inputs [V], outputs [m] -> [um]).

    Examples
    --------
    >>> g = mirror_model(ct.ss(np.eye(2) * 0.5, np.ones((2, 3)) * 1e-6, np.ones((3, 2)),
    ...                        np.zeros((3, 3)), 1 / 6400))
    >>> g.noutputs, float(g.B[0, 0])
    (3, 1.0)
    """
    model = _check_discrete("model", _check_square3("model", model))
    return ct.ss(model.A, model.B * fsm_control.UM_PER_M, model.C,
                 model.D * fsm_control.UM_PER_M, model.dt)


def relative_spread(level_responses, nominal_response):
    """The levels' output-multiplicative spread: max over levels of sigma_max((G_l - G) G^-1).

    Parameters
    ----------
    level_responses : sequence of ndarray, shape (F, n, n)
        Each level's response on the lines.
    nominal_response : ndarray, shape (F, n, n)
        The nominal's response (invertible on every line).

    Returns
    -------
    ndarray, shape (F,)

    Examples
    --------
    >>> G = np.tile(np.eye(2), (4, 1, 1))
    >>> relative_spread([1.1 * G, 0.8 * G], G)
    array([0.2, 0.2, 0.2, 0.2])
    """
    G = np.asarray(nominal_response)
    if G.ndim != 3 or G.shape[1] != G.shape[2] or not np.all(np.isfinite(G)):
        raise ValueError("nominal_response must be a finite array of shape (F, n, n)")
    levels = [np.asarray(g) for g in level_responses]
    if not levels or any(g.shape != G.shape or not np.all(np.isfinite(g)) for g in levels):
        raise ValueError(f"level_responses must be finite arrays of shape {G.shape}")
    cond = np.linalg.cond(G)
    if not np.all(cond < 1e12):
        raise ValueError("nominal_response must be invertible on every line")
    Ginv = np.linalg.inv(G)
    return np.max([np.linalg.norm((g - G) @ Ginv, 2, axis=(1, 2)) for g in levels], axis=0)


@dataclass(frozen=True)
class MirrorNominal:
    """The nominal 3 x 3 model and the reduction that made it (:func:`mirror_nominal`).

    Attributes
    ----------
    G_full : control.StateSpace
        The all-levels model [um/V], discrete.
    G_level : dict {int: control.StateSpace}
        Each level's own model [um/V].
    G_nominal : control.StateSpace
        The reduced model (feedthrough zero), discrete.
    reduction : pandas.DataFrame
        Per order: relative FRF error to the BLA [%], the levels' spread peak at 500-1100 Hz.
    hankel_relative : ndarray
    frequency_Hz : ndarray
    nominal_order : int
    bla : ndarray, shape (F, 3, 3)
        The levels' mean BLA [um/V].
    """

    G_full: object
    G_level: dict
    G_nominal: object
    reduction: pd.DataFrame
    hankel_relative: np.ndarray
    frequency_Hz: np.ndarray
    nominal_order: int
    bla: np.ndarray

    def models(self):
        """{name: model} of the loops every check closes: the all-levels model and each
        level's own [um/V]."""
        return {"all-levels model (full)": self.G_full,
                **{f"{lv} mV model": g for lv, g in self.G_level.items()}}

    def spread(self, G=None):
        """The levels' output-multiplicative spread around ``G`` (default the nominal)."""
        zl = _zl(self.frequency_Hz)
        G = self.G_nominal if G is None else G
        return relative_spread([_frf(g, zl) for g in self.G_level.values()], _frf(G, zl))

    def description(self):
        """Orders and the reduction's errors, one line."""
        row = self.reduction.loc[self.nominal_order]
        full = self.reduction.loc[self.G_full.nstates]
        return (f"3 x 3 all-levels model: {self.G_full.nstates} states, nominal "
                f"{self.G_nominal.nstates}: rms error to the BLA below 100 Hz "
                f"{row['rms error < 100 Hz [%]']:.2f} % (full {full['rms error < 100 Hz [%]']:.2f} "
                f"%), levels' spread peak 500-1100 Hz {row[_SPREAD_COLUMN]:.2f} (full "
                f"{full[_SPREAD_COLUMN]:.2f})")

    @property
    def checks(self):
        """The nominal is within 10 % of the BLA below 100 Hz and keeps the spread."""
        row = self.reduction.loc[self.nominal_order]
        full = self.reduction.loc[self.G_full.nstates]
        return {f"the {self.nominal_order}-state 3 x 3 nominal is within 10 % (rms) of the BLA "
                "below 100 Hz": bool(row["rms error < 100 Hz [%]"] < 10),
                "the 3 x 3 nominal keeps the levels' spread at 500-1100 Hz within 10 % of the "
                "full model's": bool(abs(row[_SPREAD_COLUMN] - full[_SPREAD_COLUMN])
                                              <= 0.1 * full[_SPREAD_COLUMN] + 1e-12)}


_SPREAD_COLUMN = "levels' spread, peak 500-1100 Hz"


def mirror_nominal(linear, frequency_Hz, nominal_order, orders=REDUCTION_ORDERS):
    """The all-levels 3 x 3 model balanced-truncated in the w-plane (as ``axis_nominal``).

    Parameters
    ----------
    linear : piezolib.problem.fsm_models.LinearModels
    frequency_Hz : array_like
        The excited lines [Hz].
    nominal_order : int
    orders : sequence of int
        Further orders of the reduction table.

    Returns
    -------
    MirrorNominal
    """
    check_type("linear", linear, LinearModels, "a LinearModels (fsm_models.fit_linear_models)")
    f = check_positive_values("frequency_Hz", frequency_Hz)
    nominal_order = check_integer("nominal_order", nominal_order, minimum=1)
    orders = check_integers("orders", orders, minimum=1)
    zl = _zl(f)
    G_full = mirror_model(linear.model(linear.all_name))
    G_level = {lv: mirror_model(linear.model(linear.chosen(lv))) for lv in fsm.LEVELS_MV}
    bla = fsm_control.UM_PER_M * np.moveaxis(linear.G_all, -1, 0)
    levels = [_frf(g, zl) for g in G_level.values()]
    G_w = ident.d2c(G_full, method="tustin")
    if nominal_order > G_full.nstates:
        raise ValueError(f"nominal_order must be at most the full model's {G_full.nstates} "
                         f"states, got {nominal_order}")

    def truncated(order):
        r = ct.c2d(ct.balred(G_w, order, method="matchdc"), _T(), "tustin")
        return ct.ss(r.A, r.B, r.C, np.zeros((N_AXES, N_AXES)), _T())

    def rms_error(resp, f_max):
        m = f <= f_max
        return 100 * np.sqrt(np.sum(np.abs(resp[m] - bla[m]) ** 2) / np.sum(np.abs(bla[m]) ** 2))

    res = (f >= RESONANCES_HZ[0]) & (f <= RESONANCES_HZ[1])
    rows, reduced = {}, {}
    for order in sorted({o for o in orders if o < G_full.nstates} | {nominal_order}) + [
            G_full.nstates]:
        g = G_full if order == G_full.nstates else truncated(order)
        reduced[order] = g
        resp = _frf(g, zl)
        rows[order] = {"rms error < 100 Hz [%]": rms_error(resp, 100),
                       "rms error < 1100 Hz [%]": rms_error(resp, 1100),
                       _SPREAD_COLUMN: float(relative_spread(levels, resp)[res].max())}
    hankel = ct.hankel_singular_values(G_w)
    return MirrorNominal(G_full=G_full, G_level=G_level, G_nominal=reduced[nominal_order],
                         reduction=pd.DataFrame(rows).T.rename_axis("order"),
                         hankel_relative=hankel / hankel[0], frequency_Hz=f,
                         nominal_order=nominal_order, bla=bla)


def delay_matrix(n=N_AXES):
    """n channels of one sample of delay at the mirror's rate (z^-1 I).

    Examples
    --------
    >>> delay_matrix(2).nstates
    2
    """
    n = check_integer("n", n, minimum=1)
    return ct.ss(np.zeros((n, n)), np.eye(n), np.eye(n), np.zeros((n, n)), _T())


def mirror_weights(params, nu, hull):
    """The scalar weights of the 3 x 3 design: W_m covering ``hull``, W_S, W_T, W_u.

    Parameters
    ----------
    params : dict
        As :data:`DESIGN_PARAMETERS`.
    nu : array_like
        w-plane frequencies of the lines [rad/s].
    hull : array_like
        The non-decreasing spread to cover.

    Returns
    -------
    dict {str: control.TransferFunction}
        ``W_m, W_S, W_T, W_u``.
    """
    check_mapping("params", params)
    nu = check_positive_values("nu", nu)
    hull = np.asarray(hull, dtype=float) if not isinstance(hull, str) else None
    if hull is None or hull.shape != nu.shape or not np.all(np.isfinite(hull)) or \
            np.any(hull < 0):
        raise ValueError(f"hull must hold {nu.size} finite non-negative values (one per nu)")
    missing = {"bandwidth_Hz", "error_weight", "output_weight", "output_corner",
               "rolloff"} - set(params)
    if missing:
        raise ValueError(f"params misses {sorted(missing)}")
    omega_b = 2 * np.pi * check_positive("bandwidth_Hz", params["bandwidth_Hz"])
    W_m = unc.fit_covering_weight(nu, hull, order=1, starts=1, name="W_m")
    W_S = robust.sensitivity_weight(**params["error_weight"], bandwidth_rad_s=omega_b)
    W_T = robust.complementary_sensitivity_weight(
        **params["output_weight"], bandwidth_rad_s=params["output_corner"] * omega_b)
    W_u = genplant.rolloff_weight(genplant.RolloffWeight(**params["rolloff"]))
    return {"W_m": ct.tf(W_m), "W_S": ct.tf(W_S), "W_T": ct.tf(W_T), "W_u": ct.tf(W_u)}


def _diag(w, n, inputs, outputs):
    return ct.ss(ct.append(*[ct.ss(w)] * n), inputs=inputs, outputs=outputs)


def mirror_design_plant(G, W_m, W_S, W_T, W_u):
    """Generalized plant of the 3 x 3 loop: full output-multiplicative Delta, per-axis weights.

    With u the controller output (delay and hold inside ``G``):

        v_y = G u + u_Delta,  y_Delta = W_m G u,  v_e = v_r - v_y,
        y1 = W_S v_e,  y2 = W_T v_y,  y_u = W_u u  (each weight times I_3).

    Parameters
    ----------
    G : control.LTI
        Continuous 3 x 3 plant [um/V] (e.g. the w-plane image of z^-1 G(z)).
    W_m, W_S, W_T, W_u : control.LTI
        SISO stable weights applied to every axis.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta[0..2], v_r[0..2], u[0..2]``; outputs ``y_Delta, y1, y2, y_u, v_e``
        (3 each); block structure :data:`MIMO_BLOCKS`.

    Examples
    --------
    >>> P = mirror_design_plant(ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3))),
    ...                         ct.tf([0.1], [1]), ct.tf([1], [1, 1]), ct.tf([0.1], [1]),
    ...                         ct.tf([0.1], [1]))
    >>> P.ninputs, P.noutputs
    (9, 15)
    """
    G = _check_square3("G", G)
    if G.isdtime(strict=True):
        raise ValueError("G must be continuous (the w-plane plant), got a discrete model")
    for name, W in (("W_m", W_m), ("W_S", W_S), ("W_T", W_T), ("W_u", W_u)):
        check_lti(name, W)
        if W.ninputs != 1 or W.noutputs != 1:
            raise ValueError(f"{name} must be a SISO weight (applied per axis)")
        check_stable(name, W)
    n = N_AXES
    sig = lambda s: [f"{s}[{i}]" for i in range(n)]                     # noqa: E731
    blocks = [ct.ss(G, inputs=sig("u"), outputs=sig("v_y0")),
              _diag(W_m, n, sig("v_y0"), sig("y_Delta")),
              ct.summing_junction(inputs=["v_y0", "u_Delta"], output="v_y", dimension=n),
              ct.summing_junction(inputs=["v_r", "-v_y"], output="v_e", dimension=n),
              _diag(W_S, n, sig("v_e"), sig("y1")),
              _diag(W_T, n, sig("v_y"), sig("y2")),
              _diag(W_u, n, sig("u"), sig("y_u"))]
    P = ct.interconnect(blocks, inputs=sig("u_Delta") + sig("v_r") + sig("u"),
                        outputs=sig("y_Delta") + sig("y1") + sig("y2") + sig("y_u") + sig("v_e"),
                        name="P_mirror")
    return robust.balance(P)


def block_diagonal(controllers):
    """SISO controllers side by side, one per axis (a decentralised controller).

    Parameters
    ----------
    controllers : sequence of control.LTI
        SISO controllers, axis by axis.

    Returns
    -------
    control.StateSpace

    Examples
    --------
    >>> K = block_diagonal([ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]),
    ...                     ct.ss([], [], [], [[2.0]])])
    >>> K.ninputs, K.nstates
    (2, 1)
    """
    if isinstance(controllers, (str, bytes, ct.LTI)) or not hasattr(controllers, "__len__"):
        raise TypeError(f"controllers must be a sequence of SISO controllers, got "
                        f"{type(controllers).__name__}")
    if not controllers:
        raise ValueError("controllers must hold at least one SISO controller")
    for i, k in enumerate(controllers):
        check_lti(f"controllers[{i}]", k)
        if k.ninputs != 1 or k.noutputs != 1:
            raise ValueError(f"controllers[{i}] must be SISO")
    return ct.append(*[ct.ss(k) for k in controllers])


def _tf_dict(w):
    w = ct.tf(w)
    return {"num": np.ravel(w.num[0][0]).tolist(), "den": np.ravel(w.den[0][0]).tolist()}


@dataclass(frozen=True)
class MirrorRecord:
    """The committed end point of the 3 x 3 design (:func:`derive_mirror_design`).

    Attributes
    ----------
    K_w : control.StateSpace
        The reduced 3 x 3 controller in the w-plane (continuous; Tustin gives the
        discrete one).
    K_full_order : int
        States of the DK controller before reduction.
    weights : dict {str: control.TransferFunction}
        ``W_m, W_S, W_T, W_u``.
    params : dict
        The design's choices (:data:`DESIGN_PARAMETERS`).
    history : pandas.DataFrame
        The DK iteration's μ history.
    mu_dk : float
        μ_RP upper bound of the DK controller on the DK grid.
    mu_reduced : float
        The same for the reduced controller.
    reduction : pandas.DataFrame
        μ_RP (DK grid) and stability of the candidate orders.
    siso_K_w : dict {int: control.StateSpace}
        The three SISO axis controllers (w-plane), axis index -> K.
    siso_mu : dict {int: float}
        Their own SISO μ_RP (DK).
    seconds : float
        Wall time of the DK-iteration [s] (information only).
    """

    K_w: object
    K_full_order: int
    weights: dict
    params: dict
    history: pd.DataFrame
    mu_dk: float
    mu_reduced: float
    reduction: pd.DataFrame
    siso_K_w: dict
    siso_mu: dict
    seconds: float = field(default=float("nan"))

    def K_d(self):
        """The 3 x 3 discrete controller (Tustin of :attr:`K_w`, no pre-warping)."""
        return ct.c2d(self.K_w, _T(), "tustin")

    def siso_K_d(self):
        """The three SISO loops as one block-diagonal discrete controller."""
        return ct.c2d(block_diagonal([self.siso_K_w[i] for i in range(N_AXES)]), _T(),
                      "tustin")

    def description(self):
        """The DK result and the reduction, one line."""
        return (f"3 x 3 DK controller: {self.K_full_order} states, mu_RP {self.mu_dk:.3f} on the "
                f"DK grid after {len(self.history)} iterations; reduced to {self.K_w.nstates} "
                f"states: mu_RP {self.mu_reduced:.3f}; SISO axes' own mu_RP "
                + ", ".join(f"{self.siso_mu[i]:.3f}" for i in range(N_AXES)))


def _w_plane_plant(G_d):
    return ident.d2c(ct.series(delay_matrix(G_d.ninputs), G_d), method="tustin")


def _mu_peak(plant, K, omega, blocks=MIMO_BLOCKS, lower=False):
    mu = robust.mussv(robust.lft_response(plant, K, omega), blocks, omega, lower=lower)
    return mu


def derive_mirror_design(linear, frequency_Hz, params=None, *, orders=None, siso=True):
    """The 3 x 3 DK design from scratch, its reduction, and the three SISO loops (slow).

    Parameters
    ----------
    linear : piezolib.problem.fsm_models.LinearModels
    frequency_Hz : array_like
        The excited lines [Hz].
    params : dict, optional
        :data:`DESIGN_PARAMETERS` (default) or a dict of the same keys.
    orders : sequence of int, optional
        Candidate orders of the reduced controller (default every 2 states from 8).
    siso : bool
        Also design the three SISO axis loops (:mod:`fsm_control`).

    Returns
    -------
    MirrorRecord
    """
    import time

    params = dict(DESIGN_PARAMETERS if params is None else check_mapping("params", params))
    nominal = mirror_nominal(linear, frequency_Hz, params["nominal_order"])
    plant, weights = synthesis_plant(nominal, params)
    t0 = time.perf_counter()
    dk = robust.musyn(plant, MIMO_BLOCKS, N_AXES, N_AXES, DK_W_PLANE, d_order="auto",
                      max_iter=params["dk_iterations"])
    seconds = time.perf_counter() - t0
    K = dk.K
    orders = range(8, K.nstates, 2) if orders is None else check_integers("orders", orders, 1)
    chosen, reduction = reduce_mirror_controller(plant, K, float(dk.mu_peak),
                                                 params["reduction_precision"], orders)
    siso_K, siso_mu = {}, {}
    if siso:
        for i in range(N_AXES):
            axis = fsm_control.axis_nominal(linear, frequency_Hz, params["siso_nominal_order"],
                                            pair=(i, i))
            d = fsm_control.design_axis(
                axis, bandwidth_Hz=params["bandwidth_Hz"], error_weight=params["error_weight"],
                output_weight=params["output_weight"], output_corner=params["output_corner"],
                rolloff=params["rolloff"], dk_iterations=params["siso_dk_iterations"])
            siso_K[i], siso_mu[i] = ct.ss(d.K_w), float(d.dk.mu_peak)
    return MirrorRecord(K_w=ct.ss(chosen[0]), K_full_order=K.nstates, weights=weights,
                        params=params, history=dk.history, mu_dk=float(dk.mu_peak),
                        mu_reduced=chosen[1],
                        reduction=reduction, siso_K_w=siso_K, siso_mu=siso_mu, seconds=seconds)


def reduce_mirror_controller(plant, K, mu, precision, orders):
    """The lowest order of ``orders`` whose truncated K keeps μ_RP within ``precision`` of ``mu``.

    Parameters
    ----------
    plant : control.StateSpace
        The synthesis plant (:func:`synthesis_plant`).
    K : control.StateSpace
        The DK controller (3 x 3, w-plane).
    mu : float
        Its μ_RP upper bound on the DK grid.
    precision : float
        Allowed increase of μ_RP (absolute).
    orders : sequence of int
        Candidate orders, tried in increasing order.

    Returns
    -------
    ((control.StateSpace, float), pandas.DataFrame)
        The chosen controller and its μ_RP (``K`` itself if no order qualifies), and the
        table of the orders tried.
    """
    check_lti("K", K)
    mu = check_positive("mu", mu)
    precision = check_positive("precision", precision)
    rows, chosen = {}, (ct.ss(K), mu)
    for order in sorted(check_integers("orders", orders, minimum=1)):
        if order >= K.nstates:
            break
        try:
            Kr = robust.reduce_controller(K, order).K
        except ValueError:
            continue
        stable = bool(np.linalg.eigvals(robust.lower_lft(plant, Kr).A).real.max() < 0)
        m = float(_mu_peak(plant, Kr, DK_W_PLANE).upper.max()) if stable else float("inf")
        rows[order] = {"mu_RP upper (DK grid)": m, "w-plane loop stable": stable}
        if stable and m <= mu + precision:
            chosen = (ct.ss(Kr), m)
            break
    table = pd.DataFrame(rows, index=["mu_RP upper (DK grid)", "w-plane loop stable"]).T
    return chosen, table.rename_axis("order")


def synthesis_plant(nominal, params, weights=None):
    """The 3 x 3 synthesis plant of ``nominal`` (w-plane of z^-1 G(z)) and its weights.

    Parameters
    ----------
    nominal : MirrorNominal
    params : dict
        As :data:`DESIGN_PARAMETERS` (the weights' choices).
    weights : dict, optional
        ``W_m, W_S, W_T, W_u`` (e.g. a record's); default fitted and built from ``params``.

    Returns
    -------
    (control.StateSpace, dict)
    """
    check_type("nominal", nominal, MirrorNominal, "a MirrorNominal (mirror_nominal)")
    check_mapping("params", params)
    nu = _w_of_f(nominal.frequency_Hz)
    if weights is None:
        hull = np.maximum.accumulate(nominal.spread())
        weights = mirror_weights(params, nu, hull)
    G_w = _w_plane_plant(nominal.G_nominal)
    return mirror_design_plant(G_w, **weights), weights


def record_path():
    """Where the committed 3 x 3 design lives: ``data/controllers/fsm_mimo_design.json``."""
    return paths.data_dir() / "controllers" / RECORD_NAME


def write_mirror_record(record, path):
    """Write ``record`` as JSON; return the path."""
    check_type("record", record, MirrorRecord, "a MirrorRecord (derive_mirror_design)")
    path = check_path("path", path)
    hist = record.history
    doc = {"format": 1, "what": "3 x 3 mu controller of the fine steering mirror (notebook 10), "
                                "w-plane of the 6400 Hz loop with one sample of delay",
           "params": record.params, "K_w": _ss_dict(record.K_w),
           "K_full_order": record.K_full_order,
           "weights": {k: _tf_dict(w) for k, w in record.weights.items()},
           "history": {"columns": list(hist.columns),
                       "rows": [[float(x) for x in r] for r in hist.itertuples(index=False)]},
           "mu_dk": record.mu_dk, "mu_reduced": record.mu_reduced,
           "reduction": {str(k): {"mu": (None if not np.isfinite(v.iloc[0]) else float(v.iloc[0])),
                                  "stable": bool(v.iloc[1])}
                         for k, v in record.reduction.iterrows()},
           "siso_K_w": {str(i): _ss_dict(k) for i, k in record.siso_K_w.items()},
           "siso_mu": {str(i): m for i, m in record.siso_mu.items()},
           "seconds": record.seconds}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def read_mirror_record(path=None):
    """Read a file of :func:`write_mirror_record` (default :func:`record_path`).

    Examples
    --------
    >>> rec = read_mirror_record()
    >>> rec.K_w.ninputs, sorted(rec.siso_K_w)
    (3, [0, 1, 2])
    """
    path = record_path() if path is None else check_path("path", path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        hist = pd.DataFrame(doc["history"]["rows"], columns=doc["history"]["columns"])
        red = pd.DataFrame({int(k): {"mu_RP upper (DK grid)": (np.inf if v["mu"] is None
                                                               else v["mu"]),
                                     "w-plane loop stable": v["stable"]}
                            for k, v in doc["reduction"].items()}).T.rename_axis("order")
        rec = MirrorRecord(
            K_w=_ss_of(doc["K_w"], "K_w"), K_full_order=int(doc["K_full_order"]),
            weights={k: ct.tf(v["num"], v["den"]) for k, v in doc["weights"].items()},
            params=doc["params"], history=hist, mu_dk=float(doc["mu_dk"]),
            mu_reduced=float(doc["mu_reduced"]), reduction=red,
            siso_K_w={int(i): _ss_of(k, f"siso_K_w[{i}]") for i, k in doc["siso_K_w"].items()},
            siso_mu={int(i): float(m) for i, m in doc["siso_mu"].items()},
            seconds=float(doc.get("seconds", float("nan"))))
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"path: {path} is not a 3 x 3 design record ({exc})") from None
    return rec


def sampled_radius(G_d, K_d):
    """Largest |pole| of the sampled loop: K_d, one sample of delay, G_d, negative feedback.

    Parameters
    ----------
    G_d, K_d : control.StateSpace
        Discrete square plant and controller at the same rate (K_d: n x n).

    Returns
    -------
    float

    Examples
    --------
    >>> T = 1 / 6400
    >>> g = ct.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], T)
    >>> round(sampled_radius(g, ct.ss([], [], [], [[0.5]], T)), 6)
    0.707107
    """
    G_d, K_d = _loop_models(G_d, K_d)
    L = ct.series(K_d, delay_matrix(G_d.ninputs), G_d)
    cl = ct.feedback(L, np.eye(G_d.noutputs))
    return float(np.abs(np.linalg.eigvals(cl.A)).max()) if cl.nstates else 0.0


def _loop_models(G_d, K_d):
    check_lti("G_d", G_d)
    check_lti("K_d", K_d)
    G_d, K_d = ct.ss(G_d), ct.ss(K_d)
    for name, s in (("G_d", G_d), ("K_d", K_d)):
        if not s.isdtime(strict=True):
            raise ValueError(f"{name} must be discrete, got a continuous model")
    if not np.isclose(G_d.dt, K_d.dt):
        raise ValueError(f"K_d must have G_d's sample time {G_d.dt}, got {K_d.dt}")
    if G_d.ninputs != G_d.noutputs or K_d.ninputs != G_d.noutputs or \
            K_d.noutputs != G_d.ninputs:
        raise ValueError(f"G_d must be square and K_d its {G_d.ninputs} x {G_d.noutputs} "
                         f"controller, got G_d {G_d.noutputs} x {G_d.ninputs}, K_d "
                         f"{K_d.noutputs} x {K_d.ninputs}")
    return G_d, K_d


def step_matrix(G_d, K_d, n_samples=STEP_SAMPLES):
    """Unit-step responses of the sampled loop (z^-1 G_d K_d, negative feedback) to each reference.

    Parameters
    ----------
    G_d, K_d : control.StateSpace
        As :func:`sampled_radius` (a stable loop).
    n_samples : int

    Returns
    -------
    (ndarray, ndarray)
        Time [s], shape (N,), and y[j, i, k], output j for a step on reference i.

    Examples
    --------
    >>> T = 1 / 6400
    >>> g = ct.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], T)
    >>> t, y = step_matrix(g, ct.ss([[1.0]], [[0.1]], [[1.0]], [[0.0]], T), n_samples=2000)
    >>> y.shape, round(float(y[0, 0, -1]), 3)
    ((1, 1, 2000), 1.0)
    """
    G_d, K_d = _loop_models(G_d, K_d)
    n_samples = check_integer("n_samples", n_samples, minimum=10)
    L = ct.series(K_d, delay_matrix(G_d.ninputs), G_d)
    T_cl = ct.feedback(L, np.eye(G_d.noutputs))
    if T_cl.nstates and np.abs(np.linalg.eigvals(T_cl.A)).max() >= 1:
        raise ValueError("the loop of G_d and K_d is unstable: no step response")
    n = G_d.noutputs
    t = np.arange(n_samples) * G_d.dt
    resp = ct.step_response(T_cl, T=t)
    return t, np.asarray(resp.outputs).reshape(n, n, -1)


def step_crosstalk(G_d, K_d, n_samples=STEP_SAMPLES):
    """Unit steps on each reference of the sampled loop; peaks relative to the diagonal step.

    ``result[j, i]`` is max_t |y_j(t)| over the final value of y_i, for a step on
    reference i (the diagonal: the peak over the final value, 1 + overshoot).

    Parameters
    ----------
    G_d, K_d : control.StateSpace
        As :func:`sampled_radius` (a stable loop).
    n_samples : int
        Samples of the responses.

    Returns
    -------
    ndarray, shape (n, n)

    Examples
    --------
    >>> T = 1 / 6400
    >>> g = ct.ss(np.diag([0.5, 0.5]), np.eye(2), np.eye(2), np.zeros((2, 2)), T)
    >>> k = ct.ss(np.eye(2), 0.1 * np.eye(2), np.eye(2), np.zeros((2, 2)), T)  # integrators
    >>> x = step_crosstalk(g, k)
    >>> float(x[0, 1]), bool(x[0, 0] >= 1)
    (0.0, True)
    """
    _, y = step_matrix(G_d, K_d, n_samples)                          # (output, input, t)
    n = y.shape[0]
    final = np.abs(y[np.arange(n), np.arange(n), -1])
    return np.abs(y).max(axis=2) / final[None, :]


@dataclass(frozen=True)
class MirrorVerification:
    """Checks of the 3 x 3 controller and of the three SISO loops (:func:`verify_mirror`).

    Attributes
    ----------
    mu : dict {str: robust.MuResult}
        μ_RP bounds of the 3 x 3 problem on the fine grid, per controller
        (``"3 x 3 mu"``, ``"3 SISO loops"``).
    loops : pandas.DataFrame
        Rows (controller, model): the sampled loop's largest |pole|, stability,
        the worst off-diagonal step peak (cross-talk) with that model.
    crosstalk : dict {str: ndarray}
        The step peak matrix of each controller with the all-levels (full) model.
    steps : dict {str: (ndarray, ndarray)}
        Its step responses (:func:`step_matrix`), per controller.
    margins : pandas.DataFrame or None
        Disk margins (loop-at-a-time and multi-loop, input and output) per controller.
    """

    mu: dict
    loops: pd.DataFrame
    crosstalk: dict
    steps: dict
    margins: object = None

    def table(self):
        """Per controller: μ_RP upper/lower, order, worst radius, worst cross-talk."""
        out = {}
        for name, mu in self.mu.items():
            rows = self.loops.xs(name, level=0)
            out[name] = {"mu_RP upper": float(mu.upper.max()),
                         "mu_RP lower": float(mu.lower.max()),
                         "states": int(rows["controller states"].iloc[0]),
                         "largest |pole| (all models)": float(rows["largest |pole|"].max()),
                         "stable with every model": bool(rows["stable"].all()),
                         "worst cross-talk (all models)": float(rows["worst cross-talk"].max())}
        return pd.DataFrame(out)

    @property
    def checks(self):
        """Bounds ordered, RP met and every loop stable for the 3 x 3 controller."""
        mu = self.mu[MIMO]
        rows = self.loops.xs(MIMO, level=0)
        t = self.table()
        out = {"3 x 3: mu lower bound <= upper bound on every frequency": bool(
                   np.all(mu.lower <= mu.upper * (1 + 1e-6))),
               "3 x 3: robust performance, mu_RP upper bound < 1": bool(mu.upper.max() < 1),
               "3 x 3: the sampled loop is stable with the nominal and each level's model":
                   bool(rows["stable"].all()),
               "3 x 3: worst step cross-talk below the three SISO loops'": bool(
                   t.loc["worst cross-talk (all models)", MIMO]
                   < t.loc["worst cross-talk (all models)", SISO]),
               "3 x 3: mu_RP of the 3 x 3 problem below the three SISO loops'": bool(
                   t.loc["mu_RP upper", MIMO] < t.loc["mu_RP upper", SISO])}
        if self.margins is not None:
            worst = self.margins.groupby(level=0).min()
            for side in ("input", "output"):
                col = f"multi-loop disk margin, {side}"
                out[f"3 x 3: multi-loop disk margin at the plant {side} above the three SISO "
                    "loops' (worst model)"] = bool(worst.loc[MIMO, col] > worst.loc[SISO, col])
        return out


#: Names of the two controllers compared.
MIMO = "3 x 3 mu"
SISO = "3 SISO loops"


def verify_mirror(nominal, record, omega=None):
    """μ bounds, sampled loops with every level's model, step cross-talk: 3 x 3 beside 3 SISO.

    Parameters
    ----------
    nominal : MirrorNominal
        The same nominal the record was designed on.
    record : MirrorRecord
    omega : array_like, optional
        w-plane grid of the μ bounds [rad/s] (default 700 points, 0.1 - 3e6 rad/s).

    Returns
    -------
    MirrorVerification
    """
    check_type("nominal", nominal, MirrorNominal, "a MirrorNominal (mirror_nominal)")
    check_type("record", record, MirrorRecord, "a MirrorRecord (read_mirror_record)")
    omega = FINE_W_PLANE if omega is None else check_frequency_grid("omega", omega,
                                                                    min_length=16)
    plant, _ = synthesis_plant(nominal, record.params, record.weights)
    Ks_w = {MIMO: record.K_w, SISO: block_diagonal([record.siso_K_w[i] for i in range(N_AXES)])}
    Ks_d = {MIMO: record.K_d(), SISO: record.siso_K_d()}
    models = nominal.models()
    mu, rows, cross, steps = {}, {}, {}, {}
    for name, K_w in Ks_w.items():
        mu[name] = robust.mussv(robust.lft_response(plant, K_w, omega), MIMO_BLOCKS, omega,
                                restarts=1, iterations=30)
        for mname, g in models.items():
            r = sampled_radius(g, Ks_d[name])
            x = step_crosstalk(g, Ks_d[name]) if r < 1 else np.full((N_AXES, N_AXES), np.inf)
            if mname.startswith("all-levels"):
                cross[name] = x
                steps[name] = step_matrix(g, Ks_d[name]) if r < 1 else None
            rows[(name, mname)] = {"controller states": Ks_d[name].nstates,
                                   "largest |pole|": r, "stable": r < 1,
                                   "worst cross-talk": float(x[~np.eye(N_AXES, dtype=bool)].max())}
    loops = pd.DataFrame(rows).T
    loops.index.names = ["controller", "model"]
    return MirrorVerification(mu=mu, loops=loops, crosstalk=cross, steps=steps,
                              margins=mirror_margins(models, Ks_d))


def mirror_margins(models, controllers):
    """Disk margins of each sampled loop z^-1 G K: multi-loop and loop-at-a-time, input and output.

    Parameters
    ----------
    models : dict {str: control.StateSpace}
        Discrete square plants (the hold inside; one sample of delay is added here).
    controllers : dict {str: control.StateSpace}
        Discrete controllers at the plants' rate.

    Returns
    -------
    pandas.DataFrame
        Rows (controller, model); columns the multi-loop margins alpha at the plant input
        and output, the smallest loop-at-a-time alpha at each, and the multi-loop gain and
        phase margins at the input; NaN where the loop is unstable.
    """
    check_mapping("models", models)
    check_mapping("controllers", controllers)
    rows = {}
    for cname, K in controllers.items():
        for mname, g in models.items():
            G_d, K_d = _loop_models(g, K)
            P = ct.series(delay_matrix(G_d.ninputs), G_d)
            try:
                m = robust.loop_margins_mimo(P, K_d, omega=MARGIN_GRID, input_output=False)
            except ValueError:
                rows[(cname, mname)] = {c: np.nan for c in _MARGIN_COLUMNS}
                continue
            rows[(cname, mname)] = dict(zip(_MARGIN_COLUMNS, (
                m.input.alpha, m.output.alpha, min(x.alpha for x in m.input_loops),
                min(x.alpha for x in m.output_loops), m.input.gain_margin_dB[1],
                m.input.phase_margin_deg)))
    out = pd.DataFrame(rows).T
    out.index.names = ["controller", "model"]
    return out


_MARGIN_COLUMNS = ("multi-loop disk margin, input", "multi-loop disk margin, output",
                   "loop-at-a-time disk margin, input (smallest)",
                   "loop-at-a-time disk margin, output (smallest)",
                   "multi-loop gain margin, input [dB]", "multi-loop phase margin, input [deg]")


@dataclass(frozen=True)
class MirrorExport:
    """The 3 x 3 controller exported in float32 (:func:`export_mirror`).

    Attributes
    ----------
    export : piezolib.robust.MIMOExport
        The realisation, its float32 matrices and their checks.
    radius32 : dict {str: float}
        Largest |pole| of the sampled loop with the float32 controller, per model.
    """

    export: object
    radius32: dict

    def table(self):
        """The export's numbers, one column."""
        x = self.export
        return pd.Series({
            "form": x.form, "states": x.n_states, "basis condition number": x.basis_condition,
            "spectral radius of A (float64)": x.radius64,
            "spectral radius of A (float32)": x.radius32,
            "largest relative response error of the float32 matrices": x.max_error,
            "its first-order rounding bound (largest)": float(np.nanmax(x.bound)),
            "time run: float32 arithmetic error / its bound": x.time_error / x.time_bound,
            **{f"sampled loop with the float32 K, {m}: largest |pole|": r
               for m, r in self.radius32.items()}}, name="3 x 3 controller, float32")

    @property
    def checks(self):
        """The float32 controller is stable, within its bounds, and closes stable loops."""
        x = self.export
        return {"3 x 3 float32 export: controller stable in float32": bool(x.radius32 < 1),
                "3 x 3 float32 export: response error within the rounding bound": bool(
                    x.max_error <= np.nanmax(x.bound)),
                "3 x 3 float32 export: time-domain error within its bound": bool(
                    x.time_error <= x.time_bound),
                "3 x 3 float32 export: the sampled loop with each model is stable": bool(
                    max(self.radius32.values()) < 1)}


def export_mirror(nominal, record, name="K_fsm_mimo"):
    """The discrete 3 x 3 controller as float32 matrices (``robust.export_mimo``), checked.

    Parameters
    ----------
    nominal : MirrorNominal
        Its models close the sampled loops with the float32 controller.
    record : MirrorRecord
    name : str
        C identifier of the controller.

    Returns
    -------
    MirrorExport
    """
    check_type("nominal", nominal, MirrorNominal, "a MirrorNominal (mirror_nominal)")
    check_type("record", record, MirrorRecord, "a MirrorRecord (read_mirror_record)")
    x = robust.export_mimo(record.K_d(), name=name)
    K32 = x.to_statespace("float32")
    return MirrorExport(export=x, radius32={m: sampled_radius(g, K32)
                                            for m, g in nominal.models().items()})


# -- the loop closed with the causal nonlinear model ---------------------------------------

#: RMS of the steady controller output [V] of the steps on the nonlinear model: inside the
#: 100-300 mV range the causal model was fitted on.
NONLINEAR_STEP_RMS_V = 0.2


@dataclass(frozen=True)
class NonlinearLoop:
    """The 3 x 3 controller's sampled loop closed with the causal nonlinear model
    (:func:`nonlinear_loop`), beside the same loop with the all-levels linear model.

    Attributes
    ----------
    table : pandas.DataFrame
        Rows: the reference stepped; columns per model (nonlinear, linear): the step's final
        value over the reference, the worst cross-talk (peak of the other two outputs over
        the final value) and the largest |u| [V].
    step_um : ndarray, shape (3,)
        The step on each reference [um] (its steady u has RMS :data:`NONLINEAR_STEP_RMS_V`
        on the linear model).
    responses : dict {str: ndarray}
        Outputs [um], shape (3 outputs, 3 references, n_samples), per model.
    """

    table: pd.DataFrame
    step_um: np.ndarray
    responses: dict

    @property
    def checks(self):
        """{statement: holds}: the nonlinear model's loop settles near the references."""
        nl = self.table.xs("causal nonlinear model", axis=1, level=0)
        return {"with the causal nonlinear model each step settles within 5 % of its reference":
                bool(np.all(np.abs(nl["final / reference"] - 1) < 0.05)),
                "with the causal nonlinear model the cross-talk stays below 10 %":
                bool(np.all(nl["worst cross-talk"] < 0.1))}


def _loop_run(plant_step, K_d, r, n_samples):
    """(outputs (n, 3) [um], controller outputs (n, 3) [V]) of z^-1 P K_d on the step ``r``."""
    A, B, C, D = (np.asarray(m, float) for m in (K_d.A, K_d.B, K_d.C, K_d.D))
    x, u_held = np.zeros(A.shape[0]), np.zeros(N_AXES)
    ys, us = np.empty((n_samples, N_AXES)), np.empty((n_samples, N_AXES))
    for k in range(n_samples):
        y = plant_step(u_held)                  # u computed at k - 1: one sample of delay
        e = r - y
        u = C @ x + D @ e
        x = A @ x + B @ e
        ys[k], us[k], u_held = y, u, u
    return ys, us


def nonlinear_loop(causal_model, record, nominal, n_samples=STEP_SAMPLES):
    """Steps on each reference of the sampled loop closed with the causal nonlinear model.

    The model (:class:`piezolib.identification.BasisModel`, [V] -> [m]) runs one sample
    at a time (:meth:`~piezolib.identification.BasisModel.stepper`), the 3 x 3 controller
    ``record.K_d()`` with one sample of delay, as :func:`step_matrix` closes the linear
    loop; the same run with the all-levels linear model ``nominal.G_full`` beside it.  The
    step on reference i is sized so that the linear loop's steady controller output has
    RMS :data:`NONLINEAR_STEP_RMS_V` (the causal model's amplitude range).

    Parameters
    ----------
    causal_model : piezolib.identification.BasisModel
        3 inputs [V] -> 3 outputs [m].
    record : MirrorRecord
    nominal : MirrorNominal
    n_samples : int

    Returns
    -------
    NonlinearLoop
    """
    check_type("causal_model", causal_model, ident.BasisModel, "a BasisModel (fsm_causal)")
    check_type("record", record, MirrorRecord, "a MirrorRecord (read_mirror_record)")
    check_type("nominal", nominal, MirrorNominal, "a MirrorNominal (mirror_nominal)")
    n_samples = check_integer("n_samples", n_samples, minimum=16)
    if (causal_model.n_inputs, causal_model.n_outputs) != (N_AXES, N_AXES):
        raise ValueError(f"causal_model must have {N_AXES} inputs and outputs, got "
                         f"{causal_model.n_inputs} and {causal_model.n_outputs}")
    K_d = ct.ss(record.K_d())
    G = ct.ss(nominal.G_full)
    inv_dc = np.linalg.inv(np.asarray(G.dcgain(), float))       # [V/um]
    step = NONLINEAR_STEP_RMS_V / np.sqrt(np.mean(inv_dc ** 2, axis=0))

    def linear():
        state = {"x": np.zeros(G.nstates)}
        A, B, C, D = (np.asarray(m, float) for m in (G.A, G.B, G.C, G.D))

        def run(u):
            y = C @ state["x"] + D @ u
            state["x"] = A @ state["x"] + B @ u
            return y
        return run

    def nonlinear():
        model = causal_model.stepper()
        return lambda u: 1e6 * model.step(u)    # [m] -> [um]

    rows, responses = {}, {}
    for name, make in (("causal nonlinear model", nonlinear), ("all-levels linear model", linear)):
        out = np.empty((N_AXES, N_AXES, n_samples))
        for i in range(N_AXES):
            r = np.zeros(N_AXES)
            r[i] = step[i]
            y, u = _loop_run(make(), K_d, r, n_samples)
            out[:, i] = y.T
            final = y[-1, i]
            others = np.delete(np.abs(y), i, axis=1).max()
            rows.setdefault(f"step on reference {i + 1}", {}).update({
                (name, "final / reference"): final / r[i],
                (name, "worst cross-talk"): others / abs(final),
                (name, "largest |u| [V]"): float(np.abs(u).max())})
        responses[name] = out
    table = pd.DataFrame(rows).T
    table.columns = pd.MultiIndex.from_tuples(table.columns)
    return NonlinearLoop(table=table, step_um=step, responses=responses)
