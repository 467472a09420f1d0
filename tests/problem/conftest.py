"""Fixtures shared by the tests of the problem layer."""

import pytest

from piezolib import paper


@pytest.fixture(scope="module")
def models():
    """The paper's design problem: G, H_m, H_e, H_y and the published K."""
    return paper.problem()
