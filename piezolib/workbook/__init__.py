"""What exists to run and present the notebooks.

study        studies: every choice of the pipeline in one serialisable object
pipeline     the pipeline's products, computed once per study and reused
design_run   the record of the design searches notebook 05 shows (committed: reference)
loop         the 10 kHz loop of Fig. 1 on the virtual stage
experiments  Cases I-III of Sec. V: the Table 4 and Table 5 experiments
report       paper-versus-reproduced comparison tables, the report's findings sections
document     the report as a document: notebook 07 executed and exported as HTML and PDF
tables       tables as a reader sees them: every number in one format, every text whole
two_dof      Case IV's reference feedforward: the dynamics inverse (ZPETC) ahead of the model's
set_tracking  Cases II-IV on every member of the 729-model set at once (notebook 12)
sweep        many studies at once, locally or on a dask cluster (``python -m piezolib sweep``)
style        the workbook's figure style: rcParams, named colours, the units rule
plotting     saving figures under the paper's numbering
figures      one function per paper figure, grouped by notebook
reproduce    headless run of the whole workbook (``python -m piezolib reproduce``)
warm_kernels  reproduce's kernels, forked from one process that has imported the workbook
cli          the command line (``python -m piezolib {reproduce,data}``)
outputs      where each study's outputs go
session      the one call that starts a notebook: study, claim table, figure style
interactive  the notebooks' interactive controls (one module per control) and their callbacks
feedforward_cases  notebook 03: the Dahl feedforward on the model, Case II, the cross-check
weighting_findings  notebook 04: the closing findings beyond the claim rows
tracking_setup  notebook 06: what Sec. V's runs use, the loop's margins, the mu_RP certificate
tracking_study  notebook 06: Sec. V's runs on one study, their checks, claims and findings
fsm_findings  notebook 10: the FSM benchmark's claim rows and closing findings
your_stage   notebook 08: a user's records to the plant model, one call per stage with its checks
your_stage_hysteresis  notebook 08: the loops, the hysteresis model chosen, the feedforward check
your_stage_control  notebook 08: the mu controller at the loop rate, its verification, experiments
your_stage_claims  notebook 08: the claim rows, every stage's and the known truth's checks
case_comparison  Cases I-III with several Case III controllers side by side (notebook 09)
sweep_spec   the sweep specs of ``sweep``: their TOML layout, checks and points
"""

__all__ = ["study", "pipeline", "loop", "experiments", "report", "style", "plotting", "figures",
           "reproduce", "cli", "outputs", "session", "interactive", "feedforward_cases",
           "weighting_findings", "tracking_setup", "tracking_study",
           "case_comparison", "fsm_findings", "your_stage",
           "your_stage_hysteresis", "your_stage_control", "your_stage_claims", "sweep_spec",
           "design_run", "warm_kernels"]
