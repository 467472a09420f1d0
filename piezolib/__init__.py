"""piezolib: the library behind the piezo-mu workbook.

A reproduction of Ahmad, Ali and Ko, "Robust mu-synthesis with Dahl model
based feedforward compensator design for piezo-actuated micropositioning
stage" (IEEE Access 8, 2020).  One module per concern:

paper      published numbers and models (the single source of published truth)
signals    reference and excitation signals at the 10 kHz DAQ rate
metrics    hysteresis % (eq. 25-26) and tracking error
robust     closed-loop functions, norms, mu analysis and synthesis
report     paper-versus-reproduced comparison tables
plotting   the workbook's figure style and figure saving
reproduce  headless run of the whole workbook (python -m piezolib reproduce)
"""

from . import metrics, paper, plotting, report, robust, signals

__all__ = ["metrics", "paper", "plotting", "report", "robust", "signals"]
__version__ = "0.1.0"
