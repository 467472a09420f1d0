"""The workbook's mu controllers for a design problem, in one call (Sec. IV-B).

Synthesis plant (by default the delay-aware plant with a roll-off weight),
DK-iteration, G S-weighted reduction, fixed-order mu-synthesis started from
the reduced controller and Tustin discretisation; the chain, the delay model
and the role of the roll-off weight are described in ``docs/controller_design.md``.
"""

import logging
from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib.problem import paper
from piezolib._checks import check_integer, check_model, check_positive, check_type
from piezolib.problem.analysis import exact_margins_with_delay
from piezolib.problem.genplant import (DESIGN_BLOCK_STRUCTURE, DESIGN_DELAY_SAMPLES,
                                       DESIGN_EFFORT_WEIGHT, DESIGN_PADE_ORDER, DESIGN_ROLLOFF,
                                       check_models, delay_aware_plant, design_plant,
                                       parametric_block_structure, parametric_design_plant)
from piezolib.robust.discrete import DiscreteController, discretize
from piezolib.robust.dk import MusynResult, musyn
from piezolib.robust.fixed_order import FixedOrderResult, fixed_order_musyn
from piezolib.robust.lti import loop_functions, with_signals
from piezolib.robust.reduction import ReducedController, reduce_controller

__all__ = ["ControllerDesign", "design_controller", "DESIGN_GRID", "DESIGN_D_ORDER",
           "MIXED_GRID", "MIXED_PERFORMANCE_SCALES", "MixedDesign", "design_mixed_controller",
           "mixed_tradeoff", "tradeoff_table",
           "choose_mixed_design"]

logger = logging.getLogger(__name__)

#: Frequency grid [rad/s] of the D-steps (DK-iteration and fixed-order synthesis).
DESIGN_GRID = np.logspace(-2, 7, 300)
#: Order of the fitted D-scaling.
DESIGN_D_ORDER = 4


@dataclass(frozen=True)
class ControllerDesign:
    """Full-order, reduced and fixed-order mu controllers with how they were obtained.

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
        Discretisation check of ``K_reduced`` (response match below 1 kHz,
        sampled loop without computation delay).
    plant : control.StateSpace
        The synthesis plant.
    K_fixed : control.StateSpace or None
        Fixed-order mu controller of the requested order, started from
        ``K_reduced`` (None when not asked for).
    fixed_order : FixedOrderResult or None
        The fixed-order synthesis.
    K_fixed_discrete : control.StateSpace or None
        ``K_fixed`` discretised at ``fs``.
    fixed_discrete : DiscreteController or None
        Its discretisation check.
    fs : float
        Sampling rate [Hz] of the discrete controllers.
    delay_samples : int or None
        Computation delay [samples] the design plant models (None: the
        paper's problem with the effort regulariser).
    """

    K_full: ct.StateSpace
    K_reduced: ct.StateSpace
    K_discrete: ct.StateSpace
    musyn: MusynResult
    reduction: ReducedController
    discrete: DiscreteController
    plant: ct.StateSpace = field(repr=False)
    K_fixed: ct.StateSpace | None = None
    fixed_order: FixedOrderResult | None = field(default=None, repr=False)
    K_fixed_discrete: ct.StateSpace | None = None
    fixed_discrete: DiscreteController | None = field(default=None, repr=False)
    fs: float = paper.SAMPLING_FREQUENCY_HZ
    delay_samples: int | None = DESIGN_DELAY_SAMPLES

    @property
    def K_deployed(self):
        """The controller to implement: ``K_fixed`` if designed, else ``K_reduced``."""
        return self.K_reduced if self.K_fixed is None else self.K_fixed

    @property
    def K_deployed_discrete(self):
        """``K_deployed`` discretised at ``fs``."""
        return self.K_discrete if self.K_fixed is None else self.K_fixed_discrete


