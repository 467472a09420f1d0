"""The reproduce command runs notebooks in order and names a failing cell."""

import subprocess
import sys

import nbformat
import pytest

from piezolib.workbook import reproduce


def write_notebook(path, *sources):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    nbformat.write(nb, path)


def test_failure_names_notebook_and_cell(workbook):
    write_notebook(workbook / "notebooks" / "00_ok.ipynb", "x = 1")
    write_notebook(workbook / "notebooks" / "01_bad.ipynb", "y = 2", "assert y == 3, 'y is 2'")
    write_notebook(workbook / "notebooks" / "02_never.ipynb", "z = 3")
    proc = subprocess.run([sys.executable, "-m", "piezolib", "reproduce", "--no-data",
                           "--jobs", "1"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    lines = proc.stdout.splitlines()
    assert "00_ok.ipynb" in lines[0] and lines[0].rstrip().endswith("ok")
    assert "01_bad.ipynb" in lines[1] and "FAILED at cell 1" in lines[1]
    assert "AssertionError: y is 2" in lines[1]
    assert not any("02_never" in line for line in lines)   # stops at the first failure


# each notebook announces that it started and waits (an event, not a sleep) until the
# other has started too: they finish only if they ran side by side
MEET = ("import pathlib, time\n"
        "pathlib.Path('{name}.started').touch()\n"
        "deadline = time.time() + 120\n"
        "while not pathlib.Path('{other}.started').exists():\n"
        "    assert time.time() < deadline, 'the other notebook never started'\n"
        "    time.sleep(0.02)\n"
        "pathlib.Path('{name}.done').touch()")


def test_notebooks_run_side_by_side_and_the_report_runs_after_them(workbook):
    import io

    nbs = workbook / "notebooks"
    write_notebook(nbs / "00_a.ipynb", MEET.format(name="a", other="b"))
    write_notebook(nbs / "01_b.ipynb", MEET.format(name="b", other="a"))
    write_notebook(nbs / "07_report.ipynb",      # reads what both others wrote
                   "import pathlib\nassert all(pathlib.Path(n + '.done').is_file() for n in 'ab')")
    write_notebook(nbs / "08_after.ipynb", "pass")
    out = io.StringIO()
    assert reproduce.run(data=False, stream=out, jobs=2) == 0
    lines = out.getvalue().splitlines()
    assert "07_report.ipynb" in lines[3] and lines[3].rstrip().endswith("ok")


def test_after_a_failure_no_further_notebook_starts_in_parallel_runs(workbook):
    import io

    nbs = workbook / "notebooks"

    class Reporter(io.StringIO):
        """The runner's output; marks the moment it reports the failure."""

        def write(self, text):
            if "FAILED" in text:
                (nbs / "failure.reported").touch()
            return super().write(text)

    # the slow notebook ends only after the runner has reported the other one's failure
    # (an event, not a sleep: on a loaded machine a kernel can take seconds to start), so
    # its free slot is the moment a broken scheduler would start the third notebook
    write_notebook(nbs / "00_slow.ipynb",
                   "import pathlib, time\n"
                   "deadline = time.time() + 120\n"
                   "while not pathlib.Path('failure.reported').exists():\n"
                   "    assert time.time() < deadline, 'the failure was never reported'\n"
                   "    time.sleep(0.02)\n"
                   "pathlib.Path('slow.done').touch()")
    write_notebook(nbs / "01_bad.ipynb", "assert False, 'bad'")
    write_notebook(nbs / "02_never.ipynb", "open('never.done', 'w').close()")
    out = Reporter()
    assert reproduce.run(data=False, stream=out, jobs=2) == 1
    text = out.getvalue()
    assert "FAILED at cell 0: AssertionError: bad" in text
    assert "00_slow.ipynb" in text and (nbs / "slow.done").is_file()   # finished and reported
    assert "02_never" not in text and not (nbs / "never.done").exists()
    with pytest.raises(ValueError, match="jobs must be a positive integer"):
        reproduce.run(data=False, stream=out, jobs=0)


def test_report_notebooks_form_the_last_wave():
    from pathlib import Path

    names = ["00_a.ipynb", "07_reproduction_report.ipynb", "08_b.ipynb", "09_c.ipynb"]
    waves = reproduce.notebook_waves([Path(n) for n in names])
    assert [[p.name for p in w] for w in waves] == [["00_a.ipynb", "08_b.ipynb", "09_c.ipynb"],
                                                    ["07_reproduction_report.ipynb"]]
    assert reproduce.notebook_waves([Path("00_a.ipynb")]) == [[Path("00_a.ipynb")]]


def test_selection_and_listing(workbook):
    write_notebook(workbook / "notebooks" / "00_a.ipynb", "pass")
    write_notebook(workbook / "notebooks" / "01_b.ipynb", "pass")
    assert [p.name for p in reproduce.list_notebooks(["01"])] == ["01_b.ipynb"]
    with pytest.raises(ValueError, match="no notebook matches"):
        reproduce.list_notebooks(["07"])


def test_reproduce_says_when_it_regenerates_a_file_that_failed_its_check(workbook):
    import io
    import shutil

    from piezolib.problem import stage_data
    from piezolib.workbook.outputs import project_root

    real = project_root().__class__(__file__).resolve().parents[2] / "data"
    (workbook / "data").mkdir()
    for name in [*(p.name for p in stage_data.experiment_paths(real).values()),
                 stage_data.MANIFEST_NAME]:
        shutil.copy(real / name, workbook / "data" / name)
    broken = workbook / "data" / "chirp_validation.csv"
    broken.write_text("".join(broken.read_text().splitlines(keepends=True)[:500]))
    assert list(reproduce._check_data()) == [broken]
    out = io.StringIO()
    assert reproduce.run(data=True, stream=out) == 0            # no notebooks in this workbook
    lines = out.getvalue().splitlines()
    regenerated = [line for line in lines if line.startswith("regenerating")]
    assert len(regenerated) == 1 and "chirp_validation.csv" in regenerated[0]
    assert "line 501" in regenerated[0]
    assert reproduce._check_data() == {}                          # regenerated and intact again


def test_study_is_injected_after_the_parameters_cell(workbook):
    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell("# title"),
        nbformat.v4.new_code_cell('study = "reference"'),
        nbformat.v4.new_code_cell("result = study")])
    nb.cells[1].metadata["tags"] = ["parameters"]
    path = workbook / "notebooks" / "00_param.ipynb"
    nbformat.write(nb, path)
    (workbook / "studies").mkdir(exist_ok=True)
    (workbook / "studies" / "other.toml").write_text('name = "other"\n')
    out = reproduce.run_notebook(path, study="other", save_to=workbook / "runs" / "x")
    assert [c.metadata.get("tags") for c in out.cells[1:3]] == [["parameters"],
                                                               ["injected-parameters"]]
    assert (workbook / "runs" / "x" / "00_param.ipynb").is_file()
    assert nbformat.read(path, as_version=4).cells[2].source == "result = study"   # untouched
    with pytest.raises(ValueError, match="no cell tagged 'parameters'"):
        reproduce.inject_study(nbformat.v4.new_notebook(), "other")
    with pytest.raises(ValueError, match="no study named 'missing'"):   # before any kernel
        reproduce.run_notebook(path, study="missing")


