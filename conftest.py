"""Settings for every test path of pyproject.toml: tests/, the notebooks (nbval) and the
doctests of piezolib/ (set here, at the root, so that each path run alone gets them too)."""

import os

# headless, and every kernel nbval starts inherits these settings
os.environ.setdefault("MPLBACKEND", "Agg")
# one BLAS thread: on 2 shared cores threaded small solves run many times slower
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# (no PIEZOLIB_STATIC: kernels run by nbval, as by any headless client, name no cell in their
# requests, so the interactive controls draw their static figure by themselves)