def design_controller(G, H_m, H_e, H_y, *, order=6, d_order=DESIGN_D_ORDER, max_iter=8,
                      fs=paper.SAMPLING_FREQUENCY_HZ, delay_samples=DESIGN_DELAY_SAMPLES,
                      rolloff=DESIGN_ROLLOFF, pade_order=DESIGN_PADE_ORDER,
                      effort_weight=DESIGN_EFFORT_WEIGHT, fixed_order=True):
    """Design the mu controllers: DK-iteration, reduction to ``order``, fixed-order synthesis.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI
        Plant (u_c [V] -> v_y [V]) and weights, e.g. from :func:`piezolib.problem.paper.problem`.
    order : int
        Order of the reduced and fixed-order controllers (the paper's is 6).
    d_order : int or 'auto'
        Order of the fitted D-scaling of the DK-iteration.
    max_iter : int
        Maximum number of DK iterations.
    fs : float
        Sampling rate [Hz] of the real-time loop and of the discretised controllers.
    delay_samples : int or None
        Computation delay [samples] of the loop, modelled in the synthesis
        plant (:func:`~piezolib.problem.genplant.delay_aware_plant`, default
        1).  None designs for the paper's problem as printed
        (:func:`~piezolib.problem.genplant.design_plant`, no delay, effort
        output ``effort_weight`` u_b).
    rolloff : piezolib.problem.genplant.RolloffWeight
        Roll-off requirement on the controller gain (delay-aware plant only).
    pade_order : int
        Order of the Pade approximation of the loop delay.
    effort_weight : float
        rho > 0 of the effort output when ``delay_samples`` is None.
    fixed_order : bool
        Also run the fixed-order mu-synthesis from the reduced controller.

    Returns
    -------
    ControllerDesign

    Notes
    -----
    Deterministic; the DK-iteration and the fixed-order synthesis report their
    progress through :mod:`logging` (loggers ``piezolib.robust.dk`` and
    ``piezolib.robust.fixed_order``) at INFO level.
    """
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    order = check_integer("order", order, minimum=1)
    max_iter = check_integer("max_iter", max_iter, minimum=1)
    fs = check_positive("fs", fs)
    if not isinstance(fixed_order, bool):
        raise TypeError(f"fixed_order must be True or False, got {fixed_order!r}")
    if delay_samples is None:
        effort_weight = check_positive("effort_weight", effort_weight)
        P = design_plant(G, H_m, H_e, H_y, effort_weight=effort_weight)
        logger.info("DK-iteration on the %d-state synthesis plant (rho = %g)", P.nstates,
                    effort_weight)
    else:
        delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
        P = delay_aware_plant(G, H_m, H_e, H_y, fs=fs, delay_samples=delay_samples,
                              pade_order=pade_order, rolloff=rolloff)
        logger.info("DK-iteration on the %d-state delay-aware plant (%d sample(s) at %g Hz)",
                    P.nstates, delay_samples, fs)
    mu = musyn(P, DESIGN_BLOCK_STRUCTURE, 1, 1, DESIGN_GRID, d_order=d_order,
               max_iter=max_iter)
    K_full = with_signals(mu.K, ["v_e"], ["u_b"], name=f"K_mu{mu.K.nstates}")
    red = reduce_controller(K_full, order, loop_functions(G, K_full).GS, method="residualize")
    K_red = with_signals(red.K, ["v_e"], ["u_b"], name=f"K_mu{red.order}")
    disc = discretize(K_red, fs, G=G)
    extra = {}
    if fixed_order:
        logger.info("fixed-order mu-synthesis of order %d from the reduced controller", order)
        fo = fixed_order_musyn(P, DESIGN_BLOCK_STRUCTURE, K_red, DESIGN_GRID)
        K_fixed = with_signals(fo.K, ["v_e"], ["u_b"], name=f"K_fixed{order}")
        fixed_disc = discretize(K_fixed, fs, G=G)
        extra = dict(K_fixed=K_fixed, fixed_order=fo, K_fixed_discrete=fixed_disc.K,
                     fixed_discrete=fixed_disc)
    return ControllerDesign(K_full=K_full, K_reduced=K_red, K_discrete=disc.K, musyn=mu,
                            reduction=red, discrete=disc, plant=P, fs=fs,
                            delay_samples=delay_samples, **extra)


# --- mixed mu: the coefficient box as real blocks -------------------------------------

#: Grid [rad/s] of the mixed-mu design: sparse over nine decades, dense over G's modes
#: (1e3 ... 1e5 rad/s), where the real blocks give mu its narrow peaks.
MIXED_GRID = np.union1d(np.logspace(-2, 7, 60), np.logspace(3, 5, 160))
#: Performance levels of the trade-off designs: H_e and H_y times this factor.
MIXED_PERFORMANCE_SCALES = (0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.2, 1.5, 2.0)


