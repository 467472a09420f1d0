"""Hysteresis models: Dahl (as printed and the workbook's variant), simulation, fit, feedforward.

dahl         the model (eq. 10-13): exact stroke integration, simulation
compensator  the inverse-free feedforward of eq. 14 (:func:`feedforward`, :class:`DahlFeedforward`)
fit          least-squares fit to measured loops, and the rule that picks among fits
measure      the hysteresis measure of eq. 25-26

Equations and design notes: ``docs/hysteresis.md``.  The paper's parameters
and the workbook's fit to the virtual stage are in
:mod:`piezolib.problem.hysteresis`.
"""

from piezolib.hysteresis.dahl import *          # noqa: F401,F403
from piezolib.hysteresis.compensator import *   # noqa: F401,F403
from piezolib.hysteresis.fit import *           # noqa: F401,F403
from piezolib.hysteresis.measure import *       # noqa: F401,F403
from piezolib.hysteresis import compensator, dahl, fit, measure

__all__ = [*dahl.__all__, *compensator.__all__, *fit.__all__, *measure.__all__]
