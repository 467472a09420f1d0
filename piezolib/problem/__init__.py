"""The paper's problem: its stage, its design problem and its analysis.

genplant   generalized plant of Fig. 9 / eq. 16
stage      virtual P-752.21 stage (the hardware stand-in) and its experiment files
design     the workbook's mu controller in one call
analysis   Table 3: NS, NP, RS, RP of any controller

The published numbers themselves live in :mod:`piezolib.paper`.
"""

__all__ = ["genplant", "stage", "design", "analysis"]
