"""Generalized plant of Fig. 9 (eq. 16), its lower LFT (eq. 17) and M (eq. 18).

Signals (all in volts; frequencies in rad/s):

==========  ======  ===================================================
signal      side    meaning
==========  ======  ===================================================
u_Delta     input   output of the uncertainty block Delta_r, added to u_b
v_r         input   reference voltage (the performance input)
u_b         input   feedback control voltage (controller output)
y_Delta     output  H_m u_b, the input of Delta_r
y1          output  H_e v_e, weighted tracking error
y2          output  H_y v_y, weighted measured output
y_u         output  effort_weight * u_b (only when ``effort_weight > 0``)
v_e         output  v_r - v_y, the measurement (controller input)
==========  ======  ===================================================

With u_c = u_Delta + u_b and v_y = G u_c, eq. 16 reads

    y_Delta = H_m u_b,          y1 = H_e (v_r - G u_c),
    y2 = H_y G u_c,             v_e = v_r - G u_c.

Closing u_b = K v_e gives M = F_l(P, K) (eq. 17) from [u_Delta, v_r] to
[y_Delta, y1, y2] with the entries of eq. 18.

Two options prepare P for synthesis; both are off by default (the exact
published P) and both are reported by whoever uses them:

* ``effort_weight`` adds the output y_u = rho u_b.  The only direct path from
  u_b to the performance outputs is H_m's high-frequency gain g*epsilon =
  2e-10, so D12 is numerically rank deficient; a small rho makes it full rank.
* ``weight_pole_limit`` drops the poles of H_y faster than the limit, keeping
  the DC gain (each factor 1/(1 - s/p) is replaced by 1).  The published H_y
  has a double pole at -omega_y/eps_y = -7.5e7 rad/s, four decades above the
  loop's bandwidth, which stretches the eigenvalue spread of P to about 2e7.
  The weight without those poles is improper, but H_y G stays strictly
  proper (G has relative degree 3).  :func:`weight_truncation_error` states
  what the truncation changes.  With the realisation used here (below) the
  exact P is well enough conditioned for synthesis, so :func:`design_plant`
  does not use this option; it is kept for weights with even faster poles.

How H_y G is realised matters: a direct realisation of the published H_y has
D = 1e8 and loses 0.5 % of H_y G at low frequency to cancellation, which was
enough to make the H-infinity Riccati equations fail.  Here H_y's fastest
poles (as many as G's relative degree allows) are split off as unit-DC
low-pass factors, the rest of H_y is realised jointly with G on G's states,
and y2 is that output filtered by the low-pass factors: no large numbers are
subtracted (relative error of P's frequency response about 1e-11).

Every realisation is built in scaled time (s -> s/omega_s) and balanced; the
returned models are in ordinary time (seconds).
"""

import control as ct
import numpy as np

from piezolib import paper
from piezolib._checks import check_finite_array, check_lti, check_nonnegative, check_positive, check_siso
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import DEFAULT_TIME_SCALE, balance, scale_time, scaled_coefficients

__all__ = [
    "PLANT_INPUTS", "PLANT_OUTPUTS", "M_INPUTS", "M_OUTPUTS", "BLOCK_STRUCTURE",
    "generalized_plant", "design_plant", "drop_fast_poles", "weight_truncation_error",
    "closed_loop_matrix", "DESIGN_EFFORT_WEIGHT",
    "DESIGN_BLOCK_STRUCTURE",
]

PLANT_INPUTS = ("u_Delta", "v_r", "u_b")
PLANT_OUTPUTS = ("y_Delta", "y1", "y2", "v_e")
M_INPUTS = ("u_Delta", "v_r")
M_OUTPUTS = ("y_Delta", "y1", "y2")
#: Eq. 21 in MATLAB ``mussv`` convention: Delta_r (1 x 1) from y_Delta to
#: u_Delta, then the 1 x 2 performance block from [y1, y2] to v_r.
BLOCK_STRUCTURE = ((1, 1), (1, 2))

#: Control-effort weight of the synthesis plant (see :func:`design_plant`).
DESIGN_EFFORT_WEIGHT = 1e-3


