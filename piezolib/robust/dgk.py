"""Mixed-mu synthesis (real scalars and complex blocks) by D,G-K steps: :func:`mixed_musyn`.

Real scalar uncertainties (a parameter q in [-1, 1]) are certified by the D,G
upper bound of mixed mu, much less conservatively than by complex discs.  The
synthesis here has two phases:

1. a start: DK-iteration (:func:`~piezolib.robust.dk.musyn`) with every real
   scalar taken as a complex 1 x 1 block, optionally reduced to ``order``;
2. D,G-K steps on the controller's parameters
   (:func:`~piezolib.robust.fixed_order.fixed_order_musyn` with the real
   blocks): each D,G-step takes the optimal scalings of the mixed bound at
   every frequency, each K-step lowers the D,G-scaled bound with those
   scalings fixed, and a step is kept only when the mixed upper bound,
   recomputed, has dropped.

The scalings are used frequency by frequency, never fitted: a fitted
G-scaling would have to be a causal transfer function whose frequency
response is imaginary, which cannot hold over a band (its real and imaginary
parts are Hilbert transforms of each other).  Why this was chosen over a
full-order D,G-K iteration with fitted scalings is in ``docs/robust.md``.
The controller is SISO (the parametrisation of the fixed-order steps).
"""

import inspect
import time
from dataclasses import dataclass, field

import control as ct
import numpy as np

from piezolib._checks import check_channels, check_frequency_grid, check_integer, check_model
from piezolib.robust.blocks import Block, parse_blk
from piezolib.robust.dk import MusynResult, musyn
from piezolib.robust.fixed_order import FixedOrderResult, fixed_order_musyn
from piezolib.robust.lft import lft_response
from piezolib.robust.mu import MuResult, mussv
from piezolib.robust.reduction import reduce_controller

__all__ = ["MixedMusynResult", "mixed_musyn"]


@dataclass(frozen=True)
class MixedMusynResult:
    """Outcome of :func:`mixed_musyn`.

    Attributes
    ----------
    K : control.StateSpace
        The controller (ordinary time), SISO.
    mu_peak, mu_lower_peak : float
        Peaks of the mixed upper and lower bounds for ``K`` on the final grid.
    start_mu_peak : float
        Peak of the mixed upper bound for the starting controller (after the
        complex DK-iteration and the reduction).
    complex_dk : MusynResult or None
        The complex DK-iteration of the start (its ``mu_peak`` is complex mu);
        None when the steps started from a given ``K0``.
    dg_steps : FixedOrderResult
        The D,G-K steps (their ``history`` has the mixed bound of every step).
    verified_peak, verified_lower_peak : float
        Peaks of the mixed bounds on ``omega_verify``, a grid four times as
        dense as the final one.
    omega_verify : ndarray
    mu : MuResult
        Mixed bounds of ``K`` on ``omega_verify``.
    elapsed : float
        Wall time [s] (information only).
    """

    K: ct.StateSpace
    mu_peak: float
    mu_lower_peak: float
    start_mu_peak: float
    complex_dk: MusynResult | None = field(repr=False)
    dg_steps: FixedOrderResult = field(repr=False)
    verified_peak: float
    verified_lower_peak: float
    omega_verify: np.ndarray = field(repr=False)
    mu: MuResult = field(repr=False)
    elapsed: float

    @property
    def history(self):
        """The D,G-K steps as a pandas.DataFrame (mixed upper bound after each step)."""
        return self.dg_steps.history


def _as_complex(blocks):
    """The same channels with every real scalar taken as a complex 1 x 1 full block."""
    return tuple(b if b.is_full else Block.full(1, 1) for b in blocks)


def _check_dk_options(dk_options):
    """Extra keyword arguments of :func:`piezolib.robust.musyn` (a dict naming its options)."""
    if dk_options is None:
        return {}
    if not isinstance(dk_options, dict):
        raise TypeError(f"dk_options must be a dict of keyword arguments of musyn, got "
                        f"{type(dk_options).__name__}")
    taken = {"P", "blk", "nmeas", "ncon", "omega", "d_order", "max_iter"}
    known = set(inspect.signature(musyn).parameters) - taken
    unknown = sorted(str(k) for k in dk_options if k not in known)
    if unknown:
        raise ValueError(f"dk_options: {unknown} are not options of musyn (it takes "
                         f"{sorted(known)})")
    return dk_options


