"""The workbook's speed as a new user meets it: `reproduce` and `pytest` from a fresh clone.

Clones the checkout's HEAD into a temporary folder (no disk cache, no compiled
caches: what a fresh clone has), then, in that clone with the current
environment:

* ``python -m piezolib reproduce --keep-going``: wall time, CPU time (user + system of
  every process it starts), each notebook's seconds as ``reproduce`` prints them (a failing
  notebook is reported and does not hide the others' times);
* with ``--per-notebook``: then each notebook alone (``reproduce NN --jobs 1``,
  in order, cache kept), its wall and CPU seconds — the CPU figure of one
  notebook is the fair measure on a loaded machine;
* with ``--pytest``: the default ``pytest`` (wall and CPU).

Goals (README): reproduce <= 60 s wall and <= 120 CPU-s on an idle 2-core machine,
every notebook <= 15 s; default pytest <= 3 minutes wall.  Slider latencies:
``benchmarks/bench_sliders.py``.  The load average is printed: numbers taken on
a loaded machine are not the idle machine's.

    python benchmarks/bench_workbook.py [--per-notebook] [--pytest] [--keep]
"""

import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GOALS = {"reproduce wall [s]": 60.0, "reproduce CPU [s]": 120.0, "notebook wall [s]": 15.0,
         "pytest wall [s]": 180.0}
LINE = re.compile(r"^\[\d+/\d+\] (\S+)\s+([\d.]+) s\s+(.*)$")


def children_cpu():
    """User + system seconds of the finished children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(argv, cwd, env):
    """(wall s, CPU s, stdout) of a command run to completion (a failure is reported and
    its time kept: the others' times still count)."""
    cpu, start = children_cpu(), time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode:
        print(f"{' '.join(argv[1:])} exited with {done.returncode}:\n{done.stdout[-1500:]}",
              file=sys.stderr)
    return wall, children_cpu() - cpu, done.stdout


def fresh_clone(folder):
    """A clone of HEAD in ``folder``/clone (the shared data beside it is not needed)."""
    clone = folder / "clone"
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
    return clone


def environment(clone, cache):
    """The user's environment, pointed at the clone's code and an empty disk cache."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PIEZOLIB_")}
    env.update(PYTHONPATH=str(clone), PIEZOLIB_CACHE=str(cache), PIEZOLIB_PROGRESS="0",
               NUMBA_CACHE_DIR=str(cache / "numba"))
    return env


def notebook_lines(stdout):
    """{name: (seconds, status)} from reproduce's progress lines."""
    found = {}
    for line in stdout.splitlines():
        match = LINE.match(line.strip())
        if match:
            found[match.group(1)] = (float(match.group(2)), match.group(3))
    return found


def verdict(value, goal):
    return "ok" if value <= goal else f"{value / goal:.1f}x the goal"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-notebook", action="store_true",
                        help="then time each notebook alone (wall and CPU)")
    parser.add_argument("--pytest", action="store_true", help="time the default pytest too")
    parser.add_argument("--keep", action="store_true", help="keep the temporary clone")
    args = parser.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="bench_workbook_"))
    try:
        clone = fresh_clone(folder)
        env = environment(clone, folder / "cache")
        print(f"fresh clone of {ROOT} in {clone}; load average {os.getloadavg()[0]:.2f} "
              f"on {os.cpu_count()} cores")
        wall, cpu, out = timed([sys.executable, "-m", "piezolib", "reproduce", "--keep-going"],
                               clone, env)
        lines = notebook_lines(out)
        print(f"\n{'step':<44s} {'wall [s]':>9s}")
        for name, (seconds, status) in lines.items():
            flag = "" if seconds <= GOALS["notebook wall [s]"] else "  > 15 s"
            print(f"{name:<44s} {seconds:9.1f}  {status[:30]}{flag}")
        print(f"\nreproduce: {wall:.1f} s wall ({verdict(wall, GOALS['reproduce wall [s]'])}), "
              f"{cpu:.1f} CPU-s ({verdict(cpu, GOALS['reproduce CPU [s]'])})")
        if args.per_notebook:
            print(f"\n{'notebook alone':<44s} {'wall [s]':>9s} {'CPU [s]':>9s}")
            total = 0.0
            for name in lines:
                if not name.endswith(".ipynb"):
                    continue
                w, c, _ = timed([sys.executable, "-m", "piezolib", "reproduce", name[:2],
                                 "--jobs", "1"], clone, env)
                total += c
                print(f"{name:<44s} {w:9.1f} {c:9.1f}")
            print(f"{'sum':<44s} {'':9s} {total:9.1f}")
        if args.pytest:
            w, c, out = timed([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"],
                              clone, env)
            summary = out.strip().splitlines()[-1] if out.strip() else ""
            print(f"\npytest: {w:.1f} s wall ({verdict(w, GOALS['pytest wall [s]'])}), "
                  f"{c:.1f} CPU-s; {summary}")
        print(f"load average at the end {os.getloadavg()[0]:.2f}")
    finally:
        if args.keep:
            print(f"kept {folder}")
        else:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
