"""Time and peak memory of the sized calls at (or near) their stated limits (prints numbers).

    python benchmarks/bench_size_limits.py          # about a minute on a 2-core machine

The toolkit refuses a size past a stated maximum before any work
(``identification.freqfit.MAX_ROWS``, ``uncertainty.sampled.MAX_MEMBERS`` and
``MAX_DELAY_SAMPLES``, ``hysteresis.pi.MAX_PLAYS``).  This script runs each call at a size at the limit (or a
stated fraction of it, where the full size would take long, scaled up in the line) in a
fresh process and prints its wall time and the growth of the process's peak resident set
size, so that the limits' docstrings can be checked against this machine.

``MAX_ROWS`` went from 100 to 168 so that notebook 10's order validation curve of the mirror's
3 x 3 BLA (3839 lines) could reach past its best orders (64 / 88 / 92): on that data, one
process on a shared 2-core machine, a fit with n_rows = order + 8 took 2.7-3.0 CPU-s and
+450 MiB at 100 rows, 3.5-4.3 CPU-s and +610 MiB at 136 rows, 4.5-6.1 CPU-s and +750 MiB at
168 rows: the memory grows as n_rows (the block-Hankel matrix is n_rows (n_y + n_u) by
2 F n_u, with a few copies), the QR's time as n_rows squared.
"""

import json
import subprocess
import sys

CASES = {
    "fit_frf, n_rows = MAX_ROWS (168), 3 x 3 FRF on 2000 lines, order 8": """
import numpy as np
from piezolib import identification as ident
rng = np.random.default_rng(0)
f = np.linspace(1.0, 2000.0, 2000); fs = 6400.0
G = rng.standard_normal((3, 3, f.size)) + 1j * rng.standard_normal((3, 3, f.size))
from piezolib.identification.freqfit import MAX_ROWS
run = lambda: ident.fit_frf(G, f, fs, 8, n_rows=MAX_ROWS, iterations=1)
""",
    # the size notebook 10's order curve reaches: the mirror's 3 x 3 BLA on 3839 lines
    "fit_frf, order MAX_ROWS - 8 (160, n_rows = order + 8), 3 x 3 FRF on 3839 lines": """
import numpy as np
from piezolib import identification as ident
rng = np.random.default_rng(0)
f = np.linspace(1.0, 3000.0, 3839); fs = 6400.0
G = rng.standard_normal((3, 3, f.size)) + 1j * rng.standard_normal((3, 3, f.size))
from piezolib.identification.freqfit import MAX_ROWS
run = lambda: ident.fit_frf(G, f, fs, MAX_ROWS - 8)
""",
    "random_model_set, count = MAX_MEMBERS (1e6), 3rd-order plant": """
import control as ct
from piezolib import uncertainty as unc
from piezolib.uncertainty.sampled import MAX_MEMBERS
run = lambda: unc.random_model_set(ct.tf([1.0], [1.0, 3.0, 3.0, 1.0]), 0.05, MAX_MEMBERS)
""",
    "sampled_loop_poles, delay_samples = MAX_DELAY_SAMPLES (100), 2 members": """
import control as ct
from piezolib import uncertainty as unc
from piezolib.uncertainty.sampled import MAX_DELAY_SAMPLES
mset = unc.random_model_set(ct.tf([1.0], [1.0, 3.0, 3.0, 1.0]), 0.05, 2)
K = ct.tf([0.1], [1.0], 1e-3)
run = lambda: unc.sampled_loop_poles(mset, K, 1e-3, delay_samples=MAX_DELAY_SAMPLES)
""",
    "fit_pi, n_plays = MAX_PLAYS (100), one 20,000-sample loop": """
import numpy as np
from piezolib.hysteresis import fit_pi
from piezolib.hysteresis.pi import MAX_PLAYS
t = np.linspace(0.0, 4.0, 20_000)
v = 4.0 * np.abs(np.sin(np.pi * t)); x = v + 0.1 * np.sign(np.gradient(v))
run = lambda: fit_pi((v, x), n_plays=MAX_PLAYS)
""",
}

CHILD = """
import json, resource, time, warnings
warnings.simplefilter("ignore")
{setup}
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
try:
    run(); outcome = "ran"
except Exception as exc:
    outcome = f"{{type(exc).__name__}}: {{str(exc)[:80]}}"
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({{"s": seconds, "MiB": (peak - before) / 1024, "outcome": outcome}}))
"""


def main():
    for label, setup in CASES.items():
        out = subprocess.run([sys.executable, "-c", CHILD.format(setup=setup)],
                             capture_output=True, text=True, check=False)
        try:
            r = json.loads(out.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            print(f"{label}: failed\n{out.stderr[-400:]}")
            continue
        print(f"{label}: {r['s']:.2f} s, +{r['MiB']:.0f} MiB peak ({r['outcome']})")


if __name__ == "__main__":
    main()
