"""Robust-control toolkit: LTI helpers, LFTs, mu bounds, H-infinity and mu synthesis.

General tools for any plant; nothing here knows the paper.  Every model is
passed explicitly and every numerical scaling is chosen from the model given.

lti         time scaling, balancing, realisation, loop functions, norms
matrix_exponential  exp of a stack of matrices at once (the members of a model set)
lft         lower linear fractional transformation and its frequency response
blocks      uncertainty-block type ``Block`` and the MATLAB ``blk`` parser
hinf        verified H-infinity synthesis by gamma-iteration (``hinfsyn``)
hinf_central
            the central controller at one gamma and its Riccati solutions (hinf's)
sos         second-order-section magnitude model (shared by dfit and uncertainty)
dfit        stable minimum-phase fits of magnitude data (D-scalings)
dk          mu-synthesis by DK-iteration (``musyn``)
fixed_order
            fixed-order mu-synthesis of a SISO controller (``fixed_order_musyn``),
            complex blocks and real scalars (D,G-scaled bound)
dgk         mixed-mu synthesis of a SISO controller: DK start, then D,G-K steps (``mixed_musyn``)
reduction   (weighted) balanced controller reduction
discrete    Tustin discretisation with response checks
margins     gain, phase, delay and disk margins; sampled-loop delay tolerance
mimo_margins
            multi-loop and loop-at-a-time disk margins of a MIMO loop (``diskmargin``)
achievable  lower bounds on the achievable peak mu (H-infinity certificates)
performance_weights
            templates on S and T (``sensitivity_weight``,
            ``complementary_sensitivity_weight``)
export      second-order sections: JSON, C header, reference filter
mimo_export
            a MIMO controller in a well-conditioned state space, float32 checks, C header
preview     reference feedforward with preview: zero-phase-error tracking (``zpetc``)
float32_check
            what rounding the sections to float32 does (poles, response), refused or warned
mu/         the mu wing (:mod:`piezolib.robust.mu`): structured singular value bounds,
            entry point ``mussv`` (ssv), one module per bound (upper_complex,
            upper_mixed, lower), research refinements that ``mussv(refine=...)``
            reaches by option (refine/lifted, refine/branch)

Derivations and design notes: ``docs/robust.md``; one line per module:
``docs/architecture.md``.
"""

from piezolib.robust.lti import *          # noqa: F401,F403
from piezolib.robust.matrix_exponential import *   # noqa: F401,F403
from piezolib.robust.lft import *          # noqa: F401,F403
from piezolib.robust.blocks import *       # noqa: F401,F403
from piezolib.robust.mu import *           # noqa: F401,F403
from piezolib.robust.hinf import *         # noqa: F401,F403
from piezolib.robust.dfit import *         # noqa: F401,F403
from piezolib.robust.dk import *           # noqa: F401,F403
from piezolib.robust.fixed_order import *  # noqa: F401,F403
from piezolib.robust.dgk import *          # noqa: F401,F403
from piezolib.robust.reduction import *    # noqa: F401,F403
from piezolib.robust.discrete import *     # noqa: F401,F403
from piezolib.robust.margins import *      # noqa: F401,F403
from piezolib.robust.mimo_margins import *  # noqa: F401,F403
from piezolib.robust.mimo_export import *   # noqa: F401,F403
from piezolib.robust.achievable import *   # noqa: F401,F403
from piezolib.robust.performance_weights import *  # noqa: F401,F403
from piezolib.robust.export import *       # noqa: F401,F403
from piezolib.robust.preview import *      # noqa: F401,F403
from piezolib.robust import (achievable, blocks, dfit, dgk, discrete, dk, export, fixed_order,
                             hinf, lft, lti, margins, matrix_exponential, mu,
                             performance_weights, preview, reduction)
from piezolib.robust import mimo_export, mimo_margins

__all__ = (lti.__all__ + matrix_exponential.__all__ + lft.__all__ + blocks.__all__ + mu.__all__
           + hinf.__all__
           + dfit.__all__ + dk.__all__ + fixed_order.__all__ + dgk.__all__ + reduction.__all__
           + discrete.__all__ + margins.__all__ + achievable.__all__ + export.__all__
           + performance_weights.__all__ + preview.__all__
           + mimo_margins.__all__ + mimo_export.__all__)
