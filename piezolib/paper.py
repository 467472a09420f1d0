"""The paper's published numbers, at their old address: :mod:`piezolib.problem.paper`.

``import piezolib.paper`` and ``from piezolib import paper`` give that very
module object (not a copy of its names), so attributes, private names and
monkeypatching behave the same through either name.
"""

import sys

from piezolib.problem import paper

# the import system binds the name to whatever sys.modules holds once this file has run
sys.modules[__name__] = paper
