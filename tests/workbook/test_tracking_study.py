"""Sec. V on one study (notebook 06): the checks, tables, claims and findings of
:mod:`piezolib.workbook.tracking_study` on small hand-made results (no experiment is run)."""

from types import SimpleNamespace

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib import metrics, paper
from piezolib.robust.export import controller_sos
from piezolib.workbook import experiments as ex
from piezolib.workbook import report, outputs
from piezolib.workbook import tracking_study as sec5

OURS, FULL, PUBLISHED = "ours", "ours, full", "published K"


def seeded(table, spread=0.01, seeds=(0, 1, 2)):
    """An ExperimentResult whose seeds scatter by +-``spread`` around ``table``."""
    tables = {s: table + spread * (s - 1) for s in seeds}
    per_seed = pd.concat(tables, names=["seed", "row"])
    mean, low, high = metrics.mean_interval(np.stack([t.to_numpy() for t in tables.values()]))

    def like(data):
        return pd.DataFrame(data, index=table.index, columns=table.columns)
    saturation = pd.DataFrame(0, index=[f"case_{c}" for c in ex.CASES], columns=table.columns)
    return ex.ExperimentResult(like(mean), {}, saturation, like(low), like(high), like(mean),
                               per_seed, tuple(seeds))


def experiments_like(table4=None, table5=None, no_delay_gain=0.5):
    """Experiments whose every controller has the paper's tables (or the ones given)."""
    t4 = paper.table4() if table4 is None else table4
    t5 = paper.table5() if table5 is None else table5
    hyst = {n: seeded(t4) for n in (OURS, FULL, PUBLISHED)}
    tracking = {n: seeded(t5) for n in (OURS, FULL, PUBLISHED)}
    hyst_0 = {n: seeded(t4 * no_delay_gain) for n in hyst}
    tracking_0 = {n: seeded(t5 * no_delay_gain) for n in tracking}
    return sec5.Experiments(hyst, tracking, hyst_0, tracking_0, OURS, PUBLISHED, 1, (0, 1, 2), 0.0,
                            ex.design_goal_table(tracking), ex.design_goal_table(tracking_0))


def case_iv_like(runs, factor=0.2):
    results = {f"Case IV ({m})": seeded(paper.table5() * factor) for m in ("Dahl", "PI")}
    return sec5.CaseIV({}, results, runs, 0.0, ex.design_goal_table(results))


def test_sections_error_is_rounding_for_an_exact_export_and_large_for_a_wrong_one():
    Kd = ct.ss(ct.tf([0.5, -0.3], [1.0, -0.95], 1e-4))
    assert sec5.sections_error(Kd, controller_sos(Kd), 1e4)["from 1 Hz"] < 1e-5
    wrong = sec5.sections_error(1.1 * Kd, controller_sos(Kd), 1e4)
    assert wrong["above 10 Hz"] == pytest.approx(1 - 1 / 1.1, rel=1e-3)


def test_margin_checks_name_each_controller_and_fail_on_an_unstable_loop():
    table = pd.DataFrame({OURS: {"closed loop stable": True, "stable, delay 1": True},
                          PUBLISHED: {"closed loop stable": True, "stable, delay 1": False}})
    margins = sec5.LoopMarginChecks(table, OURS, 1)
    assert all(margins.checks.values()) and len(margins.checks) == 3
    assert margins.reference_checks == {
        "ours: sampled loop stable with 1 sample of delay": True,
        "published K: sampled loop stable with 1 sample of delay": False}
    table.loc["stable, delay 1", OURS] = False
    assert not all(sec5.LoopMarginChecks(table, OURS, 1).checks.values())


def test_mu_certificate_checks_the_bound_for_every_controller():
    cert = sec5.MuCertificate(SimpleNamespace(value=0.85), {OURS: 1.2, PUBLISHED: 1.4}, 0.71)
    assert all(cert.checks.values()) and not cert.paper_attainable
    assert "below the lower bound 0.8500 by 0.1400" in cert.description()
    assert cert.table().loc[OURS, "achievable"].startswith("achievable mu_RP in [0.850, 1.200]")
    bad = sec5.MuCertificate(SimpleNamespace(value=0.85), {OURS: 0.8}, 0.9)
    assert bad.checks == {"ours: mu_RP >= the lower bound": False} and bad.paper_attainable


