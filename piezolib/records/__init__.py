"""Measured experiments: a record type, a strict CSV loader and helpers.

A :class:`Record` is one sampled experiment of a single-input single-output
device: the input (e.g. an amplifier or actuator voltage) and the output
(e.g. a displacement) at a constant sampling rate, each with its unit, and a
metadata dict.  :func:`load_csv` reads one from a delimited text file of any
column layout, encoding and number format (pandas' C parser) and checks every
line; every error is a :class:`RecordError` naming the file and the line.
Helpers find the start-up of a raw record (rest, a voltage step, the
ringing after it, the virgin stroke: :func:`find_start_up`), cut a record at
the turning points of its input, optionally after that start-up
(:func:`cut_at_turning_points`), remove an offset or trend (:func:`detrend`),
lower its rate behind an anti-alias filter (:func:`decimate`) and split it for
validation (:func:`split`).

record       the record type :class:`Record` and :class:`RecordError`
reader       the strict CSV reader: :func:`read_table` and :func:`load_csv`, every error naming
             the file and the line
preparation  a record made ready for fitting: turning points, the start-up of a raw record,
             cutting, detrending, decimation, splitting

Writing files atomically and checking them against a manifest is
:mod:`piezolib.files`.

Examples
--------
A file of two sine periods at 1 kHz, no header (time, volts, micrometres):

>>> import tempfile
>>> from pathlib import Path
>>> import numpy as np
>>> folder = tempfile.TemporaryDirectory()
>>> path = Path(folder.name) / "loop.csv"
>>> t = np.arange(500) / 1000.0
>>> v = 5.0 + 5.0 * np.sin(2 * np.pi * 4.0 * t)
>>> np.savetxt(path, np.column_stack([t, v, 1.5 * v]), delimiter=",")
>>> rec = load_csv(path, time=0, input=1, output=2, input_unit="V", output_unit="um")
>>> rec.fs, len(rec)
(1000.0, 500)
>>> train, test = split(cut_at_turning_points(rec), 0.5)  # whole strokes, then halves
>>> len(train), len(test)
(188, 188)
>>> folder.cleanup()
"""

from piezolib.records.record import *        # noqa: F401,F403
from piezolib.records.reader import *        # noqa: F401,F403
from piezolib.records.preparation import *   # noqa: F401,F403
from piezolib.records import preparation, reader, record

__all__ = list(dict.fromkeys([*record.__all__, *reader.__all__, *preparation.__all__]))
