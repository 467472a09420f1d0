"""The workbook's mu controller for a design problem, in one call (Sec. IV-B).

Synthesis plant with an effort output, DK-iteration, G S-weighted reduction and
Tustin discretisation; the chain and the role of the effort weight rho are
described in ``docs/design.md``.
"""

import logging
from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib import paper
from piezolib._checks import check_integer, check_positive
from piezolib.problem.genplant import (DESIGN_BLOCK_STRUCTURE, DESIGN_EFFORT_WEIGHT, check_models,
                                       design_plant)
from piezolib.robust.discrete import DiscreteController, discretize
from piezolib.robust.dk import MusynResult, musyn
from piezolib.robust.lti import loop_functions, with_signals
from piezolib.robust.reduction import ReducedController, reduce_controller

__all__ = ["ControllerDesign", "design_controller", "DESIGN_GRID", "DESIGN_D_ORDER"]

logger = logging.getLogger(__name__)

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
        DK-iteration controller (v_e [V] -> u_b [V]), ordinary time.
    K_reduced : control.StateSpace
        Reduced controller of the requested order.
    K_discrete : control.StateSpace
        ``K_reduced`` discretised at ``fs`` (Tustin, pre-warped).
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


def design_controller(G, H_m, H_e, H_y, *, order=6, d_order=DESIGN_D_ORDER, max_iter=8,
                      effort_weight=DESIGN_EFFORT_WEIGHT, fs=paper.SAMPLING_FREQUENCY_HZ):
    """Design the mu controller by DK-iteration and reduce it to ``order`` states.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI
        Plant (u_c [V] -> v_y [V]) and weights, e.g. from :func:`piezolib.paper.problem`.
    order : int
        Order of the reduced controller (the paper's is 6).
    d_order : int or 'auto'
        Order of the fitted D-scaling.
    max_iter : int
        Maximum number of DK iterations.
    effort_weight : float
        rho > 0 of the control-effort output rho u_b (``docs/design.md``).
    fs : float
        Sampling rate [Hz] of the discretised controller (default: the paper's 10 kHz).

    Returns
    -------
    ControllerDesign

    Notes
    -----
    Deterministic; the DK-iteration reports its progress through :mod:`logging`
    (logger ``piezolib.robust.dk``), one line per iteration at INFO level.
    """
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    order = check_integer("order", order, minimum=1)
    max_iter = check_integer("max_iter", max_iter, minimum=1)
    effort_weight = check_positive("effort_weight", effort_weight)
    fs = check_positive("fs", fs)
    P = design_plant(G, H_m, H_e, H_y, effort_weight=effort_weight)
    logger.info("DK-iteration on the %d-state synthesis plant (rho = %g)", P.nstates,
                effort_weight)
    mu = musyn(P, DESIGN_BLOCK_STRUCTURE, 1, 1, DESIGN_GRID, d_order=d_order,
               max_iter=max_iter)
    K_full = with_signals(mu.K, ["v_e"], ["u_b"], name=f"K_mu{mu.K.nstates}")
    red = reduce_controller(K_full, order, loop_functions(G, K_full).GS, method="residualize")
    K_red = with_signals(red.K, ["v_e"], ["u_b"], name=f"K_mu{red.order}")
    disc = discretize(K_red, fs, G=G)
    return ControllerDesign(K_full=K_full, K_reduced=K_red, K_discrete=disc.K, musyn=mu,
                            reduction=red, discrete=disc, plant=P)
