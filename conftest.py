"""Settings for every test path of pyproject.toml: tests/, the notebooks (nbval) and the
doctests of piezolib/ (set here, at the root, so that each path run alone gets them too).

The order of the two xdist workers' work: each test file (so each notebook) runs whole on one
worker (``--dist loadfile``), the files that share an expensive session fixture run together
(:data:`SHARED_UNITS`, so it is computed once), and the longest units start first, by the
seconds recorded in ``tests/file_durations.json`` (longest-first keeps both workers busy to the
end; a file not listed there counts 0.05 s per test). Refresh that record after a change in
where the time goes::

    pytest --file-durations tests/file_durations.json

The record orders the work only: every test runs whatever it says.
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
#: seconds per test file (its setups, calls and teardowns) of a recorded run
FILE_DURATIONS = ROOT / "tests" / "file_durations.json"
#: seconds a test of a file missing from FILE_DURATIONS counts
DEFAULT_TEST_SECONDS = 0.05
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


def _recorded_durations(path=FILE_DURATIONS):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def pytest_addoption(parser):
    parser.addoption("--file-durations", metavar="PATH", default=None,
                     help="write the seconds each test file took (setup, call, teardown) "
                          "to PATH as JSON, the order of the xdist work (conftest.py)")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` with shared units and the longest units first; any other
    ``--dist`` mode keeps xdist's own scheduler."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    seconds = _recorded_durations()

    class LongestFirstFileScheduling(LoadFileScheduling):
        _ordered = False

        def _split_scope(self, nodeid):
            return _unit_of(nodeid)

        def _assign_work_unit(self, node):
            if not self._ordered:       # the first assignment: the work queue is complete
                def cost(unit):
                    files = {_file_of(n) for n in unit[1]}
                    known = sum(seconds.get(f, 0.0) for f in files)
                    unknown = sum(1 for n in unit[1] if _file_of(n) not in seconds)
                    return known + DEFAULT_TEST_SECONDS * unknown
                units = sorted(self.workqueue.items(), key=cost, reverse=True)
                self.workqueue.clear()
                self.workqueue.update(units)
                self._ordered = True
            super()._assign_work_unit(node)

    return LongestFirstFileScheduling(config, log)


class _FileDurations:
    """Sums each test file's report durations; writes them at the end of the session."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self.seconds = {}

    def pytest_runtest_logreport(self, report):
        path = _file_of(report.nodeid)
        self.seconds[path] = self.seconds.get(path, 0.0) + report.duration

    def pytest_sessionfinish(self, session):
        rounded = {f: round(s, 1) for f, s in sorted(self.seconds.items())}
        self.path.write_text(json.dumps(rounded, indent=1) + "\n")


def pytest_configure(config):
    path = config.getoption("--file-durations", default=None)
    if path and not hasattr(config, "workerinput"):      # the controller (or a plain run)
        config.pluginmanager.register(_FileDurations(path), "file-durations")
