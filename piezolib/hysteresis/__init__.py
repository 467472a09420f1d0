"""Hysteresis models: Dahl (as printed and the workbook's variant), Prandtl-Ishlinskii, fits,
feedforwards and model choice by validation.

dahl         the Dahl model (eq. 10-13): exact stroke integration, simulation, and its
             inverse-free feedforward of eq. 14 on a record (:func:`feedforward`)
compensator  the same feedforward sample by sample for a real-time loop (:class:`DahlFeedforward`)
fit          least-squares Dahl fit to measured loops, and the rule that picks among fits
pi           Prandtl-Ishlinskii model: play operators, NNLS fit, exact inverse feedforward
preisach     Preisach operator of ramped relays: grid, bounded least-squares fit, inverse
hammerstein  a PI or Preisach operator followed by the stage's linear dynamics, fitted to raw records
common       the shared model protocol, parameter tables with confidence intervals, loop checks
select       validation on records not fitted, and the feedforward cross-check
measure      the hysteresis measure of eq. 25-26

Equations and design notes: ``docs/hysteresis.md``.  The paper's parameters
and the workbook's fit to the virtual stage are in
:mod:`piezolib.problem.hysteresis_fits`.
"""

from piezolib.hysteresis.dahl import *          # noqa: F401,F403
from piezolib.hysteresis.compensator import *   # noqa: F401,F403
from piezolib.hysteresis.common import *        # noqa: F401,F403
from piezolib.hysteresis.fit import *           # noqa: F401,F403
from piezolib.hysteresis.pi import *            # noqa: F401,F403
from piezolib.hysteresis.preisach import *      # noqa: F401,F403
from piezolib.hysteresis.hammerstein import *   # noqa: F401,F403
from piezolib.hysteresis.measure import *       # noqa: F401,F403
from piezolib.hysteresis.select import *        # noqa: F401,F403
from piezolib.hysteresis import (common, compensator, dahl, fit, hammerstein, measure, pi,
                                 preisach, select)

__all__ = list(dict.fromkeys([*dahl.__all__, *compensator.__all__, *common.__all__,
                              *fit.__all__, *pi.__all__, *preisach.__all__, *hammerstein.__all__, *measure.__all__, *select.__all__]))
