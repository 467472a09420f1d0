"""Fixtures shared by the identification tests."""

from collections import namedtuple

import numpy as np
import pytest
import scipy.signal as sg

#: A known ARX system (coefficients of z^0, z^-1, ...) and ``data(n, seed) -> (u, y)``.
ArxSystem = namedtuple("ArxSystem", "a b data")


@pytest.fixture(scope="session")
def arx_system():
    """y[k] = -a1 y[k-1] - a2 y[k-2] - a3 y[k-3] + b1 u[k-1] + b2 u[k-2], stable,
    and noise-free data of it for a white-noise input."""
    a = np.array([1.0, -1.5, 0.7, -0.1])
    b = np.array([0.0, 0.5, 0.25])

    def data(n=2000, seed=0):
        u = np.random.default_rng(seed).standard_normal(n)
        return u, sg.lfilter(b, a, u)

    return ArxSystem(a, b, data)
