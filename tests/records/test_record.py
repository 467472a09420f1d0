"""The record type (piezolib.records.record): its checks, a record from a time vector, a
segment with the right start time."""

import numpy as np
import pytest

from piezolib import records as R

FS = 5000.0


def test_record_checks_its_arrays():
    with pytest.raises(R.RecordError, match="equal lengths"):
        R.Record(np.zeros(5), np.zeros(4), FS)
    with pytest.raises(ValueError, match="output"):
        R.Record(np.zeros(5), [0, 1, np.nan, 0, 0], FS)
    with pytest.raises(R.RecordError, match="time sample 3"):
        R.Record.from_time([0, 1, 2, 2, 3], np.arange(5.0), np.arange(5.0))
    rec = R.Record.from_time(0.5 + np.arange(10) / FS, np.arange(10.0), np.arange(10.0))
    assert rec.fs == pytest.approx(FS) and rec.t0 == 0.5
    seg = rec.segment(4, 8)
    assert len(seg) == 4 and seg.t0 == pytest.approx(0.5 + 4 / FS)
