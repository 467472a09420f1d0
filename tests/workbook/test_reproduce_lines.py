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


def designs_of(study):                  # a stand-in for a design step (module-level: by name)
    designs_of.studies.append(study.name)
    return type("Designs", (), {"source": "designed now"})()


designs_of.studies = []


def test_a_studys_designs_are_steps_before_its_notebooks(workbook, monkeypatch):
    # before: notebook 09 designed the study's nine mixed-mu controllers inside a cell and
    # passed the 600 s cell limit (studies/wide_error_weight.toml)
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('study = "reference"'),
                                         nbformat.v4.new_code_cell("x = 1")])
    nb.cells[0].metadata["tags"] = ["parameters"]
    nbformat.write(nb, workbook / "notebooks" / "09_mixed.ipynb")
    nbformat.write(nb, workbook / "notebooks" / "01_other.ipynb")
    (workbook / "studies").mkdir()
    (workbook / "studies" / "other.toml").write_text('name = "other"\n')
    step = f"{__name__}:designs_of"
    monkeypatch.setattr(reproduce, "STUDY_DESIGNS", [(("09_",), "mixed designs", step),
                                                     (("05_",), "unused designs", step)])
    out = io.StringIO()
    assert reproduce.run(data=False, stream=out, study="other") == 0
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("[1/3] mixed designs") and lines[0].endswith("ok (designed now)")
    assert designs_of.studies == ["other"]              # once; 05's step: no 05 notebook
    out = io.StringIO()
    assert reproduce.run(data=False, stream=out) == 0     # the reference: committed designs
    lines = out.getvalue().splitlines()                 # two notebooks, in either order
    assert designs_of.studies == ["other"] and lines[0].startswith("[1/2] 0")
    assert "mixed designs" not in out.getvalue()
