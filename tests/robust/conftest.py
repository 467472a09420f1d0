"""Shared fixture of the robust-toolkit tests: the paper's mu design, computed once."""

import pytest

from piezolib import paper
from piezolib.problem import design


@pytest.fixture(scope="session")
def paper_models():
    """G, H_m, H_e, H_y of the paper's design problem."""
    return tuple(paper.problem()[:4])


@pytest.fixture(scope="session")
def paper_design(paper_models):
    """The one-call mu design of the paper's problem as printed (no delay), no fixed order."""
    return design.design_controller(*paper_models, delay_samples=None, fixed_order=False)


class SlowClock:
    """Stands in for the ``time`` module: every reading is 1000 s after the last one."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self):
        self.now += 1000.0
        return self.now


@pytest.fixture
def slow_clock():
    """A clock on which every step seems to take 1000 s (results must not depend on it)."""
    return SlowClock()
