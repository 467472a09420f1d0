"""Generalized plant P of Fig. 9 (eq. 16), its lower LFT M = F_l(P, K) (eq. 17-18)
and the delay-aware synthesis plant.

Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2[, y_u], v_e``, all in
volts, frequencies in rad/s.  The signal table, how H_y G is realised, why
the synthesis plant carries an effort output and how the delay-aware plant
models the sample-and-hold, the computation delay and the roll-off
requirement are in ``docs/controller_design.md``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import (check_continuous, check_finite_lti, check_frequency_grid,
                              check_integer, check_model, check_nonnegative, check_positive,
                              check_proper, check_siso, check_type)
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import (balance, from_scaled, scaled_coefficients, time_scale_of,
                                 to_scaled, with_signals)

__all__ = [
    "PLANT_INPUTS", "PLANT_OUTPUTS", "BLOCK_STRUCTURE", "DESIGN_BLOCK_STRUCTURE",
    "DESIGN_EFFORT_WEIGHT", "check_models", "generalized_plant", "design_plant",
    "closed_loop_matrix", "RolloffWeight", "DESIGN_ROLLOFF", "DESIGN_DELAY_SAMPLES",
    "DESIGN_PADE_ORDER", "effective_delay", "rolloff_weight", "delay_aware_plant",
    "delayed_closed_loop_response", "parametric_design_plant", "parametric_block_structure",
    "delayed_parametric_loop_response",
]

PLANT_INPUTS = ("u_Delta", "v_r", "u_b")
PLANT_OUTPUTS = ("y_Delta", "y1", "y2", "v_e")
#: Eq. 21 in MATLAB ``mussv`` convention: Delta_r (1 x 1) from y_Delta to
#: u_Delta, then the 1 x 2 performance block from [y1, y2] to v_r.
BLOCK_STRUCTURE = ((1, 1), (1, 2))
#: Block structure of :func:`design_plant`: the performance block also
#: receives the effort output y_u.
DESIGN_BLOCK_STRUCTURE = ((1, 1), (1, 3))
#: Control-effort weight rho of the synthesis plant (see :func:`design_plant`).
DESIGN_EFFORT_WEIGHT = 1e-3
#: Computation delay [samples] of the real-time loop the delay-aware design assumes.
DESIGN_DELAY_SAMPLES = 1
#: Order of the Pade approximation of the loop delay in :func:`delay_aware_plant`.
DESIGN_PADE_ORDER = 2


@dataclass(frozen=True)
class RolloffWeight:
    """Parameters of the roll-off weight W_u(s) on the controller output (KS weight).

    ``W_u(s) = (1 / K_hf) ((s / omega_u + r) / (s / omega_u + 1))^n`` with
    ``r = (K_hf / K_lf)^(1/n)``: gain 1 / K_lf in band, rising with n x 20
    dB/decade from about ``omega_u r`` to ``omega_u``, 1 / K_hf above.  Since
    y_u = W_u u_b joins the performance block, mu_RP < 1 implies
    |K S| < K_hf where W_u = 1 / K_hf, i.e. the controller's gain far above
    the loop bandwidth (where S ~ 1) stays below ``K_hf``.

    Attributes
    ----------
    hf_gain : float
        K_hf [V/V], largest controller gain allowed well above ``frequency``.
    lf_gain : float
        K_lf [V/V], gain allowed in band (large: no in-band penalty).
    frequency : float
        omega_u [rad/s], where the weight reaches its high-frequency level.
    order : int
        n, the slope of the transition in 20 dB/decade.

    Examples
    --------
    >>> DESIGN_ROLLOFF.hf_gain, DESIGN_ROLLOFF.order
    (10.0, 2)
    >>> RolloffWeight(hf_gain=5.0).lf_gain
    10000.0
    """

    hf_gain: float = 10.0
    lf_gain: float = 1e4
    frequency: float = 3e4
    order: int = 2


#: Roll-off requirement of the delay-aware design (docs/controller_design.md).
DESIGN_ROLLOFF = RolloffWeight()


def check_models(G, H_m, H_e, H_y):
    """Check that the plant and the weights are proper SISO LTI models (H_y: H_y G proper).

    Raises
    ------
    TypeError, ValueError
        Naming the first model that is not a SISO ``control.LTI``.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, _ = paper.problem()
    >>> check_models(G, H_m, H_e, H_y)[0] is G
    True
    """
    for name, sys in (("G", G), ("H_m", H_m), ("H_e", H_e), ("H_y", H_y)):
        check_siso(name, sys)
        check_finite_lti(name, sys)
        check_continuous(name, sys)   # a discrete G used to come back continuous
        if name != "H_y":             # H_y may be improper where G's roll-off covers it
            check_proper(name, sys)   # else G's realisation drops its polynomial part
    _check_output_weight_order(G, H_y)
    return G, H_m, H_e, H_y


def _check_output_weight_order(G, H_y):
    """Raise unless H_y G is proper: H_y's excess zeros at most G's relative degree."""
    g_num, g_den = _tf_coefficients(G)
    y_num, y_den = _tf_coefficients(H_y)
    excess, relative_degree = len(y_num) - len(y_den), len(g_den) - len(g_num)
    if excess > relative_degree:
        raise ValueError(f"H_y G is improper: H_y has {excess} excess zero(s), more than G's "
                         f"relative degree {relative_degree}; give H_y poles (roll it off)")


def _tf_coefficients(sys):
    tf = ct.tf(sys)
    return (np.trim_zeros(np.atleast_1d(tf.num[0][0]).astype(float), "f"),
            np.trim_zeros(np.atleast_1d(tf.den[0][0]).astype(float), "f"))


def _companion(den, nums):
    """Controllable canonical form of a SIMO system num_i/den (proper, den monic)."""
    den = np.asarray(den, float)
    n = len(den) - 1
    A = np.zeros((n, n))
    A[0, :] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = np.zeros((len(nums), n))
    D = np.zeros((len(nums), 1))
    for i, num in enumerate(nums):
        num = np.asarray(num, float)
        if len(num) > n + 1:
            raise ValueError("improper product: the weight's excess zeros exceed "
                             "the plant's relative degree")
        num = np.r_[np.zeros(n + 1 - len(num)), num]
        D[i, 0] = num[0]
        C[i, :] = num[1:] - num[0] * den[1:]
    return A, B, C, D


def _plant_with_output_weight(G, H_y, omega_s):
    """G and H_y G from u_c, as one block in scaled time (outputs v_y, y2).

    H_y's fastest poles (as many as G's relative degree allows) leave H_y as
    unit-DC low-pass factors F; the rest, H_y / F, is realised jointly with G
    on G's states and y2 is that output filtered by F (docs/controller_design.md).
    """
    g_num, g_den = _tf_coefficients(G)
    y_num, y_den = _tf_coefficients(H_y)
    poles = np.roots(y_den)
    poles = poles[np.argsort(-np.abs(poles))]
    relative_degree = len(g_den) - len(g_num)
    n_split = min(len(poles), relative_degree - (len(y_num) - len(y_den)))   # >= 0: checked
    split, rest = poles[:n_split], poles[n_split:]
    if np.any(split.real >= 0):
        raise ValueError(f"H_y must be stable, got poles {split[split.real >= 0]}")
    rest_den = np.real(np.poly(rest)) if rest.size else np.ones(1)
    gain = y_den[0] * np.real(np.prod(-split))
    den = np.polymul(g_den, rest_den)
    nums = [np.polymul(g_num, rest_den), np.polymul(g_num, y_num) / gain]
    scaled = [scaled_coefficients(num, den, omega_s) for num in nums]
    joint = balance(ct.ss(*_companion(scaled[0][1], [num for num, _ in scaled])))
    if split.size == 0:
        return with_signals(joint, ["u_c"], ["v_y", "y2"])
    joint = with_signals(joint, ["u_c"], ["v_y", "y2_raw"])
    f_den = np.real(np.poly(split / omega_s))
    f_num = np.array([np.real(np.prod(-split / omega_s))])
    F = with_signals(balance(ct.ss(*_companion(f_den, [f_num]))), ["y2_raw"], ["y2"])
    return ct.interconnect([joint, F], inputs="u_c", outputs=["v_y", "y2"])


def generalized_plant(G, H_m, H_e, H_y, *, effort_weight=0.0, omega_s=None):
    """Generalized plant P of Fig. 9 / eq. 16 as a named-signal state-space model.

    Parameters
    ----------
    G : control.LTI
        Plant, u_c [V] -> v_y [V].
    H_m, H_e, H_y : control.LTI
        Uncertainty weight (on u_b), error weight (on v_e) and output weight
        (on v_y), SISO.
    effort_weight : float, optional
        rho >= 0; when positive an output ``y_u = rho u_b`` is added after y2.
    omega_s : float, optional
        Internal time scale [rad/s] of the realisation; default
        ``time_scale_of(G, H_m, H_e, H_y)``.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2[, y_u], v_e``;
        ordinary time; named ``P``.  14 states for the published models.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, _ = paper.problem()
    >>> generalized_plant(G, H_m, H_e, H_y).nstates
    14
    """
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    effort_weight = check_nonnegative("effort_weight", effort_weight)
    omega_s = (time_scale_of(G, H_m, H_e, H_y) if omega_s is None
               else check_positive("omega_s", omega_s))
    blocks = [_plant_with_output_weight(G, H_y, omega_s),
              with_signals(to_scaled(H_m, omega_s), ["u_b"], ["y_Delta"]),
              with_signals(to_scaled(H_e, omega_s), ["v_e"], ["y1"]),
              ct.summing_junction(["u_Delta", "u_b"], "u_c"),
              ct.summing_junction(["v_r", "-v_y"], "v_e")]
    outputs = list(PLANT_OUTPUTS)
    if effort_weight > 0:
        blocks.append(ct.ss([], [], [], [[effort_weight]], inputs="u_b", outputs="y_u"))
        outputs.insert(3, "y_u")
    P = balance(ct.interconnect(blocks, inputs=list(PLANT_INPUTS), outputs=outputs))
    return from_scaled(P, omega_s, list(PLANT_INPUTS), outputs, name="P")


def design_plant(G, H_m, H_e, H_y, *, effort_weight=DESIGN_EFFORT_WEIGHT, omega_s=None):
    """The generalized plant used for synthesis: eq. 16 with D12 regularised.

    :func:`generalized_plant` with the output ``y_u = rho u_b``, rho =
    ``effort_weight`` (default :data:`DESIGN_EFFORT_WEIGHT` = 1e-3), which
    makes D12 full rank (the published P has D12 = [2e-10, 0, 0]).  y_u joins
    the performance block: block structure :data:`DESIGN_BLOCK_STRUCTURE`.
    Adding an output can only raise mu, so the mu of the exact M (eq. 18) is
    at most the design value.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI
        As in :func:`generalized_plant`.
    effort_weight : float, optional
        rho >= 0 (0 gives the exact P of :func:`generalized_plant`).
    omega_s : float, optional
        As in :func:`generalized_plant`.

    Returns
    -------
    control.StateSpace
        Outputs ``y_Delta, y1, y2, y_u, v_e``.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, _ = paper.problem()
    >>> design_plant(G, H_m, H_e, H_y).output_labels
    ['y_Delta', 'y1', 'y2', 'y_u', 'v_e']
    """
    return generalized_plant(G, H_m, H_e, H_y, effort_weight=effort_weight, omega_s=omega_s)


def closed_loop_matrix(K, G, H_m, H_e, H_y, *, omega_s=None):
    """M(s) = F_l(P, K) of eq. 17-18 with the exact P (no regularisation).

    Parameters
    ----------
    K : control.LTI
        Continuous-time SISO controller, v_e [V] -> u_b [V].
    G, H_m, H_e, H_y : control.LTI
        As in :func:`generalized_plant`.
    omega_s : float, optional
        Internal time scale [rad/s]; default ``time_scale_of(G, H_m, H_e, H_y, K)``.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r``; outputs ``y_Delta, y1, y2``; named ``M``.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> M = closed_loop_matrix(K, G, H_m, H_e, H_y)
    >>> M.input_labels, M.output_labels, M.nstates
    (['u_Delta', 'v_r'], ['y_Delta', 'y1', 'y2'], 20)
    """
    _check_controller(K)
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    omega_s = (time_scale_of(G, H_m, H_e, H_y, K) if omega_s is None
               else check_positive("omega_s", omega_s))
    P = generalized_plant(G, H_m, H_e, H_y, omega_s=omega_s)
    return lower_lft(P, K, omega_s)


def _check_controller(K):
    """Check K: SISO, continuous-time, finite coefficients.

    A NaN coefficient would otherwise first show in the time scale chosen from all the
    models ("systems[4] has a NaN coefficient") or as NaN responses, without naming K.
    """
    check_siso("K", K)
    return check_model("K", K)


def effective_delay(fs, delay_samples):
    """Effective loop delay [s] of a sampled loop: (d + 1/2) / fs.

    A zero-order hold acts, below the Nyquist frequency, like half a sample of
    delay; a computation delay of d whole samples adds d / fs.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    delay_samples : int
        Computation delay d >= 0 [samples].

    Returns
    -------
    float
        tau [s].

    Examples
    --------
    >>> effective_delay(10e3, 1)
    0.00015
    """
    fs = check_positive("fs", fs)
    delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
    return (delay_samples + 0.5) / fs


def rolloff_weight(params=DESIGN_ROLLOFF):
    """The roll-off weight W_u(s) of :class:`RolloffWeight` as a transfer function.

    Parameters
    ----------
    params : RolloffWeight

    Returns
    -------
    control.TransferFunction
        W_u(s), input ``u_b`` [V], output ``y_u`` [V/V-normalised].

    Raises
    ------
    TypeError
        ``params`` is not a :class:`RolloffWeight`.
    ValueError
        Non-positive gains or frequency, ``lf_gain <= hf_gain`` or order < 1.

    Examples
    --------
    >>> W_u = rolloff_weight()
    >>> W_u.name, W_u.input_labels, W_u.output_labels
    ('W_u', ['u_b'], ['y_u'])
    >>> print(f"{1 / abs(W_u(0)):.0f} {1 / abs(W_u(1e9j)):.1f}")   # K_lf in band, K_hf far above
    10000 10.0
    """
    return _rolloff_weight(params, "params")


def _rolloff_weight(params, name):
    """:func:`rolloff_weight` with errors naming the argument ``name`` (``rolloff`` in the
    functions that take the parameters under that name)."""
    check_type(name, params, RolloffWeight, "a RolloffWeight")
    k_hf = check_positive(f"{name}.hf_gain", params.hf_gain)
    k_lf = check_positive(f"{name}.lf_gain", params.lf_gain)
    w_u = check_positive(f"{name}.frequency", params.frequency)
    n = check_integer(f"{name}.order", params.order, minimum=1)
    if k_lf <= k_hf:
        raise ValueError(f"{name}.lf_gain ({k_lf}) must exceed {name}.hf_gain ({k_hf})")
    r = (k_hf / k_lf) ** (1.0 / n)
    factor = ct.tf([1.0 / w_u, r], [1.0 / w_u, 1.0])
    W = ct.tf([1.0 / k_hf], [1.0])
    for _ in range(n):
        W = W * factor
    return ct.tf(W.num, W.den, inputs="u_b", outputs="y_u", name="W_u")


def delay_aware_plant(G, H_m, H_e, H_y, *, fs, delay_samples=DESIGN_DELAY_SAMPLES,
                      pade_order=DESIGN_PADE_ORDER, rolloff=DESIGN_ROLLOFF, omega_s=None):
    """Synthesis plant for a sampled loop with computation delay and a roll-off requirement.

    The controller output u_b reaches the stage after the effective delay
    tau = (d + 1/2) / fs (:func:`effective_delay`), modelled by a Pade
    approximation of order ``pade_order``: with u_b' = e^{-s tau} u_b,

        y_Delta = H_m u_b',  u_c = u_Delta + u_b',  y1 = H_e (v_r - G u_c),
        y2 = H_y G u_c,      y_u = W_u u_b,          v_e = v_r - G u_c,

    so the uncertainty acts on the input that is really applied.  y_u, with
    the roll-off weight W_u of :func:`rolloff_weight`, joins the performance
    block (:data:`DESIGN_BLOCK_STRUCTURE`) and replaces the 1e-3 effort
    regulariser of :func:`design_plant`.  The paper's problem
    (:func:`generalized_plant`) is not changed.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI
        As in :func:`generalized_plant`.
    fs : float
        Sampling rate [Hz] of the real-time loop.
    delay_samples : int, optional
        Computation delay d [samples] (default 1: the control computed from
        v_y[k] is applied at sample k + 1).
    pade_order : int, optional
        Order of the Pade approximation of e^{-s tau} (>= 1).
    rolloff : RolloffWeight, optional
        Parameters of W_u.
    omega_s : float, optional
        Internal time scale [rad/s]; default ``time_scale_of(G, H_m, H_e, H_y)``.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2, y_u, v_e``;
        named ``P_delay``; 14 + ``pade_order`` + ``rolloff.order`` states.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, _ = paper.problem()
    >>> P = delay_aware_plant(G, H_m, H_e, H_y, fs=10e3)
    >>> P.name, P.nstates                      # 14 + Pade order 2 + roll-off order 2
    ('P_delay', 18)
    """
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    tau = effective_delay(fs, delay_samples)
    pade_order = check_integer("pade_order", pade_order, minimum=1)
    W_u = _rolloff_weight(rolloff, "rolloff")
    omega_s = (time_scale_of(G, H_m, H_e, H_y) if omega_s is None
               else check_positive("omega_s", omega_s))
    P0 = with_signals(to_scaled(generalized_plant(G, H_m, H_e, H_y, omega_s=omega_s), omega_s),
                      ["u_Delta", "v_r", "u_b_applied"], list(PLANT_OUTPUTS))
    num, den = ct.pade(tau * omega_s, pade_order)          # in scaled time
    delay = with_signals(balance(ct.ss(ct.tf(num, den))), ["u_b"], ["u_b_applied"])
    weight = with_signals(to_scaled(W_u, omega_s), ["u_b"], ["y_u"])
    outputs = ["y_Delta", "y1", "y2", "y_u", "v_e"]
    P = balance(ct.interconnect([P0, delay, weight], inputs=list(PLANT_INPUTS),
                                outputs=outputs))
    return from_scaled(P, omega_s, list(PLANT_INPUTS), outputs, name="P_delay")


def delayed_closed_loop_response(K, G, H_m, H_e, H_y, omega, *, fs, delay_samples,
                                 rolloff=None):
    """Frequency response of M = F_l(P, K) with the exact loop delay e^{-j omega tau}.

    The same loop as :func:`delay_aware_plant` with the delay exact instead
    of Pade-approximated, tau = (d + 1/2) / fs.  Without ``rolloff`` this is
    eq. 18 with the delay: outputs ``y_Delta, y1, y2``, block structure
    :data:`BLOCK_STRUCTURE`; with it the output y_u = W_u u_b is added
    (:data:`DESIGN_BLOCK_STRUCTURE`).

    Parameters
    ----------
    K : control.LTI
        Continuous SISO controller, v_e [V] -> u_b [V].
    G, H_m, H_e, H_y : control.LTI
        As in :func:`generalized_plant`.
    omega : array_like
        Frequencies [rad/s], positive and increasing.
    fs : float
        Sampling rate [Hz].
    delay_samples : int
        Computation delay d [samples].
    rolloff : RolloffWeight, optional
        Add the roll-off output.

    Returns
    -------
    ndarray, shape (len(omega), 3 or 4, 2)
        Inputs ``u_Delta, v_r``.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> R = delayed_closed_loop_response(K, G, H_m, H_e, H_y, [1e2, 1e3], fs=10e3,
    ...                                  delay_samples=1)
    >>> R.shape                                # (frequencies, y_Delta y1 y2, u_Delta v_r)
    (2, 3, 2)
    """
    _check_controller(K)
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    omega = check_frequency_grid("omega", omega, min_length=1)
    tau = effective_delay(fs, delay_samples)
    W_u = None if rolloff is None else _rolloff_weight(rolloff, "rolloff")
    P = generalized_plant(G, H_m, H_e, H_y)
    R = np.moveaxis(P(1j * omega, squeeze=False), -1, 0)
    R[:, :, 2] *= np.exp(-1j * omega * tau)[:, None]        # u_b arrives tau later
    if W_u is not None:
        w_u = np.ravel(W_u(1j * omega))
        extra = np.zeros((omega.size, 1, 3), complex)
        extra[:, 0, 2] = w_u
        R = np.concatenate([R[:, :3], extra, R[:, 3:]], axis=1)
    return _closed_loop_response(R, K, omega)


def _closed_loop_response(R, K, omega):
    """F_l(R, K) frequency by frequency: R (nf, p, q) with the measurement last among the
    outputs and the control last among the inputs, K SISO."""
    k = np.ravel(K(1j * omega))
    f = k / (1 - R[:, -1, -1] * k)
    return R[:, :-1, :-1] + f[:, None, None] * R[:, :-1, -1][:, :, None] * R[:, -1, :-1][:, None, :]



def parametric_block_structure(n_coefficients):
    """Block structure of :func:`parametric_design_plant`: one real scalar per
    coefficient, then the 1 x 3 performance block (v_r -> y1, y2, y_u).

    Examples
    --------
    >>> parametric_block_structure(2)
    ((-1, 0), (-1, 0), (1, 3))
    """
    n_coefficients = check_integer("n_coefficients", n_coefficients, minimum=1)
    return ((-1, 0),) * n_coefficients + ((1, 3),)


def parametric_design_plant(G, H_e, H_y, spread, *, fs, delay_samples=DESIGN_DELAY_SAMPLES,
                            pade_order=DESIGN_PADE_ORDER, rolloff=DESIGN_ROLLOFF, omega_s=None):
    """Delay-aware synthesis plant whose uncertainty is G's real coefficient box.

    :func:`delay_aware_plant` with the complex weight H_m replaced by the
    exact upper LFT of :func:`piezolib.uncertainty.parametric.parametric_lft`:
    one real scalar q_i in [-1, 1] per denominator coefficient of G, which
    then varies by +-``spread`` (relative).  With u_b' = e^{-s tau} u_b (Pade),

        [z; v_y] = P_G [w; u_b'],  y1 = H_e (v_r - v_y),  y2 = H_y v_y,
        y_u = W_u u_b,             v_e = v_r - v_y.

    mu_RS <= 1 on the first n blocks certifies the box of relative size
    ``spread``; the block structure is :func:`parametric_block_structure`.

    Parameters
    ----------
    G : control.LTI
        Nominal plant u_c [V] -> v_y [V], SISO, proper.
    H_e, H_y : control.LTI
        Error and output weights, as in :func:`generalized_plant`.
    spread : float
        Relative size of the coefficient box (0.05 is the paper's +-5 %).
    fs : float
        Sampling rate [Hz] of the loop.
    delay_samples, pade_order, rolloff : as in :func:`delay_aware_plant`.
    omega_s : float, optional
        Internal time scale [rad/s]; default ``time_scale_of(G, H_e, H_y)``.

    Returns
    -------
    control.StateSpace
        Inputs ``w_0 ... w_{n-1}, v_r, u_b``; outputs ``z_0 ... z_{n-1}, y1, y2,
        y_u, v_e``; named ``P_par``.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, _, H_e, H_y, _ = paper.problem()
    >>> P = parametric_design_plant(G, H_e, H_y, 0.05, fs=10e3)
    >>> P.name, P.input_labels[-2:], P.output_labels[-4:]
    ('P_par', ['v_r', 'u_b'], ['y1', 'y2', 'y_u', 'v_e'])
    """
    from piezolib.uncertainty.parametric import parametric_lft

    G, _, H_e, H_y = check_models(G, ct.tf([1.0], [1.0]), H_e, H_y)
    spread = check_positive("spread", spread)
    tau = effective_delay(fs, delay_samples)
    pade_order = check_integer("pade_order", pade_order, minimum=1)
    W_u = _rolloff_weight(rolloff, "rolloff")
    omega_s = (time_scale_of(G, H_e, H_y) if omega_s is None
               else check_positive("omega_s", omega_s))
    lft = parametric_lft(G, spread)
    n = len(lft.blk)
    w = [f"w_{i}" for i in range(n)]
    z = [f"z_{i}" for i in range(n)]
    plant = with_signals(to_scaled(lft.P, omega_s), w + ["u_b_applied"], z + ["v_y"])
    num, den = ct.pade(tau * omega_s, pade_order)          # in scaled time
    delay = with_signals(balance(ct.ss(ct.tf(num, den))), ["u_b"], ["u_b_applied"])
    blocks = [plant, delay,
              with_signals(to_scaled(W_u, omega_s), ["u_b"], ["y_u"]),
              with_signals(to_scaled(ct.ss(H_e), omega_s), ["v_e"], ["y1"]),
              with_signals(to_scaled(ct.ss(H_y), omega_s), ["v_y"], ["y2"]),
              ct.summing_junction(["v_r", "-v_y"], "v_e")]
    inputs = w + ["v_r", "u_b"]
    outputs = z + ["y1", "y2", "y_u", "v_e"]
    P = balance(ct.interconnect(blocks, inputs=inputs, outputs=outputs))
    return from_scaled(P, omega_s, inputs, outputs, name="P_par")


def delayed_parametric_loop_response(K, G, H_e, H_y, spread, omega, *, fs, delay_samples,
                                     rolloff=DESIGN_ROLLOFF):
    """F_l(P_par, K)(j omega) of :func:`parametric_design_plant` with the exact loop delay.

    The plant's Pade model of the delay is replaced by e^{-j omega tau}, tau =
    (d + 1/2) / fs, on every path from u_b except the roll-off output y_u,
    which reads u_b before the delay.

    Parameters
    ----------
    K : control.LTI
        Continuous SISO controller, v_e [V] -> u_b [V].
    G, H_e, H_y, spread : as in :func:`parametric_design_plant`.
    omega : array_like
        Frequencies [rad/s], positive and increasing.
    fs : float
        Sampling rate [Hz].
    delay_samples : int
        Computation delay d [samples].
    rolloff : RolloffWeight

    Returns
    -------
    ndarray, shape (len(omega), n + 3, n + 1)
        Outputs ``z_0 ... z_{n-1}, y1, y2, y_u``; inputs ``w_0 ... w_{n-1}, v_r``
        (structure :func:`parametric_block_structure`).

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, _, H_e, H_y, K = paper.problem()
    >>> R = delayed_parametric_loop_response(K, G, H_e, H_y, 0.05, [1e2, 1e3], fs=10e3,
    ...                                      delay_samples=1)
    >>> R.shape                                # 6 coefficients: (2, 6 + 3, 6 + 1)
    (2, 9, 7)
    """
    _check_controller(K)
    omega = check_frequency_grid("omega", omega, min_length=1)
    tau = effective_delay(fs, delay_samples)
    P = parametric_design_plant(G, H_e, H_y, spread, fs=fs, delay_samples=delay_samples,
                                pade_order=DESIGN_PADE_ORDER, rolloff=rolloff)
    num, den = ct.pade(tau, DESIGN_PADE_ORDER)
    pade = np.ravel(ct.tf(num, den)(1j * omega))
    R = np.moveaxis(P(1j * omega, squeeze=False), -1, 0)
    y_u = P.output_labels.index("y_u")
    rows = [i for i in range(P.noutputs) if i != y_u]
    R[:, rows, -1] *= (np.exp(-1j * omega * tau) / pade)[:, None]
    return _closed_loop_response(R, K, omega)
