"""Figure functions of the workbook, one per paper figure, grouped by notebook.

Each function takes the computed results, draws one figure in the workbook
style (:mod:`piezolib.workbook.style`), names it after the paper's figure
number (:func:`~piezolib.workbook.plotting.name_figure`) and returns the
``matplotlib`` figure, so that notebooks hold the
narrative and one call per figure.
"""
