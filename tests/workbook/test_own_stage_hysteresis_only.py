"""Notebook 08 on a folder that holds one raw hysteresis record only (no identification run).

The record starts at rest and steps (``raw_hysteresis_record``); there is no chirp.  The
notebook must skip identification and the plant's steps with a note, drop the record's
start-up and say so, and validate on the record's held-out second half, saying so, instead of
on the data it fitted.  Everything it writes goes under a temporary PIEZOLIB_ROOT.
"""

import json

import numpy as np
import pytest

from piezolib.problem.stage_data import raw_hysteresis_record
from piezolib.workbook import study
from piezolib.workbook.outputs import notebooks_dir


def outputs_of(path):
    text = []
    for cell in json.loads(path.read_text())["cells"]:
        for out in cell.get("outputs", []):
            text.append("".join(out.get("text", "")))
            text.append("".join(out.get("data", {}).get("text/plain", "")))
    return "\n".join(text)


@pytest.mark.slow
def test_notebook_08_on_hysteresis_records_only(tmp_path, monkeypatch):
    papermill = pytest.importorskip("papermill")
    notebook = notebooks_dir() / "08_your_own_stage.ipynb"      # read before the root moves
    raw = raw_hysteresis_record()
    rec = raw.record
    folder = tmp_path / "records"
    folder.mkdir()
    np.savetxt(folder / "raw.csv", np.column_stack([rec.time, rec.input, 3.0 * rec.output]),
               delimiter=",", fmt="%.6f")
    path = study.load("reference").replace(name="hysteresis_only", description="test").save(
        tmp_path / "hysteresis_only.toml")
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path / "root"))  # the kernel writes there
    out = tmp_path / "out.ipynb"
    papermill.execute_notebook(
        str(notebook), str(out), kernel_name="python3", progress_bar=False,
        cwd=str(notebook.parent),
        parameters=dict(study=str(path), RECORD_DIR=str(folder), CHIRP_FILE=None,
                        LOOP_FILES={"raw": "raw.csv"}, FIT_LOOPS=["raw"], VALIDATION_LOOPS=[]))
    text = outputs_of(out)
    assert "identification is skipped" in text
    assert "dropped the start-up" in text and "ringing" in text
    assert "validated on the second half (held out in time)" in text
    assert "raw (second half)" in text
    results = tmp_path / "root" / "runs" / "hysteresis_only" / "results" / "own_stage.csv"
    assert "held out in time" in results.read_text()


@pytest.mark.slow
def test_notebook_08_on_ones_own_records_leaves_the_checkout_clean(tmp_path):
    # with the default study it rewrote data/results/own_stage.csv and two committed figures
    import shutil
    import subprocess

    from piezolib.problem.foreign_hysteresis import foreign_raw_record
    from piezolib.workbook.outputs import project_root, runs_dir

    papermill = pytest.importorskip("papermill")
    notebook = notebooks_dir() / "08_your_own_stage.ipynb"
    rec = foreign_raw_record("duhem", 5000.0, periods=3.7).record     # a family no fit has
    folder = tmp_path / f"stage_{tmp_path.name}"
    folder.mkdir()
    np.savetxt(folder / "raw.csv", np.column_stack([rec.time, rec.input, rec.output]),
               delimiter=",", fmt="%.6f")

    def status():      # the source trees left out: others may edit them while this runs
        return subprocess.run(["git", "status", "--short", "--untracked-files=all", "--", "."]
                              + [f":(exclude){d}" for d in ("piezolib", "tests", "benchmarks")],
                              cwd=project_root(), capture_output=True, text=True,
                              check=True).stdout

    before = status()
    own_runs = runs_dir() / f"own_{folder.name}"
    try:
        papermill.execute_notebook(
            str(notebook), str(tmp_path / "out.ipynb"), kernel_name="python3",
            progress_bar=False, cwd=str(notebook.parent),
            parameters=dict(RECORD_DIR=str(folder), CHIRP_FILE=None,
                            LOOP_FILES={"raw": "raw.csv"}, FIT_LOOPS=["raw"],
                            VALIDATION_LOOPS=[]))
        assert status() == before
        results = (own_runs / "results" / "own_stage.csv").read_text()
        assert "Hammerstein: validation RMS" in results
    finally:
        shutil.rmtree(own_runs, ignore_errors=True)