def _defaults(G, H_m, H_e, H_y):
    G = paper.plant() if G is None else G
    H_m = paper.uncertainty_weight() if H_m is None else H_m
    H_e = paper.error_weight() if H_e is None else H_e
    H_y = paper.output_weight() if H_y is None else H_y
    for name, sys in (("G", G), ("H_m", H_m), ("H_e", H_e), ("H_y", H_y)):
        check_siso(name, sys)
    return G, H_m, H_e, H_y


def _tf_coefficients(sys):
    tf = ct.tf(sys)
    return (np.trim_zeros(np.atleast_1d(tf.num[0][0]).astype(float), "f"),
            np.trim_zeros(np.atleast_1d(tf.den[0][0]).astype(float), "f"))


def drop_fast_poles(sys, limit):
    """Numerator and denominator of ``sys`` without its poles faster than ``limit``.

    Each dropped pole p (|p| > limit [rad/s]) is removed as the factor
    1/(1 - s/p), so the DC gain is unchanged.  The result may be improper, so
    it is returned as coefficient arrays (highest power first), not as a
    transfer function.

    Returns
    -------
    num, den : ndarray
        Coefficients of the truncated weight.
    dropped : ndarray
        The dropped poles [rad/s].
    """
    check_siso("sys", sys)
    limit = check_positive("limit", limit)
    num, den = _tf_coefficients(sys)
    poles = np.roots(den)
    fast = np.abs(poles) > limit
    if np.any(poles[fast].real >= 0):
        raise ValueError("only stable poles can be dropped from a weight; "
                         f"unstable fast poles: {poles[fast & (poles.real >= 0)]}")
    kept = np.real_if_close(np.poly(poles[~fast])) if np.any(~fast) else np.ones(1)
    # den = den[0] prod(s - p); dropping 1/(1 - s/p) leaves den[0] prod_kept(s - p) prod_fast(-p)
    scale = den[0] * np.real(np.prod(-poles[fast]))
    return num.copy(), np.real(kept) * scale, poles[fast]


def weight_truncation_error(sys, limit, omega):
    """Relative error caused by :func:`drop_fast_poles`, magnitude and phase.

    Returns ``|W_trunc(j omega) / W(j omega) - 1|`` on ``omega`` [rad/s].
    Dropping a real pole p changes the phase by about omega/|p| and the
    magnitude only by about (omega/p)^2 / 2.
    """
    omega = check_finite_array("omega", omega, ndim=1)
    num, den, _ = drop_fast_poles(sys, limit)
    s = 1j * omega
    trunc = np.polyval(num, s) / np.polyval(den, s)
    return np.abs(trunc / np.ravel(sys(s)) - 1.0)


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