@dataclass(frozen=True)
class MixedDesign:
    """A fixed-order mixed-mu controller for G's coefficient box, and its certificates.

    Attributes
    ----------
    K : control.StateSpace
        Controller v_e [V] -> u_b [V], ordinary time.
    performance_scale : float
        Factor on H_e and H_y in the design plant (1: the paper's weights).
    spread : float
        Relative size of the coefficient box designed for.
    mu_peak, mu_lower_peak : float
        Mixed mu_RP of the design plant (upper and lower bound) on the final grid.
    start_mu_peak : float
        The same for the starting controller.
    margins : dict
        {delay in samples: exact parametric margin of the continuous loop with the
        effective delay (d + 1/2) / fs} for the delays of
        :data:`~piezolib.problem.analysis.MARGIN_DELAYS`
        (:func:`~piezolib.problem.analysis.exact_margins_with_delay`); 0 when the
        nominal loop is unstable.
    steps : FixedOrderResult
        The D,G-K steps.
    """

    K: ct.StateSpace
    performance_scale: float
    spread: float
    mu_peak: float
    mu_lower_peak: float
    start_mu_peak: float
    margins: dict
    steps: FixedOrderResult = field(repr=False)


def design_mixed_controller(G, H_e, H_y, K0, *, performance_scale=1.0, spread=None,
                            fs=paper.SAMPLING_FREQUENCY_HZ, delay_samples=DESIGN_DELAY_SAMPLES,
                            rolloff=DESIGN_ROLLOFF, omega=None, dg_steps=25):
    """Mixed-mu synthesis for G's coefficient box on the delay-aware plant, from ``K0``.

    The plant is :func:`~piezolib.problem.genplant.parametric_design_plant`
    with H_e and H_y scaled by ``performance_scale``; the D,G-K steps
    (:func:`piezolib.robust.fixed_order.fixed_order_musyn` with six real
    blocks) keep K0's order.  mu_RP <= 1 then certifies the box of ``spread``
    (with the Pade-modelled delay) together with the scaled performance.

    Parameters
    ----------
    G, H_e, H_y : control.LTI
        Plant and weights (e.g. from :func:`piezolib.problem.paper.problem`).
    K0 : control.LTI
        Stable starting controller that stabilises the design plant.
    performance_scale : float
        Factor (> 0) on H_e and H_y.
    spread : float, optional
        Box size; default the paper's ``paper.UNCERTAINTY_SPREAD`` (0.05).
    fs : float
        Loop rate [Hz].
    delay_samples : int
        Computation delay [samples] of the design plant.
    rolloff : RolloffWeight
    omega : array_like, optional
        Design grid [rad/s]; default :data:`MIXED_GRID`.
    dg_steps : int
        Maximum D,G-K steps per grid.

    Returns
    -------
    MixedDesign
    """
    G, _, H_e, H_y = check_models(G, ct.tf([1.0], [1.0]), H_e, H_y)
    check_model("K0", K0, proper=True)
    dg_steps = check_integer("dg_steps", dg_steps, minimum=1)
    scale = check_positive("performance_scale", performance_scale)
    spread = paper.UNCERTAINTY_SPREAD if spread is None else check_positive("spread", spread)
    fs = check_positive("fs", fs)
    P = parametric_design_plant(G, scale * H_e, scale * H_y, spread, fs=fs,
                                delay_samples=delay_samples, rolloff=rolloff)
    blk = parametric_block_structure(len(P.input_labels) - 2)
    omega = MIXED_GRID if omega is None else omega
    steps = fixed_order_musyn(P, blk, K0, omega, max_iter=dg_steps)
    K = with_signals(steps.K, ["v_e"], ["u_b"], name=f"K_mixed{steps.K.nstates}")
    return MixedDesign(K=K, performance_scale=scale, spread=spread, mu_peak=steps.mu_peak,
                       mu_lower_peak=steps.mu_lower_peak, start_mu_peak=steps.start_mu_peak,
                       margins=exact_margins_with_delay(G, K, fs), steps=steps)


