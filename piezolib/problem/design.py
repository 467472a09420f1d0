"""The workbook's mu controller for the paper's problem, in one call (Sec. IV-B).

:func:`design_controller` runs the whole chain on the published G, H_m, H_e,
H_y:

1. the synthesis plant :func:`piezolib.problem.genplant.design_plant` (eq. 16 plus a
   control-effort output rho u_b, rho = 1e-3, because D12 = 2e-10);
2. DK-iteration :func:`piezolib.robust.dk.musyn` with 4th-order D-scalings on a
   300-point grid from 1e-2 to 1e7 rad/s;
3. reduction to ``order`` states (6 = the paper's order) by frequency-weighted
   balanced residualisation with the weight G S of the full-order loop
   (:func:`piezolib.robust.reduction.reduce_controller`): ||(K - K_r) G S||_inf < 1
   guarantees that the reduced loop is stable, and residualisation keeps the
   DC gain, i.e. the tracking accuracy at low frequency;
4. Tustin discretisation at 10 kHz with pre-warping at the controller's
   sharpest feature (:func:`piezolib.discretize.discretize`).

Everything is deterministic; with the published models the result is cached,
so later notebooks (e.g. the tracking experiments) get the same controller
at no cost.

The effort weight is a regularisation, not part of the paper's problem, and
nothing else in eq. 16 penalises the controller's gain above the loop
bandwidth (H_m, the only weight on u_b, falls to 2e-10 there).  The
controller's gain therefore levels off above 3e4 rad/s where rho |K| becomes
a fraction of the mu level: about 320 V/V for rho = 1e-3, 63 for 1e-2, 6 for
0.1 (the published K rolls off, peak 12).  rho = 1e-3 costs nothing in mu
but amplifies sensor noise near the Nyquist frequency of the 10 kHz loop;
``effort_weight=0.1`` bounds that gain for +0.02 in mu (notebook 05
tabulates the trade-off).
"""

import functools
from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib import paper
from piezolib._checks import check_integer, check_positive
from piezolib.robust.discrete import DiscreteController, discretize
from piezolib.robust.dk import MusynResult, musyn
from piezolib.problem.genplant import DESIGN_BLOCK_STRUCTURE, DESIGN_EFFORT_WEIGHT, design_plant
from piezolib.robust.reduction import ReducedController, reduce_controller
from piezolib.robust.lti import loop_functions

__all__ = ["ControllerDesign", "design_controller", "DESIGN_GRID", "DESIGN_D_ORDER"]

#: Frequency grid [rad/s] of the D-steps.
DESIGN_GRID = np.logspace(-2, 7, 300)
#: Order of the fitted D-scaling.
DESIGN_D_ORDER = 4


@dataclass(frozen=True)
class ControllerDesign:
    """Full-order and reduced mu controllers with how they were obtained.

    Attributes
    ----------
    K_full : control.StateSpace
        DK-iteration controller (v_e -> u_b), ordinary time.
    K_reduced : control.StateSpace
        Reduced controller of the requested order.
    K_discrete : control.StateSpace
        ``K_reduced`` discretised at 10 kHz (Tustin, pre-warped).
    musyn : MusynResult
        The DK-iteration, with its per-iteration history.
    reduction : ReducedController
        Hankel singular values and errors of the reduction.
    discrete : DiscreteController
        Discretisation check (response match below 1 kHz, sampled loop).
    plant : control.StateSpace
        The synthesis plant.
    """

    K_full: ct.StateSpace
    K_reduced: ct.StateSpace
    K_discrete: ct.StateSpace
    musyn: MusynResult
    reduction: ReducedController
    discrete: DiscreteController
    plant: ct.StateSpace = field(repr=False)


def _design(order, d_order, max_iter, effort_weight, verbose, G, H_m, H_e, H_y):
    P = design_plant(G, H_m, H_e, H_y, effort_weight=effort_weight)
    mu = musyn(P, DESIGN_BLOCK_STRUCTURE, 1, 1, DESIGN_GRID, d_order=d_order,
               max_iter=max_iter, verbose=verbose)
    K_full = ct.ss(mu.K.A, mu.K.B, mu.K.C, mu.K.D, inputs="v_e", outputs="u_b",
                   name=f"K_mu{mu.K.nstates}")
    G_ = paper.plant() if G is None else G
    weight = loop_functions(G_, K_full).GS
    red = reduce_controller(K_full, order, weight, method="residualize")
    K_red = ct.ss(red.K.A, red.K.B, red.K.C, red.K.D, inputs="v_e", outputs="u_b",
                  name=f"K_mu{red.order}")
    disc = discretize(K_red, G=G_)
    return ControllerDesign(K_full=K_full, K_reduced=K_red, K_discrete=disc.K, musyn=mu,
                            reduction=red, discrete=disc, plant=P)


@functools.lru_cache(maxsize=8)
def _cached_design(order, d_order, max_iter, effort_weight):
    return _design(order, d_order, max_iter, effort_weight, False, None, None, None, None)


def design_controller(order=6, *, d_order=DESIGN_D_ORDER, max_iter=8,
                      effort_weight=DESIGN_EFFORT_WEIGHT, verbose=False,
                      G=None, H_m=None, H_e=None, H_y=None):
    """Design the mu controller by DK-iteration and reduce it to ``order`` states.

    Parameters
    ----------
    order : int
        Order of the reduced controller (the paper's is 6).
    d_order : int or 'auto'
        Order of the fitted D-scaling.
    max_iter : int
        Maximum number of DK iterations.
    effort_weight : float
        rho of the control-effort output rho u_b (see module docstring).
    verbose : bool
        Print the DK-iteration progress (one line per iteration); a verbose
        call always recomputes.
    G, H_m, H_e, H_y : control.LTI, optional
        Plant and weights; default the published models (then the result is
        cached).

    Returns
    -------
    ControllerDesign
    """
    order = check_integer("order", order, minimum=1)
    max_iter = check_integer("max_iter", max_iter, minimum=1)
    effort_weight = check_positive("effort_weight", effort_weight)
    if verbose or any(x is not None for x in (G, H_m, H_e, H_y)):
        return _design(order, d_order, max_iter, effort_weight, verbose, G, H_m, H_e, H_y)
    return _cached_design(order, d_order, max_iter, effort_weight)