def _plant_with_output_weight(G, H_y, limit, omega_s):
    """G and H_y G from u_c, as one block in scaled time (outputs v_y, y2).

    H_y's poles are split so that no realisation subtracts large numbers: the
    fastest poles (as many as G's relative degree allows) leave H_y as unit-DC
    low-pass factors F = prod 1/(1 - s/p); the rest, H_y / F, is realised
    jointly with G on G's states (H_y G / F is still proper), and y2 is that
    output filtered by F.  Poles faster than ``limit`` are dropped from F.
    (A direct realisation of the published H_y has D = 1e8 and loses about
    0.5 % of H_y G at low frequency to cancellation.)
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
    filt = split if limit is None else split[np.abs(split) <= limit]
    rest_den = np.real(np.poly(rest)) if rest.size else np.ones(1)
    gain = y_den[0] * np.real(np.prod(-split))
    den = np.polymul(g_den, rest_den)
    nums = [np.polymul(g_num, rest_den), np.polymul(g_num, y_num) / gain]
    scaled = [scaled_coefficients(num, den, omega_s) for num in nums]
    joint = balance(ct.ss(*_companion(scaled[0][1], [num for num, _ in scaled])))
    joint = ct.ss(joint, inputs="u_c", outputs=["v_y", "y2_raw"])
    if filt.size == 0:
        return ct.ss(joint.A, joint.B, joint.C, joint.D, inputs="u_c", outputs=["v_y", "y2"])
    f_den = np.real(np.poly(filt / omega_s))
    f_num = np.array([np.real(np.prod(-filt / omega_s))])
    F = balance(ct.ss(*_companion(f_den, [f_num])))
    F = ct.ss(F, inputs="y2_raw", outputs="y2")
    return ct.interconnect([joint, F], inputs="u_c", outputs=["v_y", "y2"])


def _scaled_block(sys, omega_s, inputs, outputs):
    sys = balance(ct.ss(scale_time(sys, omega_s)))
    return ct.ss(sys, inputs=inputs, outputs=outputs)


def generalized_plant(G=None, H_m=None, H_e=None, H_y=None, *, effort_weight=0.0,
                      weight_pole_limit=None, omega_s=DEFAULT_TIME_SCALE):
    """Generalized plant P of Fig. 9 / eq. 16 as a named-signal state-space model.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI, optional
        Plant (u_c -> v_y), uncertainty weight, error weight and output
        weight; default: the published models of :mod:`piezolib.paper`.
    effort_weight : float, optional
        rho >= 0; when positive an output ``y_u = rho u_b`` is added after y2.
    weight_pole_limit : float, optional
        Drop the poles of H_y faster than this [rad/s] (see module docstring).
    omega_s : float, optional
        Internal time scale [rad/s] of the realisation.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2[, y_u], v_e``;
        ordinary time.  ``P.nstates`` is 14 for the published models (12 with
        the fast poles of H_y dropped).
    """
    G, H_m, H_e, H_y = _defaults(G, H_m, H_e, H_y)
    effort_weight = check_nonnegative("effort_weight", effort_weight)
    omega_s = check_positive("omega_s", omega_s)
    if weight_pole_limit is not None:
        weight_pole_limit = check_positive("weight_pole_limit", weight_pole_limit)
    GHy = _plant_with_output_weight(G, H_y, weight_pole_limit, omega_s)
    blocks = [GHy,
              _scaled_block(H_m, omega_s, "u_b", "y_Delta"),
              _scaled_block(H_e, omega_s, "v_e", "y1"),
              ct.summing_junction(["u_Delta", "u_b"], "u_c"),
              ct.summing_junction(["v_r", "-v_y"], "v_e")]
    outputs = list(PLANT_OUTPUTS)
    if effort_weight > 0:
        blocks.append(ct.ss([], [], [], [[effort_weight]], inputs="u_b", outputs="y_u"))
        outputs.insert(3, "y_u")
    P = balance(ct.interconnect(blocks, inputs=list(PLANT_INPUTS), outputs=outputs))
    P = balance(scale_time(P, 1.0 / omega_s))
    return ct.ss(P.A, P.B, P.C, P.D, inputs=list(PLANT_INPUTS), outputs=outputs, name="P")


#: Block structure of :func:`design_plant`: the performance block also
#: receives the effort output y_u.
DESIGN_BLOCK_STRUCTURE = ((1, 1), (1, 3))


def design_plant(G=None, H_m=None, H_e=None, H_y=None, *, effort_weight=DESIGN_EFFORT_WEIGHT,
                 omega_s=DEFAULT_TIME_SCALE):
    """The generalized plant used for synthesis: eq. 16 with D12 regularised.

    Same as :func:`generalized_plant` with the output y_u = rho u_b,
    rho = ``effort_weight`` = 1e-3, which makes D12 full rank (the published
    P has D12 = [2e-10, 0, 0]).  y_u joins the performance block, which
    becomes 1 x 3 (y1, y2, y_u): block structure
    :data:`DESIGN_BLOCK_STRUCTURE`.  Since adding an output can only raise
    mu, the mu of the exact M (eq. 18) is at most the design value; rho =
    1e-4 ... 1e-3 changed the DK result by less than 1e-5.
    """
    return generalized_plant(G, H_m, H_e, H_y, effort_weight=effort_weight, omega_s=omega_s)


def closed_loop_matrix(K, G=None, H_m=None, H_e=None, H_y=None, omega_s=DEFAULT_TIME_SCALE):
    """M(s) of eq. 18: inputs ``u_Delta, v_r``, outputs ``y_Delta, y1, y2``.

    Built as F_l(P, K) with the exact published P (no regularisation).
    """
    check_siso("K", K)
    P = generalized_plant(G, H_m, H_e, H_y, omega_s=omega_s)
    return lower_lft(P, K, omega_s)
