"""Fixtures of the interactive controls' tests: the paper's problem, headless runs, widgets."""

import pytest

from piezolib import paper
from piezolib.workbook import interactive


@pytest.fixture(scope="module")
def problem():
    return paper.problem()


@pytest.fixture
def headless(monkeypatch):
    monkeypatch.setenv(interactive.STATIC_ENV, "1")


@pytest.fixture
def widgets():
    return pytest.importorskip("ipywidgets")
