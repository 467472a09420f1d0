"""The bad-input sweeps' shared part: one pytest parameter per (function, argument, bad value).

``tests/test_bad_input.py`` (the toolkit) and ``tests/test_bad_input_layers.py`` (the problem
and workbook layers) each hold a table ``{name: (valid call, {argument: {kind: bad value}})}``.
"""

import pytest


def bad_calls(cases):
    """``pytest.param(name, valid, argument, value)`` for every bad value of every case,
    with the id ``name-argument-kind``."""
    for qualname, (valid, corrupt) in cases.items():
        for argument, values in corrupt.items():
            for kind, value in values.items():
                yield pytest.param(qualname, valid, argument, value,
                                   id=f"{qualname}-{argument}-{kind}")
