"""The paper's design problem with its uncertainty as real coefficient blocks.

Eq. 16 with the complex multiplicative block H_m Delta replaced by the six
real offsets of the denominator coefficients a_0 ... a_5 (Sec. III-B, eq. 5:
a_i (1 + spread q_i), q_i in [-1, 1]), written as the real parametric LFT of
:func:`piezolib.uncertainty.parametric.parametric_lft`.  The performance
channels are those of :func:`piezolib.problem.genplant.design_plant`
(H_e on v_e, H_y on v_y, the effort output rho u_b).
"""

import control as ct
import numpy as np

from piezolib._checks import check_positive, check_siso
from piezolib.problem.genplant import DESIGN_EFFORT_WEIGHT
from piezolib.robust.lti import balance, from_scaled, time_scale_of, to_scaled, with_signals
from piezolib.uncertainty.parametric import parametric_lft

__all__ = ["parametric_design_plant", "parametric_block_structure"]


def parametric_block_structure(n):
    """n real scalars (the coefficients) then the 1 x 3 performance block [y1, y2, y_u] -> v_r."""
    return ((-1, 0),) * int(n) + ((1, 3),)


def parametric_design_plant(G, H_e, H_y, spread, *, effort_weight=DESIGN_EFFORT_WEIGHT):
    """Generalized plant with the coefficient box as real blocks.

    Parameters
    ----------
    G : control.LTI
        Plant u_b [V] -> v_y [V] (the nominal of the box).
    H_e, H_y : control.LTI
        Error and output weights (eq. 15).
    spread : float
        Relative spread of the coefficients (0.05 in the paper), built into P.
    effort_weight : float, optional
        rho > 0 of the effort output y_u = rho u_b.

    Returns
    -------
    P : control.StateSpace
        Inputs ``w_0 ... w_{n-1}, v_r, u_b``; outputs ``z_0 ... z_{n-1}, y1,
        y2, y_u, v_e``; ordinary time.  Structure:
        :func:`parametric_block_structure` ``(n)``, one measurement, one control.
    """
    for name, sys in (("H_e", H_e), ("H_y", H_y)):
        check_siso(name, sys)
    effort_weight = check_positive("effort_weight", effort_weight)
    lft = parametric_lft(G, spread, input_name="u_b", output_name="v_y")
    n = len(lft.blk)
    ws = time_scale_of(lft.P, H_e, H_y)
    w_names = [f"w_{i}" for i in range(n)]
    z_names = [f"z_{i}" for i in range(n)]
    parts = [to_scaled(lft.P, ws),
             with_signals(to_scaled(H_e, ws), ["v_e"], ["y1"]),
             with_signals(to_scaled(H_y, ws), ["v_y"], ["y2"]),
             ct.ss([], [], [], [[effort_weight]], inputs="u_b", outputs="y_u"),
             ct.summing_junction(["v_r", "-v_y"], "v_e")]
    inputs = w_names + ["v_r", "u_b"]
    outputs = z_names + ["y1", "y2", "y_u", "v_e"]
    P = balance(ct.interconnect(parts, inputs=inputs, outputs=outputs))
    if not np.all(np.isfinite(P.A)):
        raise ValueError("the parametric design plant is not finite")
    return from_scaled(P, ws, inputs, outputs, name="P_par")
