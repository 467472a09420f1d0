import os

# headless, and every kernel nbval starts inherits these settings
os.environ.setdefault("MPLBACKEND", "Agg")
# one BLAS thread: on 2 shared cores threaded small solves run many times slower
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# interactive controls draw their static figure: no widget frontend in tests
os.environ.setdefault("PIEZOLIB_STATIC", "1")
