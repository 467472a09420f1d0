"""Research refinements of mu's upper bound, reached through ``mussv(refine=...)`` only.

They tighten the upper bound at the frequencies where the plain bounds leave a
wide gap, at a far higher cost (``benchmarks/README.md``); no notebook needs
them, so they are kept apart from the bounds every ``mussv`` call computes.

lifted  complex structures: the symmetric-lift certificate (quadratic-form multipliers)
branch  1 x 1 real scalars: branch and bound over the box of real parameters
"""

__all__ = []