def test_the_nearer_reading_is_judged_frequency_by_frequency():
    table = pd.DataFrame({"paper Case I": [7.3, 9.5], "ours: max|e| / 12 um": [7.0, 6.0],
                          "ours: (max e - min e) / 12 um": [12.0, 11.0]},
                         index=pd.Index([1.0, 10.0], name="frequency [Hz]"))
    evidence = sec5.ErrorDefinitionEvidence(table, 12.44, [1.0, 10.0])
    assert evidence.max_abs_nearer.tolist() == [True, False]
    assert all(evidence.reference_checks.values())
    assert evidence.shown().loc["nearer the paper's Case I"].tolist() == ["max|e|", "max e - min e"]
    assert "the literal reading is excluded" in evidence.description()
    table.loc[10.0, "ours: max|e| / 12 um"] = 9.0               # now max|e| is nearer at 10 Hz
    assert not all(sec5.ErrorDefinitionEvidence(table, 12.44, [1.0, 10.0]).reference_checks.values())


def test_the_reproduced_numbers_are_checked_and_can_fail():
    runs = experiments_like()
    assert all(runs.table4_checks.values()) and len(runs.table4_checks) == 16
    # the paper's own Case III is 0.51 % at 1 Hz: our check asks for < 0.5 %
    failing = [k for k, ok in runs.table5_checks.items() if not ok]
    assert failing == ["Table 5: Case III < 0.5 % at 1 Hz and < 6 % at 50 Hz (one sample of delay)"]
    assert all(runs.controller_checks.values())
    assert runs.ours_minus_published.abs().max() == 0
    # the paper's Case III meets both goals: our checks state they are missed with the delay
    goals = runs.goal_checks
    assert not goals["with the delay every controller misses < 1 % up to 10 Hz, with a mean "
                     "below 1.3 %"]
    assert goals["ours: from 10 Hz on the delay makes every Case III error larger"]
    assert not experiments_like(no_delay_gain=1.0).goal_checks[
        "ours: from 10 Hz on the delay makes every Case III error larger"]


def test_the_tables_of_the_notebook_have_their_layout():
    runs = experiments_like()
    assert runs.side_by_side(5).columns[:2].tolist() == [(1.0, "paper"), (1.0, "ours")]
    assert runs.delay_effect().index.tolist()[0] == ("delay 1", OURS)
    assert runs.case_III_by_controller(5).index.tolist() == [
        OURS, FULL, PUBLISHED, "difference ours - published [points]", "paper (Table 5)"]
    assert runs.case_III_by_controller(4).index.tolist()[-1] == "paper (Table 4)"
    cost = runs.delay_cost()
    assert cost.loc["at 50 Hz", "delay cost, mean over the controllers"] == pytest.approx(
        0.5 * paper.table5().loc["case_III", 50.0])
    assert runs.table4_ranges().loc["case_III", ("paper", "min")] == paper.table4().loc[
        "case_III"].min()


def test_case_IV_checks_can_fail():
    runs = experiments_like()
    good = case_iv_like(runs)
    assert all(good.checks.values())
    assert all(good.reference_checks.values())
    assert not case_iv_like(runs, factor=1.0).reference_checks["Case IV (PI) < 1 % at 50 Hz"]
    assert good.table().index.tolist()[-1] == "Case IV (PI), feedforward alone"


def test_the_claims_are_those_of_the_committed_table_in_its_order():
    runs = experiments_like()
    mu = sec5.MuCertificate(SimpleNamespace(value=0.85), {OURS: 1.2, PUBLISHED: 1.4}, 0.71)
    claims = sec5.add_claims(report.ClaimTable("tracking_test", "reference"), mu, runs,
                             case_iv_like(runs))
    committed = pd.read_csv(outputs.study_results_dir("reference") / "tracking.csv")
    frame = claims.frame()
    assert frame[["section", "quantity"]].values.tolist() == \
        committed[["section", "quantity"]].values.tolist()
    found = sec5.summary(claims, True, mu, runs, case_iv_like(runs))
    assert found["title"] == "What holds (Case III: ours, 1 sample of computation delay)"
    assert found["lines"][0].startswith("μ_RP = 0.71 attainable for the published problem: no")
    assert len(found["lines"]) == 1 + 2 + 3 + 2 + 2
