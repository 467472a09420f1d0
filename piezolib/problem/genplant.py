"""Generalized plant P of Fig. 9 (eq. 16) and its lower LFT M = F_l(P, K) (eq. 17-18).

Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2[, y_u], v_e``, all in
volts, frequencies in rad/s.  The signal table, how H_y G is realised and why
the synthesis plant carries an effort output are in ``docs/design.md``.
"""

import control as ct
import numpy as np

from piezolib._checks import check_nonnegative, check_positive, check_siso
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import (balance, from_scaled, scaled_coefficients, time_scale_of,
                                 to_scaled, with_signals)

__all__ = [
    "PLANT_INPUTS", "PLANT_OUTPUTS", "BLOCK_STRUCTURE", "DESIGN_BLOCK_STRUCTURE",
    "DESIGN_EFFORT_WEIGHT", "check_models", "generalized_plant", "design_plant",
    "closed_loop_matrix",
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


def check_models(G, H_m, H_e, H_y):
    """Check that the plant and the three weights are SISO LTI models; return them.

    Raises
    ------
    TypeError, ValueError
        Naming the first model that is not a SISO ``control.LTI``.
    """
    for name, sys in (("G", G), ("H_m", H_m), ("H_e", H_e), ("H_y", H_y)):
        check_siso(name, sys)
    return G, H_m, H_e, H_y


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
    on G's states and y2 is that output filtered by F (docs/design.md).
    """
    g_num, g_den = _tf_coefficients(G)
    y_num, y_den = _tf_coefficients(H_y)
    poles = np.roots(y_den)
    poles = poles[np.argsort(-np.abs(poles))]
    relative_degree = len(g_den) - len(g_num)
    n_split = min(len(poles), relative_degree - (len(y_num) - len(y_den)))
    if n_split < 0:
        raise ValueError("H_y G is improper: H_y has more excess zeros than G's "
                         "relative degree")
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
    >>> from piezolib import paper
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
    """
    return generalized_plant(G, H_m, H_e, H_y, effort_weight=effort_weight, omega_s=omega_s)


def closed_loop_matrix(K, G, H_m, H_e, H_y, *, omega_s=None):
    """M(s) = F_l(P, K) of eq. 17-18 with the exact P (no regularisation).

    Parameters
    ----------
    K : control.LTI
        SISO controller, v_e [V] -> u_b [V].
    G, H_m, H_e, H_y : control.LTI
        As in :func:`generalized_plant`.
    omega_s : float, optional
        Internal time scale [rad/s]; default ``time_scale_of(G, H_m, H_e, H_y, K)``.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r``; outputs ``y_Delta, y1, y2``; named ``M``.
    """
    check_siso("K", K)
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    omega_s = (time_scale_of(G, H_m, H_e, H_y, K) if omega_s is None
               else check_positive("omega_s", omega_s))
    P = generalized_plant(G, H_m, H_e, H_y, omega_s=omega_s)
    return lower_lft(P, K, omega_s)
