"""piezolib: the library behind the piezo-mu workbook, in three layers.

toolkit   general tools for any plant (never import the layers above them in this list):
          :mod:`~piezolib.robust` (with the mu wing :mod:`piezolib.robust.mu`),
          :mod:`~piezolib.identification`, :mod:`~piezolib.hysteresis`,
          :mod:`~piezolib.uncertainty`, :mod:`~piezolib.signals`,
          :mod:`~piezolib.metrics`, :mod:`~piezolib.records`,
          :mod:`~piezolib.files`, :mod:`~piezolib.progress` (and its notebook outputs,
          :mod:`~piezolib.notebook_display`) and the private ``_checks``
problem   the paper's numbers, stage and design problem: :mod:`piezolib.problem`
          (the published numbers in :mod:`piezolib.problem.paper`, also reachable
          as ``from piezolib import paper``)
workbook  what runs and presents the notebooks: :mod:`piezolib.workbook`
          (``python -m piezolib`` runs its command line)

Arrows point down only: workbook -> problem -> toolkit.  Submodules load on
first use, so ``import piezolib.robust`` pulls in neither the paper nor
matplotlib.  One line per module: ``docs/architecture.md``.
"""

import importlib

__all__ = ["robust", "identification", "hysteresis", "uncertainty", "signals", "metrics",
           "paper", "problem", "workbook"]
__version__ = "0.2.0"


#: names that are not subpackages of their own but live in a layer below
_ELSEWHERE = {"paper": "piezolib.problem.paper"}


def __getattr__(name):
    # PEP 562: load subpackages lazily
    if name in __all__:
        return importlib.import_module(_ELSEWHERE.get(name, f"{__name__}.{name}"))
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
