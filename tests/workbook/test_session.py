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
