"""Paper-versus-reproduced claims: verdicts, the claim table and the reproduction table."""

import pandas as pd
import pytest

from piezolib.workbook import report


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
    assert table.add("IV-C", "||H_e S||", 0.81, 0.8077, rtol=0.01) is None   # no cell output
    table.add("IV-C", "bandwidth", None, 335.5, unit="Hz")
    assert list(table.frame().verdict) == ["agrees", "not published"]
    path = table.save()
    assert path == tmp_path / "data" / "results" / "unit_test.csv"
    text = path.read_text().splitlines()
    assert text[0] == ",".join(report.COLUMNS) and len(text) == 3
    with pytest.raises(ValueError, match="reason must be one of"):
        table.add("V", "x", 1.0, 2.0, reason="bad luck")


def test_reasons_are_kept_only_on_differing_rows():
    table = report.ClaimTable("reasons")
    table.add("A", "agrees anyway", 1.0, 1.0, reason="method")
    table.add("B", "differs", 1.0, 2.0, reason="typo", note="printed 1")
    frame = table.frame()
    assert list(frame.columns) == report.COLUMNS
    assert frame.reason.tolist() == ["", "typo"]
    with pytest.raises(ValueError, match="identifier"):
        report.ClaimTable("not a name")


def test_saved_floats_have_six_significant_digits(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    frame = pd.DataFrame({"x": [1.0 / 3.0], "mixed": [2.0 / 3.0]}).astype({"mixed": object})
    text = report.save_results(frame, "digits").read_text().splitlines()
    assert text[1] == "0.333333,0.666667"
    with pytest.raises(TypeError, match="DataFrame"):
        report.save_results([1, 2], "digits")


def test_load_claims_and_reproduction_table(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    with pytest.raises(FileNotFoundError, match="reproduce 00"):
        report.load_claims(["audit"])
    with pytest.raises(ValueError, match="unknown table"):
        report.load_claims(["nothing"])
    table = report.ClaimTable("audit")
    table.add("IV-C", "agrees", 0.81, 0.81)
    table.add("IV-C", "explained", 0.92, 0.98, rtol=0.02, reason="inconsistent parameters")
    table.add("IV-C", "unexplained", 0.48, 0.82, rtol=0.02)
    table.add("IV-C", "not published", None, 1.0)
    table.save()
    claims = report.load_claims(["audit"])
    assert list(claims.columns) == ["source"] + report.COLUMNS
    assert set(claims.source) == {report.NOTEBOOK_TABLES["audit"]}
    published = report.reproduction_table(claims)
    assert len(published) == 3
    assert published.reason.tolist() == ["", "inconsistent parameters", "unexplained"]
    counts = report.verdict_counts(published)
    assert counts.loc["all", "agrees"] == 1 and counts.loc["all", "differs"] == 2


def test_other_tables_load_only_by_name(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    assert not set(report.OTHER_TABLES) & set(report.NOTEBOOK_TABLES)
    with pytest.raises(FileNotFoundError, match="reproduce 08"):
        report.load_claims(["own_stage"])
    table = report.ClaimTable("own_stage")
    table.add("own stage", "validation fit", None, 89.5, unit="%")
    table.save()
    claims = report.load_claims(["own_stage"])
    assert claims.source.tolist() == ["08_your_own_stage"]
    with pytest.raises(FileNotFoundError, match="reproduce 00"):
        report.load_claims()                          # the default set does not include it
