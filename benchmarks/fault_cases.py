"""Fault cases of the sweep driver, rerun as a user meets them (prints what was lost).

Each case runs a real sweep (``piezolib.workbook.sweep.run_sweep``, local loky workers)
with a cheap evaluation in a temporary checkout, in a process of its own:

* kill -9 of the driver while its two workers compute: which of its processes are still
  running after 5 s, and whether a reader of the driver's output pipe gets its end;
* two sweeps of one spec at once: the second refuses (naming the first's pid), and a
  third one after the first was killed takes over its lock file;
* a full disk after the first point (a tmpfs mount; needs root): no computed point
  lost, the next run computes only the missing ones;
* a read-only output folder (a read-only mount; needs root): refused before the first
  evaluation;
* limits: a 320,000-point grid and ``[random] samples = 100000`` through
  ``python -m piezolib sweep --dry-run``: seconds to the error and the error line.

    python benchmarks/fault_cases.py            # all cases, about a minute
"""

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]


# --------------------------------------------------------------------------- the driver
def slow_evaluate(study, controller="fixed_order"):
    """Sleep ``PIEZOLIB_FAULT_SECONDS`` and give numbers (marks its start in a file)."""
    marks = Path(os.environ["PIEZOLIB_ROOT"]) / "started"
    marks.mkdir(exist_ok=True)
    (marks / f"{os.getpid()}-{study.weights.omega_e:g}").write_text("")
    time.sleep(float(os.environ.get("PIEZOLIB_FAULT_SECONDS", "60")))
    omega_e = study.weights.omega_e
    return {"mu_RP": omega_e / 1000, "controller_states": 6,
            "tracking_error_50Hz_percent": 5000 / omega_e}