def test_every_workbook_notebook_has_a_parameters_cell_naming_the_study():
    from piezolib.workbook.outputs import notebooks_dir

    for path in sorted(notebooks_dir().glob("[0-9][0-9]_*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        tagged = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
        # 08's default is None: the reference study for its example records, a study of
        # their own for a user's (it never writes a user's records into the reference)
        default = 'study = None' if path.name.startswith("08_") else 'study = "reference"'
        assert len(tagged) == 1 and default in tagged[0].source, path.name
        started = ("session.start(own.records_study(study" if path.name.startswith("08_")
                   else "session.start(study")
        assert started in "".join(c.source for c in nb.cells), path.name


def test_reproduce_first_removes_the_temporary_files_a_killed_run_left(workbook, caplog):
    import io
    import logging
    import os
    import time

    from piezolib.workbook import study

    def left(path, seconds=3600):
        """A file named as atomic_path names its temporary files, last written long ago."""
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("half a fi")
        os.utime(path, (time.time() - seconds,) * 2)
        return path

    data = left(workbook / "data" / "results" / ".tracking.csv.k2j4x9_a.tmp.csv")
    figure = left(workbook / "figures" / ".fig_05.png.abcdefgh.tmp.png")
    live = left(workbook / "data" / ".chirp.csv.abcdefgh.tmp.csv", seconds=1)
    other_study = left(workbook / "runs" / "wide" / "figures" / ".fig_05.png.abcdefgh.tmp.png")
    users = left(workbook / "data" / "notes.tmp.csv")
    with caplog.at_level(logging.WARNING):
        assert reproduce.run(data=False, stream=io.StringIO(), jobs=1) == 0
    assert not data.exists() and not figure.exists()
    assert live.exists() and users.exists()
    assert other_study.exists()                  # another study's folder: not this run's
    assert str(data) in caplog.text and str(figure) in caplog.text
    assert reproduce.remove_stale_temporaries(study.Study().replace(name="wide")) == [other_study]


def test_the_long_notebooks_of_a_wave_start_first():
    from pathlib import Path

    names = ["00_published_design_audit.ipynb", "10_real_piezo_benchmark.ipynb", "99_new.ipynb",
             "07_reproduction_report.ipynb", "05_mu_synthesis.ipynb"]
    waves = reproduce.notebook_waves([Path(n) for n in names])
    seconds = [reproduce._expected_seconds(p) for p in waves[0]]
    assert seconds == sorted(seconds, reverse=True) and waves[0][0].name.startswith("10_")
    assert reproduce._expected_seconds(Path("99_new.ipynb")) == sorted(
        reproduce.EXPECTED_SECONDS.values())[len(reproduce.EXPECTED_SECONDS) // 2]
    assert [p.name for p in waves[1]] == ["07_reproduction_report.ipynb"]
    # every notebook of the workbook has an expectation (a new one would run by the median)
    assert {p.name for p in reproduce.list_notebooks()} == set(reproduce.EXPECTED_SECONDS)
