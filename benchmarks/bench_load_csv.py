"""Speed and memory of records.load_csv against pandas.read_csv on one file (prints numbers).

    python benchmarks/bench_load_csv.py                  # about a minute
    python benchmarks/bench_load_csv.py --rows 200000 --repeats 5

Goal: load_csv reads 2e6 rows of three columns (time, input, output; a file of
about 60 MB with a header and two comment lines) in at most 2x the wall time and
at most 2x the peak memory of ``pandas.read_csv(path, comment="#")`` on the same
file.

How it measures.  Every read runs in a fresh Python process, which imports
numpy, pandas and piezolib.records, notes its peak resident set size
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``), times the read, and notes the
peak again; the difference is the memory the read itself needed at its peak.
A fresh process per read keeps one read's freed memory out of the next one's
figure, and subtracting the process's own baseline after the same imports is the
fair comparison: both sides import the same libraries (load_csv reads through
pandas), so what remains is the read.  (The peak is read inside the child, not
with RUSAGE_CHILDREN in this parent, which reports the largest of all children
waited for so far rather than the last one; tracemalloc would miss the C
parser's own buffers.)  Times and memory are the best and the median of
``--repeats`` runs, pandas and load_csv alternating.

The file is written to a temporary folder and deleted afterwards.  A last line
times load_csv on the same data with one comment line in the middle, which the
fast read declines: that is the line-by-line reader's speed (no goal).
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FS_HZ = 10_000.0
GOAL = 2.0

CHILD = r"""
import json, resource, sys, time
import numpy, pandas
from piezolib import records
which, path = sys.argv[1], sys.argv[2]
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
if which == "pandas":
    rows = len(pandas.read_csv(path, comment="#"))
elif which == "load_csv":
    rows = len(records.load_csv(path, time="t_s", input="u_V", output="y_um", header=True,
                                input_unit="V", output_unit="um"))
else:
    rows = 0
seconds = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
scale = 1 if sys.platform == "darwin" else 1024          # ru_maxrss: bytes on macOS, else kB
print(json.dumps({"rows": rows, "seconds": seconds, "baseline": before * scale,
                  "peak": peak * scale}))
"""


def write_record(path, rows):
    """A sine-driven record at 10 kHz: time [s], input [V], output [um], with a header."""
    k = np.arange(rows)
    t = k / FS_HZ
    u = 5.0 + 5.0 * np.sin(2 * np.pi * 3.0 * t)
    y = 1.5 * u + 1e-3 * np.random.default_rng(0).standard_normal(rows)
    header = f"# sample_rate_Hz = {FS_HZ:g}\n# experiment = bench_load_csv\nt_s,u_V,y_um"
    np.savetxt(path, np.column_stack([t, u, y]), fmt=["%.5f", "%.7f", "%.7f"],
               delimiter=",", header=header, comments="")


def with_comment_in_the_middle(path, target):
    data = path.read_bytes()
    middle = data.index(b"\n", len(data) // 2) + 1
    target.write_bytes(data[:middle] + b"# a note among the data\n" + data[middle:])


def measure(which, path):
    out = subprocess.run([sys.executable, "-c", CHILD, which, str(path)], cwd=ROOT,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def summary(runs):
    return {"seconds": min(r["seconds"] for r in runs),
            "memory": statistics.median(r["peak"] - r["baseline"] for r in runs),
            "baseline": statistics.median(r["baseline"] for r in runs),
            "rows": runs[0]["rows"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=2_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "record.csv"
        write_record(path, args.rows)
        print(f"file: {args.rows} rows, 3 columns, {path.stat().st_size / 1e6:.1f} MB")
        runs = {"pandas": [], "load_csv": []}
        for _ in range(args.repeats):
            for which in runs:
                runs[which].append(measure(which, path))
        result = {which: summary(r) for which, r in runs.items()}
        for which, label in (("pandas", 'pandas.read_csv(path, comment="#")'),
                             ("load_csv", "records.load_csv(path, time=..., header=True)")):
            r = result[which]
            print(f"{label:48s} {r['seconds']:6.2f} s  {r['memory'] / 2**20:7.1f} MiB peak "
                  f"above the import baseline ({r['baseline'] / 2**20:.0f} MiB), "
                  f"{r['rows']} rows")
        time_ratio = result["load_csv"]["seconds"] / result["pandas"]["seconds"]
        memory_ratio = result["load_csv"]["memory"] / result["pandas"]["memory"]
        met = time_ratio <= GOAL and memory_ratio <= GOAL
        print(f"load_csv / pandas: time {time_ratio:.2f}x, memory {memory_ratio:.2f}x; goal "
              f"(both <= {GOAL:g}x) {'met' if met else 'NOT met'}")
        slow = Path(folder) / "record_with_comment.csv"
        with_comment_in_the_middle(path, slow)
        r = summary([measure("load_csv", slow)])
        print(f"the same with a comment line among the data (line-by-line reader): "
              f"{r['seconds']:.2f} s, {r['memory'] / 2**20:.1f} MiB")


if __name__ == "__main__":
    main()
