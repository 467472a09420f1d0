"""Fixtures of the unit tests (environment settings: ../conftest.py)."""

import pytest


@pytest.fixture(autouse=True)
def _reference_study_outputs():
    """Every test starts and ends writing to the reference study's folders."""
    from piezolib.workbook import study

    yield
    study.use(study.REFERENCE)
