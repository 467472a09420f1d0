"""Settings for every test path of pyproject.toml: tests/, the notebooks (nbval) and the
doctests of piezolib/ (set here, at the root, so that each path run alone gets them too).

The order of the two xdist workers' work: each test file (so each notebook) runs whole on one
worker (``--dist loadfile``), the files that share an expensive session fixture run together
(:data:`SHARED_UNITS`, so it is computed once), and the longest units start first (longest-first
keeps both workers busy to the end), by the seconds recorded in ``tests/test_durations.json``:
each test of at least :data:`LONG_TEST_S` by its id, the others as an average per file (a file
not recorded counts :data:`DEFAULT_TEST_S` a test).  The record orders the work only: every test
runs whatever it says.  Refresh it after a change in where the time goes, from both steps::

    pytest --record-durations=tests/test_durations.json
    pytest -m slow --record-durations=tests/test_durations.json

(each run replaces the entries of the tests it ran and keeps the others).
"""

import json
import os
import pathlib

import pytest

# headless, and every kernel nbval starts inherits these settings
os.environ.setdefault("MPLBACKEND", "Agg")
# one BLAS thread: on 2 shared cores threaded small solves run many times slower
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# (no PIEZOLIB_STATIC: kernels run by nbval, as by any headless client, name no cell in their
# requests, so the interactive controls draw their static figure by themselves)

ROOT = pathlib.Path(__file__).parent
#: the recorded seconds of tests: {"tests": {test id: s}, "files": {file: [s, n tests]}}
TEST_DURATIONS = ROOT / "tests" / "test_durations.json"
#: a test that takes at least this (setup, call and teardown) is recorded by its id
LONG_TEST_S = 0.5
#: seconds a test of a file missing from TEST_DURATIONS counts
DEFAULT_TEST_S = 0.05
#: a worker holds its last test until it has more (xdist runs a test knowing the next one), so
#: a worker whose pending tests take longer than this gets the shortest unit as that "more":
#: the longest ones then go to whichever worker is free first
PREFETCH_LONG_S = 10.0
#: test files -> the work unit they share (their session fixture is then made once)
SHARED_UNITS = {
    # paper_design (tests/robust/conftest.py): the paper problem's DK design
    "tests/robust/test_dk.py": "paper_design",
    "tests/robust/test_discrete.py": "paper_design",
    "tests/robust/test_reduction.py": "paper_design",
}


def _file_of(nodeid):
    return nodeid.split("::", 1)[0]


def _unit_of(nodeid):
    path = _file_of(nodeid)
    return SHARED_UNITS.get(path, path)


def _recorded_durations(path=TEST_DURATIONS):
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        record = {}
    return record.get("tests", {}), record.get("files", {})


def _expected_seconds(nodeids, tests, files):
    """The recorded seconds of these tests (a file's average for a short test)."""
    total = 0.0
    for nodeid in nodeids:
        if nodeid in tests:
            total += tests[nodeid]
        else:
            seconds, count = files.get(_file_of(nodeid), (0.0, 0))
            total += seconds / count if count else DEFAULT_TEST_S
    return total


def pytest_addoption(parser):
    parser.addoption("--record-durations", metavar="PATH", default=None,
                     help="merge the seconds each test took (setup, call, teardown) into the "
                          "JSON record at PATH, the order of the xdist work (conftest.py)")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` with shared units and the longest units first; any other
    ``--dist`` mode keeps xdist's own scheduler."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    tests, files = _recorded_durations()

    class LongestFirstFileScheduling(LoadFileScheduling):
        _ordered = False

        def _split_scope(self, nodeid):
            return _unit_of(nodeid)

        def _assign_work_unit(self, node):
            if not self._ordered:       # the first assignment: the work queue is complete
                units = sorted(self.workqueue.items(), reverse=True,
                               key=lambda unit: _expected_seconds(unit[1], tests, files))
                self.workqueue.clear()
                self.workqueue.update(units)
                self._ordered = True
            pending = [n for unit in self.assigned_work.get(node, {}).values()
                       for n, done in unit.items() if not done]
            if _expected_seconds(pending, tests, files) > PREFETCH_LONG_S:
                self.workqueue.move_to_end(next(reversed(self.workqueue)), last=False)
            super()._assign_work_unit(node)

    return LongestFirstFileScheduling(config, log)


class _RecordDurations:
    """Sums each test's report durations; merges them into the record at the session's end."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self.seconds = {}

    def pytest_runtest_logreport(self, report):
        self.seconds[report.nodeid] = self.seconds.get(report.nodeid, 0.0) + report.duration

    def pytest_sessionfinish(self, session):
        tests, files = _recorded_durations(self.path)
        short = {}
        for nodeid, seconds in self.seconds.items():
            if seconds >= LONG_TEST_S:
                tests[nodeid] = round(seconds, 2)
            else:
                tests.pop(nodeid, None)
                total = short.setdefault(_file_of(nodeid), [0.0, 0])
                total[0] += seconds
                total[1] += 1
        # a file's short tests: the run that ran more of them (the default step, not `-m slow`)
        for path, (seconds, count) in short.items():
            if count >= files.get(path, (0.0, 0))[1]:
                files[path] = [round(seconds, 3), count]
        self.path.write_text(json.dumps({"tests": dict(sorted(tests.items())),
                                         "files": dict(sorted(files.items()))}, indent=0)
                             + "\n")


def pytest_configure(config):
    path = config.getoption("--record-durations", default=None)
    if path and not hasattr(config, "workerinput"):      # the controller (or a plain run)
        config.pluginmanager.register(_RecordDurations(path), "record-durations")
