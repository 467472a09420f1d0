"""What reproduce says: its first line (the data files checked or regenerated) and a cell
that runs past its time limit reported like any failure."""

import io
import shutil
from pathlib import Path

import nbformat

from piezolib.problem import stage_data
from piezolib.workbook import reproduce

REPOSITORY = Path(__file__).resolve().parents[2]


def copy_data(workbook):
    real = REPOSITORY / "data"
    (workbook / "data").mkdir()
    for name in [*(p.name for p in stage_data.experiment_paths(real).values()),
                 stage_data.MANIFEST_NAME]:
        shutil.copy2(real / name, workbook / "data" / name)


def test_the_first_line_says_the_data_files_were_checked_when_none_needed_regenerating(
        workbook):
    copy_data(workbook)
    before = {p.name: p.stat().st_mtime_ns for p in (workbook / "data").iterdir()}
    out = io.StringIO()
    assert reproduce.run(data=True, stream=out) == 0            # no notebooks here
    first = out.getvalue().splitlines()[0]
    # said "piezolib.problem.stage_data:write_experiment_files ... ok (7 files)" and rewrote them
    assert first.startswith("[1/1] data files") and "write_experiment_files" not in first
    assert first.endswith("checked 6 files against their manifest: intact, none regenerated")
    assert {p.name: p.stat().st_mtime_ns for p in (workbook / "data").iterdir()} == before


def test_the_first_line_names_a_regenerated_file_and_why(workbook):
    copy_data(workbook)
    (workbook / "data" / "hysteresis_loop_20V.csv").unlink()
    out = io.StringIO()
    assert reproduce.run(data=True, stream=out) == 0
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("regenerating ") and "hysteresis_loop_20V.csv" in lines[0]
    assert "it failed its check" in lines[0]
    assert lines[1].startswith("[1/1] data files") and "regenerated 7 files (1 failed" in lines[1]


def test_a_cell_past_its_time_limit_is_a_failure_naming_the_notebook_and_the_cell(workbook):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1"),
                                         nbformat.v4.new_code_cell("import time\ntime.sleep(60)")])
    nbformat.write(nb, workbook / "notebooks" / "00_slow.ipynb")
    out = io.StringIO()
    # a raw nbclient CellTimeoutError traceback before
    assert reproduce.run(timeout=1, data=False, stream=out) == 1
    lines = out.getvalue().splitlines()
    assert "00_slow.ipynb" in lines[0] and "FAILED at cell 1: timed out: the cell ran longer " \
                                            "than 1 s" in lines[0]
    assert lines[-1].startswith("1 step(s) failed")
