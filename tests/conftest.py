import os

# headless, and every kernel nbval starts inherits it
os.environ.setdefault("MPLBACKEND", "Agg")
