"""Figure functions of the workbook, one per paper figure, grouped by notebook.

Each function takes the computed results, draws one figure in the workbook
style (:mod:`piezolib.workbook.style`), names it after the paper's figure
number (:func:`~piezolib.workbook.plotting.name_figure`) and returns the
``matplotlib`` figure, so that notebooks hold the
narrative and one call per figure.

block_diagram   the engine of the signal-flow block diagrams
diagrams        the paper's block diagrams: Fig. 1, 2, 3, 5 and 9 (notebooks 00-02)
audit           notebook 00: the published design at a glance, Fig. 10 and 11
identification  notebook 01: the virtual stage and the identification, Fig. 4 and 13
uncertainty     notebook 02: Fig. 6 and the exact parametric margin
hysteresis      notebook 03: Fig. 7, Fig. 8, the Dahl audit and Case II
weights         notebook 04: the weight templates and Fig. 11 of the designs
mu              notebook 05: D-scaling fit, Hankel values, delay-aware designs, Fig. 10, 12
tracking        notebook 06 and 12: Fig. 14 and 15, tracking over the set
loop_margins    notebook 06: Nyquist plots near -1 and the sampled loop against delay
scorecard       notebook 07: every published number against ours
own_stage       notebook 08: records, identification, weight, hysteresis, design, experiments
mixed_mu        notebook 09: mu against the coefficient box, the mixed-mu trade-off
real_benchmark  notebook 10: the fine steering mirror's BLA, scores and level weight
mirror_steps    notebook 10: the mirror's closed-loop step matrix, 3 x 3 mu beside 3 SISO loops
fsm_orders      notebook 10: the linear models' order validation curve per level
sweeps          notebook 11 and ``python -m piezolib sweep``: the Pareto front
"""
