"""Sec. V before the tables (notebook 06): the checks of
:mod:`piezolib.workbook.tracking_setup` on small hand-made results (no experiment is run)."""

from types import SimpleNamespace

import control as ct
import pandas as pd
import pytest

from piezolib.robust.export import controller_sos
from piezolib.workbook import tracking_setup as setup

OURS, PUBLISHED = "ours", "published K"


def test_sections_error_is_rounding_for_an_exact_export_and_large_for_a_wrong_one():
    Kd = ct.ss(ct.tf([0.5, -0.3], [1.0, -0.95], 1e-4))
    assert setup.sections_error(Kd, controller_sos(Kd), 1e4)["from 1 Hz"] < 1e-5
    wrong = setup.sections_error(1.1 * Kd, controller_sos(Kd), 1e4)
    assert wrong["above 10 Hz"] == pytest.approx(1 - 1 / 1.1, rel=1e-3)


def test_margin_checks_name_each_controller_and_fail_on_an_unstable_loop():
    table = pd.DataFrame({OURS: {"closed loop stable": True, "stable, delay 1": True},
                          PUBLISHED: {"closed loop stable": True, "stable, delay 1": False}})
    margins = setup.LoopMarginChecks(table, OURS, 1)
    assert all(margins.checks.values()) and len(margins.checks) == 3
    assert margins.reference_checks == {
        "ours: sampled loop stable with 1 sample of delay": True,
        "published K: sampled loop stable with 1 sample of delay": False}
    table.loc["stable, delay 1", OURS] = False
    assert not all(setup.LoopMarginChecks(table, OURS, 1).checks.values())


def test_mu_certificate_checks_the_bound_for_every_controller():
    cert = setup.MuCertificate(SimpleNamespace(value=0.85), {OURS: 1.2, PUBLISHED: 1.4}, 0.71)
    assert all(cert.checks.values()) and not cert.paper_attainable
    assert "below the lower bound 0.8500 by 0.1400" in cert.description()
    assert cert.table().loc[OURS, "achievable"].startswith("achievable mu_RP in [0.850, 1.200]")
    bad = setup.MuCertificate(SimpleNamespace(value=0.85), {OURS: 0.8}, 0.9)
    assert bad.checks == {"ours: mu_RP >= the lower bound": False} and bad.paper_attainable


def test_the_nearer_reading_is_judged_frequency_by_frequency():
    table = pd.DataFrame({"paper Case I": [7.3, 9.5], "ours: max|e| / 12 um": [7.0, 6.0],
                          "ours: (max e - min e) / 12 um": [12.0, 11.0]},
                         index=pd.Index([1.0, 10.0], name="frequency [Hz]"))
    evidence = setup.ErrorDefinitionEvidence(table, 12.44, [1.0, 10.0])
    assert evidence.max_abs_nearer.tolist() == [True, False]
    assert all(evidence.reference_checks.values())
    assert evidence.shown().loc["nearer the paper's Case I"].tolist() == ["max|e|", "max e - min e"]
    assert "the literal reading is excluded" in evidence.description()
    table.loc[10.0, "ours: max|e| / 12 um"] = 9.0               # now max|e| is nearer at 10 Hz
    assert not all(setup.ErrorDefinitionEvidence(table, 12.44, [1.0, 10.0]).reference_checks.values())
