"""What exists to run and present the notebooks.

loop       the 10 kHz loop of Fig. 1 on the virtual stage; Cases I-III, Tables 4-5
report     paper-versus-reproduced comparison tables
plotting   the workbook's figure style and figure saving
reproduce  headless run of the whole workbook (``python -m piezolib reproduce``)
paths      where the workbook reads its inputs and writes its outputs
"""

__all__ = ["loop", "report", "plotting", "reproduce", "paths"]
