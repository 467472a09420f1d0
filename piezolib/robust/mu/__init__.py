"""The mu wing: structured singular value bounds, entry point :func:`mussv`.

Modules are named for what each bound is for:

ssv            the entry point: :func:`mussv` (both bounds at every frequency, with
               scalings and a worst-case Delta) and its result :class:`MuResult`
upper_complex  upper bound for complex structures by optimal D-scaling (eq. 22)
upper_mixed    upper bound with real blocks: D,G scaling (SLICOT AB13MD, then Newton)
lower          lower bounds by power iteration, with a Delta attaining them
refine/        research refinements that ``mussv(refine=...)`` reaches by option only:
               tighter upper bounds where the gap between the bounds is wide
  lifted       complex structures: the symmetric-lift certificate
  branch       real blocks: branch and bound over the real parameters
_common        private helpers the bound modules share (Newton steps, the D-balanced
               matrix, the certified D,G eigenvalue); nothing else imports them

Imports point one way: ssv -> refine -> upper_mixed -> upper_complex -> _common, and lower
and refine/lifted use _common only.
Derivations: ``docs/robust.md``; timings: ``benchmarks/README.md``.
"""

from piezolib.robust.mu.ssv import MuResult, mussv

__all__ = ["MuResult", "mussv"]