def mixed_tradeoff(G, H_e, H_y, K0, scales=MIXED_PERFORMANCE_SCALES, n_jobs=1, **options):
    """One :func:`design_mixed_controller` per performance scale, each started from ``K0``.

    The designs are independent; ``n_jobs`` > 1 runs them in that many
    processes (joblib), with the same results.

    Returns
    -------
    list of MixedDesign
        In the order of ``scales``.
    """
    from joblib import Parallel, delayed

    if isinstance(scales, str) or not hasattr(scales, "__len__") or len(scales) == 0:
        raise TypeError(f"scales must be a non-empty sequence of positive numbers, got {scales!r}")
    scales = [check_positive("scales", s) for s in scales]
    n_jobs = check_integer("n_jobs", n_jobs, minimum=1)
    return Parallel(n_jobs=n_jobs)(
        delayed(design_mixed_controller)(G, H_e, H_y, K0, performance_scale=s, **options)
        for s in scales)


def choose_mixed_design(designs, spread=None, design_delay=DESIGN_DELAY_SAMPLES):
    """The design with the largest performance scale that is certified for the box.

    Certified: the exact margin with the design delay is at least ``spread``
    and the nominal loop is stable with every checked delay.  None if no
    design qualifies.
    """
    spread = paper.UNCERTAINTY_SPREAD if spread is None else check_positive("spread", spread)
    designs = _check_designs(designs)
    ok = [d for d in designs
          if d.margins.get(design_delay, 0.0) >= spread and min(d.margins.values()) > 0]
    return max(ok, key=lambda d: d.performance_scale, default=None)


def tradeoff_table(designs, G, H_e, H_y, fs=paper.SAMPLING_FREQUENCY_HZ, *, bounds=None):
    """The trade-off of the mixed designs, recomputed from their controllers where it can be.

    One row per design (index: performance scale): mu_RP upper and lower bound
    and the start's mu_RP as the design reported them; the bound no
    controller can cross at that scale (the H-infinity optimum of the
    performance block, :func:`piezolib.robust.achievable.performance_lower_bound`);
    the exact margins [%] with the delays of
    :data:`~piezolib.problem.analysis.MARGIN_DELAYS`, recomputed from K.

    Parameters
    ----------
    designs : sequence of MixedDesign
    G, H_e, H_y : control.LTI
        The problem the designs were made for.
    fs : float
        Loop rate [Hz].
    bounds : dict, optional
        {performance scale: bound} already known (e.g. committed, see
        :func:`piezolib.problem.coefficient_box.tradeoff_bounds`); the other
        designs' bounds are computed.

    Returns
    -------
    pandas.DataFrame
    """
    import pandas as pd

    from piezolib.robust.achievable import performance_lower_bound

    designs = _check_designs(designs)
    G, _, H_e, H_y = check_models(G, ct.tf([1.0], [1.0]), H_e, H_y)
    fs = check_positive("fs", fs)
    bounds = {} if bounds is None else check_type("bounds", bounds, dict,
                                                  "a dict {performance scale: bound}")
    rows = []
    for d in designs:
        if d.performance_scale in bounds:
            value = check_positive("bounds", bounds[d.performance_scale])
        else:
            P = parametric_design_plant(G, d.performance_scale * H_e,
                                        d.performance_scale * H_y, d.spread, fs=fs)
            value = performance_lower_bound(P, 1, 1, ["y1", "y2", "y_u"], ["v_r"]).value
        rows.append({"performance scale": d.performance_scale, "mu_RP upper": d.mu_peak,
                     "mu_RP lower": d.mu_lower_peak, "no controller below": value,
                     "start: our deployed K": d.start_mu_peak,
                     **{f"exact margin, delay {k} [%]": 100 * m
                        for k, m in exact_margins_with_delay(G, d.K, fs).items()}})
    return pd.DataFrame(rows).set_index("performance scale")


def _check_designs(designs):
    """``designs`` as a list, checked to hold MixedDesign objects only."""
    if isinstance(designs, str) or not hasattr(designs, "__iter__"):
        raise TypeError(f"designs must be a sequence of MixedDesign, got {designs!r}"[:200])
    designs = list(designs)
    if not all(isinstance(d, MixedDesign) for d in designs):
        raise TypeError(f"designs must be a sequence of MixedDesign, got {designs!r}"[:200])
    return designs
