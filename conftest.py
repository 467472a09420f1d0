"""Settings for every test path of pyproject.toml: tests/, the notebooks (nbval) and the
doctests of piezolib/ (set here, at the root, so that each path run alone gets them too)."""

import os

# headless, and every kernel nbval starts inherits these settings
os.environ.setdefault("MPLBACKEND", "Agg")
# one BLAS thread: on 2 shared cores threaded small solves run many times slower
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# interactive controls draw their static figure: no widget frontend in tests
os.environ.setdefault("PIEZOLIB_STATIC", "1")
