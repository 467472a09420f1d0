"""Figure functions of the workbook, one per paper figure, grouped by notebook.

Each function takes the computed results, draws one figure in the workbook
style (:mod:`piezolib.workbook.style`), saves it under the paper's figure
number and returns the ``matplotlib`` figure, so that notebooks hold the
narrative and one call per figure.
"""
