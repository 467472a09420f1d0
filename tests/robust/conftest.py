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
