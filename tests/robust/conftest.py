"""Shared fixtures of the robust-toolkit tests: the paper's mu design, computed once, and the
textbook problems more than one test module uses."""

import pytest

import textbook_problems as tp
from piezolib import paper, robust
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


@pytest.fixture(scope="module")
def column():
    """The book's distillation column (textbook_problems.distillation_column)."""
    return tp.distillation_column()


@pytest.fixture(scope="module")
def lundstrom_plant(column):
    """The book's K-step with Lundstrom's mu-optimal scaling d_opt on both input blocks."""
    d = tp.lundstrom_scaling()
    return robust.dk.scaled_plant(column.P, tp.BLK_RP, [d, d], 2, 2)
