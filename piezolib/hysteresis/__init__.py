"""Hysteresis models: Dahl (as printed and the workbook's variant), simulation, fit, feedforward."""

from piezolib.hysteresis.dahl import *     # noqa: F401,F403
from piezolib.hysteresis import dahl

__all__ = list(dahl.__all__)
