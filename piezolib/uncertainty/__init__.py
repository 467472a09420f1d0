"""Uncertainty tools: model sets, relative-error envelope, covering weight, parametric margin."""

from piezolib.uncertainty.core import *    # noqa: F401,F403
from piezolib.uncertainty import core

__all__ = list(core.__all__)
