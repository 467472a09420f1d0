"""The paper's problem: its published numbers, its stage, its design problem and its analysis.

paper            the published numbers, the units table, ``problem()`` -> G, H_m, H_e, H_y, K
genplant         generalized plant of Fig. 9 / eq. 16
stage            virtual P-752.21 stage (the hardware stand-in): one stage, one run
stage_batch      N virtual stages run at once (noise seeds, members of a model set)
stage_loop_kernel  their closed loop with a section controller, compiled (numba)
stage_hysteresis  the virtual stage's hysteresis truth (play operators)
stage_data       its experiment files (chirps, Table 4 Case I loops): definitions, CSV I/O
stage_calibration  the Table 4 Case I experiment and the hysteresis law calibrated on it
design           the workbook's mu controller in one call
analysis         Table 3: NS, NP, RS, RP of any controller
verification     independent checks of the mu designs (notebook 05), with ``checks`` dicts
hysteresis_fits  the paper's Dahl model and the workbook's Dahl fit to the Case I loops
dahl_audit       the published Dahl parameters audited (units, steady state, loops), with checks
hysteresis_choice  the Dahl candidates fitted to Case I and the one chosen; Dahl and PI models
                 compared on unseen records, with checks
weighting        notebook 04: templates of eq. 15, P against eq. 16, M against eq. 18, Fig. 11
fsm_benchmark    the CubeSpec fine steering mirror benchmark: data, metric, baselines
fsm_models       the benchmark's models step by step (BLAs, linear, nonlinear, scores), with checks
fsm_control      a mu controller for one mirror axis: nominal, design, verification, coupling
fsm_mimo         a 3 x 3 mu controller for the whole mirror, checked beside three SISO loops
fsm_causal       one causal model of the mirror for all levels (fixed-pole LPV basis), scored
paths            where the checkout and its ``data/`` folder are
foreign_hysteresis  raw records of Bouc-Wen, Preisach and Duhem hysteresis through a resonance,
                 and the best error a fit of them can reach
published_audit  notebook 00: the published design audited (units, poles, nominal loop, Tables 4-5)
stage_identification  notebook 01: the virtual stage's calibration and identification (Sec. III-A)
coefficient_set  notebook 02: the 729-model set, E_m, H_m's coverage, the exact margin of a loop
coefficient_box  notebook 09: the coefficient box as real blocks, margins per controller, the
                 chosen mixed-mu design checked, claims and summary lines
mixed_end_points  notebook 09: the committed end points of its searches (the trade-off's
                  H-inf bounds, the sampled-loop margin brackets), keyed by their inputs

:func:`piezolib.problem.paper.problem` returns the models G, H_m, H_e, H_y, K
that the other modules here take explicitly (plant first, then the weights);
``piezolib.paper`` is the same module under its old name.
"""

__all__ = ["paper", "genplant", "stage", "stage_batch", "stage_loop_kernel", "stage_calibration",
           "stage_hysteresis", "stage_data", "design", "analysis", "verification",
           "hysteresis_fits", "dahl_audit", "hysteresis_choice",
           "weighting", "fsm_benchmark", "paths",
           "fsm_models", "fsm_control", "fsm_causal", "fsm_mimo",
           "published_audit", "stage_identification", "coefficient_set", "coefficient_box",
           "mixed_end_points", "foreign_hysteresis"]
