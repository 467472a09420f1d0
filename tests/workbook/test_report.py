"""Paper-versus-reproduced claims: verdicts, the claim table and the reproduction table."""

import numpy as np
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
    table = report.ClaimTable("unit_test", "reference")
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
    table = report.ClaimTable("reasons", "reference")
    table.add("A", "agrees anyway", 1.0, 1.0, reason="method")
    table.add("B", "differs", 1.0, 2.0, reason="typo", note="printed 1")
    frame = table.frame()
    assert list(frame.columns) == report.COLUMNS
    assert frame.reason.tolist() == ["", "typo"]
    with pytest.raises(ValueError, match="identifier"):
        report.ClaimTable("not a name", "reference")
    with pytest.raises(ValueError, match="study"):
        report.ClaimTable("audit", None)


def test_saved_floats_have_four_significant_digits(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    frame = pd.DataFrame({"x": [1.0 / 3.0], "mixed": [2.0 / 3.0]}).astype({"mixed": object})
    text = report.save_results(frame, "digits", "reference").read_text().splitlines()
    assert (tmp_path / "data" / "results" / "digits.csv").is_file()
    assert report.SIGNIFICANT_DIGITS == 4 and text[1] == "0.3333,0.6667"
    with pytest.raises(TypeError, match="DataFrame"):
        report.save_results([1, 2], "digits", "reference")


def test_load_claims_and_reproduction_table(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    with pytest.raises(FileNotFoundError, match="reproduce 00"):
        report.load_claims(["audit"])
    with pytest.raises(ValueError, match="unknown table"):
        report.load_claims(["nothing"])
    table = report.ClaimTable("audit", "reference")
    table.add("IV-C", "agrees", 0.81, 0.81)
    table.add("IV-C", "explained", 0.92, 0.98, rtol=0.02, reason="inconsistent parameters")
    table.add("IV-C", "unexplained", 0.48, 0.82, rtol=0.02)
    table.add("IV-C", "not published", None, 1.0)
    table.save()
    claims = report.load_claims(["audit"])
    assert list(claims.columns) == ["source", "study"] + report.COLUMNS
    assert set(claims.study) == {"reference"}
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
    table = report.ClaimTable("own_stage", "reference")
    table.add("own stage", "validation fit", None, 89.5, unit="%")
    table.save()
    claims = report.load_claims(["own_stage"])
    assert claims.source.tolist() == ["08_your_own_stage"]
    with pytest.raises(FileNotFoundError, match="reproduce 00"):
        report.load_claims()                          # the default set does not include it


def test_study_tables_fall_back_to_the_reference_and_compare(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    for name, value in (("reference", 0.80), ("other", 0.95)):
        table = report.ClaimTable("mu_synthesis", name)
        table.add("IV-B", "mu_RP", 0.71, value, rtol=0.05)
        table.add("IV-B", "order", 6, 6)
        table.save()
    table = report.ClaimTable("weights", "reference")
    table.add("eq. 15", "M_e", 2.0, 2.0)
    table.save()
    assert (tmp_path / "runs" / "other" / "results" / "mu_synthesis.csv").is_file()
    assert (tmp_path / "data" / "results" / "mu_synthesis.csv").is_file()
    changed = report.ClaimTable("x", "other")
    changed.add("IV-B", "unexplained in a study", 0.71, 0.9, rtol=0.05)
    changed.add("IV-B", "explained", 0.71, 0.9, rtol=0.05, reason="method")
    assert changed.frame().reason.tolist() == ["study", "method"]
    unexplained = report.ClaimTable("x", "reference")
    unexplained.add("IV-B", "unexplained in the reproduction", 0.71, 0.9, rtol=0.05)
    assert unexplained.frame().reason.tolist() == [""]
    claims = report.load_claims(["mu_synthesis", "weights"], study="other")
    assert dict(zip(claims.quantity, claims.study)) == {"mu_RP": "other", "order": "other",
                                                        "M_e": "reference"}
    both = report.compare_studies("reference", "other", names=["mu_synthesis", "weights"])
    assert both.index.get_level_values("quantity").tolist() == ["mu_RP"]
    assert both.iloc[0][["reference", "other"]].tolist() == ["0.8", "0.95"]
    assert both.iloc[0]["verdict (other)"] == "differs"
    everything = report.compare_studies("reference", "other", ["mu_synthesis"], changed_only=False)
    assert len(everything) == 2
    with pytest.raises(ValueError, match="same study"):
        report.compare_studies("other", "other")


def test_inconsistent_verdicts_finds_a_verdict_the_numbers_contradict():
    table = pd.DataFrame({
        "paper": ["1.0", "1.0", "2", "x", "1.0"], "ours": ["1.04", "1.2", "2.5", "x", "1.05"],
        "tolerance": ["+-5%", "+-5%", "+-1", "equal", "+-5%"],
        "verdict": ["agrees", "agrees", "agrees", "agrees", "differs"]})
    bad = report.inconsistent_verdicts(table)
    # row 1 lies outside its band; row 4 sits on the edge (rounding can go either way)
    assert bad.index.tolist() == [1]


def test_verdict_on_an_interval_needs_the_whole_interval_outside_the_band():
    # band 1.0 +- 0.1: an interval reaching into it agrees, one wholly outside differs
    assert report.verdict(1.0, 1.15, atol=0.1, interval=(1.08, 1.2))[0] == "agrees"
    assert report.verdict(1.0, 1.15, atol=0.1)[0] == "differs"           # the mean alone
    assert report.verdict(1.0, 1.2, atol=0.1, interval=(1.11, 1.3))[0] == "differs"
    assert report.verdict(1.0, 0.8, atol=0.1, interval=(0.7, 0.95))[0] == "agrees"
    with pytest.raises(ValueError, match="low <= high"):
        report.verdict(1.0, 1.0, interval=(1.2, 1.1))
    with pytest.raises(ValueError, match="numeric"):
        report.verdict(True, True, interval=(0, 1))


def test_claim_rows_carry_interval_and_precision():
    table = report.ClaimTable("stats", "reference")
    table.add("T", "mean", 1.0, 1.15, atol=0.1, interval=(1.08, 1.2))
    table.add("T", "residual", 0.0, 2e-10, atol=1e-7, precision=1e-7)
    table.add("T", "plain", 2.0, 2.5)
    frame = table.frame()
    assert frame.verdict.tolist() == ["agrees", "agrees", "differs"]
    assert frame.loc[0, "precision"] == pytest.approx(0.03)     # a quarter of the width
    assert frame.loc[2, ["low", "high", "precision"]].isna().all()
    with pytest.raises(ValueError, match="outside its interval"):
        table.add("T", "bad", 1.0, 2.0, interval=(0.0, 1.0))
    with pytest.raises(ValueError, match="precision"):
        table.add("T", "bad", 1.0, 1.0, precision=-1.0)


def test_a_rerun_within_precision_leaves_the_table_as_it_is(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))

    def write(residual, mean, verdict_paper=1.0, note=""):
        table = report.ClaimTable("rerun", "reference")
        table.add("T", "residual", 0.0, residual, atol=1e-7, precision=1e-7)
        table.add("T", "mean", verdict_paper, mean, atol=0.1, interval=(mean - 0.04, mean + 0.04))
        table.add("T", "value", 3.0, 3.14159, rtol=0.1, note=note)
        return table.save().read_text()

    first = write(2.226e-10, 1.15)
    assert "2.226e-10" in first
    assert write(5.081e-10, 1.16) == first       # rounding residual; mean within its precision
    changed = write(5.081e-10, 1.25)              # the mean moved beyond its precision
    assert changed != first and "1.25" in changed
    assert write(5.081e-10, 1.25, note="other") != changed       # text is compared exactly
    again = write(5.081e-10, 1.25, note="other")
    assert write(5.081e-10, 1.25, verdict_paper=1.3, note="other") != again   # paper changed


def test_same_number_allows_one_unit_of_the_last_kept_digit():
    row = pd.Series({"quantity": "q", "ours": "0.1563", "precision": ""})
    assert report.same_result(row, row.replace("0.1563", "0.1564"))
    assert not report.same_result(row, row.replace("0.1563", "0.1565"))
    assert not report.same_result(row, row.replace("q", "r"))


def test_goal_verdict_needs_the_whole_interval_on_one_side():
    assert report.goal_verdict(0.8, 0.99, 1.0) == "met"
    assert report.goal_verdict(1.0, 1.2, 1.0) == "missed"           # at the goal is not below it
    assert report.goal_verdict(0.9, 1.0, 1.0) == "undecided"
    assert report.goal_verdict(np.nan, np.nan, 1.0) == "undecided"


def test_side_by_side_pairs_each_published_column_with_ours():
    published = pd.DataFrame({20.0: [1.0], 10.0: [2.0]}, index=["case_I"])
    ours = pd.DataFrame({10.0: [2.5], 20.0: [1.5], 30.0: [9.0]}, index=["case_I"])
    both = report.side_by_side(published, ours)
    assert list(both.columns) == [(10.0, "paper"), (10.0, "ours"), (20.0, "paper"), (20.0, "ours")]
    assert both.loc["case_I", (20.0, "ours")] == 1.5


def _published(verdicts, reasons, sources, study="reference"):
    return pd.DataFrame({"source": sources, "study": study, "verdict": verdicts,
                         "reason": reasons})


def test_summary_counts_verdicts_reasons_and_notebooks():
    table = _published(["agrees", "differs", "differs", "differs"],
                       ["", "typo", "method", "method"],
                       ["00_a", "00_a", "05_b", "05_b"])
    text = report.summary(table)
    first, *rest = text.splitlines()
    assert "**4 published numbers recomputed** (study `reference`)" in first
    assert "**1 agree**" in first and "**3 differ**" in first
    assert "- Every difference has a reason: 2 method, 1 typo." in rest
    assert "- Per notebook (agree of published): 00: 1 of 2, 05: 0 of 2." in rest
    assert "reference study's tables" not in text


def test_summary_names_unexplained_differences_and_borrowed_rows():
    table = _published(["differs", "differs"], ["unexplained", "method"], ["00_a", "06_c"],
                       study="mine")
    table.loc[1, "study"] = "reference"              # a table the study has not written
    text = report.summary(table, "mine")
    assert "**1 difference has no reason**" in text
    assert "- Reasons of the others: 1 method." in text
    assert "- 1 row comes from the reference study's tables" in text
    with pytest.raises(ValueError, match="reason"):
        report.summary(table.drop(columns="reason"))


def test_rows_of_a_claim_table_compare_as_their_csv_rows_do():
    # ClaimTable.frame() holds None where a precision is not stated (the CSV holds "")
    table = report.ClaimTable("x", "reference")
    table.add("s", "q", 1.0, 1.00001)
    table.add("s", "q", 1.0, 1.002)
    rows = table.frame()
    assert report.same_result(rows.iloc[0], rows.iloc[0])
    assert not report.same_result(rows.iloc[0], rows.iloc[1])