def driver(spec_path, jobs):
    """Run the sweep of ``spec_path`` (the child process of each case)."""
    from piezolib.workbook import sweep, sweep_spec

    spec = sweep_spec.load_spec(spec_path)
    try:
        result = sweep.run_sweep(spec, jobs=int(jobs), evaluate=slow_evaluate,
                                 stream=sys.stderr)
    except Exception as exc:
        print(f"refused: {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        return 1
    print(json.dumps({"evaluated": result.evaluated, "reused": result.reused,
                      "problems": list(result.problems)}), flush=True)
    return 0


# --------------------------------------------------------------------------- helpers
def checkout(root):
    """A temporary checkout: the repository's studies, outputs under ``root``."""
    root = Path(root)
    (root / "studies").mkdir(parents=True, exist_ok=True)
    (root / "studies" / "reference.toml").write_text(
        (REPOSITORY / "studies" / "reference.toml").read_text())
    spec = root / "fault.toml"
    spec.write_text("[grid]\nweights.omega_e = [1000.0, 1200.0, 1400.0, 1600.0]\n")
    return spec


def start_driver(root, spec, seconds, jobs=2):
    env = {**os.environ, "PIEZOLIB_ROOT": str(root), "PIEZOLIB_FAULT_SECONDS": str(seconds),
           "PYTHONPATH": str(REPOSITORY)}
    return subprocess.Popen([sys.executable, __file__, "--driver", str(spec), str(jobs)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, text=True)


def wait_for(condition, timeout_s=120.0):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.2)
    return False


def pipe_ends(pipe, timeout_s):
    """Whether ``pipe`` reaches its end (every writer closed it) within ``timeout_s``."""
    import select

    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        ready, _, _ = select.select([pipe], [], [], 0.2)
        if ready and not os.read(pipe.fileno(), 65536):
            return True
    return False


def session_processes(sid):
    """{pid: command line} of the processes of session ``sid``."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields_ = (entry / "stat").read_text().rpartition(")")[2].split()
            if int(fields_[3]) == sid:
                found[int(entry.name)] = (entry / "cmdline").read_bytes().replace(
                    b"\0", b" ").decode(errors="replace")[:90]
        except (OSError, IndexError, ValueError):
            continue
    return found


def started(root):
    return len(list((Path(root) / "started").glob("*"))) if (Path(root) / "started").exists() \
        else 0


def records(root):
    return len(list((Path(root) / "runs" / "sweeps" / "fault" / "points").glob("*.json")))


# --------------------------------------------------------------------------- the cases
def kill_nine():
    with tempfile.TemporaryDirectory() as root:
        spec = checkout(root)
        proc = start_driver(root, spec, seconds=60)
        if not wait_for(lambda: started(root) >= 2):
            return print("kill -9: the workers did not start:", proc.communicate()[1][-400:])
        before = session_processes(proc.pid)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        t0 = time.monotonic()
        eof = pipe_ends(proc.stdout, 10.0)
        t_eof = time.monotonic() - t0
        time.sleep(max(0.0, 5.0 - t_eof))
        left = session_processes(proc.pid)
        print(f"kill -9 of the driver: {len(before)} processes in its session before, "
              f"{len(left)} still running 5 s after; its output pipe ended "
              f"{'after %.1f s' % t_eof if eof else 'NEVER'}")
        for pid, cmd in left.items():
            print(f"    left running: {pid} {cmd}")
            os.kill(pid, signal.SIGKILL)


def concurrent():
    with tempfile.TemporaryDirectory() as root:
        spec = checkout(root)
        first = start_driver(root, spec, seconds=60)
        if not wait_for(lambda: started(root) >= 1):
            return print("concurrent: the first sweep did not start")
        second = start_driver(root, spec, seconds=0.1)
        _, err = second.communicate(timeout=120)
        print(f"a second sweep of the same spec: exit {second.returncode}, "
              f"{started(root)} evaluations started in all; it said: {err.strip()}")
        os.killpg(first.pid, signal.SIGKILL)
        first.wait()
        third = start_driver(root, spec, seconds=0.1)
        out, err = third.communicate(timeout=300)
        print(f"after kill -9 of the first: a third run exits {third.returncode}, "
              f"{out.strip()}; lock left by the dead one taken over: "
              f"{'took over' in err}")
        if third.returncode:
            print(err[-2000:])


def mounted(kind):
    """A small tmpfs mount point (root only), or None."""
    if os.geteuid() != 0:
        print(f"{kind}: skipped (needs root for a tmpfs mount)")
        return None
    point = Path(tempfile.mkdtemp(prefix="fault-mount-"))
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(point)]).returncode:
        print(f"{kind}: skipped (mount refused)")
        return None
    return point


def unmount(point):
    subprocess.run(["umount", str(point)])
    point.rmdir()


def full_disk():
    point = mounted("full disk")
    if point is None:
        return
    try:
        spec = checkout(point)
        (point / "runs" / "sweeps" / "fault" / "points").mkdir(parents=True)
        proc = start_driver(point, spec, seconds=3, jobs=1)
        wait_for(lambda: records(point) >= 1, 120)
        filler = point / "filler"
        with open(filler, "wb") as fh:               # fill the disk after the first point
            try:
                while True:
                    fh.write(b"\0" * 65536)
            except OSError:
                pass
        out, err = proc.communicate(timeout=300)
        stored = records(point)
        said = json.loads(out.strip().splitlines()[-1]) if out.strip() else {}
        problems = said.get("problems", [])
        points = sum(p.startswith("point") for p in problems)
        print(f"full disk after the first point: exit {proc.returncode}, "
              f"{said.get('evaluated')} evaluated, {stored} records stored, {points} points "
              f"reported as not stored (in the table returned), the table "
              f"{'not written (reported)' if len(problems) > points else 'written'}")
        filler.unlink()
        again = start_driver(point, spec, seconds=0.1, jobs=1)
        out, err = again.communicate(timeout=300)
        if again.returncode:
            return print(f"    the next run failed: {err[-2000:]}")
        said = json.loads(out.strip().splitlines()[-1])
        print(f"    the next run: {said['evaluated']} evaluated (the missing ones), "
              f"{said['reused']} reused; lost: {4 - said['evaluated'] - said['reused']}")
    finally:
        unmount(point)


def read_only():
    point = mounted("read-only folder")
    if point is None:
        return
    try:
        spec = checkout(point)
        subprocess.run(["mount", "-o", "remount,ro", str(point)], check=True)
        proc = start_driver(point, spec, seconds=0.1, jobs=1)
        _, err = proc.communicate(timeout=120)
        print(f"read-only output folder: exit {proc.returncode}, {started(point)} "
              f"evaluations started; it said: {err.strip()}")
    finally:
        unmount(point)


def limits():
    with tempfile.TemporaryDirectory() as root:
        checkout(root)
        values = ", ".join(str(1000.0 + k) for k in range(200))
        cases = {
            "320,000-point grid": "[grid]\nweights.omega_e = [%s]\n"
                                  "weights.omega_y = [%s]\nuncertainty.spread = [%s]\n" % (
                values, ", ".join(str(1e5 + k) for k in range(40)),
                ", ".join(str(0.01 + 0.001 * k) for k in range(40))),
            "[random] samples = 100000": "[random]\nsamples = 100000\nseed = 0\n"
                                         "weights.omega_e = [800.0, 2500.0]\n",
        }
        env = {**os.environ, "PIEZOLIB_ROOT": root, "PYTHONPATH": str(REPOSITORY)}
        for name, text in cases.items():
            path = Path(root) / "big.toml"
            path.write_text(text)
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, "-c", "import sys; from piezolib.workbook "
                                   "import cli, sweep_spec; t=__import__('time').perf_counter(); "
                                   "code = cli.main(sys.argv[1:]); "
                                   "print(__import__('time').perf_counter() - t, file=sys.stderr);"
                                   " sys.exit(code)", "sweep", str(path), "--dry-run"],
                                  env=env, capture_output=True, text=True, timeout=600)
            lines = proc.stderr.strip().splitlines()
            print(f"{name} --dry-run: exit {proc.returncode} after {float(lines[-1]):.2f} s in "
                  f"the command ({time.perf_counter() - t0:.1f} s with start-up): {lines[0]}")


def main():
    if sys.argv[1:2] == ["--driver"]:
        return driver(*sys.argv[2:4])
    for case in (limits, kill_nine, concurrent, full_disk, read_only):
        case()
    return 0


if __name__ == "__main__":
    sys.exit(main())
