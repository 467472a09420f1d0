"""The notebook façade: one call gives the study, its claim table and its output folders."""

import matplotlib.pyplot as plt
import pandas as pd
import pytest

from piezolib.workbook import plotting, session
from piezolib.workbook.style import new_figure
from piezolib.workbook import study as studies


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    (tmp_path / "studies").mkdir()
    return tmp_path


def _named_figure():
    fig, ax = new_figure()
    ax.plot([0, 1], [1, 0])
    return plotting.name_figure(fig, 4, "chirp_validation")


def test_the_reference_session_writes_the_committed_folders(checkout):
    nb = session.start("reference", claims="audit")
    assert nb.reference and nb.study.name == "reference" and nb.claims.name == "audit"
    fig = _named_figure()
    assert nb.save(fig) is fig
    assert (checkout / "figures" / "fig04_chirp_validation.png").is_file()
    nb.claims.add("IV-B", "x", 1.0, 1.0)
    assert nb.claims.save() == checkout / "data" / "results" / "audit.csv"
    assert nb.save_table(nb.claims.frame(), "copy") == checkout / "data" / "results" / "copy.csv"
    assert pd.get_option("display.precision") == session.DISPLAY_OPTIONS["display.precision"]
    assert nb.elapsed() >= 0.0
    plt.close(fig)


def test_another_study_writes_only_under_runs(checkout):
    other = studies.Study().replace(name="explore", weights={"omega_e": 2000.0})
    nb = session.start(other, claims="weights")
    assert not nb.reference and "explore" in repr(nb)
    fig = nb.save(_named_figure())
    nb.claims.add("eq. 15", "omega_e", 1260.0, 2000.0, rtol=0.01)
    path = nb.claims.save()
    assert path == checkout / "runs" / "explore" / "results" / "weights.csv"
    assert (checkout / "runs" / "explore" / "figures" / "fig04_chirp_validation.png").is_file()
    assert not (checkout / "figures").exists() and not (checkout / "data").exists()
    # a study's own difference from the paper carries the reason "study"
    assert nb.claims.frame().reason.tolist() == ["study"]
    plt.close(fig)


def test_a_reading_notebook_has_no_claim_table_and_bad_studies_are_named(checkout):
    assert session.start("reference").claims is None
    with pytest.raises(studies.StudyError, match="no study named 'nope'"):
        session.start("nope")
    with pytest.raises(ValueError, match="no file name"):
        session.start("reference").save(plt.figure())


# a notebook as a reader of JupyterLab writes one: a session, a search that stops early with log
# lines, a pyplot figure and an interactive control
HEADLESS_CELLS = [
    """import logging
import matplotlib.pyplot as plt
import numpy as np
from piezolib import paper, progress
from piezolib.workbook import interactive, session
nb = session.start("reference")
logging.getLogger("piezolib").setLevel(logging.INFO)
log = logging.getLogger("piezolib.robust.dk")""",
    """with progress.progress(total=8, desc="musyn DK", unit="iter") as bar:
    for k in range(5):
        log.info("DK %d: mu %.3f", k, 1 - 0.05 * k)
        bar.update()
    progress.finish(bar, "no improvement > 0.005 in 2 iterations")""",
    """plt.plot([0, 1], [1, 0])
plt.show()""",
    """interactive.spread_control(paper.plant(), paper.uncertainty_weight(), np.logspace(0, 6, 200),
                           levels=2)""",
]


def test_a_notebook_run_headless_saves_static_outputs(monkeypatch):
    """nbclient (papermill's and nbconvert's executor) without any piezolib setting: the saved
    notebook holds figures as PNG, the bar's final line, no stderr and no widget view."""
    nbclient = pytest.importorskip("nbclient")
    nbformat = pytest.importorskip("nbformat")
    for name in ("PIEZOLIB_STATIC", "MPLBACKEND", "PIEZOLIB_PROGRESS"):   # conftest sets some
        monkeypatch.delenv(name, raising=False)
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in HEADLESS_CELLS])
    nbclient.NotebookClient(nb, timeout=180, kernel_name="python3").execute()
    outputs = [o for cell in nb.cells for o in cell.outputs]
    assert [o for o in outputs if o.output_type in ("stream", "error")] == []   # no stderr
    assert not any("application/vnd.jupyter.widget-view+json" in o.get("data", {})
                   for o in outputs)
    assert not any("VBox(" in o.get("data", {}).get("text/plain", "") for o in outputs)
    bar = nb.cells[1].outputs
    assert len(bar) == 1 and bar[0].output_type == "display_data"      # one output, updated
    final = bar[0].data["text/plain"]
    assert final.startswith("✔ musyn DK: done: no improvement > 0.005 in 2 iterations")
    assert "5 of at most 8 iter" in final and "DK 4: mu 0.800" in final  # log under the bar
    assert "piezolib-progress-done" in bar[0].data["text/html"]
    for cell in nb.cells[2:]:                                   # pyplot figure, the control
        assert [o.output_type for o in cell.outputs][-1] in ("display_data", "execute_result")
        assert "image/png" in cell.outputs[-1].data


_CALLS = []


def _counted(sys):
    _CALLS.append(sys.name)
    return sys.nstates


def test_cached_reads_a_product_again_whatever_python_control_numbered_its_systems(
        tmp_path, monkeypatch):
    import control as ct

    monkeypatch.setenv("PIEZOLIB_CACHE", str(tmp_path))
    _CALLS.clear()
    first = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    ct.tf([1], [1, 1])                                  # moves the generic-name counter on
    again = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    assert first.name != again.name                     # sys[n] and sys[n + 2]
    assert session.Session.cached(_counted, first) == 1
    assert session.Session.cached(_counted, again) == 1
    assert len(_CALLS) == 1                              # the second call was read from disk
    sampled = [ct.sample_system(sys, 0.1) for sys in (first, again)]   # sys[n]$sampled
    session.Session.cached(_counted, sampled[0])
    session.Session.cached(_counted, sampled[1])
    assert len(_CALLS) == 2
    other = ct.ss([[-2.0]], [[1.0]], [[1.0]], [[0.0]])
    session.Session.cached(_counted, other)      # another model is another entry
    named = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], name="plant")
    session.Session.cached(_counted, named)      # a chosen name is part of the key
    assert len(_CALLS) == 4
    with pytest.raises(TypeError, match="func"):
        session.Session.cached("not a function", 1)
