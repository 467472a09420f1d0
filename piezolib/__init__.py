"""piezolib: the library behind the piezo-mu workbook.

A reproduction of Ahmad, Ali and Ko, "Robust mu-synthesis with Dahl model
based feedforward compensator design for piezo-actuated micropositioning
stage" (IEEE Access 8, 2020).  One module per concern:

paper      published numbers and models (the single source of published truth)
signals    reference and excitation signals at the 10 kHz DAQ rate
hysteresis Dahl model, fit and inverse-free feedforward (eq. 10-14)
metrics    hysteresis % (eq. 25-26) and tracking error
stage      virtual P-752.21 stage, amplifier, sensor and DAQ; experiment files
identification  RLS (eq. 1-3), ARX at 10 kHz, d2c, 6-pole/3-zero model, validation
uncertainty  729-model set, E_m (eq. 7), weight coverage and fit, exact parametric margin
robust     closed-loop functions, norms, time scaling and balancing
mu         structured singular value bounds (mussv)
genplant   generalized plant of Fig. 9 (eq. 16), lower LFT and M (eq. 17-18)
hinf       dependable H-infinity synthesis (bounded, verified gamma-iteration)
dfit       stable minimum-phase fits of D-scalings
dk         mu-synthesis by DK-iteration (musyn)
reduction  controller reduction by (weighted) balanced truncation
discretize Tustin discretisation at 10 kHz with response checks
analysis   Table 3: NS, NP, RS, RP of any controller
design     the workbook's mu controller in one call (design_controller)
loop       the 10 kHz loop of Fig. 1 on the virtual stage; Cases I-III, Tables 4-5
report     paper-versus-reproduced comparison tables
plotting   the workbook's figure style and figure saving
reproduce  headless run of the whole workbook (python -m piezolib reproduce)
"""

from . import hysteresis, metrics, mu, paper, plotting, report, robust, signals
from . import identification
from . import uncertainty
from . import analysis, design, dfit, discretize, dk, genplant, hinf, reduction
from . import loop

# stage is imported on first use (PEP 562) so that `python -m piezolib.stage`
# runs it without a double-import warning from runpy
def __getattr__(name):
    if name == "stage":
        import importlib
        return importlib.import_module(".stage", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["hysteresis", "metrics", "mu", "paper", "plotting", "report", "robust", "signals",
           "stage", "identification", "analysis", "design", "dfit", "discretize", "dk",
           "genplant", "hinf", "reduction", "uncertainty", "loop"]
__version__ = "0.1.0"