def mixed_musyn(P, blk, omega, *, K0=None, order=None, d_order=4, dk_iterations=8,
                dg_steps=20, refinements=2, dk_options=None):
    """Mixed-mu synthesis of a SISO controller: complex DK start, then D,G-K steps.

    Parameters
    ----------
    P : control.StateSpace
        Generalized plant, ordinary time: uncertainty/performance inputs then
        the control; uncertainty/performance outputs then the measurement.
    blk : sequence of (int, int) or of Block
        ``mussv`` convention: (-1, 0) a real scalar in [-1, 1], (r, c) a
        complex full block; the last block must be complex full (its scale is
        fixed to 1 in the DK start).
    omega : array_like
        Frequency grid [rad/s] of both phases (at least 16 points).
    K0 : control.LTI, optional
        Start the D,G-K steps from this stable controller, stabilising P,
        instead of the complex DK-iteration.
    order : int, optional
        Reduce the DK controller to this order (balanced truncation of the
        stable part, residualised) before the D,G-K steps; default: keep it.
    d_order : int
        Order of the D-scalings of the DK start.
    dk_iterations : int
        Maximum DK iterations of the start.
    dg_steps : int
        Maximum D,G-K steps per grid (see ``max_iter`` of
        :func:`~piezolib.robust.fixed_order.fixed_order_musyn`).
    refinements : int
        Grid refinements of the D,G-K steps.
    dk_options : dict, optional
        Further keyword arguments of :func:`~piezolib.robust.dk.musyn`.

    Returns
    -------
    MixedMusynResult

    Raises
    ------
    ValueError, TypeError
        A structure not fitting P, with repeated scalars or without a final
        complex full block; more than one measurement or control; bad options.
    """
    t0 = time.perf_counter()
    check_model("P", P, proper=True)
    P = ct.ss(P)
    check_channels(P, 1, 1)
    blocks = parse_blk(blk, P.noutputs - 1, P.ninputs - 1)
    for b in blocks:
        if not b.is_full and b.size > 1:
            raise ValueError(f"blk: repeated scalar {b.blk_row} is not supported; write a "
                             "repeated real parameter as independent (-1, 0) blocks")
    if not blocks[-1].is_full:
        raise ValueError("blk: the last block must be a complex full block (performance)")
    omega = check_frequency_grid("omega", omega, min_length=16)
    if order is not None:
        order = check_integer("order", order, minimum=1)
    dk_iterations = check_integer("dk_iterations", dk_iterations, minimum=1)
    dg_steps = check_integer("dg_steps", dg_steps, minimum=1)
    refinements = check_integer("refinements", refinements, minimum=0)
    dk_options = _check_dk_options(dk_options)
    dk = None
    if K0 is None:
        dk = musyn(P, _as_complex(blocks), 1, 1, omega, d_order=d_order,
                   max_iter=dk_iterations, **(dk_options or {}))
        K0 = dk.K
    else:
        check_model("K0", K0, proper=True)
    if order is not None and order < K0.nstates:
        K0 = reduce_controller(K0, order, method="residualize").K
    steps = fixed_order_musyn(P, blocks, K0, omega, max_iter=dg_steps, refinements=refinements)
    dense = np.geomspace(steps.omega[0], steps.omega[-1], 4 * steps.omega.size)
    omega_v = np.union1d(dense, steps.omega)
    verified = mussv(lft_response(P, steps.K, omega_v), blocks, omega_v)
    return MixedMusynResult(
        K=steps.K, mu_peak=steps.mu_peak, mu_lower_peak=steps.mu_lower_peak,
        start_mu_peak=steps.start_mu_peak, complex_dk=dk, dg_steps=steps,
        verified_peak=float(verified.upper.max()),
        verified_lower_peak=float(verified.lower.max()), omega_verify=omega_v, mu=verified,
        elapsed=time.perf_counter() - t0)
