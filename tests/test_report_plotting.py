"""Comparison verdicts and figure naming."""

import matplotlib.pyplot as plt
import pytest

from piezolib.workbook import plotting, report


def test_verdict_relative_and_absolute():
    assert report.verdict(0.81, 0.8077, rtol=0.01)[0] == "agrees"
    assert report.verdict(0.92, 0.9817, rtol=0.02)[0] == "differs"
    assert report.verdict(0.0, 0.004, atol=0.005)[0] == "agrees"
    assert report.verdict(1.0, float("nan"), rtol=1.0)[0] == "differs"
    assert report.verdict(True, True)[0] == "agrees"
    assert report.verdict("stable", "unstable")[0] == "differs"
    with pytest.raises(ValueError, match="rtol"):
        report.verdict(1.0, 1.0, rtol=-0.1)


def test_claim_table_writes_csv(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    table = report.ClaimTable("unit_test")
    assert table.add("IV-C", "||H_e S||", 0.81, 0.8077, rtol=0.01) == "agrees"
    assert table.add("IV-C", "bandwidth", None, 335.5, unit="Hz") == "not published"
    path = table.save()
    assert path == tmp_path / "data" / "results" / "unit_test.csv"
    text = path.read_text().splitlines()
    assert text[0] == ",".join(report.COLUMNS) and len(text) == 3
    with pytest.raises(ValueError, match="reason must be one of"):
        table.add("V", "x", 1.0, 2.0, reason="bad luck")


def test_figure_names(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1])
    assert plotting.save_figure(fig, 10, "step_responses").name == "fig10_step_responses.png"
    assert plotting.save_figure(fig, None, "extra_view").name == "extra_extra_view.png"
    plt.close(fig)
    with pytest.raises(ValueError, match="what"):
        plotting.figure_path(4, "Bad Name")
    with pytest.raises(ValueError, match="number"):
        plotting.figure_path(0, "ok")
